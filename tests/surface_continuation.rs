//! The built-in completion continues the surface a removed object stood on, against a closed
//! form: a box stands on a stone bench (a slab whose top and front face meet at a convex edge)
//! in front of a textured hedge wall, over the ground. Every pixel's true surface is a ray-plane
//! intersection. After the box is removed, the hole's pixels whose true surface is the bench top
//! must be completed at the bench top's depth with the bench top's texture, and the hedge's
//! texture must not reach them.

mod common;

use cogeo::removal::complete::source_views::SourceView;
use cogeo::removal::complete::{Completer, CompletionConfig, ViewInputs};
use cogeo::scene::exposure::ColorAffine;
use cogeo::scene::Camera;

type V3 = [f64; 3];

#[derive(Clone, Copy, PartialEq, Debug)]
enum Surface {
    Ground,
    BenchTop,
    BenchFace,
    Hedge,
    Sky,
    Box,
}

/// Bench: x in [-6, bench_end], y in [-0.5, 0.5], z in [0, 0.5]; hedge wall at y = 1.6; ground z = 0;
/// the removed box on the bench top: x in [0.1, 0.7], y in [-0.3, 0.3], z in [0.5, 1.3].
fn trace(o: V3, d: V3, with_box: bool, bench_end: f64) -> (f64, Surface) {
    let mut best = (f64::INFINITY, Surface::Sky);
    let mut consider = |t: f64, s: Surface| {
        if t > 1e-9 && t < best.0 {
            best = (t, s);
        }
    };
    let at = |t: f64| [o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]];
    let inside = |p: V3, lo: V3, hi: V3| (0..3).all(|a| p[a] >= lo[a] - 1e-9 && p[a] <= hi[a] + 1e-9);
    if d[2] < 0.0 {
        consider(-o[2] / d[2], Surface::Ground);
        let t = (0.5 - o[2]) / d[2];
        if inside(at(t), [-6.0, -0.5, 0.5], [bench_end, 0.5, 0.5]) {
            consider(t, Surface::BenchTop);
        }
    }
    if d[1] > 0.0 {
        let t = (-0.5 - o[1]) / d[1];
        if inside(at(t), [-6.0, -0.5, 0.0], [bench_end, -0.5, 0.5]) {
            consider(t, Surface::BenchFace);
        }
        consider((1.6 - o[1]) / d[1], Surface::Hedge);
    }
    if let Some(t) = with_box.then(|| box_hit(o, d, [0.1, -0.3, 0.5], [0.7, 0.3, 1.3])).flatten() {
        consider(t, Surface::Box);
    }
    best
}

/// Where the ray o + t d (t >= 0) enters the axis-aligned box [lo, hi] (slab test), if it does.
fn box_hit(o: V3, d: V3, lo: V3, hi: V3) -> Option<f64> {
    let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
    for a in 0..3 {
        if d[a].abs() < 1e-12 {
            if o[a] < lo[a] || o[a] > hi[a] {
                return None;
            }
            continue;
        }
        let (ta, tb) = ((lo[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]);
        t0 = t0.max(ta.min(tb));
        t1 = t1.min(ta.max(tb));
    }
    (t0 <= t1).then_some(t0)
}

/// Each surface's texture: colors far apart from one surface to the next, with detail within.
fn color(s: Surface, p: V3) -> [f32; 3] {
    let wave = |v: f64, f: f64| (0.5 + 0.5 * (v * f).sin()) as f32;
    match s {
        Surface::Ground => [0.35 + 0.1 * wave(p[0] + p[1], 9.0), 0.3, 0.25],
        Surface::BenchTop => [0.8 + 0.1 * wave(p[0], 13.0), 0.75, 0.65 + 0.1 * wave(p[1], 11.0)],
        Surface::BenchFace => [0.55, 0.55, 0.6],
        Surface::Hedge => [0.1 + 0.1 * wave(p[0], 17.0), 0.45 + 0.2 * wave(p[2] + p[0], 23.0), 0.1],
        Surface::Sky => [0.6, 0.75, 0.95],
        Surface::Box => [0.9, 0.1, 0.1],
    }
}

/// The bench runs on past the box (its top flanks the hole on both sides): all of the top in the
/// hole is continued exactly.
#[test]
fn the_bench_top_continues_under_a_removed_box_and_the_hedge_does_not() {
    bench_top_continues(1.2, 0.95, 0.02, false);
}

/// The box stands on the bench's end (the real capture): the top runs into the hole from
/// the left only, and right of the hole lie the ground and the hedge. Where inside the hole the
/// bench ends no view says; the top goes on as far as the surfaces flanking it reach, and the
/// hedge behind it never covers it. (Before the pairwise depth order, 20 % of the top took its
/// texture and 60 % the hedge's.)
#[test]
fn a_bench_top_entering_from_one_side_is_continued_not_covered_by_the_hedge() {
    bench_top_continues(0.45, 0.75, 0.1, false);
}

/// The same when the color transfer follows the completion: the exemplar then leaves its texture
/// to the transfer's fill of what no photo gives (here the view's own photo is the only source, so
/// that is the whole hole), which must continue the bench top as the completion's own fill does.
#[test]
fn the_texture_left_to_the_color_transfer_continues_the_bench_top_too() {
    bench_top_continues(0.45, 0.75, 0.1, true);
}

/// The built-in completion with its defaults, for the one view `cam`.
fn default_completer(gpu: &cogeo::gpu::Gpu, cam: &Camera) -> Completer {
    Completer::load(gpu, &CompletionConfig::default(), 7, &[(cam.name.clone(), (cam.width, cam.height))]).unwrap()
}

/// One view's completion inputs: the render after removal (`rgb`, `alpha`, `depth`) and its hole,
/// which is all to be filled.
fn view_inputs<'a>(
    cam: &'a Camera,
    rgb: &'a [f32],
    alpha: &'a [f32],
    depth: &'a [f32],
    hole: &'a [bool],
) -> ViewInputs<'a> {
    let (width, height) = (cam.width as usize, cam.height as usize);
    ViewInputs {
        name: &cam.name,
        width,
        height,
        intrinsics: cam.into(),
        rgb,
        alpha,
        expected_depth: depth,
        front_depth: None,
        fill: hole,
        hole,
    }
}

/// Removes the box from the bench ending at x = `bench_end`; at least `top_share` of the hole
/// pixels whose true surface is the bench top must be completed at its depth (within 3 %) and
/// with its texture, at most `hedge_share` with the hedge's. With `transfer_follows` the view is
/// completed for a color transfer, which then synthesizes the texture.
fn bench_top_continues(bench_end: f64, top_share: f64, hedge_share: f64, transfer_follows: bool) {
    let gpu = common::gpu();
    let (w, h) = (160usize, 120usize);
    let cam = Camera::look_at("bench", w as u32, h as u32, 50.0, [0.9, -3.4, 1.9], [0.3, 0.4, 0.5], [0.0, 0.0, 1.0]);
    let center = cam.center();
    let r = cam.rotation;
    let (mut rgb, mut depth, mut truth, mut object) =
        (vec![0f32; 3 * w * h], vec![0f32; w * h], vec![Surface::Sky; w * h], vec![false; w * h]);
    for p in 0..w * h {
        let dc = [((p % w) as f64 + 0.5 - cam.cx) / cam.fx, ((p / w) as f64 + 0.5 - cam.cy) / cam.fy, 1.0];
        let d = [0, 1, 2].map(|a| r[0][a] * dc[0] + r[1][a] * dc[1] + r[2][a] * dc[2]);
        let (t, s) = trace(center, d, false, bench_end);
        let point = [0, 1, 2].map(|a| center[a] + t * d[a]);
        truth[p] = s;
        depth[p] = t as f32; // camera z, since the direction has z = 1 in the camera frame
        let c = color(s, point);
        for k in 0..3 {
            rgb[k * w * h + p] = c[k];
        }
        object[p] = trace(center, d, true, bench_end).1 == Surface::Box;
    }
    assert!(truth.iter().all(|&s| s != Surface::Sky), "the view must see only the modelled surfaces");
    // the hole: the box's silhouette grown by 2 pixels
    let hole: Vec<bool> = (0..w * h)
        .map(|p| {
            let (x, y) = ((p % w) as i64, (p / w) as i64);
            (-2..=2).any(|dy| {
                (-2..=2).any(|dx| {
                    let (xx, yy) = (x + dx, y + dy);
                    xx >= 0
                        && yy >= 0
                        && (xx as usize) < w
                        && (yy as usize) < h
                        && object[yy as usize * w + xx as usize]
                })
            })
        })
        .collect();
    // after removal the hole renders nothing (alpha 0); everything else is the true background
    let alpha: Vec<f32> = hole.iter().map(|&m| if m { 0.0 } else { 1.0 }).collect();
    let rendered: Vec<f32> = (0..3 * w * h).map(|k| if hole[k % (w * h)] { 0.0 } else { rgb[k] }).collect();
    let render_depth: Vec<f32> = (0..w * h).map(|p| if hole[p] { 0.0 } else { depth[p] }).collect();
    let top_in_hole: Vec<usize> = (0..w * h).filter(|&p| hole[p] && truth[p] == Surface::BenchTop).collect();
    let hedge_in_hole = (0..w * h).filter(|&p| hole[p] && truth[p] == Surface::Hedge).count();
    assert!(
        top_in_hole.len() > 150 && hedge_in_hole > 150,
        "{} bench-top, {hedge_in_hole} hedge hole pixels",
        top_in_hole.len()
    );

    let completer = default_completer(&gpu, &cam);
    let inputs = view_inputs(&cam, &rendered, &alpha, &render_depth, &hole);
    let done = if transfer_follows {
        let mut done = completer.complete_views(&[inputs], true, &mut |_, _| {}).unwrap();
        assert!(done[0].texture_pending, "the exemplar's texture waits for the transfer");
        let opaque = vec![1.0f32; w * h];
        let own = || SourceView {
            camera: &cam,
            photo: &rgb,
            hole: &hole,
            depth: &depth,
            alpha: &opaque,
            photo_colors: ColorAffine::IDENTITY,
        };
        let cameras = std::slice::from_ref(&cam);
        completer.transfer_colors(cameras, &[own()], &[&hole], &mut done, &mut |_, _| {}).unwrap();
        assert!(!done[0].texture_pending, "the transfer synthesized the texture");
        // the transfer's fills of views on several threads at once (`views_in_parallel`) are
        // those made one after another: the view, and a copy whose render is darker, so that a
        // fill landing in the other view shows
        let darker: Vec<f32> = rendered.iter().map(|v| 0.7 * v).collect();
        let two_views = |parallel: bool| {
            let completer = Completer { views_in_parallel: parallel, ..default_completer(&gpu, &cam) };
            let both = [
                view_inputs(&cam, &rendered, &alpha, &render_depth, &hole),
                view_inputs(&cam, &darker, &alpha, &render_depth, &hole),
            ];
            let mut two = completer.complete_views(&both, true, &mut |_, _| {}).unwrap();
            let cameras = [cam.clone(), cam.clone()];
            completer.transfer_colors(&cameras, &[own(), own()], &[&hole, &hole], &mut two, &mut |_, _| {}).unwrap();
            two.into_iter().map(|c| c.rgb).collect::<Vec<_>>()
        };
        let (apart, together) = (two_views(false), two_views(true));
        assert!(apart[0] != apart[1], "the two views' fills should differ");
        assert!(apart == together, "views filled in parallel differ from views filled one after another");
        done.remove(0)
    } else {
        completer.complete(&inputs, 0).unwrap()
    };
    // per pixel, which surface's texture the fill looks like: the nearest of the surfaces' colors
    // at the pixel's true point (hedge and bench differ by > 0.4 in every channel)
    let looks_like = |p: usize| {
        let c = [0, 1, 2].map(|k| done.rgb[k * w * h + p]);
        let dist = |s: Surface| {
            let t = depth[p] as f64;
            let dc = [((p % w) as f64 + 0.5 - cam.cx) / cam.fx, ((p / w) as f64 + 0.5 - cam.cy) / cam.fy, 1.0];
            let d = [0, 1, 2].map(|a| r[0][a] * dc[0] + r[1][a] * dc[1] + r[2][a] * dc[2]);
            let q = color(s, [0, 1, 2].map(|a| center[a] + t * d[a]));
            (0..3).map(|k| (c[k] - q[k]).powi(2)).sum::<f32>()
        };
        [Surface::Ground, Surface::BenchTop, Surface::BenchFace, Surface::Hedge]
            .into_iter()
            .min_by(|a, b| dist(*a).total_cmp(&dist(*b)))
            .unwrap()
    };
    let top_as_top = top_in_hole.iter().filter(|&&p| looks_like(p) == Surface::BenchTop).count();
    let top_as_hedge = top_in_hole.iter().filter(|&&p| looks_like(p) == Surface::Hedge).count();
    let top_depth_ok = top_in_hole.iter().filter(|&&p| ((done.depth[p] - depth[p]) / depth[p]).abs() < 0.03).count();
    let n = top_in_hole.len() as f64;
    eprintln!(
        "bench ending at x = {bench_end}: bench-top hole pixels: {} ; bench texture {:.3}, hedge texture {:.3}, depth within 3 %: {:.3}",
        top_in_hole.len(),
        top_as_top as f64 / n,
        top_as_hedge as f64 / n,
        top_depth_ok as f64 / n
    );
    assert!(top_depth_ok as f64 >= top_share * n, "bench top completed at the wrong depth");
    assert!(top_as_top as f64 >= top_share * n, "the bench top's texture does not reach the box's footprint");
    assert!(top_as_hedge as f64 <= hedge_share * n, "the hedge's texture covers the bench top");
}

/// A pillar stands on a wider pedestal in front of a wall, all three fronto-parallel: pillar and
/// pedestal on one plane at z = 2 (so one plane is fitted to both), the wall at z = 5. The removed
/// object covered the pillar's lower right corner and the wall beside it, down to the pedestal's
/// top. The near plane flanks the hole pixels right of the pillar from two sides (the pillar to
/// their left, the pedestal below), so it is continued over them; but the Gaussians left after
/// removal cover those pixels at the wall's depth (other views saw the wall there, past where the
/// pillar would be), and the pillar's own hole pixels at the pillar's. Each hole pixel must be
/// completed on the surface those Gaussians show: the wall's depth and texture right of the
/// pillar, the pillar's left of its edge. (Without `defer_to_covering` the wall's hole pixels
/// were completed on the near plane: a grey block beside the pillar, as on the statue capture.)
#[test]
fn a_nearer_surface_is_not_continued_over_what_the_remaining_gaussians_show_behind_it() {
    #[derive(Clone, Copy, PartialEq, Debug)]
    enum Part {
        Pillar,
        Pedestal,
        Wall,
    }
    let gpu = common::gpu();
    let (w, h) = (120usize, 90usize);
    let cam = Camera::look_at("pillar", w as u32, h as u32, 60.0, [0.0; 3], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]);
    let (pillar_right, pedestal_top, pedestal_right) = (50usize, 60usize, 100usize);
    let part = |x: usize, y: usize| match (x, y) {
        (x, y) if y >= pedestal_top && x < pedestal_right => Part::Pedestal,
        (x, y) if y < pedestal_top && x < pillar_right => Part::Pillar,
        _ => Part::Wall,
    };
    let wave = |v: f64, f: f64| (0.5 + 0.5 * (v * f).sin()) as f32;
    let (mut rgb, mut depth) = (vec![0f32; 3 * w * h], vec![0f32; w * h]);
    for p in 0..w * h {
        let (x, y) = (p % w, p / w);
        let z = if part(x, y) == Part::Wall { 5.0 } else { 2.0 };
        // the pixel's point on its plane, for a texture fixed to the surface
        let (px, py) = (((x as f64 + 0.5 - cam.cx) / cam.fx) * z, ((y as f64 + 0.5 - cam.cy) / cam.fy) * z);
        let c = match part(x, y) {
            Part::Pillar => [0.45 + 0.1 * wave(py, 19.0), 0.45, 0.5],
            Part::Pedestal => [0.9, 0.88 + 0.08 * wave(px, 17.0), 0.85],
            Part::Wall => [0.1 + 0.1 * wave(px, 13.0), 0.45 + 0.2 * wave(px + py, 23.0), 0.1],
        };
        for k in 0..3 {
            rgb[k * w * h + p] = c[k];
        }
        depth[p] = z as f32;
    }
    let hole: Vec<bool> =
        (0..w * h).map(|p| (38..78).contains(&(p % w)) && (36..pedestal_top).contains(&(p / w))).collect();
    let wall_in_hole: Vec<usize> = (0..w * h).filter(|&p| hole[p] && part(p % w, p / w) == Part::Wall).collect();
    let pillar_in_hole: Vec<usize> = (0..w * h).filter(|&p| hole[p] && part(p % w, p / w) == Part::Pillar).collect();
    // after removal the remaining Gaussians cover the whole view, the hole at the true depths
    let alpha = vec![1.0f32; w * h];
    let rendered: Vec<f32> = (0..3 * w * h).map(|k| if hole[k % (w * h)] { 0.0 } else { rgb[k] }).collect();
    let done = default_completer(&gpu, &cam).complete(&view_inputs(&cam, &rendered, &alpha, &depth, &hole), 0).unwrap();
    let at_depth = |p: usize| ((done.depth[p] - depth[p]) / depth[p]).abs() < 0.03;
    // green dominates the wall's colors, and no other part's
    let green = |p: usize| {
        let c = [0, 1, 2].map(|k| done.rgb[k * w * h + p]);
        c[1] > c[0] + 0.15 && c[1] > c[2] + 0.15
    };
    let share = |pixels: &[usize], f: &dyn Fn(usize) -> bool| {
        pixels.iter().filter(|&&p| f(p)).count() as f64 / pixels.len() as f64
    };
    let (wall_depth, wall_green) = (share(&wall_in_hole, &at_depth), share(&wall_in_hole, &green));
    let (pillar_depth, pillar_green) = (share(&pillar_in_hole, &at_depth), share(&pillar_in_hole, &green));
    eprintln!(
        "wall hole pixels {}: at the wall's depth {wall_depth:.3}, green {wall_green:.3}; pillar hole pixels {}: \
         at its depth {pillar_depth:.3}, green {pillar_green:.3}; {} pixels took the farther plane",
        wall_in_hole.len(),
        pillar_in_hole.len(),
        done.farther_covered
    );
    assert!(wall_in_hole.len() > 500 && pillar_in_hole.len() > 200);
    assert!(wall_depth >= 0.95, "the wall's hole pixels were completed in front of it");
    assert!(wall_green >= 0.9, "the wall's hole pixels took another surface's texture");
    assert!(pillar_depth >= 0.95, "the pillar's hole pixels left its plane");
    assert!(pillar_green <= 0.05, "the wall's texture covers the pillar");
}

/// A slanted panel stands in front of a box on textured ground, before a far wall; the box is
/// removed and the panel kept. The render before removal is known (`front_depth`), so the panel's
/// pixels beside the hole are found in front of the box (`depth::in_front_of_removed`: 25 of
/// its 26, and 2 of the other 62), and its plane does not continue into the hole
/// (`Surfaces::stop_in_front`; on the statue at 504x378 the statue's plane took crosses and bars
/// of the lawn behind a box in 9 of 25 views). The ground's hole pixels must be completed at the
/// ground's depth with its texture, and the panel's texture must not reach them.
#[test]
fn a_surface_in_front_of_the_removed_object_is_not_continued_into_its_hole() {
    #[derive(Clone, Copy, PartialEq, Debug)]
    enum Part {
        Ground,
        Wall,
        Panel,
        Box,
    }
    let gpu = common::gpu();
    let (w, h) = (160usize, 120usize);
    let cam = Camera::look_at("panel", w as u32, h as u32, 100.0, [0.3, -1.8, 1.5], [0.4, 2.5, 0.3], [0.0, 0.0, 1.0]);
    let center = cam.center();
    let r = cam.rotation;
    // the panel: the vertical strip of the plane through (-0.7, 0.4) and (0.12, 1.6) between
    // those two ends, 2.2 high; the box: x in [0.0, 1.1], y in [1.9, 2.6], z in [0, 1]
    let (p0, p1) = ([-0.7, 0.4], [0.12, 1.6]);
    let trace = |d: V3, with_box: bool| -> (f64, Part) {
        let mut best = (f64::INFINITY, Part::Wall);
        let mut consider = |t: f64, s: Part| {
            if t > 1e-9 && t < best.0 {
                best = (t, s);
            }
        };
        if d[2] < 0.0 {
            consider(-center[2] / d[2], Part::Ground);
        }
        if d[1] > 0.0 {
            consider((9.0 - center[1]) / d[1], Part::Wall);
        }
        // panel: points q with cross(p1 - p0, q - p0) = 0 in x, y
        let (ex, ey) = (p1[0] - p0[0], p1[1] - p0[1]);
        let denom = d[0] * ey - d[1] * ex;
        if denom.abs() > 1e-12 {
            let t = ((center[1] - p0[1]) * ex - (center[0] - p0[0]) * ey) / denom;
            let q = [0, 1, 2].map(|a| center[a] + t * d[a]);
            let s = ((q[0] - p0[0]) * ex + (q[1] - p0[1]) * ey) / (ex * ex + ey * ey);
            if (0.0..=1.0).contains(&s) && (0.0..=2.2).contains(&q[2]) {
                consider(t, Part::Panel);
            }
        }
        if let Some(t) = with_box.then(|| box_hit(center, d, [0.0, 1.9, 0.0], [1.1, 2.6, 1.0])).flatten() {
            consider(t, Part::Box);
        }
        best
    };
    let wave = |v: f64, f: f64| (0.5 + 0.5 * (v * f).sin()) as f32;
    let color = |s: Part, q: V3| match s {
        Part::Ground => [0.2 + 0.1 * wave(q[0] + q[1], 9.0), 0.55 + 0.1 * wave(q[0] - q[1], 7.0), 0.15],
        Part::Wall => [0.6, 0.7, 0.9],
        Part::Panel => [0.45 + 0.1 * wave(q[0] + q[1], 17.0), 0.35, 0.5],
        Part::Box => [0.9, 0.1, 0.1],
    };
    let n = w * h;
    let (mut rgb, mut depth, mut front, mut truth, mut object) =
        (vec![0f32; 3 * n], vec![0f32; n], vec![0f32; n], vec![Part::Wall; n], vec![false; n]);
    for p in 0..n {
        let dc = [((p % w) as f64 + 0.5 - cam.cx) / cam.fx, ((p / w) as f64 + 0.5 - cam.cy) / cam.fy, 1.0];
        let d = [0, 1, 2].map(|a| r[0][a] * dc[0] + r[1][a] * dc[1] + r[2][a] * dc[2]);
        let (t, s) = trace(d, false);
        let c = color(s, [0, 1, 2].map(|a| center[a] + t * d[a]));
        (0..3).for_each(|k| rgb[k * n + p] = c[k]);
        (depth[p], truth[p]) = (t as f32, s); // camera z: the direction has z = 1 in the camera frame
        let (tb, sb) = trace(d, true);
        (front[p], object[p]) = (tb as f32, sb == Part::Box);
    }
    // the hole: the box's visible silhouette grown by 2 pixels; it renders nothing after removal
    let hole: Vec<bool> = (0..n)
        .map(|p| {
            let (x, y) = ((p % w) as i64, (p / w) as i64);
            (-2..=2i64).any(|dy| {
                (-2..=2i64).any(|dx| {
                    let (xx, yy) = (x + dx, y + dy);
                    xx >= 0 && yy >= 0 && xx < w as i64 && yy < h as i64 && object[yy as usize * w + xx as usize]
                })
            })
        })
        .collect();
    let alpha: Vec<f32> = hole.iter().map(|&m| if m { 0.0 } else { 1.0 }).collect();
    let rendered: Vec<f32> = (0..3 * n).map(|k| if hole[k % n] { 0.0 } else { rgb[k] }).collect();
    let render_depth: Vec<f32> = (0..n).map(|p| if hole[p] { 0.0 } else { depth[p] }).collect();
    let ground: Vec<usize> = (0..n).filter(|&p| hole[p] && truth[p] == Part::Ground).collect();
    assert!(ground.len() > 300, "{} ground hole pixels", ground.len());

    let known: Vec<bool> = (0..n).map(|p| !hole[p]).collect();
    let in_front = cogeo::removal::complete::depth::in_front_of_removed(&render_depth, &front, &known, &hole, w, h);
    let beside = |p: usize| {
        let (x, y) = (p % w, p / w);
        !hole[p]
            && ((x > 0 && hole[p - 1])
                || (x + 1 < w && hole[p + 1])
                || (y > 0 && hole[p - w])
                || (y + 1 < h && hole[p + w]))
    };
    let beside_panel = (0..n).filter(|&p| beside(p) && truth[p] == Part::Panel).count();
    let flagged_panel = (0..n).filter(|&p| in_front[p] && truth[p] == Part::Panel).count();
    let beside_other = (0..n).filter(|&p| beside(p) && truth[p] != Part::Panel).count();
    let flagged_other = (0..n).filter(|&p| in_front[p] && truth[p] != Part::Panel).count();
    eprintln!(
        "in front of the box: {flagged_panel} of the {beside_panel} panel pixels beside the hole, {flagged_other} of the \
         {beside_other} others"
    );
    assert!(
        beside_panel > 10 && flagged_panel as f64 >= 0.9 * beside_panel as f64,
        "the panel is not found in front of the box"
    );
    assert!(
        flagged_other as f64 <= 0.05 * beside_other as f64,
        "the ground beside the hole was found in front of the box"
    );
    let inputs = ViewInputs { front_depth: Some(&front), ..view_inputs(&cam, &rendered, &alpha, &render_depth, &hole) };
    let done = default_completer(&gpu, &cam).complete(&inputs, 0).unwrap();
    let at_depth = |p: usize| ((done.depth[p] - depth[p]) / depth[p]).abs() < 0.03;
    // the panel's colors are the only ones whose blue exceeds their green
    let panel_like = |p: usize| done.rgb[2 * n + p] > done.rgb[n + p] + 0.05;
    let share = |f: &dyn Fn(usize) -> bool| ground.iter().filter(|&&p| f(p)).count() as f64 / ground.len() as f64;
    let (depth_ok, panel) = (share(&at_depth), share(&panel_like));
    eprintln!("ground hole pixels {}: at the ground's depth {depth_ok:.3}, panel-colored {panel:.3}", ground.len());
    assert!(depth_ok >= 0.9, "the ground's hole pixels were completed off the ground");
    assert!(panel <= 0.02, "the panel's texture reaches the ground behind the removed box");
}
