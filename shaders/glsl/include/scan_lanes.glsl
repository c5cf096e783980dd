// The lane-serial shape of the prefix scan, for CPU drivers (as the sort's, radix_lanes.glsl): the
// workgroup is one subgroup of the device's size, and each lane owns a contiguous slice of the
// block, which it reads and writes as uvec4s (the data's address is 16-byte aligned: gpu::Buffer).
// No shared-memory tree and its barriers, which on llvmpipe cost more than the slice's own work.
layout(local_size_x_id = 0) in;
// Elements per workgroup (render::scan::ScanShape::block); a multiple of 4 x the workgroup size.
layout(constant_id = 1) const uint BLOCK = 8192;
layout(push_constant) uniform Push { Uints data; Uints block_sums; uint n; };

layout(buffer_reference, std430, buffer_reference_align = 16) buffer Uvec4Words { uvec4 v[]; };

// This lane's slice of the block.
void lane_slice(uint block, out uint start, out uint end) {
    uint per_lane = BLOCK / gl_WorkGroupSize.x;
    start = min(block * BLOCK + gl_LocalInvocationID.x * per_lane, n);
    end = min(start + per_lane, n);
}
