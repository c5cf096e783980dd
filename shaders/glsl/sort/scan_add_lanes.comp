#version 460
// Exclusive prefix scan, down pass, lane-serial shape (scan_lanes.glsl): adds the block's scanned
// offset to each lane's slice, as uvec4s.
#include "common.glsl"
#include "scan_lanes.glsl"

void main() {
    uint block = linear_group_id();
    if (block * BLOCK >= n) return;
    uint add = block_sums.v[block];
    uint start, end;
    lane_slice(block, BLOCK, gl_WorkGroupSize.x, n, start, end);
    UVec4s words = UVec4s(data);
    uint i = start;
    for (; i + 4 <= end; i += 4) words.v[i / 4] += add;
    for (; i < end; i++) data.v[i] += add;
}
