#version 460
// Sums `count` floats into total[0] with one workgroup (fixed order: deterministic).
#include "common.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push { Floats values; Floats total; uint count; };

shared float s_sum[256];

void main() {
    uint t = gl_LocalInvocationID.x;
    float acc = 0.0;
    for (uint i = t; i < count; i += 256) acc += values.v[i];
    s_sum[t] = acc;
    barrier();
    for (uint off = 128; off > 0; off >>= 1) {
        if (t < off) s_sum[t] += s_sum[t + off];
        barrier();
    }
    if (t == 0) total.v[0] = s_sum[0];
}
