// Exemplar inpainting (Wexler et al. 2007 with PatchMatch, Barnes et al. 2009): every target pixel
// (a pixel whose patch touches the hole) keeps the source pixel whose fully known patch looks most
// like its own; hole pixels are then the vote of the source pixels those patches put on them.
// Shared by exemplar_nnf.comp and exemplar_vote.comp; the Rust owner is removal/complete/exemplar.rs.
#include "common.glsl"

const int RADIUS = 3;  // 7 x 7 patches; removal::complete::exemplar::PATCH_RADIUS

// info bits per pixel
const uint HOLE = 1u;    // synthesized
const uint SOURCE = 2u;  // the centre of a patch that is inside the crop and has no hole pixel
const uint TARGET = 4u;  // the patch touches the hole: it has a nearest-neighbour field entry
uint label_of(uint info) { return (info >> 8) & 0xffu; }

layout(push_constant) uniform Push {
    Floats image;     // planar RGB, width x height: known pixels fixed, hole pixels the estimate
    Uints info;
    Uints nnf_in;     // per pixel: the source pixel index of a target
    Floats dist_in;   // per pixel: the target's patch distance
    Uints nnf_out;
    Floats dist_out;
    Uints targets;    // the target pixels (nnf pass) or the hole pixels (vote pass)
    Uints sources;    // every source pixel, for global random jumps
    uint count;       // entries of `targets`
    uint num_sources;
    uint width;
    uint height;
    uint step;        // propagation distance of this nnf pass
    uint seed;
    uint radius;      // largest random-search radius
    float label_penalty;  // added to the distance of a source on another surface
    float depth_weight;   // times ln(source / target disparity)^2, added to the distance (0: off)
    uint pad;
    Floats disparity;     // per pixel, 1 / depth (the hole's completed); 0 = unknown
};

// Mean squared RGB difference between the patch at target t and the patch at source s, over the
// target patch's pixels inside the image and on the target's surface (a kept object in front of
// the hole must not pull the match toward its own edge), plus the surface penalty and the depth
// term: a source at another distance than the target is another surface even where no plane was
// found (a lawn behind a statue must not copy the blurred trees far behind it, whose smoothness
// matches a smooth first estimate best).
// Stops early (returning a value above `bound`) once the partial sum already exceeds `bound` for
// every pixel the patch could still count: the candidate cannot win.
float patch_distance(ivec2 t, ivec2 s, uint t_label, float bound) {
    uint n = width * height;
    float acc = 0.0;
    int used = 0;
    float stop = bound * float(3 * (2 * RADIUS + 1) * (2 * RADIUS + 1));
    for (int dy = -RADIUS; dy <= RADIUS; dy++) {
        int ty = t.y + dy;
        if (ty < 0 || ty >= int(height)) continue;
        for (int dx = -RADIUS; dx <= RADIUS; dx++) {
            int tx = t.x + dx;
            if (tx < 0 || tx >= int(width)) continue;
            uint a = uint(ty) * width + uint(tx);
            if (t_label != 0 && label_of(info.v[a]) != t_label) continue;
            uint b = uint(s.y + dy) * width + uint(s.x + dx);  // a source patch is inside the image
            for (uint c = 0; c < 3; c++) {
                float d = image.v[c * n + a] - image.v[c * n + b];
                acc += d * d;
            }
            used++;
        }
        if (acc > stop) return 1e30;
    }
    float dist = acc / float(3 * max(used, 1));
    uint s_label = label_of(info.v[uint(s.y) * width + uint(s.x)]);
    if (t_label != 0 && s_label != t_label) dist += label_penalty;
    if (depth_weight > 0.0) {
        float dt = disparity.v[uint(t.y) * width + uint(t.x)], ds = disparity.v[uint(s.y) * width + uint(s.x)];
        if (dt > 0.0 && ds > 0.0) {
            float r = log(ds / dt);
            dist += depth_weight * r * r;
        }
    }
    return dist;
}
