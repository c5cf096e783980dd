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
    float wa[SPAN], wb[SPAN], wc[SPAN];
    for (int j = 0; j < SPAN; j++) {
        int p = y0 - 5 + j;
        wa[j] = 0.0;
        wb[j] = 0.0;
        wc[j] = 0.0;
        if (p >= 0 && p < int(height)) {
            uint i = column + uint(p) * width;
            wa[j] = terms_x.v[i];
            wb[j] = terms_x.v[n + i];
            wc[j] = terms_x.v[2 * n + i];
        }
    }
    for (int r = 0; r < RUN && y0 + r < int(height); r++) {
        float a = 0.0, b = 0.0, c = 0.0;
        for (int k = 0; k < 11; k++) {
            float w = W[k];
            a += w * wa[r + k];
            b += w * wb[r + k];
            c += w * wc[r + k];
        }
        uint pix = uint(y0 + r) * width + id.x, o = id.z * hw + pix;
        float x = render.v[o], y = target.v[o];
        float w = (has_mask != 0 ? mask.v[pix] : 1.0) * inv_weight_sum;
        float diff = x - y;
        dl_dx.v[o] = (1.0 - lambda) * w * sign(diff) - lambda * (a + 2.0 * x * b + y * c);
        l1_map.v[o] = w * abs(diff);
    }
}
