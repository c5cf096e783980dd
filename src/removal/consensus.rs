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
//! invention covers that point (its fill, within `tolerance` of its completed depth). A view whose
//! mean squared deviation from the per-point median exceeds LEAVE_OUT times the variance of its
//! own invented colors disagrees with the rest (independent textures deviate by about their
//! variance); its invented pixels then count only where the view owns the surface in the patch.

use crate::scene::Camera;

/// Deviation from the consensus, as a share of the view's own texture variance, above which a
/// view's inventions are left to their owners.
pub const LEAVE_OUT: f64 = 0.5;
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

/// Per view, its deviation from the consensus over its own texture variance (None where too few
/// of its invented pixels are shared), and whether its inventions were left to their owners.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ViewConsensus {
    pub deviation: Option<f64>,
    pub left_out: bool,
}

/// The loss weights of every view (1, or 0 at the invented pixels a disagreeing view does not own)
/// and what was measured.
pub fn loss_masks(views: &[ConsensusView], tolerance: f32) -> (Vec<Vec<f32>>, Vec<ViewConsensus>) {
    // the views are independent
    let mut verdicts = vec![ViewConsensus { deviation: None, left_out: false }; views.len()];
    crate::parallel::for_each_item(&mut verdicts, &mut |_, _| {}, |i, verdict| *verdict = judge(views, i, tolerance));
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

/// The color of `o` where it invented the surface point `world`, if it did.
fn invention_at(o: &ConsensusView, world: [f64; 3], tolerance: f32) -> Option<[f32; 3]> {
    let (q, z) = o.camera.pixel_of(world)?;
    let hw = o.invented.len();
    let d = o.depth[q] as f64;
    (o.invented[q] && d > 0.0 && (z - d).abs() <= d * tolerance as f64).then(|| [0, 1, 2].map(|c| o.rgb[c * hw + q]))
}

fn judge(views: &[ConsensusView], vi: usize, tolerance: f32) -> ViewConsensus {
    let v = &views[vi];
    let (w, hw) = (v.camera.width as usize, v.invented.len());
    let color = |p: usize| [0, 1, 2].map(|c| v.rgb[c * hw + p]);
    let (mut deviation, mut shared) = (0.0f64, 0usize);
    let mut others: Vec<[f32; 3]> = Vec::with_capacity(views.len());
    for p in (0..hw).filter(|&p| v.invented[p] && v.depth[p] > 0.0 && v.depth[p].is_finite()) {
        let world = v.camera.pixel_point(p % w, p / w, v.depth[p] as f64);
        others.clear();
        others.extend(
            views.iter().enumerate().filter(|&(j, _)| j != vi).filter_map(|(_, o)| invention_at(o, world, tolerance)),
        );
        if others.len() < MIN_OTHERS {
            continue;
        }
        let mine = color(p);
        others.push(mine);
        for (c, &m) in mine.iter().enumerate() {
            let mut channel: Vec<f32> = others.iter().map(|o| o[c]).collect();
            let mid = channel.len() / 2;
            let median = *channel.select_nth_unstable_by(mid, f32::total_cmp).1;
            deviation += ((m - median) as f64).powi(2);
        }
        shared += 1;
    }
    // the variance of the view's own invented colors, summed over the channels
    let invented: Vec<usize> = (0..hw).filter(|&p| v.invented[p]).collect();
    let variance: f64 = (0..3)
        .map(|c| {
            let values = invented.iter().map(|&p| v.rgb[c * hw + p] as f64);
            let mean = values.clone().sum::<f64>() / invented.len().max(1) as f64;
            values.map(|x| (x - mean).powi(2)).sum::<f64>() / invented.len().max(1) as f64
        })
        .sum();
    if shared == 0 {
        return ViewConsensus { deviation: None, left_out: false };
    }
    // a smooth invention that agrees stays; 1e-4 is a color step of about 0.006
    let ratio = deviation / shared as f64 / (variance + 1e-4);
    ViewConsensus { deviation: Some(ratio), left_out: ratio > LEAVE_OUT }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three fronto-parallel views of the plane z = 3, each inventing the same square of it. a and b
    /// invent one checkerboard fixed to the plane (they agree point by point); c invents a
    /// checkerboard of its own pixel grid with another period, and owns only the left half of its
    /// square. c disagrees and keeps only what it owns; a and b keep everything.
    #[test]
    fn a_view_whose_invention_disagrees_keeps_only_what_it_owns() {
        let cam =
            |name: &str, x: f64| Camera::look_at(name, 40, 40, 60.0, [x, 0.0, 0.0], [x, 0.0, 3.0], [0.0, -1.0, 0.0]);
        let cams = [cam("a", 0.0), cam("b", 0.1), cam("c", -0.1)];
        let square: Vec<bool> =
            (0..1600).map(|i| (10..30).contains(&(i % 40)) && (10..30).contains(&(i / 40))).collect();
        let depth = vec![3.0f32; 1600];
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
        let owned = [&all, &all, &left];
        let views: Vec<ConsensusView> = (0..3)
            .map(|i| ConsensusView {
                camera: &cams[i],
                rgb: &images[i],
                depth: &depth,
                invented: square.clone(),
                owned: owned[i],
            })
            .collect();
        let (masks, verdicts) = loss_masks(&views, 0.03);
        println!("{verdicts:?}");
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
}
