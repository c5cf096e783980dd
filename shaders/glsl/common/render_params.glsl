// The per-frame parameter block shared by the render passes (projection, binning, blending).
// Mirrors `render::params::RenderParams` in Rust field for field (std430, pointers first).
layout(buffer_reference, std430, buffer_reference_align = 8) readonly buffer RenderParams {
    // scene attributes, stored before activation (conventions.md)
    Floats means;          // 3N
    Floats log_scales;     // 3N
    Floats quats;          // 4N, (w, x, y, z), not normalized
    Floats opacity_logits; // N
    Floats sh;             // N * K * 3, [gaussian][basis][channel]
    Floats features;       // N * D
    // projection outputs
    Floats xy;             // 2N, pixel coordinates of the projected mean
    Floats conic_opacity;  // 4N, (a, b, c, sigmoid(opacity))
    Floats depth;          // N, view-space z
    Floats color;          // 3N, clamped SH color
    Uints tile_rect;       // 4N, tile x0, y0, x1, y1 (x1, y1 exclusive)
    Uints tiles_touched;   // N
    Uints depth_keys;      // N, float bits of z, 0x7fffffff when culled
    Uints depth_order;     // N, Gaussian ids sorted by depth
    Uints isect_offsets;   // N + 1, exclusive scan of tiles_touched in depth order
    // intersections (tile id, Gaussian id), sorted by tile then depth
    Uints isect_tile;      // M
    Uints isect_gauss;     // M
    Uints tile_ranges;     // 2 * tiles, [start, end) into the intersection list
    // planar image outputs, width * height each
    Floats out_rgb;        // 3 planes
    Floats out_alpha;
    Floats out_depth;      // accumulated sum of w_i z_i
    Floats out_expected_depth;
    Floats out_final_t;    // transmittance after the last blended Gaussian (backward pass state)
    Uints out_n_contrib;   // one past the intersection index of the last blended Gaussian
    Floats out_features;   // feature_dim planes
    // camera
    float viewmat[12];     // row-major [R | t], world to camera
    float campos[4];       // camera center in world space, w unused
    float fx; float fy; float cx; float cy;
    float tan_fovx; float tan_fovy; float near_plane; float pad0;
    float background[4];
    uint num_gaussians;
    uint sh_degree;        // degree used for color, <= the stored degree
    uint sh_coeffs;        // stored coefficients per channel, K = (stored degree + 1)^2
    uint width;
    uint height;
    uint tiles_x;
    uint tiles_y;
    uint feature_dim;
    Floats out_median_depth; // depth where the transmittance falls to one half (blend.comp, MEDIAN_DEPTH)
    // with only_tiles != 0, the blends composite only the tiles whose entry here is nonzero and
    // leave the others empty (background, alpha 0): a render of which the caller reads a part
    Uints tile_mask;       // tiles
    uint only_tiles;
    uint pad1;
    // blend.comp's AFTER_REMOVAL variant: the scene less the removed Gaussians, 7 planes
    Floats out_after;
};

// The range of intersections the blends composite for `tile`: empty for a tile the mask leaves out.
uvec2 blended_range(RenderParams p, uint tile) {
    uvec2 range = UVec2View(p.tile_ranges).v[tile];
    return p.only_tiles != 0 && p.tile_mask.v[tile] == 0 ? uvec2(range.x) : range;
}

const uint TILE = 16;
const float ALPHA_MIN = 1.0 / 255.0;
const float ALPHA_MAX = 0.99;
const float T_MIN = 1e-4;
