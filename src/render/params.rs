//! The per-frame parameter block of the render passes; mirrors `shaders/glsl/common/render_params.glsl`
//! field for field (std430: pointers first, then 4-byte scalars, then the fields added since).

use bytemuck::{Pod, Zeroable};

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct RenderParams {
    pub means: u64,
    pub log_scales: u64,
    pub quats: u64,
    pub opacity_logits: u64,
    pub sh: u64,
    pub features: u64,
    pub xy: u64,
    pub conic_opacity: u64,
    pub depth: u64,
    pub color: u64,
    pub tile_rect: u64,
    pub tiles_touched: u64,
    pub depth_keys: u64,
    pub depth_order: u64,
    pub isect_offsets: u64,
    pub isect_tile: u64,
    pub isect_gauss: u64,
    pub tile_ranges: u64,
    pub out_rgb: u64,
    pub out_alpha: u64,
    pub out_depth: u64,
    pub out_expected_depth: u64,
    pub out_final_t: u64,
    pub out_n_contrib: u64,
    pub out_features: u64,
    pub viewmat: [f32; 12],
    pub campos: [f32; 4],
    pub fx: f32,
    pub fy: f32,
    pub cx: f32,
    pub cy: f32,
    pub tan_fovx: f32,
    pub tan_fovy: f32,
    pub near_plane: f32,
    pub pad0: f32,
    pub background: [f32; 4],
    pub num_gaussians: u32,
    pub sh_degree: u32,
    pub sh_coeffs: u32,
    pub width: u32,
    pub height: u32,
    pub tiles_x: u32,
    pub tiles_y: u32,
    pub feature_dim: u32,
    /// Written only by blend.comp's MEDIAN_DEPTH variant; after the scalars, as in the shader.
    pub out_median_depth: u64,
    /// One u32 per tile, read where `only_tiles` is nonzero: the tiles the blends composite
    /// (`RenderSettings::only_tiles`).
    pub tile_mask: u64,
    pub only_tiles: u32,
    pub pad1: u32,
    /// Written only by blend.comp's AFTER_REMOVAL variant: the 7 planes of `AfterRemoval`.
    pub out_after: u64,
}

/// Push constants of most render passes: just the address of the parameter block.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct ParamsPush {
    pub params: u64,
}

/// Push constants of passes that take the parameter block plus one more value.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct ParamsPushU32 {
    pub params: u64,
    pub value: u32,
    pub pad: u32,
}

/// Push constants of the emit pass: where to write the (unsorted) intersections.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct EmitPush {
    pub params: u64,
    pub out_tile: u64,
    pub out_gauss: u64,
}
