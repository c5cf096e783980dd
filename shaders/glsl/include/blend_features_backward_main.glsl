// Backward of blend_features.comp with respect to the features: dL/df_i = sum over pixels of
// w_i dL/dF(pixel). The weights are replayed front to back with the forward's own decisions. Gradients
// through the weights into geometry are not produced: feature training keeps geometry frozen.
// As in the color backward, each invocation owns a column of ROWS pixels (specialization constants,
// render::BlendLayout), sums a Gaussian's feature gradients over them in registers before
// the subgroup reduction and the atomics, and skips rows out of the Gaussian's reach. CHANNELS, the
// channels of one dispatch, is a specialization constant so the gradients stay in registers.
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

layout(constant_id = 0) const uint ROWS = 1;
layout(constant_id = 1) const uint GROUP_HEIGHT = 16;
layout(constant_id = 2) const uint CHANNELS = 32;
layout(local_size_x = 16, local_size_y_id = 1) in;
layout(push_constant) uniform Push { RenderParams p; BackwardParams b; uint channel_offset; };

const uint BATCH = 256;
const uint THREADS = 16 * GROUP_HEIGHT;
shared vec2 s_xy[BATCH];
shared vec4 s_conic_opacity[BATCH];
shared float s_reach[BATCH];
shared uint s_gauss[BATCH];
shared uint s_any_alive;

void main() {
    uint tile = tile_id();
    if (tile >= p.tiles_x * p.tiles_y) return;
    uint tx = tile % p.tiles_x, ty = tile / p.tiles_x;
    uint local = gl_LocalInvocationIndex;
    uint hw = p.width * p.height;
    uint channels = min(CHANNELS, p.feature_dim - channel_offset);
    vec2 pixel[ROWS];
    float T[ROWS];
    bool finished[ROWS];
    float dl_df[ROWS][CHANNELS];
    bool lane_finished = true;
    for (uint r = 0; r < ROWS; r++) {
        uvec2 pix = uvec2(tx * TILE + gl_LocalInvocationID.x, ty * TILE + gl_LocalInvocationID.y * ROWS + r);
        bool inside = pix.x < p.width && pix.y < p.height;
        uint pi = inside ? pix.y * p.width + pix.x : 0;
        pixel[r] = vec2(pix) + 0.5;
        T[r] = 1.0;
        finished[r] = !inside;
        lane_finished = lane_finished && finished[r];
        for (uint c = 0; c < CHANNELS; c++)
            dl_df[r][c] = (inside && c < channels) ? b.dl_dfeatures.v[(channel_offset + c) * hw + pi] : 0.0;
    }

    uint start = p.tile_ranges.v[2 * tile], end = p.tile_ranges.v[2 * tile + 1];
    for (uint batch = start; batch < end; batch += BATCH) {
        // stop once every pixel of the tile has saturated, as the forward pass does: long tile
        // lists behind opaque surfaces would otherwise be walked to the end
        barrier();
        if (local == 0) s_any_alive = 0;
        barrier();
        if (!lane_finished) atomicOr(s_any_alive, 1u);
        for (uint k = local; k < BATCH && batch + k < end; k += THREADS) {
            uint g = p.isect_gauss.v[batch + k];
            s_gauss[k] = g;
            s_xy[k] = vec2(p.xy.v[2 * g], p.xy.v[2 * g + 1]);
            s_conic_opacity[k] = vec4(p.conic_opacity.v[4 * g], p.conic_opacity.v[4 * g + 1],
                                      p.conic_opacity.v[4 * g + 2], p.conic_opacity.v[4 * g + 3]);
            s_reach[k] = row_reach(s_conic_opacity[k]);
        }
        barrier();
        if (s_any_alive == 0) break;
        uint count = min(BATCH, end - batch);
        for (uint j = 0; j < count; j++) {
            vec2 xy = s_xy[j];
            vec4 co = s_conic_opacity[j];
            float reach = s_reach[j];
            float w[ROWS];
            bool any_weight = false;
            lane_finished = true;
            for (uint r = 0; r < ROWS; r++) {
                w[r] = 0.0;
                // the rows of a subgroup's lanes are the same, so the reach test is uniform over it
                if (!finished[r] && abs(pixel[r].y - xy.y) <= reach) w[r] = blend_weight(pixel[r], xy, co, T[r], finished[r]);
                any_weight = any_weight || w[r] > 0.0;
                lane_finished = lane_finished && finished[r];
            }
            if (!subgroupAny(any_weight)) continue;  // uniform over the subgroup
            uint g = s_gauss[j];
            for (uint c = 0; c < CHANNELS; c++) {
                if (c >= channels) break;
                float v = 0.0;
                for (uint r = 0; r < ROWS; r++) v += w[r] * dl_df[r][c];
                v = subgroupAdd(v);
                if (subgroupElect()) grad_add(b.grad_features, g * p.feature_dim + channel_offset + c, v);
            }
        }
    }
}
