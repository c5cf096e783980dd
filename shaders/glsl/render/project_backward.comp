#version 460
// Backward of project.comp, one thread per Gaussian: the parameter gradients of the view just
// blended (project_backward_grads.glsl), accumulated into the parameter gradients over views.
#ifndef NO_FLOAT_ATOMICS
#extension GL_EXT_shader_atomic_float : require
#endif
#include "project_backward_grads.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push { RenderParams p; BackwardParams b; };

void main() {
    uint g = linear_group_id() * 256 + gl_LocalInvocationID.x;
    if (g >= p.num_gaussians) return;
    ParamGrads d;
    if (!parameter_grads(p, b, g, d)) return;
    uint K = p.sh_coeffs;
    for (uint k = 0; k < SH_BANDS; k++) {
        uint base = (g * K + k) * 3;
        b.grad_sh.v[base] += d.basis[k] * d.color_raw.x;
        b.grad_sh.v[base + 1] += d.basis[k] * d.color_raw.y;
        b.grad_sh.v[base + 2] += d.basis[k] * d.color_raw.z;
    }
    for (int i = 0; i < 3; i++) {
        b.grad_means.v[3 * g + i] += d.mean[i];
        b.grad_log_scales.v[3 * g + i] += d.log_scale[i];
    }
    for (int i = 0; i < 4; i++) b.grad_quats.v[4 * g + i] += d.quat[i];
    b.grad_opacity_logits.v[g] += d.opacity_logit;
}
