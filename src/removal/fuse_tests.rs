//! Unit tests of fuse.rs (fusion on closed-form planes), kept beside it so that it stays short.

use super::*;

/// Two fronto-parallel views of the plane z = 3, the second shifted by 2.3 pixels, each filling
/// a square of it with its own invented color (red, blue). (purple, red, blue) point counts.
fn fused_colors(one_owner: bool) -> (usize, usize, usize) {
    let cam = |name: &str, x: f64| Camera::look_at(name, 40, 40, 60.0, [x, 0.0, 0.0], [x, 0.0, 3.0], [0.0, -1.0, 0.0]);
    let (a, b) = (cam("a", 0.0), cam("b", 0.2));
    let square = |x0: usize, x1: usize| -> Vec<bool> {
        (0..1600).map(|i| (x0..x1).contains(&(i % 40)) && (10..30).contains(&(i / 40))).collect()
    };
    let (fill_a, fill_b) = (square(10, 30), square(20, 38)); // a's fill is the larger: a owns first
    let color = |c: [f32; 3]| -> Vec<f32> { c.iter().flat_map(|&v| vec![v; 1600]).collect() };
    let (red, blue, depth) = (color([1.0, 0.0, 0.0]), color([0.0, 0.0, 1.0]), vec![3.0f32; 1600]);
    let views = [
        FuseView { camera: &a, rgb: &red, depth: &depth, fill: &fill_a },
        FuseView { camera: &b, rgb: &blue, depth: &depth, fill: &fill_b },
    ];
    let (points, stats, _) = fuse_points(&views, &FuseConfig { one_owner, ..Default::default() });
    assert_eq!(stats.inconsistent, 0, "both views complete the same plane");
    let is = |p: &PatchPoint, c: [f32; 3]| p.rgb == c;
    let red_n = points.iter().filter(|p| is(p, [1.0, 0.0, 0.0])).count();
    let blue_n = points.iter().filter(|p| is(p, [0.0, 0.0, 1.0])).count();
    (points.len() - red_n - blue_n, red_n, blue_n)
}

#[test]
fn one_owner_fusion_keeps_each_views_invention_unmixed() {
    let (mixed, red, blue) = fused_colors(true);
    let (mixed_avg, _, _) = fused_colors(false);
    println!("one owner: {mixed} mixed, {red} red, {blue} blue; averaging: {mixed_avg} mixed");
    // a owns its whole square; b's reaches 10.3 pixels beyond it, 20 rows: about 206 of b's own
    assert_eq!(red, 400, "a's square");
    assert!((190..=210).contains(&blue), "{blue} points of b's own part");
    assert_eq!(mixed, 0, "points that averaged the two inventions");
    assert!(mixed_avg >= 100, "averaging fusion mixed only {mixed_avg} points");
}

/// Views a and b share a camera and fill the same square of a plane, a at depth 3 (red), b 2 %
/// farther (blue, the same surface within the tolerance); c, beside them, completes the left
/// half 4 % farther still (green). a's left half floats in front of c's completion and is
/// dropped, so a owns only its right half: b must own the left half, and c's points there are
/// b's surface. Counting a as the owner of what it dropped (and b as the owner of what it
/// then lost to a) left the left half with no point at all: the specks of background seen
/// through the bench's patches.
#[test]
fn a_view_owns_only_the_points_it_kept() {
    let cam = |name: &str, x: f64| Camera::look_at(name, 40, 40, 60.0, [x, 0.0, 0.0], [x, 0.0, 3.0], [0.0, -1.0, 0.0]);
    let (a, b, c) = (cam("a", 0.0), cam("b", 0.0), cam("c", -0.2));
    let square = |x0: usize, x1: usize| -> Vec<bool> {
        (0..1600).map(|i| (x0..x1).contains(&(i % 40)) && (10..30).contains(&(i / 40))).collect()
    };
    // c sits 4 pixels (at depth 3) to the left: its columns 14..24 see a's columns 10..20
    let (fill_ab, fill_c) = (square(10, 30), square(14, 24));
    let color = |c: [f32; 3]| -> Vec<f32> { c.iter().flat_map(|&v| vec![v; 1600]).collect() };
    let (red, blue, green) = (color([1.0, 0.0, 0.0]), color([0.0, 0.0, 1.0]), color([0.0, 1.0, 0.0]));
    let (za, zb, zc) = (vec![3.0f32; 1600], vec![3.06f32; 1600], vec![3.12f32; 1600]);
    let views = [
        FuseView { camera: &a, rgb: &red, depth: &za, fill: &fill_ab },
        FuseView { camera: &b, rgb: &blue, depth: &zb, fill: &fill_ab },
        FuseView { camera: &c, rgb: &green, depth: &zc, fill: &fill_c },
    ];
    let (points, stats, _) = fuse_points(&views, &FuseConfig::default());
    let count = |c: [f32; 3]| points.iter().filter(|p| p.rgb == c).count();
    let (r, bl, g) = (count([1.0, 0.0, 0.0]), count([0.0, 0.0, 1.0]), count([0.0, 1.0, 0.0]));
    println!("{stats:?}: red {r}, blue {bl}, green {g}");
    assert_eq!(stats.inconsistent, 200, "a's left half floats in front of c");
    assert_eq!(r, 200, "a keeps its right half");
    assert!((190..=200).contains(&bl), "b owns the left half: {bl} points");
    assert_eq!(g, 0, "c's farther points are b's surface");
    assert_eq!(r + bl + g, points.len());
}

/// View a completes a square of the plane z = 3 at depth `za`; view b, 0.2 to the side (4
/// pixels at depth 3), has no hole and renders the plane (or nothing, depth 0) everywhere. a's
/// points that lie more than `free_space_tolerance` in front of the plane are seen through by b
/// and dropped; points on it, or within the tolerance, are kept; where b renders nothing it
/// says nothing. Returns (kept, dropped).
fn seen_through(za: f32, zb: f32) -> (usize, usize) {
    let cam = |name: &str, x: f64| Camera::look_at(name, 40, 40, 60.0, [x, 0.0, 0.0], [x, 0.0, 3.0], [0.0, -1.0, 0.0]);
    let (a, b) = (cam("a", 0.0), cam("b", 0.2));
    let fill_a: Vec<bool> = (0..1600).map(|i| (10..30).contains(&(i % 40)) && (10..30).contains(&(i / 40))).collect();
    let gray = vec![0.5f32; 3 * 1600];
    let (depth_a, depth_b) = (vec![za; 1600], vec![zb; 1600]);
    let views = [
        FuseView { camera: &a, rgb: &gray, depth: &depth_a, fill: &fill_a },
        FuseView { camera: &b, rgb: &gray, depth: &depth_b, fill: &[false; 1600] },
    ];
    let (points, stats, _) = fuse_points(&views, &FuseConfig::default());
    assert_eq!(stats.sampled, 400);
    (points.len(), stats.inconsistent)
}

#[test]
fn points_another_view_sees_past_are_dropped() {
    let tolerance = FuseConfig::default().free_space_tolerance;
    assert_eq!(seen_through(3.0, 3.0), (400, 0), "on the plane b sees");
    assert_eq!(seen_through(2.7, 3.0), (0, 400), "10 % in front of it");
    let within = 3.0 * (1.0 - 0.8 * tolerance);
    assert_eq!(seen_through(within, 3.0), (400, 0), "in front by less than the tolerance");
    assert_eq!(seen_through(2.7, 0.0), (400, 0), "b renders nothing there");
}

/// The surfel's covariance, rebuilt from its scales and quaternion with the renderer's rotation
/// convention, is the closed form k^2 (sx sx^T + sy sy^T) plus its thin extent along the normal.
#[test]
fn surfel_covariance_is_the_footprint_form() {
    let k = 0.6;
    for (sx, sy) in [
        ([0.02, 0.0, 0.0], [0.0, 0.015, 0.03]),
        ([0.01, -0.004, 0.002], [0.003, 0.012, 0.09]),
        ([0.0, 0.0, 0.05], [0.05, 0.0, 0.0]),
    ] {
        let (log_scales, q) = surfel_shape([sx, sy], k);
        let r = crate::scene::camera::rotation_from_qvec(q.map(|v| v as f64));
        let s2 = log_scales.map(|l| (2.0 * l as f64).exp());
        let n = glam::DVec3::from(sx).cross(glam::DVec3::from(sy)).normalize().to_array();
        for i in 0..3 {
            for j in 0..3 {
                let got: f64 = (0..3).map(|a| r[i][a] * s2[a] * r[j][a]).sum();
                let want = k * k * (sx[i] * sx[j] + sy[i] * sy[j]) + s2[2] * n[i] * n[j];
                assert!((got - want).abs() < 1e-6 * k * k * 0.01, "({i},{j}) {got} vs {want}");
            }
        }
        assert!(s2[2] <= 0.011 * s2[1], "thin across the surface");
    }
}

/// A floor seen at a grazing angle, its completed depth scattered by +-1.5 %: the steps lie in
/// the floor and are the differences of the ray-plane intersections half a pixel either side
/// (beside a depth edge and in the floor's first row too); a lone pixel has none.
#[test]
fn surface_steps_follow_the_completed_floor() {
    let cam = Camera::look_at("c", 40, 30, 40.0, [0.0, -0.6, 0.0], [0.0, 0.0, 4.0], [0.0, -1.0, 0.0]);
    // the floor y = 0.3 (y down): the view depth where continuous image point (x, y) meets it
    let floor_z = |x: f64, y: f64| -> f64 {
        let a = glam::DVec3::from(cam.image_point(x, y, 1.0));
        let o = glam::DVec3::from(cam.image_point(x, y, 0.0));
        (0.3 - o.y) / (a.y - o.y)
    };
    let on_floor = |x: f64, y: f64| glam::DVec3::from(cam.image_point(x, y, floor_z(x, y)));
    // rows 16.. see the floor, each pixel's depth off by a deterministic +-1.5 %
    let noise = |i: usize| 0.015 * (((i * 7919) % 13) as f64 / 6.0 - 1.0);
    let mut depth: Vec<f32> = (0..1200)
        .map(|i| {
            if i / 40 >= 16 {
                (floor_z((i % 40) as f64 + 0.5, (i / 40) as f64 + 0.5) * (1.0 + noise(i))) as f32
            } else {
                0.0
            }
        })
        .collect();
    // a box edge: columns 30.. are 30 % nearer
    for (i, d) in depth.iter_mut().enumerate() {
        if i % 40 >= 30 {
            *d *= 0.7;
        }
    }
    let (rgb, fill) = (vec![0.5f32; 3600], vec![true; 1200]);
    let v = FuseView { camera: &cam, rgb: &rgb, depth: &depth, fill: &fill };
    let disparity = depth::disparity(&depth);
    for (x, y) in [(10, 20), (29, 22), (10, 16)] {
        let (cx, cy) = (x as f64 + 0.5, y as f64 + 0.5);
        let footprint = depth[y * 40 + x] as f64 / cam.fx;
        let [sx, sy] = surface_steps(&v, &disparity, x, y, 1, footprint).expect("a surface");
        let (sx, sy) = (glam::DVec3::from(sx), glam::DVec3::from(sy));
        let want_x = on_floor(cx + 0.5, cy) - on_floor(cx - 0.5, cy);
        let want_y = on_floor(cx, cy + 0.5) - on_floor(cx, cy - 0.5);
        let normal = sx.cross(sy).normalize();
        let (ex, ey) = ((sx - want_x).length() / want_x.length(), (sy - want_y).length() / want_y.length());
        println!("({x},{y}): step errors {ex:.3} {ey:.3}, normal {normal}");
        // the fit averages the noise out, up to a few percent of the step (7 % beside the
        // edge, where only 4 of the window's 7 columns are floor)
        assert!(ex < 0.1 && ey < 0.1, "({x},{y}) steps {sx} {sy} vs {want_x} {want_y}");
        assert!(normal.y.abs() > 0.9995, "({x},{y}) tilted by more than 1.8 degrees: normal {normal}");
        assert!(sy.length() > 2.5 * footprint, "stretched along the floor: {} vs {footprint}", sy.length());
    }
    // what the fit is for: the neighbours' own noisy depths tilt a central difference
    let at = |x: usize, y: usize| glam::DVec3::from(cam.pixel_point(x, y, depth[y * 40 + x] as f64));
    let raw = (at(11, 20) - at(9, 20)).cross(at(10, 21) - at(10, 19)).normalize();
    assert!(raw.y.abs() < 0.9986, "the test's noise must tilt raw differences by more than 3 degrees: {raw}");
    // none where a pixel has no neighbour with depth
    let lone: Vec<f32> = (0..1200).map(|i| if i == 20 * 40 + 10 { 4.0 } else { 0.0 }).collect();
    let v = FuseView { camera: &cam, rgb: &rgb, depth: &lone, fill: &fill };
    assert!(surface_steps(&v, &depth::disparity(&lone), 10, 20, 1, 0.1).is_none());
}

#[test]
fn back_projection_inverts_projection() {
    let cam = Camera::look_at("c", 64, 48, 50.0, [1.0, -3.0, 1.5], [0.0, 0.0, 0.3], [0.0, 0.0, 1.0]);
    let p = cam.pixel_point(10, 30, 2.5);
    let pc = cam.to_camera(p);
    assert!((pc[2] - 2.5).abs() < 1e-9);
    assert!((cam.fx * pc[0] / pc[2] + cam.cx - 10.5).abs() < 1e-9);
    assert!((cam.fy * pc[1] / pc[2] + cam.cy - 30.5).abs() < 1e-9);
}
