#version 460
// Exclusive prefix scan, down pass: adds each block's scanned offset to its SCAN_BLOCK elements.
#include "common.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push { Uints data; Uints block_sums; uint n; };

const uint SCAN_BLOCK = 1024;

void main() {
    uint block = linear_group_id();
    if (block * SCAN_BLOCK >= n) return;
    uint add = block_sums.v[block];
    for (uint i = gl_LocalInvocationID.x; i < SCAN_BLOCK; i += 256) {
        uint idx = block * SCAN_BLOCK + i;
        if (idx < n) data.v[idx] += add;
    }
}
