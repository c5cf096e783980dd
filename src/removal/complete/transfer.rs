//! Depth-guided color transfer between the edited views. A hole pixel of view i is
//! back-projected at its completed depth; where a training view saw that surface point (outside
//! that view's hole, at the depth that view's original render has there; view i itself first,
//! then the others), the point's color is taken from that view's captured image instead of being
//! invented. Only a good depth puts the point where another view really saw it, so this is where
//! depth guidance pays off in color, not just in geometry.

use super::source_views::{back_project, sees, SourceView};
use crate::image_ops::sample_lanczos3;
use crate::scene::Camera;

/// Colors found for the fill pixels of one target view.
pub struct Transfer {
    /// Planar RGB, valid where `found`.
    pub rgb: Vec<f32>,
    pub found: Vec<bool>,
}

/// Transfers colors into the `fill` pixels (the pipeline passes the whole hole) of view `target`
/// (camera, completed depth) from the `sources` (all edited views, `sources[target]` the target's
/// own). A source qualifies when the point projects inside it, off its hole, where its original
/// render is opaque (alpha > 0.5) and at the point's depth within `tolerance` (relative). The
/// target's own photo comes first: in the dilation ring and wherever else the removed objects did
/// not cover the pixel in the capture, it holds the surface's color itself, not resampled from
/// another viewpoint (held-out seen-elsewhere PSNR +0.05 to +0.15 dB on the bench scenes). Then
/// the nearest qualifying camera wins. Photos are sampled with Lanczos-3.
pub fn transfer(
    target: usize,
    camera: &Camera,
    depth: &[f32],
    fill: &[bool],
    sources: &[SourceView],
    tolerance: f64,
) -> Transfer {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let mut out = Transfer { rgb: vec![0.0; 3 * w * h], found: vec![false; w * h] };
    let center = camera.center();
    // the target itself first, then the others by distance of their camera centers to the target's
    let mut order: Vec<usize> = (0..sources.len()).collect();
    let dist = |j: usize| {
        if j == target {
            return -1.0;
        }
        let c = sources[j].camera.center();
        (0..3).map(|k| (c[k] - center[k]).powi(2)).sum::<f64>()
    };
    order.sort_by(|&a, &b| dist(a).total_cmp(&dist(b)));
    for p in (0..w * h).filter(|&p| fill[p] && depth[p] > 0.0 && depth[p].is_finite()) {
        let world = back_project(camera, p, depth[p] as f64);
        for &j in &order {
            let s = &sources[j];
            let Some((x, y)) = sees(s, world, tolerance) else { continue };
            let (sw, sh) = (s.camera.width as usize, s.camera.height as usize);
            // Lanczos, not bilinear: a transferred checkerboard keeps its edges (held-out
            // seen-elsewhere PSNR +0.3 dB on the bench scenes); clamped, as it may ring at steps
            for c in 0..3 {
                out.rgb[c * w * h + p] = sample_lanczos3(s.photo, sw, sh, c, x, y).clamp(0.0, 1.0);
            }
            out.found[p] = true;
            break;
        }
    }
    out
}

/// What one edited view invented (its fill pixels that no photo showed), for the views completed
/// after it.
pub struct Invention<'a> {
    pub camera: &'a Camera,
    /// The view's completed image and depth.
    pub rgb: Vec<f32>,
    pub depth: Vec<f32>,
    pub invented: Vec<bool>,
}

/// One invention per surface point: the `fill` pixels of a view (camera, completed depth) whose
/// surface point an earlier view invented (`inventions`, nearest camera first) take that view's
/// color, so that the views agree where no photo says what is there instead of each inventing
/// its own (which fusion and refinement would average into a blur). A point qualifies where it
/// lands on an invented pixel at that view's completed depth within `tolerance` (relative).
pub fn borrow_inventions(
    camera: &Camera,
    depth: &[f32],
    fill: &[bool],
    inventions: &[Invention],
    tolerance: f64,
) -> Transfer {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let mut out = Transfer { rgb: vec![0.0; 3 * w * h], found: vec![false; w * h] };
    let center = camera.center();
    let mut order: Vec<&Invention> = inventions.iter().collect();
    let dist = |c: [f64; 3]| (0..3).map(|k| (c[k] - center[k]).powi(2)).sum::<f64>();
    order.sort_by(|a, b| dist(a.camera.center()).total_cmp(&dist(b.camera.center())));
    for p in (0..w * h).filter(|&p| fill[p] && depth[p] > 0.0 && depth[p].is_finite()) {
        let world = back_project(camera, p, depth[p] as f64);
        for inv in &order {
            let Some((x, y, z)) = inv.camera.project_to_image(world) else { continue };
            let (iw, ih) = (inv.camera.width as usize, inv.camera.height as usize);
            let q = y as usize * iw + x as usize;
            let d = inv.depth[q] as f64;
            if !inv.invented[q] || (z - d).abs() > tolerance * d {
                continue;
            }
            for c in 0..3 {
                out.rgb[c * w * h + p] = sample_lanczos3(&inv.rgb, iw, ih, c, x, y).clamp(0.0, 1.0);
            }
            out.found[p] = true;
            break;
        }
    }
    out
}
