#version 460
// Exemplar inpainting, one PatchMatch pass over the nearest-neighbour field (Jacobi: every target
// reads nnf_in and writes nnf_out, so the result does not depend on thread order): the current
// source, the sources of the four targets `step` pixels away shifted back by that step
// (propagation), samples around the best in halving radii (random search) and one source drawn
// from anywhere (global jump). Randomness is a hash of (seed, pixel, sample): deterministic.
#include "exemplar.glsl"
#include "hash.glsl"

layout(local_size_x = 64) in;

void main() {
    uint k = linear_group_id() * 64 + gl_LocalInvocationID.x;
    if (k >= count) return;
    uint p = targets.v[k];
    ivec2 t = ivec2(p % width, p / width);
    uint t_label = label_of(info.v[p]);
    uint best = nnf_in.v[p];
    ivec2 bs = ivec2(best % width, best / width);
    load_target_patch(t, t_label);
    // the previous pass of a round left the distance of this source on the same image: the very
    // sum this would compute (a kept candidate's sum never stops early)
    float best_d = dist_known != 0u ? dist_in.v[p] : patch_distance(bs, 1e30);
    const ivec2 dirs[4] = ivec2[4](ivec2(1, 0), ivec2(-1, 0), ivec2(0, 1), ivec2(0, -1));
    for (int i = 0; i < 4; i++) {
        ivec2 q = t + dirs[i] * int(step);
        if (q.x < 0 || q.y < 0 || q.x >= int(width) || q.y >= int(height)) continue;
        uint qi = uint(q.y) * width + uint(q.x);
        if ((info.v[qi] & TARGET) == 0) continue;
        uint src = nnf_in.v[qi];
        ivec2 s = ivec2(src % width, src / width) - dirs[i] * int(step);
        if (s.x < 0 || s.y < 0 || s.x >= int(width) || s.y >= int(height)) continue;
        uint si = uint(s.y) * width + uint(s.x);
        if ((info.v[si] & SOURCE) == 0 || si == best) continue;
        float d = patch_distance(s, best_d);
        if (d < best_d) { best_d = d; best = si; bs = s; }
    }
    uint h = pcg_hash(seed ^ pcg_hash(p));
    for (uint r = radius; r >= 1; r /= 2) {
        h = pcg_hash(h);
        ivec2 s = bs + ivec2(int(h % (2 * r + 1)) - int(r), int((h >> 16) % (2 * r + 1)) - int(r));
        if (s.x < 0 || s.y < 0 || s.x >= int(width) || s.y >= int(height)) continue;
        uint si = uint(s.y) * width + uint(s.x);
        if ((info.v[si] & SOURCE) == 0 || si == best) continue;
        float d = patch_distance(s, best_d);
        if (d < best_d) { best_d = d; best = si; bs = s; }
    }
    h = pcg_hash(h);
    uint si = sources.v[h % num_sources];
    float d = patch_distance(ivec2(si % width, si / width), best_d);
    if (d < best_d) { best_d = d; best = si; }
    nnf_out.v[p] = best;
    dist_out.v[p] = best_d;
}
