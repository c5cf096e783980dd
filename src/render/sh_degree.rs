//! Pipelines specialized on the SH degree a frame renders with (project.comp, the projection
//! backward and its fusion with Adam; specialization constant 0, `SH_DEGREE` in sh.glsl). With the
//! degree a constant the bands above it compile away and the basis loops unroll into registers.
//! That matters on lavapipe, which runs both sides of a branch with the lanes masked off: at 1M
//! Gaussians, degree 0, 512x512, the fused projection backward + Adam went from 218-235 to about
//! 176 ms (bench/RESULTS.md). Each degree's pipeline is built on first use, so a scene trained at
//! one degree compiles one.

use crate::gpu::{ComputePipeline, Gpu};
use anyhow::{bail, Result};

/// The highest SH degree the shaders implement.
pub const MAX_SH_DEGREE: u32 = 3;

pub(crate) struct ShDegreePipelines {
    name: &'static str,
    spirv: &'static [u8],
    by_degree: [Option<ComputePipeline>; MAX_SH_DEGREE as usize + 1],
}

impl ShDegreePipelines {
    pub(crate) fn new(name: &'static str, spirv: &'static [u8]) -> ShDegreePipelines {
        ShDegreePipelines { name, spirv, by_degree: Default::default() }
    }

    /// Creates the pipeline for `degree` unless it exists.
    pub(crate) fn prepare(&mut self, gpu: &Gpu, degree: u32) -> Result<()> {
        if degree > MAX_SH_DEGREE {
            bail!("{}: SH degree {degree} is above the supported {MAX_SH_DEGREE}", self.name);
        }
        let slot = &mut self.by_degree[degree as usize];
        if slot.is_none() {
            *slot = Some(ComputePipeline::specialized(gpu, self.name, self.spirv, &[degree])?);
        }
        Ok(())
    }

    /// The pipeline for `degree` (after `prepare`).
    pub(crate) fn get(&self, degree: u32) -> &ComputePipeline {
        self.by_degree[degree as usize].as_ref().expect("SH degree pipeline prepared")
    }
}
