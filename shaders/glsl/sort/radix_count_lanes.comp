#version 460
// Radix sort, pass 1 of 3 in the lane-serial shape (radix_lanes.glsl): each lane counts its slice into
// its own row; per digit, the rows' running sum gives each lane its offset within the block
// (lane_offsets) and the rows' total is the block's entry in the digit-major histogram.
#include "common.glsl"
#include "radix_common.glsl"
#include "radix_lanes.glsl"

// Counts the digits of this lane's slice into its row of s_lane.
void count_lane_slice(uint start, uint end) {
    uint row = lane_row();
    for (uint d = 0; d < RADIX; d++) s_lane[row + d] = 0;
    UVec4s keys4 = UVec4s(keys_in);
    uint i = start;
    for (; i + 4 <= end; i += 4) {
        uvec4 k = keys4.v[i / 4];
        s_lane[row + digit_of(k.x)] += 1;
        s_lane[row + digit_of(k.y)] += 1;
        s_lane[row + digit_of(k.z)] += 1;
        s_lane[row + digit_of(k.w)] += 1;
    }
    for (; i < end; i++) s_lane[row + digit_of(keys_in.v[i])] += 1;
}

void main() {
    uint block = linear_group_id();
    if (block >= num_blocks) return;  // uniform over the workgroup
    uint start, end;
    lane_slice(block, BLOCK_KEYS, gl_WorkGroupSize.x, n, start, end);
    count_lane_slice(start, end);
    barrier();
    uint lanes = gl_WorkGroupSize.x;
    for (uint d = gl_LocalInvocationID.x; d < RADIX; d += lanes) {
        uint total = 0;
        for (uint l = 0; l < lanes; l++) {
            lane_offsets.v[(block * lanes + l) * RADIX + d] = total;
            total += s_lane[l * RADIX + d];
        }
        histogram.v[d * num_blocks + block] = total;
    }
}
