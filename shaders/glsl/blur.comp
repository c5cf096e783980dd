#version 460
// SSIM pass 3 of 4: the window along x of `planes` consecutive width x height planes
// (gl_GlobalInvocationID.z = plane).
#include "common.glsl"
#include "ssim_window.glsl"

RUNS_ALONG_X;
layout(push_constant) uniform Push { Floats src; Floats dst; uint width; uint height; };

void main() {
    uvec3 id = gl_GlobalInvocationID;
    int x0 = int(id.x) * RUN;
    if (x0 >= int(width) || id.y >= height) return;
    uint row = (id.z * height + id.y) * width;
    float win[SPAN];
    for (int j = 0; j < SPAN; j++) {
        int p = x0 - 5 + j;
        win[j] = 0.0;
        if (p >= 0 && p < int(width)) win[j] = src.v[row + uint(p)];
    }
    for (int r = 0; r < RUN && x0 + r < int(width); r++) {
        float acc = 0.0;
        for (int k = 0; k < 11; k++) acc += W[k] * win[r + k];
        dst.v[row + uint(x0 + r)] = acc;
    }
}
