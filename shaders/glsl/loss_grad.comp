#version 460
// SSIM pass 4 of 4, and the loss gradient with respect to the render: the x-blurred SSIM terms A, B,
// C blurred along y (G* below), then, both terms means over (masked) pixels and channels,
//   dL/dx = (1 - lambda) w sign(x - y) - lambda (G*A + 2 x G*B + y G*C).
// Also writes the weighted |x - y| for the loss value.
#include "common.glsl"
#include "ssim_window.glsl"

layout(local_size_x = 64, local_size_y = 4) in;
layout(push_constant) uniform Push { Floats render; Floats target; Floats terms_x; Floats dl_dx; Floats l1_map; Floats mask; uint width; uint height; uint channels; float inv_weight_sum; float lambda; uint has_mask; };

void main() {
    uvec3 id = gl_GlobalInvocationID;
    if (id.x >= width || id.y >= height) return;
    uint hw = width * height, n = hw * channels;
    uint column = id.z * hw + id.x;
    ivec2 t = taps(int(id.y), height);
    float a = 0.0, b = 0.0, c = 0.0;
    for (int k = t.x; k <= t.y; k++) {
        uint i = column + uint(int(id.y) + k) * width;
        float w = W[k + 5];
        a += w * terms_x.v[i];
        b += w * terms_x.v[n + i];
        c += w * terms_x.v[2 * n + i];
    }
    uint pix = id.y * width + id.x, o = id.z * hw + pix;
    float x = render.v[o], y = target.v[o];
    float w = (has_mask != 0 ? mask.v[pix] : 1.0) * inv_weight_sum;
    float diff = x - y;
    dl_dx.v[o] = (1.0 - lambda) * w * sign(diff) - lambda * (a + 2.0 * x * b + y * c);
    l1_map.v[o] = w * abs(diff);
}
