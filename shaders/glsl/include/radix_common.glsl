// Reduce-then-scan LSD radix sort of 32-bit keys with 32-bit values, 8 bits per pass.
// A block of block_keys keys is handled by one workgroup of one subgroup (the workgroup size is the
// device's subgroup size: 8 on lavapipe, 32 on NVIDIA), which walks the block in order, one row of
// consecutive keys per step (contiguous loads on a GPU, one SIMD row on a CPU driver). The keys of a
// row that share a digit find each other (match_digit); the last of them bumps the block's running
// digit offsets, so ranking needs no atomics, no per-subgroup histograms to clear and combine, and no
// rank storage between phases. No workgroup waits on another (no forward-progress assumption).
// Stable: rows in order, lanes in order, blocks in order.
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_ballot : require

// How a row's keys of one digit find each other: with RADIX_BITS ballots (GPUs, where a ballot is one
// instruction), or by comparing with each lane's digit in turn (CPU drivers, where a subgroup is one
// SIMD register and a ballot a serial loop over its lanes).
layout(constant_id = 0) const bool MATCH_BY_BROADCAST = false;
layout(local_size_x_id = 1) in;

const uint RADIX_BITS = 8;
const uint RADIX = 1u << RADIX_BITS;

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
    uint block_keys;
};

shared uint s_hist[RADIX];

uint digit_of(uint key) { return (key >> shift) & digit_mask; }

// Among the lanes holding a valid key with digit d: how many come before this lane, how many there are,
// and whether this lane is the last of them.
void match_digit(uint d, bool valid, out uint before, out uint total, out bool last) {
    if (MATCH_BY_BROADCAST) {
        uint mine = valid ? d : 0xffffffffu;  // never equal to a valid digit
        uint lane = gl_SubgroupInvocationID;
        before = 0;
        total = 0;
        last = valid;
        // bounded by the specialized workgroup size (the subgroup size the host read) so that the loop
        // unrolls and each broadcast reads a constant lane
        for (uint j = 0; j < gl_WorkGroupSize.x; j++) {
            bool same = j < gl_SubgroupSize && subgroupBroadcast(mine, j) == mine;
            total += same ? 1u : 0u;
            before += (same && j < lane) ? 1u : 0u;
            last = last && !(same && j > lane);
        }
    } else {
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
}
