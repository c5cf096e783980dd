//! Multi-object removal, the paper's stages after tagging, and the whole pipeline (`cogeo remove`):
//!
//! 1. Selection: the Gaussians whose `label` (from `cogeo tag`) is one of the chosen labels go.
//! 2. Hole masks: per edited view, M = pixels where the removed Gaussians carried more than
//!    `hole_threshold` of the pixel's blending weight in the original render (their weight is
//!    splatted as a one-channel feature), dilated by `dilate` pixels. The pixels to synthesize are
//!    the part of M that the remaining Gaussians do not already cover (alpha after removal below
//!    `keep_alpha`): background seen from other views keeps its render.
//! 3. Completion per view (complete/): inpainting, depth anchoring, depth refinement, the
//!    depth's planes guiding the built-in inpainter. Then colors of hole pixels that other views
//!    saw come from those views' captured images (complete/transfer.rs), which also corrects
//!    covered but poorly rendered ones; only the rest of the fill stays invented.
//! 4. Fusion and pruning (fuse.rs).
//! 5. Refinement (refine.rs).
//!
//! Each stage can be switched off for ablations (`Stages`).

pub mod complete;
pub mod fuse;
pub mod refine;

use crate::gpu::Gpu;
use crate::image_ops::dilate;
use crate::render::{Rasterizer, RenderSettings, SceneBuffers};
use crate::scene::{Camera, GaussianScene};
use anyhow::{bail, Result};
use complete::transfer::{transfer, SourceView, Transfer};
use complete::{Completer, ViewInputs};
use fuse::{FuseConfig, FuseView, PruneConfig};
use refine::{RefineConfig, RefineReport};
use std::time::Instant;

#[derive(Clone, Debug, serde::Serialize)]
pub struct Stages {
    /// Inpaint, complete depth and fuse new Gaussians (false: removal only).
    pub complete: bool,
    /// Take colors of fill pixels from the captured images of the views that saw the completed
    /// surface point (complete/transfer.rs).
    pub transfer: bool,
    /// Prune sparse background outliers near the patch.
    pub prune: bool,
    /// Refine against the completed views.
    pub refine: bool,
}

/// How the new Gaussians behind the removed objects are made.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Fill {
    /// CoGeo-GS: back-project the completed depth of every view, fuse, prune (fuse.rs).
    Depth,
    /// Baseline (Gaussian-Grouping-style): each removed Gaussian is replaced by a copy of its
    /// nearest remaining Gaussian, at its own position.
    NearestCopy,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct RemoveOptions {
    pub labels: Vec<u8>,
    /// Share of a pixel's weight the removed Gaussians must carry for it to be in the hole.
    pub hole_threshold: f32,
    /// Hole dilation in pixels.
    pub dilate: f32,
    /// Hole pixels the remaining Gaussians cover with at least this alpha keep their render.
    pub keep_alpha: f32,
    pub stages: Stages,
    pub fill: Fill,
    pub fuse: FuseConfig,
    /// None: from the patch spacing s (near 2 s, radius 3 s, 4 neighbours).
    pub prune: Option<PruneConfig>,
    pub refine: RefineConfig,
    pub background: [f32; 3],
}

impl Default for RemoveOptions {
    fn default() -> Self {
        RemoveOptions {
            labels: Vec::new(),
            hole_threshold: 0.3,
            dilate: 2.0,
            keep_alpha: 0.9,
            stages: Stages { complete: true, transfer: true, prune: true, refine: true },
            fill: Fill::Depth,
            fuse: FuseConfig::default(),
            prune: None,
            refine: RefineConfig::default(),
            background: [0.0; 3],
        }
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

/// Which Gaussians carry a chosen label.
pub fn select(labels: &[u8], chosen: &[u8]) -> Vec<bool> {
    labels.iter().map(|l| chosen.contains(l)).collect()
}

/// Renders RGB, alpha, expected depth and (with `removed`) the removed Gaussians' weight.
struct ViewRenderer {
    raster: Rasterizer,
    buffers: SceneBuffers,
    features: bool,
}

struct Rendered {
    rgb: Vec<f32>,
    alpha: Vec<f32>,
    depth: Vec<f32>,
    weight: Vec<f32>,
}

impl ViewRenderer {
    fn new(gpu: &Gpu, scene: &GaussianScene, removed: Option<&[bool]>) -> Result<ViewRenderer> {
        let feature: Option<Vec<f32>> = removed.map(|r| r.iter().map(|&x| x as u8 as f32).collect());
        let buffers = SceneBuffers::upload(gpu, scene, feature.as_deref().map(|f| (f, 1)))?;
        Ok(ViewRenderer { raster: Rasterizer::new(gpu)?, buffers, features: removed.is_some() })
    }

    fn render(&mut self, camera: &Camera, background: [f32; 3]) -> Result<Rendered> {
        let settings = RenderSettings { background, features: self.features, ..Default::default() };
        let o = self.raster.render(&self.buffers, camera, &settings)?;
        Ok(Rendered { rgb: o.rgb, alpha: o.alpha, depth: o.expected_depth, weight: o.features })
    }
}

/// The dilated hole of one view from the removed weight and alpha of the original render.
pub fn hole_mask(weight: &[f32], alpha: &[f32], w: usize, h: usize, threshold: f32, radius: f32) -> Vec<bool> {
    let raw: Vec<bool> = weight.iter().zip(alpha).map(|(&wt, &a)| wt > 0.02 && wt > threshold * a.max(1e-6)).collect();
    dilate(&raw, w, h, radius)
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
    let mut timings = serde_json::Map::new();
    let mut clock = Instant::now();
    let mut lap = |name: &str, timings: &mut serde_json::Map<String, serde_json::Value>| {
        timings.insert(name.into(), clock.elapsed().as_secs_f64().into());
        clock = Instant::now();
    };
    // 1. selection
    let removed = select(labels, &opts.labels);
    let n_removed = removed.iter().filter(|&&r| r).count();
    if n_removed == 0 {
        bail!("no Gaussian carries label(s) {:?}", opts.labels);
    }
    let keep: Vec<bool> = removed.iter().map(|&r| !r).collect();
    let background_scene = scene.subset(&keep);
    if background_scene.is_empty() {
        bail!("removing label(s) {:?} leaves no Gaussian", opts.labels);
    }
    lap("select", &mut timings);
    // 2. hole masks and renders before / after deletion
    let mut original = ViewRenderer::new(gpu, scene, Some(&removed))?;
    let mut remaining = ViewRenderer::new(gpu, &background_scene, None)?;
    let mut views = Vec::new();
    let mut after_removal = Vec::new();
    let mut originals = Vec::new();
    for (i, cam) in cameras.iter().enumerate() {
        let (w, h) = (cam.width as usize, cam.height as usize);
        let before = original.render(cam, opts.background)?;
        let hole = hole_mask(&before.weight, &before.alpha, w, h, opts.hole_threshold, opts.dilate);
        let rest = remaining.render(cam, opts.background)?;
        let fill: Vec<bool> = (0..w * h).map(|p| hole[p] && rest.alpha[p] < opts.keep_alpha).collect();
        views.push(ViewResult {
            name: cam.name.clone(),
            before: before.rgb,
            removed: rest.rgb.clone(),
            inpainted: rest.rgb.clone(),
            depth: Vec::new(),
            after: Vec::new(),
            hole,
            fill,
        });
        after_removal.push(rest);
        // for color transfer: the objects' own footprint with a 1-pixel margin for their
        // anti-aliased edges (the dilated hole would hide background that other views saw)
        let footprint = hole_mask(&before.weight, &before.alpha, w, h, opts.hole_threshold, 1.0);
        originals.push((before.depth, before.alpha, footprint));
        progress("masks", i + 1, cameras.len());
    }
    drop(original);
    drop(remaining);
    lap("masks", &mut timings);
    let mut per_view = Vec::new();
    let mut result = background_scene.clone();
    let mut fuse_stats = None;
    let mut pruned = 0usize;
    let mut prune_used = None;
    let mut refine_report: Option<RefineReport> = None;
    if opts.stages.complete {
        // 3. completion
        let mut surfaces = Vec::new();
        for (i, (v, rest)) in views.iter_mut().zip(&after_removal).enumerate() {
            let (w, h) = (cameras[i].width as usize, cameras[i].height as usize);
            let inputs = ViewInputs {
                width: w,
                height: h,
                rgb: &rest.rgb,
                alpha: &rest.alpha,
                expected_depth: &rest.depth,
                fill: &v.fill,
                hole: &v.hole,
            };
            let c = completer.complete(&inputs, i)?;
            per_view.push(serde_json::json!({
                "view": v.name,
                "hole_pixels": v.hole.iter().filter(|&&m| m).count(),
                "fill_pixels": v.fill.iter().filter(|&&m| m).count(),
                "depth_space": c.space,
                "scale": c.scale,
                "shift": c.shift,
                "fit_pixels": c.fit_pixels,
                "fit_rms": c.residual,
            }));
            v.inpainted = c.rgb;
            v.depth = c.depth;
            surfaces.push(c.surfaces);
            progress("complete", i + 1, cameras.len());
        }
        lap("complete", &mut timings);
        // 3b. depth-guided color transfer from the views that saw the completed surface, over the
        // whole hole: covered pixels render background that few views constrained
        if opts.stages.transfer && !photos.is_empty() {
            let sources: Vec<SourceView> = (0..views.len())
                .map(|j| SourceView {
                    camera: &cameras[j],
                    photo: &photos[j],
                    hole: &originals[j].2,
                    depth: &originals[j].0,
                    alpha: &originals[j].1,
                })
                .collect();
            let found: Vec<Transfer> = (0..views.len())
                .map(|i| transfer(i, &cameras[i], &views[i].depth, &views[i].hole, &sources, 0.05))
                .collect();
            drop(sources);
            for (i, t) in found.into_iter().enumerate() {
                let (w, h) = (cameras[i].width as usize, cameras[i].height as usize);
                let v = &mut views[i];
                let n = t.found.iter().filter(|&&f| f).count();
                if n > 0 {
                    let mut image = v.inpainted.clone();
                    for p in (0..w * h).filter(|&p| t.found[p]) {
                        for c in 0..3 {
                            image[c * w * h + p] = t.rgb[c * w * h + p];
                        }
                    }
                    // what no view saw is invented again, now from the transferred colors too
                    let rest: Vec<bool> = (0..w * h).map(|p| v.fill[p] && !t.found[p]).collect();
                    v.inpainted = completer.inpaint_again(&image, &rest, &surfaces[i], w, h)?;
                }
                per_view[i]["transferred_pixels"] = n.into();
            }
            lap("transfer", &mut timings);
        }
        // 4. fusion and pruning (or the nearest-copy baseline)
        if opts.fill == Fill::NearestCopy {
            let removed_means: Vec<[f32; 3]> =
                scene.means.iter().zip(&removed).filter(|(_, &r)| r).map(|(m, _)| *m).collect();
            let patch = fuse::nearest_copies(&result, &removed_means);
            result.append(&patch)?;
            fuse_stats = Some(serde_json::json!({ "fill": "nearest-copy", "patch_gaussians": patch.len() }));
        } else {
            let fviews: Vec<FuseView> = views
                .iter()
                .zip(cameras)
                .map(|(v, c)| FuseView { camera: c, rgb: &v.inpainted, depth: &v.depth, fill: &v.fill })
                .collect();
            let (points, stats) = fuse::fuse_points(&fviews, &opts.fuse);
            let patch = fuse::patch_gaussians(&points, result.sh_degree, opts.fuse.opacity);
            if opts.stages.prune && !patch.is_empty() {
                let cfg = opts.prune.clone().unwrap_or_else(|| {
                    let mut fp: Vec<f64> = points.iter().map(|p| p.footprint).collect();
                    fp.sort_by(|a, b| a.total_cmp(b));
                    let s = fp[fp.len() / 2];
                    PruneConfig { near: 2.0 * s, radius: 3.0 * s, min_neighbours: 4 }
                });
                let prune = fuse::prune_mask(&result.means, &patch.means, &cfg);
                pruned = prune.iter().filter(|&&p| p).count();
                let keep: Vec<bool> = prune.iter().map(|&p| !p).collect();
                result = result.subset(&keep);
                prune_used = Some(cfg);
            }
            result.append(&patch)?;
            fuse_stats = Some(serde_json::json!({ "stats": stats, "patch_gaussians": patch.len() }));
        }
        lap("fuse", &mut timings);

        // 5. refinement
        if opts.stages.refine {
            let targets: Vec<Vec<f32>> = views.iter().map(|v| v.inpainted.clone()).collect();
            let total = opts.refine.iters as usize;
            let (refined, report) = refine::refine(gpu, &result, cameras, targets, extent, &opts.refine, |it| {
                progress("refine", it as usize, total)
            })?;
            result = refined;
            refine_report = Some(report);
            lap("refine", &mut timings);
        }
    }
    // final renders and background preservation: PSNR outside the dilated hole vs the original
    let mut fin = ViewRenderer::new(gpu, &result, None)?;
    let mut bg_psnr = Vec::new();
    for (i, (v, cam)) in views.iter_mut().zip(cameras).enumerate() {
        v.after = fin.render(cam, opts.background)?.rgb;
        let outside: Vec<bool> = v.hole.iter().map(|&m| !m).collect();
        if let Some(p) = crate::eval::masked_psnr(&v.after, &v.before, &outside) {
            bg_psnr.push(p);
        }
        progress("render", i + 1, cameras.len());
    }
    lap("render", &mut timings);
    let mean = |v: &[f64]| if v.is_empty() { f64::NAN } else { v.iter().sum::<f64>() / v.len() as f64 };
    let report = serde_json::json!({
        "labels": opts.labels,
        "options": opts,
        "completion": completer_summary(completer, &opts.stages),
        "gaussians": { "input": scene.len(), "removed": n_removed, "pruned": pruned, "output": result.len() },
        "views": per_view,
        "fusion": fuse_stats,
        "prune": prune_used,
        "refine": refine_report,
        "background_psnr_vs_original": { "mean": mean(&bg_psnr), "min": bg_psnr.iter().copied().fold(f64::INFINITY, f64::min) },
        "seconds": timings,
    });
    Ok(Removal { scene: result, views, report })
}

fn completer_summary(c: &Completer, stages: &Stages) -> serde_json::Value {
    if !stages.complete {
        return serde_json::json!(null);
    }
    serde_json::json!({
        "inpainter": c.inpainter.name(),
        "depth_guidance": c.depth_guidance,
        "depth_prior": c.prior.name(),
        "depth_refiner": c.refiner.as_ref().map(|r| r.path().display().to_string()).unwrap_or_else(|| format!("built-in edge-aware ({} sweeps)", c.refine_sweeps)),
    })
}

/// Renders `scene` from `cameras` (planar RGB each).
pub fn render_rgb(gpu: &Gpu, scene: &GaussianScene, cameras: &[Camera], background: [f32; 3]) -> Result<Vec<Vec<f32>>> {
    let mut r = ViewRenderer::new(gpu, scene, None)?;
    cameras.iter().map(|c| Ok(r.render(c, background)?.rgb)).collect()
}
