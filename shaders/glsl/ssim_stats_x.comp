#version 460
// SSIM pass 1 of 4: the five local statistics' inputs x, y, x^2, y^2, xy (x the render, y the
// target) blurred along x, per channel; laid out [quantity][channel][pixel]. The products are formed
// on the fly instead of being written and read back.
#include "common.glsl"
#include "ssim_window.glsl"

layout(local_size_x = 64, local_size_y = 4) in;
layout(push_constant) uniform Push { Floats render; Floats target; Floats stats; uint width; uint height; uint channels; };

void main() {
    uvec3 id = gl_GlobalInvocationID;
    if (id.x >= width || id.y >= height) return;
    uint hw = width * height, n = hw * channels;
    uint row = id.z * hw + id.y * width;
    ivec2 t = taps(int(id.x), width);
    float sx = 0.0, sy = 0.0, sxx = 0.0, syy = 0.0, sxy = 0.0;
    for (int k = t.x; k <= t.y; k++) {
        uint i = row + uint(int(id.x) + k);
        float x = render.v[i], y = target.v[i], w = W[k + 5];
        sx += w * x;
        sy += w * y;
        sxx += w * (x * x);
        syy += w * (y * y);
        sxy += w * (x * y);
    }
    uint o = row + id.x;
    stats.v[o] = sx;
    stats.v[n + o] = sy;
    stats.v[2 * n + o] = sxx;
    stats.v[3 * n + o] = syy;
    stats.v[4 * n + o] = sxy;
}
