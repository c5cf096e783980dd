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
    TAPS(v)
#define LOAD(p, k) { int p_ = (p); v##k = p_ >= 0 && p_ < int(width) ? src.v[row + uint(max(p_, 0))] : 0.0; }
    PRIME(x0)
    for (int r = 0; r < RUN && x0 + r < int(width); r++) {
        SLIDE(v)
        LOAD(x0 + r + 5, 10)
        dst.v[row + uint(x0 + r)] = WINDOW(v);
    }
}
