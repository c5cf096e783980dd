//! The refinement's window (removal/refine.rs): a view refined over part of its image must see
//! those pixels exactly as the whole view does, and the window must hold the view's hole and
//! every patch Gaussian it sees. Stage 2 renders the view after the deletion over such a window
//! too (`ViewRenderer::render_within`), and the hull's redraws a window's tiles before and after
//! the removal from one walk (`ViewRenderer::removal`).

mod common;

use cogeo::image_ops::Rect;
use cogeo::removal::refine::{refine_window, seen_by_any, window_camera};
use cogeo::removal::select::{select_gaussians, DepthPlanes, Rendered, ViewRenderer};
use cogeo::render::{RenderSettings, SceneRenderer};
use common::{random_scene, test_camera, SceneMix};

/// The window's render equals the whole view's render cropped to it, pixel for pixel (up to the
/// float rounding of the moved principal point).
#[test]
fn a_window_camera_renders_the_windows_pixels_as_the_whole_view_does() {
    let gpu = common::gpu();
    let scene = random_scene(11, 1, SceneMix::default());
    let mut camera = test_camera(96, 72);
    camera.cx += 0.37; // a principal point off the pixel grid, as real cameras have
    let window = Rect { x0: 13, y0: 9, x1: 70, y1: 50 };
    let mut renderer = SceneRenderer::new(&gpu, &scene, None).unwrap();
    let settings = RenderSettings { background: [0.2, 0.4, 0.6], ..Default::default() };
    let whole = renderer.render(&camera, &settings).unwrap();
    let part = renderer.render(&window_camera(&camera, window), &settings).unwrap();
    assert_eq!((part.width, part.height), (57, 41));
    let (w, h) = (96usize, 72usize);
    let expected_rgb = cogeo::image_ops::crop(&whole.rgb, w, h, 3, window);
    let expected_alpha = cogeo::image_ops::crop(&whole.alpha, w, h, 1, window);
    let worst = |a: &[f32], b: &[f32]| a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0f32, f32::max);
    let covered = expected_alpha.iter().filter(|&&a| a > 0.5).count();
    assert!(covered > 500, "the window must show the scene, not background: {covered} covered pixels");
    assert!(worst(&part.rgb, &expected_rgb) < 2e-4, "rgb differs by {}", worst(&part.rgb, &expected_rgb));
    assert!(worst(&part.alpha, &expected_alpha) < 2e-4, "alpha differs by {}", worst(&part.alpha, &expected_alpha));
}

/// A window rendered from only the Gaussians that can reach it (`ViewRenderer::render_window`,
/// on a CPU device; `render::reach`) is the window rendered from the whole scene, bit for bit:
/// colors at SH degree 2, alpha, both depths and the marked Gaussians' weight.
#[test]
fn a_window_from_the_gaussians_that_reach_it_is_the_whole_scenes_window() {
    let gpu = common::gpu();
    let scene = random_scene(31, 2, SceneMix::default());
    let mut camera = test_camera(96, 72);
    camera.cx += 0.37;
    let window = window_camera(&camera, Rect { x0: 60, y0: 8, x1: 84, y1: 30 });
    let near = RenderSettings::default().near as f64;
    let reach = cogeo::render::reach::reaching(&scene, &window, near);
    let kept = reach.iter().filter(|&&r| r).count();
    assert!(kept > 20 && kept < scene.len() / 2, "{kept} of {} Gaussians reach the window", scene.len());
    let marked: Vec<bool> = scene.means.iter().map(|m| m[0] > 0.5).collect();
    let mut renderer = ViewRenderer::new(&gpu, &scene, Some(&marked), DepthPlanes::Both).unwrap();
    let bg = [0.2f32, 0.4, 0.6];
    let whole = renderer.render(&window, bg).unwrap();
    assert!(whole.alpha.iter().filter(|&&a| a > 0.5).count() > 300, "the window shows little of the scene");
    assert!(whole.weight.iter().filter(|&&x| x > 0.1).count() > 50, "no marked weight in the window");
    // twice: the second part goes into the first one's buffers
    for _ in 0..2 {
        let part = renderer.render_window(&window, bg).unwrap();
        assert!(part.rgb == whole.rgb, "rgb differs");
        assert!(part.alpha == whole.alpha, "alpha differs");
        assert!(part.depth == whole.depth, "expected depth differs");
        assert!(part.median == whole.median, "median depth differs");
        assert!(part.weight == whole.weight, "weight differs");
    }
}

/// The point 4 units in front of `camera` at pixel (x, y), mirrored through the eye: behind it.
fn behind_camera(camera: &cogeo::scene::Camera, x: usize, y: usize) -> [f32; 3] {
    let (c, eye) = (camera.pixel_point(x, y, 4.0), camera.pixel_point(x, y, 0.0));
    [0, 1, 2].map(|k| (2.0 * eye[k] - c[k]) as f32)
}

/// The window is the bounding box of the hole and of the patch centres that land in the image,
/// grown by the margin, clamped to the image and widened to whole vec4s of the loss (to the
/// right); a centre behind the camera or outside the image does not count, and a view that sees
/// neither has no window.
#[test]
fn the_window_holds_the_hole_and_the_patch_the_view_sees() {
    let camera = test_camera(80, 60);
    let (w, h) = (80usize, 60usize);
    let hole: Vec<bool> = (0..w * h).map(|i| (30..40).contains(&(i % w)) && (20..26).contains(&(i / w))).collect();
    // a patch centre 4 units in front of the camera that lands at a known pixel
    let at = |x: usize, y: usize| camera.pixel_point(x, y, 4.0).map(|v| v as f32);
    let behind = behind_camera(&camera, 10, 10);
    let far_left = camera.pixel_point(0, 0, 4.0);
    let outside = [0, 1, 2].map(|k| (far_left[k] + 10.0 * (far_left[k] - camera.pixel_point(1, 0, 4.0)[k])) as f32);
    assert!(camera.project_to_image(outside.map(f64::from)).is_none());

    let r = refine_window(&camera, &hole, &[], 5).unwrap();
    assert_eq!((r.x0, r.y0, r.x1, r.y1), (25, 15, 45, 31));
    let patch = [at(50, 40), behind, outside];
    let r = refine_window(&camera, &hole, &patch, 5).unwrap();
    assert_eq!((r.x0, r.y0, r.x1, r.y1), (25, 15, 57, 46), "31 pixels wide, widened to 32");
    let r = refine_window(&camera, &hole, &[at(2, 57)], 5).unwrap();
    assert_eq!((r.x0, r.y0, r.x1, r.y1), (0, 15, 48, 60), "clamped to the image, widened to 48");
    assert!(refine_window(&camera, &vec![false; w * h], &[behind, outside], 5).is_none());
}

/// The refinement leaves out the Gaussians no view shows (`seen_by_any`): without them every
/// view renders bit for bit as with the whole scene, here windows that see part of a scene whose
/// Gaussians are huge, tiny, behind the camera and far off to the side.
#[test]
fn the_gaussians_no_window_shows_change_no_pixel() {
    let gpu = common::gpu();
    let scene = random_scene(23, 1, SceneMix { normal: 300, tiny: 20, huge: 6, behind: 10, faint: 20, opaque: 30 });
    let camera = test_camera(96, 72);
    let windows = [Rect { x0: 4, y0: 6, x1: 30, y1: 28 }, Rect { x0: 60, y0: 40, x1: 90, y1: 70 }];
    let cameras: Vec<_> = windows.iter().map(|&r| window_camera(&camera, r)).collect();
    let seen = seen_by_any(&scene, &cameras, 0.005);
    let kept = seen.iter().filter(|&&s| s).count();
    assert!(kept > 20 && kept + 100 < scene.len(), "{kept} of {} seen: the test needs both kinds", scene.len());
    let part = scene.subset(&seen);
    let settings = RenderSettings { background: [0.3, 0.1, 0.5], ..Default::default() };
    let (mut all, mut some) =
        (SceneRenderer::new(&gpu, &scene, None).unwrap(), SceneRenderer::new(&gpu, &part, None).unwrap());
    for cam in &cameras {
        let (a, b) = (all.render(cam, &settings).unwrap(), some.render(cam, &settings).unwrap());
        assert!(a.alpha.iter().filter(|&&x| x > 0.1).count() > 100, "the window must show the scene");
        for (name, x, y) in [("rgb", &a.rgb, &b.rgb), ("alpha", &a.alpha, &b.alpha), ("depth", &a.depth, &b.depth)] {
            let differ = x.iter().zip(y.iter()).filter(|(p, q)| p.to_bits() != q.to_bits()).count();
            assert_eq!(differ, 0, "{name}: {differ} values differ without the unseen Gaussians");
        }
    }
}

/// The render after deleting a cluster of Gaussians, over the box of the pixels they blended
/// and the original render elsewhere, equals a whole render of the remaining Gaussians: within
/// the window's float rounding inside it, within the transmittance a pixel ends with outside;
/// with kept objects marked, so does their weight within the window.
#[test]
fn the_render_after_deletion_over_the_removed_gaussians_box_is_the_whole_render() {
    let gpu = common::gpu();
    let scene = random_scene(21, 0, SceneMix::default());
    let camera = test_camera(96, 72);
    let (w, h) = (96usize, 72usize);
    // the small Gaussians of a cluster on one side of the view
    let removed: Vec<bool> = (0..scene.len())
        .map(|i| {
            let m = scene.means[i];
            (m[0] - 0.6).hypot(m[1] - 0.3) < 0.6 && scene.log_scales[i].iter().all(|&s| s < -1.2)
        })
        .collect();
    let count = removed.iter().filter(|&&r| r).count();
    assert!(count > 3 && count < scene.len() / 3, "{count} of {} removed", scene.len());
    let remaining = scene.subset(&removed.iter().map(|&r| !r).collect::<Vec<_>>());
    let bg = [0.2f32, 0.4, 0.6];
    let before =
        ViewRenderer::new(&gpu, &scene, Some(&removed), DepthPlanes::Expected).unwrap().render(&camera, bg).unwrap();
    let touched: Vec<bool> = before.weight.iter().map(|&x| x > 0.0).collect();
    let window = cogeo::image_ops::bounding_box(&touched, w).expect("the removed Gaussians show");
    assert!(window.width() * window.height() < w * h / 2, "window {window:?} is most of the view");
    let mut after = ViewRenderer::new(&gpu, &remaining, None, DepthPlanes::Expected).unwrap();
    let whole = after.render(&camera, bg).unwrap();
    let within = after.render_within(&camera, window, bg, &before).unwrap();
    let differ = |a: &[f32], b: &[f32]| {
        let worst = a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0f32, f32::max);
        assert!(worst < 2e-4, "differs by {worst}");
    };
    differ(&within.rgb, &whole.rgb);
    differ(&within.alpha, &whole.alpha);
    for p in (0..w * h).filter(|&p| whole.alpha[p] > 0.5) {
        assert!((within.depth[p] - whole.depth[p]).abs() < 1e-4 * whole.depth[p], "depth at {p}");
    }
    // and the deletion did change the window
    let changed = (0..w * h).filter(|&p| (before.alpha[p] - whole.alpha[p]).abs() > 0.05).count();
    assert!(changed > 50, "only {changed} pixels changed by the deletion");
    // with kept objects marked among the remaining Gaussians, their weight within the window
    let kept: Vec<bool> = remaining.means.iter().map(|m| m[1] > 0.0).collect();
    let mut after = ViewRenderer::new(&gpu, &remaining, Some(&kept), DepthPlanes::Expected).unwrap();
    let whole = after.render(&camera, bg).unwrap();
    let within = after.render_within(&camera, window, bg, &before).unwrap();
    differ(&within.rgb, &whole.rgb);
    let crop = |v: &[f32]| cogeo::image_ops::crop(v, w, h, 1, window);
    differ(&crop(&within.weight), &crop(&whole.weight));
    assert!(crop(&whole.weight).iter().filter(|&&x| x > 0.1).count() > 50, "no kept weight in the window");
}

/// The removal's renderer (`ViewRenderer::removal`) gives the view before and after the removal
/// from one walk: each, bit for bit, what a renderer of its own scene gives (the removed
/// Gaussians' weight before, the kept objects' after), whole and in a window's marked tiles from
/// only the Gaussians that reach them, as the hull's redraws render them.
#[test]
fn the_removal_renderer_gives_both_scenes_renders_bit_for_bit() {
    let gpu = common::gpu();
    let scene = random_scene(21, 2, SceneMix::default());
    let camera = test_camera(96, 72);
    // a cluster of small Gaussians goes (label 1); those above the middle are a kept object (2)
    let labels: Vec<u8> = (0..scene.len())
        .map(|i| {
            let m = scene.means[i];
            let cluster = (m[0] - 0.6).hypot(m[1] - 0.3) < 0.6 && scene.log_scales[i].iter().all(|&s| s < -1.2);
            if cluster {
                1
            } else {
                2 * (m[1] < -0.3) as u8
            }
        })
        .collect();
    let selection = select_gaussians(&scene, &labels, &[1]).unwrap();
    assert!(selection.count > 3 && selection.count < scene.len() / 3, "{} of {} removed", selection.count, scene.len());
    let bg = [0.2f32, 0.4, 0.6];
    let planes = DepthPlanes::Both;
    let mut original = ViewRenderer::new(&gpu, &scene, Some(&selection.removed), planes).unwrap();
    let mut after = ViewRenderer::new(&gpu, &selection.background, Some(&selection.kept_objects), planes).unwrap();
    let mut both = ViewRenderer::removal(&gpu, &scene, &selection, planes).unwrap();
    let same = |got: &Rendered, want: &Rendered, what: &str| {
        for (plane, g, w) in [
            ("rgb", &got.rgb, &want.rgb),
            ("alpha", &got.alpha, &want.alpha),
            ("depth", &got.depth, &want.depth),
            ("median depth", &got.median, &want.median),
            ("weight", &got.weight, &want.weight),
        ] {
            let differ = g.iter().zip(w.iter()).filter(|(p, q)| p.to_bits() != q.to_bits()).count();
            assert!(g.len() == w.len() && differ == 0, "{what}, {plane}: {differ} values differ");
        }
    };
    let (want_before, want_after) = (original.render(&camera, bg).unwrap(), after.render(&camera, bg).unwrap());
    let changed = (0..96 * 72).filter(|&p| (want_before.alpha[p] - want_after.alpha[p]).abs() > 0.05).count();
    assert!(changed > 50, "only {changed} pixels changed by the removal");
    assert!(want_before.weight.iter().filter(|&&x| x > 0.1).count() > 50, "no removed weight");
    assert!(want_after.weight.iter().filter(|&&x| x > 0.1).count() > 50, "no kept objects' weight");
    let (before, after_removal) = both.render_window_tiles_both(&camera, bg, None).unwrap();
    same(&before, &want_before, "whole view before");
    same(&after_removal, &want_after, "whole view after");
    // a window's marked tiles, twice (the second goes into the first one's buffers)
    let window = window_camera(&camera, Rect { x0: 40, y0: 10, x1: 90, y1: 60 });
    let tiles: Vec<bool> = (0..16).map(|t| t % 3 != 1).collect();
    for _ in 0..2 {
        let want_before = original.render_window_tiles(&window, bg, Some(tiles.clone())).unwrap();
        let want_after = after.render_window_tiles(&window, bg, Some(tiles.clone())).unwrap();
        let (before, after_removal) = both.render_window_tiles_both(&window, bg, Some(tiles.clone())).unwrap();
        same(&before, &want_before, "window before");
        same(&after_removal, &want_after, "window after");
    }
}

/// The refinement moves the patch Gaussians (the last of the scene) and those whose centre lands
/// in some view's hole, however small or large; a centre beside every hole, behind the camera or
/// outside the image holds still, even when its footprint reaches into a hole
/// (`movable_gaussians`); which of the movers keep their higher SH bands follows
/// `--refine-view-dependence`.
#[test]
fn the_gaussians_the_holes_show_and_the_patch_move() {
    use cogeo::removal::refine::{movable_gaussians, ViewDependence};
    use cogeo::scene::GaussianScene;
    use cogeo::train::trainer::Motion::{Free, Held, ViewIndependent};
    let (a, b) = (test_camera(80, 60), test_camera(40, 30));
    let hole_a: Vec<bool> =
        (0..80 * 60).map(|i| (30..40).contains(&(i % 80)) && (20..26).contains(&(i / 80))).collect();
    let hole_b: Vec<bool> = (0..40 * 30).map(|i| (0..5).contains(&(i % 40)) && (0..5).contains(&(i / 40))).collect();
    let on =
        |cam: &cogeo::scene::Camera, x: usize, y: usize, depth: f64| cam.pixel_point(x, y, depth).map(|v| v as f32);
    // behind b too: the two share their pose
    let behind = behind_camera(&a, 35, 22);
    // a footprint of 0.3 px^2 (the renderer's blur alone), and one of 6 px per deviation
    let (tiny, large) = (-9.0f32, (6.0 * 4.0 / a.fx).ln() as f32);
    let gaussians = [
        (on(&a, 35, 22, 4.0), tiny),  // in a's hole
        (on(&a, 30, 25, 9.0), tiny),  // its corner pixel, farther
        (on(&a, 39, 21, 4.0), large), // a large one at its right edge
        (on(&a, 40, 22, 4.0), tiny),  // the pixel right of a's hole
        (on(&a, 42, 22, 4.0), large), // a large one reaching 12 px into it
        (on(&b, 2, 3, 3.0), tiny),    // in b's hole only
        (behind, tiny),
        (on(&a, 60, 50, 4.0), tiny), // a patch Gaussian beside every hole
        (on(&a, 35, 22, 4.0), tiny), // a patch Gaussian in the hole
    ];
    let mut scene = GaussianScene { sh_degree: 0, ..Default::default() };
    for (m, s) in gaussians {
        scene.push(m, [s; 3], [1.0, 0.0, 0.0, 0.0], 0.0, &[0.5; 3]);
    }
    let both = [a.clone(), b.clone()];
    let movable = movable_gaussians(&scene, &both, &[&hole_a, &hole_b], 2, ViewDependence::Kept);
    let (f, h, v) = (Free, Held, ViewIndependent);
    assert_eq!(movable, [f, f, f, h, h, f, h, v, v]);
    let all = movable_gaussians(&scene, &both, &[&hole_a, &hole_b], 2, ViewDependence::All);
    assert_eq!(all, [f, f, f, h, h, f, h, f, f]);
    let none = movable_gaussians(&scene, &both, &[&hole_a, &hole_b], 2, ViewDependence::None);
    assert_eq!(none, [v, v, v, h, h, v, h, v, v]);
    let holes_only = movable_gaussians(&scene, &[a], &[&hole_a], 0, ViewDependence::Kept);
    assert_eq!(holes_only, [f, f, f, h, h, h, h, h, f]);
}
