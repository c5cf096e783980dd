#version 460
// Backward of blend.comp. One 16x16 workgroup per tile (each of its subgroups on its own) walks the
// tile's intersections back to front, recovering each contributor's transmittance from the final one
// (T_i = T_{i+1} / (1 - alpha_i)) and the sums of what lies behind it, so
//   dC/dalpha_i = T_i c_i - (sum_{j>i} w_j c_j + T_final bg) / (1 - alpha_i)
// and likewise for alpha (1 - T_final), accumulated depth and the weight sum behind expected depth.
// Each invocation owns ROWS x COLS pixels of the tile (the workgroup is 16/COLS x 16/ROWS), so a
// subgroup covers that many times more pixels: a Gaussian's gradients are summed over the lane's
// pixels in registers, then over the subgroup (any size), and added with one atomic per subgroup
// and value, by the lane that loaded the Gaussian, once its batch is done. Subgroups where the
// Gaussian contributed to no pixel skip both. The fewer subgroups a Gaussian meets, the fewer
// reductions and atomics it costs (with a pixel per invocation, two thirds of the pass on lavapipe).
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_vote : require
#extension GL_KHR_shader_subgroup_ballot : require
#ifndef NO_FLOAT_ATOMICS
#extension GL_EXT_shader_atomic_float : require
#endif
#include "common.glsl"
#include "render_params.glsl"
#include "backward_params.glsl"
#include "blend_common.glsl"

// ROWS x COLS pixels per invocation and the workgroup's 16/COLS x 16/ROWS are set per device by
// render::BlendLayout. An invocation's pixels are its rows in COLS columns 16/COLS apart.
layout(constant_id = 0) const uint ROWS = 1;
layout(constant_id = 1) const uint COLS = 1;
layout(constant_id = 2) const uint GROUP_WIDTH = 16;
layout(constant_id = 3) const uint GROUP_HEIGHT = 16;
const uint PIXELS = ROWS * COLS;
// COLOR_ONLY = 1 when only the color has upstream gradients (training's loss, the refinement's):
// the alpha, depth and weight terms, all zero then, are left out, and with them five of an
// invocation's per-pixel arrays (on lavapipe an invocation's ROWS x COLS pixels live in registers
// and spill: blend backward 227-254 -> 204-219 ms per iteration of the statue's refinement).
layout(constant_id = 4) const uint COLOR_ONLY = 0;
layout(local_size_x_id = 2, local_size_y_id = 3) in;
layout(push_constant) uniform Push { RenderParams p; BackwardParams b; };

void main() {
    uint tile = tile_id();
    if (tile >= p.tiles_x * p.tiles_y) return;
    uint tx = tile % p.tiles_x, ty = tile / p.tiles_x;
    uint hw = p.width * p.height;
    vec3 bg = vec3(p.background[0], p.background[1], p.background[2]);

    // per owned pixel: position, the forward's final state, the upstream gradients, and the running
    // transmittance and sums of what lies behind (back to front)
    vec2 pixel[PIXELS];
    uint last[PIXELS];
    float t_final[PIXELS], T[PIXELS], dl_da[PIXELS], dl_dd[PIXELS], dl_dw[PIXELS], behind_depth[PIXELS],
        behind_weight[PIXELS];
    vec3 dl_dc[PIXELS], behind_color[PIXELS];
    uint last_max = 0;
    for (uint r = 0; r < PIXELS; r++) {
        uvec2 pix = uvec2(tx * TILE + gl_LocalInvocationID.x + (r / ROWS) * GROUP_WIDTH,
                          ty * TILE + gl_LocalInvocationID.y * ROWS + r % ROWS);
        bool inside = pix.x < p.width && pix.y < p.height;
        uint pi = inside ? pix.y * p.width + pix.x : 0;
        pixel[r] = vec2(pix) + 0.5;
        t_final[r] = inside ? p.out_final_t.v[pi] : 1.0;
        last[r] = inside ? p.out_n_contrib.v[pi] : 0;
        last_max = max(last_max, last[r]);
        dl_dc[r] = inside ? vec3(b.dl_drgb.v[pi], b.dl_drgb.v[hw + pi], b.dl_drgb.v[2 * hw + pi]) : vec3(0.0);
        dl_da[r] = (COLOR_ONLY == 0 && inside && b.use_alpha != 0) ? b.dl_dalpha.v[pi] : 0.0;
        // expected depth ED = D / W folds into gradients of D and of W = sum w_i (= 1 - T_final)
        dl_dd[r] = 0.0;
        dl_dw[r] = 0.0;
        if (COLOR_ONLY == 0 && inside && b.use_depth != 0) {
            float w_total = 1.0 - t_final[r];
            float d_total = p.out_depth.v[pi];
            float dl_ded = b.dl_dexpected_depth.v[pi];
            dl_dd[r] = b.dl_ddepth.v[pi];
            if (w_total > 1e-10) {
                dl_dd[r] += dl_ded / w_total;
                dl_dw[r] = -dl_ded * d_total / (w_total * w_total);
            }
        }
        T[r] = t_final[r];
        behind_color[r] = t_final[r] * bg;
        behind_depth[r] = 0.0;
        behind_weight[r] = 0.0;
    }

    // Each subgroup walks the list on its own, from the last Gaussian any of its pixels blended, a
    // subgroup's worth at a time: lane l loads the batch's l-th Gaussian into registers and every lane
    // takes them back to front by broadcast (on lavapipe a shared load is a loop over the lanes, a
    // broadcast one register move: 237 -> 129 ms on a trained 31.5k scene at 256x192). No shared
    // memory and no barriers. `lanes` counts the lanes present: a workgroup smaller than a subgroup
    // fills only the low lanes.
    uvec2 range = UVec2View(p.tile_ranges).v[tile];
    uint start = range.x, end = range.y;
    end = min(end, max(subgroupMax(last_max), start));
    uint lanes = subgroupBallotBitCount(subgroupBallot(true));
    for (uint batch_end = end; batch_end > start;) {
        uint count = min(lanes, batch_end - start);
        uint batch_start = batch_end - count;
        uint my_g = 0;
        vec2 my_xy = vec2(0.0);
        vec4 my_co = vec4(0.0), my_cd = vec4(0.0);
        float my_reach = -1.0;
        if (gl_SubgroupInvocationID < count) {
            my_g = p.isect_gauss.v[batch_start + gl_SubgroupInvocationID];
            my_xy = Vec2View(p.xy).v[my_g];
            my_co = Vec4View(p.conic_opacity).v[my_g];
            my_cd = vec4(Vec3View(p.color).v[my_g], p.depth.v[my_g]);
            my_reach = row_reach(my_co);
        }
        // The subgroup's sums for the batch's j-th Gaussian end up in lane j, which adds them after
        // the batch: the lanes' atomics go out together, not one elected lane per Gaussian (on
        // lavapipe each atomic is a loop over the lanes, whichever are active).
        vec2 my_g_xy = vec2(0.0);
        vec3 my_g_conic = vec3(0.0), my_g_color = vec3(0.0);
        float my_g_opacity = 0.0, my_g_depth = 0.0;
        for (uint jj = count; jj > 0; jj--) {
            uint j = jj - 1;
            uint idx = batch_start + j;
            vec4 co = subgroupBroadcast(my_co, j);
            vec2 xy = subgroupBroadcast(my_xy, j);
            vec4 cd = subgroupBroadcast(my_cd, j);
            float reach = subgroupBroadcast(my_reach, j);
            vec2 g_xy = vec2(0.0);
            vec3 g_conic = vec3(0.0);
            float g_opacity = 0.0, g_depth = 0.0;
            vec3 g_color = vec3(0.0);
            bool contributed = false;
            for (uint r = 0; r < PIXELS; r++) {
                vec2 d = xy - pixel[r];
                // the rows of a subgroup's lanes are the same, so the reach test is uniform over it
                if (idx >= last[r] || abs(d.y) > reach) continue;
                float power = -0.5 * (co.x * d.x * d.x + co.z * d.y * d.y) - co.y * d.x * d.y;
                // the forward decisions, recomputed identically (see blend_weight)
                if (power > 0.0 || power < POWER_SKIP) continue;
                float gauss = exp(power);
                float raw = co.w * gauss;
                float alpha = min(ALPHA_MAX, raw);
                if (alpha < ALPHA_MIN) continue;
                contributed = true;
                float one_minus = 1.0 - alpha;
                T[r] = T[r] / one_minus;
                float w = alpha * T[r];
                vec3 c = cd.rgb;
                float z = cd.w;
                g_color += w * dl_dc[r];
                float dl_dalpha = dot(dl_dc[r], T[r] * c - behind_color[r] / one_minus);
                if (COLOR_ONLY == 0) {
                    g_depth += w * dl_dd[r];
                    dl_dalpha += dl_da[r] * t_final[r] / one_minus
                               + dl_dd[r] * (T[r] * z - behind_depth[r] / one_minus)
                               + dl_dw[r] * (T[r] - behind_weight[r] / one_minus);
                    behind_depth[r] += w * z;
                    behind_weight[r] += w;
                }
                behind_color[r] += w * c;
                if (raw < ALPHA_MAX) {  // no gradient through the 0.99 clamp
                    g_opacity += dl_dalpha * gauss;
                    float dl_dpower = dl_dalpha * alpha;
                    g_conic += dl_dpower * vec3(-0.5 * d.x * d.x, -d.x * d.y, -0.5 * d.y * d.y);
                    g_xy += -dl_dpower * vec2(co.x * d.x + co.y * d.y, co.y * d.x + co.z * d.y);
                }
            }
            // j is uniform, so every lane of the subgroup reaches these reductions together. Most
            // (Gaussian, subgroup) pairs of a tile have no contribution at all: their sums are zero.
            if (!subgroupAny(contributed)) continue;
            g_xy = subgroupAdd(g_xy);
            g_conic = subgroupAdd(g_conic);
            g_opacity = subgroupAdd(g_opacity);
            g_color = subgroupAdd(g_color);
            g_depth = subgroupAdd(g_depth);
            if (gl_SubgroupInvocationID == j) {
                my_g_xy = g_xy;
                my_g_conic = g_conic;
                my_g_opacity = g_opacity;
                my_g_color = g_color;
                my_g_depth = g_depth;
            }
        }
        if (my_g_opacity != 0.0 || any(notEqual(my_g_color, vec3(0.0))) || my_g_depth != 0.0
            || any(notEqual(my_g_xy, vec2(0.0))) || any(notEqual(my_g_conic, vec3(0.0)))) {
            uint g = my_g;
            grad_add(b.grad_xy, 2 * g, my_g_xy.x);
            grad_add(b.grad_xy, 2 * g + 1, my_g_xy.y);
            grad_add(b.grad_conic, 3 * g, my_g_conic.x);
            grad_add(b.grad_conic, 3 * g + 1, my_g_conic.y);
            grad_add(b.grad_conic, 3 * g + 2, my_g_conic.z);
            grad_add(b.grad_opacity, g, my_g_opacity);
            grad_add(b.grad_color, 3 * g, my_g_color.x);
            grad_add(b.grad_color, 3 * g + 1, my_g_color.y);
            grad_add(b.grad_color, 3 * g + 2, my_g_color.z);
            if (COLOR_ONLY == 0) grad_add(b.grad_depth, g, my_g_depth);  // else zero, as filled
        }
        batch_end = batch_start;
    }
}
