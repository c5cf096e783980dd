// SSIM's window: the 11-tap Gaussian (sigma 1.5), normalized, applied separably with zero padding
// (as in the INRIA reference). The loss passes run on a 2D grid (gl_GlobalInvocationID.z = channel or
// plane), so no pass divides an index. Each invocation of a blurring pass owns a run of RUN
// consecutive outputs along the blurred axis and reads the RUN + 10 inputs under them once, each
// into a window that slides through variables (TAPS/SLIDE/WINDOW below), instead of 11 gathered
// loads per output.

// exp(-k^2 / (2 * 1.5^2)) for k = -5..5, normalized to sum 1
const float W[11] = float[11](1.028380084e-03, 7.598758135e-03, 3.600077213e-02, 1.093606895e-01, 2.130055377e-01, 2.660117249e-01, 2.130055377e-01, 1.093606895e-01, 3.600077213e-02, 7.598758135e-03, 1.028380084e-03);

// An 11-tap window sliding down a run in variables v0..v10 (SLIDE drops v0 and frees v10 for the
// next input; WINDOW is the weighted sum). Arrays of the run's RUN + 10 inputs, indexed by the run's
// loop counter, cost more on llvmpipe than moving ten registers: at 512x512 the statistics along y
// took 6.3 ms with arrays and 4.6 ms sliding, the partials' blur along y 9.3 and 7.7 ms, the terms
// along x 9.2 and 8.3 ms (whole loss 31.7 -> 27.1 ms). On a GPU the window stays in 11 registers
// whatever the run's length.
#define TAPS(v) float v##0, v##1, v##2, v##3, v##4, v##5, v##6, v##7, v##8, v##9, v##10;
#define SLIDE(v) v##0 = v##1; v##1 = v##2; v##2 = v##3; v##3 = v##4; v##4 = v##5; v##5 = v##6; \
    v##6 = v##7; v##7 = v##8; v##8 = v##9; v##9 = v##10;
#define WINDOW(v) (W[0] * v##0 + W[1] * v##1 + W[2] * v##2 + W[3] * v##3 + W[4] * v##4 + W[5] * v##5 + \
    W[6] * v##6 + W[7] * v##7 + W[8] * v##8 + W[9] * v##9 + W[10] * v##10)
// The window before a run's first output at `origin`: inputs origin - 5 .. origin + 4 into taps
// 1..10, through the shader's own LOAD(position, tap); each step then slides and loads tap 10.
#define PRIME(origin) LOAD((origin) - 5, 1) LOAD((origin) - 4, 2) LOAD((origin) - 3, 3) \
    LOAD((origin) - 2, 4) LOAD((origin) - 1, 5) LOAD((origin), 6) LOAD((origin) + 1, 7) \
    LOAD((origin) + 2, 8) LOAD((origin) + 3, 9) LOAD((origin) + 4, 10)
#define WINDOW_OF_PRODUCTS(v, u) (W[0] * (v##0 * u##0) + W[1] * (v##1 * u##1) + W[2] * (v##2 * u##2) + \
    W[3] * (v##3 * u##3) + W[4] * (v##4 * u##4) + W[5] * (v##5 * u##5) + W[6] * (v##6 * u##6) + \
    W[7] * (v##7 * u##7) + W[8] * (v##8 * u##8) + W[9] * (v##9 * u##9) + W[10] * (v##10 * u##10))

// The same along x with vec4s: four consecutive outputs, whose inputs f[3..16] (relative to the
// first vec4) lie in the five consecutive vec4s v0..v4; output e takes f[e + 3 + k], k = 0..10.
vec4 window4(vec4 v0, vec4 v1, vec4 v2, vec4 v3, vec4 v4) {
    return W[0] * vec4(v0.w, v1.xyz) + W[1] * v1 + W[2] * vec4(v1.yzw, v2.x) + W[3] * vec4(v1.zw, v2.xy) +
           W[4] * vec4(v1.w, v2.xyz) + W[5] * v2 + W[6] * vec4(v2.yzw, v3.x) + W[7] * vec4(v2.zw, v3.xy) +
           W[8] * vec4(v2.w, v3.xyz) + W[9] * v3 + W[10] * vec4(v3.yzw, v4.x);
}
#define TAPS4(v) vec4 v##0, v##1, v##2, v##3, v##4;
#define SLIDE4(v) v##0 = v##1; v##1 = v##2; v##2 = v##3; v##3 = v##4;
#define WINDOW4(v) window4(v##0, v##1, v##2, v##3, v##4)
// The first four vec4s of a run's inputs into v1..v4, through the shader's LOAD(vec4 index, slot).
#define PRIME4 LOAD(0, 1) LOAD(1, 2) LOAD(2, 3) LOAD(3, 4)

// RUN is chosen per device (train/loss.rs): 64 on CPU devices, where loads are per-lane gathers and
// each run's 10 extra inputs are overhead; 8 on GPUs, which want many invocations in flight.
layout(constant_id = 0) const int RUN = 8;

const float C1 = 0.0001;  // 0.01^2
const float C2 = 0.0009;  // 0.03^2

// From the windowed means mu_x, mu_y and second moments E[x^2], E[y^2], E[xy]: the SSIM value s
// and its partials with respect to mu_x, E[x^2] and E[xy] (derived in ssim_terms_y.comp), for one
// pixel (float) or four (vec4; ssim_terms_x.comp).
#define SSIM_TERMS(T) \
    void ssim_terms(T mx, T my, T exx, T eyy, T exy, out T s, out T d_mu, out T d_xx, out T d_xy) { \
        T sxx = exx - mx * mx, syy = eyy - my * my, sxy = exy - mx * my; \
        T n1 = 2.0 * mx * my + C1, n2 = 2.0 * sxy + C2; \
        T d1 = mx * mx + my * my + C1, d2 = sxx + syy + C2; \
        T d = d1 * d2; \
        s = n1 * n2 / d; \
        d_mu = 2.0 * my * (n2 - n1) / d - 2.0 * mx * s * (d2 - d1) / d; \
        d_xx = -s / d2; \
        d_xy = 2.0 * n1 / d; \
    }
SSIM_TERMS(float)
SSIM_TERMS(vec4)

// Workgroup shapes: runs along x are 8 runs (64 pixels) wide and 8 rows high; runs along y are 64
// columns wide, so each row of a run is one contiguous 64-float read.
#define RUNS_ALONG_X layout(local_size_x = 8, local_size_y = 8) in
#define RUNS_ALONG_Y layout(local_size_x = 64, local_size_y = 1) in

// Where the rows are 16-byte aligned (width a multiple of 4, every buffer 16-byte aligned:
// `PhotometricLoss::vectorized`), the passes along x move vec4s: on lavapipe a vec4 per lane costs
// about what a float did (the partials' blur along x went from 13.7 to 7.5 ms at 512x512). Along
// y the lanes already read consecutive floats, and vec4s of 4 columns measured 1.5x slower there.
// So there every pass runs along the other axis (ssim_stats_y, ssim_terms_x, blur_y,
// loss_grad_x), the two that read the most planes along x. Runs are multiples of 4 outputs in the
// vec4 passes (Vec4s in common.glsl).
