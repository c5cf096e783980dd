//! A scene's attributes on the GPU, one buffer per attribute: what every render pass reads.

use crate::gpu::{Buffer, Gpu, MemoryKind};
use crate::scene::GaussianScene;
use anyhow::Result;

/// A scene's attributes on the GPU (structure of arrays, one buffer per attribute).
pub struct SceneBuffers {
    pub means: Buffer,
    pub log_scales: Buffer,
    pub quats: Buffer,
    pub opacity_logits: Buffer,
    pub sh: Buffer,
    /// N x D row-major identity features, when present.
    pub features: Option<Buffer>,
    pub num_gaussians: u32,
    pub sh_degree: u32,
    pub feature_dim: u32,
}

impl SceneBuffers {
    /// Uploads a scene; `features` is an N x D row-major matrix.
    pub fn upload(gpu: &Gpu, scene: &GaussianScene, features: Option<(&[f32], usize)>) -> Result<SceneBuffers> {
        let n = scene.len();
        let bytes = n as u64 * (3 + 3 + 4 + 1 + 3 * scene.sh_coeffs() as u64) * 4;
        let with_context = |r: Result<Buffer>| {
            r.map_err(|e| {
                e.context(format!(
                    "cannot upload a scene of {n} Gaussians (SH degree {}, {} MiB of attributes) to {}",
                    scene.sh_degree,
                    bytes >> 20,
                    gpu.info().name
                ))
            })
        };
        let features = match features {
            Some((f, d)) => {
                assert_eq!(f.len(), n * d, "feature matrix must be N x D");
                Some((with_context(Buffer::from_slice(gpu, "features", f))?, d as u32))
            }
            None => None,
        };
        Ok(SceneBuffers {
            means: with_context(Buffer::from_slice(gpu, "means", &scene.means))?,
            log_scales: with_context(Buffer::from_slice(gpu, "log_scales", &scene.log_scales))?,
            quats: with_context(Buffer::from_slice(gpu, "quats", &scene.quats))?,
            opacity_logits: with_context(Buffer::from_slice(gpu, "opacity_logits", &scene.opacity_logits))?,
            sh: with_context(Buffer::from_slice(gpu, "sh", &scene.sh))?,
            num_gaussians: n as u32,
            sh_degree: scene.sh_degree,
            feature_dim: features.as_ref().map(|f| f.1).unwrap_or(0),
            features: features.map(|f| f.0),
        })
    }

    /// The trainable parameter tensors in a fixed order (means, log-scales, rotations, opacity
    /// logits, SH), each with its number of floats.
    pub fn parameters(&self) -> [(&Buffer, u32); 5] {
        let n = self.num_gaussians;
        let k = crate::scene::sh_coeffs(self.sh_degree) as u32;
        [
            (&self.means, 3 * n),
            (&self.log_scales, 3 * n),
            (&self.quats, 4 * n),
            (&self.opacity_logits, n),
            (&self.sh, 3 * k * n),
        ]
    }

    /// Puts `scene` (and `features`, N x D) in these buffers in place of the scene they hold: each
    /// attribute into its buffer where it fits, else into a new one half again as large, so that a
    /// run of parts of one scene (`SceneRenderer::upload`) soon stops allocating.
    pub fn reload(&mut self, gpu: &Gpu, scene: &GaussianScene, features: Option<(&[f32], usize)>) -> Result<()> {
        fn fill<T: bytemuck::Pod>(gpu: &Gpu, buffer: &mut Buffer, name: &str, data: &[T]) -> Result<()> {
            let bytes = std::mem::size_of_val(data) as u64;
            if bytes > buffer.size() {
                *buffer = Buffer::new(gpu, name, bytes + bytes / 2, MemoryKind::Device)?;
            }
            buffer.upload(gpu, data)
        }
        let n = scene.len();
        fill(gpu, &mut self.means, "means", &scene.means)?;
        fill(gpu, &mut self.log_scales, "log_scales", &scene.log_scales)?;
        fill(gpu, &mut self.quats, "quats", &scene.quats)?;
        fill(gpu, &mut self.opacity_logits, "opacity_logits", &scene.opacity_logits)?;
        fill(gpu, &mut self.sh, "sh", &scene.sh)?;
        if let Some((f, d)) = features {
            assert_eq!(f.len(), n * d, "feature matrix must be N x D");
        }
        match (features, &mut self.features) {
            (Some((f, _)), Some(buffer)) => fill(gpu, buffer, "features", f)?,
            (Some((f, _)), none) => *none = Some(Buffer::from_slice(gpu, "features", f)?),
            (None, features) => *features = None,
        }
        self.num_gaussians = n as u32;
        self.sh_degree = scene.sh_degree;
        self.feature_dim = features.map_or(0, |f| f.1 as u32);
        Ok(())
    }
}
