//! Dense f64 CPU reference rasterizer: every Gaussian is tested at every pixel, in depth order, with
//! exactly the conventions the GPU passes follow (shared/docs/conventions.md). Used by the tests to
//! check the tiled GPU result; not a product path.
//!
//! Besides the images it marks *ambiguous* pixels: where a discrete decision (alpha >= 1/255,
//! T >= 1e-4, the order of two nearly equal depths) is so close to its threshold that float32
//! evaluation may legitimately decide the other way. Comparisons skip those pixels, and tests
//! assert that they are rare.

use crate::scene::camera::rotation_from_qvec;
use crate::scene::{Camera, GaussianScene, SH_C0, SH_C1, SH_C2, SH_C3};

/// A Gaussian projected in f64.
#[derive(Clone, Debug)]
pub struct ProjectedGaussian {
    pub index: usize,
    pub xy: [f64; 2],
    pub conic: [f64; 3],
    pub cov2d: [f64; 3],
    pub opacity: f64,
    pub depth: f64,
    /// Bound on the float32 rounding error of `depth` (a few ulps of its largest term).
    pub depth_error: f64,
    pub color: [f64; 3],
}

impl ProjectedGaussian {
    /// The box [x0, x1] x [y0, y1] of image points where this Gaussian can blend: its ellipse of
    /// alpha >= 1/255 (conventions.md); None when its opacity is below 1/255.
    pub fn support(&self) -> Option<[f64; 4]> {
        let r2 = 2.0 * (255.0 * self.opacity).ln();
        if r2.is_nan() || r2 < 0.0 {
            return None;
        }
        let (hx, hy) = ((r2 * self.cov2d[0]).sqrt(), (r2 * self.cov2d[2]).sqrt());
        Some([self.xy[0] - hx, self.xy[0] + hx, self.xy[1] - hy, self.xy[1] + hy])
    }
}

pub struct ReferenceImage {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<f64>,
    pub alpha: Vec<f64>,
    pub depth: Vec<f64>,
    pub expected_depth: Vec<f64>,
    /// Depth of the Gaussian that takes the transmittance to one half or below; the expected depth
    /// where it never gets there (blend.comp's median depth).
    pub median_depth: Vec<f64>,
    pub features: Vec<f64>,
    pub ambiguous: Vec<bool>,
}

/// Real SH basis values (INRIA order) for a unit direction, degree <= 3.
pub fn sh_basis(d: [f64; 3], degree: u32) -> [f64; 16] {
    let mut b = [0.0; 16];
    b[0] = SH_C0;
    if degree < 1 {
        return b;
    }
    let (x, y, z) = (d[0], d[1], d[2]);
    b[1] = -SH_C1 * y;
    b[2] = SH_C1 * z;
    b[3] = -SH_C1 * x;
    if degree < 2 {
        return b;
    }
    let (xx, yy, zz, xy, yz, xz) = (x * x, y * y, z * z, x * y, y * z, x * z);
    b[4] = SH_C2[0] * xy;
    b[5] = SH_C2[1] * yz;
    b[6] = SH_C2[2] * (2.0 * zz - xx - yy);
    b[7] = SH_C2[3] * xz;
    b[8] = SH_C2[4] * (xx - yy);
    if degree < 3 {
        return b;
    }
    b[9] = SH_C3[0] * y * (3.0 * xx - yy);
    b[10] = SH_C3[1] * xy * z;
    b[11] = SH_C3[2] * y * (4.0 * zz - xx - yy);
    b[12] = SH_C3[3] * z * (2.0 * zz - 3.0 * xx - 3.0 * yy);
    b[13] = SH_C3[4] * x * (4.0 * zz - xx - yy);
    b[14] = SH_C3[5] * z * (xx - yy);
    b[15] = SH_C3[6] * x * (xx - 3.0 * yy);
    b
}

type M3 = [[f64; 3]; 3];

fn mul(a: &M3, b: &M3) -> M3 {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

fn transpose(a: &M3) -> M3 {
    let mut t = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            t[i][j] = a[j][i];
        }
    }
    t
}

/// Projects Gaussian `i` (None when culled by the near plane or a degenerate covariance).
pub fn project(
    scene: &GaussianScene,
    i: usize,
    camera: &Camera,
    near: f64,
    sh_degree: u32,
) -> Option<ProjectedGaussian> {
    let m = scene.means[i].map(|v| v as f64);
    let pv = camera.to_camera(m);
    if pv[2] <= near {
        return None;
    }
    let q = scene.quats[i].map(|v| v as f64);
    let rq = rotation_from_qvec(q);
    let s = scene.log_scales[i].map(|v| (v as f64).exp());
    let mut ms = rq;
    for row in ms.iter_mut() {
        for (c, v) in row.iter_mut().enumerate() {
            *v *= s[c];
        }
    }
    let cov_world = mul(&ms, &transpose(&ms));
    let w = camera.rotation;
    let cov_view = mul(&mul(&w, &cov_world), &transpose(&w));
    let (tan_x, tan_y) = camera.tan_half_fov();
    let (lim_x, lim_y) = (1.3 * tan_x, 1.3 * tan_y);
    let z = pv[2];
    let tx = (pv[0] / z).clamp(-lim_x, lim_x) * z;
    let ty = (pv[1] / z).clamp(-lim_y, lim_y) * z;
    let j = [[camera.fx / z, 0.0, -camera.fx * tx / (z * z)], [0.0, camera.fy / z, -camera.fy * ty / (z * z)]];
    // cov2d = J cov_view J^T
    let mut c2 = [[0.0; 2]; 2];
    for a in 0..2 {
        for b in 0..2 {
            let mut acc = 0.0;
            for k in 0..3 {
                for l in 0..3 {
                    acc += j[a][k] * cov_view[k][l] * j[b][l];
                }
            }
            c2[a][b] = acc;
        }
    }
    let (a, b, c) = (c2[0][0] + 0.3, c2[0][1], c2[1][1] + 0.3);
    let det = a * c - b * b;
    if det <= 0.0 {
        return None;
    }
    let conic = [c / det, -b / det, a / det];
    let xy = [camera.fx * pv[0] / z + camera.cx, camera.fy * pv[1] / z + camera.cy];
    let opacity = 1.0 / (1.0 + (-(scene.opacity_logits[i] as f64)).exp());
    let center = camera.center();
    let d = [m[0] - center[0], m[1] - center[1], m[2] - center[2]];
    let dn = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let basis = sh_basis([d[0] / dn, d[1] / dn, d[2] / dn], sh_degree.min(scene.sh_degree));
    let k = scene.sh_coeffs();
    let mut color = [0.0; 3];
    for (bi, bv) in basis.iter().enumerate().take(k) {
        for (ch, col) in color.iter_mut().enumerate() {
            *col += bv * scene.sh[(i * k + bi) * 3 + ch] as f64;
        }
    }
    let color = color.map(|v| (v + 0.5).max(0.0));
    let r = camera.rotation[2];
    let magnitude = (0..3).map(|k| (r[k] * m[k]).abs()).sum::<f64>() + camera.translation[2].abs();
    let depth_error = 4.0 * f32::EPSILON as f64 * magnitude;
    Some(ProjectedGaussian { index: i, xy, conic, cov2d: [a, b, c], opacity, depth: z, depth_error, color })
}

/// Renders with every Gaussian at every pixel. `features`: optional N x D row-major matrix.
pub fn render_reference(
    scene: &GaussianScene,
    camera: &Camera,
    background: [f64; 3],
    near: f64,
    sh_degree: u32,
    features: Option<(&[f32], usize)>,
) -> ReferenceImage {
    let mut gs: Vec<ProjectedGaussian> =
        (0..scene.len()).filter_map(|i| project(scene, i, camera, near, sh_degree)).collect();
    gs.sort_by(|a, b| a.depth.partial_cmp(&b.depth).unwrap().then(a.index.cmp(&b.index)));
    let (w, h) = (camera.width as usize, camera.height as usize);
    let hw = w * h;
    let d = features.map(|f| f.1).unwrap_or(0);
    let mut out = ReferenceImage {
        width: camera.width,
        height: camera.height,
        rgb: vec![0.0; 3 * hw],
        alpha: vec![0.0; hw],
        depth: vec![0.0; hw],
        expected_depth: vec![0.0; hw],
        median_depth: vec![0.0; hw],
        features: vec![0.0; d * hw],
        ambiguous: vec![false; hw],
    };
    const ALPHA_MIN: f64 = 1.0 / 255.0;
    let mut feat = vec![0.0; d];
    for py in 0..h {
        for px in 0..w {
            let pixel = [px as f64 + 0.5, py as f64 + 0.5];
            let mut t = 1.0f64;
            let mut c = [0.0; 3];
            let (mut dsum, mut wsum) = (0.0, 0.0);
            let mut median = None;
            feat.iter_mut().for_each(|v| *v = 0.0);
            let mut ambiguous = false;
            let mut last: Option<&ProjectedGaussian> = None;
            for g in &gs {
                let dx = g.xy[0] - pixel[0];
                let dy = g.xy[1] - pixel[1];
                let (a, b, cc) = (g.conic[0], g.conic[1], g.conic[2]);
                let power = -0.5 * (a * dx * dx + cc * dy * dy) - b * dx * dy;
                if power > 0.0 {
                    continue;
                }
                let raw = g.opacity * power.exp();
                // float32 uncertainty of the power: rounding of its terms, and of the 2D mean
                let terms = a.abs() * dx * dx + cc.abs() * dy * dy + 2.0 * (b * dx * dy).abs();
                let slope = (a * dx + b * dy).abs() + (b * dx + cc * dy).abs();
                let tol = 2e-4 + 2e-6 * terms + 1e-5 * slope * (1.0 + g.xy[0].abs().max(g.xy[1].abs())) / 100.0;
                if (raw.ln() - ALPHA_MIN.ln()).abs() < tol {
                    ambiguous = true;
                }
                let alpha = raw.min(0.99);
                if alpha < ALPHA_MIN {
                    continue;
                }
                let t_next = t * (1.0 - alpha);
                if (t_next / 1e-4).ln().abs() < 1e-3 {
                    ambiguous = true;
                }
                if t_next < 1e-4 {
                    break;
                }
                // float32 can put the transmittance on either side of one half
                if (t_next / 0.5).ln().abs() < 2e-5 {
                    ambiguous = true;
                }
                // two contributors whose depths float32 cannot order reliably; identical means are
                // ordered by index on both sides
                if let Some(l) = last {
                    let same_mean = scene.means[l.index] == scene.means[g.index];
                    if !same_mean && (g.depth - l.depth).abs() <= g.depth_error + l.depth_error {
                        ambiguous = true;
                    }
                }
                last = Some(g);
                let wgt = alpha * t;
                for ch in 0..3 {
                    c[ch] += wgt * g.color[ch];
                }
                dsum += wgt * g.depth;
                wsum += wgt;
                if let Some((f, dim)) = features {
                    for (ch, v) in feat.iter_mut().enumerate() {
                        *v += wgt * f[g.index * dim + ch] as f64;
                    }
                }
                t = t_next;
                if median.is_none() && t <= 0.5 {
                    median = Some(g.depth);
                }
            }
            let pi = py * w + px;
            for ch in 0..3 {
                out.rgb[ch * hw + pi] = c[ch] + t * background[ch];
            }
            out.alpha[pi] = 1.0 - t;
            out.depth[pi] = dsum;
            out.expected_depth[pi] = dsum / wsum.max(1e-10);
            out.median_depth[pi] = median.unwrap_or(out.expected_depth[pi]);
            for (ch, v) in feat.iter().enumerate() {
                out.features[ch * hw + pi] = *v;
            }
            out.ambiguous[pi] = ambiguous;
        }
    }
    out
}
