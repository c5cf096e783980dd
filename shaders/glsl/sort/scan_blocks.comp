#version 460
// Exclusive prefix scan, level pass: each workgroup scans SCAN_BLOCK consecutive uints in place and
// writes the block's total to block_sums, which the host scans recursively (reduce-then-scan; no
// workgroup waits on another).
#include "common.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push { Uints data; Uints block_sums; uint n; };

const uint PER_THREAD = 4;
const uint SCAN_BLOCK = 256 * PER_THREAD;
shared uint s_sums[256];

void main() {
    uint block = linear_group_id();
    if (block * SCAN_BLOCK >= n) return;  // uniform over the workgroup
    uint t = gl_LocalInvocationID.x;
    uint base = block * SCAN_BLOCK + t * PER_THREAD;
    uint v[PER_THREAD];
    uint sum = 0;
    for (uint i = 0; i < PER_THREAD; i++) {
        v[i] = base + i < n ? data.v[base + i] : 0;
        sum += v[i];
    }
    s_sums[t] = sum;
    barrier();
    for (uint off = 1; off < 256; off <<= 1) {
        uint x = t >= off ? s_sums[t - off] : 0;
        barrier();
        s_sums[t] += x;
        barrier();
    }
    uint prefix = s_sums[t] - sum;
    for (uint i = 0; i < PER_THREAD; i++) {
        if (base + i < n) data.v[base + i] = prefix;
        prefix += v[i];
    }
    if (t == 255) block_sums.v[block] = s_sums[255];
}
