//! After a removal: the held-out views rendered from the original and the edited scene, and, for a
//! `cogeo synth` dataset at its own resolution, both scored against its exact ground truth (the
//! held-out renders inside the removed objects' silhouettes, the fill's completed depth).

use super::ViewResult;
use crate::eval::{synth_depth_error, synth_metrics, SynthMetrics};
use crate::gpu::Gpu;
use crate::render::render_rgb;
use crate::scene::undistort::Undistortion;
use crate::scene::{Camera, GaussianScene};
use anyhow::Result;
use std::path::Path;

pub struct HeldOut {
    pub before: Vec<Vec<f32>>,
    pub after: Vec<Vec<f32>>,
}

/// Renders the held-out `cameras` from the `original` and the `edited` scene.
pub fn render_held_out(
    gpu: &Gpu,
    original: &GaussianScene,
    edited: &GaussianScene,
    cameras: &[Camera],
    background: [f32; 3],
) -> Result<HeldOut> {
    Ok(HeldOut {
        before: render_rgb(gpu, original, cameras, background)?,
        after: render_rgb(gpu, edited, cameras, background)?,
    })
}

/// The removal scored against a synth dataset's ground truth (report.json's last two entries).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct GroundTruthScores {
    /// The held-out renders after removal inside the removed objects' silhouettes.
    pub held_out_vs_ground_truth: Option<SynthMetrics>,
    /// The completed depth of the edited views' fill against the true depth.
    pub fill_depth_vs_ground_truth: Option<DepthError>,
}

#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct DepthError {
    pub abs_rel: f64,
    pub rmse: f64,
}

/// Scores a removal of `labels` on the dataset at `data` when it is a `cogeo synth` dataset (both
/// entries None otherwise): `test_cameras` (with the undistortion of their photos, `frames`)
/// with their renders after removal, the edited `cameras` with their `views`. The fill's depth
/// is scored only where the photos needed no undistortion (the true depth is not resampled).
pub fn score_against_synth(
    data: &Path,
    labels: &[u8],
    test_cameras: &[Camera],
    frames: &[Option<&Undistortion>],
    held_out: &HeldOut,
    cameras: &[Camera],
    views: &[ViewResult],
) -> Result<GroundTruthScores> {
    let depths: Vec<Vec<f32>> = views.iter().map(|v| v.depth.clone()).collect();
    let fills: Vec<Vec<bool>> = views.iter().map(|v| v.fill.clone()).collect();
    let pinhole = frames.iter().all(|f| f.is_none());
    Ok(GroundTruthScores {
        held_out_vs_ground_truth: synth_metrics(data, test_cameras, frames, &held_out.after, labels)?,
        fill_depth_vs_ground_truth: match pinhole {
            true => synth_depth_error(data, labels, cameras, &depths, &fills)?
                .map(|(abs_rel, rmse)| DepthError { abs_rel, rmse }),
            false => None,
        },
    })
}
