// Front-to-back compositing step shared by the color and feature blend passes, so both make exactly
// the same per-pixel decisions (conventions.md "Blending").

const float POWER_SKIP = -5.6;

// The alpha of one Gaussian at one pixel, or 0 where it is skipped: the part of blend_weight that
// does not depend on the transmittance, so that blend.comp's two states (AFTER_REMOVAL) share it.
float gaussian_alpha(vec2 pixel, vec2 xy, vec4 conic_opacity) {
    vec2 d = xy - pixel;
    float power = -0.5 * (conic_opacity.x * d.x * d.x + conic_opacity.z * d.y * d.y) - conic_opacity.y * d.x * d.y;
    if (power > 0.0) return 0.0;
    // opacity <= 1, so power < -5.6 means alpha <= exp(-5.6) = 0.0037 < 1/255: skipped anyway. Testing it
    // first avoids the exp for most pairs in a tile and the subnormal results of exp(power < -87),
    // which are very slow on CPUs (lavapipe) that do not flush them to zero.
    if (power < POWER_SKIP) return 0.0;
    float alpha = min(ALPHA_MAX, conic_opacity.w * exp(power));
    return alpha < ALPHA_MIN ? 0.0 : alpha;
}

// The blending weight alpha * T of a Gaussian of `alpha` (gaussian_alpha) and advances T, or 0 when
// it is skipped. Sets `finished` when T would fall below T_MIN (that Gaussian is not blended).
float take_weight(float alpha, inout float T, inout bool finished) {
    if (alpha == 0.0) return 0.0;
    float t_next = T * (1.0 - alpha);
    if (t_next < T_MIN) {
        finished = true;
        return 0.0;
    }
    float w = alpha * T;
    T = t_next;
    return w;
}

// Returns the blending weight alpha * T of one Gaussian at one pixel and advances T, or 0 when the
// Gaussian is skipped. Sets `finished` when T would fall below T_MIN (that Gaussian is not blended).
float blend_weight(vec2 pixel, vec2 xy, vec4 conic_opacity, inout float T, inout bool finished) {
    return take_weight(gaussian_alpha(pixel, xy, conic_opacity), T, finished);
}

// How far (in pixels, vertically) from its center a Gaussian can still pass blend_weight's tests: for
// a row at offset dy, the largest power over the row is -dy^2 (ac - b^2) / (2a) (conic (a, b, c)),
// and a pixel needs power >= max(POWER_SKIP, log(ALPHA_MIN / opacity)). Widened far beyond float
// rounding, so a pass that skips the rows outside it makes exactly the decisions it would have made.
float row_reach(vec4 conic_opacity) {
    float a = conic_opacity.x, b = conic_opacity.y, c = conic_opacity.z;
    float det = a * c - b * b;
    if (!(a > 0.0 && det > 0.0)) return 1e30;  // degenerate: skip nothing
    float threshold = max(POWER_SKIP, log(ALPHA_MIN / conic_opacity.w));
    if (threshold > 0.0) return -1.0;  // opacity below ALPHA_MIN: no pixel passes
    return sqrt(-2.0 * threshold * a / det) * 1.001 + 0.01;
}

// A workgroup is one 16x16 tile; tiles are numbered row-major.
uint tile_id() { return linear_group_id(); }
