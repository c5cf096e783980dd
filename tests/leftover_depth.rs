//! The leftovers' depth against the closed form of a textured wall (common/wall.rs): a fill
//! pixel takes the depth of the Gaussians left behind the object only where the other views'
//! photos agree on it better than on the completed depth. And their colors: where no photo lent
//! one, and where the transferred ones disagree with them on average.

mod common;

use cogeo::removal::complete::leftover_depth::prefer_leftover_depth;
use cogeo::removal::complete::Completed;
use common::wall::{self, WALL_Z};

/// Four fill regions of a view of the wall (z = 5), with a completed and a leftover depth each:
/// A, completed 2 % too near, leftover on the wall: the photos agree on the leftover, which wins;
/// B, the other way round: the completion stays;
/// C, completed 20 % too near, where no view's depth says it saw the point, leftover on the wall:
///    only the leftover's point was seen, and it wins;
/// D, completed 20 % too near, no leftover (not covered): stays.
#[test]
fn fill_takes_the_leftover_depth_only_where_the_photos_agree_on_it_better() {
    let (w, h) = (96usize, 72usize);
    let rig = wall::Rig::new(w, h);
    let sources = rig.sources();
    let region = |p: usize| {
        let (x, y) = (p % w, p / w);
        match (x, y) {
            (20..40, 16..34) => Some('A'),
            (56..76, 16..34) => Some('B'),
            (20..40, 40..58) => Some('C'),
            (56..76, 40..58) => Some('D'),
            _ => None,
        }
    };
    let z = WALL_Z as f32;
    // (completed, leftover) depth
    let depths = |p: usize| match region(p) {
        Some('A') => (0.98 * z, z),
        Some('B') => (z, 0.98 * z),
        Some('C') => (0.8 * z, z),
        Some('D') => (0.8 * z, 0.0),
        _ => (z, z),
    };
    let completed_at = |p: usize| depths(p).0;
    let fill: Vec<bool> = (0..w * h).map(|p| region(p).is_some()).collect();
    let leftover: Vec<f32> = (0..w * h).map(|p| depths(p).1).collect();
    let mut completed = Completed::unguided(fill.clone(), vec![0.5; 3 * w * h], (0..w * h).map(completed_at).collect());
    let taken = prefer_leftover_depth(0, &rig.cams[0], &mut completed, &leftover, &sources, &rig.interleaved, 0.05);
    // the share of region r's pixels seen twice whose depth is the wall's
    let on_wall = |r: char| {
        let pixels: Vec<usize> = (0..w * h).filter(|&p| region(p) == Some(r) && rig.seen_twice(p)).collect();
        assert!(pixels.len() > 300, "region {r}: {} pixels", pixels.len());
        pixels.iter().filter(|&&p| completed.depth[p] == z).count() as f64 / pixels.len() as f64
    };
    let (a, c) = (on_wall('A'), on_wall('C'));
    assert!(a > 0.95 && c > 0.95, "the leftover depth where the photos agree on it: A {a}, C {c}");
    let b = on_wall('B');
    assert!(b == 1.0, "the completed depth where the photos agree on it: B {b}");
    assert!((0..w * h).filter(|&p| region(p) == Some('D')).all(|p| completed.depth[p] == 0.8 * z), "D: no leftover");
    assert!((0..w * h).filter(|&p| !fill[p]).all(|p| completed.depth[p] == z), "off the fill nothing changes");
    let changed = (0..w * h).filter(|&p| completed.depth[p] != completed_at(p)).count();
    assert_eq!(taken, changed);
}

/// `EditedView::take_leftover_colors` on a 24 x 24 view with a 16 x 16 hole. Of its fill
/// pixels, those no photo lent a color, that the leftovers cover (alpha at least keep_alpha) and
/// whose render looks like the invention on average take the leftovers' render, mapped into the
/// photo's colors (here photo = 0.5 render + 0.1 per channel), and stop counting as invented.
/// The leftovers render a one-pixel checkerboard 0.5 +- 0.3 (0.35 +- 0.15 in the photo's
/// colors) and the invention is flat 0.35: a window's means differ by at most 0.15 / 9 (a 3 x 3
/// corner window). In a 6 x 6 corner of the covered part the leftovers are a brown smear (0.3,
/// 0.3, 0.1; 0.25, 0.25, 0.15 in the photo's colors): a window that holds at least 16 of its
/// pixels (of at most 25, the smear's inner 5 x 5) departs by at least (0.2 * 16 - 0.15) / 25 in
/// blue, and those pixels keep the invention.
#[test]
fn untransferred_fill_under_the_leftovers_takes_their_render_where_it_looks_like_the_invention() {
    use cogeo::removal::complete::leftover_colors::{MAX_UNLIKE_INVENTION, WINDOW_RADIUS};
    use cogeo::removal::select::{MaskedView, Rendered};
    use cogeo::removal::view::EditedView;
    const { assert!(0.15 / 9.0 < MAX_UNLIKE_INVENTION && (0.2 * 16.0 - 0.15) / 25.0 > MAX_UNLIKE_INVENTION) };
    assert_eq!(WINDOW_RADIUS, 2, "the bounds above count 5 x 5 windows");
    let (w, h) = (24usize, 24usize);
    let n = w * h;
    let (x, y) = (|p: usize| p % w, |p: usize| p / w);
    let camera = wall::camera("v", w, h, 0.0, 0.0);
    let mut rng = cogeo::rng::Rng::new(7);
    let before: Vec<f32> = (0..3 * n).map(|_| 0.1 + 0.8 * rng.uniform() as f32).collect();
    let photo: Vec<f32> = before.iter().map(|&c| 0.5 * c + 0.1).collect();
    // the hole: x and y in 4..20; the leftovers cover x < 16 (alpha 1), not the 4 columns right
    // of it (alpha 0.5); the rows y < 8 took a photo's color
    let hole: Vec<bool> = (0..n).map(|p| (4..20).contains(&x(p)) && (4..20).contains(&y(p))).collect();
    let alpha: Vec<f32> = (0..n).map(|p| if hole[p] && x(p) >= 16 { 0.5 } else { 1.0 }).collect();
    let transferred: Vec<bool> = (0..n).map(|p| hole[p] && y(p) < 8).collect();
    let smear = |p: usize| (4..10).contains(&x(p)) && (14..20).contains(&y(p));
    let inner_smear = |p: usize| x(p) < 9 && y(p) > 14 && smear(p);
    let leftover_rgb: Vec<f32> = (0..3 * n)
        .map(|i| {
            let (c, p) = (i / n, i % n);
            match (smear(p), c) {
                (true, 2) => 0.1,
                (true, _) => 0.3,
                _ if (x(p) + y(p)) % 2 == 0 => 0.8,
                _ => 0.2,
            }
        })
        .collect();
    let rendered = |rgb: Vec<f32>, alpha: Vec<f32>| Rendered { rgb, alpha, depth: vec![5.0; n], weight: vec![0.0; n] };
    let keep_alpha = 0.75;
    let masked = MaskedView {
        before: rendered(before, vec![1.0; n]),
        after_removal: rendered(leftover_rgb.clone(), alpha.clone()),
        hole: hole.clone(),
        fill: hole.clone(),
        footprint: hole.clone(),
        keep_alpha,
    };
    let mut view = EditedView::new(&camera, Some(&photo), masked);
    // the transferred colors are 0.05 off the leftovers' (in the photo's colors): close enough
    // to keep (`leftover_colors::MAX_DISAGREEMENT`)
    let completed_rgb: Vec<f32> =
        (0..3 * n).map(|i| if transferred[i % n] { 0.5 * leftover_rgb[i] + 0.1 + 0.05 } else { 0.35 }).collect();
    view.completed = Some(Completed::unguided(hole.clone(), completed_rgb.clone(), vec![5.0; n]));
    view.transferred = Some(transferred.clone());
    let counts = view.take_leftover_colors();
    let covered_invented = |p: usize| hole[p] && !transferred[p] && alpha[p] >= keep_alpha;
    assert_eq!(counts.refused, 0, "the transferred colors agree with the leftovers'");
    assert_eq!(counts.taken + counts.invention_kept, (0..n).filter(|&p| covered_invented(p)).count());
    // a window with no smear pixel: x or y more than 2 from it
    let smear_free = |p: usize| x(p) >= 12 || y(p) + 2 < 14;
    let rgb = &view.completed.as_ref().unwrap().rgb;
    let invented_after = view.invented();
    let in_photo_colors = |i: usize| 0.5 * leftover_rgb[i] + 0.1;
    let (mut took, mut kept) = (0, 0);
    for p in 0..n {
        let took_leftovers = (0..3).all(|c| (rgb[c * n + p] - in_photo_colors(c * n + p)).abs() < 1e-4);
        let kept_own = (0..3).all(|c| (rgb[c * n + p] - completed_rgb[c * n + p]).abs() < 1e-4);
        if covered_invented(p) && smear_free(p) {
            assert!(
                took_leftovers && !invented_after[p],
                "({}, {}): the leftovers look like the invention",
                x(p),
                y(p)
            );
            took += 1;
        } else if covered_invented(p) && inner_smear(p) {
            assert!(kept_own && invented_after[p], "({}, {}): the smear stays out", x(p), y(p));
            kept += 1;
        } else if !covered_invented(p) {
            assert!(kept_own && invented_after[p] == (hole[p] && !transferred[p]), "({}, {}): not covered", x(p), y(p));
        }
    }
    // 4 rows of 8 columns above the smear's windows and the 12 rows of the 4 columns right of them
    assert_eq!((took, kept), (8 * 4 + 4 * 12, 25));
    assert!(counts.taken >= took && counts.invention_kept >= kept);
}

/// `leftover_colors::disagreeing_transfers` on a 40 x 20 view whose leftovers render flat gray
/// (0.5) over the compared pixels (x in 2..18 and 20..38, y in 2..18; columns 18 and 19 are not
/// compared, so no window mixes the two halves):
/// - left, a one-pixel checkerboard 0.5 +- 0.3: every pixel departs by 0.3, its window's mean by
///   at most 0.3 / 9 (a corner's 3 x 3 window): kept;
/// - right, rows 2..10, red 0.25 above the leftovers: refused;
/// - right, rows 10..18, green 0.12 below them (under MAX_DISAGREEMENT): kept, away from the
///   rows whose windows see the red blotch.
#[test]
fn transferred_colors_are_refused_where_their_window_mean_departs_from_the_leftovers() {
    use cogeo::removal::complete::leftover_colors::{disagreeing_transfers, MAX_DISAGREEMENT};
    const { assert!(0.3 / 9.0 < MAX_DISAGREEMENT && 0.12 < MAX_DISAGREEMENT && 0.25 > MAX_DISAGREEMENT) };
    let (w, h) = (40usize, 20usize);
    let n = w * h;
    let (left, right) = (2..18usize, 20..38usize);
    let rows = 2..18usize;
    let compared: Vec<bool> =
        (0..n).map(|p| (left.contains(&(p % w)) || right.contains(&(p % w))) && rows.contains(&(p / w))).collect();
    let leftovers = vec![0.5f32; 3 * n];
    let transferred: Vec<f32> = (0..3 * n)
        .map(|i| {
            let (c, p) = (i / n, i % n);
            let (x, y) = (p % w, p / w);
            if left.contains(&x) {
                if (x + y) % 2 == 0 {
                    0.8
                } else {
                    0.2
                }
            } else if y < 10 {
                if c == 0 {
                    0.75
                } else {
                    0.5
                }
            } else if c == 1 {
                0.38
            } else {
                0.5
            }
        })
        .collect();
    let refused = disagreeing_transfers(&transferred, &leftovers, &compared, w, h);
    for p in 0..n {
        let (x, y) = (p % w, p / w);
        if !compared[p] || left.contains(&x) {
            assert!(!refused[p], "({x}, {y}): not compared, or the checkerboard");
        } else if y < 8 {
            assert!(refused[p], "({x}, {y}): the red blotch");
        } else if y >= 12 {
            assert!(!refused[p], "({x}, {y}): the slight green tint");
        }
    }
}
