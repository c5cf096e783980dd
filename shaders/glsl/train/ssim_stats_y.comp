#version 460
// SSIM pass 1 of 4 where rows are 16-byte aligned: the five local statistics' inputs x, y, x^2,
// y^2, xy (x the render, y the target) blurred along y, per channel; laid out
// [quantity][channel][pixel]. The passes along x (ssim_terms_x.comp, loss_grad_x.comp) then move
// vec4s; otherwise ssim_stats_x.comp and ssim_terms_y.comp take the two directions the other way.
#include "common.glsl"
#include "ssim_window.glsl"

RUNS_ALONG_Y;
layout(push_constant) uniform Push { Floats render; Floats target; Floats stats; uint width; uint height; uint channels; uint pad; };

void main() {
    uvec3 id = gl_GlobalInvocationID;
    int y0 = int(id.y) * RUN;
    if (id.x >= width || y0 >= int(height)) return;
    uint hw = width * height, n = hw * channels;
    uint column = id.z * hw + id.x;
    TAPS(xs) TAPS(ys)  // x (render) and y (target) under the window
#define LOAD(p, k) { int p_ = (p); bool in_ = p_ >= 0 && p_ < int(height); uint i_ = column + uint(max(p_, 0)) * width; \
        xs##k = in_ ? render.v[i_] : 0.0; ys##k = in_ ? target.v[i_] : 0.0; }
    PRIME(y0)
    for (int r = 0; r < RUN && y0 + r < int(height); r++) {
        SLIDE(xs) SLIDE(ys)
        LOAD(y0 + r + 5, 10)
        uint o = column + uint(y0 + r) * width;
        stats.v[o] = WINDOW(xs);
        stats.v[n + o] = WINDOW(ys);
        stats.v[2 * n + o] = WINDOW_OF_PRODUCTS(xs, xs);
        stats.v[3 * n + o] = WINDOW_OF_PRODUCTS(ys, ys);
        stats.v[4 * n + o] = WINDOW_OF_PRODUCTS(xs, ys);
    }
}
