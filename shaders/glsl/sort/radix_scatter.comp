#version 460
// Radix sort, pass 3 of 3 (pass 2 is the exclusive scan of the histogram): each key goes to the global
// offset of (digit, block) plus the number of keys of its digit before it in the block.
#include "common.glsl"
#include "radix_common.glsl"

shared uint s_hist[RADIX];

void main() {
    uint block = linear_group_id();
    if (block >= num_blocks) return;
    // s_hist[d]: where the block's next key of digit d goes
    for (uint d = gl_LocalInvocationID.x; d < RADIX; d += gl_WorkGroupSize.x) {
        s_hist[d] = histogram.v[d * num_blocks + block];
    }
    barrier();
    // The workgroup is one subgroup wherever the driver honours the reported size; if it splits it,
    // the first subgroup walks the whole block alone, which stays correct.
    if (gl_SubgroupID != 0) return;
    uint start = block * BLOCK_KEYS, end = min(start + BLOCK_KEYS, n);
    for (uint row = start; row < end; row += gl_SubgroupSize) {
        uint idx = row + gl_SubgroupInvocationID;
        bool valid = idx < end;
        uint key = valid ? keys_in.v[idx] : 0;
        uint d = digit_of(key);
        uint below, total;
        bool last;
        match_digit(d, valid, below, total, last);
        uint base = valid ? s_hist[d] : 0;
        subgroupBarrier();  // every lane has read s_hist before the last lane of each digit bumps it
        if (last) s_hist[d] = base + total;
        subgroupMemoryBarrierShared();
        subgroupBarrier();
        if (valid) {
            uint dst = base + below;
            keys_out.v[dst] = key;
            values_out.v[dst] = values_in.v[idx];
        }
    }
}
