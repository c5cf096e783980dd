#version 460
// Radix sort, pass 1 of 3: each block's digit histogram, written digit-major so one exclusive scan of the
// whole histogram gives every (digit, block) its global output offset.
#include "common.glsl"
#include "radix_common.glsl"

layout(local_size_x = 256) in;
shared uint s_hist[RADIX];

void main() {
    uint block = linear_group_id();
    if (block >= num_blocks) return;  // uniform over the workgroup
    uint t = gl_LocalInvocationID.x;
    if (t < RADIX) s_hist[t] = 0;
    barrier();
    uvec4 packed = count_run(block, t);
    for (uint d = 0; d < RADIX; d++) {
        uint c = unpack_count(packed, d);
        if (c != 0) atomicAdd(s_hist[d], c);
    }
    barrier();
    if (t < RADIX) histogram.v[t * num_blocks + block] = s_hist[t];
}
