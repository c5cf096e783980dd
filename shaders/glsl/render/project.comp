#version 460
// Projection + SH evaluation, one thread per Gaussian: view-space depth, 2D mean, conic with the 0.3
// low-pass dilation, activated opacity, SH color, conservative tile rectangle and the exact number of
// tiles the Gaussian touches (counted with the same test the emit pass uses). Also writes the depth
// sort key. Conventions: shared/docs/conventions.md.
#include "common.glsl"
#include "render_params.glsl"
#include "sh.glsl"
#include "quat.glsl"
#include "tile_binning.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push { RenderParams p; };

void cull(uint g) {
    p.tiles_touched.v[g] = 0;
    p.depth_keys.v[g] = 0x7fffffffu;
    p.depth.v[g] = 0.0;
    UVec4View(p.tile_rect).v[g] = uvec4(0);
}

void main() {
    uint g = linear_group_id() * 256 + gl_LocalInvocationID.x;
    if (g >= p.num_gaussians) return;
    p.depth_order.v[g] = g;  // identity values for the depth sort

    vec3 m = Vec3View(p.means).v[g];
    mat3 R_view = mat3(p.viewmat[0], p.viewmat[4], p.viewmat[8],   // column-major: columns of R
                       p.viewmat[1], p.viewmat[5], p.viewmat[9],
                       p.viewmat[2], p.viewmat[6], p.viewmat[10]);
    vec3 t_view = vec3(p.viewmat[3], p.viewmat[7], p.viewmat[11]);
    vec3 pv = R_view * m + t_view;
    if (!(pv.z > p.near_plane)) { cull(g); return; }

    // 3D covariance R S S^T R^T from the normalized quaternion and exp(log scale)
    vec4 q = Vec4View(p.quats).v[g];
    q = q / length(q);
    mat3 Rq = quat_to_rotation(q);
    vec3 s = exp(Vec3View(p.log_scales).v[g]);
    mat3 M = Rq * mat3(s.x, 0, 0, 0, s.y, 0, 0, 0, s.z);
    mat3 cov_world = M * transpose(M);
    mat3 cov_view = R_view * cov_world * transpose(R_view);

    // perspective Jacobian with x/z, y/z clamped to 1.3 tan(fov/2)
    float lim_x = 1.3 * p.tan_fovx, lim_y = 1.3 * p.tan_fovy;
    float tx = clamp(pv.x / pv.z, -lim_x, lim_x) * pv.z;
    float ty = clamp(pv.y / pv.z, -lim_y, lim_y) * pv.z;
    float rz = 1.0 / pv.z;
    // J is 2x3; written as the columns of a mat3x2 (3 columns, 2 rows)
    mat3x2 J = mat3x2(p.fx * rz, 0.0, 0.0, p.fy * rz, -p.fx * tx * rz * rz, -p.fy * ty * rz * rz);
    mat2 cov2d = J * cov_view * transpose(J);
    cov2d[0][0] += 0.3;
    cov2d[1][1] += 0.3;
    float det = cov2d[0][0] * cov2d[1][1] - cov2d[0][1] * cov2d[1][0];
    if (!(det > 0.0)) { cull(g); return; }
    vec3 conic = vec3(cov2d[1][1], -cov2d[0][1], cov2d[0][0]) / det;
    vec2 xy = vec2(p.fx * pv.x * rz + p.cx, p.fy * pv.y * rz + p.cy);
    float opacity = 1.0 / (1.0 + exp(-p.opacity_logits.v[g]));

    // conservative pixel-center bounding box of the ellipse, then the exact per-tile test
    float threshold = binning_q_threshold(opacity);
    uint touched = 0;
    uvec4 rect = uvec4(0);
    if (threshold >= 0.0) {
        float rx = sqrt(threshold * cov2d[0][0]) * 1.001 + 1.0;
        float ry = sqrt(threshold * cov2d[1][1]) * 1.001 + 1.0;
        // pixels whose centers (px + 0.5) lie within [xy - r, xy + r]
        float fx0 = ceil(xy.x - rx - 0.5), fx1 = floor(xy.x + rx - 0.5);
        float fy0 = ceil(xy.y - ry - 0.5), fy1 = floor(xy.y + ry - 0.5);
        fx0 = max(fx0, 0.0); fy0 = max(fy0, 0.0);
        fx1 = min(fx1, float(p.width) - 1.0); fy1 = min(fy1, float(p.height) - 1.0);
        if (fx0 <= fx1 && fy0 <= fy1) {
            rect = uvec4(uint(fx0) / TILE, uint(fy0) / TILE, uint(fx1) / TILE + 1, uint(fy1) / TILE + 1);
            uint tx_ = rect.x, ty_ = rect.y;
            for (uint i = 0; i < rect_tiles(rect); i++, next_tile(rect, tx_, ty_))
                if (gaussian_touches_tile(xy, conic, threshold, tx_, ty_, p.width, p.height)) touched++;
        }
    }
    if (touched == 0) rect = uvec4(0);

    // view-dependent color
    vec3 dir = normalize(m - vec3(p.campos[0], p.campos[1], p.campos[2]));
    float basis[16];
    sh_basis(dir, SH_DEGREE, basis);
    uint K = p.sh_coeffs;
    // precise: the sum in this order, no fused multiply-adds. A pipeline specialized to a lower
    // degree must give the same bits as a higher one over zero bands (SceneRenderer renders the
    // learnt degree); NVIDIA's compiler fused the two specializations' sums differently (2.5 ulp).
    precise vec3 color = vec3(0.0);
    Vec3View sh = Vec3View(p.sh);
    for (uint k = 0; k < SH_BANDS; k++) color += basis[k] * sh.v[g * K + k];
    color = max(color + 0.5, vec3(0.0));

    Vec2View(p.xy).v[g] = xy;
    Vec4View(p.conic_opacity).v[g] = vec4(conic, opacity);
    p.depth.v[g] = pv.z;
    Vec3View(p.color).v[g] = color;
    UVec4View(p.tile_rect).v[g] = rect;
    p.tiles_touched.v[g] = touched;
    p.depth_keys.v[g] = touched > 0 ? floatBitsToUint(pv.z) : 0x7fffffffu;
}
