// The lane-serial shape of the prefix scan, for CPU drivers (as the sort's, radix_lanes.glsl): the
// workgroup is one subgroup of the device's size, and each lane owns a contiguous slice of the
// block, which it reads and writes as uvec4s (the data's address is 16-byte aligned: gpu::Buffer).
// No shared-memory tree and its barriers, which on llvmpipe cost more than the slice's own work.
layout(local_size_x_id = 0) in;
// Elements per workgroup (render::scan::ScanShape::block); a multiple of 4 x the workgroup size.
layout(constant_id = 1) const uint BLOCK = 8192;
layout(push_constant) uniform Push { Uints data; Uints block_sums; uint n; };

