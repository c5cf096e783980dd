#version 460
// Adam with a trust region, pass 1 of 3: updates the moments, writes each element's update
//   u = rate * (m / (1 - b1^t)) / (sqrt(v / (1 - b2^t)) + eps)
// to `update`, and each workgroup's sum of u^2 to partial[workgroup] (reduce_sum.comp totals them,
// apply_update.comp applies u scaled so that |u| <= radius for the whole tensor).
#include "common.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push {
    Floats grad; Floats m; Floats v; Floats update; Floats partial;
    uint n; float lr; float beta1; float beta2; float eps; float bias1; float bias2;
    uint period; uint head; float lr_tail;
};

shared float s_sum[256];

void main() {
    uint group = linear_group_id();
    uint i = group * 256 + gl_LocalInvocationID.x;
    float u2 = 0.0;
    if (i < n) {
        float g = grad.v[i];
        float mi = beta1 * m.v[i] + (1.0 - beta1) * g;
        float vi = beta2 * v.v[i] + (1.0 - beta2) * g * g;
        m.v[i] = mi;
        v.v[i] = vi;
        float rate = (i % period) < head ? lr : lr_tail;
        float u = rate * (mi / bias1) / (sqrt(vi / bias2) + eps);
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
    if (t == 0 && group * 256 < n) partial.v[group] = s_sum[0];
}
