// Front-to-back compositing step shared by the color and feature blend passes, so both make exactly
// the same per-pixel decisions (conventions.md "Blending").

const float POWER_SKIP = -5.6;

// Returns the blending weight alpha * T of one Gaussian at one pixel and advances T, or 0 when the
// Gaussian is skipped. Sets `finished` when T would fall below T_MIN (that Gaussian is not blended).
float blend_weight(vec2 pixel, vec2 xy, vec4 conic_opacity, inout float T, inout bool finished) {
    vec2 d = xy - pixel;
    float power = -0.5 * (conic_opacity.x * d.x * d.x + conic_opacity.z * d.y * d.y) - conic_opacity.y * d.x * d.y;
    if (power > 0.0) return 0.0;
    // opacity <= 1, so power < -5.6 means alpha <= exp(-5.6) = 0.0037 < 1/255: skipped anyway. Testing it
    // first avoids the exp for most pairs in a tile and the subnormal results of exp(power < -87),
    // which are very slow on CPUs (lavapipe) that do not flush them to zero.
    if (power < POWER_SKIP) return 0.0;
    float alpha = min(ALPHA_MAX, conic_opacity.w * exp(power));
    if (alpha < ALPHA_MIN) return 0.0;
    float t_next = T * (1.0 - alpha);
    if (t_next < T_MIN) {
        finished = true;
        return 0.0;
    }
    float w = alpha * T;
    T = t_next;
    return w;
}

// A workgroup is one 16x16 tile; tiles are numbered row-major.
uint tile_id() { return linear_group_id(); }
