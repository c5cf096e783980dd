//! The invented parts of a view's fill with their texture's contrast lowered around its local mean,
//! where the texture is random, and their level taken up from the known colors beside them.
//!
//! Where no photo saw the background, the exemplar's texture is a plausible copy of the surface's
//! texture, not the texture that is there: on grass or gravel its light and dark patches fall
//! where the photo's do not. Against the truth such a copy costs its own variance on top of the
//! truth's, where a fill of the local mean alone costs the truth's only (the perception-distortion
//! trade): on the real-photo bench the statue's never-seen lawn scored under the nearest-copy
//! baseline's blur on masked PSNR while far ahead of it on LPIPS.
//!
//! The copy is split by scale around m, the mean of the invented pixels of its own surface within
//! `CONTRAST_RADIUS`: its grain (each pixel's difference from the mean of its 3 x 3 neighbours,
//! `GRAIN_RADIUS`) and its structure (that 3 x 3 mean's difference from m: the clumps of the
//! copied patches). An invented pixel becomes m + structure (g - m) + grain (v - g), g its 3 x 3
//! mean (`Contrast`; 1 and 1 keep the copy as it is). LPIPS reads mostly the grain, the error
//! pays for both. Masked PSNR / LPIPS held out on the real-photo bench (one training per scene;
//! bench/JOURNAL.md, 2026-12-01), statue-one, statue-two-of-three, cup-one, cup-two-of-three:
//! - 0.7 of both (before): 20.96 / 0.326, 21.11 / 0.245, 27.13 / 0.143, 27.73 / 0.119;
//! - grain 1, no structure: 21.03 / 0.314, 21.52 / 0.247, 27.23 / 0.143, 27.71 / 0.118;
//! - grain 0.7, no structure (the default until 2026-12-03): 21.08 / 0.355, 22.37 / 0.334, 27.25 /
//!   0.142, 27.70 / 0.118; 0.5 of both gave statue-one 21.08 / 0.364, nearest-copy 21.07 / 0.528
//!   and 22.37 / 0.453.
//!
//! The grain's default is 0.85, no structure: on the trainings of 2026-12-03 grain 0.7 left the
//! statue's never-seen LPIPS at 0.7002 and 0.7113 of the harmonic fill's (the bound is
//! 0.7; 0.58 and 0.66 on the trainings before), 0.85 at 0.6675 and 0.6678 for 0.07 and 0.04 dB of
//! masked PSNR, and the cups did not move (bench/JOURNAL.md, 2026-12-03, 13:21).
//!
//! Next to the colors the view knows the inventions then take up their level
//! (`follow_known_colors`, `MEMBRANE_FADE`): there the points are mostly ones the photos saw and
//! the transfer missed.
//!
//! A texture that repeats (a checkerboard, bricks) is continued in phase with the truth, and
//! lowering its contrast costs what it would gain: at contrast 0.5 on every invention the synth
//! rooms fell 2.3-3.4 dB; with repeating planes spared they moved -0.06 to +0.05 dB at 0.7
//! (bench/JOURNAL.md, 2026-11-30).
//!
//! The means are taken over the same surface only (`surfaces::surfaces_around`), so that a
//! floor's invention next to a wall's keeps its own tone and the edge between them stays sharp.
//!
//! A CPU pass like edge_tone.rs, after the GPU inpainting: two box sums of the image per surface
//! that holds inventions, a membrane of the known colors and a distance transform.

use super::surfaces::{fill_by_surface_within, Boundary, SurfaceWindow};
use crate::image_ops::{distance_to, masked_box_mean};

/// Half the window of the local mean, in pixels: wider than the exemplar's patches (7 px), so
/// that the mean is of several copied 7 x 7 patches, not of the one a pixel lies in (on statue-one
/// radii 12 and 24 scored alike, 6 a little lower on both masked PSNR and LPIPS).
pub const CONTRAST_RADIUS: usize = 12;

/// Half the window of the grain's mean, in pixels: the grain is what a pixel adds to its 3 x 3
/// neighbourhood, the finest scale. A 7 x 7 mean keeps more of the copy as grain: with a grain of
/// 0.7 and no structure statue-one scored 20.96 / 0.305 with it against 21.08 / 0.355 at 3 x 3,
/// the other end of the same trade (bench/JOURNAL.md, 2026-12-01).
pub const GRAIN_RADIUS: usize = 1;

/// How much of a random invention is kept, scale by scale (`lower_contrast`): the grain (what each
/// pixel adds to its 3 x 3 mean) and the structure (what that mean adds to the surface's local
/// mean). Both 1: the copy as it is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contrast {
    pub grain: f32,
    pub structure: f32,
}

impl Contrast {
    /// The copy as it is.
    pub const UNCHANGED: Contrast = Contrast { grain: 1.0, structure: 1.0 };
}

/// The `fill` pixels whose invention is a random copy: all but those on a background plane
/// (`labels`, 1 + the plane's index) whose known texture repeats (`repeats`, by label: the
/// exemplar's rectification found it so, `exemplar::RectifiedFill`). A repeating texture (a
/// checkerboard, bricks: 48 of the synth rooms' 55 planes) is continued in phase with the truth
/// and keeps its contrast; grass, gravel and wood grain (none of the real captures' 173 planes)
/// are not, nor is what lies on no plane.
fn random_copies(fill: &[bool], labels: &[u8], repeats: &[bool; 256]) -> Vec<bool> {
    fill.iter().zip(labels).map(|(&f, &l)| f && !repeats[l as usize]).collect()
}

/// The exemplar's inventions `invented` in planar RGB `rgb` (w x h) tempered where they are random
/// copies (`random_copies`, by `repeats`): their contrast lowered (`lower_contrast`), then next to
/// the known colors their level taken up from those (`follow_known_colors`). `known` holds the
/// image the exemplar filled (its colors outside `invented` are the view's own and those the
/// photos gave) and the pixels whose colors count as known (not the leftovers' render).
#[allow(clippy::too_many_arguments)]
pub fn temper(
    rgb: &mut [f32],
    invented: &[bool],
    (image, known): (&[f32], &[bool]),
    surfaces: &[u8],
    repeats: &[bool; 256],
    contrast: Contrast,
    w: usize,
    h: usize,
) {
    let random = random_copies(invented, surfaces, repeats);
    if !random.iter().any(|&r| r) {
        return;
    }
    let membrane = fill_by_surface_within(
        image,
        invented,
        surfaces,
        (w, h),
        3,
        Boundary::TypicalColors,
        SurfaceWindow::Margin(MEMBRANE_MARGIN),
    );
    let weight = membrane_weights(known, w, h);
    lower_contrast(rgb, &random, surfaces, w, h, contrast);
    follow_known_colors(rgb, &random, (&membrane, &weight), w, h);
}

/// `--invention-contrast` and `--invention-structure`'s parser: a number from 0 to 1.
pub fn parse_contrast(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(v) if (0.0..=1.0).contains(&v) => Ok(v),
        _ => Err(format!("{s} is not a contrast from 0 to 1")),
    }
}

/// How far (pixels) from the colors a view knows around its inventions (those the photos gave
/// and those outside the fill) an invention's local mean follows them: its weight on the
/// membrane of those colors is exp(-d / MEMBRANE_FADE), d the distance to the nearest known
/// pixel. A hole's points the photos saw but the transfer missed (the completed depth's error
/// moves the edge of what they saw) lie within a few pixels of the found colors: on statue-one's
/// training views 8742 of the 24324 seen-elsewhere hole pixels were invented, all within 12 px of
/// a transferred pixel (4178 within 1.5), and there the membrane scored 21.39 dB against the
/// photos where the copies' mean scored 20.57; farther in, both are guesses of a surface no photo
/// saw and scored alike (bench/JOURNAL.md, 2026-12-03, 16:08). Held out, statue-one rose from
/// 21.15 / 0.357 to 21.41 / 0.352 (a flat weight of one half scored 21.39, a fade of 16 px 21.41,
/// the membrane everywhere 21.36); the other real scenes moved by -0.04 to +0.02 dB.
pub const MEMBRANE_FADE: f32 = 8.0;

/// How far (pixels) around the inventions' bounding box the membrane takes its boundary values
/// (`SurfaceWindow::Margin`): four fades, past which a pixel's weight on it is under 2 %. Solved
/// in the fill window instead (the box grown by its own size), the per-surface membranes took 15
/// of the 22 s of color transfer of the statue `images_2` removal on lavapipe; at 32 px the
/// transfer took 10.6-11.6 s. The real scenes' hand runs (seed 0; cup-two-of-three seed 2) scored
/// as in the fill window, masked PSNR / LPIPS (the fill window's in brackets): statue-one 21.39 /
/// 0.347 (21.40 / 0.350), statue-two-of-three 22.08 / 0.295 (22.08 / 0.296), cup-one 27.13 /
/// 0.1445 (27.13 / 0.1445), cup-two-of-three 28.24 / 0.1306 (28.24 / 0.1307); at 16 px within
/// 0.01 dB and 0.001 of those (bench/JOURNAL.md, 2026-12-04, 07:20).
pub const MEMBRANE_MARGIN: usize = 32;

/// Each pixel's weight on the membrane: exp(-d / MEMBRANE_FADE), d its distance to the nearest
/// `known` pixel (1 on a known pixel, 0 where none is known).
fn membrane_weights(known: &[bool], w: usize, h: usize) -> Vec<f32> {
    distance_to(known, w, h).into_iter().map(|d| (-d / MEMBRANE_FADE).exp()).collect()
}

/// Moves each `invented` pixel v of planar RGB `rgb` (w x h) to m + structure (g - m) + grain (v -
/// g) (`contrast`), per channel: m the mean of the invented pixels on its surface (`surfaces`; 0 =
/// none, one group of its own) in the (2 CONTRAST_RADIUS + 1)^2 window around it, g that mean in
/// the (2 GRAIN_RADIUS + 1)^2 window. Other pixels are untouched.
fn lower_contrast(rgb: &mut [f32], invented: &[bool], surfaces: &[u8], w: usize, h: usize, contrast: Contrast) {
    let n = w * h;
    if contrast == Contrast::UNCHANGED {
        return;
    }
    let mut labels: Vec<u8> = (0..n).filter(|&p| invented[p]).map(|p| surfaces[p]).collect();
    labels.sort_unstable();
    labels.dedup();
    for s in labels {
        let on_s: Vec<bool> = (0..n).map(|p| invented[p] && surfaces[p] == s).collect();
        // the pixel itself is in both windows: the means are of at least one pixel
        let local = masked_box_mean(rgb, &on_s, w, h, 3, CONTRAST_RADIUS);
        let grain = masked_box_mean(rgb, &on_s, w, h, 3, GRAIN_RADIUS);
        for p in (0..n).filter(|&p| on_s[p]) {
            for c in 0..3 {
                let (m, g) = (local[c * n + p], grain[c * n + p]);
                let v = &mut rgb[c * n + p];
                *v = m + contrast.structure * (g - m) + contrast.grain * (*v - g);
            }
        }
    }
}

/// Shifts each `invented` pixel of planar RGB `rgb` (w x h) toward the known colors: by weight
/// (membrane - l), `membrane` planar RGB, the harmonic fill of each surface from its known pixels
/// (what `--inpainter harmonic` fills), `weight` the pixel's weight on it (`membrane_weights`), l
/// the mean of the invented pixels of every surface in the (2 CONTRAST_RADIUS + 1)^2 window around
/// it. The inventions' level moves as a whole; what a pixel adds to l (its grain, and its
/// surface's tone against its neighbours') stays. Replacing each surface's own local mean by the
/// membrane instead scored statue-one 21.24 / 0.360 against 21.41 / 0.352 this way
/// (bench/JOURNAL.md, 2026-12-03, 16:08).
fn follow_known_colors(rgb: &mut [f32], invented: &[bool], (membrane, weight): (&[f32], &[f32]), w: usize, h: usize) {
    let n = w * h;
    let local = masked_box_mean(rgb, invented, w, h, 3, CONTRAST_RADIUS);
    for p in (0..n).filter(|&p| invented[p]) {
        for c in 0..3 {
            rgb[c * n + p] += weight[p] * (membrane[c * n + p] - local[c * n + p]);
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

    /// Against brute-force window means: each invented pixel is the mean of its surface's invented
    /// pixels in the wide window, plus `structure` times what their mean in its 3 x 3 window adds
    /// to it, plus `grain` times what the pixel adds to that; everything else, and a second
    /// surface's part beside it, keeps or takes only its own values.
    #[test]
    fn each_invented_pixel_keeps_its_grain_and_structure_by_their_contrasts() {
        let (w, h) = (40, 34);
        let contrast = Contrast { grain: 0.6, structure: 0.3 };
        let n = w * h;
        let invented: Vec<bool> = (0..n).map(|p| (3..37).contains(&(p % w)) && (3..31).contains(&(p / w))).collect();
        // two surfaces meet inside the invented part
        let surfaces: Vec<u8> = (0..n).map(|p| if p % w < 20 { 1 } else { 2 }).collect();
        let before: Vec<f32> = (0..3 * n).map(|i| noise(i % n, i / n)).collect();
        let mut after = before.clone();
        lower_contrast(&mut after, &invented, &surfaces, w, h, contrast);
        let mean = |p: usize, c: usize, r: usize| {
            let (x, y) = ((p % w) as i64, (p / w) as i64);
            let window: Vec<f32> = (0..n)
                .filter(|&q| ((q % w) as i64 - x).abs() <= r as i64 && ((q / w) as i64 - y).abs() <= r as i64)
                .filter(|&q| invented[q] && surfaces[q] == surfaces[p])
                .map(|q| before[c * n + q])
                .collect();
            window.iter().sum::<f32>() / window.len() as f32
        };
        for p in 0..n {
            for c in 0..3 {
                let v = before[c * n + p];
                let want = if !invented[p] {
                    v
                } else {
                    let (m, g) = (mean(p, c, CONTRAST_RADIUS), mean(p, c, GRAIN_RADIUS));
                    m + contrast.structure * (g - m) + contrast.grain * (v - g)
                };
                let got = after[c * n + p];
                assert!((got - want).abs() < 1e-5, "pixel ({}, {}) channel {c}: {got} against {want}", p % w, p / w);
            }
        }
    }

    /// On white noise around a constant (the truth a copy does not know), the error of the fill
    /// falls with the contrasts by the closed form of independent pixels: a mean of k pixels
    /// varies by 1/k of the noise's variance, so with the structure dropped (g - m) the error is
    /// grain^2 (1 - 1/9) of the noise's, plus 1/625 for m and the wide mean's covariances (under
    /// 0.2 % here, away from the borders); with the grain dropped the 3 x 3 mean's 1/9 stays.
    /// A constant part stays exactly as it is whatever the contrasts.
    #[test]
    fn an_uncorrelated_texture_comes_closer_to_the_mean_by_scale_and_a_constant_stays() {
        let (w, h) = (64, 64);
        let n = w * h;
        let invented = vec![true; n];
        let surfaces = vec![1u8; n];
        let truth = 0.5;
        let mut rng = crate::rng::Rng::new(7);
        let textured: Vec<f32> = (0..3 * n).map(|_| truth + 0.1 * rng.normal() as f32).collect();
        // away from the borders, where every window is whole
        let inner = |i: usize| (12..w - 12).contains(&(i % n % w)) && (12..h - 12).contains(&(i % n / w));
        let mse = |img: &[f32]| {
            let e: Vec<f32> = (0..3 * n).filter(|&i| inner(i)).map(|i| (img[i] - truth).powi(2)).collect();
            e.iter().sum::<f32>() / e.len() as f32
        };
        for (contrast, want) in [
            (Contrast { grain: 0.5, structure: 0.0 }, 0.25 * 8.0 / 9.0),
            (Contrast { grain: 0.0, structure: 1.0 }, 1.0 / 9.0),
            (Contrast { grain: 0.5, structure: 0.5 }, 0.25),
        ] {
            let mut damped = textured.clone();
            lower_contrast(&mut damped, &invented, &surfaces, w, h, contrast);
            let ratio = mse(&damped) / mse(&textured);
            assert!(
                (ratio - want).abs() < 0.03 * want,
                "{contrast:?}: mean square error ratio {ratio}, {want} expected"
            );
        }

        let mut constant = vec![0.3; 3 * n];
        lower_contrast(&mut constant, &invented, &surfaces, w, h, Contrast { grain: 0.0, structure: 0.0 });
        assert!(constant.iter().all(|&v| (v - 0.3).abs() < 1e-6));
    }

    /// Next to the known colors an invention's local mean is theirs, far from them the copies':
    /// a surface known as 0.2 left of x = 20 and invented right of it as copies of noise around
    /// 0.6. The membrane of a constant boundary is that constant (the closed form of a harmonic
    /// fill), so each invented pixel's 3 x 3 mean (with the structure dropped, its local mean)
    /// is 0.6 + exp(-d / MEMBRANE_FADE) (0.2 - 0.6) up to the local mean's noise, d = x - 19 (the
    /// chamfer distance is exact along a row), and what a pixel adds to its 3 x 3 mean is kept.
    #[test]
    fn next_to_the_known_colors_the_inventions_mean_follows_the_membrane_and_keeps_its_grain() {
        let (w, h) = (96, 48);
        let n = w * h;
        let invented: Vec<bool> = (0..n).map(|p| p % w >= 20).collect();
        let known: Vec<bool> = invented.iter().map(|&i| !i).collect();
        let surfaces = vec![1u8; n];
        let mut rng = crate::rng::Rng::new(11);
        let image: Vec<f32> = (0..3 * n).map(|i| if invented[i % n] { 0.0 } else { 0.2 }).collect();
        let copies: Vec<f32> =
            (0..3 * n).map(|i| if invented[i % n] { 0.6 + 0.1 * rng.normal() as f32 } else { 0.2 }).collect();
        let membrane = fill_by_surface_within(
            &image,
            &invented,
            &surfaces,
            (w, h),
            3,
            Boundary::TypicalColors,
            SurfaceWindow::Margin(MEMBRANE_MARGIN),
        );
        assert!(membrane.iter().all(|&v| (v - 0.2).abs() < 1e-4), "the membrane of a constant boundary");
        let weight = membrane_weights(&known, w, h);
        let mut after = copies.clone();
        lower_contrast(&mut after, &invented, &surfaces, w, h, Contrast { grain: 1.0, structure: 0.0 });
        follow_known_colors(&mut after, &invented, (&membrane, &weight), w, h);
        let mean3 = |img: &[f32], p: usize, c: usize| {
            let (x, y) = (p % w, p / w);
            let q: Vec<usize> = (y.saturating_sub(1)..(y + 2).min(h))
                .flat_map(|yy| (x.saturating_sub(1)..(x + 2).min(w)).map(move |xx| yy * w + xx))
                .filter(|&q| invented[q])
                .collect();
            q.iter().map(|&q| img[c * n + q]).sum::<f32>() / q.len() as f32
        };
        let mut worst: f32 = 0.0;
        for p in (0..n).filter(|&p| invented[p] && (2..h - 2).contains(&(p / w)) && p % w < w - 2) {
            let d = (p % w - 19) as f32;
            let want = 0.6 + (-d / MEMBRANE_FADE).exp() * (0.2 - 0.6);
            for c in 0..3 {
                // the local mean of 25 x 25 noisy copies (sd 0.1) is off by about 0.004
                let got = copies[c * n + p] - mean3(&copies, p, c) + want;
                assert!(
                    (after[c * n + p] - got).abs() < 0.02,
                    "x {} channel {c}: {} against {got}",
                    p % w,
                    after[c * n + p]
                );
                worst = worst.max((after[c * n + p] - got).abs());
            }
        }
        assert!(worst > 0.0);
        // beside the known colors the column's level is nearly theirs, far from them the copies'
        // (the mean of 144 grains of sd 0.094 is off by about 0.008)
        let column = |x: usize| (0..3 * h).map(|i| after[(i / h) * n + (i % h) * w + x]).sum::<f32>() / (3 * h) as f32;
        let beside = 0.2 + 0.4 * (1.0 - (-1.0 / MEMBRANE_FADE).exp());
        assert!((column(20) - beside).abs() < 0.025, "beside the known colors: {} against {beside}", column(20));
        assert!((column(w - 1) - 0.6).abs() < 0.025, "far from them: {}", column(w - 1));
        // the known pixels are untouched
        assert!((0..n).filter(|&p| known[p]).all(|p| after[p] == 0.2));
    }
}
