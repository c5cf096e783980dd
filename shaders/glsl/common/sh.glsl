// Real spherical harmonics up to degree 3 in the INRIA basis order (conventions.md).

// The SH degree a pipeline renders with: the frame's RenderParams::sh_degree, to which the host
// specializes the pipeline (render::specialized). As a constant, the bands above it compile away
// and the basis loops unroll into registers; lavapipe would otherwise run every band's code with
// its lanes masked off (it runs both sides of a branch) and keep the basis arrays in memory.
layout(constant_id = 0) const uint SH_DEGREE = 3;
// Basis functions in use, (SH_DEGREE + 1)^2; the host renders at most the stored degree, so the
// scene holds at least this many coefficients per channel.
const uint SH_BANDS = (SH_DEGREE + 1) * (SH_DEGREE + 1);
const float SH_C0 = 0.28209479177387814;
const float SH_C1 = 0.4886025119029199;
const float SH_C2[5] = float[5](1.0925484305920792, -1.0925484305920792, 0.31539156525252005,
                                -1.0925484305920792, 0.5462742152960396);
const float SH_C3[7] = float[7](-0.5900435899266435, 2.890611442640554, -0.4570457994644658,
                                0.3731763325901154, -0.4570457994644658, 1.445305721320277,
                                -0.5900435899266435);

// Basis values for direction d (unit), degree <= 3; unused entries are zero.
void sh_basis(vec3 d, uint degree, out float b[16]) {
    for (int i = 0; i < 16; i++) b[i] = 0.0;
    b[0] = SH_C0;
    if (degree < 1) return;
    float x = d.x, y = d.y, z = d.z;
    b[1] = -SH_C1 * y;
    b[2] = SH_C1 * z;
    b[3] = -SH_C1 * x;
    if (degree < 2) return;
    float xx = x * x, yy = y * y, zz = z * z, xy = x * y, yz = y * z, xz = x * z;
    b[4] = SH_C2[0] * xy;
    b[5] = SH_C2[1] * yz;
    b[6] = SH_C2[2] * (2.0 * zz - xx - yy);
    b[7] = SH_C2[3] * xz;
    b[8] = SH_C2[4] * (xx - yy);
    if (degree < 3) return;
    b[9] = SH_C3[0] * y * (3.0 * xx - yy);
    b[10] = SH_C3[1] * xy * z;
    b[11] = SH_C3[2] * y * (4.0 * zz - xx - yy);
    b[12] = SH_C3[3] * z * (2.0 * zz - 3.0 * xx - 3.0 * yy);
    b[13] = SH_C3[4] * x * (4.0 * zz - xx - yy);
    b[14] = SH_C3[5] * z * (xx - yy);
    b[15] = SH_C3[6] * x * (xx - 3.0 * yy);
}
