#version 460
// Exemplar inpainting, the vote: each hole pixel becomes the weighted mean of what the patches
// covering it put there (target t at offset d from the pixel puts source(t) + d), each weighted
// by exp(-(distance - the best of them) / sigma2) (`dist_in`; label_penalty carries sigma2 here),
// so the best-matching patches dominate and the result stays sharp. A hole pixel on a surface takes
// only source pixels on that surface where there are any (no kept object's edge dragged in). It reads only source
// patches, which hold no hole pixel, so writing the hole in place is safe.
#include "exemplar.glsl"

layout(local_size_x = 64) in;

void main() {
    uint k = linear_group_id() * 64 + gl_LocalInvocationID.x;
    if (k >= count) return;
    uint p = targets.v[k];
    uint n = width * height;
    ivec2 x = ivec2(p % width, p / width);
    float best = 1e30;
    for (int dy = -RADIUS; dy <= RADIUS; dy++) {
        for (int dx = -RADIUS; dx <= RADIUS; dx++) {
            ivec2 t = x - ivec2(dx, dy);
            if (t.x < 0 || t.y < 0 || t.x >= int(width) || t.y >= int(height)) continue;
            uint ti = uint(t.y) * width + uint(t.x);
            if ((info.v[ti] & TARGET) != 0) best = min(best, dist_in.v[ti]);
        }
    }
    uint label = label_of(info.v[p]);
    vec3 acc = vec3(0.0), acc_any = vec3(0.0);
    float weight = 0.0, weight_any = 0.0;
    for (int dy = -RADIUS; dy <= RADIUS; dy++) {
        for (int dx = -RADIUS; dx <= RADIUS; dx++) {
            ivec2 t = x - ivec2(dx, dy);
            if (t.x < 0 || t.y < 0 || t.x >= int(width) || t.y >= int(height)) continue;
            uint ti = uint(t.y) * width + uint(t.x);
            if ((info.v[ti] & TARGET) == 0) continue;
            uint src = nnf_in.v[ti];
            uint si = (src / width + uint(dy)) * width + (src % width + uint(dx));
            float w = exp(-(dist_in.v[ti] - best) / label_penalty);
            vec3 color = vec3(image.v[si], image.v[n + si], image.v[2 * n + si]);
            acc_any += w * color;
            weight_any += w;
            if (label == 0 || label_of(info.v[si]) == label) {
                acc += w * color;
                weight += w;
            }
        }
    }
    if (weight == 0.0) {
        acc = acc_any;
        weight = weight_any;
    }
    if (weight > 0.0) {
        acc /= weight;
        image.v[p] = acc.x;
        image.v[n + p] = acc.y;
        image.v[2 * n + p] = acc.z;
        packed.v[p] = pack_rgb(acc);
    }
}
