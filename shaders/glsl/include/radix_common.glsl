// Reduce-then-scan LSD radix sort of 32-bit keys with 32-bit values, 4 bits per pass.
// A block of BLOCK_KEYS keys is handled by one workgroup; thread t owns the contiguous run
// [t * ITEMS, (t + 1) * ITEMS) of its block, so ranking a key needs only per-thread serial counts and
// one workgroup scan: no subgroup operations (any subgroup size works) and no inter-workgroup
// communication (no forward-progress assumptions). Stable: equal digits keep their input order.
const uint SORT_THREADS = 256;
const uint ITEMS = 16;
const uint BLOCK_KEYS = SORT_THREADS * ITEMS;
const uint RADIX = 16;

layout(push_constant) uniform Push {
    Uints keys_in;
    Uints values_in;
    Uints keys_out;
    Uints values_out;
    Uints histogram;   // RADIX * num_blocks, digit-major; scanned in place between the two passes
    uint n;
    uint shift;
    uint num_blocks;
};

uint digit_of(uint key) { return (key >> shift) & (RADIX - 1u); }

// Per-thread digit counts of its run, packed 8 bits per digit (a run holds at most 16 keys).
uvec4 count_run(uint block, uint t) {
    uvec4 packed = uvec4(0);
    uint base = block * BLOCK_KEYS + t * ITEMS;
    for (uint i = 0; i < ITEMS; i++) {
        uint idx = base + i;
        if (idx >= n) break;
        uint d = digit_of(keys_in.v[idx]);
        packed[d >> 2] += 1u << ((d & 3u) * 8u);
    }
    return packed;
}

uint unpack_count(uvec4 packed, uint d) { return (packed[d >> 2] >> ((d & 3u) * 8u)) & 0xffu; }
