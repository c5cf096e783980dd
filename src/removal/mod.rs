//! Multi-object removal: the paper's stages after tagging, one file each, and the pipeline that
//! strings them together (`cogeo remove`).
//!
//! 1. Selection (select.rs): the Gaussians whose `label` (from `cogeo tag`) is one of the chosen
//!    labels go.
//! 2. Hole masks (select.rs): per edited view, the pixels the removed Gaussians carried, dilated;
//!    the part the remaining Gaussians do not cover is to be synthesized.
//!    Every depth read from here on is the expected or the median rendered depth, whichever the
//!    captured photos agree with (rendered_depth.rs: stages 2 to 3b run under both).
//! 3. Completion per view (complete/): inpainting, depth anchoring, depth refinement, the
//!    depth's planes guiding the built-in inpainter. Then the hole's depth is corrected to where
//!    the captured photos agree: the depth of the Gaussians left behind the objects where the
//!    photos prefer it (complete/leftover_depth.rs), then one factor and a local search
//!    (complete/photo_depth.rs). Colors of hole pixels that other views saw come from those
//!    views' captured images (complete/transfer.rs), which also corrects covered but poorly
//!    rendered ones; only what remains stays invented.
//! 4. Fusion and pruning (fuse.rs, prune.rs): completed depth back-projected into new Gaussians;
//!    sparse background outliers near them pruned. Then (consensus.rs) which invented pixels each
//!    view's refinement keeps.
//! 5. Refinement (refine.rs): color first, then trust-region clipped geometry; each view's hole
//!    weighs more in the loss than the rest of it, whose target is the scene's own render.
//!
//! Each stage is a function over the edited views (`view::EditedView`: a view's renders, hole,
//! completion, transferred pixels and loss weights, and its line of the report), and the report
//! is a typed struct (report.rs). Each stage can be switched off for ablations (`Stages`).
//! After a removal, held_out.rs renders the held-out views and scores them against synth ground
//! truth.

pub mod select;
pub mod complete;
pub mod consensus;
pub mod fuse;
pub mod prune;
pub mod held_out;
pub mod hull;
pub mod refine;
pub mod rendered_depth;
pub mod report;
pub mod view;

pub use fuse::Fill;
pub use select::{hole_mask, select};

use crate::gpu::Gpu;
use crate::image_ops::{crop, Rect};
use crate::scene::{Camera, GaussianScene};
use anyhow::{bail, Result};
use complete::source_views::SourceView;
use complete::{Completed, Completer, ViewInputs};
use consensus::ConsensusView;
use fuse::{FuseConfig, FuseView, Patched};
use prune::PruneSettings;
use refine::{RefineConfig, RefineReport};
use rendered_depth::{RenderedDepth, StageInputs, Staged};
use report::{BackgroundPsnr, CompletionSummary, GaussianCounts, RemovalReport, StageClock};
use select::{DepthPlanes, Selection, ViewRenderer};
use view::EditedView;

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
    /// Where they cover a fill pixel with at least this alpha, their depth competes with the
    /// completed one on photo-consistency, and where they lie more than 6 % in front of the
    /// completed surface the pixel gets no new Gaussian.
    #[arg(long, default_value_t = 0.9)]
    pub keep_alpha: f32,
    /// The rendered depth the removal reads (the masks, the hull, the completion and the color
    /// transfer; rendered_depth.rs).
    #[arg(long, value_enum, default_value_t)]
    pub rendered_depth: RenderedDepth,
    #[command(flatten)]
    pub stages: Stages,
    #[command(flatten)]
    pub hull: hull::HullConfig,
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
    #[arg(long, default_value = crate::flag_values::DEFAULT_BACKGROUND, value_parser = crate::flag_values::parse_rgb)]
    pub background: [f32; 3],
    /// Random seed (exemplar fill, refinement view order, diffusion noise).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

crate::default_from_flags!(RemoveOptions);

impl RemoveOptions {
    /// The refinement's settings with the removal's background and seed.
    pub fn refine_config(&self) -> RefineConfig {
        RefineConfig { background: self.background, seed: self.seed, ..self.refine.clone() }
    }

    /// The fusion's settings; without refinement the patch must cover the hole on its own and
    /// starts at `fuse::UNREFINED_OPACITY`.
    pub fn fuse_config(&self) -> FuseConfig {
        let opacity = if self.stages.refine { self.fuse.opacity } else { fuse::UNREFINED_OPACITY };
        FuseConfig { opacity, ..self.fuse.clone() }
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
    pub report: RemovalReport,
}

/// Progress callback: (stage, done, total).
pub type Progress<'a> = &'a mut dyn FnMut(&str, usize, usize);

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
    completer: &Completer,
    progress: Progress,
) -> Result<Removal> {
    check_inputs(scene, labels, cameras, photos, opts)?;
    let mut clock = StageClock::start();
    // 1. selection
    let selection = select::select_gaussians(scene, labels, &opts.labels)?;
    clock.lap("select");
    // 2. to 3b., under the rendered depth the captured photos agree with (both tried for
    // `RenderedDepth::Auto`)
    let inputs = StageInputs { gpu, scene, labels, cameras, photos, opts, completer };
    let (staged, depth_choice) = rendered_depth::stage_in_chosen_depth(&inputs, &selection, &mut clock, progress)?;
    let Staged { mut views, selection, left_inside } = staged;
    let Selection { removed, count: removed_count, background, .. } = selection;
    let mut result = background;
    let (mut fusion, mut prune_used, mut pruned) = (None, None, 0);
    let (mut refine_report, mut refine_windows) = (None, Vec::new());
    if opts.stages.complete {
        // 3c. colors from the views that saw the completed surface
        if !photos.is_empty() && opts.stages.transfer {
            transfer_colors(&mut views, cameras, completer, progress)?;
            clock.lap("transfer");
        }
        // 4. fusion and pruning (or the nearest-copy baseline)
        let patch = fuse_patch(&mut views, scene, &removed, result, opts)?;
        (result, fusion, pruned, prune_used) = (patch.scene, Some(patch.report), patch.pruned, patch.prune);
        clock.lap("fuse");
        if opts.stages.refine {
            // 4b. which invented pixels each view's refinement keeps
            let consensus =
                (!patch.owned.is_empty()).then(|| consensus_weights(&mut views, &patch.owned, opts.fuse.tolerance));
            // 5. refinement, the holes weighing more than the rest of each view
            let (refined, report, windows) =
                refine_views(gpu, &result, &views, cameras, consensus, patch.added, extent, opts, progress)?;
            (result, refine_report, refine_windows) = (refined, Some(report), windows);
            clock.lap("refine");
        }
    }
    // final renders and background preservation: PSNR outside the dilated hole vs the original
    let (after, bg_psnr) = final_renders(gpu, &result, &views, opts.background, progress)?;
    if let Some(report) = refine_report.as_mut() {
        let targets: Vec<&[f32]> = views.iter().map(|v| v.completion().rgb.as_slice()).collect();
        report.psnr_after = Some(refine::window_psnr(&after, &targets, cameras, &refine_windows));
    }
    clock.lap("render");
    let report = RemovalReport {
        labels: opts.labels.clone(),
        // the fusion's settings as used (its opacity depends on the refinement)
        options: RemoveOptions { fuse: opts.fuse_config(), ..opts.clone() },
        completion: opts.stages.complete.then(|| CompletionSummary::of(completer, !photos.is_empty())),
        rendered_depth: opts.stages.complete.then_some(depth_choice),
        gaussians: GaussianCounts {
            input: scene.len(),
            removed: removed_count,
            left_inside,
            pruned,
            output: result.len(),
        },
        views: if opts.stages.complete { views.iter().map(|v| v.report.clone()).collect() } else { Vec::new() },
        fusion,
        prune: prune_used,
        refine: refine_report,
        background_psnr_vs_original: BackgroundPsnr::of(&bg_psnr),
        seconds: clock.seconds,
    };
    let views = views.into_iter().zip(after).map(|(v, after)| view_result(v, after)).collect();
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
    if !(0.0..=1.0).contains(&opts.hull.share) {
        bail!("--hull-share {} is not a share in [0, 1]", opts.hull.share);
    }
    if !(0.0..).contains(&opts.hull.surface_tolerance) {
        bail!("--hull-surface-tolerance {} is not a number >= 0", opts.hull.surface_tolerance);
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

/// Stage 3 over the views `at` (the others keep what they have).
fn complete_views(
    views: &mut [EditedView],
    at: &[usize],
    completer: &Completer,
    transfer_follows: bool,
    progress: Progress,
) -> Result<()> {
    let completed = {
        let inputs: Vec<ViewInputs> = at.iter().map(|&i| views[i].completion_inputs()).collect();
        let indexed: Vec<(usize, &ViewInputs)> = at.iter().copied().zip(&inputs).collect();
        completer.complete_views_at(&indexed, transfer_follows, &mut |d, t| progress("complete", d, t))?
    };
    for (&i, k) in at.iter().zip(completed) {
        views[i].set_completed(k);
    }
    Ok(())
}

/// The views' completions, taken out while the views lend their photos to each other.
fn take_completions(views: &mut [EditedView]) -> Vec<Completed> {
    views.iter_mut().map(|v| v.completed.take().expect("stage 3 ran")).collect()
}

fn put_back(views: &mut [EditedView], completed: Vec<Completed>) {
    for (v, k) in views.iter_mut().zip(completed) {
        v.completed = Some(k);
    }
}

/// Every view as a source of captured colors for the others (needs the photos), and its hole.
fn sources_and_holes<'v>(views: &'v [EditedView]) -> (Vec<SourceView<'v>>, Vec<&'v [bool]>) {
    views.iter().map(|v| (v.source().expect("photos were given"), v.masked.hole.as_slice())).unzip()
}

/// Stage 3b over the views `at`, completed (`cameras`: every view's; needs the photos).
fn correct_depths(
    views: &mut [EditedView],
    at: &[usize],
    cameras: &[Camera],
    completer: &Completer,
    progress: Progress,
) {
    let leftovers: Vec<Vec<f32>> = views.iter().map(|v| v.masked.leftover_depth()).collect();
    let mut completed: Vec<(usize, Completed)> =
        at.iter().map(|&i| (i, views[i].completed.take().expect("stage 3 ran"))).collect();
    let (sources, holes) = sources_and_holes(views);
    let found = completer.correct_depths(cameras, &sources, &holes, &leftovers, &mut completed, &mut |d, t| {
        progress("photo depth", d, t)
    });
    drop((sources, holes));
    for ((i, k), (scale, taken)) in completed.into_iter().zip(found) {
        let v = &mut views[i];
        v.completed = Some(k);
        v.report.hole_depth_scale = Some(scale);
        v.report.leftover_depth_pixels = Some(taken);
    }
}

/// Stage 3c over every view (`cameras`, the views' own; needs the photos). The Gaussians left
/// behind the objects lend no color: on composites trained like their captures (from the
/// capture's own sparse points) they rendered a dark box-shaped patch of desk where the cup's box
/// stood, and the targets that took their render kept it (held-out masked PSNR 22.26 -> 27.39 dB
/// without; statue-one -0.10 dB, LPIPS 0.322 -> 0.282, statue-two-of-three -0.04 dB, LPIPS
/// 0.231 -> 0.210; bench/JOURNAL.md, 2026-11-29, 19:52).
fn transfer_colors(
    views: &mut [EditedView],
    cameras: &[Camera],
    completer: &Completer,
    progress: Progress,
) -> Result<()> {
    let mut completed = take_completions(views);
    let (sources, holes) = sources_and_holes(views);
    let transferred =
        completer.transfer_colors(cameras, &sources, &holes, &mut completed, &mut |d, t| progress("transfer", d, t))?;
    drop((sources, holes));
    put_back(views, completed);
    for (v, t) in views.iter_mut().zip(transferred) {
        v.report.transferred_pixels = Some(t.iter().filter(|&&f| f).count());
        v.transferred = Some(t);
    }
    Ok(())
}

/// Stage 4: the patch from the completed views, added to the scene without the removed
/// Gaussians (pruned near it), or the nearest-copy baseline.
fn fuse_patch(
    views: &mut [EditedView],
    scene: &GaussianScene,
    removed: &[bool],
    background: GaussianScene,
    opts: &RemoveOptions,
) -> Result<Patched> {
    let patch_pixels: Vec<Vec<bool>> = views.iter().map(|v| v.masked.patch_pixels(&v.completion().depth)).collect();
    for (v, p) in views.iter_mut().zip(&patch_pixels) {
        let count = |x: &[bool]| x.iter().filter(|&&f| f).count();
        v.report.fill_pixels_without_patch = count(&v.masked.fill) - count(p);
    }
    let fviews: Vec<FuseView> = views
        .iter()
        .zip(&patch_pixels)
        .map(|(v, fill)| {
            let k = v.completion();
            FuseView { camera: v.camera, rgb: &k.rgb, depth: &k.depth, fill }
        })
        .collect();
    let removed_means: Vec<[f32; 3]> = scene.means.iter().zip(removed).filter(|(_, &r)| r).map(|(m, _)| *m).collect();
    fuse::patch_scene(
        background,
        opts.fill,
        &fviews,
        &removed_means,
        &opts.fuse_config(),
        opts.stages.prune,
        &opts.prune,
    )
}

/// Stage 4b: each view's refinement weights from how its inventions agree with the others'
/// (consensus.rs); `owned` per view, from the fusion. Each view's report gets its verdict.
fn consensus_weights(views: &mut [EditedView], owned: &[Vec<bool>], tolerance: f32) -> Vec<Vec<f32>> {
    let cviews: Vec<ConsensusView> = views
        .iter()
        .zip(owned)
        .map(|(v, owned)| {
            let k = v.completion();
            ConsensusView { camera: v.camera, rgb: &k.rgb, depth: &k.depth, invented: v.invented(), owned }
        })
        .collect();
    let (masks, verdicts) = consensus::loss_masks(&cviews, tolerance);
    drop(cviews);
    for (v, verdict) in views.iter_mut().zip(verdicts) {
        v.report.consensus = Some(verdict);
    }
    masks
}

/// Stage 5: refines `scene` against the completed views (`cameras`, theirs), each view's hole
/// weighing `hole_weight` times the rest, times its `consensus` weights where there are some;
/// each view over its window around the hole and the `patch_gaussians` (the last of `scene`)
/// unless `whole_views` is set. Also returns each view's window (None: the whole view).
#[allow(clippy::too_many_arguments)]
fn refine_views(
    gpu: &Gpu,
    scene: &GaussianScene,
    views: &[EditedView],
    cameras: &[Camera],
    consensus: Option<Vec<Vec<f32>>>,
    patch_gaussians: usize,
    extent: f64,
    opts: &RemoveOptions,
    progress: Progress,
) -> Result<(GaussianScene, RefineReport, Vec<Option<Rect>>)> {
    let holes: Vec<&[bool]> = views.iter().map(|v| v.masked.hole.as_slice()).collect();
    let mut masks = refine::loss_weights(&holes, consensus, opts.refine.hole_weight);
    // the pixels the coverage term draws, only where it weighs
    let mut drawn: Option<Vec<Vec<bool>>> = (opts.refine.coverage_weight > 0.0).then(|| {
        let on = opts.refine.coverage_on;
        let per_view = views.iter().zip(&masks);
        per_view.map(|(v, mask)| refine::coverage_pixels(on, mask, &v.masked.fill, v.transferred.as_deref())).collect()
    });
    let mut targets: Vec<Vec<f32>> = views.iter().map(|v| v.completion().rgb.clone()).collect();
    let movable = (!opts.refine.all_gaussians)
        .then(|| refine::movable_gaussians(scene, cameras, &holes, patch_gaussians, opts.refine.view_dependence));
    let mut cameras = cameras.to_vec();
    let mut windows = vec![None; cameras.len()];
    if !opts.refine.whole_views {
        // each view over its window (`refine::refine_window`); a view that sees neither its
        // hole nor the patch keeps its whole frame, the anchor of everything it sees
        let patch = &scene.means[scene.len() - patch_gaussians..];
        for (i, cam) in cameras.iter_mut().enumerate() {
            let Some(win) = refine::refine_window(cam, holes[i], patch, opts.refine.margin) else { continue };
            let (w, h) = (cam.width as usize, cam.height as usize);
            targets[i] = crop(&targets[i], w, h, 3, win);
            masks[i] = crop(&masks[i], w, h, 1, win);
            if let Some(drawn) = drawn.as_mut() {
                drawn[i] = crop(&drawn[i], w, h, 1, win);
            }
            *cam = refine::window_camera(cam, win);
            windows[i] = Some(win);
        }
    }
    let coverage =
        drawn.map(|d| refine::coverage_gradients(&masks, &d, opts.refine.hole_weight, opts.refine.coverage_weight));
    let total = opts.refine.iterations(cameras.len()) as usize;
    let (refined, report) = refine::refine(
        gpu,
        scene,
        &cameras,
        targets,
        Some(&masks),
        coverage.as_deref(),
        movable.as_deref(),
        extent,
        &opts.refine_config(),
        |it| progress("refine", it as usize, total),
    )?;
    Ok((refined, report, windows))
}

/// Renders the result from every edited view; PSNR against the original render outside each
/// view's dilated hole measures how well the background was kept.
fn final_renders(
    gpu: &Gpu,
    scene: &GaussianScene,
    views: &[EditedView],
    background: [f32; 3],
    progress: Progress,
) -> Result<(Vec<Vec<f32>>, Vec<f64>)> {
    let mut renderer = ViewRenderer::new(gpu, scene, None, DepthPlanes::Expected)?;
    let (mut after, mut bg_psnr) = (Vec::new(), Vec::new());
    for (i, v) in views.iter().enumerate() {
        let rgb = renderer.render(v.camera, background)?.rgb;
        let outside: Vec<bool> = v.masked.hole.iter().map(|&x| !x).collect();
        if let Some(p) = crate::eval::masked_psnr(&rgb, &v.masked.before.rgb, &outside) {
            bg_psnr.push(p);
        }
        after.push(rgb);
        progress("render", i + 1, views.len());
    }
    Ok((after, bg_psnr))
}

/// One view's images for the caller: stage 2's renders and holes, the completion (when it ran)
/// and the final render.
fn view_result(v: EditedView, after: Vec<f32>) -> ViewResult {
    let m = v.masked;
    let (inpainted, depth) = match v.completed {
        Some(k) => (k.rgb, k.depth),
        None => (m.after_removal.rgb.clone(), Vec::new()),
    };
    ViewResult {
        name: v.camera.name.clone(),
        before: m.before.rgb,
        removed: m.after_removal.rgb,
        inpainted,
        depth,
        after,
        hole: m.hole,
        fill: m.fill,
    }
}
