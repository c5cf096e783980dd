//! Iterate averaging (Polyak-Ruppert) for `Trainer`: the mean of its parameters over the steps
//! that follow `IterateAverage::new`, kept on the GPU (`running_mean.comp`), which can replace the
//! parameters of the last step (`IterateAverage::apply`).
//!
//! A trainer that steps one view at a time at a constant rate ends where the last views pulled
//! it. Where the views' targets agree, every step pulls the same way and the mean of the last
//! steps is the last step; where they disagree (the removal's per-view fills), the mean over a
//! pass of the views is the compromise they all pull around, not the last views' side of it
//! (removal/refine.rs `AVERAGE_PASSES`).

use super::Trainer;
use crate::gpu::{dispatch_1d, Buffer, ComputePipeline, Recorder};
use crate::shaders;
use anyhow::{ensure, Result};
use bytemuck::{Pod, Zeroable};

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct RunningMeanPush {
    value: u64,
    mean: u64,
    n: u32,
    weight: f32,
}

/// The running mean of a trainer's parameters, one buffer per parameter tensor.
pub struct IterateAverage {
    pipeline: ComputePipeline,
    /// Means, log-scales, rotations, opacity logits and SH, as `SceneBuffers::parameters` orders
    /// them.
    means: Vec<Buffer>,
    /// Floats per tensor.
    lengths: Vec<u32>,
    /// Iterates averaged so far.
    count: u32,
}

impl IterateAverage {
    /// An empty average over the parameters `trainer` holds now (their number must not change:
    /// no densification while it runs).
    pub fn new(trainer: &Trainer) -> Result<IterateAverage> {
        let gpu = &trainer.gpu;
        let tensors = trainer.scene.parameters();
        let means = tensors
            .iter()
            .map(|(_, len)| Buffer::zeroed(gpu, "iterate average", 4 * (*len).max(1) as u64))
            .collect::<Result<Vec<_>>>()?;
        Ok(IterateAverage {
            pipeline: ComputePipeline::new(gpu, "running_mean", shaders::RUNNING_MEAN)?,
            means,
            lengths: tensors.map(|(_, len)| len).to_vec(),
            count: 0,
        })
    }

    /// Iterates averaged so far.
    pub fn count(&self) -> u32 {
        self.count
    }

    /// Takes `trainer`'s parameters as they are now into the mean.
    pub fn add(&mut self, trainer: &Trainer) -> Result<()> {
        let tensors = self.tensors_of(trainer)?;
        self.count += 1;
        let weight = 1.0 / self.count as f32;
        let mut rec = Recorder::new(&trainer.gpu)?;
        for ((param, n), mean) in tensors.iter().zip(&self.means) {
            let push = RunningMeanPush { value: param.address(), mean: mean.address(), n: *n, weight };
            rec.dispatch(&self.pipeline, &push, dispatch_1d(n.div_ceil(256)));
        }
        rec.submit_and_wait()?;
        Ok(())
    }

    /// Replaces `trainer`'s parameters by their mean, copied exactly (nothing when no iterate was
    /// added). Its Adam moments stay those of its last step.
    pub fn apply(&self, trainer: &mut Trainer) -> Result<()> {
        if self.count == 0 {
            return Ok(());
        }
        let tensors = self.tensors_of(trainer)?;
        let mut rec = Recorder::new(&trainer.gpu)?;
        for ((param, n), mean) in tensors.iter().zip(&self.means).filter(|((_, n), _)| *n > 0) {
            rec.copy(mean, param, 4 * *n as u64);
        }
        rec.submit_and_wait()?;
        Ok(())
    }

    /// `trainer`'s parameter tensors, which must be as many floats as when the average began.
    fn tensors_of<'t>(&self, trainer: &'t Trainer) -> Result<[(&'t Buffer, u32); 5]> {
        let tensors = trainer.scene.parameters();
        ensure!(
            tensors.iter().map(|(_, len)| *len).eq(self.lengths.iter().copied()),
            "the trainer's Gaussians changed while their iterates were averaged"
        );
        Ok(tensors)
    }
}
