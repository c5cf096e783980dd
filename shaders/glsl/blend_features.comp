#version 460
// N-dim feature maps blended with the same weights as the color pass, reusing its sorted intersection
// lists. Handles channels [channel_offset, channel_offset + 32) per dispatch so any feature_dim works.
#include "common.glsl"
#include "render_params.glsl"
#include "blend_common.glsl"

layout(local_size_x = 16, local_size_y = 16) in;
layout(push_constant) uniform Push { RenderParams p; uint channel_offset; };

const uint BATCH = 256;
const uint CHANNELS = 32;
shared vec2 s_xy[BATCH];
shared vec4 s_conic_opacity[BATCH];
shared uint s_gauss[BATCH];
shared uint s_any_alive;

void main() {
    uint tile = tile_id();
    if (tile >= p.tiles_x * p.tiles_y) return;
    uint tx = tile % p.tiles_x, ty = tile / p.tiles_x;
    uvec2 pix = uvec2(tx * TILE + gl_LocalInvocationID.x, ty * TILE + gl_LocalInvocationID.y);
    bool inside = pix.x < p.width && pix.y < p.height;
    vec2 pixel = vec2(pix) + 0.5;
    uint local = gl_LocalInvocationIndex;
    uint channels = min(CHANNELS, p.feature_dim - channel_offset);

    uint start = p.tile_ranges.v[2 * tile], end = p.tile_ranges.v[2 * tile + 1];
    float T = 1.0;
    float acc[CHANNELS];
    for (uint c = 0; c < CHANNELS; c++) acc[c] = 0.0;
    bool finished = !inside;

    for (uint batch = start; batch < end; batch += BATCH) {
        barrier();
        if (local == 0) s_any_alive = 0;
        barrier();
        if (!finished) atomicOr(s_any_alive, 1u);
        uint idx = batch + local;
        if (idx < end) {
            uint g = p.isect_gauss.v[idx];
            s_gauss[local] = g;
            s_xy[local] = vec2(p.xy.v[2 * g], p.xy.v[2 * g + 1]);
            s_conic_opacity[local] = vec4(p.conic_opacity.v[4 * g], p.conic_opacity.v[4 * g + 1],
                                          p.conic_opacity.v[4 * g + 2], p.conic_opacity.v[4 * g + 3]);
        }
        barrier();
        if (s_any_alive == 0) break;
        uint count = min(BATCH, end - batch);
        for (uint j = 0; j < count && !finished; j++) {
            float w = blend_weight(pixel, s_xy[j], s_conic_opacity[j], T, finished);
            if (w > 0.0) {
                uint base = s_gauss[j] * p.feature_dim + channel_offset;
                for (uint c = 0; c < channels; c++) acc[c] += w * p.features.v[base + c];
            }
        }
    }
    if (!inside) return;
    uint hw = p.width * p.height;
    uint pi = pix.y * p.width + pix.x;
    for (uint c = 0; c < channels; c++) p.out_features.v[(channel_offset + c) * hw + pi] = acc[c];
}
