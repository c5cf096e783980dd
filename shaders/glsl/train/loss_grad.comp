#version 460
// SSIM pass 4 of 4, and the loss gradient with respect to the render: the x-blurred SSIM terms A, B,
// C blurred along y (G* below), then, both terms means over (masked) pixels and channels,
//   dL/dx = (1 - lambda) w sign(x - y) - lambda (G*A + 2 x G*B + y G*C).
// Also writes the weighted |x - y| for the loss value.
#include "common.glsl"
#include "ssim_window.glsl"

RUNS_ALONG_Y;
layout(push_constant) uniform Push { Floats render; Floats target; Floats terms_x; Floats dl_dx; Floats l1_map; Floats mask; uint width; uint height; uint channels; float inv_weight_sum; float lambda; uint has_mask; };

void main() {
    uvec3 id = gl_GlobalInvocationID;
    int y0 = int(id.y) * RUN;
    if (id.x >= width || y0 >= int(height)) return;
    uint hw = width * height, n = hw * channels;
    uint column = id.z * hw + id.x;
    TAPS(a) TAPS(b) TAPS(c)
#define LOAD(p, k) { int p_ = (p); bool in_ = p_ >= 0 && p_ < int(height); uint i_ = column + uint(max(p_, 0)) * width; \
        a##k = in_ ? terms_x.v[i_] : 0.0; b##k = in_ ? terms_x.v[n + i_] : 0.0; c##k = in_ ? terms_x.v[2 * n + i_] : 0.0; }
    PRIME(y0)
    for (int r = 0; r < RUN && y0 + r < int(height); r++) {
        SLIDE(a) SLIDE(b) SLIDE(c)
        LOAD(y0 + r + 5, 10)
        uint pix = uint(y0 + r) * width + id.x, o = id.z * hw + pix;
        float x = render.v[o], y = target.v[o];
        float w = (has_mask != 0 ? mask.v[pix] : 1.0) * inv_weight_sum;
        float diff = x - y;
        dl_dx.v[o] = (1.0 - lambda) * w * sign(diff) - lambda * (WINDOW(a) + 2.0 * x * WINDOW(b) + y * WINDOW(c));
        l1_map.v[o] = w * abs(diff);
    }
}
