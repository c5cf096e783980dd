// One Adam step of one element, shared by adam.comp, adam_clipped.comp and
// project_backward_adam.comp so all follow PyTorch's formulation (as the INRIA reference uses)
// exactly:
//   m = b1 m + (1 - b1) g,  v = b2 v + (1 - b2) g^2,
//   u = rate * (m / (1 - b1^t)) / (sqrt(v / (1 - b2^t)) + eps)
// The host passes the bias corrections. Element i uses `lr` when i % period < head and `lr_tail`
// otherwise (SH: DC vs higher bands). Mirrors `train::adam::AdamStep`.
struct AdamStep {
    uint n; float lr; float beta1; float beta2; float eps; float bias1; float bias2;
    uint period; uint head; float lr_tail;
};

// The rate of element i: lr when i % period < head, else lr_tail.
float adam_rate(uint i, AdamStep s) {
    return (i % s.period) < s.head ? s.lr : s.lr_tail;
}

// Updates the moments of element i with gradient g and returns its update u (to be subtracted)
// at `rate`.
float adam_update_value(float g, Floats m, Floats v, uint i, AdamStep s, float rate) {
    float mi = s.beta1 * m.v[i] + (1.0 - s.beta1) * g;
    float vi = s.beta2 * v.v[i] + (1.0 - s.beta2) * g * g;
    m.v[i] = mi;
    v.v[i] = vi;
    return rate * (mi / s.bias1) / (sqrt(vi / s.bias2) + s.eps);
}

// As adam_update_value, with the gradient read from grad[i].
float adam_update(Floats grad, Floats m, Floats v, uint i, AdamStep s, float rate) {
    return adam_update_value(grad.v[i], m, v, i, s, rate);
}

// The factor that clips a row's update of squared norm u2 to Euclidean norm `radius` (a trust
// region per Gaussian: adam_clipped.comp and project_backward_adam.comp); 1 when the radius is
// infinite, leaving the update exactly as it is.
float trust_scale(float u2, float radius) {
    float norm = sqrt(u2);
    return norm > radius ? radius / norm : 1.0;
}
