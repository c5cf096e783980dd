//! Photo-consistent depth for the hole. The completed depth of a hole comes from the render and
//! the planes around it, and both sit in front of the true surface: a blended depth weights the
//! front of a surface's Gaussians most, and the Gaussians left behind a removed object were
//! constrained by few views. On the bench scenes the hole's depth was 1.7-2.3 % too near (median;
//! 90 % of its pixels more than 1.4 %), which shifts a transferred texel by a pixel or two in the
//! other views: the transfer then copies the checkerboard out of phase, and the patch Gaussians
//! land off the surface.
//!
//! Where two or more other views saw a hole pixel's surface, their photos must agree on its
//! color at the right depth. `correct_hole_depth` first sweeps one factor for the whole hole (the
//! bias is shared, and a factor fitted on thousands of pixels does not chase noise or flat color),
//! then each such pixel searches near it with the costs of a 7x7 window (plane-sweep stereo with
//! cost aggregation, on the views' own photos). With the hole's factor alone, on the removal bench's
//! scene one: the hole's depth error went from -1.9 % to -0.03 % (median), and the transferred
//! colors from 24.7 to 27.7 dB against the exact truth.

use super::source_views::{back_project, sees, SourceView};
use crate::image_ops::sample_bilinear_pixels;
use crate::scene::Camera;

/// The factor found for one view's hole depth.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct DepthScale {
    /// The factor of the whole hole (1: unchanged); each pixel two views saw has its own near it.
    pub scale: f64,
    /// Hole pixels whose surface at least two other views saw (the pixels the cost sums).
    pub pixels: usize,
    /// Mean color variance across those views (RGB summed), at the completed depth and after
    /// the per-pixel factors.
    pub cost_before: f64,
    pub cost_after: f64,
}

impl DepthScale {
    /// No correction.
    pub fn unchanged() -> DepthScale {
        DepthScale { scale: 1.0, pixels: 0, cost_before: f64::NAN, cost_after: f64::NAN }
    }
}

/// Relative depth range searched either side of the completed depth.
pub const SCALE_RANGE: f64 = 0.05;
/// Candidates either side of 1 (0.1 % apart).
const SCALE_STEPS: i32 = 50;
/// Fewer consistent pixels than this leave the depth as it is.
const MIN_PIXELS: usize = 64;
/// The per-pixel search: relative range either side of the hole's factor, candidates either
/// side, and the window (radius in pixels, fewest scored pixels) whose costs decide.
const LOCAL_RANGE: f64 = 0.03;
const LOCAL_STEPS: i32 = 15;
const WINDOW_RADIUS: usize = 3;
const MIN_WINDOW_PIXELS: usize = 8;
/// Hole pixels no two views saw: the distance (4-connected pixels) over which the nearest scored
/// pixel's correction fades out.
const FADE_PIXELS: usize = 8;

/// The spread of the colors several photos show of one point: sums and sums of squares, so that
/// adding a color allocates nothing.
#[derive(Clone, Default)]
pub struct ColorSpread {
    k: usize,
    sum: [f64; 3],
    squares: [f64; 3],
}

impl ColorSpread {
    pub fn add(&mut self, rgb: [f32; 3]) {
        for c in 0..3 {
            let v = rgb[c] as f64;
            self.sum[c] += v;
            self.squares[c] += v * v;
        }
        self.k += 1;
    }

    /// Color variance (RGB summed); None with fewer than two colors.
    pub fn variance(&self) -> Option<f64> {
        if self.k < 2 {
            return None;
        }
        let k = self.k as f64;
        Some((0..3).map(|c| (self.squares[c] / k - (self.sum[c] / k).powi(2)).max(0.0)).sum())
    }
}

/// Scales `add_samples` projects at once.
const LANDINGS: usize = 16;

/// Where the point a + s b (camera frame, `line` = [a, b]) lands in `camera`'s image for each s
/// of `scales` (at most `LANDINGS`): `Camera::camera_point_landing` for all the scales in one
/// loop the compiler vectorizes, NaN where it lands nowhere.
#[inline(always)]
fn landings(camera: &Camera, line: &[[f64; 3]; 2], scales: &[f64]) -> [(f64, f64); LANDINGS] {
    let [a, b] = line;
    let mut out = [(f64::NAN, f64::NAN); LANDINGS];
    for (o, &scale) in out.iter_mut().zip(scales) {
        let (x, y, lands) =
            camera.camera_point_landing([a[0] + scale * b[0], a[1] + scale * b[1], a[2] + scale * b[2]]);
        *o = if lands { (x, y) } else { (f64::NAN, f64::NAN) };
    }
    out
}

/// The hole pixels of one view that two or more other views saw, with those views: pixel i is
/// `pixels[i]`, its views `views[starts[i]..starts[i + 1]]`, in one flat list since the cost
/// reads them ~130 times per pixel.
struct SeenPixels<'a> {
    sources: &'a [SourceView<'a>],
    /// The sources' photos, one [r, g, b] per pixel (`interleave_rgb`).
    photos: &'a [Vec<[f32; 3]>],
    pixels: Vec<usize>,
    views: Vec<u32>,
    /// Per entry of `views`: the pixel's point in that view's camera frame at depth factor s is
    /// a + s b (the pixel's ray is a line in every frame), as [a, b].
    lines: Vec<[[f64; 3]; 2]>,
    starts: Vec<usize>,
}

impl SeenPixels<'_> {
    /// Color variance (RGB summed) across the views that still see pixel `i`'s point off their
    /// holes at its depth times `scale`; None with fewer than two.
    fn variance(&self, i: usize, scale: f64) -> Option<f64> {
        let mut spread = [ColorSpread::default()];
        self.add_samples(i, &[scale], &mut spread);
        spread[0].variance()
    }

    /// Adds to `spreads[k]` the color of pixel `i`'s point at its depth times `scales[k]` in each
    /// view that sees it there off its hole. View after view, every scale at once: a view's
    /// camera, hole and photo are looked up once for all the scales, and its samples lie close
    /// together in its photo. Each spread still takes the views in their order: the sums of one
    /// scale at a time, bit for bit (the stage 3.6 -> 2.9 s on the statue `images_2`, ~130 scales
    /// per pixel). Where a chunk of scales lands is found first, in a loop the compiler
    /// vectorizes (`landings`), then each landing is sampled: this function's samples in a
    /// `--no-refine` removal of the statue `images_2` fell by a fifth (bench/JOURNAL.md,
    /// 2026-12-03, 06:31).
    fn add_samples(&self, i: usize, scales: &[f64], spreads: &mut [ColorSpread]) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2, checked just above
            return unsafe { self.add_samples_avx2(i, scales, spreads) };
        }
        self.add_samples_portable(i, scales, spreads)
    }

    /// `add_samples` compiled for AVX2 too: four scales' landings at once, the same IEEE
    /// operations (no fused multiply-add), so the same sums.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn add_samples_avx2(&self, i: usize, scales: &[f64], spreads: &mut [ColorSpread]) {
        self.add_samples_portable(i, scales, spreads)
    }

    #[inline(always)]
    fn add_samples_portable(&self, i: usize, scales: &[f64], spreads: &mut [ColorSpread]) {
        let range = self.starts[i]..self.starts[i + 1];
        for (&j, line) in self.views[range.clone()].iter().zip(&self.lines[range]) {
            let s = &self.sources[j as usize];
            let (sw, sh) = (s.camera.width as usize, s.camera.height as usize);
            let photo = &self.photos[j as usize];
            for (scales, spreads) in scales.chunks(LANDINGS).zip(spreads.chunks_mut(LANDINGS)) {
                let landed = landings(s.camera, line, scales);
                for (spread, &(x, y)) in spreads.iter_mut().zip(&landed) {
                    if x.is_nan() || s.hole[y as usize * sw + x as usize] {
                        continue;
                    }
                    spread.add(sample_bilinear_pixels(photo, sw, sh, x, y));
                }
            }
        }
    }

    /// The variance of pixel `i` at each of `scales` (`variance`), into `out`; `spreads` is
    /// scratch of the same length.
    fn variances(&self, i: usize, scales: &[f64], spreads: &mut [ColorSpread], out: &mut [Option<f64>]) {
        spreads.iter_mut().for_each(|s| *s = ColorSpread::default());
        self.add_samples(i, scales, spreads);
        for (o, s) in out.iter_mut().zip(spreads.iter()) {
            *o = s.variance();
        }
    }

    /// Mean variance over all pixels (those that have one, in pixel order; infinity when none
    /// does) at each of `scales`. Pixel by pixel, all scales at once: a pixel's samples at
    /// neighbouring scales lie close together in each photo, where a sweep of every pixel per
    /// scale went through all the photos' sampled pixels once per scale (the photo depth stage
    /// 4.7 -> 3.0 s on the statue `images_2`, the same sums).
    fn mean_variances(&self, scales: &[f64]) -> Vec<f64> {
        // -0.0: where `Sum for f64` starts, as the per-scale sums did before
        let mut sums = vec![(-0.0f64, 0usize); scales.len()];
        let mut spreads: Vec<ColorSpread> = scales.iter().map(|_| ColorSpread::default()).collect();
        let mut values = vec![None; scales.len()];
        for i in 0..self.pixels.len() {
            self.variances(i, scales, &mut spreads, &mut values);
            for (sum, v) in sums.iter_mut().zip(&values) {
                if let Some(v) = v {
                    sum.0 += v;
                    sum.1 += 1;
                }
            }
        }
        sums.iter().map(|&(sum, k)| if k == 0 { f64::INFINITY } else { sum / k as f64 }).collect()
    }
}

/// The candidate of least cost, placed between its neighbours by a parabola through the three.
fn parabola_minimum(scales: &[f64], costs: &[f64]) -> Option<f64> {
    let best = (0..costs.len()).filter(|&i| costs[i].is_finite()).min_by(|&a, &b| costs[a].total_cmp(&costs[b]))?;
    let mut scale = scales[best];
    if best > 0 && best + 1 < costs.len() {
        let (l, m, r) = (costs[best - 1], costs[best], costs[best + 1]);
        let curvature = l - 2.0 * m + r;
        if curvature.is_finite() && curvature > 0.0 {
            scale += 0.5 * (l - r) / curvature * (scales[1] - scales[0]);
        }
    }
    Some(scale)
}

/// Corrects the hole depth of view `target` in place so that the other views' photos agree on
/// the hole's colors (see the module comment): one factor for the whole hole, then per pixel
/// within `LOCAL_RANGE` of it, from the costs of a window around the pixel (two removed objects
/// leave holes at different distances, with different biases). Pixels no two views saw take the
/// correction of the nearest one that was, fading out over `FADE_PIXELS` (so the surface stays
/// continuous where it is measured, and is left alone where nothing was seen twice). `photos`
/// are the sources' photos as `interleave_rgb` stores them.
pub fn correct_hole_depth(
    target: usize,
    camera: &Camera,
    depth: &mut [f32],
    hole: &[bool],
    sources: &[SourceView],
    photos: &[Vec<[f32; 3]>],
    tolerance: f64,
) -> DepthScale {
    let w = camera.width as usize;
    let (mut pixels, mut views, mut lines, mut starts) = (Vec::new(), Vec::new(), Vec::new(), vec![0]);
    let origin = camera.center();
    for p in (0..depth.len()).filter(|&p| hole[p] && depth[p] > 0.0 && depth[p].is_finite()) {
        let world = back_project(camera, p, depth[p] as f64);
        let start = views.len();
        for (j, s) in sources.iter().enumerate().filter(|&(j, _)| j != target) {
            if sees(s, world, tolerance).is_some() {
                let (a, at_world) = (s.camera.to_camera(origin), s.camera.to_camera(world));
                views.push(j as u32);
                lines.push([a, std::array::from_fn(|c| at_world[c] - a[c])]);
            }
        }
        if views.len() - start >= 2 {
            pixels.push(p);
            starts.push(views.len());
        } else {
            views.truncate(start);
            lines.truncate(start);
        }
    }
    let seen = SeenPixels { sources, photos, pixels, views, lines, starts };
    let n = seen.pixels.len();
    let unchanged = DepthScale { pixels: n, ..DepthScale::unchanged() };
    if n < MIN_PIXELS {
        return unchanged;
    }
    // the hole's factor
    let scales: Vec<f64> =
        (-SCALE_STEPS..=SCALE_STEPS).map(|k| 1.0 + SCALE_RANGE * k as f64 / SCALE_STEPS as f64).collect();
    // every candidate: searched coarse to fine (every 5th, then around the best two) the mean
    // cost chose another basin on a cup view (1.0 instead of 1.044), where it has several
    let costs = seen.mean_variances(&scales);
    let cost_before = costs[SCALE_STEPS as usize];
    let Some(global) = parabola_minimum(&scales, &costs) else { return unchanged };
    // a minimum at the end of the range is no minimum: the cost still falls outside it (on the
    // statue's grass, towards where the views sample a smoother, farther texture)
    if (global - 1.0).abs() >= SCALE_RANGE * (1.0 - 0.5 / SCALE_STEPS as f64) {
        return DepthScale { cost_before, cost_after: cost_before, ..unchanged };
    }
    // NaN or no better: leave the depth
    if seen.mean_variances(&[global])[0].partial_cmp(&cost_before) != Some(std::cmp::Ordering::Less) {
        return DepthScale { cost_before, cost_after: cost_before, ..unchanged };
    }
    // per pixel around it: each candidate's costs summed over a window of seen pixels
    let local: Vec<f64> =
        (-LOCAL_STEPS..=LOCAL_STEPS).map(|k| global * (1.0 + LOCAL_RANGE * k as f64 / LOCAL_STEPS as f64)).collect();
    let mut spreads: Vec<ColorSpread> = local.iter().map(|_| ColorSpread::default()).collect();
    let volume: Vec<Vec<Option<f64>>> = (0..n)
        .map(|i| {
            let mut values = vec![None; local.len()];
            seen.variances(i, &local, &mut spreads, &mut values);
            values
        })
        .collect();
    let mut index = vec![usize::MAX; depth.len()];
    for (i, &p) in seen.pixels.iter().enumerate() {
        index[p] = i;
    }
    let h = depth.len() / w;
    let r = WINDOW_RADIUS as isize;
    let mut factor = vec![global; depth.len()];
    for &p in &seen.pixels {
        let (x, y) = ((p % w) as isize, (p / w) as isize);
        let mut sums = vec![(0.0, 0usize); local.len()];
        for yy in (y - r).max(0)..=(y + r).min(h as isize - 1) {
            for xx in (x - r).max(0)..=(x + r).min(w as isize - 1) {
                let i = index[yy as usize * w + xx as usize];
                if i == usize::MAX {
                    continue;
                }
                for (k, c) in volume[i].iter().enumerate() {
                    if let Some(c) = c {
                        sums[k].0 += c;
                        sums[k].1 += 1;
                    }
                }
            }
        }
        // a candidate counts only where most of the window could score it
        let most = sums.iter().map(|s| s.1).max().unwrap_or(0);
        let costs: Vec<f64> = sums
            .iter()
            .map(|&(c, m)| if m >= MIN_WINDOW_PIXELS && 2 * m >= most { c / m as f64 } else { f64::INFINITY })
            .collect();
        if let Some(s) = parabola_minimum(&local, &costs) {
            factor[p] = s;
        }
    }
    // the rest of the hole: the factor of the nearest scored pixel, fading to 1 over
    // `FADE_PIXELS`. Away from what two views saw it is a guess, and there it pushed the tail of
    // the never-seen depths behind the surface (floaters on the bench scenes: 137 -> 94 mean).
    let mut queue: std::collections::VecDeque<usize> = seen.pixels.iter().copied().collect();
    let mut reached: Vec<bool> = index.iter().map(|&i| i != usize::MAX).collect();
    let mut origin = factor.clone();
    let mut distance = vec![0usize; depth.len()];
    for p in (0..depth.len()).filter(|&p| !reached[p]) {
        factor[p] = 1.0;
    }
    while let Some(p) = queue.pop_front() {
        let (x, y) = (p % w, p / w);
        let next =
            [(x > 0).then(|| p - 1), (x + 1 < w).then(|| p + 1), (y > 0).then(|| p - w), (y + 1 < h).then(|| p + w)];
        for q in next.into_iter().flatten() {
            if hole[q] && !reached[q] {
                reached[q] = true;
                origin[q] = origin[p];
                distance[q] = distance[p] + 1;
                let keep = (1.0 - distance[q] as f64 / FADE_PIXELS as f64).max(0.0);
                factor[q] = 1.0 + (origin[q] - 1.0) * keep;
                queue.push_back(q);
            }
        }
    }
    let cost_after = {
        let v: Vec<f64> = (0..n).filter_map(|i| seen.variance(i, factor[seen.pixels[i]])).collect();
        v.iter().sum::<f64>() / v.len().max(1) as f64
    };
    for (p, d) in depth.iter_mut().enumerate().filter(|(p, _)| hole[*p]) {
        *d = (*d as f64 * factor[p]) as f32;
    }
    DepthScale { scale: global, pixels: n, cost_before, cost_after }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// `add_samples` (the landings of a chunk of scales at once, compiled for AVX2 where the CPU
    /// has it) adds the same colors in the same order as one scale at a time through
    /// `Camera::camera_point_to_image` and `sample_bilinear_pixels`, bit for bit: lines through
    /// three views at 101 scales (chunks and a remainder), points that land outside an image,
    /// behind a camera or on a hole.
    #[test]
    fn landings_chunk_by_chunk_add_what_one_scale_at_a_time_adds() {
        let mut rng = Rng::new(5);
        let (w, h) = (64usize, 48usize);
        let cameras: Vec<Camera> = (0..3)
            .map(|k| {
                let eye = [-1.0 + k as f64, 0.2 * k as f64, -3.0];
                Camera::look_at("s", w as u32, h as u32, 60.0, eye, [0.0, 0.0, 1.0], [0.0, -1.0, 0.0])
            })
            .collect();
        let holes: Vec<Vec<bool>> = (0..3).map(|_| (0..w * h).map(|_| rng.uniform() < 0.1).collect()).collect();
        let planar: Vec<Vec<f32>> = (0..3).map(|_| (0..3 * w * h).map(|_| rng.uniform() as f32).collect()).collect();
        let photos: Vec<Vec<[f32; 3]>> = planar.iter().map(|p| crate::image_ops::interleave_rgb(p, w * h)).collect();
        let flat = vec![1.0f32; w * h];
        let sources: Vec<SourceView> = (0..3)
            .map(|k| SourceView {
                camera: &cameras[k],
                photo: &planar[k],
                hole: &holes[k],
                depth: &flat,
                alpha: &flat,
                photo_colors: Default::default(),
            })
            .collect();
        // 40 pixels' world lines, each seen by all three views; some reach behind the cameras
        let (mut views, mut lines, mut starts) = (Vec::new(), Vec::new(), vec![0]);
        for _ in 0..40 {
            let world = [rng.range(-3.0, 3.0), rng.range(-2.0, 2.0), rng.range(-4.0, 3.0)];
            let origin = [rng.range(-0.5, 0.5), rng.range(-0.5, 0.5), -3.5];
            for (j, cam) in cameras.iter().enumerate() {
                let (a, at) = (cam.to_camera(origin), cam.to_camera(world));
                views.push(j as u32);
                lines.push([a, std::array::from_fn(|c| at[c] - a[c])]);
            }
            starts.push(views.len());
        }
        let seen = SeenPixels { sources: &sources, photos: &photos, pixels: vec![0; 40], views, lines, starts };
        let scales: Vec<f64> = (0..101).map(|k| 0.5 + k as f64 * 0.01).collect();
        // where each scale lands, to the bit
        for (k, line) in seen.lines.iter().enumerate() {
            let camera = sources[seen.views[k] as usize].camera;
            for chunk in scales.chunks(LANDINGS) {
                for (&(x, y), &scale) in landings(camera, line, chunk).iter().zip(chunk) {
                    let [a, b] = line;
                    let pc = [a[0] + scale * b[0], a[1] + scale * b[1], a[2] + scale * b[2]];
                    match camera.camera_point_to_image(pc) {
                        Some((ex, ey, _)) => assert_eq!((x.to_bits(), y.to_bits()), (ex.to_bits(), ey.to_bits())),
                        None => assert!(x.is_nan() && y.is_nan()),
                    }
                }
            }
        }
        let (mut sampled, mut skipped) = (0, 0);
        for i in 0..40 {
            let mut chunked = vec![ColorSpread::default(); scales.len()];
            seen.add_samples(i, &scales, &mut chunked);
            let mut single = vec![ColorSpread::default(); scales.len()];
            for (spread, &scale) in single.iter_mut().zip(&scales) {
                for k in seen.starts[i]..seen.starts[i + 1] {
                    let (s, [a, b]) = (&sources[seen.views[k] as usize], seen.lines[k]);
                    let pc = [a[0] + scale * b[0], a[1] + scale * b[1], a[2] + scale * b[2]];
                    let Some((x, y, _)) = s.camera.camera_point_to_image(pc) else {
                        skipped += 1;
                        continue;
                    };
                    if s.hole[y as usize * w + x as usize] {
                        skipped += 1;
                        continue;
                    }
                    sampled += 1;
                    spread.add(sample_bilinear_pixels(&photos[seen.views[k] as usize], w, h, x, y));
                }
            }
            for (c, s) in chunked.iter().zip(&single) {
                assert_eq!(
                    (c.k, c.sum.map(f64::to_bits), c.squares.map(f64::to_bits)),
                    (s.k, s.sum.map(f64::to_bits), s.squares.map(f64::to_bits))
                );
            }
        }
        assert!(sampled > 2000 && skipped > 500, "{sampled} samples, {skipped} off the images or on holes");
    }
}
