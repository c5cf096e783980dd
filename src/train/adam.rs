//! Adam on the GPU (adam.comp), one parameter tensor per dispatch, with per-tensor learning rates.

use crate::gpu::{dispatch_1d, Buffer, ComputePipeline, Gpu, Recorder};
use crate::shaders;
use anyhow::Result;
use bytemuck::{Pod, Zeroable};

pub const BETA1: f32 = 0.9;
pub const BETA2: f32 = 0.999;
pub const EPS: f32 = 1e-15;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct AdamPush {
    param: u64,
    grad: u64,
    m: u64,
    v: u64,
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

pub struct Adam {
    pipeline: ComputePipeline,
}

impl Adam {
    pub fn new(gpu: &Gpu) -> Result<Adam> {
        Ok(Adam { pipeline: ComputePipeline::new(gpu, "adam", shaders::ADAM)? })
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
        let (lr, period, head, lr_tail) = rates;
        let push = AdamPush {
            param: param.address(),
            grad: grad.address(),
            m: moments.m.address(),
            v: moments.v.address(),
            n: moments.len,
            lr,
            beta1: BETA1,
            beta2: BETA2,
            eps: EPS,
            bias1: 1.0 - BETA1.powi(step as i32),
            bias2: 1.0 - BETA2.powi(step as i32),
            period,
            head,
            lr_tail,
        };
        rec.dispatch(&self.pipeline, &push, dispatch_1d(moments.len.div_ceil(256)));
    }
}
