#version 460
// 3DGS-MCMC regularizers (Kheradmand et al. 2024), added to the parameter gradients before Adam:
//   L_reg = w_o * mean_i sigmoid(o_i) + w_s * mean_{i,a} exp(s_ia)
// so dL/do_i = w_o / N * sigma (1 - sigma) and dL/ds_ia = w_s / (3N) * exp(s_ia). They push unused
// Gaussians towards zero opacity and small size, where relocation can recycle them.
#include "common.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push {
    Floats opacity_logits;
    Floats log_scales;
    Floats grad_opacity;
    Floats grad_log_scales;
    uint n;
    float opacity_weight;
    float scale_weight;
};

void main() {
    uint i = linear_group_id() * 256 + gl_LocalInvocationID.x;
    if (i >= n) return;
    float sig = 1.0 / (1.0 + exp(-opacity_logits.v[i]));
    grad_opacity.v[i] += opacity_weight / float(n) * sig * (1.0 - sig);
    for (uint a = 0; a < 3; a++) {
        grad_log_scales.v[3 * i + a] += scale_weight / float(3 * n) * exp(log_scales.v[3 * i + a]);
    }
}
