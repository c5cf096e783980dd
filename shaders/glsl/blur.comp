#version 460
// Separable 11-tap Gaussian blur (sigma 1.5, zero padding: SSIM's window as in the INRIA reference),
// along x or y, of `planes` consecutive width x height float planes.
#include "common.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push { Floats src; Floats dst; uint width; uint height; uint planes; uint vertical; };

// exp(-k^2 / (2 * 1.5^2)) for k = -5..5, normalized to sum 1
const float W[11] = float[11](1.028380084e-03, 7.598758135e-03, 3.600077213e-02, 1.093606895e-01, 2.130055377e-01, 2.660117249e-01, 2.130055377e-01, 1.093606895e-01, 3.600077213e-02, 7.598758135e-03, 1.028380084e-03);

void main() {
    uint i = linear_group_id() * 256 + gl_LocalInvocationID.x;
    uint hw = width * height;
    if (i >= hw * planes) return;
    uint plane = i / hw, pix = i % hw;
    int x = int(pix % width), y = int(pix / width);
    float acc = 0.0;
    for (int k = -5; k <= 5; k++) {
        int xx = vertical != 0 ? x : x + k;
        int yy = vertical != 0 ? y + k : y;
        if (xx >= 0 && xx < int(width) && yy >= 0 && yy < int(height))
            acc += W[k + 5] * src.v[plane * hw + uint(yy) * width + uint(xx)];
    }
    dst.v[i] = acc;
}
