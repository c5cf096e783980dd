// The chain rule of projection backward for one Gaussian, shared by project_backward.comp (which
// accumulates the result into the parameter gradients) and project_backward_adam.comp (which feeds
// it straight to Adam): from the per-view gradients of the 2D mean, conic, activated opacity, color
// and depth to the stored parameters (mean, log scale, quaternion, opacity logit, SH coefficients,
// including the view-direction path of SH). Reads the per-view gradients (the host zeroes them
// before each view's blend backward) and updates the densification statistics. The including
// shader enables GL_EXT_shader_atomic_float unless NO_FLOAT_ATOMICS.
#include "common.glsl"
#include "render_params.glsl"
#include "backward_params.glsl"
#include "sh.glsl"
#include "quat.glsl"

// dL/d(stored parameters) of one Gaussian in one view. The SH gradient is separable: coefficient
// k of channel c gets basis[k] * color_raw[c] for k < bands, and nothing for k >= bands.
struct ParamGrads {
    vec3 mean;
    vec3 log_scale;
    vec4 quat;
    float opacity_logit;
    vec3 color_raw;   // dL/d(raw SH color) (zero where the color clamp is active)
    float basis[16];
    uint bands;       // SH coefficients in use at the rendered degree (SH_BANDS), 0 when culled
    // The Gaussian's stored mean, log scales, quaternion and DC coefficients, read once here
    // whether or not the view culled it, so that the fused Adam step need not read them again.
    vec3 mean_value;
    vec3 log_scale_value;
    vec4 quat_value;
    vec3 dc_value;
};

// d(basis_k)/d(direction), rows k = 0..15, for the unit direction d.
void sh_basis_grad(vec3 d, uint degree, out vec3 g[16]) {
    for (int i = 0; i < 16; i++) g[i] = vec3(0.0);
    if (degree < 1) return;
    float x = d.x, y = d.y, z = d.z;
    g[1] = vec3(0.0, -SH_C1, 0.0);
    g[2] = vec3(0.0, 0.0, SH_C1);
    g[3] = vec3(-SH_C1, 0.0, 0.0);
    if (degree < 2) return;
    float xx = x * x, yy = y * y, zz = z * z;
    g[4] = SH_C2[0] * vec3(y, x, 0.0);
    g[5] = SH_C2[1] * vec3(0.0, z, y);
    g[6] = SH_C2[2] * vec3(-2.0 * x, -2.0 * y, 4.0 * z);
    g[7] = SH_C2[3] * vec3(z, 0.0, x);
    g[8] = SH_C2[4] * vec3(2.0 * x, -2.0 * y, 0.0);
    if (degree < 3) return;
    g[9] = SH_C3[0] * vec3(6.0 * x * y, 3.0 * xx - 3.0 * yy, 0.0);
    g[10] = SH_C3[1] * vec3(y * z, x * z, x * y);
    g[11] = SH_C3[2] * vec3(-2.0 * x * y, 4.0 * zz - xx - 3.0 * yy, 8.0 * y * z);
    g[12] = SH_C3[3] * vec3(-6.0 * x * z, -6.0 * y * z, 6.0 * zz - 3.0 * xx - 3.0 * yy);
    g[13] = SH_C3[4] * vec3(4.0 * zz - 3.0 * xx - yy, -2.0 * x * y, 8.0 * x * z);
    g[14] = SH_C3[5] * vec3(2.0 * x * z, -2.0 * y * z, xx - yy);
    g[15] = SH_C3[6] * vec3(3.0 * xx - 3.0 * yy, -6.0 * x * y, 0.0);
}

// The gradients of Gaussian g in the view just blended; false (and no gradient) when the view
// culled it.
bool parameter_grads(RenderParams p, BackwardParams b, uint g, out ParamGrads r) {
    r.mean = vec3(0.0);
    r.log_scale = vec3(0.0);
    r.quat = vec4(0.0);
    r.opacity_logit = 0.0;
    r.color_raw = vec3(0.0);
    r.bands = 0;
    uint K = p.sh_coeffs;
    r.mean_value = Vec3View(p.means).v[g];
    r.log_scale_value = Vec3View(p.log_scales).v[g];
    r.quat_value = Vec4View(p.quats).v[g];
    r.dc_value = Vec3View(p.sh).v[g * K];
    if (p.tiles_touched.v[g] == 0) return false;  // culled or off-screen: no gradient

    vec2 dl_dxy = vec2(grad_read(b.grad_xy, 2 * g), grad_read(b.grad_xy, 2 * g + 1));
    vec3 dl_dconic = vec3(grad_read(b.grad_conic, 3 * g), grad_read(b.grad_conic, 3 * g + 1), grad_read(b.grad_conic, 3 * g + 2));
    float dl_dopacity = grad_read(b.grad_opacity, g);
    vec3 dl_dcolor = vec3(grad_read(b.grad_color, 3 * g), grad_read(b.grad_color, 3 * g + 1), grad_read(b.grad_color, 3 * g + 2));
    float dl_dz = grad_read(b.grad_depth, g);

    // densification statistic: |dL/d(mean2d)| in NDC units (pixel gradient times W/2, H/2)
    b.grad_xy_norm_sum.v[g] += length(dl_dxy * vec2(0.5 * float(p.width), 0.5 * float(p.height)));
    b.grad_xy_views.v[g] += 1;

    // ---- recompute the forward quantities
    vec3 m = r.mean_value;
    mat3 Rv = mat3(p.viewmat[0], p.viewmat[4], p.viewmat[8],
                   p.viewmat[1], p.viewmat[5], p.viewmat[9],
                   p.viewmat[2], p.viewmat[6], p.viewmat[10]);
    vec3 pv = Rv * m + vec3(p.viewmat[3], p.viewmat[7], p.viewmat[11]);
    vec4 q_raw = r.quat_value;
    float q_norm = length(q_raw);
    vec4 q = q_raw / q_norm;
    float w = q.x, x = q.y, y = q.z, z = q.w;
    mat3 Rq = quat_to_rotation(q);
    vec3 s = exp(r.log_scale_value);
    mat3 M = Rq * mat3(s.x, 0, 0, 0, s.y, 0, 0, 0, s.z);
    mat3 cov_world = M * transpose(M);
    mat3 cov_view = Rv * cov_world * transpose(Rv);
    float lim_x = 1.3 * p.tan_fovx, lim_y = 1.3 * p.tan_fovy;
    float rz = 1.0 / pv.z, rz2 = rz * rz;
    float ux = pv.x * rz, uy = pv.y * rz;
    bool free_x = abs(ux) <= lim_x, free_y = abs(uy) <= lim_y;
    float cux = clamp(ux, -lim_x, lim_x), cuy = clamp(uy, -lim_y, lim_y);
    mat3x2 J = mat3x2(p.fx * rz, 0.0, 0.0, p.fy * rz, -p.fx * cux * rz, -p.fy * cuy * rz);
    vec4 conic_opacity = Vec4View(p.conic_opacity).v[g];
    vec3 conic = conic_opacity.xyz;
    float opacity = conic_opacity.w;

    vec3 dl_dpv = vec3(0.0);
    vec3 dl_dm = vec3(0.0);

    // ---- opacity
    float dl_dlogit = dl_dopacity * opacity * (1.0 - opacity);

    // ---- color from SH, with the view-direction path
    vec3 dir_raw = m - vec3(p.campos[0], p.campos[1], p.campos[2]);
    float dir_len = length(dir_raw);
    vec3 dir = dir_raw / dir_len;
    sh_basis(dir, SH_DEGREE, r.basis);
    Vec3View sh = Vec3View(p.sh);
    vec3 raw = r.basis[0] * r.dc_value;
    for (uint k = 1; k < SH_BANDS; k++) raw += r.basis[k] * sh.v[g * K + k];
    // max(raw + 0.5, 0): no gradient where the clamp is active
    vec3 dl_draw = mix(vec3(0.0), dl_dcolor, greaterThanEqual(raw + 0.5, vec3(0.0)));
    vec3 basis_grad[16];
    sh_basis_grad(dir, SH_DEGREE, basis_grad);
    vec3 dl_ddir = vec3(0.0);
    for (uint k = 1; k < SH_BANDS; k++) dl_ddir += dot(dl_draw, sh.v[g * K + k]) * basis_grad[k];
    dl_dm += (dl_ddir - dir * dot(dir, dl_ddir)) / dir_len;

    // ---- depth and 2D mean
    dl_dpv.z += dl_dz;
    dl_dpv.x += p.fx * rz * dl_dxy.x;
    dl_dpv.y += p.fy * rz * dl_dxy.y;
    dl_dpv.z += -p.fx * pv.x * rz2 * dl_dxy.x - p.fy * pv.y * rz2 * dl_dxy.y;

    // ---- conic = inverse(cov2d): dcov2d = -conic G conic, G the symmetric gradient matrix
    mat2 C = mat2(conic.x, conic.y, conic.y, conic.z);
    mat2 G = mat2(dl_dconic.x, 0.5 * dl_dconic.y, 0.5 * dl_dconic.y, dl_dconic.z);
    mat2 dl_dcov2d = -(C * G * C);
    // cov2d = J cov_view J^T (+0.3 I)
    mat3 dl_dcov_view = transpose(J) * dl_dcov2d * J;
    mat3x2 dl_dJ = 2.0 * dl_dcov2d * J * cov_view;
    // J = [[fx/z, 0, -fx u_x / z], [0, fy/z, -fy u_y / z]] with u = clamp(x/z); columns of mat3x2
    float dJ00 = dl_dJ[0][0], dJ11 = dl_dJ[1][1], dJ02 = dl_dJ[2][0], dJ12 = dl_dJ[2][1];
    dl_dpv.z += -p.fx * rz2 * dJ00 - p.fy * rz2 * dJ11;
    if (free_x) {
        dl_dpv.x += -p.fx * rz2 * dJ02;
        dl_dpv.z += 2.0 * p.fx * pv.x * rz2 * rz * dJ02;
    } else {
        dl_dpv.z += p.fx * cux * rz2 * dJ02;
    }
    if (free_y) {
        dl_dpv.y += -p.fy * rz2 * dJ12;
        dl_dpv.z += 2.0 * p.fy * pv.y * rz2 * rz * dJ12;
    } else {
        dl_dpv.z += p.fy * cuy * rz2 * dJ12;
    }
    dl_dm += transpose(Rv) * dl_dpv;

    // cov_view = Rv cov_world Rv^T; cov_world = M M^T, M = Rq S
    mat3 dl_dcov_world = transpose(Rv) * dl_dcov_view * Rv;
    mat3 dl_dM = 2.0 * dl_dcov_world * M;
    vec3 dl_ds = vec3(dot(Rq[0], dl_dM[0]), dot(Rq[1], dl_dM[1]), dot(Rq[2], dl_dM[2]));
    mat3 dR = mat3(dl_dM[0] * s.x, dl_dM[1] * s.y, dl_dM[2] * s.z);  // columns scaled
    // dR[col][row]: R_rc = dR[c][r]
    float dR00 = dR[0][0], dR01 = dR[1][0], dR02 = dR[2][0];
    float dR10 = dR[0][1], dR11 = dR[1][1], dR12 = dR[2][1];
    float dR20 = dR[0][2], dR21 = dR[1][2], dR22 = dR[2][2];
    vec4 dl_dq = 2.0 * vec4(
        -z * dR01 + y * dR02 + z * dR10 - x * dR12 - y * dR20 + x * dR21,
        y * dR01 + z * dR02 + y * dR10 - 2.0 * x * dR11 - w * dR12 + z * dR20 + w * dR21 - 2.0 * x * dR22,
        -2.0 * y * dR00 + x * dR01 + w * dR02 + x * dR10 + z * dR12 - w * dR20 + z * dR21 - 2.0 * y * dR22,
        -2.0 * z * dR00 - w * dR01 + x * dR02 + w * dR10 - 2.0 * z * dR11 + y * dR12 + x * dR20 + y * dR21);
    // through the normalization q / |q|
    dl_dq = (dl_dq - q * dot(q, dl_dq)) / q_norm;

    r.mean = dl_dm;
    r.log_scale = dl_ds * s;
    r.quat = dl_dq;
    r.opacity_logit = dl_dlogit;
    r.color_raw = dl_draw;
    r.bands = SH_BANDS;
    return true;
}
