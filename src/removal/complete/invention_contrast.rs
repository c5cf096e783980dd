//! The invented parts of a view's fill with their texture's contrast lowered around its local mean,
//! where the texture is random.
//!
//! Where no photo saw the background, the exemplar's texture is a plausible copy of the surface's
//! texture, not the texture that is there: on grass or gravel its light and dark patches fall
//! where the photo's do not. Against the truth such a copy costs its own variance on top of the
//! truth's, where a fill of the local mean alone costs the truth's only (the perception-distortion
//! trade): on the real-photo bench the statue's never-seen lawn scored under the nearest-copy
//! baseline's blur on masked PSNR while far ahead of it on LPIPS. Each such invented pixel becomes
//! m + contrast (v - m), m the mean of the invented pixels of its own surface within
//! `CONTRAST_RADIUS`: contrast 1 keeps the copy as it is, 0 leaves the local mean. A texture that
//! repeats (a checkerboard, bricks) is continued in phase with the truth, and lowering its
//! contrast costs what it would gain: at contrast 0.5 on every invention the synth rooms fell
//! 2.3-3.4 dB; with repeating planes spared they moved -0.06 to +0.05 dB at 0.7 (bench/JOURNAL.md,
//! 2026-11-30).
//!
//! The mean is taken over the same surface only (`surfaces::surfaces_around`), so that a floor's
//! invention next to a wall's keeps its own tone and the edge between them stays sharp.
//!
//! A CPU pass like edge_tone.rs, after the GPU inpainting: one box sum of the image per surface
//! that holds inventions.

use crate::image_ops::{box_count, box_sum};

/// Half the window of the local mean, in pixels: wider than the exemplar's patches (7 px), so
/// that the mean is of several copied 7 x 7 patches, not of the one a pixel lies in (on statue-one
/// radii 12 and 24 scored alike, 6 a little lower on both masked PSNR and LPIPS).
pub const CONTRAST_RADIUS: usize = 12;

/// The `fill` pixels whose invention is a random copy: all but those on a background plane
/// (`labels`, 1 + the plane's index) whose known texture repeats (`repeats`, by label: the
/// exemplar's rectification found it so, `exemplar::RectifiedFill`). A repeating texture (a
/// checkerboard, bricks: 48 of the synth rooms' 55 planes) is continued in phase with the truth
/// and keeps its contrast; grass, gravel and wood grain (none of the real captures' 173 planes)
/// are not, nor is what lies on no plane.
pub fn random_copies(fill: &[bool], labels: &[u8], repeats: &[bool; 256]) -> Vec<bool> {
    fill.iter().zip(labels).map(|(&f, &l)| f && !repeats[l as usize]).collect()
}

/// `--invention-contrast`'s parser: a number from 0 to 1.
pub fn parse_contrast(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(v) if (0.0..=1.0).contains(&v) => Ok(v),
        _ => Err(format!("{s} is not a contrast from 0 to 1")),
    }
}

/// Moves each `invented` pixel of planar RGB `rgb` (w x h) to m + `contrast` (v - m), m the
/// per-channel mean of the invented pixels on its surface (`surfaces`; 0 = none, one group of
/// its own) in the (2 CONTRAST_RADIUS + 1)^2 window around it. Other pixels are untouched.
pub fn lower_contrast(rgb: &mut [f32], invented: &[bool], surfaces: &[u8], w: usize, h: usize, contrast: f32) {
    let radius = CONTRAST_RADIUS;
    let n = w * h;
    if contrast >= 1.0 {
        return;
    }
    let mut labels: Vec<u8> = (0..n).filter(|&p| invented[p]).map(|p| surfaces[p]).collect();
    labels.sort_unstable();
    labels.dedup();
    for s in labels {
        let on_s: Vec<bool> = (0..n).map(|p| invented[p] && surfaces[p] == s).collect();
        let masked: Vec<f32> = (0..3 * n).map(|i| if on_s[i % n] { rgb[i] } else { 0.0 }).collect();
        let sums = box_sum(&masked, w, h, 3, radius);
        let counts = box_count(&on_s, w, h, radius);
        for p in (0..n).filter(|&p| on_s[p]) {
            // the pixel itself is in its window: the count is at least 1
            let count = counts[p] as f32;
            for c in 0..3 {
                let mean = sums[c * n + p] / count;
                let v = &mut rgb[c * n + p];
                *v = mean + contrast * (*v - mean);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::planes::Plane;
    use crate::removal::complete::rectify::{rectify, Intrinsics, PlaneFrame};

    /// A deterministic texture in [0, 1] (a hash of the pixel and channel).
    fn noise(p: usize, c: usize) -> f32 {
        let mut x = (p as u32).wrapping_mul(2654435761) ^ (c as u32).wrapping_mul(40503);
        x ^= x >> 13;
        x = x.wrapping_mul(0x5bd1e995);
        x ^= x >> 15;
        (x % 1000) as f32 / 999.0
    }

    /// On a plane facing the camera with a square hole, a checkerboard's inventions keep their
    /// contrast and white noise's do not; the hole's pixels on no plane (label 0) are random
    /// copies whatever the plane around them.
    #[test]
    fn only_a_repeating_planes_inventions_are_spared() {
        let (w, h) = (160, 160);
        let n = w * h;
        let k = Intrinsics { fx: 100.0, fy: 100.0, cx: 80.0, cy: 80.0 };
        let planes = [Plane { a: 0.0, b: 0.0, c: 1.0 }];
        let fill: Vec<bool> = (0..n).map(|p| (60..100).contains(&(p % w)) && (60..100).contains(&(p / w))).collect();
        // the hole's top rows lie on no plane
        let labels: Vec<u8> = (0..n).map(|p| if fill[p] && p / w < 64 { 0 } else { 1 }).collect();
        let checker = |p: usize| ((p % w / 6 + p / w / 6) % 2) as f32;
        for (name, texture, random_on_plane) in
            [("checkerboard", &checker as &dyn Fn(usize) -> f32, false), ("white noise", &|p| noise(p, 0), true)]
        {
            let image: Vec<f32> = (0..3 * n).map(|i| if fill[i % n] { 0.0 } else { texture(i % n) }).collect();
            // what the exemplar's fill_rectified records of each plane it rectifies
            let frame = PlaneFrame::new(&planes[0], &k).unwrap();
            let mut repeats = [false; 256];
            repeats[1] = rectify(&frame, &image, &fill, &vec![false; n], &labels, 1, w, h).unwrap().repeats;
            let random = random_copies(&fill, &labels, &repeats);
            for p in 0..n {
                let want = fill[p] && (labels[p] == 0 || random_on_plane);
                assert_eq!(random[p], want, "{name}: pixel ({}, {})", p % w, p / w);
            }
        }
    }

    /// Against a brute-force window mean: each invented pixel is the mean of its surface's
    /// invented pixels in its window plus `contrast` times its deviation from it; everything
    /// else, and a second surface's part beside it, keeps or takes only its own values.
    #[test]
    fn each_invented_pixel_moves_toward_its_surfaces_window_mean() {
        let (w, h, r, contrast) = (40, 34, CONTRAST_RADIUS, 0.4);
        let n = w * h;
        let invented: Vec<bool> = (0..n).map(|p| (3..37).contains(&(p % w)) && (3..31).contains(&(p / w))).collect();
        // two surfaces meet inside the invented part
        let surfaces: Vec<u8> = (0..n).map(|p| if p % w < 20 { 1 } else { 2 }).collect();
        let before: Vec<f32> = (0..3 * n).map(|i| noise(i % n, i / n)).collect();
        let mut after = before.clone();
        lower_contrast(&mut after, &invented, &surfaces, w, h, contrast);
        for p in 0..n {
            let (x, y) = ((p % w) as i64, (p / w) as i64);
            for c in 0..3 {
                let want = if !invented[p] {
                    before[c * n + p]
                } else {
                    let window: Vec<f32> = (0..n)
                        .filter(|&q| {
                            let (qx, qy) = ((q % w) as i64, (q / w) as i64);
                            (qx - x).abs() <= r as i64 && (qy - y).abs() <= r as i64
                        })
                        .filter(|&q| invented[q] && surfaces[q] == surfaces[p])
                        .map(|q| before[c * n + q])
                        .collect();
                    let mean = window.iter().sum::<f32>() / window.len() as f32;
                    mean + contrast * (before[c * n + p] - mean)
                };
                let got = after[c * n + p];
                assert!((got - want).abs() < 1e-5, "pixel ({x}, {y}) channel {c}: {got} against {want}");
            }
        }
    }

    /// On a texture around a constant (the truth a copy does not know), the error of the fill
    /// falls with the contrast: its mean square against the constant is the texture's, about
    /// contrast^2 of it after (the local means' own spread adds a little), and a constant part stays
    /// exactly as it is whatever the contrast.
    #[test]
    fn an_uncorrelated_texture_comes_closer_to_the_mean_and_a_constant_stays() {
        let (w, h) = (64, 64);
        let n = w * h;
        let invented = vec![true; n];
        let surfaces = vec![1u8; n];
        let truth = 0.5;
        let textured: Vec<f32> = (0..3 * n).map(|i| truth + 0.3 * (noise(i % n, i / n) - 0.5)).collect();
        let mse = |img: &[f32]| img.iter().map(|v| (v - truth).powi(2)).sum::<f32>() / img.len() as f32;
        let mut damped = textured.clone();
        lower_contrast(&mut damped, &invented, &surfaces, w, h, 0.5);
        let ratio = mse(&damped) / mse(&textured);
        assert!((0.25..0.27).contains(&ratio), "mean square error ratio {ratio}, 0.25 expected");

        let mut constant = vec![0.3; 3 * n];
        lower_contrast(&mut constant, &invented, &surfaces, w, h, 0.0);
        assert!(constant.iter().all(|&v| (v - 0.3).abs() < 1e-6));
    }
}
