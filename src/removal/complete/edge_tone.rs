//! The invented parts of a view's fill brought to the tone of what surrounds them.
//!
//! The exemplar copies texture from elsewhere on the same surface, and where the light falls off
//! across that surface the copied patches bring their own brightness with them: on the cup
//! composites the invented pixels of the training views' targets sat 1-10 levels darker than the
//! photos, and 37 in the worst view (bench/JOURNAL.md, 2026-11-30). Each invented part (an
//! 8-connected component) is shifted, channel by channel, by the median difference across its
//! edge: a known pixel minus the invented pixel beside it.
//!
//! Pairs across the edge, not the two sides' own medians: a texture continued in phase (a
//! checkerboard, bricks, the desk's grain) differs across the edge only where the edge crosses one
//! of the texture's own lines, so the median difference stays 0 there, while the median of a
//! checkerboard's band is one of its two colours (synth room one fell 2 dB with band medians). A
//! constant offset comes out exactly where the edge's rises and falls balance (a ramp across a
//! whole part), and within one pixel's step of the surroundings otherwise.
//!
//! A CPU pass: a few thousand edge pairs per view and a median, beside the GPU inpainting it
//! follows.

use crate::image_ops::components;

/// Fewest edge pairs a part needs before its tone is trusted (per channel: one pair each).
const MIN_EDGE_PAIRS: usize = 3;

/// Shifts each connected part of `invented` on one surface (`surfaces`: the labels of
/// `surfaces::surfaces_around`, 0 = none) in planar RGB `rgb` (w x h, values in [0, 1]) by the
/// per-channel median of (neighbour - pixel) over its 4-neighbour pairs whose neighbour is in
/// `lends` (the pixels whose colours are not invented: found in the photos, or outside the hole)
/// and on the same surface (any, for a part on none): a kept object beside the hole lends no
/// tone to the floor. Parts with fewer than MIN_EDGE_PAIRS such pairs stay as they are. Returns
/// how many parts moved.
pub fn match_edge_tone(
    rgb: &mut [f32],
    invented: &[bool],
    lends: &[bool],
    surfaces: &[u8],
    w: usize,
    h: usize,
) -> usize {
    let n = w * h;
    let mut moved = 0;
    let mut labels: Vec<u8> = (0..n).filter(|&p| invented[p]).map(|p| surfaces[p]).collect();
    labels.sort_unstable();
    labels.dedup();
    let parts = labels.into_iter().flat_map(|s| {
        let on_s: Vec<bool> = (0..n).map(|p| invented[p] && surfaces[p] == s).collect();
        components(&on_s, w, h).into_iter().map(move |part| (s, part))
    });
    for (s, part) in parts.collect::<Vec<_>>() {
        let mut diffs: [Vec<f32>; 3] = Default::default();
        for &p in &part {
            let (x, y) = (p % w, p / w);
            let neighbours = [
                (x > 0).then(|| p - 1),
                (x + 1 < w).then(|| p + 1),
                (y > 0).then(|| p - w),
                (y + 1 < h).then(|| p + w),
            ];
            let same_surface = |q: usize| s == 0 || surfaces[q] == s;
            for q in neighbours.into_iter().flatten().filter(|&q| lends[q] && !invented[q] && same_surface(q)) {
                for (c, d) in diffs.iter_mut().enumerate() {
                    d.push(rgb[c * n + q] - rgb[c * n + p]);
                }
            }
        }
        if diffs[0].len() < MIN_EDGE_PAIRS {
            continue;
        }
        let shift = diffs.map(|mut d| median(&mut d));
        for &p in &part {
            for (c, s) in shift.iter().enumerate() {
                let v = &mut rgb[c * n + p];
                *v = (*v + s).clamp(0.0, 1.0);
            }
        }
        moved += 1;
    }
    moved
}

/// The median of `v` (an even count: the mean of the two middle values, so that edges that rise
/// and fall alike cancel); `v` is reordered.
fn median(v: &mut [f32]) -> f32 {
    let (mid, odd) = (v.len() / 2, v.len() % 2 == 1);
    let (below, upper, _) = v.select_nth_unstable_by(mid, f32::total_cmp);
    if odd {
        return *upper;
    }
    let lower = below.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    0.5 * (lower + *upper)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A planar RGB image of `f` per pixel and channel.
    fn image(w: usize, h: usize, f: impl Fn(usize, usize, usize) -> f32) -> Vec<f32> {
        (0..3).flat_map(|c| (0..w * h).map(move |p| (c, p))).map(|(c, p)| f(p % w, p / w, c)).collect()
    }

    fn inside(x: usize, y: usize, x0: usize, x1: usize, y0: usize, y1: usize) -> bool {
        (x0..x1).contains(&x) && (y0..y1).contains(&y)
    }

    fn max_error(a: &[f32], b: &[f32]) -> f32 {
        a.iter().zip(b).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max)
    }

    /// Two parts on a ramp, each invented a different constant too dark or too bright, come back
    /// to the ramp exactly. The second is a thin column between two leftover strips that lend
    /// nothing: if they did, their brightness would outvote its top and bottom edges.
    #[test]
    fn a_constant_offset_on_a_ramp_comes_out_exactly() {
        let (w, h) = (48, 32);
        let truth = image(w, h, |x, y, c| 0.2 + 0.01 * x as f32 + 0.005 * y as f32 + 0.05 * c as f32);
        let part_a = |x, y| inside(x, y, 6, 16, 8, 20);
        let part_b = |x, y| inside(x, y, 26, 30, 6, 26);
        let leftover = |x, y| inside(x, y, 24, 26, 6, 26) || inside(x, y, 30, 32, 6, 26);
        let invented: Vec<bool> = (0..w * h).map(|p| part_a(p % w, p / w) || part_b(p % w, p / w)).collect();
        let lends: Vec<bool> = (0..w * h).map(|p| !invented[p] && !leftover(p % w, p / w)).collect();
        let mut rgb = image(w, h, |x, y, c| {
            let t = truth[c * w * h + y * w + x];
            if part_a(x, y) {
                t - 0.12
            } else if part_b(x, y) {
                t + 0.07 * (c as f32 - 1.0)
            } else if leftover(x, y) {
                1.0
            } else {
                t
            }
        });
        let moved = match_edge_tone(&mut rgb, &invented, &lends, &vec![0; w * h], w, h);
        assert_eq!(moved, 2);
        let on_parts = |img: &[f32]| -> Vec<f32> {
            (0..3).flat_map(|c| (0..w * h).filter(|&p| invented[p]).map(move |p| img[c * w * h + p])).collect()
        };
        let err = max_error(&on_parts(&rgb), &on_parts(&truth));
        assert!(err < 1e-5, "parts off their ramp by {err}");
    }

    /// A checkerboard continued in phase into the part keeps it; the same part invented 0.2 too
    /// bright comes back to the checkerboard, where the two sides' own medians would move it by a
    /// whole square's contrast.
    #[test]
    fn a_checkerboard_continued_in_phase_keeps_its_squares() {
        let (w, h) = (40, 40);
        let square = 4;
        let checker = image(w, h, |x, y, _| if (x / square + y / square) % 2 == 0 { 0.2 } else { 0.8 });
        // edges inside the squares (x 5..15 starts and ends mid-square), as a continued texture's are
        let part = |x, y| inside(x, y, 5, 15, 9, 23);
        let invented: Vec<bool> = (0..w * h).map(|p| part(p % w, p / w)).collect();
        let lends: Vec<bool> = invented.iter().map(|&i| !i).collect();

        let mut same = checker.clone();
        match_edge_tone(&mut same, &invented, &lends, &vec![0; w * h], w, h);
        assert_eq!(same, checker);

        let mut bright: Vec<f32> =
            checker.iter().enumerate().map(|(i, &v)| if invented[i % (w * h)] { v + 0.2 } else { v }).collect();
        match_edge_tone(&mut bright, &invented, &lends, &vec![0; w * h], w, h);
        let err = max_error(&bright, &checker);
        assert!(err < 1e-6, "checkerboard off by {err}");
    }

    /// A part with fewer than MIN_EDGE_PAIRS lending neighbours stays as it is.
    #[test]
    fn a_part_without_lending_neighbours_stays() {
        let (w, h) = (8, 8);
        let invented: Vec<bool> = (0..w * h).map(|p| p % w < 4).collect();
        let lends = vec![false; w * h];
        let mut rgb = vec![0.5; 3 * w * h];
        assert_eq!(match_edge_tone(&mut rgb, &invented, &lends, &vec![0; w * h], w, h), 0);
        assert!(rgb.iter().all(|&v| v == 0.5));
    }

    /// A floor part (surface 1) invented 0.1 too dark, with a bright kept object (surface 2) along
    /// three of its four sides, takes the floor's tone from its one floor side: the object's
    /// pairs, the majority, would have lifted it toward the object's white.
    #[test]
    fn a_kept_object_beside_the_part_lends_no_tone() {
        let (w, h) = (32, 32);
        let part = |x, y| inside(x, y, 10, 20, 10, 20);
        let object = |x, y| inside(x, y, 8, 22, 8, 22) && !part(x, y) && y < 20;
        let invented: Vec<bool> = (0..w * h).map(|p| part(p % w, p / w)).collect();
        let surfaces: Vec<u8> = (0..w * h).map(|p| if object(p % w, p / w) { 2 } else { 1 }).collect();
        let lends: Vec<bool> = invented.iter().map(|&i| !i).collect();
        let mut rgb = image(w, h, |x, y, c| {
            if object(x, y) {
                1.0
            } else if part(x, y) {
                0.3 + 0.1 * c as f32
            } else {
                0.4 + 0.1 * c as f32
            }
        });
        match_edge_tone(&mut rgb, &invented, &lends, &surfaces, w, h);
        let err = (0..3)
            .flat_map(|c| (0..w * h).filter(|&p| invented[p]).map(move |p| (c, p)))
            .map(|(c, p)| (rgb[c * w * h + p] - (0.4 + 0.1 * c as f32)).abs())
            .fold(0.0, f32::max);
        assert!(err < 1e-6, "floor part off the floor's tone by {err}");
    }
}
