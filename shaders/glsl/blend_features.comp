#version 460
// N-dim feature maps blended with the same weights as the color pass, reusing its sorted intersection
// lists. Handles channels [channel_offset, channel_offset + CHANNELS) per dispatch so any feature_dim
// works. Laid out as blend.comp: each invocation owns a column of ROWS pixels, a Gaussian's
// parameters and features are read from shared memory once for the column, and rows out of the
// Gaussian's reach are skipped. CHANNELS is a specialization constant so the accumulators are
// registers, not a dynamically indexed array. Every pixel makes exactly the decisions of blend_weight.
#include "common.glsl"
#include "render_params.glsl"
#include "blend_common.glsl"

layout(constant_id = 0) const uint ROWS = 1;
layout(constant_id = 1) const uint GROUP_HEIGHT = 16;
layout(constant_id = 2) const uint CHANNELS = 32;
layout(local_size_x = 16, local_size_y_id = 1) in;
layout(push_constant) uniform Push { RenderParams p; uint channel_offset; };

// 64 Gaussians of up to 32 channels: 8 KiB of features, well inside 32 KiB of shared memory
const uint BATCH = 64;
const uint THREADS = 16 * GROUP_HEIGHT;
shared vec2 s_xy[BATCH];
shared vec4 s_conic_opacity[BATCH];
shared float s_reach[BATCH];
shared float s_features[BATCH * CHANNELS];
shared uint s_any_alive;

void main() {
    uint tile = tile_id();
    if (tile >= p.tiles_x * p.tiles_y) return;  // uniform over the workgroup
    uint tx = tile % p.tiles_x, ty = tile / p.tiles_x;
    uint local = gl_LocalInvocationIndex;

    uint start = p.tile_ranges.v[2 * tile], end = p.tile_ranges.v[2 * tile + 1];
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

    for (uint batch = start; batch < end; batch += BATCH) {
        barrier();  // everyone is done with the previous batch and with s_any_alive
        if (local == 0) s_any_alive = 0;
        barrier();
        if (!lane_finished) atomicOr(s_any_alive, 1u);
        for (uint k = local; k < BATCH && batch + k < end; k += THREADS) {
            uint g = p.isect_gauss.v[batch + k];
            s_xy[k] = vec2(p.xy.v[2 * g], p.xy.v[2 * g + 1]);
            s_conic_opacity[k] = vec4(p.conic_opacity.v[4 * g], p.conic_opacity.v[4 * g + 1],
                                      p.conic_opacity.v[4 * g + 2], p.conic_opacity.v[4 * g + 3]);
            s_reach[k] = row_reach(s_conic_opacity[k]);
            uint base = g * p.feature_dim + channel_offset;
            uint channels = min(CHANNELS, p.feature_dim - channel_offset);
            for (uint c = 0; c < CHANNELS; c++) s_features[k * CHANNELS + c] = c < channels ? p.features.v[base + c] : 0.0;
        }
        barrier();
        if (s_any_alive == 0) break;
        uint count = min(BATCH, end - batch);
        for (uint j = 0; j < count && !lane_finished; j++) {
            vec2 xy = s_xy[j];
            vec4 co = s_conic_opacity[j];
            float reach = s_reach[j];
            lane_finished = true;
            for (uint r = 0; r < ROWS; r++) {
                // the rows of a subgroup's lanes are the same, so this skip is uniform over it
                if (!finished[r] && abs(pixel[r].y - xy.y) <= reach) {
                    float w = blend_weight(pixel[r], xy, co, T[r], finished[r]);
                    if (w > 0.0) {
                        for (uint c = 0; c < CHANNELS; c++) acc[r * CHANNELS + c] += w * s_features[j * CHANNELS + c];
                    }
                }
                lane_finished = lane_finished && finished[r];
            }
        }
    }
    uint hw = p.width * p.height;
    uint channels = min(CHANNELS, p.feature_dim - channel_offset);
    for (uint r = 0; r < ROWS; r++) {
        uvec2 pix = uvec2(tx * TILE + gl_LocalInvocationID.x, ty * TILE + gl_LocalInvocationID.y * ROWS + r);
        if (pix.x >= p.width || pix.y >= p.height) continue;
        uint pi = pix.y * p.width + pix.x;
        for (uint c = 0; c < channels; c++) p.out_features.v[(channel_offset + c) * hw + pi] = acc[r * CHANNELS + c];
    }
}
