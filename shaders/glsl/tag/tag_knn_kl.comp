#version 460
// L_space: for `samples` Gaussians i drawn uniformly (a hash of (seed, s)), the mean over their k
// nearest neighbours j of KL(p_i || p_j), p = softmax(W f + b), scaled by `weight` = lambda /
// (samples k). With a = log p_i - log p_j and KL = sum p_i a:
//   dKL/dz_i = p_i (a - KL),   dKL/dz_j = p_j - p_i,
// then dL/df = W^T dL/dz (accumulated per Gaussian) and dL/dW = dz f^T, dL/db = dz.
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_basic : require
#ifndef NO_FLOAT_ATOMICS
#extension GL_EXT_shader_atomic_float : require
#endif
#include "common.glsl"
#include "grad_add.glsl"
#include "classifier.glsl"
#include "hash.glsl"

layout(local_size_x = 64) in;
layout(push_constant) uniform Push {
    Floats features;      // n x dim, row-major
    Uints neighbors;      // n x k, nearest first, self excluded
    Floats classifier;
    GradBuf grad_features;
    GradBuf grad_classifier;
    GradBuf loss_sum;     // [0] += loss
    uint n;
    uint samples;
    uint k;
    uint dim;
    uint classes;
    uint seed;
    float weight;
};

void load_feature(uint g, bool valid, out float f[MAX_DIM]) {
    for (uint d = 0; d < MAX_DIM; d++) f[d] = (valid && d < dim) ? features.v[g * dim + d] : 0.0;
}

void add_feature_grad(uint g, bool valid, float dz[MAX_CLASSES]) {
    if (!valid) return;
    for (uint d = 0; d < dim; d++) {
        float v = 0.0;
        for (uint c = 0; c < classes; c++) v += classifier.v[c * dim + d] * dz[c];
        grad_add(grad_features, g * dim + d, v);
    }
}

void main() {
    uint s = linear_group_id() * 64 + gl_LocalInvocationID.x;
    bool valid = s < samples;
    uint i = valid ? (samples >= n ? s : pcg_hash(seed ^ pcg_hash(s)) % n) : 0;
    float fi[MAX_DIM];
    load_feature(i, valid, fi);
    float lpi[MAX_CLASSES];
    classifier_log_softmax(classifier, dim, classes, fi, lpi);
    float dzi[MAX_CLASSES];
    for (uint c = 0; c < MAX_CLASSES; c++) dzi[c] = 0.0;
    float loss = 0.0;
    for (uint jj = 0; jj < k; jj++) {
        uint j = valid ? neighbors.v[i * k + jj] : 0;
        float fj[MAX_DIM];
        load_feature(j, valid, fj);
        float lpj[MAX_CLASSES];
        classifier_log_softmax(classifier, dim, classes, fj, lpj);
        float kl = 0.0;
        for (uint c = 0; c < classes; c++) kl += exp(lpi[c]) * (lpi[c] - lpj[c]);
        float dzj[MAX_CLASSES];
        for (uint c = 0; c < MAX_CLASSES; c++) {
            bool on = valid && c < classes;
            float pi = on ? exp(lpi[c]) : 0.0;
            dzi[c] += on ? weight * pi * (lpi[c] - lpj[c] - kl) : 0.0;
            dzj[c] = on ? weight * (exp(lpj[c]) - pi) : 0.0;
        }
        add_feature_grad(j, valid, dzj);
        classifier_grad_add(grad_classifier, dim, classes, dzj, fj);
        loss += valid ? weight * kl : 0.0;
    }
    add_feature_grad(i, valid, dzi);
    classifier_grad_add(grad_classifier, dim, classes, dzi, fi);
    loss = subgroupAdd(loss);
    if (subgroupElect()) grad_add(loss_sum, 0, loss);
}
