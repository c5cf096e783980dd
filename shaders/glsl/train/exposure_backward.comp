#version 460
// Per-view exposure backward (train/exposure.rs). With y = A x + b per pixel and g = dL/dy (the
// loss's gradient of the corrected render): dL/dx = A^T g per pixel, for the rasterizer's
// backward, and this workgroup's share of dL/dA = sum g x^T and dL/db = sum g, written as 12
// partial sums (partials[12 group ..]) that exposure_step.comp adds up in a fixed order: no float
// atomics, so the step is the same run to run. A workgroup covers one contiguous chunk of pixels,
// its invocations consecutive pixels, then a tree reduction in shared memory.
#include "common.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push {
    Floats render;
    Floats dl_dy;
    Floats dl_dx;
    Floats params;
    Floats partials;
    uint view;
    uint pixels;
    uint chunk;  // pixels per workgroup
};

shared float sums[12][256];

void main() {
    uint base = 12 * view;
    mat3 a;
    for (uint r = 0; r < 3; r++)
        for (uint c = 0; c < 3; c++) a[c][r] = params.v[base + 3 * r + c];
    mat3 at = transpose(a);
    uint lane = gl_LocalInvocationID.x;
    uint start = gl_WorkGroupID.x * chunk;
    uint end = min(start + chunk, pixels);
    mat3 ga = mat3(0.0);  // ga[d][c] = sum g_c x_d
    vec3 gb = vec3(0.0);
    for (uint p = start + lane; p < end; p += 256) {
        vec3 x = vec3(render.v[p], render.v[pixels + p], render.v[2 * pixels + p]);
        vec3 g = vec3(dl_dy.v[p], dl_dy.v[pixels + p], dl_dy.v[2 * pixels + p]);
        vec3 back = at * g;
        dl_dx.v[p] = back.x;
        dl_dx.v[pixels + p] = back.y;
        dl_dx.v[2 * pixels + p] = back.z;
        ga += outerProduct(g, x);
        gb += g;
    }
    for (uint r = 0; r < 3; r++) {
        for (uint c = 0; c < 3; c++) sums[3 * r + c][lane] = ga[c][r];
        sums[9 + r][lane] = gb[r];
    }
    barrier();
    for (uint half_width = 128; half_width > 0; half_width /= 2) {
        if (lane < half_width)
            for (uint j = 0; j < 12; j++) sums[j][lane] += sums[j][lane + half_width];
        barrier();
    }
    if (lane < 12) partials.v[12 * gl_WorkGroupID.x + lane] = sums[lane][0];
}
