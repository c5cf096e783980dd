#version 460
// SSIM inputs per channel: x, y, x^2, y^2, xy (x the render, y the target), 5 planes per channel,
// laid out [quantity][channel][pixel] for the blur that follows.
#include "common.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push { Floats render; Floats target; Floats products; uint hw; uint channels; };

void main() {
    uint i = linear_group_id() * 256 + gl_LocalInvocationID.x;
    uint n = hw * channels;
    if (i >= n) return;
    float x = render.v[i], y = target.v[i];
    products.v[i] = x;
    products.v[n + i] = y;
    products.v[2 * n + i] = x * x;
    products.v[3 * n + i] = y * y;
    products.v[4 * n + i] = x * y;
}
