#version 460
// One thread per Gaussian in depth order: writes (tile id, Gaussian id) for every tile it touches,
// starting at its scanned offset. Intersections therefore come out in depth order, and the stable
// tile-id sort that follows keeps that order inside each tile.
#include "common.glsl"
#include "render_params.glsl"
#include "tile_binning.glsl"

layout(local_size_x = 256) in;
// The unsorted lists go to out_tile / out_gauss; p.isect_tile / p.isect_gauss name where the tile sort
// leaves the sorted ones.
layout(push_constant) uniform Push { RenderParams p; Uints out_tile; Uints out_gauss; };

void main() {
    uint s = linear_group_id() * 256 + gl_LocalInvocationID.x;
    if (s >= p.num_gaussians) return;
    uint g = p.depth_order.v[s];
    if (p.tiles_touched.v[g] == 0) return;
    uint slot = p.isect_offsets.v[s];
    vec2 xy = vec2(p.xy.v[2 * g], p.xy.v[2 * g + 1]);
    vec3 conic = vec3(p.conic_opacity.v[4 * g], p.conic_opacity.v[4 * g + 1], p.conic_opacity.v[4 * g + 2]);
    float threshold = binning_q_threshold(p.conic_opacity.v[4 * g + 3]);
    uvec4 rect = uvec4(p.tile_rect.v[4 * g], p.tile_rect.v[4 * g + 1], p.tile_rect.v[4 * g + 2], p.tile_rect.v[4 * g + 3]);
    for (uint ty = rect.y; ty < rect.w; ty++)
        for (uint tx = rect.x; tx < rect.z; tx++)
            if (gaussian_touches_tile(xy, conic, threshold, tx, ty, p.width, p.height)) {
                out_tile.v[slot] = ty * p.tiles_x + tx;
                out_gauss.v[slot] = g;
                slot++;
            }
}
