#version 460
// One step of a running mean over `n` floats: mean += weight * (value - mean). With weight 1/k at
// the k-th value, `mean` holds the mean of the k values so far (Polyak-Ruppert averaging of a
// trainer's iterates, train/trainer/iterate_average.rs); the first value (weight 1 on a zeroed mean)
// is taken exactly.
#include "common.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push { Floats value; Floats mean; uint n; float weight; };

void main() {
    uint i = linear_group_id() * 256 + gl_LocalInvocationID.x;
    if (i >= n) return;
    float m = mean.v[i];
    mean.v[i] = m + weight * (value.v[i] - m);
}
