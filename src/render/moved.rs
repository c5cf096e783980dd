//! Device-memory bytes each forward pass must read and write at least (every input element read
//! once, every output written once), for the benches' roofline columns.

/// Means, scales, rotations, opacity and the active SH in; 2D mean, conic and opacity, color,
/// depth, sort key and index, tile rectangle and touched count out.
pub fn project(n: u32, sh_degree: u32) -> u64 {
    let sh = 12 * (sh_degree as u64 + 1).pow(2);
    n as u64 * ((12 + 12 + 16 + 4 + sh) + (8 + 16 + 12 + 4 + 4 + 4 + 16 + 4))
}

/// A stable radix sort of `count` (key, value) pairs by `bits` bits: per 8-bit pass the count
/// reads the keys, the scatter reads the pairs and writes them.
pub fn sort(count: u32, bits: u32) -> u64 {
    count as u64 * (4 + 8 + 8) * crate::sort::passes_for_bits(bits) as u64
}

/// Per Gaussian its index, touched count, offset, 2D mean, conic and tile rectangle in; per
/// intersection its tile and Gaussian out.
pub fn emit(n: u32, intersections: u32) -> u64 {
    n as u64 * (4 + 4 + 4 + 8 + 16 + 16) + intersections as u64 * 8
}

/// Per intersection its Gaussian index and that Gaussian's 2D mean, conic, opacity, color and
/// depth in; per pixel RGB, alpha, depth, expected depth, final transmittance and contributor
/// count out; the tile ranges in.
pub fn blend(intersections: u32, pixels: u32, tiles: u32) -> u64 {
    intersections as u64 * (4 + 8 + 16 + 16) + pixels as u64 * 32 + tiles as u64 * 8
}
