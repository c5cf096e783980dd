#version 460
// Radix sort, pass 3 of 3 (pass 2 is the exclusive scan of the histogram): each key goes to
// global offset of (digit, block) + number of equal digits in earlier runs of the block + its rank
// within its own run.
#include "common.glsl"
#include "radix_common.glsl"

layout(local_size_x = 256) in;
// s_counts[d * 256 + t]: run t's count of digit d, then its exclusive scan over the whole array.
shared uint s_counts[RADIX * SORT_THREADS];
shared uint s_sums[SORT_THREADS];
shared uint s_global[RADIX];
shared uint s_digit_base[RADIX];

void main() {
    uint block = linear_group_id();
    if (block >= num_blocks) return;
    uint t = gl_LocalInvocationID.x;
    uvec4 packed = count_run(block, t);
    for (uint d = 0; d < RADIX; d++) s_counts[d * SORT_THREADS + t] = unpack_count(packed, d);
    if (t < RADIX) s_global[t] = histogram.v[t * num_blocks + block];
    barrier();

    // exclusive scan of s_counts: each thread scans 16 consecutive entries serially ...
    uint run_sum = 0;
    for (uint i = 0; i < RADIX; i++) run_sum += s_counts[t * RADIX + i];
    s_sums[t] = run_sum;
    barrier();
    // ... then a Hillis-Steele scan over the 256 partial sums (inclusive) ...
    for (uint off = 1; off < SORT_THREADS; off <<= 1) {
        uint v = t >= off ? s_sums[t - off] : 0;
        barrier();
        s_sums[t] += v;
        barrier();
    }
    // ... and each thread writes its entries back as exclusive prefixes.
    uint prefix = s_sums[t] - run_sum;
    for (uint i = 0; i < RADIX; i++) {
        uint c = s_counts[t * RADIX + i];
        s_counts[t * RADIX + i] = prefix;
        prefix += c;
    }
    barrier();

    // s_counts[d * 256 + t] becomes run t's next output slot for digit d, relative to s_digit_base[d]
    if (t < RADIX) s_digit_base[t] = s_global[t] - s_counts[t * SORT_THREADS];
    barrier();
    uint first = block * BLOCK_KEYS + t * ITEMS;
    for (uint i = 0; i < ITEMS; i++) {
        uint idx = first + i;
        if (idx >= n) break;
        uint key = keys_in.v[idx];
        uint d = digit_of(key);
        uint slot = s_counts[d * SORT_THREADS + t];
        s_counts[d * SORT_THREADS + t] = slot + 1;  // only this thread touches column t
        uint dst = s_digit_base[d] + slot;
        keys_out.v[dst] = key;
        values_out.v[dst] = values_in.v[idx];
    }
}
