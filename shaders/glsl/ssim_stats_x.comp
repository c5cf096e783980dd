#version 460
// SSIM pass 1 of 4: the five local statistics' inputs x, y, x^2, y^2, xy (x the render, y the
// target) blurred along x, per channel; laid out [quantity][channel][pixel]. The products are formed
// on the fly instead of being written and read back.
#include "common.glsl"
#include "ssim_window.glsl"

RUNS_ALONG_X;
layout(push_constant) uniform Push { Floats render; Floats target; Floats stats; uint width; uint height; uint channels; uint aligned; };

void main() {
    uvec3 id = gl_GlobalInvocationID;
    int x0 = int(id.x) * RUN;
    if (x0 >= int(width) || id.y >= height) return;
    uint hw = width * height, n = hw * channels;
    uint row = id.z * hw + id.y * width;
    if (aligned != 0 && RUN % 4 == 0) {
        // the windows [x0 - 8, x0 + RUN + 8) as vec4s; output r takes [r + 3 .. r + 13]
        Vec4s r4s = Vec4s(render), t4s = Vec4s(target), o4 = Vec4s(stats);
        float wx[RUN + 16], wy[RUN + 16];
        for (int j = 0; j < RUN / 4 + 4; j++) {
            int p = x0 - 8 + 4 * j;
            bool inside = p >= 0 && p < int(width);
            vec4 a = inside ? r4s.v[(row + uint(p)) / 4] : vec4(0.0);
            vec4 b = inside ? t4s.v[(row + uint(p)) / 4] : vec4(0.0);
            for (int e = 0; e < 4; e++) {
                wx[4 * j + e] = a[e];
                wy[4 * j + e] = b[e];
            }
        }
        for (int r4 = 0; r4 < RUN / 4; r4++) {
            if (x0 + 4 * r4 >= int(width)) continue;
            vec4 sx = vec4(0.0), sy = vec4(0.0), sxx = vec4(0.0), syy = vec4(0.0), sxy = vec4(0.0);
            for (int e = 0; e < 4; e++) {
                for (int k = 0; k < 11; k++) {
                    float x = wx[4 * r4 + e + 3 + k], y = wy[4 * r4 + e + 3 + k], w = W[k];
                    sx[e] += w * x;
                    sy[e] += w * y;
                    sxx[e] += w * (x * x);
                    syy[e] += w * (y * y);
                    sxy[e] += w * (x * y);
                }
            }
            uint o = (row + uint(x0)) / 4 + uint(r4), q = n / 4;
            o4.v[o] = sx;
            o4.v[q + o] = sy;
            o4.v[2 * q + o] = sxx;
            o4.v[3 * q + o] = syy;
            o4.v[4 * q + o] = sxy;
        }
        return;
    }
    float wx[SPAN], wy[SPAN];
    for (int j = 0; j < SPAN; j++) {
        int p = x0 - 5 + j;
        wx[j] = 0.0;
        wy[j] = 0.0;
        if (p >= 0 && p < int(width)) {
            wx[j] = render.v[row + uint(p)];
            wy[j] = target.v[row + uint(p)];
        }
    }
    for (int r = 0; r < RUN && x0 + r < int(width); r++) {
        float sx = 0.0, sy = 0.0, sxx = 0.0, syy = 0.0, sxy = 0.0;
        for (int k = 0; k < 11; k++) {
            float x = wx[r + k], y = wy[r + k], w = W[k];
            sx += w * x;
            sy += w * y;
            sxx += w * (x * x);
            syy += w * (y * y);
            sxy += w * (x * y);
        }
        uint o = row + uint(x0 + r);
        stats.v[o] = sx;
        stats.v[n + o] = sy;
        stats.v[2 * n + o] = sxx;
        stats.v[3 * n + o] = syy;
        stats.v[4 * n + o] = sxy;
    }
}
