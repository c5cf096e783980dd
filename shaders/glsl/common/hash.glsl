// PCG hash (Jarzynski & Olano 2020): a counter-based random number per (seed, index), so passes that
// need randomness stay deterministic and need no RNG state.
uint pcg_hash(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}
