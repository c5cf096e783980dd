// Exemplar inpainting (Wexler et al. 2007 with PatchMatch, Barnes et al. 2009): every target pixel
// (a pixel whose patch touches the hole) keeps the source pixel whose fully known patch looks most
// like its own; hole pixels are then the vote of the source pixels those patches put on them.
// Shared by exemplar_nnf.comp and exemplar_vote.comp; the Rust owner is removal/complete/exemplar.rs.
#extension GL_EXT_control_flow_attributes : require
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
    uint dist_known;      // nnf pass: dist_in holds each target's distance to its nnf_in source
    Floats disparity;     // per pixel, 1 / depth (the hole's completed); 0 = unknown
    Uints packed;         // per pixel, `image` in 10 bits per channel (pack_rgb): what patches compare
};

// The patch distances read a pixel's color as one word instead of three planes: on lavapipe each
// read of a scattered pixel is a gather, and the search is mostly those reads (the transfer stage,
// which runs the fills, 0.62x on the statue `images_2`). Ten bits per channel over [0, 1] move a
// color by at most 1/2046, an eighth of the photos' 8-bit step; the vote still averages the
// planes themselves. On the bench scenes the full pipeline's masked PSNR stayed within 0.04 dB.
uint pack_rgb(vec3 c) {
    uvec3 q = uvec3(roundEven(clamp(c, 0.0, 1.0) * 1023.0));
    return q.r | (q.g << 10) | (q.b << 20);
}
vec3 unpack_rgb(uint v) {
    return vec3(uvec3(v, v >> 10, v >> 20) & 1023u) * (1.0 / 1023.0);
}

// The target's patch, read once per target and compared with every candidate source: its colors
// in (dy, dx, channel) order and a bit per pixel that counts (inside the image and on the
// target's surface: a kept object in front of the hole must not pull the match toward its own
// edge). Reading it once halves a candidate's scattered reads (the fill ran about 5 % faster on
// lavapipe; the source patch's reads remain); the sums run in the same order as before.
const int SIDE = 2 * RADIUS + 1;
struct TargetPatch {
    float rgb[3 * SIDE * SIDE];
    uint rows[SIDE];   // per row dy + RADIUS: bit dx + RADIUS set where the pixel counts
    uint row_inside;   // bit dy + RADIUS set where the row is inside the image
    int used;          // pixels that count
    ivec2 t;
    uint label;
    float disparity;   // 1 / depth at t (0 = unknown, or no depth term)
};
// The invocation's target patch: a global, not a parameter, so that no call copies its 160 words.
TargetPatch tp;

// Loads the target patch of t into `tp`.
void load_target_patch(ivec2 t, uint t_label) {
    tp.t = t;
    tp.label = t_label;
    tp.used = 0;
    tp.row_inside = 0u;
    [[unroll]] for (int dy = -RADIUS; dy <= RADIUS; dy++) {
        int ty = t.y + dy;
        bool row_in = ty >= 0 && ty < int(height);
        tp.row_inside |= row_in ? 1u << (dy + RADIUS) : 0u;
        uint row = 0u;
        [[unroll]] for (int dx = -RADIUS; dx <= RADIUS; dx++) {
            int tx = t.x + dx;
            uint a = uint(clamp(ty, 0, int(height) - 1)) * width + uint(clamp(tx, 0, int(width) - 1));
            bool counts = row_in && tx >= 0 && tx < int(width) && (t_label == 0 || label_of(info.v[a]) == t_label);
            row |= counts ? 1u << (dx + RADIUS) : 0u;
            tp.used += counts ? 1 : 0;
            int k = 3 * ((dy + RADIUS) * SIDE + dx + RADIUS);
            vec3 rgb = counts ? unpack_rgb(packed.v[a]) : vec3(0.0);
            [[unroll]] for (int c = 0; c < 3; c++) tp.rgb[k + c] = rgb[c];
        }
        tp.rows[dy + RADIUS] = row;
    }
    tp.disparity = depth_weight > 0.0 ? disparity.v[uint(t.y) * width + uint(t.x)] : 0.0;
}

// Mean squared RGB difference between the target patch and the patch at source s over the target
// patch's pixels that count, plus the surface penalty and the depth term: a source at another
// distance than the target is another surface even where no plane was found (a lawn behind a
// statue must not copy the blurred trees far behind it, whose smoothness matches a smooth first
// estimate best).
// Stops early (returning a value above `bound`) once the partial sum already exceeds `bound` for
// every pixel the patch could still count: the candidate cannot win.
float patch_distance(ivec2 s, float bound) {
    float acc = 0.0;
    float stop = bound * float(3 * SIDE * SIDE);
    [[unroll]] for (int dy = -RADIUS; dy <= RADIUS; dy++) {
        if ((tp.row_inside & (1u << (dy + RADIUS))) == 0u) continue;
        uint row = tp.rows[dy + RADIUS];
        uint b0 = uint(s.y + dy) * width + uint(s.x);  // a source patch is inside the image
        [[unroll]] for (int dx = -RADIUS; dx <= RADIUS; dx++) {
            if ((row & (1u << (dx + RADIUS))) == 0u) continue;
            uint b = uint(int(b0) + dx);
            int k = 3 * ((dy + RADIUS) * SIDE + dx + RADIUS);
            vec3 rgb = unpack_rgb(packed.v[b]);
            [[unroll]] for (int c = 0; c < 3; c++) {
                float d = tp.rgb[k + c] - rgb[c];
                acc += d * d;
            }
        }
        if (acc > stop) return 1e30;
    }
    float dist = acc / float(3 * max(tp.used, 1));
    uint s_label = label_of(info.v[uint(s.y) * width + uint(s.x)]);
    if (tp.label != 0 && s_label != tp.label) dist += label_penalty;
    if (depth_weight > 0.0) {
        float dt = tp.disparity, ds = disparity.v[uint(s.y) * width + uint(s.x)];
        if (dt > 0.0 && ds > 0.0) {
            float r = log(ds / dt);
            dist += depth_weight * r * r;
        }
    }
    return dist;
}
