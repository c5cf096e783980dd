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

/// `EditedView::take_leftover_colors`: of a view's fill pixels, exactly those no photo lent a
/// color and the leftovers cover (alpha at least keep_alpha) take the leftovers' render, mapped
/// into the photo's colors (here photo = 0.5 render + 0.1 per channel), and stop counting as
/// invented.
#[test]
fn untransferred_fill_under_the_leftovers_takes_their_render_in_the_photos_colors() {
    use cogeo::removal::select::{MaskedView, Rendered};
    use cogeo::removal::view::EditedView;
    let (w, h) = (16usize, 16usize);
    let n = w * h;
    let camera = wall::camera("v", w, h, 0.0, 0.0);
    let mut rng = cogeo::rng::Rng::new(7);
    let render = |rng: &mut cogeo::rng::Rng| (0..3 * n).map(|_| 0.1 + 0.8 * rng.uniform() as f32).collect::<Vec<f32>>();
    let before = render(&mut rng);
    let photo: Vec<f32> = before.iter().map(|&c| 0.5 * c + 0.1).collect();
    let leftover_rgb = render(&mut rng);
    // the hole: the middle 8 x 8; in it, the leftovers' alpha falls from 1 (left) to 0.3 (right)
    let hole: Vec<bool> = (0..n).map(|p| (4..12).contains(&(p % w)) && (4..12).contains(&(p / w))).collect();
    let alpha: Vec<f32> = (0..n).map(|p| if hole[p] { 1.0 - 0.1 * ((p % w) as f32 - 4.0) } else { 1.0 }).collect();
    let rendered = |rgb: Vec<f32>, alpha: Vec<f32>| Rendered { rgb, alpha, depth: vec![5.0; n], weight: vec![0.0; n] };
    let masked = MaskedView {
        before: rendered(before, vec![1.0; n]),
        after_removal: rendered(leftover_rgb.clone(), alpha.clone()),
        hole: hole.clone(),
        fill: hole.clone(),
        footprint: hole.clone(),
    };
    let mut view = EditedView::new(&camera, Some(&photo), masked);
    // the top half of the hole took a photo's color, 0.05 off the leftovers' (in the photo's
    // colors): close enough to keep it (`leftover_colors::MAX_DISAGREEMENT`); the rest is invented
    let transferred: Vec<bool> = (0..n).map(|p| hole[p] && p / w < 8).collect();
    let completed_rgb: Vec<f32> =
        (0..3 * n).map(|i| if transferred[i % n] { 0.5 * leftover_rgb[i] + 0.1 + 0.05 } else { 0.25 }).collect();
    view.completed = Some(Completed::unguided(hole.clone(), completed_rgb.clone(), vec![5.0; n]));
    view.transferred = Some(transferred.clone());
    let keep_alpha = 0.75;
    let (taken, refused) = view.take_leftover_colors(keep_alpha);
    assert_eq!(refused, 0, "the transferred colors agree with the leftovers'");
    let expected: Vec<bool> = (0..n).map(|p| hole[p] && !transferred[p] && alpha[p] >= keep_alpha).collect();
    // columns 4..=6 of the hole's 4 lower rows: alpha 1, 0.9, 0.8 (0.7 and under stay invented)
    assert_eq!(taken, 12);
    assert_eq!(taken, expected.iter().filter(|&&e| e).count());
    let rgb = &view.completed.as_ref().unwrap().rgb;
    for p in 0..n {
        for c in 0..3 {
            let want = if expected[p] { 0.5 * leftover_rgb[c * n + p] + 0.1 } else { completed_rgb[c * n + p] };
            assert!((rgb[c * n + p] - want).abs() < 1e-4, "pixel {p} channel {c}: {} vs {want}", rgb[c * n + p]);
        }
    }
    let invented_after = view.invented();
    assert!((0..n).all(|p| invented_after[p] == (hole[p] && !transferred[p] && !expected[p])));
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
