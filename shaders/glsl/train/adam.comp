#version 460
// Adam step for one parameter tensor: p -= u (include/adam_step.glsl). Frozen tensors are simply
// not dispatched. A workgroup updates a block of PER x 256 elements in PER steps, its invocations
// on consecutive elements in each step: a GPU sees coalesced accesses, and lavapipe, which pays
// microseconds per workgroup, runs a quarter as many (the compute copy doubles its throughput the
// same way, gpu/bandwidth.rs).
#include "common.glsl"
#include "adam_step.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push { Floats param; Floats grad; Floats m; Floats v; AdamStep s; };

const uint PER = 4;  // train::adam::ELEMENTS_PER_GROUP = 256 * PER

void main() {
    uint first = linear_group_id() * (256 * PER) + gl_LocalInvocationID.x;
    // i % period, stepped instead of divided for every element (256 % period < period)
    uint r = first % s.period;
    uint step = 256 % s.period;
    for (uint k = 0; k < PER; k++) {
        uint i = first + k * 256;
        if (i >= s.n) return;
        param.v[i] -= adam_update(grad, m, v, i, s, r < s.head ? s.lr : s.lr_tail);
        r += step;
        if (r >= s.period) r -= s.period;
    }
}
