#version 460
// Per pixel and channel, from the blurred statistics: the SSIM value s and its partial derivatives
// with respect to the render's local mean mu_x, E[x^2] and E[xy]:
//   s = (2 mu_x mu_y + C1)(2 s_xy + C2) / ((mu_x^2 + mu_y^2 + C1)(s_x^2 + s_y^2 + C2)) = N1 N2 / (D1 D2)
//   ds/dmu_x = 2 mu_y (N2 - N1) / D - 2 mu_x s (D2 - D1) / D,  ds/dE[x^2] = -s / D2,  ds/dE[xy] = 2 N1 / D.
// Each is multiplied by the pixel's weight (mask / sum of mask, or 1 / pixels), so blurring them and
// combining gives dSSIM/dx (loss_grad.comp). Writes the weighted SSIM map for the loss value.
#include "common.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push { Floats stats; Floats terms; Floats ssim_map; Floats mask; uint hw; uint channels; float inv_weight_sum; uint has_mask; };

const float C1 = 0.0001;  // 0.01^2
const float C2 = 0.0009;  // 0.03^2

void main() {
    uint i = linear_group_id() * 256 + gl_LocalInvocationID.x;
    uint n = hw * channels;
    if (i >= n) return;
    float mx = stats.v[i], my = stats.v[n + i];
    float sxx = stats.v[2 * n + i] - mx * mx;
    float syy = stats.v[3 * n + i] - my * my;
    float sxy = stats.v[4 * n + i] - mx * my;
    float n1 = 2.0 * mx * my + C1, n2 = 2.0 * sxy + C2;
    float d1 = mx * mx + my * my + C1, d2 = sxx + syy + C2;
    float d = d1 * d2;
    float s = n1 * n2 / d;
    float w = (has_mask != 0 ? mask.v[i % hw] : 1.0) * inv_weight_sum;
    terms.v[i] = w * (2.0 * my * (n2 - n1) / d - 2.0 * mx * s * (d2 - d1) / d);
    terms.v[n + i] = w * (-s / d2);
    terms.v[2 * n + i] = w * (2.0 * n1 / d);
    ssim_map.v[i] = w * s;
}
