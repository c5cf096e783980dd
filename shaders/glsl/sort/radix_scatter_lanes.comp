#version 460
// Radix sort, pass 3 of 3 in the lane-serial shape (radix_lanes.glsl): each lane's next output slot
// per digit is the block's scanned offset plus the lane's offset within the block (left by the count
// pass); each lane then walks its slice in order, placing every key at its digit's next slot.
#include "common.glsl"
#include "radix_common.glsl"
#include "radix_lanes.glsl"

void main() {
    uint block = linear_group_id();
    if (block >= num_blocks) return;  // uniform over the workgroup
    uint lanes = gl_WorkGroupSize.x;
    for (uint d = gl_LocalInvocationID.x; d < RADIX; d += lanes) {
        uint base = histogram.v[d * num_blocks + block];
        for (uint l = 0; l < lanes; l++) {
            s_lane[l * RADIX + d] = base + lane_offsets.v[(block * lanes + l) * RADIX + d];
        }
    }
    barrier();
    uint start, end;
    lane_slice(block, BLOCK_KEYS, gl_WorkGroupSize.x, n, start, end);
    uint row = lane_row();
    UVec4s keys4 = UVec4s(keys_in), values4 = UVec4s(values_in);
    uint i = start;
    for (; i + 4 <= end; i += 4) {
        uvec4 k = keys4.v[i / 4], v = values4.v[i / 4];
        for (uint j = 0; j < 4; j++) {
            uint slot = row + digit_of(k[j]);
            uint dst = s_lane[slot];
            s_lane[slot] = dst + 1;
            keys_out.v[dst] = k[j];
            values_out.v[dst] = v[j];
        }
    }
    for (; i < end; i++) {
        uint key = keys_in.v[i];
        uint slot = row + digit_of(key);
        uint dst = s_lane[slot];
        s_lane[slot] = dst + 1;
        keys_out.v[dst] = key;
        values_out.v[dst] = values_in.v[i];
    }
}
