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
