//! Stable GPU radix sort of (u32 key, u32 value) pairs: 8-bit digits, reduce-then-scan per pass
//! (radix_count.comp, exclusive scan of the digit-major histogram, radix_scatter.comp). A block's
//! keys are ranked by one subgroup walking it in rows (the workgroup is one subgroup of the device's
//! size) and no workgroup waits on another. Only the key bits asked for are sorted: tile ids take
//! ceil(log2(tiles)) bits, so a 1080p frame's tile sort is two passes.
//!
//! CPU drivers run the count and scatter in the lane-serial shape instead (radix_count_lanes.comp,
//! radix_scatter_lanes.comp): each lane owns a contiguous slice of the block and its own digit
//! counters, so a key costs a few plain loads and stores rather than RADIX_BITS ballots.

pub mod scan;

use crate::gpu::{dispatch_1d, Buffer, ComputePipeline, Gpu, MemoryKind, Recorder};
use crate::shaders;
use anyhow::{bail, Result};
use bytemuck::{Pod, Zeroable};
use scan::PrefixScan;

pub const RADIX_BITS: u32 = 8;
/// The widest workgroup the lane-serial shape has counter rows for (MAX_LANES in radix_lanes.glsl).
pub const LANE_SERIAL_MAX_LANES: u32 = 16;
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
    lane_offsets: u64,
}

/// How a block's keys are counted and ranked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SortShape {
    /// One subgroup walks the block in rows; keys of a row find their digit peers with ballots.
    /// Coalesced on a GPU.
    Ballot,
    /// Each lane walks its own contiguous slice with private counters. For CPU drivers, where a
    /// workgroup is one SIMD row and a ballot costs as much as a whole key's scalar work.
    LaneSerial,
}

impl SortShape {
    /// Keys per workgroup (BLOCK_KEYS in radix_common.glsl). Ballot: one subgroup walks 4096 in
    /// rows. Lane-serial: larger blocks mean fewer histogram entries to scan and fewer lane offsets
    /// to write and read, until the walk's writes spread too thin. On llvmpipe (1M / 4M / 16M pairs,
    /// ms): 4096 keys 31 / 122 / 435, 8192 27-31 / 114 / 391-416, 16384 18-26 / 90-101 / 360-372,
    /// 32768 18 / 101 / 415, 65536 27 / 110 / 445.
    pub fn block_keys(self) -> u32 {
        match self {
            SortShape::Ballot => 4096,
            SortShape::LaneSerial => 16384,
        }
    }

    /// The shape for this device. Measured on llvmpipe (random 32-bit pairs, 4 passes, old and new
    /// binary alternating, 3 runs each): 1M pairs ballot 41.4-42.0 ms, lane-serial 19.4-20.7 ms;
    /// 4M 167-170 against 97-98 ms; 16M 656-680 against 380-382 ms.
    pub fn for_device(info: &crate::gpu::DeviceInfo) -> SortShape {
        if info.is_cpu() && info.subgroup_size <= LANE_SERIAL_MAX_LANES {
            SortShape::LaneSerial
        } else {
            SortShape::Ballot
        }
    }
}

pub struct RadixSort {
    gpu: Gpu,
    shape: SortShape,
    count: ComputePipeline,
    scatter: ComputePipeline,
    scan: PrefixScan,
    histogram: Option<Buffer>,
    /// Lane-serial shape: each lane's offsets within its block, [block][lane][digit].
    lane_offsets: Option<Buffer>,
    capacity: u64,
}

/// Number of 8-bit passes needed to sort keys below 2^bits.
pub fn passes_for_bits(bits: u32) -> u32 {
    bits.div_ceil(RADIX_BITS)
}

impl RadixSort {
    /// The sort for this device, in its shape; its workgroups are one subgroup of the device's size.
    pub fn new(gpu: &Gpu) -> Result<RadixSort> {
        RadixSort::with_shape(gpu, SortShape::for_device(gpu.info()))
    }

    /// The sort in a given shape (tests run both on any device).
    pub fn with_shape(gpu: &Gpu, shape: SortShape) -> Result<RadixSort> {
        let subgroup = gpu.info().subgroup_size;
        if !subgroup.is_power_of_two() || !(4..=128).contains(&subgroup) {
            bail!("radix sort: subgroup size {subgroup} is not a power of two from 4 to 128");
        }
        if shape == SortShape::LaneSerial && subgroup > LANE_SERIAL_MAX_LANES {
            bail!("radix sort: the lane-serial shape has rows for {LANE_SERIAL_MAX_LANES} lanes, the subgroup has {subgroup}");
        }
        let constants = [subgroup, shape.block_keys()];
        let (count, scatter) = match shape {
            SortShape::Ballot => (
                ComputePipeline::specialized(gpu, "radix_count", shaders::RADIX_COUNT, &constants)?,
                ComputePipeline::specialized(gpu, "radix_scatter", shaders::RADIX_SCATTER, &constants)?,
            ),
            SortShape::LaneSerial => (
                ComputePipeline::specialized(gpu, "radix_count_lanes", shaders::RADIX_COUNT_LANES, &constants)?,
                ComputePipeline::specialized(gpu, "radix_scatter_lanes", shaders::RADIX_SCATTER_LANES, &constants)?,
            ),
        };
        Ok(RadixSort {
            gpu: gpu.clone(),
            shape,
            count,
            scatter,
            scan: PrefixScan::new(gpu)?,
            histogram: None,
            lane_offsets: None,
            capacity: 0,
        })
    }

    pub fn shape(&self) -> SortShape {
        self.shape
    }

    pub fn block_keys(&self) -> u32 {
        self.shape.block_keys()
    }

    /// Bytes a sort of `n` pairs by `bits` key bits must move: per pass, the count reads the keys, the
    /// histogram scan reads and writes the block histograms, the scatter reads them and the pairs and
    /// writes the pairs; the lane-serial count also writes each lane's offsets, which the scatter
    /// reads. The roofline of `cargo bench --bench sort` divides by this.
    pub fn bytes_moved(&self, n: u64, bits: u32) -> u64 {
        let histogram = n.div_ceil(self.block_keys() as u64) * RADIX as u64 * 4;
        let lane_offsets = match self.shape {
            SortShape::Ballot => 0,
            SortShape::LaneSerial => 2 * histogram * self.gpu.info().subgroup_size as u64,
        };
        let per_pass = 4 * n + 2 * histogram + (histogram + 16 * n) + lane_offsets;
        passes_for_bits(bits) as u64 * per_pass
    }

    /// Makes sure up to `n` pairs can be sorted.
    pub fn reserve(&mut self, n: u64) -> Result<()> {
        if n <= self.capacity && self.histogram.is_some() {
            return Ok(());
        }
        let n = n.max(1) + n / 4;
        let hist = n.div_ceil(self.block_keys() as u64) * RADIX as u64;
        self.histogram = Some(Buffer::new(&self.gpu, "radix histogram", hist * 4, MemoryKind::Device)?);
        if self.shape == SortShape::LaneSerial {
            let bytes = hist * self.gpu.info().subgroup_size as u64 * 4;
            self.lane_offsets = Some(Buffer::new(&self.gpu, "radix lane offsets", bytes, MemoryKind::Device)?);
        }
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
        if self.shape == SortShape::LaneSerial {
            for b in [keys, values, keys_alt, values_alt] {
                assert!(b.address() % 16 == 0, "radix sort: the lane-serial shape reads uvec4s");
            }
        }
        let hist = self.histogram.as_ref().unwrap();
        let num_blocks = n.div_ceil(self.block_keys());
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
                lane_offsets: self.lane_offsets.as_ref().map_or(0, |b| b.address()),
            };
            rec.dispatch(&self.count, &push, dispatch_1d(num_blocks));
            self.scan.record(rec, hist, num_blocks * RADIX);
            rec.dispatch(&self.scatter, &push, dispatch_1d(num_blocks));
            std::mem::swap(&mut src, &mut dst);
        }
        passes % 2 == 1
    }
}
