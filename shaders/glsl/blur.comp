#version 460
// SSIM pass 3 of 4: the window along x of `planes` consecutive width x height planes
// (gl_GlobalInvocationID.z = plane).
#include "common.glsl"
#include "ssim_window.glsl"

layout(local_size_x = 64, local_size_y = 4) in;
layout(push_constant) uniform Push { Floats src; Floats dst; uint width; uint height; };

void main() {
    uvec3 id = gl_GlobalInvocationID;
    if (id.x >= width || id.y >= height) return;
    uint row = (id.z * height + id.y) * width;
    ivec2 t = taps(int(id.x), width);
    float acc = 0.0;
    for (int k = t.x; k <= t.y; k++) acc += W[k + 5] * src.v[row + uint(int(id.x) + k)];
    dst.v[row + id.x] = acc;
}
