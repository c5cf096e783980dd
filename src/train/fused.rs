//! Projection backward fused with Adam (project_backward_adam.comp): the training step of one view
//! takes each Gaussian's parameter gradients from the per-view projected gradients and applies
//! Adam to its elements in the same thread, so the parameter gradient tensors are never written,
//! zeroed or read back. Apart, the projection backward and Adam move 2.5 GB per step at 1M SH-3
//! Gaussians; fused, 1.5 GB. The same arithmetic as `Backward::record` + the MCMC regularizer +
//! `Adam::record` per tensor (tests/train.rs compares the two paths), the trust region per Gaussian
//! (`Adam::record_clipped`) included: each thread owns a Gaussian's rows, so it clips them itself.
//! The removal's refinement steps in a trust region; apart, its iterations cost 1.32x a training
//! iteration on the composited statue (fused, see bench/JOURNAL.md).

use super::adam::{AdamStep, Moments};
use crate::gpu::{dispatch_1d, Buffer, Gpu, MemoryKind, Recorder};
use crate::render::specialized::SpecializedPipelines;
use crate::render::SceneBuffers;
use crate::shaders;
use anyhow::Result;
use bytemuck::{Pod, Zeroable};

/// Mirrors `FusedAdam` in shaders/glsl/train/project_backward_adam.comp (std430, pointers first).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct FusedAdamParams {
    params: [u64; 5],
    /// (m, v) per group, in the order of `params`.
    moments: [[u64; 2]; 5],
    /// u32 per Gaussian, its `trainer::Motion` (`Trainer::set_movable`); 0 and unread when all move.
    movable: u64,
    steps: [AdamStep; 5],
    opacity_reg: f32,
    scale_reg: f32,
    frozen: u32,
    sh_stepped: u32,
    /// Each Gaussian's update of each geometry row clipped to this norm; infinite: no clip.
    trust_radius: f32,
    _pad: u32,
}

/// One parameter group's step: its moments, learning rate (and the rate of SH bands above the
/// first), and whether it is frozen (neither it nor its moments change).
pub struct GroupStep<'a> {
    pub moments: &'a Moments,
    pub lr: f32,
    pub lr_tail: f32,
    pub frozen: bool,
}

/// The five groups in scene order: means, log scales, quaternions, opacity logits, SH.
pub type Groups<'a> = [GroupStep<'a>; 5];

/// Bytes moved per Gaussian when nothing is frozen and `sh_stepped` SH coefficients per channel
/// are stepped: those parameters and both moments read and written (59 floats each at SH 3), the
/// per-view projected gradients (10 floats) read, the densification statistics (2 words) read and
/// written, conic and opacity (4 floats) and the tile count read.
pub fn bytes_per_gaussian(sh_stepped: u32) -> u64 {
    let params = 3 + 3 + 4 + 1 + 3 * sh_stepped as u64;
    4 * (6 * params + 10 + 2 * 2 + 4 + 1)
}

pub struct ProjectBackwardAdam {
    gpu: Gpu,
    pipelines: SpecializedPipelines,
    params: Buffer,
}

impl ProjectBackwardAdam {
    /// `cas`: the compare-and-swap variant, for a `Backward` that accumulates that way.
    pub fn new(gpu: &Gpu, cas: bool) -> Result<ProjectBackwardAdam> {
        let spirv = if cas { shaders::PROJECT_BACKWARD_ADAM_CAS } else { shaders::PROJECT_BACKWARD_ADAM };
        Ok(ProjectBackwardAdam {
            gpu: gpu.clone(),
            pipelines: SpecializedPipelines::new("project_backward_adam", spirv),
            params: Buffer::new(
                gpu,
                "fused adam params",
                std::mem::size_of::<FusedAdamParams>() as u64,
                MemoryKind::Upload,
            )?,
        })
    }

    /// Records Adam step `step` (from 1) of every group of `scene`, with the gradients of the view
    /// whose blend backward was recorded last (`render_params` and `backward_params` are the
    /// rasterizer's and the backward's parameter blocks of that view, `sh_degree` the degree that
    /// view was rendered with, its `RenderParams::sh_degree`). `regularizer` = the MCMC
    /// (opacity, scale) weights, zero when off. Only the first `sh_stepped` SH coefficients per
    /// channel are stepped: the caller guarantees the others have zero moments and get no gradient
    /// (bands not rendered yet), so a step would leave them unchanged. With `trust_radius` each
    /// Gaussian's update of its position, of its log-scales and of its rotation is clipped to that
    /// norm (as `Adam::record_clipped`). With `movable` (a `trainer::Motion` per Gaussian) only the
    /// Gaussians it marks step, the view-independent ones all but their higher SH bands; the
    /// others keep their parameters and moments. The constants go to one
    /// host-visible block: one recording per submission.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &mut self,
        rec: &mut Recorder,
        render_params: &Buffer,
        backward_params: &Buffer,
        sh_degree: u32,
        scene: &SceneBuffers,
        groups: &Groups,
        regularizer: (f32, f32),
        step: u32,
        sh_stepped: u32,
        trust_radius: Option<f32>,
        movable: Option<&Buffer>,
    ) -> Result<()> {
        let n = scene.num_gaussians;
        let step_of = |g: &GroupStep| AdamStep::new(g.moments.len, (g.lr, 1, 1, g.lr_tail), step);
        let params = FusedAdamParams {
            params: scene.parameters().map(|(t, _)| t.address()),
            moments: [0, 1, 2, 3, 4].map(|i| [groups[i].moments.m.address(), groups[i].moments.v.address()]),
            movable: movable.map_or(0, |b| b.address()),
            steps: [0, 1, 2, 3, 4].map(|i| step_of(&groups[i])),
            opacity_reg: regularizer.0 / n as f32,
            scale_reg: regularizer.1 / (3 * n) as f32,
            frozen: groups.iter().enumerate().map(|(i, g)| (g.frozen as u32) << i).sum::<u32>()
                | (movable.is_some() as u32) << 5,
            sh_stepped: sh_stepped.min(crate::scene::sh_coeffs(scene.sh_degree) as u32),
            trust_radius: trust_radius.unwrap_or(f32::INFINITY),
            _pad: 0,
        };
        // Constants: the rendered degree, and whether bands above it are stepped (moments of a
        // higher degree rendered before); usually not, and then their loop compiles away.
        let above = params.sh_stepped > crate::scene::sh_coeffs(sh_degree) as u32;
        let pipeline = self.pipelines.get(&self.gpu, &[sh_degree, above as u32])?;
        self.params.write_pod(&params)?;
        let push = [render_params.address(), backward_params.address(), self.params.address()];
        rec.dispatch(pipeline, &push, dispatch_1d(n.div_ceil(256)));
        Ok(())
    }
}
