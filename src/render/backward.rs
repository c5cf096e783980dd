//! Backward passes of the rasterizer: blend_backward.comp (per-pixel, back to front, subgroup-reduced
//! atomics into per-view gradients of the projected quantities), project_backward.comp (chain rule
//! to the stored parameters, accumulated over views) and blend_features_backward.comp. Each has a
//! `_cas` twin that accumulates with compare-and-swap on devices without float atomics.

use super::features::FeaturePipelines;
use super::params::RenderParams;
use super::specialized::SpecializedPipelines;
use super::{BlendLayout, SceneBuffers};
use crate::gpu::{dispatch_1d, Buffer, Gpu, MemoryKind, Recorder};
use crate::shaders;
use anyhow::Result;
use bytemuck::{Pod, Zeroable};

/// Mirrors `shaders/glsl/common/backward_params.glsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct BackwardParams {
    pub dl_drgb: u64,
    pub dl_dalpha: u64,
    pub dl_ddepth: u64,
    pub dl_dexpected_depth: u64,
    pub dl_dfeatures: u64,
    pub grad_xy: u64,
    pub grad_conic: u64,
    pub grad_opacity: u64,
    pub grad_color: u64,
    pub grad_depth: u64,
    pub grad_features: u64,
    pub grad_means: u64,
    pub grad_log_scales: u64,
    pub grad_quats: u64,
    pub grad_opacity_logits: u64,
    pub grad_sh: u64,
    pub grad_xy_norm_sum: u64,
    pub grad_xy_views: u64,
    pub use_alpha: u32,
    pub use_depth: u32,
    pub pad0: u32,
    pub pad1: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct BackwardPush {
    render: u64,
    backward: u64,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct FeatureBackwardPush {
    render: u64,
    backward: u64,
    channel_offset: u32,
    pad: u32,
}

/// Gradients of a scene's stored parameters (accumulated over the views of a step), plus the
/// densification statistics. Same layouts as `SceneBuffers`.
pub struct SceneGradients {
    pub means: Buffer,
    pub log_scales: Buffer,
    pub quats: Buffer,
    pub opacity_logits: Buffer,
    pub sh: Buffer,
    /// N x D, when the scene has features.
    pub features: Option<Buffer>,
    /// Sum over views of |dL/d(mean2d)| in NDC units.
    pub xy_norm_sum: Buffer,
    /// Number of views in which each Gaussian was visible.
    pub xy_views: Buffer,
    pub num_gaussians: u32,
}

impl SceneGradients {
    pub fn new(gpu: &Gpu, scene: &SceneBuffers) -> Result<SceneGradients> {
        Self::with_rows(gpu, scene, scene.num_gaussians as u64)
    }

    /// Gradients for the features-only backward (`Backward::record` with `features_only`), which
    /// never touches the geometry and color groups: those get one element instead of N rows, so
    /// feature training on millions of Gaussians does not allocate SH-sized gradient buffers.
    pub fn for_features(gpu: &Gpu, scene: &SceneBuffers) -> Result<SceneGradients> {
        anyhow::ensure!(scene.feature_dim > 0, "the scene has no features to train");
        let mut g = Self::with_rows(gpu, scene, 1)?;
        g.features =
            Some(Buffer::zeroed(gpu, "grad features", scene.num_gaussians as u64 * scene.feature_dim as u64 * 4)?);
        Ok(g)
    }

    fn with_rows(gpu: &Gpu, scene: &SceneBuffers, n: u64) -> Result<SceneGradients> {
        let k = ((scene.sh_degree + 1) * (scene.sh_degree + 1)) as u64;
        let buf = |name: &str, per: u64| Buffer::zeroed(gpu, name, n * per * 4);
        Ok(SceneGradients {
            means: buf("grad means", 3)?,
            log_scales: buf("grad log_scales", 3)?,
            quats: buf("grad quats", 4)?,
            opacity_logits: buf("grad opacity_logits", 1)?,
            sh: buf("grad sh", 3 * k)?,
            features: if scene.feature_dim > 0 { Some(buf("grad features", scene.feature_dim as u64)?) } else { None },
            xy_norm_sum: buf("grad xy norm sum", 1)?,
            xy_views: buf("grad xy views", 1)?,
            num_gaussians: scene.num_gaussians,
        })
    }

    /// Records zeroing of the parameter gradients only (keeps the densification statistics).
    pub fn record_zero_parameters(&self, rec: &mut Recorder) {
        for b in [&self.means, &self.log_scales, &self.quats, &self.opacity_logits, &self.sh]
            .into_iter()
            .chain(self.features.as_ref())
        {
            rec.fill(b, 0, b.size(), 0);
        }
    }
}

/// Upstream gradients dL/d(image), planar like `RenderOutput` (width * height per plane).
pub struct PixelGradients<'a> {
    pub rgb: &'a Buffer,
    pub alpha: Option<&'a Buffer>,
    pub depth: Option<&'a Buffer>,
    pub expected_depth: Option<&'a Buffer>,
    pub features: Option<&'a Buffer>,
}

/// Per-view gradients of the projected quantities, zeroed before each view's blend backward (a
/// buffer fill runs at copy-engine speed; clearing them in the projection backward cost a store
/// per float at shader speed).
struct ViewGradients {
    capacity: u32,
    xy: Buffer,
    conic: Buffer,
    opacity: Buffer,
    color: Buffer,
    depth: Buffer,
}

pub struct Backward {
    gpu: Gpu,
    /// blend_backward.comp by its specialization constants: the layout's four, then COLOR_ONLY.
    blend: SpecializedPipelines,
    /// The layout's constants: rows and columns per invocation, the workgroup's width and height.
    layout: [u32; 4],
    project: SpecializedPipelines,
    features: FeaturePipelines,
    params: Buffer,
    view: Option<ViewGradients>,
    /// Compare-and-swap accumulation instead of float atomics.
    pub uses_cas: bool,
}

impl Backward {
    /// `force_cas` selects the compare-and-swap variants even where float atomics exist (tests).
    pub fn new(gpu: &Gpu, force_cas: bool) -> Result<Backward> {
        Self::with_layout(gpu, force_cas, BlendLayout::for_device(gpu.info()))
    }

    /// As `new`, with the backward blend passes' pixels per invocation given instead of chosen for
    /// the device (tests run every layout on one device).
    pub fn with_layout(gpu: &Gpu, force_cas: bool, layout: BlendLayout) -> Result<Backward> {
        layout.check()?;
        let BlendLayout { backward_rows: rows, backward_cols: cols, feature_rows, .. } = layout;
        let cas = force_cas || !gpu.info().float_atomic_add;
        let (blend, project, features) = if cas {
            (shaders::BLEND_BACKWARD_CAS, shaders::PROJECT_BACKWARD_CAS, shaders::BLEND_FEATURES_BACKWARD_CAS)
        } else {
            (shaders::BLEND_BACKWARD, shaders::PROJECT_BACKWARD, shaders::BLEND_FEATURES_BACKWARD)
        };
        Ok(Backward {
            gpu: gpu.clone(),
            blend: SpecializedPipelines::new("blend_backward", blend),
            layout: [rows, cols, 16 / cols, 16 / rows],
            project: SpecializedPipelines::new("project_backward", project),
            features: FeaturePipelines::new("blend_features_backward", features, feature_rows),
            params: Buffer::new(
                gpu,
                "backward params",
                std::mem::size_of::<BackwardParams>() as u64,
                MemoryKind::Upload,
            )?,
            view: None,
            uses_cas: cas,
        })
    }

    fn reserve(&mut self, n: u32) -> Result<()> {
        if self.view.as_ref().is_some_and(|v| v.capacity >= n) {
            return Ok(());
        }
        self.view = None;
        let cap = super::grow(n as u64);
        let buf = |name: &str, per: u64| Buffer::zeroed(&self.gpu, name, cap * per * 4);
        let view = ViewGradients {
            capacity: cap as u32,
            xy: buf("view grad xy", 2)?,
            conic: buf("view grad conic", 3)?,
            opacity: buf("view grad opacity", 1)?,
            color: buf("view grad color", 3)?,
            depth: buf("view grad depth", 1)?,
        };
        self.view = Some(view);
        Ok(())
    }

    /// Records the backward of the last forward pass whose parameter block is `render_params` (the
    /// rasterizer's, still holding that frame): pixel gradients to per-view projected gradients,
    /// then to `grads` (accumulated). `features_only` skips the geometry and color passes.
    pub fn record(
        &mut self,
        rec: &mut Recorder,
        render_params: &Buffer,
        frame: &RenderParams,
        upstream: &PixelGradients,
        grads: &SceneGradients,
        features_only: bool,
    ) -> Result<()> {
        let project = !features_only;
        self.record_passes(rec, render_params, frame, upstream, grads, features_only, project)
    }

    /// As `record` without the projection backward: the blend backward leaves the per-view
    /// gradients of the projected quantities for a pass that consumes them through `params()`
    /// (train::fused, which feeds them straight to Adam). `grads` then only receives the
    /// densification statistics, from that pass.
    pub fn record_to_projected(
        &mut self,
        rec: &mut Recorder,
        render_params: &Buffer,
        frame: &RenderParams,
        upstream: &PixelGradients,
        grads: &SceneGradients,
    ) -> Result<()> {
        self.record_passes(rec, render_params, frame, upstream, grads, false, false)
    }

    /// The parameter block (`BackwardParams`) of the last recorded backward.
    pub fn params(&self) -> &Buffer {
        &self.params
    }

    #[allow(clippy::too_many_arguments)]
    fn record_passes(
        &mut self,
        rec: &mut Recorder,
        render_params: &Buffer,
        frame: &RenderParams,
        upstream: &PixelGradients,
        grads: &SceneGradients,
        features_only: bool,
        project: bool,
    ) -> Result<()> {
        if frame.only_tiles != 0 {
            // the blend backward walks every tile's list from the forward's state
            anyhow::bail!("a render of only some tiles (RenderSettings::only_tiles) has no backward pass");
        }
        self.reserve(frame.num_gaussians)?;
        if upstream.features.is_some() {
            self.features.prepare(&self.gpu, frame.feature_dim)?;
        }
        let v = self.view.as_ref().unwrap();
        let params = BackwardParams {
            dl_drgb: upstream.rgb.address(),
            dl_dalpha: upstream.alpha.map_or(0, |b| b.address()),
            dl_ddepth: upstream.depth.map_or(0, |b| b.address()),
            dl_dexpected_depth: upstream.expected_depth.map_or(0, |b| b.address()),
            dl_dfeatures: upstream.features.map_or(0, |b| b.address()),
            grad_xy: v.xy.address(),
            grad_conic: v.conic.address(),
            grad_opacity: v.opacity.address(),
            grad_color: v.color.address(),
            grad_depth: v.depth.address(),
            grad_features: grads.features.as_ref().map_or(0, |b| b.address()),
            grad_means: grads.means.address(),
            grad_log_scales: grads.log_scales.address(),
            grad_quats: grads.quats.address(),
            grad_opacity_logits: grads.opacity_logits.address(),
            grad_sh: grads.sh.address(),
            grad_xy_norm_sum: grads.xy_norm_sum.address(),
            grad_xy_views: grads.xy_views.address(),
            use_alpha: upstream.alpha.is_some() as u32,
            use_depth: (upstream.depth.is_some() && upstream.expected_depth.is_some()) as u32,
            pad0: 0,
            pad1: 0,
        };
        if (upstream.depth.is_some()) != (upstream.expected_depth.is_some()) {
            anyhow::bail!(
                "depth and expected-depth gradients must be given together (pass a zero buffer for the unused one)"
            );
        }
        self.params.write_pod(&params)?;
        let push = BackwardPush { render: render_params.address(), backward: self.params.address() };
        let tiles = frame.tiles_x * frame.tiles_y;
        if !features_only {
            for (buf, per) in [(&v.xy, 2), (&v.conic, 3), (&v.opacity, 1), (&v.color, 3), (&v.depth, 1)] {
                rec.fill(buf, 0, frame.num_gaussians as u64 * per * 4, 0);
            }
            // the color-only variant where nothing else has an upstream gradient
            let color_only = params.use_alpha == 0 && params.use_depth == 0;
            let [a, b, c, d] = self.layout;
            rec.dispatch(self.blend.get(&self.gpu, &[a, b, c, d, color_only as u32])?, &push, dispatch_1d(tiles));
            rec.mark("blend backward");
        }
        if project {
            rec.dispatch(
                self.project.get(&self.gpu, &[frame.sh_degree])?,
                &push,
                dispatch_1d(frame.num_gaussians.div_ceil(256)),
            );
            rec.mark("project backward");
        }
        if let (Some(_), Some(_)) = (upstream.features, grads.features.as_ref()) {
            for (offset, channels) in FeaturePipelines::passes(frame.feature_dim) {
                let p = FeatureBackwardPush {
                    render: push.render,
                    backward: push.backward,
                    channel_offset: offset,
                    pad: 0,
                };
                rec.dispatch(self.features.get(channels), &p, dispatch_1d(tiles));
            }
            rec.mark("features backward");
        }
        Ok(())
    }
}
