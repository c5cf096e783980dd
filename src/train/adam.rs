//! Adam on the GPU (adam.comp), one parameter tensor per dispatch, with per-tensor learning rates.

use crate::gpu::{dispatch_1d, Buffer, ComputePipeline, Gpu, Recorder};
use crate::shaders;
use anyhow::Result;
use bytemuck::{Pod, Zeroable};

pub const BETA1: f32 = 0.9;
pub const BETA2: f32 = 0.999;
pub const EPS: f32 = 1e-15;

/// The scalars of one Adam step of one tensor; mirrors `AdamStep` in train/adam_step.glsl.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(crate) struct AdamStep {
    n: u32,
    lr: f32,
    beta1: f32,
    beta2: f32,
    eps: f32,
    bias1: f32,
    bias2: f32,
    period: u32,
    head: u32,
    lr_tail: f32,
}

impl AdamStep {
    /// Step `step` (from 1) over `n` elements; `rates` = (lr, period, head, lr_tail).
    pub(crate) fn new(n: u32, rates: (f32, u32, u32, f32), step: u32) -> AdamStep {
        let (lr, period, head, lr_tail) = rates;
        AdamStep {
            n,
            lr,
            beta1: BETA1,
            beta2: BETA2,
            eps: EPS,
            bias1: 1.0 - BETA1.powi(step as i32),
            bias2: 1.0 - BETA2.powi(step as i32),
            period,
            head,
            lr_tail,
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct AdamPush {
    param: u64,
    grad: u64,
    m: u64,
    v: u64,
    step: AdamStep,
}

/// First and second moments of one tensor.
pub struct Moments {
    pub m: Buffer,
    pub v: Buffer,
    pub len: u32,
}

impl Moments {
    pub fn new(gpu: &Gpu, name: &str, len: u32) -> Result<Moments> {
        let m = Buffer::zeroed(gpu, &format!("{name} adam m"), len as u64 * 4)?;
        let v = Buffer::zeroed(gpu, &format!("{name} adam v"), len as u64 * 4)?;
        Ok(Moments { m, v, len })
    }
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ClippedPush {
    param: u64,
    grad: u64,
    m: u64,
    v: u64,
    step: AdamStep,
    width: u32,
    radius: f32,
}

/// Device-memory bytes one Adam step moves per element: parameter, gradient and both moments read,
/// parameter and moments written (4 bytes each).
pub const BYTES_PER_ELEMENT: u64 = 7 * 4;

/// Elements one workgroup of adam.comp updates (256 invocations, PER = 4 each).
const ELEMENTS_PER_GROUP: u32 = 4 * 256;

pub struct Adam {
    pipeline: ComputePipeline,
    clipped: ComputePipeline,
}

impl Adam {
    pub fn new(gpu: &Gpu) -> Result<Adam> {
        Ok(Adam {
            pipeline: ComputePipeline::new(gpu, "adam", shaders::ADAM)?,
            clipped: ComputePipeline::new(gpu, "adam_clipped", shaders::ADAM_CLIPPED)?,
        })
    }

    /// Records one step (`step` counts from 1) of `param -= ...` with gradient `grad`.
    pub fn record(&self, rec: &mut Recorder, param: &Buffer, grad: &Buffer, moments: &Moments, lr: f32, step: u32) {
        self.record_split(rec, param, grad, moments, (lr, 1, 1, lr), step);
    }

    /// As `record`, with two rates: element i uses `rates.0` when i % rates.1 < rates.2, else `rates.3`.
    pub fn record_split(
        &self,
        rec: &mut Recorder,
        param: &Buffer,
        grad: &Buffer,
        moments: &Moments,
        rates: (f32, u32, u32, f32),
        step: u32,
    ) {
        let push = AdamPush {
            param: param.address(),
            grad: grad.address(),
            m: moments.m.address(),
            v: moments.v.address(),
            step: AdamStep::new(moments.len, rates, step),
        };
        rec.dispatch(&self.pipeline, &push, dispatch_1d(moments.len.div_ceil(ELEMENTS_PER_GROUP)));
    }

    /// As `record`, for a tensor of rows of `width` elements (one per Gaussian, at most 4), with
    /// each row's update clipped to Euclidean norm `radius` (a trust region per Gaussian):
    /// p_row -= u_row * min(1, radius / |u_row|).
    #[allow(clippy::too_many_arguments)]
    pub fn record_clipped(
        &self,
        rec: &mut Recorder,
        param: &Buffer,
        grad: &Buffer,
        moments: &Moments,
        lr: f32,
        step: u32,
        width: u32,
        radius: f32,
    ) {
        assert!(
            (1..=4).contains(&width) && moments.len.is_multiple_of(width),
            "rows of {width} over {} elements",
            moments.len
        );
        let push = ClippedPush {
            param: param.address(),
            grad: grad.address(),
            m: moments.m.address(),
            v: moments.v.address(),
            step: AdamStep::new(moments.len, (lr, 1, 1, lr), step),
            width,
            radius,
        };
        rec.dispatch(&self.clipped, &push, dispatch_1d((moments.len / width).div_ceil(256)));
    }
}
