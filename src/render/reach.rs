//! Which Gaussians a render of a camera can bin, as supersets: a cheap one (`may_reach`), so that
//! a render of a small window (the removal's hull redraws each view's hole in one,
//! `removal::select`) projects and sorts only the Gaussians that can reach it, not the whole
//! scene, and a render of some of its tiles only those that can reach them (`reaching_tiles`);
//! and a tight one (`reaches`), for the Gaussians a refinement over windows leaves out
//! (`removal::refine::seen_by_any`).
//!
//! The bound follows project.comp: a Gaussian is binned only where its ellipse, at the binning
//! threshold (`binning_q_threshold`, at most 2 ln 255 and its float32 margin, under `Q_MAX`), is
//! within a pixel of the image; the ellipse's half extent along x is sqrt(q cov2d_xx) and
//! cov2d_xx = j0 cov j0^T + 0.3 with j0 = fx / z (1, 0, -x / z) the Jacobian's first row (its
//! x / z clamped, which only shortens it), at most |j0|^2 times the largest scale squared plus
//! 0.3. Every other Gaussian touches no pixel, and the renderer's sorts are stable (by depth,
//! then by tile), so a render of the subset, in the scene's order, is the render of the scene,
//! bit for bit (`tests/refine_window.rs`).

use crate::render::reference;
use crate::scene::{Camera, GaussianScene};

/// Above the binning threshold at opacity 1, 2 ln(255) with its margin (11.09).
const Q_MAX: f64 = 12.0;

/// Whether Gaussian `i` of `scene` can be binned into any pixel of `camera`'s image, its view
/// depth culled at `near` (a superset: 1 % and two pixels wider than the bound for float32).
pub fn may_reach(scene: &GaussianScene, i: usize, camera: &Camera, near: f64) -> bool {
    reach_box(scene, i, camera, near).is_some_and(|(center, half)| box_meets_image(center, half, camera))
}

/// `may_reach`'s bound of Gaussian `i`: the centre and half extents of the image box it can be
/// binned in, or None in front of the near plane.
fn reach_box(scene: &GaussianScene, i: usize, camera: &Camera, near: f64) -> Option<([f64; 2], [f64; 2])> {
    let m = scene.means[i];
    let [x, y, z] = camera.to_camera([m[0] as f64, m[1] as f64, m[2] as f64]);
    // float32's view depth may pass the near plane where float64's does not
    if z <= near - 1e-6 * (1.0 + near.abs() + z.abs()) {
        return None;
    }
    let largest = scene.log_scales[i].iter().fold(f32::NEG_INFINITY, |a, &b| a.max(b)) as f64;
    let variance = (2.0 * largest).exp();
    let z = z.max(f64::MIN_POSITIVE);
    let (u, v) = (x / z, y / z);
    let half = |f: f64, slope: f64| {
        let row = (f / z).powi(2) * (1.0 + slope * slope);
        (Q_MAX * (row * variance + 0.3)).sqrt() * 1.01 + 2.0
    };
    let (rx, ry) = (half(camera.fx, u), half(camera.fy, v));
    Some(([camera.fx * u + camera.cx, camera.fy * v + camera.cy], [rx, ry]))
}

/// Whether the box of half-extents `half` around image point `center` meets `camera`'s image. NaN
/// anywhere (a degenerate Gaussian) keeps it: the renderer decides.
fn box_meets_image(center: [f64; 2], half: [f64; 2], camera: &Camera) -> bool {
    let ([x, y], [rx, ry]) = (center, half);
    !(x + rx < 0.0 || y + ry < 0.0 || x - rx > camera.width as f64 || y - ry > camera.height as f64)
}

/// Whether Gaussian `i` of `scene` can be binned into any pixel of `camera`'s image: `may_reach`,
/// then the bound of its own ellipse, its 2D covariance (the reference projection's) at its own
/// opacity's binning threshold, 1 % and two pixels wider, and 1 % more on the threshold (the
/// refinement of the statue `images_2`'s removal keeps 33210 Gaussians by it, 33616 at opacity 1).
/// Where the reference projection finds nothing to bound (within `may_reach`'s float32 margin of
/// the near plane, or a degenerate covariance) the Gaussian is kept: the renderer decides.
pub fn reaches(scene: &GaussianScene, i: usize, camera: &Camera, near: f64) -> bool {
    if !may_reach(scene, i, camera, near) {
        return false;
    }
    let Some(g) = reference::project(scene, i, camera, near, 0) else { return true };
    // binning_q_threshold: nothing below ALPHA_MIN (float32's sigmoid may round just above it)
    if g.opacity < (1.0 - 1e-4) / 255.0 {
        return false;
    }
    let q = (2.0 * (255.0 * g.opacity).ln()).max(0.0) * 1.01 + 0.01;
    let half = [(q * g.cov2d[0]).sqrt() * 1.01 + 2.0, (q * g.cov2d[2]).sqrt() * 1.01 + 2.0];
    box_meets_image(g.xy, half, camera)
}

/// `may_reach` for every Gaussian of `scene`. (Not `reaches`: for the hull's window renders its
/// reference projections cost more than the Gaussians they leave out save, hull 8.6 -> 8.9 s on
/// the statue `images_2`.)
pub fn reaching(scene: &GaussianScene, camera: &Camera, near: f64) -> Vec<bool> {
    (0..scene.len()).map(|i| may_reach(scene, i, camera, near)).collect()
}

/// `reaching` for a render of only the tiles `tiles` marks (`RenderSettings::only_tiles`, 16 x 16
/// pixels row-major over `camera`'s image): the Gaussians whose `may_reach` box meets a marked
/// tile. The others bin into no pixel of those tiles, so the marked tiles render the same bits
/// without them.
pub fn reaching_tiles(scene: &GaussianScene, camera: &Camera, near: f64, tiles: &[bool]) -> Vec<bool> {
    let t = crate::render::TILE as f64;
    let tiles_x = (camera.width as usize).div_ceil(t as usize);
    let tiles_y = tiles.len() / tiles_x.max(1);
    (0..scene.len())
        .map(|i| {
            let Some(([x, y], [rx, ry])) = reach_box(scene, i, camera, near) else { return false };
            if !box_meets_image([x, y], [rx, ry], camera) {
                return false;
            }
            // NaN (a degenerate Gaussian) keeps it: the renderer decides
            if !(x - rx).is_finite() || !(x + rx).is_finite() || !(y - ry).is_finite() || !(y + ry).is_finite() {
                return true;
            }
            // the tiles the box meets, a tile's pixels [16 t, 16 t + 16) and a pixel more each way
            let span = |lo: f64, hi: f64, n: usize| {
                let first = ((lo - 1.0) / t).floor().max(0.0) as usize;
                let last = (((hi + 1.0) / t).floor().max(0.0) as usize).min(n - 1);
                first..=last
            };
            let (xs, ys) = (span(x - rx, x + rx, tiles_x), span(y - ry, y + ry, tiles_y));
            ys.into_iter().any(|ty| xs.clone().any(|tx| tiles[ty * tiles_x + tx]))
        })
        .collect()
}

/// The Gaussians `keep` marks, with only what a render reads (positions, scales, rotations,
/// opacities) and their SH bands up to `degree`, in order.
pub fn render_subset(scene: &GaussianScene, keep: &[bool], degree: u32) -> GaussianScene {
    let k = scene.sh_coeffs() * 3;
    let kept = crate::scene::sh_coeffs(degree) * 3;
    let idx: Vec<usize> = (0..scene.len()).filter(|&i| keep[i]).collect();
    GaussianScene {
        means: idx.iter().map(|&i| scene.means[i]).collect(),
        normals: Vec::new(),
        log_scales: idx.iter().map(|&i| scene.log_scales[i]).collect(),
        quats: idx.iter().map(|&i| scene.quats[i]).collect(),
        opacity_logits: idx.iter().map(|&i| scene.opacity_logits[i]).collect(),
        sh_degree: degree,
        sh: idx.iter().flat_map(|&i| scene.sh[i * k..i * k + kept].iter().copied()).collect(),
        extras: Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image_ops::Rect;
    use crate::render::reference::project;
    use crate::rng::Rng;

    /// 20000 random Gaussians, their centres within `x` and `y` (and depth -1 to 9), their log
    /// scales within `log_scales`, in front of and behind the tests' camera at z = -3.
    fn random_scene(seed: u64, x: f64, y: f64, log_scales: (f64, f64)) -> GaussianScene {
        let mut rng = Rng::new(seed);
        let mut scene = GaussianScene::default();
        for _ in 0..20000 {
            let mean = [rng.range(-x, x) as f32, rng.range(-y, y) as f32, rng.range(-1.0, 9.0) as f32];
            let scales = [0; 3].map(|_| rng.range(log_scales.0, log_scales.1) as f32);
            let quat = [0; 4].map(|_| rng.normal() as f32);
            scene.push(mean, scales, quat, rng.range(-4.0, 6.0) as f32, &[0.1, 0.2, 0.3]);
        }
        scene
    }

    /// Every Gaussian whose support (the reference projection's pixel box at its opacity) meets
    /// the image is kept by both bounds, over random Gaussians in and around the view of a camera
    /// and of a small window of it; `reaches` keeps a subset of what `may_reach` keeps; and most
    /// of those that do not meet it are left out, by `reaches` all but a few.
    #[test]
    fn keeps_every_gaussian_whose_support_meets_the_image() {
        let scene = random_scene(7, 20.0, 15.0, (-5.0, -0.5));
        let camera = Camera::look_at("v", 160, 120, 70.0, [0.0, 0.0, -3.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]);
        let window = Rect { x0: 70, y0: 50, x1: 100, y1: 70 };
        for cam in [camera.clone(), crate::removal::refine::window_camera(&camera, window)] {
            let (mut met, mut kept, mut tight, mut far) = (0, 0, 0, 0);
            for i in 0..scene.len() {
                let (loose, reach) = (may_reach(&scene, i, &cam, 0.01), reaches(&scene, i, &cam, 0.01));
                assert!(loose || !reach, "Gaussian {i}: reaches keeps it, may_reach does not");
                (kept, tight) = (kept + loose as usize, tight + reach as usize);
                match project(&scene, i, &cam, 0.01, 0).and_then(|g| g.support()) {
                    Some([x0, x1, y0, y1])
                        if x1 >= 0.0 && y1 >= 0.0 && x0 <= cam.width as f64 && y0 <= cam.height as f64 =>
                    {
                        met += 1;
                        assert!(reach, "Gaussian {i} meets the {}x{} image but was left out", cam.width, cam.height);
                    }
                    _ => far += 1,
                }
            }
            assert!(met > 100, "{met} Gaussians meet the {}x{} image: the test needs more", cam.width, cam.height);
            assert!(kept - met < far / 2, "may_reach kept {kept}, of which {met} meet the image and {far} do not");
            assert!(tight - met < far / 100, "reaches kept {tight}, of which {met} meet the image and {far} do not");
        }
    }

    /// `reaching_tiles` keeps every Gaussian whose support meets a pixel of a marked tile, only
    /// Gaussians `reaching` keeps, and fewer than it where tiles are left out.
    #[test]
    fn keeps_every_gaussian_whose_support_meets_a_marked_tile() {
        let scene = random_scene(11, 6.0, 5.0, (-5.0, -1.0));
        let cam = Camera::look_at("v", 150, 100, 70.0, [0.0, 0.0, -3.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]);
        let (tiles_x, tiles_y) = (150usize.div_ceil(16), 100usize.div_ceil(16));
        let tiles: Vec<bool> = (0..tiles_x * tiles_y).map(|t| (t * 5) % 7 < 3).collect();
        let (all, some) = (reaching(&scene, &cam, 0.01), reaching_tiles(&scene, &cam, 0.01, &tiles));
        let mut met = 0;
        for i in 0..scene.len() {
            assert!(all[i] || !some[i], "Gaussian {i}: kept for the tiles, not for the image");
            let Some([x0, x1, y0, y1]) = project(&scene, i, &cam, 0.01, 0).and_then(|g| g.support()) else { continue };
            // the pixels whose centres (px + 0.5, py + 0.5) the support holds
            let (px0, px1) = ((x0 - 0.5).ceil().max(0.0), (x1 - 0.5).floor().min(149.0));
            let (py0, py1) = ((y0 - 0.5).ceil().max(0.0), (y1 - 0.5).floor().min(99.0));
            if px0 > px1 || py0 > py1 {
                continue;
            }
            let (tx, ty) = ((px0 as usize / 16)..=(px1 as usize / 16), (py0 as usize / 16)..=(py1 as usize / 16));
            if ty.into_iter().any(|y| tx.clone().any(|x| tiles[y * tiles_x + x])) {
                met += 1;
                assert!(some[i], "Gaussian {i} blends in a marked tile but was left out");
            }
        }
        let (kept_all, kept_some) = (all.iter().filter(|&&k| k).count(), some.iter().filter(|&&k| k).count());
        assert!(met > 100, "{met} Gaussians meet a marked tile: the test needs more");
        assert!(kept_some < kept_all * 9 / 10, "{kept_some} of {kept_all} kept for under half of the tiles");
    }
}
