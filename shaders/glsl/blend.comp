#version 460
// Tile rasterizer: one 16x16 workgroup per tile composites the tile's depth-sorted Gaussians front to
// back. Outputs RGB (+ background), alpha, accumulated depth, expected depth, and the per-pixel state the
// backward pass replays: final transmittance and the index past the last blended intersection.
#include "common.glsl"
#include "render_params.glsl"
#include "blend_common.glsl"

layout(local_size_x = 16, local_size_y = 16) in;
layout(push_constant) uniform Push { RenderParams p; };

const uint BATCH = 256;
shared vec2 s_xy[BATCH];
shared vec4 s_conic_opacity[BATCH];
shared vec4 s_color_depth[BATCH];
shared uint s_any_alive;

void main() {
    uint tile = tile_id();
    if (tile >= p.tiles_x * p.tiles_y) return;  // uniform over the workgroup
    uint tx = tile % p.tiles_x, ty = tile / p.tiles_x;
    uvec2 pix = uvec2(tx * TILE + gl_LocalInvocationID.x, ty * TILE + gl_LocalInvocationID.y);
    bool inside = pix.x < p.width && pix.y < p.height;
    vec2 pixel = vec2(pix) + 0.5;
    uint local = gl_LocalInvocationIndex;

    uint start = p.tile_ranges.v[2 * tile], end = p.tile_ranges.v[2 * tile + 1];
    float T = 1.0;
    vec3 C = vec3(0.0);
    float D = 0.0, W = 0.0;
    uint n_contrib = start;
    bool finished = !inside;

    for (uint batch = start; batch < end; batch += BATCH) {
        barrier();  // everyone is done with the previous batch and with s_any_alive
        if (local == 0) s_any_alive = 0;
        barrier();
        if (!finished) atomicOr(s_any_alive, 1u);
        uint idx = batch + local;
        if (idx < end) {
            uint g = p.isect_gauss.v[idx];
            s_xy[local] = vec2(p.xy.v[2 * g], p.xy.v[2 * g + 1]);
            s_conic_opacity[local] = vec4(p.conic_opacity.v[4 * g], p.conic_opacity.v[4 * g + 1],
                                          p.conic_opacity.v[4 * g + 2], p.conic_opacity.v[4 * g + 3]);
            s_color_depth[local] = vec4(p.color.v[3 * g], p.color.v[3 * g + 1], p.color.v[3 * g + 2], p.depth.v[g]);
        }
        barrier();
        if (s_any_alive == 0) break;
        uint count = min(BATCH, end - batch);
        for (uint j = 0; j < count && !finished; j++) {
            float w = blend_weight(pixel, s_xy[j], s_conic_opacity[j], T, finished);
            if (w > 0.0) {
                C += w * s_color_depth[j].rgb;
                D += w * s_color_depth[j].w;
                W += w;
                n_contrib = batch + j + 1;
            }
        }
    }
    if (!inside) return;
    uint hw = p.width * p.height;
    uint pi = pix.y * p.width + pix.x;
    vec3 rgb = C + T * vec3(p.background[0], p.background[1], p.background[2]);
    p.out_rgb.v[pi] = rgb.r;
    p.out_rgb.v[hw + pi] = rgb.g;
    p.out_rgb.v[2 * hw + pi] = rgb.b;
    p.out_alpha.v[pi] = 1.0 - T;
    p.out_depth.v[pi] = D;
    p.out_expected_depth.v[pi] = D / max(W, 1e-10);
    p.out_final_t.v[pi] = T;
    p.out_n_contrib.v[pi] = n_contrib;
}
