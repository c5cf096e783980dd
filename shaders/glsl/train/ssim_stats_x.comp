#version 460
// SSIM pass 1 of 4: the five local statistics' inputs x, y, x^2, y^2, xy (x the render, y the
// target) blurred along x, per channel; laid out [quantity][channel][pixel]. The products are formed
// on the fly instead of being written and read back.
#include "common.glsl"
#include "ssim_window.glsl"

RUNS_ALONG_X;
layout(push_constant) uniform Push { Floats render; Floats target; Floats stats; uint width; uint height; uint channels; };

void main() {
    uvec3 id = gl_GlobalInvocationID;
    int x0 = int(id.x) * RUN;
    if (x0 >= int(width) || id.y >= height) return;
    uint hw = width * height, n = hw * channels;
    uint row = id.z * hw + id.y * width;
    TAPS(xs) TAPS(ys)  // x (render) and y (target) under the window
#define LOAD(p, k) { int p_ = (p); bool in_ = p_ >= 0 && p_ < int(width); uint i_ = row + uint(max(p_, 0)); \
        xs##k = in_ ? render.v[i_] : 0.0; ys##k = in_ ? target.v[i_] : 0.0; }
    PRIME(x0)
    for (int r = 0; r < RUN && x0 + r < int(width); r++) {
        SLIDE(xs) SLIDE(ys)
        LOAD(x0 + r + 5, 10)
        uint o = row + uint(x0 + r);
        stats.v[o] = WINDOW(xs);
        stats.v[n + o] = WINDOW(ys);
        stats.v[2 * n + o] = WINDOW_OF_PRODUCTS(xs, xs);
        stats.v[3 * n + o] = WINDOW_OF_PRODUCTS(ys, ys);
        stats.v[4 * n + o] = WINDOW_OF_PRODUCTS(xs, ys);
    }
}
