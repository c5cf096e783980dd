#version 460
// SSIM pass 2 of 4 where rows are 16-byte aligned (after ssim_stats_y.comp): the statistics blurred
// along x (finishing the 2D window), then per pixel and channel the SSIM value and its weighted
// partials, as ssim_terms_y.comp derives them. All loads and stores are vec4s: windows
// [x0 - 8, x0 + RUN + 8), output r takes [r + 3 .. r + 13]; RUN is a multiple of 4 here.
#include "common.glsl"
#include "ssim_window.glsl"

RUNS_ALONG_X;
layout(push_constant) uniform Push { Floats stats; Floats terms; Floats ssim_map; Floats mask; uint width; uint height; uint channels; float inv_weight_sum; uint has_mask; uint pad; };

void main() {
    uvec3 id = gl_GlobalInvocationID;
    int x0 = int(id.x) * RUN;
    if (x0 >= int(width) || id.y >= height) return;
    uint hw = width * height, q = hw * channels / 4;
    uint row = id.z * hw + id.y * width, mask_row = id.y * width;
    Vec4s s4 = Vec4s(stats), t4 = Vec4s(terms), m4 = Vec4s(ssim_map), k4 = Vec4s(mask);
    TAPS4(mx) TAPS4(my) TAPS4(xx) TAPS4(yy) TAPS4(xy)
    // vec4 j of the run's inputs, which start at x0 - 8
#define LOAD(j, k) { int p_ = x0 - 8 + 4 * (j); bool in_ = p_ >= 0 && p_ < int(width); uint i_ = (row + uint(max(p_, 0))) / 4; \
        mx##k = in_ ? s4.v[i_] : vec4(0.0); my##k = in_ ? s4.v[q + i_] : vec4(0.0); xx##k = in_ ? s4.v[2 * q + i_] : vec4(0.0); \
        yy##k = in_ ? s4.v[3 * q + i_] : vec4(0.0); xy##k = in_ ? s4.v[4 * q + i_] : vec4(0.0); }
    PRIME4
    for (int r4 = 0; r4 < RUN / 4 && x0 + 4 * r4 < int(width); r4++) {
        SLIDE4(mx) SLIDE4(my) SLIDE4(xx) SLIDE4(yy) SLIDE4(xy)
        LOAD(r4 + 4, 4)
        vec4 s, d_mu, d_xx, d_xy;
        ssim_terms(WINDOW4(mx), WINDOW4(my), WINDOW4(xx), WINDOW4(yy), WINDOW4(xy), s, d_mu, d_xx, d_xy);
        uint o = (row + uint(x0)) / 4 + uint(r4);
        vec4 w = (has_mask != 0 ? k4.v[(mask_row + uint(x0)) / 4 + uint(r4)] : vec4(1.0)) * inv_weight_sum;
        t4.v[o] = w * d_mu;
        t4.v[q + o] = w * d_xx;
        t4.v[2 * q + o] = w * d_xy;
        m4.v[o] = w * s;
    }
}
