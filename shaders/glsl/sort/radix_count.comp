#version 460
// Radix sort, pass 1 of 3: each block's digit histogram, written digit-major so one exclusive scan of the
// whole histogram gives every (digit, block) its global output offset.
#include "common.glsl"
#include "radix_common.glsl"

shared uint s_hist[RADIX];

void main() {
    uint block = linear_group_id();
    if (block >= num_blocks) return;  // uniform over the workgroup
    for (uint d = gl_LocalInvocationID.x; d < RADIX; d += gl_WorkGroupSize.x) s_hist[d] = 0;
    barrier();
    uint start = block * BLOCK_KEYS, end = min(start + BLOCK_KEYS, n);
    for (uint i = start + gl_LocalInvocationID.x; i < end; i += gl_WorkGroupSize.x) {
        atomicAdd(s_hist[digit_of(keys_in.v[i])], 1u);
    }
    barrier();
    for (uint d = gl_LocalInvocationID.x; d < RADIX; d += gl_WorkGroupSize.x) {
        histogram.v[d * num_blocks + block] = s_hist[d];
    }
}
