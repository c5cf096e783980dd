#version 460
// Adam with a trust region, pass 3 of 3: p -= u * min(1, radius / |u|), |u| the norm of the whole
// tensor's update (sqrt of total[0]).
#include "common.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push { Floats param; Floats update; Floats total; uint n; float radius; };

void main() {
    uint i = linear_group_id() * 256 + gl_LocalInvocationID.x;
    if (i >= n) return;
    float norm = sqrt(total.v[0]);
    float s = norm > radius ? radius / norm : 1.0;
    param.v[i] -= s * update.v[i];
}
