// Backward of blend_features.comp with respect to the features: dL/df_i = sum over pixels of
// w_i dL/dF(pixel). The weights are replayed front to back with the forward's own decisions. Gradients
// through the weights into geometry are not produced: feature training keeps geometry frozen.
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_vote : require
#ifndef NO_FLOAT_ATOMICS
#extension GL_EXT_shader_atomic_float : require
#endif
#include "common.glsl"
#include "render_params.glsl"
#include "backward_params.glsl"
#include "blend_common.glsl"

layout(local_size_x = 16, local_size_y = 16) in;
layout(push_constant) uniform Push { RenderParams p; BackwardParams b; uint channel_offset; };

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
    uint hw = p.width * p.height;
    uint pi = inside ? pix.y * p.width + pix.x : 0;
    uint channels = min(CHANNELS, p.feature_dim - channel_offset);
    float dl_df[CHANNELS];
    for (uint c = 0; c < CHANNELS; c++) dl_df[c] = (inside && c < channels) ? b.dl_dfeatures.v[(channel_offset + c) * hw + pi] : 0.0;

    uint start = p.tile_ranges.v[2 * tile], end = p.tile_ranges.v[2 * tile + 1];
    float T = 1.0;
    bool finished = !inside;
    for (uint batch = start; batch < end; batch += BATCH) {
        // stop once every pixel of the tile has saturated, as the forward pass does: long tile
        // lists behind opaque surfaces would otherwise be walked to the end
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
        for (uint j = 0; j < count; j++) {
            float w = finished ? 0.0 : blend_weight(pixel, s_xy[j], s_conic_opacity[j], T, finished);
            bool any_weight = subgroupAny(w > 0.0);
            if (!any_weight) continue;  // uniform over the subgroup
            uint g = s_gauss[j];
            for (uint c = 0; c < channels; c++) {
                float v = subgroupAdd(w * dl_df[c]);
                if (subgroupElect()) grad_add(b.grad_features, g * p.feature_dim + channel_offset + c, v);
            }
        }
    }
}
