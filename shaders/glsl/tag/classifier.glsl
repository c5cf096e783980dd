// The identity classifier Phi(f) = W f + b shared by pixels and Gaussians (tag/distill.rs), stored
// as W (classes x dim, row-major) followed by b (classes), and its log-softmax.
const uint MAX_DIM = 32;
const uint MAX_CLASSES = 32;

void classifier_log_softmax(Floats phi, uint dim, uint classes, float f[MAX_DIM], out float lp[MAX_CLASSES]) {
    float zmax = -3.0e38;
    for (uint c = 0; c < classes; c++) {
        float z = phi.v[classes * dim + c];
        for (uint d = 0; d < dim; d++) z += phi.v[c * dim + d] * f[d];
        lp[c] = z;
        zmax = max(zmax, z);
    }
    float sum = 0.0;
    for (uint c = 0; c < classes; c++) sum += exp(lp[c] - zmax);
    float lse = zmax + log(sum);
    for (uint c = 0; c < classes; c++) lp[c] -= lse;
}

// Accumulates dL/dW = dz f^T and dL/db = dz over the subgroup, one atomic per element per subgroup.
// Every invocation of the subgroup must call it (inactive ones with dz = 0).
void classifier_grad_add(GradBuf grad, uint dim, uint classes, float dz[MAX_CLASSES], float f[MAX_DIM]) {
    for (uint c = 0; c < classes; c++) {
        for (uint d = 0; d < dim; d++) {
            float v = subgroupAdd(dz[c] * f[d]);
            if (subgroupElect()) grad_add(grad, c * dim + d, v);
        }
        float vb = subgroupAdd(dz[c]);
        if (subgroupElect()) grad_add(grad, classes * dim + c, vb);
    }
}
