#version 460
// Per-view exposure (train/exposure.rs): the render seen through view v's color correction,
// corrected = A render + b per pixel (A 3x3, b 3; params[12 v ..] = A row-major, then b), so the
// loss compares the photo with what that view's camera would have recorded. Each invocation
// corrects PER consecutive pixels of a planar RGB image.
#include "common.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push {
    Floats render;
    Floats corrected;
    Floats params;
    uint view;
    uint pixels;
};

const uint PER = 4;

void main() {
    uint base = 12 * view;
    mat3 a;  // a[column][row]: GLSL matrices are column-major
    for (uint r = 0; r < 3; r++)
        for (uint c = 0; c < 3; c++) a[c][r] = params.v[base + 3 * r + c];
    vec3 b = vec3(params.v[base + 9], params.v[base + 10], params.v[base + 11]);
    uint first = linear_group_id() * (256 * PER) + gl_LocalInvocationID.x;
    for (uint k = 0; k < PER; k++) {
        uint p = first + k * 256;
        if (p >= pixels) return;
        vec3 x = vec3(render.v[p], render.v[pixels + p], render.v[2 * pixels + p]);
        vec3 y = a * x + b;
        corrected.v[p] = y.x;
        corrected.v[pixels + p] = y.y;
        corrected.v[2 * pixels + p] = y.z;
    }
}
