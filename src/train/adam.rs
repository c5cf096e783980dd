//! Adam on the GPU (adam.comp), one parameter tensor per dispatch, with per-tensor learning rates.

use crate::gpu::{dispatch_1d, Buffer, ComputePipeline, Gpu, Recorder};
use crate::shaders;
use anyhow::Result;
use bytemuck::{Pod, Zeroable};

pub const BETA1: f32 = 0.9;
pub const BETA2: f32 = 0.999;
pub const EPS: f32 = 1e-15;

/// The scalars of one Adam step of one tensor; mirrors `AdamStep` in include/adam_step.glsl.
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
struct UpdatePush {
    grad: u64,
    m: u64,
    v: u64,
    update: u64,
    partial: u64,
    step: AdamStep,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ReducePush {
    values: u64,
    total: u64,
    count: u32,
    pad: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ApplyPush {
    param: u64,
    update: u64,
    total: u64,
    n: u32,
    radius: f32,
}

/// Scratch of the trust-region step: per-element updates, per-workgroup sums, the total.
struct ClipScratch {
    capacity: u32,
    update: Buffer,
    partial: Buffer,
    total: Buffer,
}

impl ClipScratch {
    fn new(gpu: &Gpu, capacity: u64) -> Result<ClipScratch> {
        let buf = |name: &str, floats: u64| Buffer::new(gpu, name, floats * 4, crate::gpu::MemoryKind::Device);
        Ok(ClipScratch {
            capacity: capacity as u32,
            update: buf("trust region update", capacity)?,
            partial: buf("trust region partial sums", capacity.div_ceil(256))?,
            total: buf("trust region total", 1)?,
        })
    }
}

/// Device-memory bytes one Adam step moves per element: parameter, gradient and both moments read,
/// parameter and moments written (4 bytes each).
pub const BYTES_PER_ELEMENT: u64 = 7 * 4;

/// Elements one workgroup of adam.comp updates (256 invocations, PER = 4 each).
const ELEMENTS_PER_GROUP: u32 = 4 * 256;

pub struct Adam {
    gpu: Gpu,
    pipeline: ComputePipeline,
    update: ComputePipeline,
    reduce: ComputePipeline,
    apply: ComputePipeline,
    /// Per slot, so tensors clipped in one submission do not share scratch.
    scratch: Vec<Option<ClipScratch>>,
}

impl Adam {
    pub fn new(gpu: &Gpu) -> Result<Adam> {
        Ok(Adam {
            gpu: gpu.clone(),
            pipeline: ComputePipeline::new(gpu, "adam", shaders::ADAM)?,
            update: ComputePipeline::new(gpu, "adam_update", shaders::ADAM_UPDATE)?,
            reduce: ComputePipeline::new(gpu, "reduce_sum", shaders::REDUCE_SUM)?,
            apply: ComputePipeline::new(gpu, "apply_update", shaders::APPLY_UPDATE)?,
            scratch: Vec::new(),
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

    /// As `record_split`, with the update of the whole tensor clipped to Euclidean norm `radius`
    /// (a trust region): p -= u * min(1, radius / |u|). `slot` names a scratch area: tensors clipped
    /// in the same submission need different slots.
    #[allow(clippy::too_many_arguments)]
    pub fn record_clipped(
        &mut self,
        rec: &mut Recorder,
        param: &Buffer,
        grad: &Buffer,
        moments: &Moments,
        rates: (f32, u32, u32, f32),
        step: u32,
        radius: f32,
        slot: usize,
    ) -> Result<()> {
        let n = moments.len;
        let groups = n.div_ceil(256);
        if self.scratch.len() <= slot {
            self.scratch.resize_with(slot + 1, || None);
        }
        if self.scratch[slot].as_ref().is_none_or(|s| s.capacity < n) {
            self.scratch[slot] = Some(ClipScratch::new(&self.gpu, crate::render::grow(n as u64))?);
        }
        let s = self.scratch[slot].as_ref().unwrap();
        let push = UpdatePush {
            grad: grad.address(),
            m: moments.m.address(),
            v: moments.v.address(),
            update: s.update.address(),
            partial: s.partial.address(),
            step: AdamStep::new(n, rates, step),
        };
        rec.dispatch(&self.update, &push, dispatch_1d(groups));
        rec.dispatch(
            &self.reduce,
            &ReducePush { values: s.partial.address(), total: s.total.address(), count: groups, pad: 0 },
            [1, 1, 1],
        );
        let apply =
            ApplyPush { param: param.address(), update: s.update.address(), total: s.total.address(), n, radius };
        rec.dispatch(&self.apply, &apply, dispatch_1d(groups));
        Ok(())
    }
}
