#version 460
// Copies `n` 16-byte words: the memory-bound reference pass whose throughput is "the device's copy
// bandwidth" in the benches (gpu::bandwidth), the roof every elementwise pass is measured against.
// Each workgroup copies a contiguous block of 256 * `per` words; within a step its invocations touch
// consecutive words (`blocked` = 0) or each invocation copies `per` consecutive words (`blocked` = 1).
#include "common.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push { UVec4s src; UVec4s dst; uint n; uint per; uint blocked; };

void main() {
    uint block = linear_group_id() * 256 * per;
    for (uint k = 0; k < per; k++) {
        uint i = blocked != 0 ? block + gl_LocalInvocationID.x * per + k : block + k * 256 + gl_LocalInvocationID.x;
        if (i < n) dst.v[i] = src.v[i];
    }
}
