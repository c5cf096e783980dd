//! Structure before texture: where one surface holds two regions of clearly different color that
//! run into the hole (a path across a lawn, a rug on a floor), the regions are continued straight
//! through the hole before any texture is copied, and the exemplar then fills each continuation
//! from its own region's texture only (`split_surfaces`, used by
//! `exemplar::ExemplarFill::fill_rectified` for what it synthesizes in the image).
//!
//! The exemplar alone matches patches by color and depth: it carries what runs into the hole only
//! as far as its patches reach, and across a wide hole the region that matches the smooth first
//! estimate best wins: on a receding lawn with a path across a hole three times the path's width,
//! lawn filled 0.90 of the path's continuation (`tests/exemplar.rs`).
//!
//! The regions: the surface's known pixels within BAND of the hole, their color smoothed over
//! SMOOTH_RADIUS (the grain of grass or gravel averages out, a path's edge stays), split in two by
//! 2-means; a split counts only when the two means lie SEPARATION standard deviations apart along
//! the line through them (two halves of one Gaussian spread lie at most about 2.7 apart; on the
//! statue's lawn alone, with its leaves, up to 3.1), at least MIN_APART apart in color and
//! MIN_HUE_DEGREES in hue, and each region holds MIN_SHARE of those pixels. Every known pixel of
//! the surface takes the nearer mean.
//! The continuation: the edges between the regions near the hole must run along one direction
//! (the structure tensor of the region map, coherence at least MIN_COHERENCE: a band or a border,
//! not blobs); the line through each hole pixel along it runs both ways to the hole's edge, and
//! the pixel takes the region both ends land on, or the nearer end's. (Lines in every direction,
//! voting by their length, let the many long crossings of the region around a band outvote the
//! few short ones along it.) Hole pixels whose line leaves the surface both ways take the region
//! nearest to them.
//!
//! A CPU pass over each surface's pixels in the exemplar's window, beside the GPU synthesis
//! (0.5-0.7 s of the statue `images_2` removal's 25 views, whose holes' windows are nearly the
//! whole image; 15 ms over cup-one's 18 views); textures that repeat (a
//! checkerboard, `exemplar::RectifiedFill::repeats`) are continued in phase by the rectified
//! synthesis and are left whole. On the benchmarks no path crosses a hole, and the step changes
//! nothing measurable there (none of the synth rooms' surfaces splits; on the real-photo scenes
//! within 0.01 dB); without the hue criterion the statue's shade edges and the pixels on no
//! plane split too, and cost statue-two-of-three 0.05 dB (bench/JOURNAL.md, 2026-12-02, 18:57).
//! On the statue capture itself the path behind the statue stays broken: the capture's training
//! renders the path there at the hedge's depth, both lie on one far plane, and that plane's
//! pixels around the hole hold three colors (hedge, lawn, path), which two regions do not
//! separate.

use super::surfaces::fill_window;
use crate::image_ops::{bounding_box, crop, distance_within, masked_box_mean};
use std::collections::VecDeque;

/// Half the window the colors are smoothed over before the split, in pixels.
const SMOOTH_RADIUS: usize = 3;
/// The known pixels within this many pixels of the hole decide the split.
const BAND: f32 = 16.0;
/// Fewest band pixels for a split.
const MIN_BAND_PIXELS: usize = 64;
/// The two means must lie this many standard deviations (pooled, along the line through them) apart.
const SEPARATION: f64 = 3.0;
/// And this far apart in color (RGB, Euclidean): the grass's light and dark patches are not a path.
const MIN_APART: f64 = 0.2;
/// And this far apart in hue: the angle between the two mean colors as RGB vectors, in degrees.
/// Light and dark grass differ mostly in brightness (5 degrees on the statue capture), its grey
/// path and the lawn beside it in color too (12 degrees); shaded and sunlit lawn on
/// statue-two-of-three lie 10-12 degrees apart and still split (to no measurable effect).
const MIN_HUE_DEGREES: f64 = 8.0;
/// Each region's share of the band at least.
const MIN_SHARE: f64 = 0.1;
/// The edges between the regions must run along one direction this coherently (the structure
/// tensor's (l1 - l2) / (l1 + l2)): a band or a border, not scattered blobs.
const MIN_COHERENCE: f64 = 0.5;
/// 2-means iterations.
const ITERATIONS: usize = 10;

/// The two regions of the `known` pixels of a surface and their continuation into its `hole`
/// (w x h, `image` planar RGB): per pixel 1 or 2 (0 off both), or None where the surface does not
/// split in two (module comment).
pub fn continue_regions(image: &[f32], hole: &[bool], known: &[bool], w: usize, h: usize) -> Option<Vec<u8>> {
    let n = w * h;
    let near = distance_within(hole, w, h, BAND);
    let band: Vec<usize> = (0..n).filter(|&p| known[p] && near[p] <= BAND).collect();
    if band.len() < MIN_BAND_PIXELS || !hole.iter().any(|&m| m) {
        return None;
    }
    // each known pixel's color, the mean of the known pixels in its window
    let smooth = masked_box_mean(image, known, w, h, 3, SMOOTH_RADIUS);
    let means = two_means(&smooth, &band, n)?;
    let region = |p: usize| {
        let d = |m: &[f64; 3]| (0..3).map(|c| (smooth[c * n + p] as f64 - m[c]).powi(2)).sum::<f64>();
        if d(&means[0]) <= d(&means[1]) {
            1
        } else {
            2
        }
    };
    let mut labels: Vec<u8> = (0..n).map(|p| if known[p] { region(p) } else { 0 }).collect();
    let direction = edge_direction(&labels, &band, w, h)?;
    let nearest = nearest_region(&labels, hole, w, h);
    let continued = continue_along(&labels, hole, direction, w, h);
    for p in (0..n).filter(|&p| hole[p]) {
        labels[p] = continued[p].unwrap_or(nearest[p]);
    }
    Some(labels)
}

/// First label of the regions `split_surfaces` gives (the surfaces' own labels are 1 + a plane's
/// index, at most 32 planes).
pub const FIRST_REGION_LABEL: u8 = 128;

/// The surface labels (`labels`, 0 = none, a group of its own) of an image (w x h, planar RGB)
/// whose `fill` is to be synthesized, with every surface that splits in two regions
/// (`continue_regions`; the surface's known pixels are those outside `fill` and `avoid`) given
/// two labels of its own from FIRST_REGION_LABEL on, in the fill and around it (as far as the
/// exemplar's window reaches); surfaces in `keep` (a texture that repeats, continued in phase
/// already) stay whole.
pub fn split_surfaces(
    image: &[f32],
    fill: &[bool],
    avoid: &[bool],
    labels: &[u8],
    keep: &[bool; 256],
    w: usize,
    h: usize,
) -> Vec<u8> {
    let mut out = labels.to_vec();
    let Some(b) = bounding_box(fill, w) else { return out };
    // The exemplar reads labels only in its window around the fill (`surfaces::fill_window`);
    // grown by the band and its smoothing, every pixel of that window is classified here as over
    // the whole image, at the window's cost, not the image's
    let reach = BAND.ceil() as usize + SMOOTH_RADIUS + 1;
    let win = fill_window(b, w, h).grown(reach, reach, w, h);
    let (cw, ch) = (win.width(), win.height());
    let cn = cw * ch;
    let at = |k: usize| win.pixel(k, w);
    let window = crop(image, w, h, 3, win);
    let mut present: Vec<u8> = (0..cn).filter(|&k| fill[at(k)]).map(|k| labels[at(k)]).collect();
    present.sort_unstable();
    present.dedup();
    let mut next = FIRST_REGION_LABEL as u16;
    for s in present.into_iter().filter(|&s| !keep[s as usize]) {
        if next + 1 > u8::MAX as u16 {
            break; // no two labels left
        }
        let hole: Vec<bool> = (0..cn).map(|k| fill[at(k)] && labels[at(k)] == s).collect();
        let known: Vec<bool> = (0..cn).map(|k| !fill[at(k)] && !avoid[at(k)] && labels[at(k)] == s).collect();
        let Some(regions) = continue_regions(&window, &hole, &known, cw, ch) else { continue };
        for k in (0..cn).filter(|&k| regions[k] != 0 && (hole[k] || known[k])) {
            out[at(k)] = (next + regions[k] as u16 - 1) as u8;
        }
        next += 2;
    }
    out
}

/// The two means of the `pixels`' colors (planar RGB of n pixels) by 2-means, started from a split
/// at the median along the colors' principal axis; None unless they lie SEPARATION pooled
/// standard deviations (along the line through them), MIN_APART and MIN_HUE_DEGREES apart and
/// each holds MIN_SHARE of the pixels.
fn two_means(colors: &[f32], pixels: &[usize], n: usize) -> Option<[[f64; 3]; 2]> {
    let color = |p: usize| [0, 1, 2].map(|c| colors[c * n + p] as f64);
    let k = pixels.len() as f64;
    let mean = pixels.iter().fold([0.0; 3], |a, &p| {
        let v = color(p);
        [a[0] + v[0] / k, a[1] + v[1] / k, a[2] + v[2] / k]
    });
    // the principal axis, by power iteration on the covariance
    let mut cov = [[0.0f64; 3]; 3];
    for &p in pixels {
        let v = color(p);
        for i in 0..3 {
            for j in 0..3 {
                cov[i][j] += (v[i] - mean[i]) * (v[j] - mean[j]) / k;
            }
        }
    }
    let mut axis = [1.0, 1.0, 1.0];
    for _ in 0..20 {
        let next = [0, 1, 2].map(|i| (0..3).map(|j| cov[i][j] * axis[j]).sum::<f64>());
        let norm = next.iter().map(|x| x * x).sum::<f64>().sqrt();
        if norm <= 1e-30 {
            return None; // one flat color
        }
        axis = next.map(|x| x / norm);
    }
    let along = |p: usize| (0..3).map(|c| (color(p)[c] - mean[c]) * axis[c]).sum::<f64>();
    let mut projections: Vec<f64> = pixels.iter().map(|&p| along(p)).collect();
    let mid = projections.len() / 2;
    let median = *projections.select_nth_unstable_by(mid, f64::total_cmp).1;
    let mut side: Vec<bool> = pixels.iter().map(|&p| along(p) > median).collect();
    let mut means = [[0.0; 3]; 2];
    for _ in 0..ITERATIONS {
        let mut sums = [[0.0; 3]; 2];
        let mut counts = [0usize; 2];
        for (&p, &s) in pixels.iter().zip(&side) {
            let v = color(p);
            (0..3).for_each(|c| sums[s as usize][c] += v[c]);
            counts[s as usize] += 1;
        }
        if counts.contains(&0) {
            return None;
        }
        means = [0, 1].map(|r| sums[r].map(|s| s / counts[r] as f64));
        let d = |v: &[f64; 3], m: &[f64; 3]| (0..3).map(|c| (v[c] - m[c]).powi(2)).sum::<f64>();
        side = pixels.iter().map(|&p| d(&color(p), &means[1]) < d(&color(p), &means[0])).collect();
    }
    // the spread along the line through the two means: texture across it does not hide a split
    let apart = (0..3).map(|c| (means[0][c] - means[1][c]).powi(2)).sum::<f64>().sqrt();
    let unit = [0, 1, 2].map(|c| (means[1][c] - means[0][c]) / apart.max(1e-12));
    let (mut within, mut counts) = (0.0, [0usize; 2]);
    for (&p, &s) in pixels.iter().zip(&side) {
        let v = color(p);
        within += (0..3).map(|c| (v[c] - means[s as usize][c]) * unit[c]).sum::<f64>().powi(2);
        counts[s as usize] += 1;
    }
    let pooled = (within / k).sqrt();
    let share = counts.iter().map(|&c| c as f64 / k).fold(1.0, f64::min);
    // the angle between the two mean colors: light and shade of one material scale its color
    let norm = |m: &[f64; 3]| m.iter().map(|x| x * x).sum::<f64>().sqrt().max(1e-12);
    let cos = (0..3).map(|c| means[0][c] * means[1][c]).sum::<f64>() / (norm(&means[0]) * norm(&means[1]));
    let hue_apart = cos.clamp(-1.0, 1.0).acos().to_degrees() >= MIN_HUE_DEGREES;
    (apart >= SEPARATION * pooled.max(1e-6) && apart >= MIN_APART && hue_apart && share >= MIN_SHARE).then_some(means)
}

/// The direction (radians) along which the edges between the regions run in the `band`, the
/// structure tensor of the region map's gradient; None where the edges do not share one
/// (coherence under MIN_COHERENCE: blobs, not a band or a border).
fn edge_direction(labels: &[u8], band: &[usize], w: usize, h: usize) -> Option<f64> {
    let (mut jxx, mut jxy, mut jyy) = (0.0f64, 0.0f64, 0.0f64);
    let value = |q: usize| (labels[q] == 1) as u8 as f64;
    for &p in band {
        let (x, y) = (p % w, p / w);
        if x == 0 || y == 0 || x + 1 >= w || y + 1 >= h {
            continue;
        }
        let (l, r, u, d) = (p - 1, p + 1, p - w, p + w);
        if [l, r, u, d].iter().any(|&q| labels[q] == 0) {
            continue;
        }
        let (gx, gy) = ((value(r) - value(l)) / 2.0, (value(d) - value(u)) / 2.0);
        (jxx, jxy, jyy) = (jxx + gx * gx, jxy + gx * gy, jyy + gy * gy);
    }
    let trace = jxx + jyy;
    if trace <= 0.0 {
        return None;
    }
    let coherence = ((jxx - jyy).powi(2) + 4.0 * jxy * jxy).sqrt() / trace;
    // the gradient's direction, and the edges across it
    let across = 0.5 * (2.0 * jxy).atan2(jxx - jyy);
    (coherence >= MIN_COHERENCE).then_some(across + std::f64::consts::FRAC_PI_2)
}

/// Per hole pixel, the region that the line through it along `direction` continues: the region
/// both ends of the line (where it leaves the hole) land on, or the nearer end's where they
/// differ; None where neither end lands on a region (off the surface or the image). One march
/// per line, not per pixel: every hole pixel a march crosses takes that line's answer, so the
/// pass costs about one visit per hole pixel however wide the hole (per pixel it was the hole's
/// width times its area).
fn continue_along(labels: &[u8], hole: &[bool], direction: f64, w: usize, h: usize) -> Vec<Option<u8>> {
    let (dx, dy) = (direction.cos(), direction.sin());
    // steps of at most one pixel along the larger axis: no pixel of the line is skipped
    let step = 1.0 / dx.abs().max(dy.abs());
    let mut out: Vec<Option<u8>> = vec![None; w * h];
    let mut done = vec![false; w * h];
    let mut crossed: Vec<(usize, f64)> = Vec::new();
    for p in (0..w * h).filter(|&p| hole[p]) {
        if done[p] {
            continue;
        }
        let (x, y) = ((p % w) as f64 + 0.5, (p / w) as f64 + 0.5);
        crossed.clear();
        crossed.push((p, 0.0));
        // the hole pixels the line crosses each way, and the region where it leaves the hole
        let mut end = |sign: f64| {
            let mut t = step;
            loop {
                let (px, py) = (x + sign * t * dx, y + sign * t * dy);
                if px < 0.0 || py < 0.0 || px >= w as f64 || py >= h as f64 {
                    return None;
                }
                let q = py as usize * w + px as usize;
                if !hole[q] {
                    return (labels[q] != 0).then_some((labels[q], sign * t));
                }
                crossed.push((q, sign * t));
                t += step;
            }
        };
        let (ahead, behind) = (end(1.0), end(-1.0));
        for &(q, t) in &crossed {
            if done[q] {
                continue;
            }
            done[q] = true;
            out[q] = match (ahead, behind) {
                (Some((a, ta)), Some((b, tb))) => Some(if a == b || ta - t <= t - tb { a } else { b }),
                (Some((a, _)), None) | (None, Some((a, _))) => Some(a),
                (None, None) => None,
            };
        }
    }
    out
}

/// Per hole pixel, the region of the nearest labelled pixel (4-connected steps through the hole;
/// 0 where none is reached).
fn nearest_region(labels: &[u8], hole: &[bool], w: usize, h: usize) -> Vec<u8> {
    let mut out = labels.to_vec();
    let mut queue: VecDeque<usize> = (0..w * h).filter(|&p| labels[p] != 0).collect();
    while let Some(p) = queue.pop_front() {
        let (x, y) = (p % w, p / w);
        let next =
            [(x > 0).then(|| p - 1), (x + 1 < w).then(|| p + 1), (y > 0).then(|| p - w), (y + 1 < h).then(|| p + w)];
        for q in next.into_iter().flatten() {
            if hole[q] && out[q] == 0 {
                out[q] = out[p];
                queue.push_back(q);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic grain in [-1, 1] (a hash of the pixel and channel).
    fn grain(p: usize, c: usize) -> f32 {
        let mut x = (p as u32).wrapping_mul(2654435761) ^ (c as u32 + 1).wrapping_mul(40503);
        x ^= x >> 13;
        x = x.wrapping_mul(0x5bd1e995);
        x ^= x >> 15;
        (x % 2001) as f32 / 1000.0 - 1.0
    }

    /// 120 x 90: a grainy green field with a grey band (rows 40..52) across it, and a hole
    /// (columns 50..70, rows 10..80) over the band's middle.
    fn field_with_band() -> (Vec<f32>, Vec<bool>, Vec<bool>, usize, usize) {
        let (w, h) = (120, 90);
        let n = w * h;
        let band = |p: usize| (40..52).contains(&(p / w));
        let (green, grey) = ([0.35f32, 0.45, 0.2], [0.5f32, 0.5, 0.5]);
        let image = (0..3 * n)
            .map(|i| {
                let p = i % n;
                let base = if band(p) { grey[i / n] } else { green[i / n] };
                base + 0.08 * grain(p, i / n)
            })
            .collect();
        let hole: Vec<bool> = (0..n).map(|p| (50..70).contains(&(p % w)) && (10..80).contains(&(p / w))).collect();
        let known = hole.iter().map(|&m| !m).collect();
        (image, hole, known, w, h)
    }

    #[test]
    fn a_band_across_a_field_runs_straight_through_the_hole() {
        let (image, hole, known, w, h) = field_with_band();
        let labels = continue_regions(&image, &hole, &known, w, h).expect("the band splits from the field");
        let band_label = labels[45 * w + 10];
        let field_label = labels[20 * w + 10];
        assert_ne!(band_label, field_label);
        // the band's own rows inside the hole are band, the rest field; a row at each of the
        // band's edges may go either way (the smoothing blurs the edge by its radius)
        let mut wrong = 0;
        let mut total = 0;
        for p in (0..w * h).filter(|&p| hole[p]) {
            let row = p / w;
            if row == 39 || row == 40 || row == 51 || row == 52 {
                continue;
            }
            let want = if (40..52).contains(&row) { band_label } else { field_label };
            total += 1;
            wrong += (labels[p] != want) as usize;
        }
        assert!(wrong * 100 <= total, "{wrong} of {total} hole pixels in the wrong region");
    }

    #[test]
    fn a_grainy_field_alone_does_not_split() {
        let (w, h) = (120, 90);
        let n = w * h;
        let image: Vec<f32> = (0..3 * n).map(|i| [0.35f32, 0.45, 0.2][i / n] + 0.08 * grain(i % n, i / n)).collect();
        let hole: Vec<bool> = (0..n).map(|p| (50..70).contains(&(p % w)) && (10..80).contains(&(p / w))).collect();
        let known: Vec<bool> = hole.iter().map(|&m| !m).collect();
        assert!(continue_regions(&image, &hole, &known, w, h).is_none());
    }

    #[test]
    fn a_surface_that_splits_gets_two_labels_and_one_that_repeats_stays_whole() {
        let (image, hole, _, w, h) = field_with_band();
        let (labels, avoid) = (vec![1u8; w * h], vec![false; w * h]);
        let mut keep = [false; 256];
        let split = split_surfaces(&image, &hole, &avoid, &labels, &keep, w, h);
        let (band, field) = (split[45 * w + 60], split[20 * w + 60]);
        assert_eq!([band.min(field), band.max(field)], [FIRST_REGION_LABEL, FIRST_REGION_LABEL + 1]);
        assert_eq!(split[45 * w + 10], band, "the band outside the hole has the band's label");
        keep[1] = true;
        assert_eq!(split_surfaces(&image, &hole, &avoid, &labels, &keep, w, h), labels);
    }
}
