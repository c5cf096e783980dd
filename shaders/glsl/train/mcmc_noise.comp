#version 460
// 3DGS-MCMC position noise (the SGLD term), after the Adam step:
//   mu_i += scale * Sigma_i z * sigmoid(-k (sigma(o_i) - t)),  z ~ N(0, I),  k = 100, t = 0.005
// Sigma_i = R S S^T R^T is the Gaussian's own covariance, so noise follows its shape; the sigmoid
// gate keeps opaque Gaussians in place and lets near-transparent ones explore. `scale` is the
// noise learning rate times the current position learning rate. z comes from a counter-based hash of
// (seed, i), so the pass is deterministic for a given step.
#include "common.glsl"
#include "quat.glsl"
#include "hash.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push {
    Floats means;
    Floats log_scales;
    Floats quats;
    Floats opacity_logits;
    uint n;
    float scale;
    uint seed;
};

// uniform in (0, 1]
float unit(inout uint s) {
    s = pcg_hash(s);
    return (float(s >> 8) + 1.0) / 16777216.0;
}

void main() {
    uint i = linear_group_id() * 256 + gl_LocalInvocationID.x;
    if (i >= n) return;
    float sig = 1.0 / (1.0 + exp(-opacity_logits.v[i]));
    float gate = 1.0 / (1.0 + exp(100.0 * (sig - 0.005)));
    if (gate < 1e-12) return;
    uint s = pcg_hash(seed ^ pcg_hash(i));
    // Box-Muller: three normals from two pairs
    float r0 = sqrt(-2.0 * log(unit(s))), t0 = 6.283185307 * unit(s);
    float r1 = sqrt(-2.0 * log(unit(s))), t1 = 6.283185307 * unit(s);
    vec3 z = vec3(r0 * cos(t0), r0 * sin(t0), r1 * cos(t1));
    vec4 q = vec4(quats.v[4 * i], quats.v[4 * i + 1], quats.v[4 * i + 2], quats.v[4 * i + 3]);
    q /= max(length(q), 1e-12);
    mat3 R = quat_to_rotation(q);
    vec3 sc = exp(vec3(log_scales.v[3 * i], log_scales.v[3 * i + 1], log_scales.v[3 * i + 2]));
    mat3 M = R * mat3(sc.x, 0, 0, 0, sc.y, 0, 0, 0, sc.z);
    vec3 d = (M * transpose(M)) * z * (scale * gate);
    for (uint a = 0; a < 3; a++) means.v[3 * i + a] += d[a];
}
