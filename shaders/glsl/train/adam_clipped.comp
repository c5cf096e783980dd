#version 460
// Adam with a trust region per Gaussian: each invocation owns one Gaussian's row of `width`
// elements (3 for means and log-scales, 4 for rotations), computes the row's Adam updates u
// (include/adam_step.glsl) and applies p -= u * min(1, radius / |u|). Bounding each Gaussian's
// step, not the whole tensor's, keeps the bound independent of how many Gaussians there are: a
// whole-tensor norm of 0.01 over 20k Gaussians let each move about 1/20 of a plain Adam step.
#include "common.glsl"
#include "adam_step.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push { Floats param; Floats grad; Floats m; Floats v; AdamStep s; uint width; float radius; };

void main() {
    uint first = (linear_group_id() * 256 + gl_LocalInvocationID.x) * width;
    if (first >= s.n) return;
    float u[4];
    float u2 = 0.0;
    for (uint k = 0; k < width; k++) {
        uint i = first + k;
        u[k] = adam_update(grad, m, v, i, s, adam_rate(i, s));
        u2 += u[k] * u[k];
    }
    float scale = trust_scale(u2, radius);
    for (uint k = 0; k < width; k++) {
        param.v[first + k] -= scale * u[k];
    }
}
