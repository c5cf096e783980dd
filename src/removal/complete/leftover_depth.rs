//! The depth of the Gaussians left behind a removed object, where the photos prefer it. The
//! completed depth of a fill pixel comes from the surfaces around the hole (planes continued, a
//! smooth prior in between). On a real capture the surface behind an object is often not what
//! the ring around the hole continues: on the cup composite a tumbler's base stood beside the
//! box, the prior bent the desk's depth towards it, beyond the photo-depth stage's 5 % search,
//! so few views "saw" the completed points and most of the hole was invented (the targets: a
//! dark blob ringed by pale specks; the held-out renders: a pale haze). The Gaussians the capture
//! left there were trained by every view that saw the desk around the box, and their depth is
//! what those views' photos agree on.
//!
//! So, per fill pixel that those Gaussians cover (alpha at least the removal's `keep_alpha`), the
//! two depths compete on photo-consistency: the color variance across the other views that saw
//! each point (`sees`: off their holes, at their original depth), summed over a window as the
//! photo-depth stage does. The leftover depth wins where its window agrees clearly better
//! (`BETTER`), or where two views saw its point and no two saw the completed one. Elsewhere the
//! completion stands: on the synth rooms, where the planes continue the floor exactly, a
//! leftover depth taken everywhere cost 1.3-2.7 dB masked PSNR.

use super::photo_depth::ColorSpread;
use super::source_views::{back_project, sees, SourceView};
use super::Completed;
use crate::image_ops::sample_bilinear_pixels;
use crate::scene::Camera;

/// Window radius (pixels) and fewest pixels scored by both depths for the windows to compare.
const WINDOW_RADIUS: usize = 3;
const MIN_WINDOW_PIXELS: usize = 8;
/// Where both depths were seen, the leftover one wins when its window's variance is under this
/// share of the completed one's. Masked PSNR (synth one / two-of-three / three-of-four, the cup
/// composite) and the cup's LPIPS, paired on one training each: at 1 (any lower variance wins)
/// 25.81 / 26.08 / 26.13, 25.38 dB, 0.186; at 0.7 25.95 / 26.19 / 26.19, 25.22, 0.183; at 0.5
/// two-of-three 26.31, the cup 25.20, 0.203; without the stage 25.84 / 26.29 / 26.12, 25.10,
/// 0.229. Flat colors (the synth rooms' walls) give both depths about the same variance, and
/// there the completion's planes are the better guess.
const BETTER: f64 = 0.7;

/// Color variance (RGB summed) of the photos of the views other than `target` that saw `world`
/// (`sees` within `tolerance`); None with fewer than two.
fn photo_variance(
    target: usize,
    world: [f64; 3],
    sources: &[SourceView],
    photos: &[Vec<[f32; 3]>],
    tolerance: f64,
) -> Option<f64> {
    let mut spread = ColorSpread::default();
    for (j, s) in sources.iter().enumerate().filter(|&(j, _)| j != target) {
        let Some((x, y)) = sees(s, world, tolerance) else { continue };
        spread.add(sample_bilinear_pixels(&photos[j], s.camera.width as usize, s.camera.height as usize, x, y));
    }
    spread.variance()
}

/// Replaces the depth of view `target`'s `completed` fill pixels by the `leftover` depth
/// (`MaskedView::leftover_depth`: the render after removal where the leftovers cover the pixel,
/// 0 elsewhere) where the other views' photos agree on it better (module comment). `photos` as
/// `interleave_rgb` stores them.
/// Returns the pixels that took the leftover depth.
pub fn prefer_leftover_depth(
    target: usize,
    camera: &Camera,
    completed: &mut Completed,
    leftover: &[f32],
    sources: &[SourceView],
    photos: &[Vec<[f32; 3]>],
    tolerance: f64,
) -> usize {
    let Completed { depth, fill, .. } = completed;
    let (w, n) = (camera.width as usize, depth.len());
    let h = n / w;
    let candidate = |p: usize| fill[p] && leftover[p] > 0.0 && depth[p] > 0.0 && depth[p].is_finite();
    let variance =
        |p: usize, z: f32| photo_variance(target, back_project(camera, p, z as f64), sources, photos, tolerance);
    // per candidate pixel: (completed, leftover) variances
    let scored: Vec<(usize, Option<f64>, Option<f64>)> =
        (0..n).filter(|&p| candidate(p)).map(|p| (p, variance(p, depth[p]), variance(p, leftover[p]))).collect();
    let mut at = vec![usize::MAX; n];
    for (i, s) in scored.iter().enumerate() {
        at[s.0] = i;
    }
    let r = WINDOW_RADIUS as isize;
    let mut chosen = Vec::new();
    for &(p, _, _) in &scored {
        let (x, y) = ((p % w) as isize, (p / w) as isize);
        // window sums over the pixels both depths score, and counts of each depth's scored pixels
        let (mut both, mut completed, mut left, mut seen_completed, mut seen_left) = (0usize, 0.0, 0.0, 0usize, 0usize);
        for yy in (y - r).max(0)..=(y + r).min(h as isize - 1) {
            for xx in (x - r).max(0)..=(x + r).min(w as isize - 1) {
                let i = at[yy as usize * w + xx as usize];
                if i == usize::MAX {
                    continue;
                }
                let (_, c, l) = scored[i];
                seen_completed += c.is_some() as usize;
                seen_left += l.is_some() as usize;
                if let (Some(c), Some(l)) = (c, l) {
                    both += 1;
                    completed += c;
                    left += l;
                }
            }
        }
        let better = both >= MIN_WINDOW_PIXELS && left < BETTER * completed;
        let only_left_seen = seen_left >= MIN_WINDOW_PIXELS && seen_completed < MIN_WINDOW_PIXELS / 2;
        if better || only_left_seen {
            chosen.push(p);
        }
    }
    for &p in &chosen {
        depth[p] = leftover[p];
    }
    chosen.len()
}
