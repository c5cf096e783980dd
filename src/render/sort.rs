//! Stable GPU radix sort of (u32 key, u32 value) pairs: 8-bit digits, reduce-then-scan per pass
//! (radix_count.comp, exclusive scan of the digit-major histogram, radix_scatter.comp). A block's
//! keys are ranked by one subgroup walking it in rows (the workgroup is one subgroup of the device's
//! size) and no workgroup waits on another. Only the key bits asked for are sorted: tile ids take
//! ceil(log2(tiles)) bits, so a 1080p frame's tile sort is two passes.

use super::scan::PrefixScan;
use crate::gpu::{dispatch_1d, Buffer, ComputePipeline, Gpu, MemoryKind, Recorder};
use crate::shaders;
use anyhow::{bail, Result};
use bytemuck::{Pod, Zeroable};

/// Keys per workgroup (one subgroup walks them in rows of its size; BLOCK_KEYS in radix_common.glsl).
pub const BLOCK_KEYS: u32 = 4096;
pub const RADIX_BITS: u32 = 8;
const RADIX: u32 = 1 << RADIX_BITS;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct SortPush {
    keys_in: u64,
    values_in: u64,
    keys_out: u64,
    values_out: u64,
    histogram: u64,
    n: u32,
    shift: u32,
    num_blocks: u32,
    digit_mask: u32,
}

pub struct RadixSort {
    gpu: Gpu,
    count: ComputePipeline,
    scatter: ComputePipeline,
    scan: PrefixScan,
    histogram: Option<Buffer>,
    capacity: u64,
}

/// Number of 8-bit passes needed to sort keys below 2^bits.
pub fn passes_for_bits(bits: u32) -> u32 {
    bits.div_ceil(RADIX_BITS)
}

/// Bytes a sort of `n` pairs by `bits` key bits must move: per pass, the count reads the keys, the
/// histogram scan reads and writes the block histograms, the scatter reads them and the pairs and
/// writes the pairs. The roofline of `cargo bench --bench sort` divides by this.
pub fn bytes_moved(n: u64, bits: u32) -> u64 {
    let histogram = n.div_ceil(BLOCK_KEYS as u64) * RADIX as u64 * 4;
    let per_pass = 4 * n + 2 * histogram + (histogram + 16 * n);
    passes_for_bits(bits) as u64 * per_pass
}

impl RadixSort {
    /// The sort for this device; its workgroups are one subgroup of the device's size.
    pub fn new(gpu: &Gpu) -> Result<RadixSort> {
        let subgroup = gpu.info().subgroup_size;
        if !subgroup.is_power_of_two() || !(4..=128).contains(&subgroup) {
            bail!("radix sort: subgroup size {subgroup} is not a power of two from 4 to 128");
        }
        let constants = [subgroup];
        Ok(RadixSort {
            gpu: gpu.clone(),
            count: ComputePipeline::specialized(gpu, "radix_count", shaders::RADIX_COUNT, &constants)?,
            scatter: ComputePipeline::specialized(gpu, "radix_scatter", shaders::RADIX_SCATTER, &constants)?,
            scan: PrefixScan::new(gpu)?,
            histogram: None,
            capacity: 0,
        })
    }

    /// Makes sure up to `n` pairs can be sorted.
    pub fn reserve(&mut self, n: u64) -> Result<()> {
        if n <= self.capacity && self.histogram.is_some() {
            return Ok(());
        }
        let n = n.max(1) + n / 4;
        let hist = n.div_ceil(BLOCK_KEYS as u64) * RADIX as u64;
        self.histogram = Some(Buffer::new(&self.gpu, "radix histogram", hist * 4, MemoryKind::Device)?);
        self.scan.reserve(hist)?;
        self.capacity = n;
        Ok(())
    }

    /// Records a stable sort of `n` pairs by the low `bits` bits of the keys, ping-ponging between
    /// (keys, values) and (keys_alt, values_alt). Returns true when the result ends in the alt buffers.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        rec: &mut Recorder,
        keys: &Buffer,
        values: &Buffer,
        keys_alt: &Buffer,
        values_alt: &Buffer,
        n: u32,
        bits: u32,
    ) -> bool {
        assert!(n as u64 <= self.capacity, "radix sort: reserve({n}) first");
        if n == 0 {
            return false;
        }
        let hist = self.histogram.as_ref().unwrap();
        let num_blocks = n.div_ceil(BLOCK_KEYS);
        let mut src = (keys, values);
        let mut dst = (keys_alt, values_alt);
        let passes = passes_for_bits(bits);
        for pass in 0..passes {
            let push = SortPush {
                keys_in: src.0.address(),
                values_in: src.1.address(),
                keys_out: dst.0.address(),
                values_out: dst.1.address(),
                histogram: hist.address(),
                n,
                shift: pass * RADIX_BITS,
                num_blocks,
                digit_mask: (1u32 << (bits - pass * RADIX_BITS).min(RADIX_BITS)) - 1,
            };
            rec.dispatch(&self.count, &push, dispatch_1d(num_blocks));
            self.scan.record(rec, hist, num_blocks * RADIX);
            rec.dispatch(&self.scatter, &push, dispatch_1d(num_blocks));
            std::mem::swap(&mut src, &mut dst);
        }
        passes % 2 == 1
    }
}
