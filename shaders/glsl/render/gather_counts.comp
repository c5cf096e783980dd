#version 460
// Puts each Gaussian's touched-tile count into depth order, ready for the exclusive scan that gives
// every Gaussian its first slot in the intersection list. Slot N is zeroed so the scan leaves the
// total number of intersections there.
#include "common.glsl"
#include "render_params.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push { RenderParams p; };

void main() {
    uint s = linear_group_id() * 256 + gl_LocalInvocationID.x;
    if (s < p.num_gaussians) p.isect_offsets.v[s] = p.tiles_touched.v[p.depth_order.v[s]];
    if (s == p.num_gaussians) p.isect_offsets.v[s] = 0;
}
