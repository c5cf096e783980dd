#version 460
// SSIM pass 1 of 4 where rows are 16-byte aligned: the five local statistics' inputs x, y, x^2,
// y^2, xy (x the render, y the target) blurred along y, per channel; laid out
// [quantity][channel][pixel]. The passes along x (ssim_terms_x.comp, loss_grad_x.comp) then move
// vec4s; otherwise ssim_stats_x.comp and ssim_terms_y.comp take the two directions the other way.
#include "common.glsl"
#include "ssim_window.glsl"

RUNS_ALONG_Y;
layout(push_constant) uniform Push { Floats render; Floats target; Floats stats; uint width; uint height; uint channels; uint pad; };

void main() {
    uvec3 id = gl_GlobalInvocationID;
    int y0 = int(id.y) * RUN;
    if (id.x >= width || y0 >= int(height)) return;
    uint hw = width * height, n = hw * channels;
    uint column = id.z * hw + id.x;
    float wx[SPAN], wy[SPAN];
    for (int j = 0; j < SPAN; j++) {
        int p = y0 - 5 + j;
        bool inside = p >= 0 && p < int(height);
        uint i = column + uint(max(p, 0)) * width;
        wx[j] = inside ? render.v[i] : 0.0;
        wy[j] = inside ? target.v[i] : 0.0;
    }
    for (int r = 0; r < RUN && y0 + r < int(height); r++) {
        float sx = 0.0, sy = 0.0, sxx = 0.0, syy = 0.0, sxy = 0.0;
        for (int k = 0; k < 11; k++) {
            float x = wx[r + k], y = wy[r + k], w = W[k];
            sx += w * x;
            sy += w * y;
            sxx += w * (x * x);
            syy += w * (y * y);
            sxy += w * (x * y);
        }
        uint o = column + uint(y0 + r) * width;
        stats.v[o] = sx;
        stats.v[n + o] = sy;
        stats.v[2 * n + o] = sxx;
        stats.v[3 * n + o] = syy;
        stats.v[4 * n + o] = sxy;
    }
}
