//! The feature passes' pipelines (blend_features.comp and blend_features_backward): N-dim
//! features go through the tile lists in dispatches of up to 32 channels, each specialized on its
//! channel count so the per-pixel accumulators are registers.

use crate::gpu::{ComputePipeline, Gpu};
use anyhow::Result;

/// Channels a feature pass handles per dispatch.
const FEATURE_CHANNELS_PER_PASS: u32 = 32;

/// The pipelines of a feature pass (blend_features or its backward), one per channel count of a
/// dispatch, specialized on first use with (rows, 16 / rows, channels). A column holds rows x
/// channels accumulators, so its rows are the layout's, halved until that is at most 64 floats
/// (registers, not spilled memory, on a CPU driver).
pub(crate) struct FeaturePipelines {
    name: &'static str,
    spirv: &'static [u8],
    rows: u32,
    by_channels: Vec<(u32, ComputePipeline)>,
}

impl FeaturePipelines {
    pub(crate) fn new(name: &'static str, spirv: &'static [u8], rows: u32) -> FeaturePipelines {
        FeaturePipelines { name, spirv, rows, by_channels: Vec::new() }
    }

    /// The dispatches of `feature_dim` channels: (first channel, channels).
    pub(crate) fn passes(feature_dim: u32) -> impl Iterator<Item = (u32, u32)> {
        (0..feature_dim)
            .step_by(FEATURE_CHANNELS_PER_PASS as usize)
            .map(move |offset| (offset, FEATURE_CHANNELS_PER_PASS.min(feature_dim - offset)))
    }

    /// Creates the pipelines `feature_dim` channels need.
    pub(crate) fn prepare(&mut self, gpu: &Gpu, feature_dim: u32) -> Result<()> {
        for (_, channels) in Self::passes(feature_dim) {
            if self.by_channels.iter().any(|(c, _)| *c == channels) {
                continue;
            }
            let mut rows = self.rows;
            while rows > 1 && rows * channels > 64 {
                rows /= 2;
            }
            let pipeline = ComputePipeline::specialized(gpu, self.name, self.spirv, &[rows, 16 / rows, channels])?;
            self.by_channels.push((channels, pipeline));
        }
        Ok(())
    }

    /// The pipeline for a dispatch of `channels` (after `prepare`).
    pub(crate) fn get(&self, channels: u32) -> &ComputePipeline {
        &self.by_channels.iter().find(|(c, _)| *c == channels).expect("feature pipeline prepared").1
    }
}
