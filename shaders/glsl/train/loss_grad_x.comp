#version 460
// SSIM pass 4 of 4 where rows are 16-byte aligned (after blur_y.comp), and the loss gradient with
// respect to the render: the y-blurred SSIM terms A, B, C blurred along x (G* below), then, both
// terms means over (masked) pixels and channels,
//   dL/dx = (1 - lambda) w sign(x - y) - lambda (G*A + 2 x G*B + y G*C).
// Also writes the weighted |x - y| for the loss value. All loads and stores are vec4s: windows
// [x0 - 8, x0 + RUN + 8), output r takes [r + 3 .. r + 13]; RUN is a multiple of 4 here.
#include "common.glsl"
#include "ssim_window.glsl"

RUNS_ALONG_X;
layout(push_constant) uniform Push { Floats render; Floats target; Floats terms_y; Floats dl_dx; Floats l1_map; Floats mask; uint width; uint height; uint channels; float inv_weight_sum; float lambda; uint has_mask; };

void main() {
    uvec3 id = gl_GlobalInvocationID;
    int x0 = int(id.x) * RUN;
    if (x0 >= int(width) || id.y >= height) return;
    uint hw = width * height, n = hw * channels, q = n / 4;
    uint row = id.z * hw + id.y * width, mask_row = id.y * width;
    Vec4s t4 = Vec4s(terms_y), r4 = Vec4s(render), y4 = Vec4s(target), g4 = Vec4s(dl_dx), l4 = Vec4s(l1_map);
    Vec4s k4 = Vec4s(mask);
    TAPS4(a) TAPS4(b) TAPS4(c)
    // vec4 j of the run's inputs, which start at x0 - 8
#define LOAD(j, k) { int p_ = x0 - 8 + 4 * (j); bool in_ = p_ >= 0 && p_ < int(width); uint i_ = (row + uint(max(p_, 0))) / 4; \
        a##k = in_ ? t4.v[i_] : vec4(0.0); b##k = in_ ? t4.v[q + i_] : vec4(0.0); c##k = in_ ? t4.v[2 * q + i_] : vec4(0.0); }
    PRIME4
    for (int r4i = 0; r4i < RUN / 4 && x0 + 4 * r4i < int(width); r4i++) {
        SLIDE4(a) SLIDE4(b) SLIDE4(c)
        LOAD(r4i + 4, 4)
        uint o = (row + uint(x0)) / 4 + uint(r4i);
        vec4 x = r4.v[o], y = y4.v[o];
        vec4 w = (has_mask != 0 ? k4.v[(mask_row + uint(x0)) / 4 + uint(r4i)] : vec4(1.0)) * inv_weight_sum;
        vec4 diff = x - y;
        g4.v[o] = (1.0 - lambda) * w * sign(diff) - lambda * (WINDOW4(a) + 2.0 * x * WINDOW4(b) + y * WINDOW4(c));
        l4.v[o] = w * abs(diff);
    }
}
