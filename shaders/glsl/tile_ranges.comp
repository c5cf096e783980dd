#version 460
// Finds each tile's [start, end) in the tile-sorted intersection list. Ranges start zeroed (the host
// fills them), so tiles nothing touches stay empty.
#include "common.glsl"
#include "render_params.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push { RenderParams p; uint num_intersections; };

void main() {
    uint i = linear_group_id() * 256 + gl_LocalInvocationID.x;
    if (i >= num_intersections) return;
    uint t = p.isect_tile.v[i];
    if (i == 0 || p.isect_tile.v[i - 1] != t) p.tile_ranges.v[2 * t] = i;
    if (i + 1 == num_intersections || p.isect_tile.v[i + 1] != t) p.tile_ranges.v[2 * t + 1] = i + 1;
}
