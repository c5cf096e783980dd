//! The removal's report (report.json of `cogeo remove`): what was asked, what each stage did, and
//! how long it took.

use super::complete::Completer;
use super::prune::PruneConfig;
use super::refine::RefineReport;
use super::view::ViewReport;
use super::RemoveOptions;
use std::collections::BTreeMap;
use std::time::Instant;

#[derive(Clone, Debug, serde::Serialize)]
pub struct RemovalReport {
    pub labels: Vec<u8>,
    pub options: RemoveOptions,
    /// The models completion used (None: removal only).
    pub completion: Option<CompletionSummary>,
    /// The rendered depth the removal read and how the photos chose it (None: removal only).
    pub rendered_depth: Option<super::rendered_depth::DepthChoice>,
    pub gaussians: GaussianCounts,
    /// Per edited view (empty without completion).
    pub views: Vec<ViewReport>,
    /// Stage 4's statistics (`fuse::Patched::report`).
    pub fusion: Option<serde_json::Value>,
    /// The pruning criteria used (None: no pruning ran).
    pub prune: Option<PruneConfig>,
    pub refine: Option<RefineReport>,
    /// PSNR of the final renders against the original ones outside each view's dilated hole:
    /// how well the background was kept.
    pub background_psnr_vs_original: BackgroundPsnr,
    /// Seconds per stage.
    pub seconds: BTreeMap<String, f64>,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct CompletionSummary {
    pub inpainter: String,
    pub depth_guidance: bool,
    pub photo_consistent_hole_depth: bool,
    pub depth_prior: String,
    pub depth_refiner: String,
}

impl CompletionSummary {
    /// What `completer` runs; `photos`: whether captured photos were given.
    pub fn of(c: &Completer, photos: bool) -> CompletionSummary {
        CompletionSummary {
            inpainter: c.inpainter.name(),
            depth_guidance: c.depth_guidance,
            photo_consistent_hole_depth: c.photo_depth && photos,
            depth_prior: c.prior.name(),
            depth_refiner: c
                .refiner
                .as_ref()
                .map(|r| r.path().display().to_string())
                .unwrap_or_else(|| format!("built-in edge-aware ({} sweeps)", c.refine_sweeps)),
        }
    }
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct GaussianCounts {
    pub input: usize,
    /// All removed, those `left_inside` included.
    pub removed: usize,
    /// Background Gaussians removed as left inside the objects (stage 1b, `removal::hull`).
    pub left_inside: usize,
    pub pruned: usize,
    pub output: usize,
}

/// Mean and minimum over the views (null in JSON where no view had a pixel outside its hole).
#[derive(Clone, Debug, serde::Serialize)]
pub struct BackgroundPsnr {
    pub mean: f64,
    pub min: f64,
}

impl BackgroundPsnr {
    pub fn of(per_view: &[f64]) -> BackgroundPsnr {
        let mean = if per_view.is_empty() { f64::NAN } else { per_view.iter().sum::<f64>() / per_view.len() as f64 };
        BackgroundPsnr { mean, min: per_view.iter().copied().fold(f64::INFINITY, f64::min) }
    }
}

/// Seconds per stage, for the report.
pub struct StageClock {
    clock: Instant,
    pub seconds: BTreeMap<String, f64>,
}

impl StageClock {
    pub fn start() -> StageClock {
        StageClock { clock: Instant::now(), seconds: BTreeMap::new() }
    }
    /// Adds the time since the last lap to `stage`'s (a stage that runs twice, as stage 3 under
    /// both rendered depths, sums its runs).
    pub fn lap(&mut self, stage: &str) {
        *self.seconds.entry(stage.into()).or_default() += self.clock.elapsed().as_secs_f64();
        self.clock = Instant::now();
    }
}
