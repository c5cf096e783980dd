#version 460
// Adam step for one parameter tensor (PyTorch's formulation, as the INRIA reference uses):
//   m = b1 m + (1 - b1) g,  v = b2 v + (1 - b2) g^2,
//   p -= lr * (m / (1 - b1^t)) / (sqrt(v / (1 - b2^t)) + eps).
// The host passes the bias corrections; frozen tensors are simply not dispatched. Within a tensor,
// element i uses `lr` when i % period < head and `lr_tail` otherwise (SH: DC vs higher bands).
#include "common.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push {
    Floats param; Floats grad; Floats m; Floats v;
    uint n; float lr; float beta1; float beta2; float eps; float bias1; float bias2;
    uint period; uint head; float lr_tail;
};

void main() {
    uint i = linear_group_id() * 256 + gl_LocalInvocationID.x;
    if (i >= n) return;
    float g = grad.v[i];
    float mi = beta1 * m.v[i] + (1.0 - beta1) * g;
    float vi = beta2 * v.v[i] + (1.0 - beta2) * g * g;
    m.v[i] = mi;
    v.v[i] = vi;
    float rate = (i % period) < head ? lr : lr_tail;
    param.v[i] -= rate * (mi / bias1) / (sqrt(vi / bias2) + eps);
}
