#version 460
// SSIM pass 3 of 4 where rows are 16-byte aligned (after ssim_terms_x.comp): the window along y of
// the three partials (planes `plane_stride` floats apart; gl_GlobalInvocationID.z = channel), so
// that pass 4 (loss_grad_x.comp) runs along x, where vec4s pay. One invocation takes all three
// partials of its column (9.1 against 10.4 ms at 512x512 for one plane per invocation).
#include "common.glsl"
#include "ssim_window.glsl"

RUNS_ALONG_Y;
layout(push_constant) uniform Push { Floats src; Floats dst; uint width; uint height; uint plane_stride; };

void main() {
    uvec3 id = gl_GlobalInvocationID;
    int y0 = int(id.y) * RUN;
    if (id.x >= width || y0 >= int(height)) return;
    uint column = id.z * width * height + id.x;
    float wa[SPAN], wb[SPAN], wc[SPAN];
    for (int j = 0; j < SPAN; j++) {
        int p = y0 - 5 + j;
        bool inside = p >= 0 && p < int(height);
        uint i = column + uint(max(p, 0)) * width;
        wa[j] = inside ? src.v[i] : 0.0;
        wb[j] = inside ? src.v[plane_stride + i] : 0.0;
        wc[j] = inside ? src.v[2 * plane_stride + i] : 0.0;
    }
    for (int r = 0; r < RUN && y0 + r < int(height); r++) {
        float a = 0.0, b = 0.0, c = 0.0;
        for (int k = 0; k < 11; k++) {
            a += W[k] * wa[r + k];
            b += W[k] * wb[r + k];
            c += W[k] * wc[r + k];
        }
        uint o = column + uint(y0 + r) * width;
        dst.v[o] = a;
        dst.v[plane_stride + o] = b;
        dst.v[2 * plane_stride + o] = c;
    }
}
