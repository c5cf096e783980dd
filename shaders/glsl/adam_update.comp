#version 460
// Adam with a trust region, pass 1 of 3: updates the moments, writes each element's update u
// (include/adam_step.glsl) to `update`, and each workgroup's sum of u^2 to partial[workgroup] (reduce_sum.comp totals them,
// apply_update.comp applies u scaled so that |u| <= radius for the whole tensor).
#include "common.glsl"
#include "adam_step.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push { Floats grad; Floats m; Floats v; Floats update; Floats partial; AdamStep s; };

shared float s_sum[256];

void main() {
    uint group = linear_group_id();
    uint i = group * 256 + gl_LocalInvocationID.x;
    float u2 = 0.0;
    if (i < s.n) {
        float u = adam_update(grad, m, v, i, s, adam_rate(i, s));
        update.v[i] = u;
        u2 = u * u;
    }
    uint t = gl_LocalInvocationID.x;
    s_sum[t] = u2;
    barrier();
    for (uint off = 128; off > 0; off >>= 1) {
        if (t < off) s_sum[t] += s_sum[t + off];
        barrier();
    }
    if (t == 0 && group * 256 < s.n) partial.v[group] = s_sum[0];
}
