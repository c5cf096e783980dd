//! Pipelines specialized per dispatch on values known only when a frame is recorded, such as the
//! SH degree it renders with (constant 0, `SH_DEGREE` in sh.glsl: project.comp, the projection
//! backward and its fusion with Adam). With those values constants, the code they switch off
//! compiles away and loops over them unroll. That matters on lavapipe, which runs both sides of
//! every branch with the lanes masked off, and the body of a loop once more after its last
//! iteration: at 1M Gaussians, degree 0, 512x512, the fused projection backward + Adam went from
//! 221-229 to 180-183 ms with the degree a constant (bench/JOURNAL.md, 2026-11-25). Each variant
//! is built on first use, so a scene trained at one degree compiles one.

use crate::gpu::{ComputePipeline, Gpu};
use anyhow::Result;

pub(crate) struct SpecializedPipelines {
    name: &'static str,
    spirv: &'static [u8],
    built: Vec<(Vec<u32>, ComputePipeline)>,
}

impl SpecializedPipelines {
    pub(crate) fn new(name: &'static str, spirv: &'static [u8]) -> SpecializedPipelines {
        SpecializedPipelines { name, spirv, built: Vec::new() }
    }

    /// The pipeline with specialization constants 0, 1, ... set to `constants`, built on first use.
    pub(crate) fn get(&mut self, gpu: &Gpu, constants: &[u32]) -> Result<&ComputePipeline> {
        let index = match self.built.iter().position(|(c, _)| c == constants) {
            Some(i) => i,
            None => {
                let pipeline = ComputePipeline::specialized(gpu, self.name, self.spirv, constants)?;
                self.built.push((constants.to_vec(), pipeline));
                self.built.len() - 1
            }
        };
        Ok(&self.built[index].1)
    }
}
