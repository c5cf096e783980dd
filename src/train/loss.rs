//! The photometric loss on the GPU: (1 - lambda) L1 + lambda (1 - SSIM), SSIM with an 11x11 Gaussian
//! window (sigma 1.5, zero padding) as in the INRIA reference, optional per-pixel mask, and its
//! gradient with respect to the rendered image, in four passes over a 2D grid (ssim_stats_x.comp,
//! ssim_terms_y.comp, blur.comp, loss_grad.comp: each blur direction fused with what comes before or
//! after it). Where rows are 16-byte aligned every pass runs along the other axis
//! (ssim_stats_y.comp, ssim_terms_x.comp, blur_y.comp, loss_grad_x.comp), so that the two heavy
//! ones, along x, move vec4s. `reference` has the f64 CPU twin the tests compare against.

use crate::gpu::{Buffer, ComputePipeline, Gpu, MemoryKind, Recorder};
use crate::shaders;
use anyhow::{bail, Result};
use bytemuck::{Pod, Zeroable};

pub const SSIM_LAMBDA: f32 = 0.2;
/// The loss moves vec4s only for images whose width is a multiple of this (`PhotometricLoss::vectorized`).
pub const VECTOR_WIDTH: u32 = 4;
const CHANNELS: u32 = 3;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct StatsPush {
    render: u64,
    target: u64,
    stats: u64,
    width: u32,
    height: u32,
    channels: u32,
    pad: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct TermsPush {
    stats: u64,
    terms: u64,
    ssim_map: u64,
    mask: u64,
    width: u32,
    height: u32,
    channels: u32,
    inv_weight_sum: f32,
    has_mask: u32,
    pad: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct BlurPush {
    src: u64,
    dst: u64,
    width: u32,
    height: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct BlurYPush {
    src: u64,
    dst: u64,
    width: u32,
    height: u32,
    /// Floats between the three partials' planes.
    plane_stride: u32,
    pad: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GradPush {
    render: u64,
    target: u64,
    /// The partials blurred along one axis (x for loss_grad.comp, y for loss_grad_x.comp).
    terms: u64,
    dl_dx: u64,
    l1_map: u64,
    mask: u64,
    width: u32,
    height: u32,
    channels: u32,
    inv_weight_sum: f32,
    lambda: f32,
    has_mask: u32,
}

/// Workgroups of the passes that blur along x: each invocation a run of `run` pixels of a row, a
/// workgroup 8 runs by 8 rows (ssim_window.glsl).
fn grid_runs_along_x(run: u32, width: u32, height: u32, planes: u32) -> [u32; 3] {
    [width.div_ceil(8 * run), height.div_ceil(8), planes]
}

/// Workgroups of the passes that blur along y: each invocation a run of `run` rows of a column, a
/// workgroup 64 columns.
fn grid_runs_along_y(run: u32, width: u32, height: u32, planes: u32) -> [u32; 3] {
    [width.div_ceil(64), height.div_ceil(run), planes]
}

/// Outputs per invocation along the blurred axis (RUN in ssim_window.glsl). Measured on llvmpipe, the
/// loss at 512x512 in one session: one output per invocation 470 ms, runs of 8 169 ms, runs of 16
/// 137 ms; in a later session runs of 16 124 ms, runs of 32 116 ms; with the vec4 passes of aligned
/// rows, runs of 32 32.8 / 32.9 / 34.8 ms against runs of 64 30.5 / 31.5 / 30.9 ms (alternating).
fn run_for_device(info: &crate::gpu::DeviceInfo) -> u32 {
    if info.is_cpu() {
        64
    } else {
        8
    }
}

struct Scratch {
    width: u32,
    height: u32,
    a: Buffer,
    b: Buffer,
    ssim_map: Buffer,
    l1_map: Buffer,
    dl_drgb: Buffer,
}

/// Where the image, target and mask live; offsets let one buffer hold all of a dataset's targets.
pub struct LossInputs<'a> {
    /// Planar RGB render, width * height per plane.
    pub render: &'a Buffer,
    /// Planar RGB target at `target_offset` (in floats).
    pub target: &'a Buffer,
    pub target_offset: u64,
    /// Optional width * height mask (1 = counts) and its sum.
    pub mask: Option<(&'a Buffer, u64, f64)>,
}

pub struct PhotometricLoss {
    gpu: Gpu,
    stats_x: ComputePipeline,
    terms_y: ComputePipeline,
    blur: ComputePipeline,
    grad: ComputePipeline,
    stats_y: ComputePipeline,
    terms_x: ComputePipeline,
    blur_y: ComputePipeline,
    grad_x: ComputePipeline,
    scratch: Option<Scratch>,
    /// Outputs per invocation along the blurred axis.
    run: u32,
    pub lambda: f32,
}

impl PhotometricLoss {
    pub fn new(gpu: &Gpu) -> Result<PhotometricLoss> {
        Self::with_run(gpu, run_for_device(gpu.info()))
    }

    /// As `new`, with `run` outputs per invocation along the blurred axis (a power of two, 1-64).
    pub fn with_run(gpu: &Gpu, run: u32) -> Result<PhotometricLoss> {
        if !run.is_power_of_two() || run > 64 {
            bail!("loss: a run of {run} outputs per invocation is not a power of two up to 64");
        }
        let pass = |name, spirv| ComputePipeline::specialized(gpu, name, spirv, &[run]);
        Ok(PhotometricLoss {
            gpu: gpu.clone(),
            run,
            stats_x: pass("ssim_stats_x", shaders::SSIM_STATS_X)?,
            terms_y: pass("ssim_terms_y", shaders::SSIM_TERMS_Y)?,
            blur: pass("blur", shaders::BLUR)?,
            stats_y: pass("ssim_stats_y", shaders::SSIM_STATS_Y)?,
            terms_x: pass("ssim_terms_x", shaders::SSIM_TERMS_X)?,
            blur_y: pass("blur_y", shaders::BLUR_Y)?,
            grad_x: pass("loss_grad_x", shaders::LOSS_GRAD_X)?,
            grad: pass("loss_grad", shaders::LOSS_GRAD)?,
            scratch: None,
            lambda: SSIM_LAMBDA,
        })
    }

    fn reserve(&mut self, width: u32, height: u32) -> Result<()> {
        if self.scratch.as_ref().is_some_and(|s| s.width == width && s.height == height) {
            return Ok(());
        }
        let n = (width * height * CHANNELS) as u64;
        let g = &self.gpu;
        self.scratch = Some(Scratch {
            width,
            height,
            a: Buffer::new(g, "ssim scratch a", 5 * n * 4, MemoryKind::Device)?,
            b: Buffer::new(g, "ssim scratch b", 5 * n * 4, MemoryKind::Device)?,
            ssim_map: Buffer::new(g, "ssim map", n * 4, MemoryKind::Device)?,
            l1_map: Buffer::new(g, "l1 map", n * 4, MemoryKind::Device)?,
            dl_drgb: Buffer::new(g, "dl/drgb", n * 4, MemoryKind::Device)?,
        });
        Ok(())
    }

    /// Whether `record` moves vec4s for an image `width` wide with these inputs: every row and
    /// buffer 16-byte aligned (width a multiple of 4; the target and mask offsets too). Sizes the
    /// scratch buffers for width x height, as `record` does.
    pub fn vectorized(&mut self, width: u32, height: u32, inputs: &LossInputs) -> Result<bool> {
        self.reserve(width, height)?;
        let s = self.scratch.as_ref().unwrap();
        let target = inputs.target.address() + inputs.target_offset * 4;
        let mask = inputs.mask.map_or(0, |(b, offset, _)| b.address() + offset * 4);
        let scratch = [s.a.address(), s.b.address(), s.ssim_map.address(), s.l1_map.address(), s.dl_drgb.address()];
        let addresses = [inputs.render.address(), target, mask].into_iter().chain(scratch);
        Ok(width.is_multiple_of(VECTOR_WIDTH)
            && self.run.is_multiple_of(4)
            && addresses.into_iter().all(|a| a.is_multiple_of(16)))
    }

    /// Records the loss gradient into `dl_drgb()` and the weighted per-pixel SSIM and L1 maps.
    pub fn record(&mut self, rec: &mut Recorder, width: u32, height: u32, inputs: &LossInputs) -> Result<()> {
        let aligned = self.vectorized(width, height, inputs)?;
        let s = self.scratch.as_ref().unwrap();
        let hw = width * height;
        let n = hw * CHANNELS;
        let target = inputs.target.address() + inputs.target_offset * 4;
        let (mask, has_mask, weight_sum) = match inputs.mask {
            Some((b, offset, sum)) => (b.address() + offset * 4, 1, sum * CHANNELS as f64),
            None => (0, 0, n as f64),
        };
        let inv = (1.0 / weight_sum.max(1.0)) as f32;
        let (render, channels) = (inputs.render.address(), CHANNELS);
        // 1. x, y, x^2, y^2, xy blurred along x (along y where aligned) -> a
        let stats = StatsPush { render, target, stats: s.a.address(), width, height, channels, pad: 0 };
        if aligned {
            rec.dispatch(&self.stats_y, &stats, grid_runs_along_y(self.run, width, height, CHANNELS));
        } else {
            rec.dispatch(&self.stats_x, &stats, grid_runs_along_x(self.run, width, height, CHANNELS));
        }
        // 2. blurred along the other axis; SSIM and its weighted partials -> b, the SSIM map
        let terms = TermsPush {
            stats: s.a.address(),
            terms: s.b.address(),
            ssim_map: s.ssim_map.address(),
            mask,
            width,
            height,
            channels,
            inv_weight_sum: inv,
            has_mask,
            pad: 0,
        };
        if aligned {
            rec.dispatch(&self.terms_x, &terms, grid_runs_along_x(self.run, width, height, CHANNELS));
        } else {
            rec.dispatch(&self.terms_y, &terms, grid_runs_along_y(self.run, width, height, CHANNELS));
        }
        // 3. the partials blurred along x (along y where aligned) -> a
        let (src, dst) = (s.b.address(), s.a.address());
        if aligned {
            let blur = BlurYPush { src, dst, width, height, plane_stride: n, pad: 0 };
            rec.dispatch(&self.blur_y, &blur, grid_runs_along_y(self.run, width, height, CHANNELS));
        } else {
            let blur = BlurPush { src, dst, width, height };
            rec.dispatch(&self.blur, &blur, grid_runs_along_x(self.run, width, height, 3 * CHANNELS));
        }
        // 4. along the other axis, combined with L1 into dL/dx, and the L1 map
        let grad = GradPush {
            render,
            target,
            terms: s.a.address(),
            dl_dx: s.dl_drgb.address(),
            l1_map: s.l1_map.address(),
            mask,
            width,
            height,
            channels,
            inv_weight_sum: inv,
            lambda: self.lambda,
            has_mask,
        };
        if aligned {
            rec.dispatch(&self.grad_x, &grad, grid_runs_along_x(self.run, width, height, CHANNELS));
        } else {
            rec.dispatch(&self.grad, &grad, grid_runs_along_y(self.run, width, height, CHANNELS));
        }
        rec.mark_moved("loss", Self::bytes_moved(hw, inputs.mask.is_some()));
        Ok(())
    }

    /// Device-memory bytes the passes of `record` read and write for `hw` pixels, each plane counted
    /// once however many taps read it: render and target in, 5 statistics out; 5 in, 3 partials
    /// and the SSIM map out; 3 in, 3 out; 3 partials, render and target in, dL/dx and the L1 map out;
    /// per channel, 4 bytes each, plus the mask read twice.
    pub fn bytes_moved(hw: u32, masked: bool) -> u64 {
        let planes = (2 + 5) + (5 + 4) + (3 + 3) + (5 + 2);
        4 * hw as u64 * (planes * CHANNELS as u64 + if masked { 2 } else { 0 })
    }

    /// dL/d(render), planar RGB, after `record` ran.
    pub fn dl_drgb(&self) -> &Buffer {
        &self.scratch.as_ref().unwrap().dl_drgb
    }

    /// Reads back (loss, L1, SSIM) of the last recorded evaluation.
    pub fn read_values(&self) -> Result<(f64, f64, f64)> {
        let s = self.scratch.as_ref().unwrap();
        let n = (s.width * s.height * CHANNELS) as usize;
        let ssim: f64 = s.ssim_map.download::<f32>(&self.gpu, n)?.iter().map(|&v| v as f64).sum();
        let l1: f64 = s.l1_map.download::<f32>(&self.gpu, n)?.iter().map(|&v| v as f64).sum();
        let lambda = self.lambda as f64;
        Ok(((1.0 - lambda) * l1 + lambda * (1.0 - ssim), l1, ssim))
    }
}

/// f64 CPU twins of the loss (the metric math lives in `eval::image_metrics`), for tests.
pub use crate::eval::image_metrics as reference;
