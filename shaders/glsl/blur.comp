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
    LOAD(x0 - 5, 1) LOAD(x0 - 4, 2) LOAD(x0 - 3, 3) LOAD(x0 - 2, 4) LOAD(x0 - 1, 5)
    LOAD(x0, 6) LOAD(x0 + 1, 7) LOAD(x0 + 2, 8) LOAD(x0 + 3, 9) LOAD(x0 + 4, 10)
    for (int r = 0; r < RUN && x0 + r < int(width); r++) {
        SLIDE(v)
        LOAD(x0 + r + 5, 10)
        dst.v[row + uint(x0 + r)] = WINDOW(v);
    }
}
