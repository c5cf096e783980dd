#version 460
// Per-view exposure update (train/exposure.rs): the 12 parameters of view v summed from
// exposure_backward.comp's partials (a fixed order), plus the gradient of the regularizer
// reg * |params - identity|^2 that keeps each correction near identity, then one Adam step with
// the view's own step count (a view is only updated when it is drawn). The gain-and-bias model
// learns the diagonal and the bias only.
#include "common.glsl"
#include "adam_step.glsl"

layout(local_size_x = 16) in;
layout(push_constant) uniform Push {
    Floats params;
    Floats partials;
    Floats m;
    Floats v;
    AdamStep s;
    uint view;
    uint groups;
    float reg;
    uint full_matrix;  // 0: per-channel gain and bias only (the matrix's off-diagonal stays 0)
};

void main() {
    uint j = gl_LocalInvocationID.x;
    if (j >= 12) return;
    bool off_diagonal = j < 9 && j % 4 != 0;
    if (off_diagonal && full_matrix == 0) return;
    float g = 0.0;
    for (uint k = 0; k < groups; k++) g += partials.v[12 * k + j];
    uint i = 12 * view + j;
    float identity = (j == 0 || j == 4 || j == 8) ? 1.0 : 0.0;
    g += 2.0 * reg * (params.v[i] - identity);
    params.v[i] -= adam_update_value(g, m, v, i, s, s.lr);
}
