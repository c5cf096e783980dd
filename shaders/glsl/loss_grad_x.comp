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
    float wa[RUN + 16], wb[RUN + 16], wc[RUN + 16];
    for (int j = 0; j < RUN / 4 + 4; j++) {
        int p = x0 - 8 + 4 * j;
        bool inside = p >= 0 && p < int(width);
        uint i = (row + uint(max(p, 0))) / 4;
        vec4 a = inside ? t4.v[i] : vec4(0.0), b = inside ? t4.v[q + i] : vec4(0.0), c = inside ? t4.v[2 * q + i] : vec4(0.0);
        for (int e = 0; e < 4; e++) {
            wa[4 * j + e] = a[e];
            wb[4 * j + e] = b[e];
            wc[4 * j + e] = c[e];
        }
    }
    for (int r4i = 0; r4i < RUN / 4; r4i++) {
        if (x0 + 4 * r4i >= int(width)) continue;
        vec4 a = vec4(0.0), b = vec4(0.0), c = vec4(0.0);
        for (int e = 0; e < 4; e++) {
            for (int k = 0; k < 11; k++) {
                float w = W[k];
                a[e] += w * wa[4 * r4i + e + 3 + k];
                b[e] += w * wb[4 * r4i + e + 3 + k];
                c[e] += w * wc[4 * r4i + e + 3 + k];
            }
        }
        uint o = (row + uint(x0)) / 4 + uint(r4i);
        vec4 x = r4.v[o], y = y4.v[o];
        vec4 w = (has_mask != 0 ? k4.v[(mask_row + uint(x0)) / 4 + uint(r4i)] : vec4(1.0)) * inv_weight_sum;
        vec4 diff = x - y;
        g4.v[o] = (1.0 - lambda) * w * sign(diff) - lambda * (a + 2.0 * x * b + y * c);
        l4.v[o] = w * abs(diff);
    }
}

