#version 460
// L_obj: per-pixel softmax cross-entropy of the classifier applied to the rendered identity feature
// F(u) against the view's label O(u), averaged over the supervised pixels (`weight` = 1 / their
// count; label 255 = unsupervised). Writes dL/dF(u) (the feature backward's upstream) and accumulates
// dL/dW, dL/db and the loss. With p = softmax(W F + b): dL/dz = weight (p - onehot(O(u))),
// dL/dF = W^T dL/dz.
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_basic : require
#ifndef NO_FLOAT_ATOMICS
#extension GL_EXT_shader_atomic_float : require
#endif
#include "common.glsl"
#include "grad_add.glsl"
#include "classifier.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push {
    Floats features;      // dim planes of hw: the feature render
    Uints labels;         // one label per pixel, all training views back to back
    Floats classifier;
    Floats dl_dfeatures;  // out: dim planes of hw
    GradBuf grad_classifier;
    GradBuf loss_sum;     // [0] += loss
    uint hw;
    uint label_offset;
    uint dim;
    uint classes;
    float weight;
};

void main() {
    uint u = linear_group_id() * 256 + gl_LocalInvocationID.x;
    bool in_image = u < hw;
    uint label = in_image ? labels.v[label_offset + u] : 255u;
    bool valid = label < classes;
    float f[MAX_DIM];
    for (uint d = 0; d < MAX_DIM; d++) f[d] = (valid && d < dim) ? features.v[d * hw + u] : 0.0;
    float lp[MAX_CLASSES];
    classifier_log_softmax(classifier, dim, classes, f, lp);
    float dz[MAX_CLASSES];
    for (uint c = 0; c < MAX_CLASSES; c++) {
        dz[c] = (valid && c < classes) ? weight * (exp(lp[c]) - (c == label ? 1.0 : 0.0)) : 0.0;
    }
    if (in_image) {
        for (uint d = 0; d < dim; d++) {
            float g = 0.0;
            for (uint c = 0; c < classes; c++) g += classifier.v[c * dim + d] * dz[c];
            dl_dfeatures.v[d * hw + u] = g;
        }
    }
    classifier_grad_add(grad_classifier, dim, classes, dz, f);
    float loss = subgroupAdd(valid ? -weight * lp[label] : 0.0);
    if (subgroupElect()) grad_add(loss_sum, 0, loss);
}
