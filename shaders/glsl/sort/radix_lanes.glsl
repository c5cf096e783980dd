// The lane-serial shape of the radix sort's count and scatter, for CPU drivers (llvmpipe runs a
// workgroup as one SIMD row of its lanes): each lane owns a contiguous slice of the block and keeps its
// own row of digit counters in shared memory, so counting and ranking are plain loads and stores with
// no atomics, ballots or barriers per key. Lane l's slice precedes lane l+1's, so the sort stays stable.
// On a GPU the slices' loads would not coalesce; GPUs keep the ballot shape (radix_count/scatter.comp).
// The count pass leaves each lane's offsets within the block in lane_offsets, [block][lane][digit]:
// the scatter starts from them instead of counting its slice again.

const uint MAX_LANES = 16;  // render::sort::LANE_SERIAL_MAX_LANES

shared uint s_lane[MAX_LANES * RADIX];  // s_lane[lane * RADIX + digit]

uint lane_row() { return gl_LocalInvocationID.x * RADIX; }

// A lane's slice (lane_slice in common.glsl) is BLOCK_KEYS / lanes keys, a multiple of 4, so it
// starts on a uvec4 (the keys' address is 16-byte aligned, checked by the host).
