//! "Render these cameras": a scene uploaded once (with optional per-Gaussian features) and
//! rendered from any number of cameras. Every caller that only renders, without a backward pass,
//! goes through it: `cogeo render`, the removal's views, label maps, held-out renders.

use super::{Rasterizer, RenderOutput, RenderSettings, SceneBuffers};
use crate::gpu::Gpu;
use crate::scene::{Camera, GaussianScene};
use anyhow::Result;

pub struct SceneRenderer {
    raster: Rasterizer,
    buffers: SceneBuffers,
    /// The scene's highest SH band with a nonzero coefficient (`learnt_sh_degree`).
    learnt_sh_degree: u32,
}

impl SceneRenderer {
    /// Uploads `scene`, with `features` (n x dim, row-major) when given.
    pub fn new(gpu: &Gpu, scene: &GaussianScene, features: Option<(&[f32], usize)>) -> Result<SceneRenderer> {
        Ok(SceneRenderer {
            buffers: SceneBuffers::upload(gpu, scene, features)?,
            raster: Rasterizer::new(gpu)?,
            learnt_sh_degree: scene.learnt_sh_degree(),
        })
    }

    /// Replaces the uploaded scene (and features) by `scene`'s, keeping the rasterizer and the
    /// buffers where they are large enough: a render of a part of a scene after another.
    pub fn upload(&mut self, gpu: &Gpu, scene: &GaussianScene, features: Option<(&[f32], usize)>) -> Result<()> {
        self.buffers.reload(gpu, scene, features)?;
        self.learnt_sh_degree = scene.learnt_sh_degree();
        Ok(())
    }

    /// Renders at most the bands the scene learnt: the higher ones are exactly zero and add
    /// exactly nothing, but a PLY stores degree 3 after a training that reached only the DC band
    /// (under 1000 iterations, as the removal speed scene's 800), and projecting 48 coefficients
    /// per Gaussian instead of 3 is work for nothing.
    pub fn render(&mut self, camera: &Camera, settings: &RenderSettings) -> Result<RenderOutput> {
        let degree = settings.sh_degree.map_or(self.learnt_sh_degree, |d| d.min(self.learnt_sh_degree));
        let settings = RenderSettings { sh_degree: Some(degree), ..settings.clone() };
        self.raster.render(&self.buffers, camera, &settings)
    }
}

/// Planar RGB of `scene` from each of `cameras` over `background`.
pub fn render_rgb(gpu: &Gpu, scene: &GaussianScene, cameras: &[Camera], background: [f32; 3]) -> Result<Vec<Vec<f32>>> {
    let mut renderer = SceneRenderer::new(gpu, scene, None)?;
    let settings = RenderSettings { background, ..Default::default() };
    cameras.iter().map(|c| Ok(renderer.render(c, &settings)?.rgb)).collect()
}
