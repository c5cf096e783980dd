//! Forward rasterization: projection + SH (project.comp), global depth sort, tile binning
//! (gather_counts.comp, scan, emit_intersections.comp), stable tile sort, tile ranges
//! (tile_ranges.comp), 16x16 tile alpha blending of RGB / alpha / depth (blend.comp) and N-dim
//! features (blend_features.comp). `reference` is the dense f64 CPU twin the tests check against.

mod after_removal;
pub mod backward;
mod blend_layout;
mod features;
mod moved;
pub mod params;
pub mod reach;
pub mod reference;
mod scene_buffers;
mod scene_renderer;
pub(crate) mod specialized;

use crate::gpu::{dispatch_1d, Buffer, ComputePipeline, Gpu, MemoryKind, PassTiming, Readback, Recorder};
use crate::scene::{Camera, MAX_SH_DEGREE};
use crate::shaders;
use crate::sort::{self, scan, RadixSort};
pub use after_removal::AfterRemoval;
use after_removal::AFTER_PLANES;
use anyhow::{bail, Result};
pub use blend_layout::BlendLayout;
use features::FeaturePipelines;
use params::{EmitPush, ParamsPush, ParamsPushU32, RenderParams};
pub use scene_buffers::SceneBuffers;
pub use scene_renderer::{render_rgb, SceneRenderer};
use specialized::SpecializedPipelines;

pub const TILE: u32 = 16;

/// Consecutive intersections per invocation of tile_ranges.comp.
const TILE_RANGE_RUN: u32 = 8;

/// Per-render options.
#[derive(Clone, Debug)]
pub struct RenderSettings {
    pub background: [f32; 3],
    /// Gaussians with view depth z <= near are culled (conventions.md; INRIA uses 0.2).
    pub near: f32,
    /// SH degree used for color (clamped to the stored degree); None = stored degree.
    pub sh_degree: Option<u32>,
    /// Also blend the scene's feature matrix.
    pub features: bool,
    /// Record GPU timestamps per pass.
    pub timestamps: bool,
    /// Also the median depth (`RenderOutput::median_depth`; empty without it).
    pub median_depth: bool,
    /// Composite only the tiles marked here (row-major over the image's 16 x 16 pixel tiles); the
    /// others come out empty (the background, alpha 0). For a forward render of which the caller
    /// reads a part: a tile's pixels are those of the whole render, bit for bit.
    pub only_tiles: Option<Vec<bool>>,
    /// Also the scene less the Gaussians whose one feature is 1 (`RenderOutput::after_removal`):
    /// the feature then marks the removal, 1 a removed Gaussian and 2 a kept object's (blend.comp).
    pub after_removal: bool,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            background: [0.0; 3],
            near: 0.01,
            sh_degree: None,
            features: false,
            timestamps: false,
            median_depth: false,
            only_tiles: None,
            after_removal: false,
        }
    }
}

/// Rendered planes (row-major, width * height each).
#[derive(Clone, Debug)]
pub struct RenderOutput {
    pub width: u32,
    pub height: u32,
    /// 3 planes: R, G, B.
    pub rgb: Vec<f32>,
    pub alpha: Vec<f32>,
    /// Accumulated depth sum w_i z_i.
    pub depth: Vec<f32>,
    pub expected_depth: Vec<f32>,
    /// Depth of the Gaussian that takes the transmittance to one half or below (the expected depth
    /// where the pixel never gets half opaque): a surface's depth where faint layers in front of
    /// or behind it pull the expected depth off it. Empty unless `RenderSettings::median_depth`.
    pub median_depth: Vec<f32>,
    pub final_t: Vec<f32>,
    pub n_contrib: Vec<u32>,
    /// feature_dim planes, when features were rendered.
    pub features: Vec<f32>,
    pub feature_dim: u32,
    pub num_intersections: u32,
    pub timings: Vec<PassTiming>,
    /// With `RenderSettings::after_removal`, the scene less the removed Gaussians from the same
    /// walk; its planes are, bit for bit, those a render of that scene alone gives.
    pub after_removal: Option<AfterRemoval>,
}

/// What a forward pass leaves for the host: its parameter block (camera, sizes, buffer addresses)
/// and statistics.
#[derive(Clone, Debug)]
pub struct Frame {
    pub params: RenderParams,
    pub num_intersections: u32,
    /// Whether the median depth was blended (`RenderSettings::median_depth`).
    pub median_depth: bool,
    /// Whether the scene after removal was blended too (`RenderSettings::after_removal`).
    pub after_removal: bool,
    pub timings: Vec<PassTiming>,
}

/// The output planes of the last forward pass, on the GPU.
pub struct FrameOutputs<'a> {
    pub rgb: &'a Buffer,
    pub alpha: &'a Buffer,
    pub depth: &'a Buffer,
    pub expected_depth: &'a Buffer,
    pub features: &'a Buffer,
}

/// Working buffers of one frame, grown on demand and reused.
struct FrameBuffers {
    gaussian_capacity: u32,
    xy: Buffer,
    conic_opacity: Buffer,
    depth: Buffer,
    color: Buffer,
    tile_rect: Buffer,
    tiles_touched: Buffer,
    depth_keys: Buffer,
    depth_order: Buffer,
    isect_offsets: Buffer,
}

struct IntersectionBuffers {
    capacity: u32,
    tile: Buffer,
    gauss: Buffer,
    tile_alt: Buffer,
    gauss_alt: Buffer,
}

struct ImageBuffers {
    width: u32,
    height: u32,
    feature_dim: u32,
    tile_ranges: Buffer,
    rgb: Buffer,
    alpha: Buffer,
    depth: Buffer,
    expected_depth: Buffer,
    median_depth: Buffer,
    final_t: Buffer,
    n_contrib: Buffer,
    features: Buffer,
    /// `RenderSettings::only_tiles`, one u32 per tile.
    tile_mask: Buffer,
    /// `RenderSettings::after_removal`'s planes, made on first use.
    after: Option<Buffer>,
}

/// Owner of the forward-pass pipelines and their working memory.
pub struct Rasterizer {
    gpu: Gpu,
    project: SpecializedPipelines,
    gather: ComputePipeline,
    emit: ComputePipeline,
    ranges: ComputePipeline,
    blend: ComputePipeline,
    /// blend.comp with its one-feature pass (ONE_FEATURE) or the median depth (MEDIAN_DEPTH), built
    /// on first use.
    blend_variants: SpecializedPipelines,
    blend_rows: u32,
    blend_features: FeaturePipelines,
    sort: RadixSort,
    scan: scan::PrefixScan,
    params: Buffer,
    /// Host-visible copy of the intersection count, written at the end of the first submission so
    /// that reading it costs no submission of its own (on a discrete GPU a download would).
    intersection_count: Buffer,
    frame: Option<FrameBuffers>,
    isect: Option<IntersectionBuffers>,
    image: Option<ImageBuffers>,
    /// The output planes' way back to the host: one submission for all of them.
    readback: Readback,
}

/// Capacity to allocate for `n` elements: headroom so growing scenes do not reallocate every time.
pub(crate) fn grow(n: u64) -> u64 {
    (n + n / 4).max(1024)
}

impl Rasterizer {
    pub fn new(gpu: &Gpu) -> Result<Rasterizer> {
        Self::with_layout(gpu, BlendLayout::for_device(gpu.info()))
    }

    /// As `new`, with the forward blend's pixels per invocation (`layout.forward_rows`) given instead
    /// of chosen for the device (tests run every layout on one device).
    pub fn with_layout(gpu: &Gpu, layout: BlendLayout) -> Result<Rasterizer> {
        layout.check()?;
        let rows = layout.forward_rows;
        Ok(Rasterizer {
            gpu: gpu.clone(),
            project: SpecializedPipelines::new("project", shaders::PROJECT),
            gather: ComputePipeline::new(gpu, "gather_counts", shaders::GATHER_COUNTS)?,
            emit: ComputePipeline::new(gpu, "emit_intersections", shaders::EMIT_INTERSECTIONS)?,
            ranges: ComputePipeline::new(gpu, "tile_ranges", shaders::TILE_RANGES)?,
            blend: ComputePipeline::specialized(gpu, "blend", shaders::BLEND, &[rows, 16 / rows])?,
            blend_variants: SpecializedPipelines::new("blend", shaders::BLEND),
            blend_rows: rows,
            blend_features: FeaturePipelines::new("blend_features", shaders::BLEND_FEATURES, layout.forward_rows),
            sort: RadixSort::new(gpu)?,
            scan: scan::PrefixScan::new(gpu)?,
            params: Buffer::new(gpu, "render params", std::mem::size_of::<RenderParams>() as u64, MemoryKind::Upload)?,
            intersection_count: Buffer::new(gpu, "intersection count", 4, MemoryKind::Readback)?,
            frame: None,
            isect: None,
            image: None,
            readback: Readback::default(),
        })
    }

    fn reserve_gaussians(&mut self, n: u32) -> Result<()> {
        if self.frame.as_ref().is_some_and(|f| f.gaussian_capacity >= n) {
            return Ok(());
        }
        self.frame = None;
        let cap = grow(n as u64);
        let g = &self.gpu;
        let buf = |name: &str, per: u64| Buffer::new(g, name, cap * per * 4, MemoryKind::Device);
        self.frame = Some(FrameBuffers {
            gaussian_capacity: cap as u32,
            xy: buf("xy", 2)?,
            conic_opacity: buf("conic_opacity", 4)?,
            depth: buf("depth", 1)?,
            color: buf("color", 3)?,
            tile_rect: buf("tile_rect", 4)?,
            tiles_touched: buf("tiles_touched", 1)?,
            depth_keys: buf("depth_keys", 1)?,
            depth_order: buf("depth_order", 1)?,
            isect_offsets: Buffer::new(g, "isect_offsets", (cap + 1) * 4, MemoryKind::Device)?,
        });
        self.sort.reserve(cap)?;
        self.scan.reserve(cap + 1)?;
        // the depth sort ping-pongs through the intersection buffers' alternates
        self.reserve_intersections(cap as u32)?;
        Ok(())
    }

    fn reserve_intersections(&mut self, m: u32) -> Result<()> {
        if self.isect.as_ref().is_some_and(|b| b.capacity >= m) {
            return Ok(());
        }
        self.isect = None;
        let cap = grow(m as u64);
        let g = &self.gpu;
        let buf = |name: &str| Buffer::new(g, name, cap * 4, MemoryKind::Device);
        self.isect = Some(IntersectionBuffers {
            capacity: cap as u32,
            tile: buf("isect_tile")?,
            gauss: buf("isect_gauss")?,
            tile_alt: buf("isect_tile_alt")?,
            gauss_alt: buf("isect_gauss_alt")?,
        });
        self.sort.reserve(cap)?;
        Ok(())
    }

    fn reserve_image(&mut self, width: u32, height: u32, feature_dim: u32) -> Result<()> {
        if self.image.as_ref().is_some_and(|i| i.width == width && i.height == height && i.feature_dim >= feature_dim) {
            return Ok(());
        }
        self.image = None;
        let g = &self.gpu;
        let hw = width as u64 * height as u64;
        let tiles = (width.div_ceil(TILE) * height.div_ceil(TILE)) as u64;
        let buf = |name: &str, n: u64| Buffer::new(g, name, n * 4, MemoryKind::Device);
        self.image = Some(ImageBuffers {
            width,
            height,
            feature_dim,
            tile_ranges: buf("tile_ranges", 2 * tiles)?,
            rgb: buf("out_rgb", 3 * hw)?,
            alpha: buf("out_alpha", hw)?,
            depth: buf("out_depth", hw)?,
            expected_depth: buf("out_expected_depth", hw)?,
            median_depth: buf("out_median_depth", hw)?,
            final_t: buf("out_final_t", hw)?,
            n_contrib: buf("out_n_contrib", hw)?,
            features: buf("out_features", feature_dim.max(1) as u64 * hw)?,
            tile_mask: Buffer::new(g, "tile_mask", tiles * 4, MemoryKind::Upload)?,
            after: None,
        });
        Ok(())
    }

    /// Renders one view. Two submissions: projection, depth sort and the scan of tile counts; then,
    /// once the number of intersections is known, emission, tile sort, ranges and blending.
    pub fn render(&mut self, scene: &SceneBuffers, camera: &Camera, settings: &RenderSettings) -> Result<RenderOutput> {
        let frame = self.forward(scene, camera, settings)?;
        self.read_output(&frame)
    }

    /// Runs the forward passes and leaves every output and the per-pixel state on the GPU (see
    /// `outputs`), ready for a loss and the backward passes.
    pub fn forward(&mut self, scene: &SceneBuffers, camera: &Camera, settings: &RenderSettings) -> Result<Frame> {
        let (mut frame, rec) = self.forward_open(scene, camera, settings)?;
        frame.timings.extend(rec.submit_and_wait()?);
        Ok(frame)
    }

    /// As `forward`, but the second submission (tile passes and blends) is returned unsubmitted, so
    /// that a caller records what follows (a training iteration's loss, backward and Adam) into it
    /// and pays one submission and wait for both. The outputs exist once it has been submitted.
    pub fn forward_open(
        &mut self,
        scene: &SceneBuffers,
        camera: &Camera,
        settings: &RenderSettings,
    ) -> Result<(Frame, Recorder)> {
        let (width, height) = (camera.width, camera.height);
        if width == 0 || height == 0 {
            bail!("camera {:?} has an empty image size", camera.name);
        }
        let n = scene.num_gaussians;
        if n == 0 {
            bail!("cannot render an empty scene");
        }
        let feature_dim = if settings.features { scene.feature_dim } else { 0 };
        if settings.features && scene.features.is_none() {
            bail!("features requested but the scene has none");
        }
        if settings.after_removal && feature_dim != 1 {
            bail!("the render after removal needs the one feature that marks the removal, not {feature_dim}");
        }
        self.reserve_gaussians(n)?;
        self.reserve_image(width, height, feature_dim)?;
        if settings.after_removal {
            let image = self.image.as_mut().unwrap();
            if image.after.is_none() {
                let size = AFTER_PLANES * 4 * width as u64 * height as u64;
                image.after = Some(Buffer::new(&self.gpu, "out_after", size, MemoryKind::Device)?);
            }
        }
        // (one feature blends in blend.comp: no feature pipeline to build)
        self.blend_features.prepare(&self.gpu, if feature_dim == 1 { 0 } else { feature_dim })?;
        let tiles_x = width.div_ceil(TILE);
        let tiles_y = height.div_ceil(TILE);
        let num_tiles = tiles_x * tiles_y;

        let mut params = self.frame_params(scene, camera, settings, feature_dim, tiles_x, tiles_y);
        if let Some(tiles) = &settings.only_tiles {
            if tiles.len() != num_tiles as usize {
                bail!("only_tiles marks {} tiles, the {width}x{height} image has {num_tiles}", tiles.len());
            }
            let mask: Vec<u32> = tiles.iter().map(|&t| t as u32).collect();
            let image = self.image.as_ref().unwrap();
            image.tile_mask.upload(&self.gpu, &mask)?;
            (params.tile_mask, params.only_tiles) = (image.tile_mask.address(), 1);
        }
        let degree = params.sh_degree;
        if degree > MAX_SH_DEGREE {
            bail!("cannot render SH degree {degree}: the shaders implement degrees 0..={MAX_SH_DEGREE}");
        }
        self.params.write_pod(&params)?;
        let push = ParamsPush { params: self.params.address() };
        let frame = self.frame.as_ref().unwrap();
        let isect = self.isect.as_ref().unwrap();

        // submission 1: project, depth sort, scan of touched counts in depth order
        let mut rec = Recorder::with_timestamps(&self.gpu, settings.timestamps)?;
        rec.dispatch(self.project.get(&self.gpu, &[degree])?, &push, dispatch_1d(n.div_ceil(256)));
        rec.mark_moved("project", moved::project(n, degree));
        let in_alt =
            self.sort.record(&mut rec, &frame.depth_keys, &frame.depth_order, &isect.tile_alt, &isect.gauss_alt, n, 31);
        assert!(!in_alt, "the 31-bit depth sort has an even number of passes");
        rec.mark_moved("depth sort", moved::sort(n, 31));
        rec.dispatch(&self.gather, &push, dispatch_1d((n + 1).div_ceil(256)));
        self.scan.record(&mut rec, &frame.isect_offsets, n + 1);
        rec.copy_region(&frame.isect_offsets, n as u64 * 4, &self.intersection_count, 0, 4);
        rec.mark("tile count scan");
        let timings = rec.submit_and_wait()?;
        // the one readback a frame needs: the intersection count sizes the buffers and dispatches of
        // the second submission
        let m = self.intersection_count.download::<u32>(&self.gpu, 1)?[0];

        // submission 2: emit intersections, sort by tile, find ranges, blend
        self.reserve_intersections(m)?;
        let isect = self.isect.as_ref().unwrap();
        let image = self.image.as_ref().unwrap();
        let tile_bits = 32 - (num_tiles.max(2) - 1).leading_zeros();
        let sorted_in_alt = sort::passes_for_bits(tile_bits) % 2 == 1;
        let (sorted_tile, sorted_gauss) =
            if sorted_in_alt { (&isect.tile_alt, &isect.gauss_alt) } else { (&isect.tile, &isect.gauss) };
        params.isect_tile = sorted_tile.address();
        params.isect_gauss = sorted_gauss.address();
        self.params.write_pod(&params)?;

        let mut rec = Recorder::with_timestamps(&self.gpu, settings.timestamps)?;
        rec.fill(&image.tile_ranges, 0, num_tiles as u64 * 8, 0);
        if m > 0 {
            let emit_push =
                EmitPush { params: push.params, out_tile: isect.tile.address(), out_gauss: isect.gauss.address() };
            rec.dispatch(&self.emit, &emit_push, dispatch_1d(n.div_ceil(256)));
            rec.mark_moved("emit intersections", moved::emit(n, m));
            let ended_in_alt =
                self.sort.record(&mut rec, &isect.tile, &isect.gauss, &isect.tile_alt, &isect.gauss_alt, m, tile_bits);
            debug_assert_eq!(ended_in_alt, sorted_in_alt);
            rec.mark_moved("tile sort", moved::sort(m, tile_bits));
            rec.dispatch(
                &self.ranges,
                &ParamsPushU32 { params: push.params, value: m, pad: 0 },
                dispatch_1d(m.div_ceil(256 * TILE_RANGE_RUN)),
            );
            rec.mark("tile ranges");
        }
        // the one feature rides along with the color (blend.comp, ONE_FEATURE); the median depth
        // is a variant of its own (MEDIAN_DEPTH), so that other renders do not pay for it (+5 %
        // blend time on lavapipe)
        let one_feature = feature_dim == 1;
        if one_feature || settings.median_depth {
            let rows = self.blend_rows;
            let (median, after) = (settings.median_depth as u32, settings.after_removal as u32);
            let constants = [rows, 16 / rows, one_feature as u32, median, after];
            rec.dispatch(self.blend_variants.get(&self.gpu, &constants)?, &push, dispatch_1d(num_tiles));
        } else {
            rec.dispatch(&self.blend, &push, dispatch_1d(num_tiles));
        }
        rec.mark_moved("blend", moved::blend(m, width * height, num_tiles));
        if !one_feature && feature_dim > 0 {
            for (offset, channels) in FeaturePipelines::passes(feature_dim) {
                let push = ParamsPushU32 { params: push.params, value: offset, pad: 0 };
                rec.dispatch(self.blend_features.get(channels), &push, dispatch_1d(num_tiles));
            }
            rec.mark("blend features");
        }
        let after_removal = settings.after_removal;
        Ok((Frame { params, num_intersections: m, median_depth: settings.median_depth, after_removal, timings }, rec))
    }

    /// Reads the outputs back through a staging buffer even where the device memory is mapped: a
    /// discrete GPU's path, for tests on any device.
    pub fn stage_readbacks(&mut self, always: bool) {
        self.readback.always_stage = always;
    }

    /// Reads a frame's outputs back to the host.
    pub fn read_output(&mut self, frame: &Frame) -> Result<RenderOutput> {
        let image = self.image.as_ref().unwrap();
        let (width, height, feature_dim) = (frame.params.width, frame.params.height, frame.params.feature_dim);
        let hw = (width * height) as usize;
        let mut rgb = vec![0f32; 3 * hw];
        let [mut alpha, mut depth, mut expected_depth, mut final_t] = [(); 4].map(|_| vec![0f32; hw]);
        let mut median_depth = vec![0f32; if frame.median_depth { hw } else { 0 }];
        let mut features = vec![0f32; feature_dim as usize * hw];
        let mut n_contrib = vec![0u32; hw];
        let mut after = vec![0f32; if frame.after_removal { AFTER_PLANES as usize * hw } else { 0 }];
        use bytemuck::cast_slice_mut as bytes;
        // without the render after removal its part is empty, and any buffer serves for no bytes
        let after_buffer = image.after.as_ref().unwrap_or(&image.features);
        self.readback.read_into(
            &self.gpu,
            &mut [
                (&image.rgb, 0, bytes(&mut rgb)),
                (&image.alpha, 0, bytes(&mut alpha)),
                (&image.depth, 0, bytes(&mut depth)),
                (&image.expected_depth, 0, bytes(&mut expected_depth)),
                (&image.median_depth, 0, bytes(&mut median_depth)),
                (&image.final_t, 0, bytes(&mut final_t)),
                (&image.n_contrib, 0, bytes(&mut n_contrib)),
                (&image.features, 0, bytes(&mut features)),
                (after_buffer, 0, bytes(&mut after)),
            ],
        )?;
        let after_removal = frame.after_removal.then(|| AfterRemoval::from_planes(&after, hw, frame.median_depth));
        Ok(RenderOutput {
            width,
            height,
            rgb,
            alpha,
            depth,
            expected_depth,
            median_depth,
            final_t,
            n_contrib,
            features,
            feature_dim,
            num_intersections: frame.num_intersections,
            timings: frame.timings.clone(),
            after_removal,
        })
    }

    /// The GPU buffers of the last frame's outputs.
    pub fn outputs(&self) -> Option<FrameOutputs<'_>> {
        self.image.as_ref().map(|i| FrameOutputs {
            rgb: &i.rgb,
            alpha: &i.alpha,
            depth: &i.depth,
            expected_depth: &i.expected_depth,
            features: &i.features,
        })
    }

    /// The parameter block of the last frame (what the backward passes read).
    pub fn params_buffer(&self) -> &Buffer {
        &self.params
    }

    fn frame_params(
        &self,
        scene: &SceneBuffers,
        camera: &Camera,
        settings: &RenderSettings,
        feature_dim: u32,
        tiles_x: u32,
        tiles_y: u32,
    ) -> RenderParams {
        let f = self.frame.as_ref().unwrap();
        let im = self.image.as_ref().unwrap();
        let r = &camera.rotation;
        let t = &camera.translation;
        let c = camera.center();
        let (tan_fovx, tan_fovy) = camera.tan_half_fov();
        let sh_coeffs = (scene.sh_degree + 1) * (scene.sh_degree + 1);
        RenderParams {
            means: scene.means.address(),
            log_scales: scene.log_scales.address(),
            quats: scene.quats.address(),
            opacity_logits: scene.opacity_logits.address(),
            sh: scene.sh.address(),
            features: scene.features.as_ref().map(|b| b.address()).unwrap_or(0),
            xy: f.xy.address(),
            conic_opacity: f.conic_opacity.address(),
            depth: f.depth.address(),
            color: f.color.address(),
            tile_rect: f.tile_rect.address(),
            tiles_touched: f.tiles_touched.address(),
            depth_keys: f.depth_keys.address(),
            depth_order: f.depth_order.address(),
            isect_offsets: f.isect_offsets.address(),
            isect_tile: 0,
            isect_gauss: 0,
            tile_ranges: im.tile_ranges.address(),
            out_rgb: im.rgb.address(),
            out_alpha: im.alpha.address(),
            out_depth: im.depth.address(),
            out_expected_depth: im.expected_depth.address(),
            out_final_t: im.final_t.address(),
            out_n_contrib: im.n_contrib.address(),
            out_features: im.features.address(),
            out_median_depth: im.median_depth.address(),
            viewmat: [
                r[0][0] as f32,
                r[0][1] as f32,
                r[0][2] as f32,
                t[0] as f32,
                r[1][0] as f32,
                r[1][1] as f32,
                r[1][2] as f32,
                t[1] as f32,
                r[2][0] as f32,
                r[2][1] as f32,
                r[2][2] as f32,
                t[2] as f32,
            ],
            campos: [c[0] as f32, c[1] as f32, c[2] as f32, 0.0],
            fx: camera.fx as f32,
            fy: camera.fy as f32,
            cx: camera.cx as f32,
            cy: camera.cy as f32,
            tan_fovx: tan_fovx as f32,
            tan_fovy: tan_fovy as f32,
            near_plane: settings.near,
            pad0: 0.0,
            background: [settings.background[0], settings.background[1], settings.background[2], 0.0],
            num_gaussians: scene.num_gaussians,
            sh_degree: settings.sh_degree.unwrap_or(scene.sh_degree).min(scene.sh_degree),
            sh_coeffs,
            width: camera.width,
            height: camera.height,
            tiles_x,
            tiles_y,
            feature_dim,
            // every tile unless `forward_open` marks some (`RenderSettings::only_tiles`)
            tile_mask: 0,
            only_tiles: 0,
            pad1: 0,
            out_after: im.after.as_ref().map_or(0, |b| b.address()),
        }
    }
}
