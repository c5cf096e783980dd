//! Per-view exposure compensation in training (`cogeo train --exposure`): each training view v
//! has an affine color map y = A_v x + b_v (scene::exposure::ColorAffine) applied to the render
//! before that view's loss, so a photo taken brighter or warmer than the others is explained by
//! its camera, not painted into the scene. The maps start at identity, learn by Adam with each
//! view's own step count, and are pulled toward identity by `reg |A - I|^2 + reg |b|^2`. The
//! maps' common part, which no image depends on, is moved into the scene at the end of training
//! (`Trainer::settle_exposure_gauge`); each view's own part never is.
//!
//! Three passes: exposure_apply.comp (render -> corrected), exposure_backward.comp (dL/dx = A^T
//! dL/dy for the rasterizer's backward, and per-workgroup partial sums of dL/dA, dL/db),
//! exposure_step.comp (the sums in a fixed order, the regularizer, Adam).

use super::adam::{AdamStep, Moments};
use crate::gpu::{dispatch_1d, Buffer, ComputePipeline, Gpu, MemoryKind, Recorder};
use crate::scene::exposure::ColorAffine;
use crate::shaders;
use anyhow::{bail, Result};
use bytemuck::{Pod, Zeroable};

/// Parameters per view: A row-major, then b.
pub const PARAMS: usize = 12;
/// Pixels per workgroup of exposure_apply.comp (256 invocations, PER = 4).
const APPLY_PIXELS_PER_GROUP: u32 = 4 * 256;
/// At most this many workgroups share the gradient sums (each writes 12 partials).
const MAX_REDUCE_GROUPS: u32 = 64;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ApplyPush {
    render: u64,
    corrected: u64,
    params: u64,
    view: u32,
    pixels: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct BackwardPush {
    render: u64,
    dl_dy: u64,
    dl_dx: u64,
    params: u64,
    partials: u64,
    view: u32,
    pixels: u32,
    chunk: u32,
    pad: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct StepPush {
    params: u64,
    partials: u64,
    m: u64,
    v: u64,
    step: AdamStep,
    view: u32,
    groups: u32,
    reg: f32,
    full_matrix: u32,
}

/// Workgroups of exposure_backward.comp for `pixels` and the pixels each covers (a multiple of 256).
fn reduce_grid(pixels: u32) -> (u32, u32) {
    let groups = pixels.div_ceil(4 * 256).clamp(1, MAX_REDUCE_GROUPS);
    (groups, pixels.div_ceil(groups).next_multiple_of(256))
}

/// The learned maps of a dataset's training views and the passes that apply and learn them.
pub struct ViewExposures {
    gpu: Gpu,
    apply: ComputePipeline,
    backward: ComputePipeline,
    step: ComputePipeline,
    params: Buffer,
    moments: Moments,
    /// Adam steps taken per view.
    steps: Vec<u32>,
    corrected: Option<Buffer>,
    dl_dx: Option<Buffer>,
    partials: Buffer,
    pixels: u32,
    /// Whether the maps learn (false: fixed, e.g. read from a trained scene's exposure.json).
    pub learn: bool,
    /// Which of the 12 parameters learn.
    pub model: ExposureModel,
}

/// What a view's map may do.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize, clap::ValueEnum)]
pub enum ExposureModel {
    /// Per-channel gain and bias (6 numbers per view): exposure and white balance. On the synth
    /// captures with jittered gains it recovers them better than the full matrix, whose 3x3 mixes
    /// channels that the scene's colors do not tell apart.
    #[default]
    GainBias,
    /// A full 3x3 color matrix and bias (12 numbers per view), for color-processing changes
    /// beyond white balance.
    Affine,
}

impl ViewExposures {
    /// Maps for `views` training views, starting at `initial` (identity where None).
    pub fn new(gpu: &Gpu, views: usize, initial: Option<&[ColorAffine]>) -> Result<ViewExposures> {
        if initial.is_some_and(|i| i.len() != views) {
            bail!("exposure: {} initial maps for {views} views", initial.unwrap().len());
        }
        let params: Vec<f32> =
            (0..views).flat_map(|v| initial.map_or(ColorAffine::IDENTITY, |i| i[v]).to_params()).collect();
        Ok(ViewExposures {
            gpu: gpu.clone(),
            apply: ComputePipeline::new(gpu, "exposure_apply", shaders::EXPOSURE_APPLY)?,
            backward: ComputePipeline::new(gpu, "exposure_backward", shaders::EXPOSURE_BACKWARD)?,
            step: ComputePipeline::new(gpu, "exposure_step", shaders::EXPOSURE_STEP)?,
            params: Buffer::from_slice(gpu, "exposure maps", &params)?,
            moments: Moments::new(gpu, "exposure", (views * PARAMS) as u32)?,
            steps: vec![0; views],
            corrected: None,
            dl_dx: None,
            partials: Buffer::zeroed(gpu, "exposure partial sums", (MAX_REDUCE_GROUPS as u64) * PARAMS as u64 * 4)?,
            pixels: 0,
            learn: true,
            model: ExposureModel::default(),
        })
    }

    fn reserve(&mut self, pixels: u32) -> Result<()> {
        if self.corrected.is_some() && self.pixels == pixels {
            return Ok(());
        }
        let bytes = 3 * pixels as u64 * 4;
        self.corrected = Some(Buffer::new(&self.gpu, "exposure-corrected render", bytes, MemoryKind::Device)?);
        self.dl_dx = Some(Buffer::new(&self.gpu, "dl/drender through exposure", bytes, MemoryKind::Device)?);
        self.pixels = pixels;
        Ok(())
    }

    /// Records view `view`'s map applied to `render` (planar RGB, `pixels` per plane); returns
    /// the corrected image's buffer, the loss's input.
    pub fn record_apply(&mut self, rec: &mut Recorder, render: &Buffer, view: usize, pixels: u32) -> Result<&Buffer> {
        self.reserve(pixels)?;
        let corrected = self.corrected.as_ref().unwrap();
        let push = ApplyPush {
            render: render.address(),
            corrected: corrected.address(),
            params: self.params.address(),
            view: view as u32,
            pixels,
        };
        rec.dispatch(&self.apply, &push, dispatch_1d(pixels.div_ceil(APPLY_PIXELS_PER_GROUP)));
        rec.mark("exposure apply");
        Ok(corrected)
    }

    /// Records the backward of `record_apply` for the loss gradient `dl_dy`: dL/d(render) into
    /// the returned buffer and, when the maps learn, one Adam step of view `view`'s map at `lr`
    /// with regularizer weight `reg`.
    pub fn record_backward(
        &mut self,
        rec: &mut Recorder,
        render: &Buffer,
        dl_dy: &Buffer,
        view: usize,
        lr: f32,
        reg: f32,
    ) -> Result<&Buffer> {
        let pixels = self.pixels;
        let (groups, chunk) = reduce_grid(pixels);
        let dl_dx = self.dl_dx.as_ref().expect("record_apply ran");
        let push = BackwardPush {
            render: render.address(),
            dl_dy: dl_dy.address(),
            dl_dx: dl_dx.address(),
            params: self.params.address(),
            partials: self.partials.address(),
            view: view as u32,
            pixels,
            chunk,
            pad: 0,
        };
        rec.dispatch(&self.backward, &push, [groups, 1, 1]);
        if self.learn {
            self.steps[view] += 1;
            let step = AdamStep::new(self.moments.len, (lr, 1, 1, lr), self.steps[view]);
            let push = StepPush {
                params: self.params.address(),
                partials: self.partials.address(),
                m: self.moments.m.address(),
                v: self.moments.v.address(),
                step,
                view: view as u32,
                groups,
                reg,
                full_matrix: (self.model == ExposureModel::Affine) as u32,
            };
            rec.dispatch(&self.step, &push, [1, 1, 1]);
        }
        rec.mark("exposure backward");
        Ok(self.dl_dx.as_ref().unwrap())
    }

    /// The maps, in training-view order.
    pub fn download(&self) -> Result<Vec<ColorAffine>> {
        let p: Vec<f32> = self.params.download(&self.gpu, self.steps.len() * PARAMS)?;
        Ok(p.chunks(PARAMS).map(ColorAffine::from_params).collect())
    }

    /// The sums of the last `record_backward` (dL/dA row-major, dL/db), for tests.
    pub fn download_gradient(&self) -> Result<[f64; PARAMS]> {
        let (groups, _) = reduce_grid(self.pixels);
        let p: Vec<f32> = self.partials.download(&self.gpu, groups as usize * PARAMS)?;
        let mut g = [0f64; PARAMS];
        for row in p.chunks(PARAMS) {
            for (s, &v) in g.iter_mut().zip(row) {
                *s += v as f64;
            }
        }
        Ok(g)
    }

    /// The corrected render of the last `record_apply`, for tests.
    pub fn corrected(&self) -> Option<&Buffer> {
        self.corrected.as_ref()
    }

    /// dL/d(render) of the last `record_backward`, for tests.
    pub fn dl_drender(&self) -> Option<&Buffer> {
        self.dl_dx.as_ref()
    }
}
