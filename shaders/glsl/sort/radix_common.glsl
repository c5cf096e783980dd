// Reduce-then-scan LSD radix sort of 32-bit keys with 32-bit values, 8 bits per pass.
// A block of BLOCK_KEYS keys is handled by one workgroup of one subgroup (the workgroup size is the
// device's subgroup size: 8 on lavapipe, 32 on NVIDIA), which walks the block in order, one row of
// consecutive keys per step (contiguous loads on a GPU, one SIMD row on a CPU driver). The keys of a
// row that share a digit find each other with ballots (match_digit); the last of them bumps the
// block's running digit offsets, so ranking needs no atomics, no per-subgroup histograms to clear and
// combine, and no rank storage between phases. No workgroup waits on another (no forward-progress assumption).
// Stable: rows in order, lanes in order, blocks in order. CPU drivers use the lane-serial shape of the
// count and scatter instead (radix_lanes.glsl); the histogram and its scan are the same.
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_ballot : require

// The workgroup size is specialized to the device's subgroup size (render/sort.rs).
layout(local_size_x_id = 0) in;

const uint RADIX_BITS = 8;
const uint RADIX = 1u << RADIX_BITS;
// Keys per block, specialized per shape (render::sort::SortShape::block_keys).
layout(constant_id = 1) const uint BLOCK_KEYS = 4096;

layout(push_constant) uniform Push {
    Uints keys_in;
    Uints values_in;
    Uints keys_out;
    Uints values_out;
    Uints histogram;   // RADIX * num_blocks, digit-major; scanned in place between the two passes
    uint n;
    uint shift;
    uint num_blocks;
    uint digit_mask;   // (1 << bits of this pass) - 1: key bits above the sorted width never order
    Uints lane_offsets;  // lane-serial shape only (radix_lanes.glsl)
};

uint digit_of(uint key) { return (key >> shift) & digit_mask; }

// Among the lanes holding a valid key with digit d: how many come before this lane, how many there are,
// and whether this lane is the last of them, from RADIX_BITS ballots. (Comparing with each lane's
// digit by broadcasts measured the same on llvmpipe, about 31 ms per 1M-key scatter pass either way,
// so only ballots are kept.)
void match_digit(uint d, bool valid, out uint before, out uint total, out bool last) {
    uvec4 peers = subgroupBallot(valid);
    for (uint b = 0; b < RADIX_BITS; b++) {
        bool bit = ((d >> b) & 1u) != 0;
        uvec4 vote = subgroupBallot(bit);
        peers &= bit ? vote : ~vote;
    }
    before = subgroupBallotExclusiveBitCount(peers);
    total = subgroupBallotBitCount(peers);
    last = valid && subgroupBallotFindMSB(peers) == gl_SubgroupInvocationID;
}
