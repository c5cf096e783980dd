#version 460
// Projection backward fused with Adam, one thread per Gaussian: the parameter gradients of the
// view just blended (project_backward_grads.glsl) go straight into the Adam step of every element
// of the Gaussian. A training step of one view thereby never writes, zeroes or reads back the
// parameter gradient tensors: at 1M SH-3 Gaussians that is 1.0 GB of the 2.5 GB the two passes
// moved apart (train/fused.rs). Same arithmetic as project_backward.comp + mcmc_regularize.comp +
// adam.comp on zeroed gradients; a Gaussian the view culled gets a zero gradient and still steps.
#ifndef NO_FLOAT_ATOMICS
#extension GL_EXT_shader_atomic_float : require
#endif
#include "project_backward_grads.glsl"
#include "adam_step.glsl"

// Mirrors `train::fused::FusedAdamParams` (std430, pointers first). The parameters are written
// through these pointers; RenderParams reads the same tensors (read-only) for the chain rule.
layout(buffer_reference, std430, buffer_reference_align = 8) buffer FusedAdam {
    Floats means; Floats log_scales; Floats quats; Floats opacity_logits; Floats sh;
    Floats m_means; Floats v_means;
    Floats m_log_scales; Floats v_log_scales;
    Floats m_quats; Floats v_quats;
    Floats m_opacity; Floats v_opacity;
    Floats m_sh; Floats v_sh;
    Uints movable;         // per Gaussian (`Motion`): 0 no update, 1 update, 2 update all but the
                           // SH bands above the first (read only when `frozen & 32` is set)
    AdamStep step_means; AdamStep step_log_scales; AdamStep step_quats; AdamStep step_opacity;
    AdamStep step_sh;      // lr for the DC coefficient, lr_tail for the higher bands
    float opacity_reg;     // 3DGS-MCMC regularizer weights over N (opacity) and 3N (scales); 0 = off
    float scale_reg;
    uint frozen;           // bits: 1 means, 2 log_scales, 4 quats, 8 opacity, 16 sh (no update);
                           // 32: only the Gaussians `movable` marks update
    uint sh_stepped;       // SH coefficients per channel stepped; see main
    float trust_radius;    // each Gaussian's geometry row update clipped to this norm (inf: off)
};

// Whether coefficients above the rendered bands are stepped (sh_stepped > SH_BANDS: moments of a
// higher degree rendered before). Usually not, and a constant, so that their loop compiles away:
// lavapipe would run its body once with every lane masked off.
layout(constant_id = 1) const bool STEP_ABOVE_RENDERED = false;

layout(local_size_x = 256) in;
layout(push_constant) uniform Push { RenderParams p; BackwardParams b; FusedAdam a; };

void step_element(Floats param, Floats m, Floats v, uint i, float g, AdamStep s, float rate) {
    param.v[i] -= adam_update_value(g, m, v, i, s, rate);
}

void main() {
    uint g = linear_group_id() * 256 + gl_LocalInvocationID.x;
    if (g >= p.num_gaussians) return;
    // a Gaussian held still: neither it, its moments nor its densification statistics change
    uint motion = (a.frozen & 32u) != 0u ? a.movable.v[g] : 1u;
    if (motion == 0u) return;
    ParamGrads d;
    parameter_grads(p, b, g, d);  // zero when culled
    // Everything read from the parameter blocks is copied to locals first: the stores below could
    // alias those blocks as far as the compiler knows, and would make it load them again per element.
    uint frozen = a.frozen;
    float radius = a.trust_radius;
    if ((frozen & 1u) == 0u) {
        Floats param = a.means, m = a.m_means, v = a.v_means;
        AdamStep s = a.step_means;
        vec3 u;
        for (uint i = 0; i < 3; i++) u[i] = adam_update_value(d.mean[i], m, v, 3 * g + i, s, s.lr);
        float k = trust_scale(dot(u, u), radius);
        for (uint i = 0; i < 3; i++) param.v[3 * g + i] = d.mean_value[i] - k * u[i];
    }
    if ((frozen & 2u) == 0u) {
        Floats param = a.log_scales, m = a.m_log_scales, v = a.v_log_scales;
        AdamStep s = a.step_log_scales;
        float weight = a.scale_reg;
        vec3 u;
        for (uint i = 0; i < 3; i++) {
            u[i] = adam_update_value(d.log_scale[i] + weight * exp(d.log_scale_value[i]), m, v, 3 * g + i, s, s.lr);
        }
        float k = trust_scale(dot(u, u), radius);
        for (uint i = 0; i < 3; i++) param.v[3 * g + i] = d.log_scale_value[i] - k * u[i];
    }
    if ((frozen & 4u) == 0u) {
        Floats param = a.quats, m = a.m_quats, v = a.v_quats;
        AdamStep s = a.step_quats;
        vec4 u;
        for (uint i = 0; i < 4; i++) u[i] = adam_update_value(d.quat[i], m, v, 4 * g + i, s, s.lr);
        float k = trust_scale(dot(u, u), radius);
        for (uint i = 0; i < 4; i++) param.v[4 * g + i] = d.quat_value[i] - k * u[i];
    }
    if ((frozen & 8u) == 0u) {
        Floats param = a.opacity_logits;
        float value = param.v[g];
        float sig = 1.0 / (1.0 + exp(-value));
        float reg = a.opacity_reg * sig * (1.0 - sig);
        AdamStep s = a.step_opacity;
        param.v[g] = value - adam_update_value(d.opacity_logit + reg, a.m_opacity, a.v_opacity, g, s, s.lr);
    }
    if ((frozen & 16u) == 0u) {
        Floats param = a.sh, m = a.m_sh, v = a.v_sh;
        AdamStep s = a.step_sh;  // lr: the DC coefficient, lr_tail: higher bands
        // Coefficients at and above sh_stepped belong to bands never rendered yet (the degree grows
        // during training): zero gradient and zero moments, where an Adam step changes nothing.
        uint K = p.sh_coeffs, stepped = motion == 2u ? 1u : a.sh_stepped;
        // The rendered bands first, in a loop of constant length (the basis stays in registers),
        // then those stepped before at a higher degree, if any, with zero gradient.
        for (uint k = 0; k < SH_BANDS; k++) {
            if (k >= stepped) break;
            vec3 grad = d.bands > 0u ? d.basis[k] * d.color_raw : vec3(0.0);  // 0 when culled
            float rate = k == 0 ? s.lr : s.lr_tail;
            for (uint c = 0; c < 3; c++) {
                uint e = (g * K + k) * 3 + c;
                float value = k == 0 ? d.dc_value[c] : param.v[e];  // k is a constant once unrolled
                param.v[e] = value - adam_update_value(grad[c], m, v, e, s, rate);
            }
        }
        if (STEP_ABOVE_RENDERED) {
            for (uint k = SH_BANDS; k < stepped; k++) {
                for (uint c = 0; c < 3; c++) step_element(param, m, v, (g * K + k) * 3 + c, 0.0, s, s.lr_tail);
            }
        }
    }
}
