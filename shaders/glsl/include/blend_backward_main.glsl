// Backward of blend.comp. One 16x16 workgroup per tile walks the tile's intersections back to front,
// recovering each contributor's transmittance from the final one (T_i = T_{i+1} / (1 - alpha_i)) and the
// sums of what lies behind it, so
//   dC/dalpha_i = T_i c_i - (sum_{j>i} w_j c_j + T_final bg) / (1 - alpha_i)
// and likewise for alpha (1 - T_final), accumulated depth and the weight sum behind expected depth.
// Per-pair gradients are summed over the subgroup (any size) and added with one atomic per subgroup;
// subgroups where the Gaussian contributed to no pixel skip both.
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_vote : require
#ifndef NO_FLOAT_ATOMICS
#extension GL_EXT_shader_atomic_float : require
#endif
#include "common.glsl"
#include "render_params.glsl"
#include "backward_params.glsl"
#include "blend_common.glsl"

layout(local_size_x = 16, local_size_y = 16) in;
layout(push_constant) uniform Push { RenderParams p; BackwardParams b; };

const uint BATCH = 256;
shared vec2 s_xy[BATCH];
shared vec4 s_conic_opacity[BATCH];
shared vec4 s_color_depth[BATCH];
shared uint s_gauss[BATCH];
shared uint s_last;  // largest n_contrib of the tile: nothing after it contributed anywhere

void main() {
    uint tile = tile_id();
    if (tile >= p.tiles_x * p.tiles_y) return;
    uint tx = tile % p.tiles_x, ty = tile / p.tiles_x;
    uvec2 pix = uvec2(tx * TILE + gl_LocalInvocationID.x, ty * TILE + gl_LocalInvocationID.y);
    bool inside = pix.x < p.width && pix.y < p.height;
    vec2 pixel = vec2(pix) + 0.5;
    uint local = gl_LocalInvocationIndex;
    uint hw = p.width * p.height;
    uint pi = inside ? pix.y * p.width + pix.x : 0;

    uint start = p.tile_ranges.v[2 * tile], end = p.tile_ranges.v[2 * tile + 1];
    float t_final = inside ? p.out_final_t.v[pi] : 1.0;
    uint last = inside ? p.out_n_contrib.v[pi] : 0;
    vec3 bg = vec3(p.background[0], p.background[1], p.background[2]);
    vec3 dl_dc = inside ? vec3(b.dl_drgb.v[pi], b.dl_drgb.v[hw + pi], b.dl_drgb.v[2 * hw + pi]) : vec3(0.0);
    float dl_da = (inside && b.use_alpha != 0) ? b.dl_dalpha.v[pi] : 0.0;
    // expected depth ED = D / W folds into gradients of D and of W = sum w_i (= 1 - T_final)
    float dl_dd = 0.0, dl_dw = 0.0;
    if (inside && b.use_depth != 0) {
        float w_total = 1.0 - t_final;
        float d_total = p.out_depth.v[pi];
        float dl_ded = b.dl_dexpected_depth.v[pi];
        dl_dd = b.dl_ddepth.v[pi];
        if (w_total > 1e-10) {
            dl_dd += dl_ded / w_total;
            dl_dw = -dl_ded * d_total / (w_total * w_total);
        }
    }

    if (local == 0) s_last = 0;
    barrier();
    atomicMax(s_last, last);
    barrier();
    end = min(end, max(s_last, start));

    float T = t_final;
    vec3 behind_color = t_final * bg;
    float behind_depth = 0.0, behind_weight = 0.0;

    for (uint batch_end = end; batch_end > start;) {
        uint count = min(BATCH, batch_end - start);
        uint batch_start = batch_end - count;
        barrier();
        if (local < count) {
            uint g = p.isect_gauss.v[batch_start + local];
            s_gauss[local] = g;
            s_xy[local] = vec2(p.xy.v[2 * g], p.xy.v[2 * g + 1]);
            s_conic_opacity[local] = vec4(p.conic_opacity.v[4 * g], p.conic_opacity.v[4 * g + 1],
                                          p.conic_opacity.v[4 * g + 2], p.conic_opacity.v[4 * g + 3]);
            s_color_depth[local] = vec4(p.color.v[3 * g], p.color.v[3 * g + 1], p.color.v[3 * g + 2], p.depth.v[g]);
        }
        barrier();
        for (uint jj = count; jj > 0; jj--) {
            uint j = jj - 1;
            uint idx = batch_start + j;
            vec2 g_xy = vec2(0.0);
            vec3 g_conic = vec3(0.0);
            float g_opacity = 0.0, g_depth = 0.0;
            vec3 g_color = vec3(0.0);
            bool contributed = false;
            if (idx < last) {
                vec4 co = s_conic_opacity[j];
                vec2 d = s_xy[j] - pixel;
                float power = -0.5 * (co.x * d.x * d.x + co.z * d.y * d.y) - co.y * d.x * d.y;
                // the forward decisions, recomputed identically (see blend_weight)
                if (power <= 0.0 && power >= POWER_SKIP) {
                    float gauss = exp(power);
                    float raw = co.w * gauss;
                    float alpha = min(ALPHA_MAX, raw);
                    if (alpha >= ALPHA_MIN) {
                        contributed = true;
                        float one_minus = 1.0 - alpha;
                        T = T / one_minus;
                        float w = alpha * T;
                        vec3 c = s_color_depth[j].rgb;
                        float z = s_color_depth[j].w;
                        g_color = w * dl_dc;
                        g_depth = w * dl_dd;
                        float dl_dalpha = dot(dl_dc, T * c - behind_color / one_minus)
                                        + dl_da * t_final / one_minus
                                        + dl_dd * (T * z - behind_depth / one_minus)
                                        + dl_dw * (T - behind_weight / one_minus);
                        behind_color += w * c;
                        behind_depth += w * z;
                        behind_weight += w;
                        if (raw < ALPHA_MAX) {  // no gradient through the 0.99 clamp
                            g_opacity = dl_dalpha * gauss;
                            float dl_dpower = dl_dalpha * alpha;
                            g_conic = dl_dpower * vec3(-0.5 * d.x * d.x, -d.x * d.y, -0.5 * d.y * d.y);
                            g_xy = -dl_dpower * vec2(co.x * d.x + co.y * d.y, co.y * d.x + co.z * d.y);
                        }
                    }
                }
            }
            // j is uniform, so every lane of the subgroup reaches these reductions together. Most
            // (Gaussian, subgroup) pairs of a tile have no contribution at all: one vote skips their ten
            // reductions and the atomics (the sums would be zero, so nothing else changes).
            if (!subgroupAny(contributed)) continue;
            g_xy = subgroupAdd(g_xy);
            g_conic = subgroupAdd(g_conic);
            g_opacity = subgroupAdd(g_opacity);
            g_color = subgroupAdd(g_color);
            g_depth = subgroupAdd(g_depth);
            if (subgroupElect() && (g_opacity != 0.0 || any(notEqual(g_color, vec3(0.0))) || g_depth != 0.0
                                    || any(notEqual(g_xy, vec2(0.0))))) {
                uint g = s_gauss[j];
                grad_add(b.grad_xy, 2 * g, g_xy.x);
                grad_add(b.grad_xy, 2 * g + 1, g_xy.y);
                grad_add(b.grad_conic, 3 * g, g_conic.x);
                grad_add(b.grad_conic, 3 * g + 1, g_conic.y);
                grad_add(b.grad_conic, 3 * g + 2, g_conic.z);
                grad_add(b.grad_opacity, g, g_opacity);
                grad_add(b.grad_color, 3 * g, g_color.x);
                grad_add(b.grad_color, 3 * g + 1, g_color.y);
                grad_add(b.grad_color, 3 * g + 2, g_color.z);
                grad_add(b.grad_depth, g, g_depth);
            }
        }
        batch_end = batch_start;
    }
}
