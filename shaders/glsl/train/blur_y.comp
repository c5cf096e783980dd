#version 460
// SSIM pass 3 of 4 where rows are 16-byte aligned (after ssim_terms_x.comp): the window along y of
// the three partials (planes `plane_stride` floats apart; gl_GlobalInvocationID.z = channel), so
// that pass 4 (loss_grad_x.comp) runs along x, where vec4s pay. One invocation takes all three
// partials of its column (9.1 against 10.4 ms at 512x512 for one plane per invocation), down a run
// whose 11-tap windows slide through variables (7.6-7.9 against 9.3 ms for windows in arrays
// indexed by the run's counter).
#include "common.glsl"
#include "ssim_window.glsl"

RUNS_ALONG_Y;
layout(push_constant) uniform Push { Floats src; Floats dst; uint width; uint height; uint plane_stride; };

void main() {
    uvec3 id = gl_GlobalInvocationID;
    int y0 = int(id.y) * RUN;
    if (id.x >= width || y0 >= int(height)) return;
    uint column = id.z * width * height + id.x;
    TAPS(a) TAPS(b) TAPS(c)
#define LOAD(p, k) { int p_ = (p); bool in_ = p_ >= 0 && p_ < int(height); uint i_ = column + uint(max(p_, 0)) * width; \
        a##k = in_ ? src.v[i_] : 0.0; b##k = in_ ? src.v[plane_stride + i_] : 0.0; c##k = in_ ? src.v[2 * plane_stride + i_] : 0.0; }
    PRIME(y0)
    for (int r = 0; r < RUN && y0 + r < int(height); r++) {
        SLIDE(a) SLIDE(b) SLIDE(c)
        LOAD(y0 + r + 5, 10)
        uint o = column + uint(y0 + r) * width;
        dst.v[o] = WINDOW(a);
        dst.v[plane_stride + o] = WINDOW(b);
        dst.v[2 * plane_stride + o] = WINDOW(c);
    }
}
