#version 460
// Exclusive prefix scan, level pass, lane-serial shape (scan_lanes.glsl): each lane sums its slice,
// the lanes' totals are scanned in shared memory (one entry per lane), and each lane writes its
// slice's exclusive prefix; the block's total goes to block_sums, as scan_blocks.comp does.
#include "common.glsl"
#include "scan_lanes.glsl"

const uint MAX_LANES = 128;
shared uint s_totals[MAX_LANES];

void main() {
    uint block = linear_group_id();
    if (block * BLOCK >= n) return;  // uniform over the workgroup
    uint start, end;
    lane_slice(block, BLOCK, gl_WorkGroupSize.x, n, start, end);
    UVec4s words = UVec4s(data);
    uint i = start, total = 0;
    for (; i + 4 <= end; i += 4) {
        uvec4 v = words.v[i / 4];
        total += v.x + v.y + v.z + v.w;
    }
    for (; i < end; i++) total += data.v[i];
    uint lane = gl_LocalInvocationID.x;
    s_totals[lane] = total;
    barrier();
    uint prefix = 0;
    for (uint l = 0; l < lane; l++) prefix += s_totals[l];
    for (i = start; i + 4 <= end; i += 4) {
        uvec4 v = words.v[i / 4];
        uvec4 out_ = uvec4(prefix, prefix + v.x, prefix + v.x + v.y, prefix + v.x + v.y + v.z);
        words.v[i / 4] = out_;
        prefix = out_.w + v.w;
    }
    for (; i < end; i++) {
        uint v = data.v[i];
        data.v[i] = prefix;
        prefix += v;
    }
    if (lane == gl_WorkGroupSize.x - 1) block_sums.v[block] = prefix;
}
