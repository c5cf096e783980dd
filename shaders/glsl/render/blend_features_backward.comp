#version 460
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
#extension GL_KHR_shader_subgroup_ballot : require
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

void main() {
    uint tile = tile_id();
    if (tile >= p.tiles_x * p.tiles_y) return;
    uint tx = tile % p.tiles_x, ty = tile / p.tiles_x;
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

    uvec2 range = UVec2View(p.tile_ranges).v[tile];
    uint start = range.x, end = range.y;
    // Fed as blend.comp: each subgroup walks the list on its own, lane l loading the batch's l-th
    // Gaussian into registers and every lane taking them in order by broadcast; it stops once its
    // own pixels have saturated, as the forward pass does.
    uint lanes = subgroupBallotBitCount(subgroupBallot(true));
    for (uint batch = start; batch < end; batch += lanes) {
        if (subgroupAll(lane_finished)) break;
        uint k = batch + gl_SubgroupInvocationID;
        uint my_g = 0;
        vec2 my_xy = vec2(0.0);
        vec4 my_co = vec4(0.0);
        float my_reach = -1.0;  // past the end: reaches no row
        if (k < end) {
            my_g = p.isect_gauss.v[k];
            my_xy = Vec2View(p.xy).v[my_g];
            my_co = Vec4View(p.conic_opacity).v[my_g];
            my_reach = row_reach(my_co);
        }
        uint count = min(lanes, end - batch);
        // As in blend_backward: the subgroup's sums for the batch's j-th Gaussian end up in lane j,
        // and the lanes add theirs together after the batch (one atomic loop per channel and batch
        // on lavapipe, not one per channel and Gaussian).
        float my_v[CHANNELS];
        for (uint c = 0; c < CHANNELS; c++) my_v[c] = 0.0;
        bool my_any = false;
        for (uint j = 0; j < count; j++) {
            vec2 xy = subgroupBroadcast(my_xy, j);
            vec4 co = subgroupBroadcast(my_co, j);
            float reach = subgroupBroadcast(my_reach, j);
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
            bool mine = gl_SubgroupInvocationID == j;
            my_any = my_any || mine;
            for (uint c = 0; c < CHANNELS; c++) {
                float v = 0.0;
                for (uint r = 0; r < ROWS; r++) v += w[r] * dl_df[r][c];
                v = subgroupAdd(v);
                my_v[c] = mine ? v : my_v[c];
            }
        }
        if (my_any) {
            for (uint c = 0; c < CHANNELS; c++) {
                if (c >= channels) break;
                grad_add(b.grad_features, my_g * p.feature_dim + channel_offset + c, my_v[c]);
            }
        }
    }
}
