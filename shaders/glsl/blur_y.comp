#version 460
// SSIM pass 3 of 4 where rows are 16-byte aligned: the window along y of `planes` consecutive
// width x height planes (gl_GlobalInvocationID.z = plane), the partials of pass 2, so that pass 4
// (loss_grad_x.comp) runs along x, where vec4s pay. Otherwise blur.comp and loss_grad.comp take
// the two directions the other way round.
#include "common.glsl"
#include "ssim_window.glsl"

RUNS_ALONG_Y;
layout(push_constant) uniform Push { Floats src; Floats dst; uint width; uint height; };

void main() {
    uvec3 id = gl_GlobalInvocationID;
    int y0 = int(id.y) * RUN;
    if (id.x >= width || y0 >= int(height)) return;
    uint column = id.z * width * height + id.x;
    float win[SPAN];
    for (int j = 0; j < SPAN; j++) {
        int p = y0 - 5 + j;
        win[j] = 0.0;
        if (p >= 0 && p < int(height)) win[j] = src.v[column + uint(p) * width];
    }
    for (int r = 0; r < RUN && y0 + r < int(height); r++) {
        float acc = 0.0;
        for (int k = 0; k < 11; k++) acc += W[k] * win[r + k];
        dst.v[column + uint(y0 + r) * width] = acc;
    }
}
