// SSIM's window: the 11-tap Gaussian (sigma 1.5), normalized, applied separably with zero padding
// (as in the INRIA reference). The loss passes run on a 2D grid, one invocation per pixel of one
// plane (gl_GlobalInvocationID.xy = pixel, .z = channel or plane), so no pass divides an index.

// exp(-k^2 / (2 * 1.5^2)) for k = -5..5, normalized to sum 1
const float W[11] = float[11](1.028380084e-03, 7.598758135e-03, 3.600077213e-02, 1.093606895e-01, 2.130055377e-01, 2.660117249e-01, 2.130055377e-01, 1.093606895e-01, 3.600077213e-02, 7.598758135e-03, 1.028380084e-03);

// The taps k = -5..5 that fall inside [0, size) around position `at`: [lo, hi].
ivec2 taps(int at, uint size) {
    return ivec2(max(-5, -at), min(5, int(size) - 1 - at));
}
