//! The device's copy bandwidth: the roof a memory-bound pass is measured against. Two copies of
//! the same buffer are timed with GPU timestamps: the transfer copy (vkCmdCopyBuffer; on lavapipe
//! a memcpy on one thread) and a compute pass copying 16-byte words (copy_words.comp, in a few
//! shapes, the best counts). The compute copy is what a shader that streams its bytes once can
//! reach, so it is the roof of the benches' roofline columns; on lavapipe it is far below the
//! memcpy (its loads and stores are per-lane gathers and scatters), on a GPU the two are close.

use super::{dispatch_1d, Buffer, ComputePipeline, Gpu, MemoryKind, Recorder};
use crate::shaders;
use anyhow::{bail, Result};

#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct CopyBandwidth {
    /// Bytes read plus bytes written per second, GB/s, of vkCmdCopyBuffer.
    pub transfer_gbps: f64,
    /// The same for the compute copy.
    pub shader_gbps: f64,
}

impl CopyBandwidth {
    /// The roof of a compute pass: the compute copy.
    pub fn roof_gbps(&self) -> f64 {
        self.shader_gbps
    }
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct CopyPush {
    src: u64,
    dst: u64,
    n: u32,
    per: u32,
    blocked: u32,
    pad: u32,
}

/// Measures both copies of `bytes` (a multiple of 16) `repeats` times; each result is the median.
/// A copy moves 2 x `bytes` (read and write), which is what the GB/s count.
pub fn measure(gpu: &Gpu, bytes: u64, repeats: usize) -> Result<CopyBandwidth> {
    if bytes == 0 || !bytes.is_multiple_of(16) || repeats == 0 {
        bail!("copy bandwidth: need a positive multiple of 16 bytes and at least one repeat");
    }
    let src = Buffer::new(gpu, "bandwidth source", bytes, MemoryKind::Device)?;
    let dst = Buffer::new(gpu, "bandwidth destination", bytes, MemoryKind::Device)?;
    let pipeline = ComputePipeline::new(gpu, "copy_words", shaders::COPY_WORDS)?;
    let words = (bytes / 16) as u32;
    // shapes of the compute copy (words per invocation; consecutive across invocations, or per
    // invocation): lavapipe pays microseconds per workgroup, so one word per invocation reaches half
    // of what four do; a GPU is indifferent. The best shape is the roof.
    let shapes = [(1, 0), (4, 0), (16, 0), (4, 1)];
    let (mut transfer, mut shader) = (Vec::new(), vec![Vec::new(); shapes.len()]);
    for _ in 0..repeats + 1 {
        let mut rec = Recorder::with_timestamps(gpu, true)?;
        rec.fill(&src, 0, bytes, 0x3f80_0000);
        rec.mark("fill");
        rec.copy(&src, &dst, bytes);
        rec.mark("transfer");
        for (k, &(per, blocked)) in shapes.iter().enumerate() {
            let push = CopyPush { src: src.address(), dst: dst.address(), n: words, per, blocked, pad: 0 };
            rec.dispatch(&pipeline, &push, dispatch_1d(words.div_ceil(256 * per)));
            rec.mark(&format!("shader {k}"));
        }
        let t = rec.submit_and_wait()?;
        let gbps = |name: &str| t.iter().find(|p| p.pass == name).map(|p| 2.0 * bytes as f64 / (p.ms * 1e6));
        transfer.push(gbps("transfer").ok_or_else(|| anyhow::anyhow!("copy bandwidth: the device has no timestamps"))?);
        for (k, times) in shader.iter_mut().enumerate() {
            times.push(gbps(&format!("shader {k}")).unwrap());
        }
    }
    // the first round warms up allocations and caches
    let median = |mut v: Vec<f64>| {
        v.remove(0);
        v.sort_by(|a, b| a.total_cmp(b));
        v[v.len() / 2]
    };
    let shader_gbps = shader.into_iter().map(median).fold(0.0, f64::max);
    Ok(CopyBandwidth { transfer_gbps: median(transfer), shader_gbps })
}
