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
    float wmx[RUN + 16], wmy[RUN + 16], wxx[RUN + 16], wyy[RUN + 16], wxy[RUN + 16];
    for (int j = 0; j < RUN / 4 + 4; j++) {
        int p = x0 - 8 + 4 * j;
        bool inside = p >= 0 && p < int(width);
        uint i = (row + uint(max(p, 0))) / 4;
        vec4 a = inside ? s4.v[i] : vec4(0.0), b = inside ? s4.v[q + i] : vec4(0.0);
        vec4 c = inside ? s4.v[2 * q + i] : vec4(0.0), d = inside ? s4.v[3 * q + i] : vec4(0.0);
        vec4 e4 = inside ? s4.v[4 * q + i] : vec4(0.0);
        for (int e = 0; e < 4; e++) {
            wmx[4 * j + e] = a[e];
            wmy[4 * j + e] = b[e];
            wxx[4 * j + e] = c[e];
            wyy[4 * j + e] = d[e];
            wxy[4 * j + e] = e4[e];
        }
    }
    for (int r4 = 0; r4 < RUN / 4; r4++) {
        if (x0 + 4 * r4 >= int(width)) continue;
        vec4 mx = vec4(0.0), my = vec4(0.0), exx = vec4(0.0), eyy = vec4(0.0), exy = vec4(0.0);
        for (int e = 0; e < 4; e++) {
            for (int k = 0; k < 11; k++) {
                int t = 4 * r4 + e + 3 + k;
                float w = W[k];
                mx[e] += w * wmx[t];
                my[e] += w * wmy[t];
                exx[e] += w * wxx[t];
                eyy[e] += w * wyy[t];
                exy[e] += w * wxy[t];
            }
        }
        vec4 s, d_mu, d_xx, d_xy;
        ssim_terms(mx, my, exx, eyy, exy, s, d_mu, d_xx, d_xy);
        uint o = (row + uint(x0)) / 4 + uint(r4);
        vec4 w = (has_mask != 0 ? k4.v[(mask_row + uint(x0)) / 4 + uint(r4)] : vec4(1.0)) * inv_weight_sum;
        t4.v[o] = w * d_mu;
        t4.v[q + o] = w * d_xx;
        t4.v[2 * q + o] = w * d_xy;
        m4.v[o] = w * s;
    }
}
