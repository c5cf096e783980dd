//! Exclusive prefix scan of u32 arrays on the GPU (reduce-then-scan over levels of 1024-element
//! blocks; no workgroup waits on another). Shaders: scan_blocks.comp, scan_add.comp.

use crate::gpu::{dispatch_1d, Buffer, ComputePipeline, Gpu, MemoryKind, Recorder};
use crate::shaders;
use anyhow::Result;
use bytemuck::{Pod, Zeroable};

pub const SCAN_BLOCK: u32 = 1024;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ScanPush {
    data: u64,
    block_sums: u64,
    n: u32,
    pad: u32,
}

pub struct PrefixScan {
    gpu: Gpu,
    blocks: ComputePipeline,
    add: ComputePipeline,
    /// Block sums of each level; level i holds ceil(n_i / 1024) entries.
    levels: Vec<Buffer>,
    capacity: u64,
}

fn level_sizes(n: u64) -> Vec<u64> {
    let mut sizes = Vec::new();
    let mut m = n;
    loop {
        let blocks = m.div_ceil(SCAN_BLOCK as u64).max(1);
        sizes.push(blocks);
        if blocks == 1 {
            return sizes;
        }
        m = blocks;
    }
}

impl PrefixScan {
    pub fn new(gpu: &Gpu) -> Result<PrefixScan> {
        Ok(PrefixScan {
            gpu: gpu.clone(),
            blocks: ComputePipeline::new(gpu, "scan_blocks", shaders::SCAN_BLOCKS)?,
            add: ComputePipeline::new(gpu, "scan_add", shaders::SCAN_ADD)?,
            levels: Vec::new(),
            capacity: 0,
        })
    }

    /// Makes sure arrays of up to `n` elements can be scanned.
    pub fn reserve(&mut self, n: u64) -> Result<()> {
        if n <= self.capacity {
            return Ok(());
        }
        let n = n + n / 4;
        self.levels = level_sizes(n)
            .iter()
            .map(|&s| Buffer::new(&self.gpu, "scan block sums", s * 4, MemoryKind::Device))
            .collect::<Result<_>>()?;
        self.capacity = n;
        Ok(())
    }

    /// Records an in-place exclusive scan of the first `n` u32 of `data` (n <= reserved capacity).
    pub fn record(&self, rec: &mut Recorder, data: &Buffer, n: u32) {
        assert!(n as u64 <= self.capacity, "prefix scan: reserve({n}) first");
        self.record_level(rec, data.address(), n, 0);
    }

    fn record_level(&self, rec: &mut Recorder, data: u64, n: u32, level: usize) {
        let blocks = n.div_ceil(SCAN_BLOCK).max(1);
        let sums = &self.levels[level];
        rec.dispatch(&self.blocks, &ScanPush { data, block_sums: sums.address(), n, pad: 0 }, dispatch_1d(blocks));
        if blocks > 1 {
            self.record_level(rec, sums.address(), blocks, level + 1);
            rec.dispatch(&self.add, &ScanPush { data, block_sums: sums.address(), n, pad: 0 }, dispatch_1d(blocks));
        }
    }
}
