#version 460
// Tile rasterizer: one workgroup per 16x16 tile composites the tile's depth-sorted Gaussians front to
// back. Outputs RGB (+ background), alpha, accumulated depth, expected depth, and the per-pixel state the
// backward pass replays: final transmittance and the index past the last blended intersection.
// Each invocation owns a column of ROWS pixels (the workgroup is 16 x 16/ROWS; render::BlendLayout
// picks ROWS per device), so a Gaussian's parameters are fetched once for ROWS pixels, and rows out
// of the Gaussian's reach (row_reach) are skipped. Every pixel makes exactly the decisions of
// blend_weight, whatever ROWS is. Gaussians reach the lanes by subgroup broadcast, not shared memory:
// on lavapipe a shared load is a loop over the lanes, a broadcast one register move (trained 31.5k
// scene at 256x192: 210 -> 130 ms).
// With ONE_FEATURE = 1 (a scene with one feature per Gaussian, such as the removal's marker of the
// removed Gaussians) the feature is blended here too, with the very sums of blend_features.comp,
// instead of a second walk over the tile lists (on lavapipe that walk was 40 % of a render).
// With AFTER_REMOVAL = 1 (and ONE_FEATURE = 1) the feature marks the removal: 1 a removed Gaussian,
// 2 a kept object's, 0 the background. The walk then also blends the scene less the removed
// Gaussians, into out_after, with the very decisions a render of that scene alone makes (its tile
// lists are these less the removed Gaussians, in the same order): the hull's redraws need both
// renders of a view's tiles, and the one walk spares the second scene's projection, sorts and
// walk. The original's feature plane is then the removed Gaussians' weight, the after-removal one
// the kept objects'.
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_vote : require
#extension GL_KHR_shader_subgroup_ballot : require
#include "common.glsl"
#include "render_params.glsl"
#include "blend_common.glsl"

layout(constant_id = 0) const uint ROWS = 1;
layout(constant_id = 1) const uint GROUP_HEIGHT = 16;
layout(constant_id = 2) const uint ONE_FEATURE = 0;
layout(constant_id = 3) const uint MEDIAN_DEPTH = 0;
layout(constant_id = 4) const uint AFTER_REMOVAL = 0;
layout(local_size_x = 16, local_size_y_id = 1) in;
layout(push_constant) uniform Push { RenderParams p; };

void main() {
    uint tile = tile_id();
    if (tile >= p.tiles_x * p.tiles_y) return;  // uniform over the workgroup
    uint tx = tile % p.tiles_x, ty = tile / p.tiles_x;

    uvec2 range = blended_range(p, tile);
    uint start = range.x, end = range.y;
    vec2 pixel[ROWS];
    float T[ROWS], D[ROWS], W[ROWS], F[ROWS], M[ROWS];
    vec3 C[ROWS];
    uint n_contrib[ROWS];
    bool finished[ROWS];
    // the scene after removal (AFTER_REMOVAL): transmittance, color, depth sum, weight sum, kept
    // objects' weight, median depth
    float T2[ROWS], D2[ROWS], W2[ROWS], F2[ROWS], M2[ROWS];
    vec3 C2[ROWS];
    bool finished2[ROWS];
    bool lane_finished = true;  // every owned pixel finished
    for (uint r = 0; r < ROWS; r++) {
        uvec2 pix = uvec2(tx * TILE + gl_LocalInvocationID.x, ty * TILE + gl_LocalInvocationID.y * ROWS + r);
        pixel[r] = vec2(pix) + 0.5;
        T[r] = 1.0;
        C[r] = vec3(0.0);
        D[r] = 0.0;
        W[r] = 0.0;
        F[r] = 0.0;
        M[r] = -1.0;  // not yet half opaque
        n_contrib[r] = start;
        finished[r] = !(pix.x < p.width && pix.y < p.height);
        lane_finished = lane_finished && finished[r];
        if (AFTER_REMOVAL != 0) {
            T2[r] = 1.0;
            C2[r] = vec3(0.0);
            D2[r] = 0.0;
            W2[r] = 0.0;
            F2[r] = 0.0;
            M2[r] = -1.0;
            finished2[r] = finished[r];
        }
    }

    // Each subgroup walks the list on its own, a subgroup's worth of Gaussians at a time: lane l
    // loads the batch's l-th Gaussian into registers, and every lane then takes them in order by
    // broadcast. No shared memory and no barriers, and a subgroup stops when its own pixels are done.
    // `lanes` counts the lanes present: a workgroup smaller than a subgroup fills only the low lanes.
    uint lanes = subgroupBallotBitCount(subgroupBallot(true));
    for (uint batch = start; batch < end; batch += lanes) {
        if (subgroupAll(lane_finished)) break;
        uint k = batch + gl_SubgroupInvocationID;
        vec2 my_xy = vec2(0.0);
        vec4 my_co = vec4(0.0), my_cd = vec4(0.0);
        float my_reach = -1.0;  // past the end: reaches no row
        float my_f = 0.0;
        if (k < end) {
            uint g = p.isect_gauss.v[k];
            my_xy = Vec2View(p.xy).v[g];
            my_co = Vec4View(p.conic_opacity).v[g];
            my_cd = vec4(Vec3View(p.color).v[g], p.depth.v[g]);
            my_reach = row_reach(my_co);
            if (ONE_FEATURE != 0) my_f = p.features.v[g];
        }
        uint count = min(lanes, end - batch);
        for (uint j = 0; j < count; j++) {
            vec2 xy = subgroupBroadcast(my_xy, j);
            vec4 co = subgroupBroadcast(my_co, j);
            float reach = subgroupBroadcast(my_reach, j);
            vec4 cd = subgroupBroadcast(my_cd, j);
            float f = ONE_FEATURE != 0 ? subgroupBroadcast(my_f, j) : 0.0;
            lane_finished = true;
            for (uint r = 0; r < ROWS; r++) {
                // the rows of a subgroup's lanes are the same on a CPU driver, so this skip is uniform there
                bool in_reach = abs(pixel[r].y - xy.y) <= reach;
                // With AFTER_REMOVAL both states take the one alpha, and the removed Gaussians
                // (feature 1) blend in the original only. (Keeping one state until a removed
                // Gaussian first blends at the pixel, and the second only from there, was slower on
                // lavapipe, whose lanes take both branches: the hull's redraws of the statue
                // `images_2` 4.2 -> 5.2-5.5 s.)
                bool after_blends = AFTER_REMOVAL != 0 && f != 1.0 && !finished2[r];
                if (in_reach && (!finished[r] || after_blends)) {
                    float alpha = gaussian_alpha(pixel[r], xy, co);
                    if (!finished[r]) {
                        float w = take_weight(alpha, T[r], finished[r]);
                        if (w > 0.0) {
                            C[r] += w * cd.rgb;
                            D[r] += w * cd.w;
                            W[r] += w;
                            if (ONE_FEATURE != 0) F[r] += AFTER_REMOVAL != 0 ? (f == 1.0 ? w : 0.0) : w * f;
                            if (MEDIAN_DEPTH != 0 && M[r] < 0.0 && T[r] <= 0.5) M[r] = cd.w;
                            n_contrib[r] = batch + j + 1;
                        }
                    }
                    if (after_blends) {
                        float w = take_weight(alpha, T2[r], finished2[r]);
                        if (w > 0.0) {
                            C2[r] += w * cd.rgb;
                            D2[r] += w * cd.w;
                            W2[r] += w;
                            if (f == 2.0) F2[r] += w;
                            if (MEDIAN_DEPTH != 0 && M2[r] < 0.0 && T2[r] <= 0.5) M2[r] = cd.w;
                        }
                    }
                }
                lane_finished = lane_finished && finished[r] && (AFTER_REMOVAL == 0 || finished2[r]);
            }
        }
    }
    uint hw = p.width * p.height;
    for (uint r = 0; r < ROWS; r++) {
        uvec2 pix = uvec2(tx * TILE + gl_LocalInvocationID.x, ty * TILE + gl_LocalInvocationID.y * ROWS + r);
        if (pix.x >= p.width || pix.y >= p.height) continue;
        uint pi = pix.y * p.width + pix.x;
        vec3 rgb = C[r] + T[r] * vec3(p.background[0], p.background[1], p.background[2]);
        p.out_rgb.v[pi] = rgb.r;
        p.out_rgb.v[hw + pi] = rgb.g;
        p.out_rgb.v[2 * hw + pi] = rgb.b;
        p.out_alpha.v[pi] = 1.0 - T[r];
        p.out_depth.v[pi] = D[r];
        p.out_expected_depth.v[pi] = D[r] / max(W[r], 1e-10);
        // a pixel never half opaque has no median: its expected depth stands in, computed again
        // rather than kept in a temporary, which slowed the default variant's blend by 2.5 % on
        // lavapipe (bench/JOURNAL.md, 2026-11-30, 03:14)
        if (MEDIAN_DEPTH != 0) p.out_median_depth.v[pi] = M[r] >= 0.0 ? M[r] : D[r] / max(W[r], 1e-10);
        p.out_final_t.v[pi] = T[r];
        p.out_n_contrib.v[pi] = n_contrib[r];
        if (ONE_FEATURE != 0) p.out_features.v[pi] = F[r];
        if (AFTER_REMOVAL != 0) {
            // planes: R, G, B, alpha, expected depth, median depth, kept objects' weight
            vec3 rgb2 = C2[r] + T2[r] * vec3(p.background[0], p.background[1], p.background[2]);
            float expected2 = D2[r] / max(W2[r], 1e-10);
            p.out_after.v[pi] = rgb2.r;
            p.out_after.v[hw + pi] = rgb2.g;
            p.out_after.v[2 * hw + pi] = rgb2.b;
            p.out_after.v[3 * hw + pi] = 1.0 - T2[r];
            p.out_after.v[4 * hw + pi] = expected2;
            if (MEDIAN_DEPTH != 0) p.out_after.v[5 * hw + pi] = M2[r] >= 0.0 ? M2[r] : expected2;
            p.out_after.v[6 * hw + pi] = F2[r];
        }
    }
}
