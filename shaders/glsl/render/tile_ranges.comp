#version 460
// Finds each tile's [start, end) in the tile-sorted intersection list. Ranges start zeroed (the host
// fills them), so tiles nothing touches stay empty. Each invocation walks a run of RUN consecutive
// intersections, loading each tile id once (plus one on either side) instead of three times: on
// lavapipe every per-lane load is a scalar loop, and the runs also cut the workgroups eightfold.
#include "common.glsl"
#include "render_params.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push { RenderParams p; uint num_intersections; };

const uint RUN = 8;  // render::TILE_RANGE_RUN
const uint NONE = 0xffffffffu;  // never a tile id

void main() {
    uint first = (linear_group_id() * 256 + gl_LocalInvocationID.x) * RUN;
    if (first >= num_intersections) return;
    uint last = min(first + RUN, num_intersections);
    uint before = first == 0 ? NONE : p.isect_tile.v[first - 1];
    uint t = p.isect_tile.v[first];
    for (uint i = first; i < last; i++) {
        uint after = i + 1 < num_intersections ? p.isect_tile.v[i + 1] : NONE;
        if (t != before) p.tile_ranges.v[2 * t] = i;
        if (t != after) p.tile_ranges.v[2 * t + 1] = i + 1;
        before = t;
        t = after;
    }
}
