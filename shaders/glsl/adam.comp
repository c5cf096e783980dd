#version 460
// Adam step for one parameter tensor: p -= u (include/adam_step.glsl). Frozen tensors are simply
// not dispatched.
#include "common.glsl"
#include "adam_step.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push { Floats param; Floats grad; Floats m; Floats v; AdamStep s; };

void main() {
    uint i = linear_group_id() * 256 + gl_LocalInvocationID.x;
    if (i >= s.n) return;
    param.v[i] -= adam_update(grad, m, v, i, s);
}
