//! The rendered depth the removal reads (removal/rendered_depth.rs), chosen by the captured
//! photos: a textured wall at z = 5 (`common::wall`, whose photos are its closed form) rendered
//! from Gaussians, with a removed square at z = 3 in front of it, and a layer that pulls one of the
//! two rendered depths off the wall. The photos agree with the depth that stays on the wall, and
//! the hole's completed depth must land there.

mod common;

use cogeo::removal::complete::{Completer, CompletionConfig};
use cogeo::removal::rendered_depth::{choose, decisive, judged_views, PhotoCost, RenderedDepth, JUDGED_VIEWS};
use cogeo::removal::{remove, RemoveOptions, Stages};
use cogeo::scene::{logit, GaussianScene, SH_C0};
use common::wall;

const W: usize = 96;
const H: usize = 72;

/// A square grid of Gaussians in the plane z (half extents `hx`, `hy`, spacing `step`, footprint
/// 0.7 of it), colored by `color`, each with `opacity`.
#[allow(clippy::too_many_arguments)]
fn layer(
    scene: &mut GaussianScene,
    labels: &mut Vec<u8>,
    z: f64,
    (hx, hy, step): (f64, f64, f64),
    opacity: f32,
    label: u8,
    color: &dyn Fn([f64; 3]) -> [f64; 3],
) {
    let (nx, ny) = ((hx / step).ceil() as i32, (hy / step).ceil() as i32);
    for j in -ny..=ny {
        for i in -nx..=nx {
            let p = [i as f64 * step, j as f64 * step, z];
            let dc = color(p).map(|c| ((c - 0.5) / SH_C0) as f32);
            let s = (0.7 * step).ln() as f32;
            scene.push(
                p.map(|v| v as f32),
                [s, s, (0.2 * step).ln() as f32],
                [1.0, 0.0, 0.0, 0.0],
                logit(opacity as f64),
                &dc,
            );
            labels.push(label);
        }
    }
}

/// The wall (opacity `wall_opacity`), `extra` layers (z, opacity), and the removed dark square.
fn scene(wall_opacity: f32, extra: &[(f64, f32)]) -> (GaussianScene, Vec<u8>) {
    let mut scene = GaussianScene { sh_degree: 0, ..Default::default() };
    let mut labels = Vec::new();
    // one Gaussian per pixel or so at each depth (f = 83 pixels), over every view's frame
    let grid = |z: f64| (0.8 * z + 1.6, 0.6 * z + 1.6, z / 83.0);
    layer(&mut scene, &mut labels, wall::WALL_Z, grid(wall::WALL_Z), wall_opacity, 0, &wall::color);
    for &(z, opacity) in extra {
        // a farther layer shows the wall's texture (the photos' colors), a nearer one is grey
        let color: &dyn Fn([f64; 3]) -> [f64; 3] = if z > wall::WALL_Z { &wall::color } else { &|_| [0.5; 3] };
        layer(&mut scene, &mut labels, z, grid(z), opacity, 0, color);
    }
    layer(&mut scene, &mut labels, 3.0, (0.45, 0.45, 3.0 / 83.0), 0.99, 1, &|_| [0.15, 0.1, 0.1]);
    (scene, labels)
}

/// Removes the square with `depth`, without refinement (the completions are what is compared),
/// seen by the wall rig's four cameras.
fn run(scene: &GaussianScene, labels: &[u8], depth: RenderedDepth) -> cogeo::removal::Removal {
    let rig = wall::Rig::new(W, H);
    run_with(scene, labels, depth, &rig.cams, &rig.photos)
}

/// `run` seen by `cams`, their `photos`.
fn run_with(
    scene: &GaussianScene,
    labels: &[u8],
    depth: RenderedDepth,
    cams: &[cogeo::scene::Camera],
    photos: &[Vec<f32>],
) -> cogeo::removal::Removal {
    let gpu = common::gpu();
    let views: Vec<(String, (u32, u32))> = cams.iter().map(|c| (c.name.clone(), (c.width, c.height))).collect();
    let completer = Completer::load(&gpu, &CompletionConfig::default(), 0, &views).unwrap();
    let opts = RemoveOptions {
        labels: vec![1],
        rendered_depth: depth,
        stages: Stages { refine: false, ..RemoveOptions::default().stages },
        ..Default::default()
    };
    remove(&gpu, scene, labels, cams, photos, 5.0, &opts, &completer, &mut |_, _, _| {}).unwrap()
}

/// The target view's fill pixels' completed depth relative to the wall's: median and the share
/// within 2 %.
fn hole_depth_error(r: &cogeo::removal::Removal) -> (f64, f64) {
    let v = &r.views[0];
    let mut errors: Vec<f64> =
        (0..W * H).filter(|&p| v.fill[p]).map(|p| v.depth[p] as f64 / wall::WALL_Z - 1.0).collect();
    assert!(errors.len() > 300, "the square's hole: {} fill pixels", errors.len());
    let near = errors.iter().filter(|e| e.abs() < 0.02).count() as f64 / errors.len() as f64;
    errors.sort_by(f64::total_cmp);
    (errors[errors.len() / 2], near)
}

/// `Auto` kept the run of the depth it chose: the same views, bit for bit, as that depth forced.
fn assert_same_views(auto: &cogeo::removal::Removal, forced: &cogeo::removal::Removal) {
    for (a, f) in auto.views.iter().zip(&forced.views) {
        assert!(a.depth == f.depth && a.inpainted == f.inpainted && a.fill == f.fill, "view {}", a.name);
    }
    assert_eq!(auto.scene.means, forced.scene.means);
}

/// Removes the square from `scene` under `Auto`, which must choose `chosen` at under half the
/// other depth's cost, put the hole's depth on the wall and keep the chosen run bit for bit; the
/// other depth forced puts it off the wall as `other_is_off` says (its relative error).
fn assert_photos_choose(scene: &(GaussianScene, Vec<u8>), chosen: RenderedDepth, other_is_off: fn(f64) -> bool) {
    let (scene, labels) = scene;
    let other = if chosen == RenderedDepth::Median { RenderedDepth::Expected } else { RenderedDepth::Median };
    let auto = run(scene, labels, RenderedDepth::Auto);
    let choice = auto.report.rendered_depth.clone().expect("completion ran");
    let (e, m) = (choice.expected.expect("scored"), choice.median.expect("scored"));
    let (kept, lost) = if chosen == RenderedDepth::Median { (m, e) } else { (e, m) };
    assert!(choice.chosen == chosen && kept.cost < 0.5 * lost.cost, "{choice:?}");
    let (error, on_wall) = hole_depth_error(&auto);
    assert!(error.abs() < 0.01 && on_wall > 0.8, "hole depth off the wall by {error}, {on_wall} within 2 %");
    let forced = run(scene, labels, other);
    let (error, _) = hole_depth_error(&forced);
    assert!(other_is_off(error), "the {other:?} depth's hole lies {error} off the wall");
    let forced_choice = forced.report.rendered_depth.unwrap();
    let forced_cost = if other == RenderedDepth::Median { forced_choice.median } else { forced_choice.expected };
    assert_eq!(forced_cost, Some(lost), "the same run, the same cost");
    assert_same_views(&auto, &run(scene, labels, chosen));
}

/// A faint grey veil at z = 3.6 (alpha about 0.3) pulls the expected depth 9 % in front of the
/// wall, beyond the 5 % the photo-consistent hole depth searches; the median depth stays on the
/// wall. The photos prefer the median depth.
#[test]
fn a_veil_in_front_of_the_wall_makes_the_photos_choose_the_median_depth() {
    assert_photos_choose(&scene(0.99, &[(3.6, 0.08)]), RenderedDepth::Median, |error| error < -0.05);
}

/// The wall half transparent (alpha about 0.4) before a second layer of its texture 6 % behind
/// it: the median depth lies on that layer, beyond the hole depth's search, the expected depth
/// about 4 % behind the wall, within it. The photos prefer the expected depth.
#[test]
fn a_layer_behind_the_wall_makes_the_photos_choose_the_expected_depth() {
    assert_photos_choose(&scene(0.1, &[(5.3, 0.99)]), RenderedDepth::Expected, |error| error > 0.04);
}

/// The choice's rule and the pooled cost, in closed form: the pixel-weighted mean of the views'
/// costs after the correction, views without a scored pixel (or a NaN cost) left out; the median
/// depth only where both were scored and it costs strictly less.
#[test]
fn the_choice_pools_the_views_costs_by_their_pixels() {
    use cogeo::removal::complete::photo_depth::DepthScale;
    use cogeo::removal::view::ViewReport;
    let report = |pixels, cost_after| ViewReport {
        hole_depth_scale: Some(DepthScale { scale: 1.0, pixels, cost_before: 1.0, cost_after }),
        ..Default::default()
    };
    let views =
        [report(100, 0.002), report(300, 0.006), report(0, f64::NAN), report(50, f64::NAN), ViewReport::default()];
    let pooled = PhotoCost::of(&views).unwrap();
    assert_eq!(pooled.pixels, 400);
    assert!((pooled.cost - (100.0 * 0.002 + 300.0 * 0.006) / 400.0).abs() < 1e-15, "{pooled:?}");
    assert_eq!(PhotoCost::of(&[ViewReport::default()]), None);
    let cost = |cost| Some(PhotoCost { cost, pixels: 10 });
    assert_eq!(choose(cost(0.002), cost(0.001)), RenderedDepth::Median);
    assert_eq!(choose(cost(0.001), cost(0.002)), RenderedDepth::Expected);
    assert_eq!(choose(cost(0.001), cost(0.001)), RenderedDepth::Expected);
    assert_eq!(choose(None, cost(0.001)), RenderedDepth::Expected);
    assert_eq!(choose(cost(0.001), None), RenderedDepth::Expected);
}

/// Stage 2 in both depths from one render of each view gives what it gives in each depth alone,
/// bit for bit; on the veiled wall the two depths differ by the veil's pull.
#[test]
fn masks_in_both_depths_are_the_masks_of_each() {
    use cogeo::removal::select::{hole_masks, select_gaussians, DepthPlanes, HoleConfig, MaskedView, Rendered};
    let gpu = common::gpu();
    let (scene, labels) = scene(0.99, &[(3.6, 0.08)]);
    let rig = wall::Rig::new(W, H);
    let selection = select_gaussians(&scene, &labels, &[1]).unwrap();
    let masks = |depth| {
        let cfg = HoleConfig { threshold: 0.3, dilate: 2.0, keep_alpha: 0.9, background: [0.0; 3], depth };
        hole_masks(&gpu, &scene, &selection, &rig.cams, &cfg, &mut |_, _| {}).unwrap()
    };
    let mut expected = masks(DepthPlanes::Both);
    let median: Vec<MaskedView> = expected.iter_mut().map(MaskedView::take_median_twin).collect();
    let same = |a: &[MaskedView], b: &[MaskedView]| {
        let r = |x: &Rendered, y: &Rendered| {
            (x.rgb == y.rgb && x.alpha == y.alpha && x.depth == y.depth && x.weight == y.weight)
                && (x.median.is_empty() && y.median.is_empty())
        };
        a.len() == b.len()
            && a.iter().zip(b).all(|(a, b)| {
                (r(&a.before, &b.before) && r(&a.after_removal, &b.after_removal))
                    && (a.hole == b.hole && a.fill == b.fill && a.footprint == b.footprint)
            })
    };
    assert!(same(&expected, &masks(DepthPlanes::Expected)), "the expected depth's masks");
    assert!(same(&median, &masks(DepthPlanes::Median)), "the median depth's masks");
    // away from the square the veil pulls the expected depth to about 4.55; the median stays on
    // the wall
    let p = 10 * W + 10;
    let (e, m) = (expected[0].before.depth[p], median[0].before.depth[p]);
    assert!((m - 5.0).abs() < 0.05 && e < 4.7, "expected {e}, median {m}");
}

/// Twelve cameras at (x, y, 0) on a 4 x 3 grid, within 1.2 of the rig's target camera, and their
/// photos of the wall.
fn twelve_cameras() -> (Vec<cogeo::scene::Camera>, Vec<Vec<f32>>) {
    let cams: Vec<_> = (0..12)
        .map(|k| {
            let (x, y) = (-1.2 + 0.8 * (k % 4) as f64, -0.8 + 0.8 * (k / 4) as f64);
            wall::camera(&format!("v{k}"), W, H, x, y)
        })
        .collect();
    let photos = wall::photos(&cams);
    (cams, photos)
}

/// With more views than `JUDGED_VIEWS`, `Auto` completes the judged ones under both depths
/// first. Where their costs part clearly (the veil) it completes the others under the chosen
/// depth alone, and every view is what that depth forced gives it, bit for bit; where they do
/// not (the bare wall, whose two depths agree) every view is completed under both and the
/// costs pool them all, as the forced runs' do.
#[test]
fn the_judged_views_decide_only_where_their_costs_part_clearly() {
    let (cams, photos) = twelve_cameras();
    let veiled = scene(0.99, &[(3.6, 0.08)]);
    let auto = run_with(&veiled.0, &veiled.1, RenderedDepth::Auto, &cams, &photos);
    let choice = auto.report.rendered_depth.clone().expect("completion ran");
    assert_eq!((choice.chosen, choice.judged_views), (RenderedDepth::Median, JUDGED_VIEWS), "{choice:?}");
    assert!(decisive(choice.expected, choice.median), "{choice:?}");
    assert_same_views(&auto, &run_with(&veiled.0, &veiled.1, RenderedDepth::Median, &cams, &photos));

    let bare = scene(0.99, &[]);
    let auto = run_with(&bare.0, &bare.1, RenderedDepth::Auto, &cams, &photos);
    let choice = auto.report.rendered_depth.clone().expect("completion ran");
    assert_eq!(choice.judged_views, cams.len(), "{choice:?}");
    let forced = |depth| run_with(&bare.0, &bare.1, depth, &cams, &photos).report.rendered_depth.unwrap();
    assert_eq!(choice.expected, forced(RenderedDepth::Expected).expected, "pooled over every view");
    assert_eq!(choice.median, forced(RenderedDepth::Median).median, "pooled over every view");
    let kept = if choice.chosen == RenderedDepth::Median { RenderedDepth::Median } else { RenderedDepth::Expected };
    assert_same_views(&auto, &run_with(&bare.0, &bare.1, kept, &cams, &photos));
}

/// The judged views are the `JUDGED_VIEWS` largest holes (ties to the first view), in order; they
/// decide at a cost ratio of `DECISIVE_RATIO` or less, and only with both depths scored.
#[test]
fn the_judged_views_are_the_largest_holes_and_decide_at_the_ratio() {
    assert_eq!(JUDGED_VIEWS, 8);
    let (judged, rest) = judged_views(&[5, 0, 9, 9, 1, 3, 7, 2, 8, 4, 2]);
    assert_eq!(judged, vec![0, 2, 3, 5, 6, 7, 8, 9], "idx 7 before idx 10 of the same size");
    assert_eq!(rest, vec![1, 4, 10]);
    let (judged, rest) = judged_views(&[3, 1, 2]);
    assert_eq!((judged, rest), (vec![0, 1, 2], vec![]));
    let cost = |cost| Some(PhotoCost { cost, pixels: 10 });
    let ratio = cogeo::removal::rendered_depth::DECISIVE_RATIO;
    assert!(decisive(cost(1.0), cost(ratio)) && decisive(cost(ratio), cost(1.0)));
    assert!(!decisive(cost(1.0), cost(ratio + 1e-9)) && !decisive(cost(ratio + 1e-9), cost(1.0)));
    assert!(!decisive(None, cost(0.001)) && !decisive(cost(0.001), None));
}
