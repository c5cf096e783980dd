#version 460
// SSIM pass 2 of 4: the statistics blurred along y (finishing the 2D window), then per pixel and
// channel the SSIM value s and its partial derivatives with respect to the render's local mean
// mu_x, E[x^2] and E[xy]:
//   s = (2 mu_x mu_y + C1)(2 s_xy + C2) / ((mu_x^2 + mu_y^2 + C1)(s_x^2 + s_y^2 + C2)) = N1 N2 / (D1 D2)
//   ds/dmu_x = 2 mu_y (N2 - N1) / D - 2 mu_x s (D2 - D1) / D,  ds/dE[x^2] = -s / D2,  ds/dE[xy] = 2 N1 / D.
// Each is multiplied by the pixel's weight (mask / sum of mask, or 1 / pixels), so blurring them and
// combining gives dSSIM/dx (passes 3 and 4). Writes the weighted SSIM map for the loss value.
#include "common.glsl"
#include "ssim_window.glsl"

RUNS_ALONG_Y;
layout(push_constant) uniform Push { Floats stats; Floats terms; Floats ssim_map; Floats mask; uint width; uint height; uint channels; float inv_weight_sum; uint has_mask; };


void main() {
    uvec3 id = gl_GlobalInvocationID;
    int y0 = int(id.y) * RUN;
    if (id.x >= width || y0 >= int(height)) return;
    uint hw = width * height, n = hw * channels;
    uint column = id.z * hw + id.x;
    // windows of the five x-blurred statistics down this column
    TAPS(mx) TAPS(my) TAPS(xx) TAPS(yy) TAPS(xy)
#define LOAD(p, k) { int p_ = (p); bool in_ = p_ >= 0 && p_ < int(height); uint i_ = column + uint(max(p_, 0)) * width; \
        mx##k = in_ ? stats.v[i_] : 0.0; my##k = in_ ? stats.v[n + i_] : 0.0; xx##k = in_ ? stats.v[2 * n + i_] : 0.0; \
        yy##k = in_ ? stats.v[3 * n + i_] : 0.0; xy##k = in_ ? stats.v[4 * n + i_] : 0.0; }
    PRIME(y0)
    for (int r = 0; r < RUN && y0 + r < int(height); r++) {
        SLIDE(mx) SLIDE(my) SLIDE(xx) SLIDE(yy) SLIDE(xy)
        LOAD(y0 + r + 5, 10)
        float s, d_mu, d_xx, d_xy;
        ssim_terms(WINDOW(mx), WINDOW(my), WINDOW(xx), WINDOW(yy), WINDOW(xy), s, d_mu, d_xx, d_xy);
        uint pix = uint(y0 + r) * width + id.x, o = id.z * hw + pix;
        float w = (has_mask != 0 ? mask.v[pix] : 1.0) * inv_weight_sum;
        terms.v[o] = w * d_mu;
        terms.v[n + o] = w * d_xx;
        terms.v[2 * n + o] = w * d_xy;
        ssim_map.v[o] = w * s;
    }
}
