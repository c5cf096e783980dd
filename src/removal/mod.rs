//! Multi-object removal: the paper's stages after tagging, one file each, and the pipeline that
//! strings them together (`cogeo remove`).
//!
//! 1. Selection (select.rs): the Gaussians whose `label` (from `cogeo tag`) is one of the chosen
//!    labels go.
//! 2. Hole masks (select.rs): per edited view, the pixels the removed Gaussians carried, dilated;
//!    the part the remaining Gaussians do not cover is to be synthesized.
//! 3. Completion per view (complete/): inpainting, depth anchoring, depth refinement, the
//!    depth's planes guiding the built-in inpainter. Then the hole's depth is corrected to where
//!    the captured photos agree (complete/photo_depth.rs), and colors of hole pixels that other
//!    views saw come from those views' captured images (complete/transfer.rs), which also
//!    corrects covered but poorly rendered ones; only the rest of the fill stays invented.
//! 4. Fusion and pruning (fuse.rs): completed depth back-projected into new Gaussians; sparse
//!    background outliers near them pruned.
//! 5. Refinement (refine.rs): color first, then trust-region clipped geometry; each view's hole
//!    weighs more in the loss than the rest of it, whose target is the scene's own render.
//!
//! Each stage takes and returns plain data; each can be switched off for ablations (`Stages`).

pub mod select;
pub mod complete;
pub mod consensus;
pub mod fuse;
pub mod prune;
pub mod refine;

pub use fuse::Fill;
pub use select::{hole_mask, select};

use crate::gpu::Gpu;
use crate::scene::{Camera, GaussianScene};
use anyhow::{bail, Result};
use complete::source_views::SourceView;
use complete::{Completed, Completer, ViewInputs};
use consensus::ConsensusView;
use fuse::{FuseConfig, FuseView};
use prune::PruneSettings;
use refine::{RefineConfig, RefineReport};
use select::{HoleConfig, MaskedView, ViewRenderer};
use std::time::Instant;

/// Which stages run (each can be switched off for ablations).
#[derive(Clone, Debug, serde::Serialize, clap::Args)]
pub struct Stages {
    /// Inpaint, complete depth and fuse new Gaussians (false: removal only). Its flag is the
    /// ablation that only deletes the Gaussians (no inpainting, no new Gaussians, no refinement).
    #[arg(id = "removal-only", long = "removal-only", action = clap::ArgAction::SetFalse)]
    pub complete: bool,
    /// Take colors of fill pixels from the captured images of the views that saw the completed
    /// surface point (complete/transfer.rs). Its flag is the ablation without depth-guided color
    /// transfer (hole pixels that other views saw keep their render or are inpainted like the rest
    /// instead of taking those views' captured colors).
    #[arg(id = "no-transfer", long = "no-transfer", action = clap::ArgAction::SetFalse)]
    pub transfer: bool,
    /// Prune sparse background outliers near the patch (flag: skip pruning).
    #[arg(id = "no-prune", long = "no-prune", action = clap::ArgAction::SetFalse)]
    pub prune: bool,
    /// Refine against the completed views (flag: skip the refinement stage).
    #[arg(id = "no-refine", long = "no-refine", action = clap::ArgAction::SetFalse)]
    pub refine: bool,
}

/// Removal settings: the one home of their defaults, also `cogeo remove`'s flags (with the
/// completion's, `complete::CompletionConfig`).
#[derive(Clone, Debug, serde::Serialize, clap::Args)]
pub struct RemoveOptions {
    /// The labels to remove (the command line resolves them from --labels and --prompt).
    #[arg(skip)]
    pub labels: Vec<u8>,
    /// A pixel is in the hole when the removed Gaussians carry more than this share of its weight.
    #[arg(long, default_value_t = 0.3)]
    pub hole_threshold: f32,
    /// Hole dilation in pixels.
    #[arg(long, default_value_t = 2.0)]
    pub dilate: f32,
    /// Hole pixels that a kept object (a remaining Gaussian with a nonzero label) covers with at
    /// least this alpha keep their render, unless it lies 1.25x behind the surfaces around the
    /// hole; 1 fills the whole hole. The background Gaussians left behind the removed objects never
    /// keep a pixel: it is filled (photo colors where other views saw it) and gets new Gaussians.
    #[arg(long, default_value_t = 0.9)]
    pub keep_alpha: f32,
    #[command(flatten)]
    pub stages: Stages,
    /// How new Gaussians are made: depth (back-projected completed depth, fused and pruned) or
    /// nearest-copy (baseline: each removed Gaussian replaced by a copy of its nearest remaining one).
    #[arg(long, value_enum, default_value_t)]
    pub fill: Fill,
    #[command(flatten)]
    pub fuse: FuseConfig,
    #[command(flatten)]
    pub prune: PruneSettings,
    #[command(flatten)]
    pub refine: RefineConfig,
    /// Background color r,g,b in [0, 1] (the one the scene was trained with).
    #[arg(long, default_value = "0,0,0", value_parser = crate::flag_values::parse_rgb)]
    pub background: [f32; 3],
    /// Random seed (exemplar fill, refinement view order, diffusion noise).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

impl Default for RemoveOptions {
    fn default() -> Self {
        crate::config::defaults()
    }
}

impl RemoveOptions {
    /// The refinement's settings with the removal's background and seed.
    pub fn refine_config(&self) -> RefineConfig {
        RefineConfig { background: self.background, seed: self.seed, ..self.refine.clone() }
    }
}

/// Per-view images of a removal.
pub struct ViewResult {
    pub name: String,
    /// Original render.
    pub before: Vec<f32>,
    /// Render right after deleting the Gaussians.
    pub removed: Vec<f32>,
    /// The completion target (inpainted view); equals `removed` without completion.
    pub inpainted: Vec<f32>,
    /// Completed depth (camera z), empty without completion.
    pub depth: Vec<f32>,
    /// Final render.
    pub after: Vec<f32>,
    /// Dilated hole M.
    pub hole: Vec<bool>,
    /// Synthesized part of the hole.
    pub fill: Vec<bool>,
}

pub struct Removal {
    pub scene: GaussianScene,
    pub views: Vec<ViewResult>,
    pub report: serde_json::Value,
}

/// Progress callback: (stage, done, total).
pub type Progress<'a> = &'a mut dyn FnMut(&str, usize, usize);

/// Seconds per stage, for the report.
struct StageClock {
    clock: Instant,
    seconds: serde_json::Map<String, serde_json::Value>,
}

impl StageClock {
    fn start() -> StageClock {
        StageClock { clock: Instant::now(), seconds: serde_json::Map::new() }
    }
    fn lap(&mut self, stage: &str) {
        self.seconds.insert(stage.into(), self.clock.elapsed().as_secs_f64().into());
        self.clock = Instant::now();
    }
}

/// Runs the pipeline on `scene` (tagged: `labels` per Gaussian) with the edited `cameras` and
/// their captured images `photos` (planar RGB; empty: no color transfer).
#[allow(clippy::too_many_arguments)]
pub fn remove(
    gpu: &Gpu,
    scene: &GaussianScene,
    labels: &[u8],
    cameras: &[Camera],
    photos: &[Vec<f32>],
    extent: f64,
    opts: &RemoveOptions,
    completer: &mut Completer,
    progress: Progress,
) -> Result<Removal> {
    check_inputs(scene, labels, cameras, photos, opts)?;
    let mut clock = StageClock::start();
    // 1. selection
    let selection = select::select_gaussians(scene, labels, &opts.labels)?;
    clock.lap("select");
    // 2. hole masks, from renders before and after deletion
    let holes = HoleConfig {
        threshold: opts.hole_threshold,
        dilate: opts.dilate,
        keep_alpha: opts.keep_alpha,
        background: opts.background,
    };
    let mut masked = select::hole_masks(gpu, scene, &selection, cameras, &holes, &mut |d, t| progress("masks", d, t))?;
    clock.lap("masks");
    let mut result = selection.background; // moved: only the removed mask and count are used below
    let mut completed: Vec<Completed> = Vec::new();
    // per view, the hole pixels that took a photo's color (stage 3c)
    let mut transferred: Vec<Vec<bool>> = Vec::new();
    let mut per_view = Vec::new();
    let (mut fusion, mut pruned, mut prune_used) = (None, 0, None);
    let mut refine_report: Option<RefineReport> = None;
    if opts.stages.complete {
        // 3. completion
        let inputs: Vec<ViewInputs> = masked.iter().zip(cameras).map(|(m, c)| completion_inputs(m, c)).collect();
        completed = completer.complete_views(&inputs, &mut |d, t| progress("complete", d, t))?;
        drop(inputs);
        let mut through = Vec::new();
        for (m, k) in masked.iter_mut().zip(&completed) {
            // with the covered pixels that looked through a gap
            through.push(k.fill.iter().filter(|&&f| f).count() - m.fill.iter().filter(|&&f| f).count());
            m.fill.clone_from(&k.fill);
        }
        per_view = masked.iter().zip(cameras).zip(&completed).map(|((m, c), k)| view_report(&c.name, m, k)).collect();
        for (r, n) in per_view.iter_mut().zip(through) {
            r["see_through_pixels"] = n.into();
        }
        clock.lap("complete");
        // 3b. the hole depth the captured photos agree on, then 3c. colors from the views that
        // saw the completed surface
        if !photos.is_empty() {
            let sources = transfer_sources(&masked, cameras, photos);
            let holes: Vec<&[bool]> = masked.iter().map(|m| m.hole.as_slice()).collect();
            if completer.photo_depth {
                let scales = completer.correct_depths(cameras, &sources, &holes, &mut completed);
                for (r, scale) in per_view.iter_mut().zip(scales) {
                    r["hole_depth_scale"] = serde_json::to_value(scale)?;
                }
                clock.lap("photo_depth");
            }
            if opts.stages.transfer {
                let fills: Vec<&[bool]> = masked.iter().map(|m| m.fill.as_slice()).collect();
                transferred = completer.transfer_colors(cameras, &sources, &holes, &fills, &mut completed)?;
                for (r, t) in per_view.iter_mut().zip(&transferred) {
                    r["transferred_pixels"] = t.iter().filter(|&&f| f).count().into();
                }
                clock.lap("transfer");
            }
        }
        // 4. fusion and pruning (or the nearest-copy baseline)
        let patch_pixels: Vec<Vec<bool>> =
            masked.iter().zip(&completed).map(|(m, k)| m.patch_pixels(&k.depth, opts.keep_alpha)).collect();
        for ((r, m), p) in per_view.iter_mut().zip(&masked).zip(&patch_pixels) {
            r["fill_pixels_without_patch"] =
                (m.fill.iter().filter(|&&f| f).count() - p.iter().filter(|&&f| f).count()).into();
        }
        let fviews: Vec<FuseView> = completed
            .iter()
            .zip(&patch_pixels)
            .zip(cameras)
            .map(|((k, fill), camera)| FuseView { camera, rgb: &k.rgb, depth: &k.depth, fill })
            .collect();
        let removed_means: Vec<[f32; 3]> =
            scene.means.iter().zip(&selection.removed).filter(|(_, &r)| r).map(|(m, _)| *m).collect();
        let (fill, prune) = (opts.fill, opts.stages.prune);
        let patch = fuse::patch_scene(result, fill, &fviews, &removed_means, &opts.fuse, prune, &opts.prune)?;
        (result, fusion, pruned, prune_used) = (patch.scene, Some(patch.report), patch.pruned, patch.prune);
        clock.lap("fuse");
        // 4b. which invented pixels each view's refinement keeps
        let consensus_weights = if opts.stages.refine && !patch.owned.is_empty() {
            let views: Vec<ConsensusView> = (0..completed.len())
                .map(|i| ConsensusView {
                    camera: &cameras[i],
                    rgb: &completed[i].rgb,
                    depth: &completed[i].depth,
                    invented: (0..masked[i].fill.len())
                        .map(|p| masked[i].fill[p] && !transferred.get(i).is_some_and(|t| t[p]))
                        .collect(),
                    owned: &patch.owned[i],
                })
                .collect();
            let (masks, verdicts) = consensus::loss_masks(&views, opts.fuse.tolerance);
            for (r, v) in per_view.iter_mut().zip(verdicts) {
                r["consensus"] = serde_json::to_value(v)?;
            }
            Some(masks)
        } else {
            None
        };
        // 5. refinement, the holes weighing more than the rest of each view
        if opts.stages.refine {
            let holes: Vec<&[bool]> = masked.iter().map(|m| m.hole.as_slice()).collect();
            let masks = refine::loss_weights(&holes, consensus_weights, opts.refine.hole_weight);
            let targets: Vec<Vec<f32>> = completed.iter().map(|k| k.rgb.clone()).collect();
            let total = opts.refine.iters as usize;
            let (refined, report) =
                refine::refine(gpu, &result, cameras, targets, Some(&masks), extent, &opts.refine_config(), |it| {
                    progress("refine", it as usize, total)
                })?;
            result = refined;
            refine_report = Some(report);
            clock.lap("refine");
        }
    }
    // final renders and background preservation: PSNR outside the dilated hole vs the original
    let (after, bg_psnr) = final_renders(gpu, &result, cameras, &masked, opts.background, progress)?;
    clock.lap("render");
    let mean = |v: &[f64]| if v.is_empty() { f64::NAN } else { v.iter().sum::<f64>() / v.len() as f64 };
    let report = serde_json::json!({
        "labels": opts.labels,
        "options": opts,
        "completion": completer_summary(completer, &opts.stages, !photos.is_empty()),
        "gaussians": { "input": scene.len(), "removed": selection.count, "pruned": pruned, "output": result.len() },
        "views": per_view,
        "fusion": fusion,
        "prune": prune_used,
        "refine": refine_report,
        "background_psnr_vs_original": { "mean": mean(&bg_psnr), "min": bg_psnr.iter().copied().fold(f64::INFINITY, f64::min) },
        "seconds": clock.seconds,
    });
    let views = view_results(masked, cameras, completed, after);
    Ok(Removal { scene: result, views, report })
}

fn check_inputs(
    scene: &GaussianScene,
    labels: &[u8],
    cameras: &[Camera],
    photos: &[Vec<f32>],
    opts: &RemoveOptions,
) -> Result<()> {
    if labels.len() != scene.len() {
        bail!("{} labels for {} Gaussians", labels.len(), scene.len());
    }
    if opts.labels.is_empty() {
        bail!("no labels to remove");
    }
    if !photos.is_empty() && photos.len() != cameras.len() {
        bail!("{} photos for {} views", photos.len(), cameras.len());
    }
    for (p, c) in photos.iter().zip(cameras) {
        if p.len() != 3 * (c.width * c.height) as usize {
            bail!("{}: the photo's size differs from the camera's {}x{}", c.name, c.width, c.height);
        }
    }
    Ok(())
}

/// The per-view images of the result: stage 2's renders and holes, the completion (when it ran)
/// and the final renders.
fn view_results(
    masked: Vec<MaskedView>,
    cameras: &[Camera],
    completed: Vec<Completed>,
    after: Vec<Vec<f32>>,
) -> Vec<ViewResult> {
    let mut completed = completed.into_iter();
    masked
        .into_iter()
        .zip(cameras)
        .zip(after)
        .map(|((m, cam), after)| {
            let (inpainted, depth) = match completed.next() {
                Some(k) => (k.rgb, k.depth),
                None => (m.after_removal.rgb.clone(), Vec::new()),
            };
            ViewResult {
                name: cam.name.clone(),
                before: m.before.rgb,
                removed: m.after_removal.rgb,
                inpainted,
                depth,
                after,
                hole: m.hole,
                fill: m.fill,
            }
        })
        .collect()
}

/// Every edited view as a source of captured colors: its photo, read off the objects' footprint
/// where the original render (with the objects) is opaque at the right depth.
fn transfer_sources<'a>(
    masked: &'a [MaskedView],
    cameras: &'a [Camera],
    photos: &'a [Vec<f32>],
) -> Vec<SourceView<'a>> {
    masked
        .iter()
        .zip(cameras)
        .zip(photos)
        .map(|((m, camera), photo)| SourceView {
            camera,
            photo,
            hole: &m.footprint,
            depth: &m.before.depth,
            alpha: &m.before.alpha,
        })
        .collect()
}

/// What completion reads of one view after stage 2.
fn completion_inputs<'a>(m: &'a MaskedView, camera: &Camera) -> ViewInputs<'a> {
    ViewInputs {
        width: camera.width as usize,
        height: camera.height as usize,
        intrinsics: complete::rectify::Intrinsics::from(camera),
        rgb: &m.after_removal.rgb,
        alpha: &m.after_removal.alpha,
        expected_depth: &m.after_removal.depth,
        fill: &m.fill,
        hole: &m.hole,
    }
}

fn view_report(name: &str, m: &MaskedView, c: &Completed) -> serde_json::Value {
    serde_json::json!({
        "view": name,
        "hole_pixels": m.hole.iter().filter(|&&x| x).count(),
        "fill_pixels": m.fill.iter().filter(|&&x| x).count(),
        "depth_space": c.space,
        "scale": c.scale,
        "shift": c.shift,
        "fit_pixels": c.fit_pixels,
        "fit_rms": c.residual,
    })
}

/// Renders the result from every edited view; PSNR against the original render outside each
/// view's dilated hole measures how well the background was kept.
fn final_renders(
    gpu: &Gpu,
    scene: &GaussianScene,
    cameras: &[Camera],
    masked: &[MaskedView],
    background: [f32; 3],
    progress: Progress,
) -> Result<(Vec<Vec<f32>>, Vec<f64>)> {
    let mut renderer = ViewRenderer::new(gpu, scene, None)?;
    let (mut after, mut bg_psnr) = (Vec::new(), Vec::new());
    for (i, (m, cam)) in masked.iter().zip(cameras).enumerate() {
        let rgb = renderer.render(cam, background)?.rgb;
        let outside: Vec<bool> = m.hole.iter().map(|&x| !x).collect();
        if let Some(p) = crate::eval::masked_psnr(&rgb, &m.before.rgb, &outside) {
            bg_psnr.push(p);
        }
        after.push(rgb);
        progress("render", i + 1, cameras.len());
    }
    Ok((after, bg_psnr))
}

fn completer_summary(c: &Completer, stages: &Stages, photos: bool) -> serde_json::Value {
    if !stages.complete {
        return serde_json::json!(null);
    }
    serde_json::json!({
        "inpainter": c.inpainter.name(),
        "depth_guidance": c.depth_guidance,
        "photo_consistent_hole_depth": c.photo_depth && photos,
        "depth_prior": c.prior.name(),
        "depth_refiner": c.refiner.as_ref().map(|r| r.path().display().to_string()).unwrap_or_else(|| format!("built-in edge-aware ({} sweeps)", c.refine_sweeps)),
    })
}
