#version 460
// N-dim feature maps blended with the same weights as the color pass, reusing its sorted intersection
// lists. Handles channels [channel_offset, channel_offset + CHANNELS) per dispatch so any feature_dim
// works. Laid out and fed as blend.comp: each invocation owns a column of ROWS pixels, a Gaussian's
// parameters and features reach it by subgroup broadcast once for the column, and rows out of the
// Gaussian's reach are skipped. CHANNELS is a specialization constant so the accumulators are
// registers, not a dynamically indexed array. Every pixel makes exactly the decisions of blend_weight.
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_vote : require
#extension GL_KHR_shader_subgroup_ballot : require
#include "common.glsl"
#include "render_params.glsl"
#include "blend_common.glsl"

layout(constant_id = 0) const uint ROWS = 1;
layout(constant_id = 1) const uint GROUP_HEIGHT = 16;
layout(constant_id = 2) const uint CHANNELS = 32;
layout(local_size_x = 16, local_size_y_id = 1) in;
layout(push_constant) uniform Push { RenderParams p; uint channel_offset; };

void main() {
    uint tile = tile_id();
    if (tile >= p.tiles_x * p.tiles_y) return;  // uniform over the workgroup
    uint tx = tile % p.tiles_x, ty = tile / p.tiles_x;

    uvec2 range = blended_range(p, tile);
    uint start = range.x, end = range.y;
    vec2 pixel[ROWS];
    float T[ROWS];
    float acc[ROWS * CHANNELS];
    bool finished[ROWS];
    bool lane_finished = true;
    for (uint r = 0; r < ROWS; r++) {
        uvec2 pix = uvec2(tx * TILE + gl_LocalInvocationID.x, ty * TILE + gl_LocalInvocationID.y * ROWS + r);
        pixel[r] = vec2(pix) + 0.5;
        T[r] = 1.0;
        finished[r] = !(pix.x < p.width && pix.y < p.height);
        lane_finished = lane_finished && finished[r];
    }
    for (uint k = 0; k < ROWS * CHANNELS; k++) acc[k] = 0.0;

    // Fed as blend.comp: each subgroup walks the list on its own, lane l loading the batch's l-th
    // Gaussian and its features into registers, every lane taking them in order by broadcast.
    uint channels = min(CHANNELS, p.feature_dim - channel_offset);
    uint lanes = subgroupBallotBitCount(subgroupBallot(true));
    for (uint batch = start; batch < end; batch += lanes) {
        if (subgroupAll(lane_finished)) break;
        uint k = batch + gl_SubgroupInvocationID;
        vec2 my_xy = vec2(0.0);
        vec4 my_co = vec4(0.0);
        float my_reach = -1.0;  // past the end: reaches no row
        float my_features[CHANNELS];
        for (uint c = 0; c < CHANNELS; c++) my_features[c] = 0.0;
        if (k < end) {
            uint g = p.isect_gauss.v[k];
            my_xy = Vec2View(p.xy).v[g];
            my_co = Vec4View(p.conic_opacity).v[g];
            my_reach = row_reach(my_co);
            uint base = g * p.feature_dim + channel_offset;
            for (uint c = 0; c < CHANNELS; c++) my_features[c] = c < channels ? p.features.v[base + c] : 0.0;
        }
        uint count = min(lanes, end - batch);
        for (uint j = 0; j < count; j++) {
            vec2 xy = subgroupBroadcast(my_xy, j);
            vec4 co = subgroupBroadcast(my_co, j);
            float reach = subgroupBroadcast(my_reach, j);
            float w[ROWS];
            bool any_weight = false;
            lane_finished = true;
            for (uint r = 0; r < ROWS; r++) {
                w[r] = 0.0;
                // the rows of a subgroup's lanes are the same on a CPU driver, so this skip is uniform there
                if (!finished[r] && abs(pixel[r].y - xy.y) <= reach) w[r] = blend_weight(pixel[r], xy, co, T[r], finished[r]);
                any_weight = any_weight || w[r] > 0.0;
                lane_finished = lane_finished && finished[r];
            }
            if (!subgroupAny(any_weight)) continue;  // uniform: the features are only fetched when used
            for (uint c = 0; c < CHANNELS; c++) {
                float f = subgroupBroadcast(my_features[c], j);
                for (uint r = 0; r < ROWS; r++) {
                    if (w[r] > 0.0) acc[r * CHANNELS + c] += w[r] * f;
                }
            }
        }
    }
    uint hw = p.width * p.height;
    for (uint r = 0; r < ROWS; r++) {
        uvec2 pix = uvec2(tx * TILE + gl_LocalInvocationID.x, ty * TILE + gl_LocalInvocationID.y * ROWS + r);
        if (pix.x >= p.width || pix.y >= p.height) continue;
        uint pi = pix.y * p.width + pix.x;
        for (uint c = 0; c < channels; c++) p.out_features.v[(channel_offset + c) * hw + pi] = acc[r * CHANNELS + c];
    }
}
