// Shared declarations for every cogeo compute pass. All buffers are reached through buffer device
// addresses, so no pass is bound by a driver's per-binding storage-buffer limit (128 MiB on lavapipe).
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference2 : require
#extension GL_EXT_scalar_block_layout : require

layout(buffer_reference, std430, buffer_reference_align = 4) buffer Floats { float v[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) buffer Uints { uint v[]; };

// Vector views of float and uint buffers in scalar layout (4-byte aligned, no padding), so that a
// Gaussian's 2-4 consecutive values are one access per lane. On lavapipe every per-lane access is a
// loop over the lanes whatever its width, so fewer, wider accesses are what a pass pays less for.
layout(buffer_reference, scalar, buffer_reference_align = 4) buffer Vec2View { vec2 v[]; };
layout(buffer_reference, scalar, buffer_reference_align = 4) buffer Vec3View { vec3 v[]; };
layout(buffer_reference, scalar, buffer_reference_align = 4) buffer Vec4View { vec4 v[]; };
layout(buffer_reference, scalar, buffer_reference_align = 4) buffer UVec2View { uvec2 v[]; };
layout(buffer_reference, scalar, buffer_reference_align = 4) buffer UVec4View { uvec4 v[]; };

// Whole buffers read as 16-byte words from their start (every gpu::Buffer starts 16-byte aligned):
// the copy-bandwidth reference, the loss's vec4 passes, the lane-serial sort and scan.
layout(buffer_reference, std430, buffer_reference_align = 16) buffer Vec4s { vec4 v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) buffer UVec4s { uvec4 v[]; };

// The lane-serial shape (the sort's and the scan's on CPU drivers): lane i of a workgroup of `lanes`
// owns the i-th of their equal, contiguous slices of the `block_size` elements of block `block`,
// clipped to n. `lanes` is the caller's gl_WorkGroupSize.x: read here, before the shader declares
// its workgroup size, gl_WorkGroupSize does not hold that size (the sort and scan tests failed).
void lane_slice(uint block, uint block_size, uint lanes, uint n, out uint start, out uint end) {
    uint per_lane = block_size / lanes;
    start = min(block * block_size + gl_LocalInvocationID.x * per_lane, n);
    end = min(start + per_lane, n);
}

// Dispatches over more than 65535 workgroups are split into a 2D grid by the host (gpu::dispatch_1d);
// this linearizes the workgroup id again.
uint linear_group_id() {
    return gl_WorkGroupID.x + gl_WorkGroupID.y * gl_NumWorkGroups.x;
}
