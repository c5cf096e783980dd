//! Between fusion and refinement: which invented pixels each edited view's refinement loss keeps.
//!
//! An invented pixel is one the inpainter synthesized (in the view's fill, no photo's color
//! transferred to it). Where the views invent the same thing, as on the bench's checkerboards,
//! refining towards all of them averages out each view's small errors. Where each view invents a
//! texture of its own, as the lawn behind the statue, the refinement averages 25 different
//! textures into a smooth patch, although the fusion gave each surface point one owner's texture.
//!
//! So each view's inventions are compared with the others' at the same surface points: each
//! invented pixel is back-projected at its completed depth and looked up in every other view whose
//! invention covers that point (its fill, within `tolerance` of its completed depth). A view
//! disagrees with the rest (its invented pixels then count only where the view owns the surface
//! in the patch) when, by either of two measures, its mean squared deviation from the per-point
//! median exceeds LEAVE_OUT times its own variance (independent textures deviate by about their
//! variance):
//! - its colors against the variance of its invented colors: a tone of its own;
//! - its detail (each color less the mean of its DETAIL_RADIUS window) against the variance of
//!   its detail: a texture of its own. Colors alone miss it where the views share a tone that
//!   varies across the hole, as the lawn running into the path behind the statue's boxes: that
//!   variance swells the measure's denominator, and views inventing grass of their own seeds
//!   scored 0.45-0.48, kept their whole invention and blurred the patch (bench/JOURNAL.md,
//!   2026-12-02, 06:24).

use crate::image_ops::masked_box_mean;
use crate::scene::Camera;

/// Deviation from the consensus, as a share of the view's own variance (of its colors, or of
/// their detail), above which a view's inventions are left to their owners.
pub const LEAVE_OUT: f64 = 0.5;
/// Half-width of the window whose mean of invented colors a pixel's detail is taken against: 5 x 5
/// holds a grass blade's or a wood grain line's contrast, not the tone across the hole.
const DETAIL_RADIUS: usize = 2;
/// Other views that must share a surface point for it to have a consensus.
const MIN_OTHERS: usize = 2;

/// One edited view's completion, as the consensus sees it.
pub struct ConsensusView<'a> {
    pub camera: &'a Camera,
    /// The completed image (planar RGB): the refinement's target.
    pub rgb: &'a [f32],
    /// Completed camera-z depth.
    pub depth: &'a [f32],
    /// Synthesized pixels: the fill minus what a photo gave.
    pub invented: Vec<bool>,
    /// Pixels whose point the fusion kept (`fuse::Patched::owned`).
    pub owned: &'a [bool],
}

/// Per view, its deviation from the consensus over its own variance, in color and in detail
/// (None where too few of its invented pixels are shared), and whether its inventions were left
/// to their owners.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ViewConsensus {
    pub deviation: Option<f64>,
    pub detail_deviation: Option<f64>,
    pub left_out: bool,
}

/// The loss weights of every view (1, or 0 at the invented pixels a disagreeing view does not own)
/// and what was measured.
pub fn loss_masks(views: &[ConsensusView], tolerance: f32) -> (Vec<Vec<f32>>, Vec<ViewConsensus>) {
    let colors: Vec<&[f32]> = views.iter().map(|v| v.rgb).collect();
    let details: Vec<Vec<f32>> = views.iter().map(detail).collect();
    let details: Vec<&[f32]> = details.iter().map(Vec::as_slice).collect();
    // the views are independent
    let mut verdicts = vec![ViewConsensus { deviation: None, detail_deviation: None, left_out: false }; views.len()];
    crate::parallel::for_each_item(&mut verdicts, &mut |_, _| {}, |i, verdict| {
        let [deviation, detail_deviation] = deviations_from_others(views, [&colors, &details], i, tolerance);
        let left_out = [deviation, detail_deviation].iter().any(|d| d.is_some_and(|d| d > LEAVE_OUT));
        *verdict = ViewConsensus { deviation, detail_deviation, left_out };
    });
    let masks = views
        .iter()
        .zip(&verdicts)
        .map(|(v, verdict)| {
            (0..v.invented.len())
                .map(|p| if verdict.left_out && v.invented[p] && !v.owned[p] { 0.0 } else { 1.0 })
                .collect()
        })
        .collect();
    (masks, verdicts)
}

/// `o`'s pixel where it invented the surface point `world`, if it did.
fn invented_pixel(o: &ConsensusView, world: [f64; 3], tolerance: f32) -> Option<usize> {
    let (q, z) = o.camera.pixel_of(world)?;
    let d = o.depth[q] as f64;
    (o.invented[q] && d > 0.0 && (z - d).abs() <= d * tolerance as f64).then_some(q)
}

/// Each invented pixel's color less the mean of the invented colors in its DETAIL_RADIUS window
/// (planar RGB; 0 off the inventions).
fn detail(v: &ConsensusView) -> Vec<f32> {
    let (w, hw) = (v.camera.width as usize, v.invented.len());
    let h = hw / w;
    let means = masked_box_mean(v.rgb, &v.invented, w, h, 3, DETAIL_RADIUS);
    (0..3 * hw).map(|i| if v.invented[i % hw] { v.rgb[i] - means[i] } else { 0.0 }).collect()
}

/// View `vi`'s mean squared deviation of each of the `measures` (per view: the colors, or their
/// detail; planar RGB) from the other views' median at the surface points it shares, over the
/// variance of its own. The points and the other views' pixels are found once for all measures.
fn deviations_from_others<const N: usize>(
    views: &[ConsensusView],
    measures: [&[&[f32]]; N],
    vi: usize,
    tolerance: f32,
) -> [Option<f64>; N] {
    let v = &views[vi];
    let (w, hw) = (v.camera.width as usize, v.invented.len());
    let (mut deviation, mut shared) = ([0.0f64; N], 0usize);
    // the other views that invented the point, and their pixel there
    let mut others: Vec<(usize, usize)> = Vec::with_capacity(views.len());
    let mut channel: Vec<f32> = Vec::with_capacity(views.len());
    for p in (0..hw).filter(|&p| v.invented[p] && v.depth[p] > 0.0 && v.depth[p].is_finite()) {
        let world = v.camera.pixel_point(p % w, p / w, v.depth[p] as f64);
        others.clear();
        others.extend(
            views
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != vi)
                .filter_map(|(j, o)| invented_pixel(o, world, tolerance).map(|q| (j, q))),
        );
        if others.len() < MIN_OTHERS {
            continue;
        }
        for (values, deviation) in measures.iter().zip(&mut deviation) {
            for c in 0..3 {
                let mine = values[vi][c * hw + p];
                channel.clear();
                channel.extend(others.iter().map(|&(j, q)| values[j][c * views[j].invented.len() + q]));
                channel.push(mine);
                let mid = channel.len() / 2;
                let median = *channel.select_nth_unstable_by(mid, f32::total_cmp).1;
                *deviation += ((mine - median) as f64).powi(2);
            }
        }
        shared += 1;
    }
    let invented: Vec<usize> = (0..hw).filter(|&p| v.invented[p]).collect();
    std::array::from_fn(|m| {
        // the variance of the view's own invented values, summed over the channels
        let own = measures[m][vi];
        let variance: f64 = (0..3)
            .map(|c| {
                let values = invented.iter().map(|&p| own[c * hw + p] as f64);
                let mean = values.clone().sum::<f64>() / invented.len().max(1) as f64;
                values.map(|x| (x - mean).powi(2)).sum::<f64>() / invented.len().max(1) as f64
            })
            .sum();
        // a smooth invention that agrees stays; 1e-4 is a color step of about 0.006
        (shared > 0).then(|| deviation[m] / shared as f64 / (variance + 1e-4))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three fronto-parallel 40 x 40 views of the plane z = 3 (a at x = 0, b at 0.1, c at -0.1),
    /// each inventing the same 20 x 20 square of its pixels.
    fn three_views_of_a_plane() -> ([Camera; 3], Vec<bool>, Vec<f32>) {
        let cam =
            |name: &str, x: f64| Camera::look_at(name, 40, 40, 60.0, [x, 0.0, 0.0], [x, 0.0, 3.0], [0.0, -1.0, 0.0]);
        let square = (0..1600).map(|i| (10..30).contains(&(i % 40)) && (10..30).contains(&(i / 40))).collect();
        ([cam("a", 0.0), cam("b", 0.1), cam("c", -0.1)], square, vec![3.0f32; 1600])
    }

    /// The consensus of `images` (planar RGB of 40 x 40) inventing `square` at `depth`, each view
    /// owning `owned[i]`.
    fn consensus_of(
        cams: &[Camera; 3],
        images: &[Vec<f32>; 3],
        square: &[bool],
        depth: &[f32],
        owned: [&[bool]; 3],
    ) -> (Vec<Vec<f32>>, Vec<ViewConsensus>) {
        let views: Vec<ConsensusView> = (0..3)
            .map(|i| ConsensusView {
                camera: &cams[i],
                rgb: &images[i],
                depth,
                invented: square.to_vec(),
                owned: owned[i],
            })
            .collect();
        let (masks, verdicts) = loss_masks(&views, 0.03);
        println!("{verdicts:?}");
        (masks, verdicts)
    }

    /// a and b invent one checkerboard fixed to the plane (they agree point by point); c invents a
    /// checkerboard of its own pixel grid with another period, and owns only the left half of its
    /// square. c disagrees and keeps only what it owns; a and b keep everything.
    #[test]
    fn a_view_whose_invention_disagrees_keeps_only_what_it_owns() {
        let (cams, square, depth) = three_views_of_a_plane();
        let image = |camera: &Camera, on_plane: bool| -> Vec<f32> {
            let value = |i: usize| {
                let (x, y) = (i % 40, i / 40);
                let cell = if on_plane {
                    // cells of 0.25 on the plane, wherever the camera is
                    let p = camera.pixel_point(x, y, 3.0);
                    ((p[0] / 0.25).floor() + (p[1] / 0.25).floor()) as i64
                } else {
                    (x / 3 + y / 3) as i64
                };
                if cell.rem_euclid(2) == 0 {
                    0.2
                } else {
                    0.8
                }
            };
            (0..3).flat_map(|_| (0..1600).map(value)).collect()
        };
        let images = [image(&cams[0], true), image(&cams[1], true), image(&cams[2], false)];
        let all = vec![true; 1600];
        let left: Vec<bool> = (0..1600).map(|i| i % 40 < 20).collect();
        let (masks, verdicts) = consensus_of(&cams, &images, &square, &depth, [&all, &all, &left]);
        for v in &verdicts[..2] {
            assert!(v.deviation.unwrap() < 0.1 && !v.left_out, "a and b agree: {v:?}");
        }
        assert!(verdicts[2].deviation.unwrap() > 1.0 && verdicts[2].left_out, "c disagrees: {:?}", verdicts[2]);
        assert!(masks[0].iter().chain(&masks[1]).all(|&w| w == 1.0));
        for p in 0..1600 {
            let expected = if square[p] && !left[p] { 0.0 } else { 1.0 };
            assert_eq!(masks[2][p], expected, "c's weight at pixel {p}");
        }
    }

    /// The three invent a tone ramp fixed to the plane (0.2 to 0.8 across the square) with a fine
    /// grain on it of +-0.05: a and b the grain of the plane (cells of 0.15), c a grain of its own
    /// pixel grid. By colors c deviates from the others by about 0.05 of its variance, which the
    /// shared ramp fills, and would keep its grain; by detail by about twice its grain's variance,
    /// and it is left to what it owns.
    #[test]
    fn a_view_sharing_the_tone_but_not_the_texture_is_left_out_by_its_detail() {
        let (cams, square, depth) = three_views_of_a_plane();
        let image = |camera: &Camera, own_grain: bool| -> Vec<f32> {
            let value = |i: usize| {
                let (x, y) = (i % 40, i / 40);
                let p = camera.pixel_point(x, y, 3.0);
                let cell =
                    if own_grain { (x + y) as i64 } else { ((p[0] / 0.15).floor() + (p[1] / 0.15).floor()) as i64 };
                let grain = if cell.rem_euclid(2) == 0 { -0.05 } else { 0.05 };
                (0.5 + 0.6 * p[0] + grain) as f32
            };
            (0..3).flat_map(|_| (0..1600).map(value)).collect()
        };
        let images = [image(&cams[0], false), image(&cams[1], false), image(&cams[2], true)];
        let all = vec![true; 1600];
        let (_, verdicts) = consensus_of(&cams, &images, &square, &depth, [&all, &all, &all]);
        for v in &verdicts[..2] {
            assert!(v.deviation.unwrap() < 0.05 && v.detail_deviation.unwrap() < 0.2 && !v.left_out, "a, b: {v:?}");
        }
        let c = &verdicts[2];
        assert!(c.deviation.unwrap() < LEAVE_OUT, "c's colors alone would keep it: {c:?}");
        assert!(c.detail_deviation.unwrap() > 1.5 && c.left_out, "c's detail disagrees: {c:?}");
    }
}
