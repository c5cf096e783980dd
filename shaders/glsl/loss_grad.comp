#version 460
// Gradient of loss = (1 - lambda) L1 + lambda (1 - SSIM) with respect to the render, both terms
// means over (masked) pixels and channels:
//   dL/dx = (1 - lambda) w sign(x - y) - lambda (G*A + 2 x G*B + y G*C)
// with A, B, C the weighted SSIM partials of ssim_terms.comp blurred by the same window G.
// Also writes the weighted |x - y| for the loss value.
#include "common.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push { Floats render; Floats target; Floats blurred_terms; Floats dl_dx; Floats l1_map; Floats mask; uint hw; uint channels; float inv_weight_sum; float lambda; uint has_mask; };

void main() {
    uint i = linear_group_id() * 256 + gl_LocalInvocationID.x;
    uint n = hw * channels;
    if (i >= n) return;
    float x = render.v[i], y = target.v[i];
    float w = (has_mask != 0 ? mask.v[i % hw] : 1.0) * inv_weight_sum;
    float dssim = blurred_terms.v[i] + 2.0 * x * blurred_terms.v[n + i] + y * blurred_terms.v[2 * n + i];
    float diff = x - y;
    dl_dx.v[i] = (1.0 - lambda) * w * sign(diff) - lambda * dssim;
    l1_map.v[i] = w * abs(diff);
}
