//! The training loop: per iteration one training view is rendered (forward passes), the photometric
//! loss and its gradient are computed, and the backward passes end in Adam updating every parameter
//! group with its INRIA learning rate (conventions.md): inside the projection backward
//! (train/fused.rs), or, for a trust-region step, on accumulated gradients per tensor. SH degree
//! grows by one every `TrainConfig::sh_band_every` iterations (1000). Densification runs on the
//! host every 100 iterations, carrying the Adam moments of surviving Gaussians: INRIA clone /
//! split / prune with opacity resets (`Strategy::Adc`), or 3DGS-MCMC relocation and growth to the
//! budget (`Strategy::Mcmc`, train/mcmc.rs, which also adds regularizer gradients before Adam and
//! a noise pass after it).

use super::adam::{Adam, Moments};
use super::exposure::ViewExposures;
use super::fused::{GroupStep, ProjectBackwardAdam};
use super::loss::{LossInputs, PhotometricLoss};
use super::mcmc::{self, McmcPasses, RelocationStats};
use crate::gpu::{Buffer, Gpu, Recorder};
use crate::render::backward::{Backward, PixelGradients, SceneGradients};
use crate::render::{Rasterizer, RenderSettings, SceneBuffers};
use crate::rng::Rng;
use crate::scene::colmap::Point3D;
use crate::scene::dataset::Dataset;
use crate::scene::{logit, sh_coeffs, GaussianScene, SH_C0};
use anyhow::{bail, Result};

mod adc;
mod evaluate;
mod exposure_maps;
mod iterate_average;

pub use evaluate::Metrics;
pub use iterate_average::IterateAverage;

pub use super::config::{Frozen, Motion, Strategy, TrainConfig};

/// Learning rates (conventions.md, INRIA defaults).
pub const LR_POSITION_INIT: f64 = 1.6e-4;
pub const LR_POSITION_FINAL: f64 = 1.6e-6;
pub const LR_SH_DC: f32 = 2.5e-3;
pub const LR_SH_REST: f32 = 2.5e-3 / 20.0;
pub const LR_OPACITY: f32 = 0.025;
pub const LR_SCALE: f32 = 5e-3;
pub const LR_ROTATION: f32 = 1e-3;

/// INRIA initialization from sparse points: color from the point, isotropic scale from the mean
/// squared distance to the 3 nearest neighbours, identity rotation, opacity 0.1.
pub fn init_from_points(points: &[Point3D], sh_degree: u32) -> Result<GaussianScene> {
    if points.len() < 4 {
        bail!("need at least 4 sparse points to initialize, got {}", points.len());
    }
    use kiddo::{KdTree, SquaredEuclidean};
    let mut tree: KdTree<f64, 3> = KdTree::new();
    for (i, p) in points.iter().enumerate() {
        tree.add(&p.xyz, i as u64);
    }
    let k = sh_coeffs(sh_degree);
    let mut scene = GaussianScene { sh_degree, ..Default::default() };
    for p in points {
        let nearest = tree.nearest_n::<SquaredEuclidean>(&p.xyz, 4);
        let d2: f64 = nearest.iter().skip(1).map(|n| n.distance).sum::<f64>() / 3.0;
        let s = d2.max(1e-7).sqrt().ln() as f32;
        let mut sh = vec![0.0; 3 * k];
        for c in 0..3 {
            sh[c] = ((p.rgb[c] as f64 / 255.0 - 0.5) / SH_C0) as f32;
        }
        scene.push(p.xyz.map(|v| v as f32), [s; 3], [1.0, 0.0, 0.0, 0.0], logit(0.1), &sh);
    }
    Ok(scene)
}

/// Adam state of the five parameter groups.
struct GroupMoments {
    means: Moments,
    log_scales: Moments,
    quats: Moments,
    opacity_logits: Moments,
    sh: Moments,
}

impl GroupMoments {
    fn new(gpu: &Gpu, n: u32, k: u32) -> Result<GroupMoments> {
        Ok(GroupMoments {
            means: Moments::new(gpu, "means", 3 * n)?,
            log_scales: Moments::new(gpu, "log_scales", 3 * n)?,
            quats: Moments::new(gpu, "quats", 4 * n)?,
            opacity_logits: Moments::new(gpu, "opacity", n)?,
            sh: Moments::new(gpu, "sh", 3 * k * n)?,
        })
    }
}

pub struct Trainer {
    gpu: Gpu,
    pub cfg: TrainConfig,
    extent: f64,
    scene: SceneBuffers,
    grads: SceneGradients,
    moments: GroupMoments,
    raster: Rasterizer,
    backward: Backward,
    loss: PhotometricLoss,
    adam: Adam,
    /// Every training image, planar RGB, one after another.
    targets: Buffer,
    target_offsets: Vec<u64>,
    /// The training views' camera names, in the dataset's order.
    view_names: Vec<String>,
    /// Per-pixel loss weights of every training view (`set_loss_masks`), one plane per view,
    /// and each view's weight sum.
    loss_masks: Option<(Buffer, Vec<f64>)>,
    /// Per training view, the loss's gradient with respect to the rendered alpha of each pixel
    /// (`set_alpha_gradients`), a constant: a loss linear in the alpha.
    alpha_gradients: Option<Vec<Buffer>>,
    /// Per-view exposure maps (`TrainConfig::exposure`, or fixed ones from `set_exposures`).
    exposure: Option<ViewExposures>,
    pub step: u32,
    rng: Rng,
    order: Vec<usize>,
    /// (loss, L1) of the last iteration whose values were read.
    pub last_loss: Option<(f64, f64)>,
    /// Record GPU timestamps per pass (see `last_timings`).
    pub profile: bool,
    /// Groups that get no update.
    pub frozen: Frozen,
    /// When set, each Gaussian's update per step of each geometry tensor (means, scales,
    /// rotations) is clipped to this Euclidean norm (a trust region per Gaussian).
    pub trust_radius: Option<f32>,
    /// Render with this SH degree from the first step (fine-tuning a trained scene) instead of
    /// growing it one band per `TrainConfig::sh_band_every` iterations.
    pub fixed_sh_degree: Option<u32>,
    /// Apply Adam inside the projection backward (train/fused.rs) instead of writing the parameter
    /// gradients and running Adam per tensor; on by default.
    pub fused_step: bool,
    fused: ProjectBackwardAdam,
    /// Set by `set_movable`: a `Motion` per Gaussian as a u32; and how many step all their
    /// parameters and how many all but the higher SH bands.
    movable: Option<(Buffer, [u32; 2])>,
    /// SH coefficients per channel whose Adam moments may be nonzero: those of every band rendered
    /// so far (the fused step leaves the rest alone, an exact no-op for them).
    sh_stepped: u32,
    mcmc: McmcPasses,
    /// What the last MCMC relocation did.
    pub last_relocation: RelocationStats,
    pub last_timings: Vec<crate::gpu::PassTiming>,
}

impl Trainer {
    pub fn new(gpu: &Gpu, dataset: &Dataset, scene: &GaussianScene, cfg: TrainConfig) -> Result<Trainer> {
        scene.validate("initial scene")?;
        let mut all = Vec::new();
        let mut target_offsets = Vec::new();
        for v in &dataset.train {
            target_offsets.push(all.len() as u64);
            all.extend_from_slice(&v.image);
        }
        let buffers = SceneBuffers::upload(gpu, scene, None)?;
        let grads = SceneGradients::new(gpu, &buffers)?;
        let k = sh_coeffs(scene.sh_degree) as u32;
        let backward = Backward::new(gpu, false)?;
        let exposure = match cfg.exposure {
            true => {
                let mut e = ViewExposures::new(gpu, dataset.train.len(), None)?;
                e.model = cfg.exposure_model;
                Some(e)
            }
            false => None,
        };
        Ok(Trainer {
            gpu: gpu.clone(),
            extent: dataset.extent,
            moments: GroupMoments::new(gpu, buffers.num_gaussians, k)?,
            scene: buffers,
            grads,
            raster: Rasterizer::new(gpu)?,
            loss: PhotometricLoss::new(gpu)?,
            adam: Adam::new(gpu)?,
            targets: Buffer::from_slice(gpu, "training images", &all)?,
            target_offsets,
            view_names: dataset.train.iter().map(|v| v.camera.name.clone()).collect(),
            loss_masks: None,
            alpha_gradients: None,
            exposure,
            step: 0,
            rng: Rng::new(cfg.seed),
            order: Vec::new(),
            cfg,
            last_loss: None,
            profile: false,
            frozen: Frozen::default(),
            trust_radius: None,
            fixed_sh_degree: None,
            fused_step: true,
            sh_stepped: 0,
            fused: ProjectBackwardAdam::new(gpu, backward.uses_cas)?,
            movable: None,
            backward,
            mcmc: McmcPasses::new(gpu)?,
            last_relocation: RelocationStats::default(),
            last_timings: Vec::new(),
        })
    }

    pub fn num_gaussians(&self) -> u32 {
        self.scene.num_gaussians
    }

    /// Weights each training view's loss per pixel (width x height per view, in the dataset's
    /// order; 0 = the pixel does not count): the loss becomes the weighted mean.
    pub fn set_loss_masks(&mut self, masks: &[Vec<f32>]) -> Result<()> {
        self.check_planes(masks, "loss masks", "weights")?;
        // one plane per view, one after another: view i's starts at target_offsets[i] / 3 (the
        // targets are planar RGB)
        let all: Vec<f32> = masks.concat();
        let sums = masks.iter().map(|m| m.iter().map(|&w| w as f64).sum()).collect();
        self.loss_masks = Some((Buffer::from_slice(&self.gpu, "loss masks", &all)?, sums));
        Ok(())
    }

    /// Adds to the loss a term linear in each training view's rendered alpha: `gradients` holds,
    /// per view and pixel, its derivative by that pixel's alpha (negative: coverage is rewarded).
    /// Without it the backward runs its color-only variant.
    pub fn set_alpha_gradients(&mut self, gradients: &[Vec<f32>]) -> Result<()> {
        self.check_planes(gradients, "alpha gradients", "values")?;
        let buffers = gradients.iter().map(|g| Buffer::from_slice(&self.gpu, "alpha gradients", g));
        self.alpha_gradients = Some(buffers.collect::<Result<_>>()?);
        Ok(())
    }

    /// One plane of `what` per training view, each of its view's pixel count.
    fn check_planes(&self, planes: &[Vec<f32>], what: &str, values: &str) -> Result<()> {
        if planes.len() != self.target_offsets.len() {
            anyhow::bail!("{} {what} for {} training views", planes.len(), self.target_offsets.len());
        }
        let total = self.targets.size() as usize / 4;
        for (i, (p, &offset)) in planes.iter().zip(&self.target_offsets).enumerate() {
            let pixels = (self.target_offsets.get(i + 1).map_or(total, |&o| o as usize) - offset as usize) / 3;
            if p.len() != pixels {
                anyhow::bail!("{what} {i}: {} {values} for an image of {pixels} pixels", p.len());
            }
        }
        Ok(())
    }

    /// Only the Gaussians `movable` marks (one `Motion` per Gaussian, in the scene's order) step
    /// from now on; the held ones still render and pass gradients on, but their parameters and
    /// Adam moments never change (the removal's refinement holds the scene away from the holes
    /// still). Needs the fused step, no densification (it would reorder the Gaussians) and the
    /// ADC strategy.
    pub fn set_movable(&mut self, movable: &[Motion]) -> Result<()> {
        if movable.len() != self.scene.num_gaussians as usize {
            anyhow::bail!("{} movable flags for {} Gaussians", movable.len(), self.scene.num_gaussians);
        }
        if self.cfg.densify {
            anyhow::bail!("movable Gaussians with densification: it reorders the Gaussians");
        }
        if self.cfg.strategy == Strategy::Mcmc {
            anyhow::bail!("movable Gaussians with the MCMC strategy: its position noise moves every Gaussian");
        }
        let flags: Vec<u32> = movable.iter().map(|&m| m as u32).collect();
        let count = |motion| movable.iter().filter(|&&m| m == motion).count() as u32;
        let moving = [count(Motion::Free), count(Motion::ViewIndependent)];
        self.movable = Some((Buffer::from_slice(&self.gpu, "movable Gaussians", &flags)?, moving));
        Ok(())
    }

    /// Fraction of the run done, for the decaying learning rates.
    fn progress(&self) -> f64 {
        (self.step as f64 / self.cfg.iters.max(1) as f64).min(1.0)
    }

    fn position_lr(&self) -> f32 {
        let t = self.progress();
        ((LR_POSITION_INIT.ln() * (1.0 - t) + LR_POSITION_FINAL.ln() * t).exp() * self.extent) as f32
    }

    /// Learning rates of the SH DC coefficient and of the higher bands.
    fn sh_lrs(&self) -> (f32, f32) {
        (self.cfg.color_lr_gain * LR_SH_DC, self.cfg.color_lr_gain * LR_SH_REST)
    }

    /// Learning rates of the log-scales and of the rotations.
    fn shape_lrs(&self) -> (f32, f32) {
        (self.cfg.shape_lr_gain * LR_SCALE, self.cfg.shape_lr_gain * LR_ROTATION)
    }

    /// The SH degree the next iteration renders with.
    pub fn active_sh_degree(&self) -> u32 {
        if let Some(d) = self.fixed_sh_degree {
            return d.min(self.scene.sh_degree);
        }
        (self.step / self.cfg.sh_band_every.max(1)).min(self.scene.sh_degree)
    }

    fn next_view(&mut self, count: usize) -> usize {
        if self.order.is_empty() {
            self.order = (0..count).collect();
            for i in (1..count).rev() {
                let j = (self.rng.next_u64() % (i as u64 + 1)) as usize;
                self.order.swap(i, j);
            }
        }
        self.order.pop().unwrap()
    }

    /// One iteration. `read_loss` reads the loss back (costs a sync and a download).
    pub fn iterate(&mut self, dataset: &Dataset, read_loss: bool) -> Result<()> {
        self.step += 1;
        let vi = self.next_view(dataset.train.len());
        let view = &dataset.train[vi];
        let settings = RenderSettings {
            background: self.cfg.background,
            sh_degree: Some(self.active_sh_degree()),
            timestamps: self.profile,
            ..Default::default()
        };
        // the forward's second submission stays open: loss, backward and Adam follow in it, so an
        // iteration is two submissions (the first ends at the one readback, the intersection count)
        let (frame, mut rec) = self.raster.forward_open(&self.scene, &view.camera, &settings)?;
        let outputs = self.raster.outputs().unwrap();
        self.sh_stepped = self.sh_stepped.max(sh_coeffs(self.active_sh_degree()) as u32);
        let fused = self.fused_step;
        if !fused && self.movable.is_some() {
            anyhow::bail!("movable Gaussians (set_movable) need the fused step");
        }
        if !fused {
            self.grads.record_zero_parameters(&mut rec);
        }
        let (width, height) = (view.camera.width, view.camera.height);
        let rendered = match self.exposure.as_mut() {
            Some(e) => e.record_apply(&mut rec, outputs.rgb, vi, width * height)?,
            None => outputs.rgb,
        };
        let inputs = LossInputs {
            render: rendered,
            target: &self.targets,
            target_offset: self.target_offsets[vi],
            mask: self.loss_masks.as_ref().map(|(b, sums)| (b, self.target_offsets[vi] / 3, sums[vi])),
        };
        self.loss.record(&mut rec, width, height, &inputs)?;
        let exposure_lr = self.exposure_lr();
        let dl_drgb = match self.exposure.as_mut() {
            Some(e) => {
                e.record_backward(&mut rec, outputs.rgb, self.loss.dl_drgb(), vi, exposure_lr, self.cfg.exposure_reg)?
            }
            None => self.loss.dl_drgb(),
        };
        let alpha = self.alpha_gradients.as_ref().map(|g| &g[vi]);
        let upstream = PixelGradients { rgb: dl_drgb, alpha, depth: None, expected_depth: None, features: None };
        let render_params = self.raster.params_buffer();
        if fused {
            self.backward.record_to_projected(&mut rec, render_params, &frame.params, &upstream, &self.grads)?;
        } else {
            self.backward.record(&mut rec, render_params, &frame.params, &upstream, &self.grads, false)?;
        }
        let f = self.frozen;
        let mcmc = self.cfg.strategy == Strategy::Mcmc;
        let regularizer = if mcmc {
            (if f.opacity { 0.0 } else { mcmc::OPACITY_REG }, if f.log_scales { 0.0 } else { mcmc::SCALE_REG })
        } else {
            (0.0, 0.0)
        };
        if fused {
            self.record_fused_step(&mut rec, frame.params.sh_degree, regularizer)?;
        } else {
            self.record_adam_apart(&mut rec, mcmc, regularizer)?;
        }
        if mcmc && !f.means {
            let seed = (self.cfg.seed as u32).wrapping_mul(0x9e37_79b9) ^ self.step;
            self.mcmc.record_noise(&mut rec, &self.scene, mcmc::NOISE_LR * self.position_lr(), seed);
            rec.mark("mcmc noise");
        }
        let mut timings = frame.timings;
        timings.extend(rec.submit_and_wait()?);
        self.last_timings = timings;
        if read_loss {
            let (loss, l1, _) = self.loss.read_values()?;
            self.last_loss = Some((loss, l1));
        }
        if self.cfg.densify && self.step <= self.cfg.densify_until {
            if self.step >= self.cfg.densify_from && self.step.is_multiple_of(self.cfg.densify_interval) {
                match self.cfg.strategy {
                    Strategy::Adc => self.densify()?,
                    Strategy::Mcmc => self.relocate()?,
                }
            }
            if self.cfg.strategy == Strategy::Adc && self.step.is_multiple_of(self.cfg.opacity_reset_interval) {
                self.reset_opacity()?;
            }
        }
        Ok(())
    }

    /// Accumulate gradients with compare-and-swap even where float atomics exist (tests of the
    /// `_cas` shader variants).
    pub fn force_compare_and_swap(&mut self) -> Result<()> {
        self.backward = Backward::new(&self.gpu, true)?;
        self.fused = ProjectBackwardAdam::new(&self.gpu, true)?;
        Ok(())
    }

    /// Projection backward and Adam of every group in one pass (train/fused.rs).
    fn record_fused_step(&mut self, rec: &mut Recorder, sh_degree: u32, regularizer: (f32, f32)) -> Result<()> {
        let (s, m, f) = (&self.scene, &self.moments, self.frozen);
        let group = |moments, lr, lr_tail, frozen| GroupStep { moments, lr, lr_tail, frozen };
        let (sh_dc, sh_rest) = self.sh_lrs();
        let (scale_lr, rotation_lr) = self.shape_lrs();
        let groups = [
            group(&m.means, self.position_lr(), self.position_lr(), f.means),
            group(&m.log_scales, scale_lr, scale_lr, f.log_scales),
            group(&m.quats, rotation_lr, rotation_lr, f.quats),
            group(&m.opacity_logits, LR_OPACITY, LR_OPACITY, f.opacity),
            group(&m.sh, sh_dc, sh_rest, f.sh),
        ];
        let params = self.raster.params_buffer();
        let stepped = self.sh_stepped;
        self.fused.record(
            rec,
            params,
            self.backward.params(),
            sh_degree,
            s,
            &groups,
            regularizer,
            self.step,
            stepped,
            self.trust_radius,
            self.movable.as_ref().map(|(flags, _)| flags),
        )?;
        // a held Gaussian reads its flag only
        let bytes = match self.movable {
            Some((_, [free, first_band])) => {
                let held = s.num_gaussians - free - first_band;
                free as u64 * super::fused::bytes_per_gaussian(stepped)
                    + first_band as u64 * super::fused::bytes_per_gaussian(stepped.min(1))
                    + 4 * held as u64
            }
            None => s.num_gaussians as u64 * super::fused::bytes_per_gaussian(stepped),
        };
        rec.mark_moved("project backward + adam", bytes);
        Ok(())
    }

    /// The MCMC regularizer and Adam per tensor on the accumulated parameter gradients; geometry
    /// steps clipped to the trust radius when one is set.
    fn record_adam_apart(&mut self, rec: &mut Recorder, mcmc: bool, regularizer: (f32, f32)) -> Result<()> {
        let s = &self.scene;
        let g = &self.grads;
        let m = &self.moments;
        let k = sh_coeffs(s.sh_degree) as u32;
        let f = self.frozen;
        if mcmc {
            self.mcmc.record_regularize(rec, s, g, regularizer);
        }
        // bytes of the Adam passes (the clipped step moves the same per element)
        let adam_elements = |frozen: bool, m: &super::adam::Moments| if frozen { 0 } else { m.len as u64 };
        let adam_bytes = super::adam::BYTES_PER_ELEMENT
            * (adam_elements(f.means, &m.means)
                + adam_elements(f.log_scales, &m.log_scales)
                + adam_elements(f.quats, &m.quats)
                + adam_elements(f.opacity, &m.opacity_logits)
                + adam_elements(f.sh, &m.sh));
        let (scale_lr, rotation_lr) = self.shape_lrs();
        let geometry = [
            (f.means, &s.means, &g.means, &m.means, self.position_lr(), 3),
            (f.log_scales, &s.log_scales, &g.log_scales, &m.log_scales, scale_lr, 3),
            (f.quats, &s.quats, &g.quats, &m.quats, rotation_lr, 4),
        ];
        for (frozen, param, grad, moments, lr, width) in geometry {
            match (frozen, self.trust_radius) {
                (true, _) => {}
                (false, Some(radius)) => {
                    self.adam.record_clipped(rec, param, grad, moments, lr, self.step, width, radius)
                }
                (false, None) => self.adam.record(rec, param, grad, moments, lr, self.step),
            }
        }
        if !f.opacity {
            self.adam.record(rec, &s.opacity_logits, &g.opacity_logits, &m.opacity_logits, LR_OPACITY, self.step);
        }
        if !f.sh {
            let (dc, rest) = self.sh_lrs();
            self.adam.record_split(rec, &s.sh, &g.sh, &m.sh, (dc, 3 * k, 3, rest), self.step);
        }
        rec.mark_moved("adam", adam_bytes);
        Ok(())
    }

    /// Downloads the current scene.
    pub fn download_scene(&self) -> Result<GaussianScene> {
        let g = &self.gpu;
        let s = &self.scene;
        let n = s.num_gaussians as usize;
        let k = sh_coeffs(s.sh_degree);
        let f = |b: &Buffer, per: usize| b.download::<f32>(g, n * per);
        let means = f(&s.means, 3)?;
        let scales = f(&s.log_scales, 3)?;
        let quats = f(&s.quats, 4)?;
        Ok(GaussianScene {
            means: means.chunks(3).map(|c| [c[0], c[1], c[2]]).collect(),
            normals: vec![[0.0; 3]; n],
            log_scales: scales.chunks(3).map(|c| [c[0], c[1], c[2]]).collect(),
            quats: quats.chunks(4).map(|c| [c[0], c[1], c[2], c[3]]).collect(),
            opacity_logits: f(&s.opacity_logits, 1)?,
            sh_degree: s.sh_degree,
            sh: f(&s.sh, 3 * k)?,
            extras: Vec::new(),
        })
    }

    fn download_moments(&self, m: &Moments) -> Result<(Vec<f32>, Vec<f32>)> {
        Ok((m.m.download(&self.gpu, m.len as usize)?, m.v.download(&self.gpu, m.len as usize)?))
    }

    /// Replaces the scene; `keep[i]` = Some(old index) carries that Gaussian's Adam moments, None starts
    /// from zero.
    fn replace_scene(&mut self, scene: &GaussianScene, keep: &[Option<usize>]) -> Result<()> {
        let gpu = self.gpu.clone();
        let carry = |m: &Moments, per: usize| -> Result<Moments> {
            let (mm, vv) = self.download_moments(m)?;
            let pick = |src: &[f32]| -> Vec<f32> {
                keep.iter()
                    .flat_map(|o| match o {
                        Some(i) => src[i * per..(i + 1) * per].to_vec(),
                        None => vec![0.0; per],
                    })
                    .collect()
            };
            Ok(Moments {
                m: Buffer::from_slice(&gpu, "adam m", &pick(&mm))?,
                v: Buffer::from_slice(&gpu, "adam v", &pick(&vv))?,
                len: (keep.len() * per) as u32,
            })
        };
        let k = sh_coeffs(scene.sh_degree);
        let moments = GroupMoments {
            means: carry(&self.moments.means, 3)?,
            log_scales: carry(&self.moments.log_scales, 3)?,
            quats: carry(&self.moments.quats, 4)?,
            opacity_logits: carry(&self.moments.opacity_logits, 1)?,
            sh: carry(&self.moments.sh, 3 * k)?,
        };
        self.moments = moments;
        self.scene = SceneBuffers::upload(&gpu, scene, None)?;
        self.grads = SceneGradients::new(&gpu, &self.scene)?;
        Ok(())
    }

    /// MCMC step: relocate dead Gaussians and grow towards the budget (train/mcmc.rs).
    fn relocate(&mut self) -> Result<()> {
        let scene = self.download_scene()?;
        let (out, keep, stats) = mcmc::relocate_and_grow(&scene, self.cfg.max_gaussians, &mut self.rng)?;
        self.last_relocation = stats;
        self.replace_scene(&out, &keep)
    }

    /// Restores the optimizer position after a resume.
    pub fn set_step(&mut self, step: u32) {
        self.step = step;
    }

    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    /// Host copies of the Adam moments, in group order (for checkpoints).
    pub fn moments_host(&self) -> Result<Vec<(Vec<f32>, Vec<f32>)>> {
        let m = &self.moments;
        [&m.means, &m.log_scales, &m.quats, &m.opacity_logits, &m.sh].iter().map(|x| self.download_moments(x)).collect()
    }

    /// Replaces the Adam moments (from a checkpoint); lengths must match the scene.
    pub fn load_moments(&mut self, host: &[(Vec<f32>, Vec<f32>)]) -> Result<()> {
        let mm = &self.moments;
        let groups = [&mm.means, &mm.log_scales, &mm.quats, &mm.opacity_logits, &mm.sh];
        if host.len() != groups.len() {
            bail!("checkpoint has {} optimizer groups, expected {}", host.len(), groups.len());
        }
        for (g, (m, v)) in groups.iter().zip(host) {
            if m.len() != g.len as usize || v.len() != g.len as usize {
                bail!("checkpoint optimizer state does not match the scene size");
            }
            g.m.upload(&self.gpu, m)?;
            g.v.upload(&self.gpu, v)?;
        }
        // the SH coefficients with any nonzero moment, per channel ([gaussian][coefficient][channel])
        let k = sh_coeffs(self.scene.sh_degree);
        let (m, v) = &host[4];
        let last_nonzero = (0..k).rev().find(|&c| {
            let touched = |x: &Vec<f32>| x.chunks(3 * k).any(|row| row[3 * c..3 * c + 3].iter().any(|&e| e != 0.0));
            touched(m) || touched(v)
        });
        self.sh_stepped = last_nonzero.map_or(0, |c| c as u32 + 1);
        Ok(())
    }
}
