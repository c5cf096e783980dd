//! Lens distortion of the COLMAP camera models. A model maps the normalized coordinates (u, v) =
//! (X / Z, Y / Z) of a ray in the camera frame to the normalized coordinates (x, y) where the lens
//! images it; the pixel is then (fx x + cx, fy y + cy). `distort` is that map as COLMAP writes it;
//! `undistort` inverts it by Newton iteration (the models have no closed-form inverse), which is
//! what loading a capture needs: every pixel of the undistorted pinhole image asks where the
//! distorted photo saw its ray (scene/undistort.rs).

use anyhow::{bail, Result};

/// A camera's distortion, with the parameters COLMAP stores after the focal lengths and the
/// principal point.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub enum Lens {
    Pinhole,
    /// SIMPLE_RADIAL (k2 = 0) and RADIAL: radial polynomial k1 r^2 + k2 r^4.
    Radial {
        k1: f64,
        k2: f64,
    },
    /// OPENCV (k3..k6 = 0) and FULL_OPENCV: rational radial (1 + k1 r^2 + k2 r^4 + k3 r^6) /
    /// (1 + k4 r^2 + k5 r^4 + k6 r^6) and tangential p1, p2.
    OpenCv {
        k: [f64; 6],
        p: [f64; 2],
    },
    /// OPENCV_FISHEYE (Kannala-Brandt), and SIMPLE_RADIAL_FISHEYE / RADIAL_FISHEYE (the higher
    /// coefficients 0): the angle theta from the axis is imaged at theta (1 + k1 theta^2 + ... +
    /// k4 theta^8).
    Fisheye {
        k: [f64; 4],
    },
    /// THIN_PRISM_FISHEYE: the equidistant fisheye (theta u / r), then radial k1..k4,
    /// tangential p1, p2 and thin-prism sx1, sy1 terms.
    ThinPrismFisheye {
        k: [f64; 4],
        p: [f64; 2],
        s: [f64; 2],
    },
}

/// A COLMAP camera reduced to its focal lengths, principal point and lens.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ColmapIntrinsics {
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
    pub lens: Lens,
}

/// The number of parameters of each COLMAP camera model (FOV is not supported).
pub fn parameter_count(model: &str) -> Option<usize> {
    Some(match model {
        "SIMPLE_PINHOLE" => 3,
        "PINHOLE" => 4,
        "SIMPLE_RADIAL" => 4,
        "RADIAL" => 5,
        "OPENCV" => 8,
        "OPENCV_FISHEYE" => 8,
        "FULL_OPENCV" => 12,
        "SIMPLE_RADIAL_FISHEYE" => 4,
        "RADIAL_FISHEYE" => 5,
        "THIN_PRISM_FISHEYE" => 12,
        _ => return None,
    })
}

impl ColmapIntrinsics {
    /// Reads COLMAP's parameter list `p` of `model` (`what` names the camera in errors).
    pub fn from_colmap(model: &str, p: &[f64], what: &str) -> Result<ColmapIntrinsics> {
        let Some(n) = parameter_count(model) else {
            bail!(
                "{what}: unsupported camera model {model:?} (supported: SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, \
                 RADIAL, OPENCV, FULL_OPENCV, OPENCV_FISHEYE, SIMPLE_RADIAL_FISHEYE, RADIAL_FISHEYE, \
                 THIN_PRISM_FISHEYE)"
            );
        };
        if p.len() != n {
            bail!("{what}: camera model {model} takes {n} parameters, got {}", p.len());
        }
        // one focal length (f, cx, cy, ...) or two (fx, fy, cx, cy, ...)
        let single =
            matches!(model, "SIMPLE_PINHOLE" | "SIMPLE_RADIAL" | "RADIAL" | "SIMPLE_RADIAL_FISHEYE" | "RADIAL_FISHEYE");
        let (fx, fy, cx, cy, e) =
            if single { (p[0], p[0], p[1], p[2], &p[3..]) } else { (p[0], p[1], p[2], p[3], &p[4..]) };
        if !(fx.is_finite() && fy.is_finite() && fx > 0.0 && fy > 0.0 && cx.is_finite() && cy.is_finite()) {
            bail!("{what}: camera with invalid intrinsics (fx {fx}, fy {fy}, cx {cx}, cy {cy})");
        }
        if let Some(v) = e.iter().find(|v| !v.is_finite()) {
            bail!("{what}: camera model {model} with a non-finite distortion parameter ({v})");
        }
        let lens = match model {
            "SIMPLE_PINHOLE" | "PINHOLE" => Lens::Pinhole,
            "SIMPLE_RADIAL" => Lens::Radial { k1: e[0], k2: 0.0 },
            "RADIAL" => Lens::Radial { k1: e[0], k2: e[1] },
            "OPENCV" => Lens::OpenCv { k: [e[0], e[1], 0.0, 0.0, 0.0, 0.0], p: [e[2], e[3]] },
            "FULL_OPENCV" => Lens::OpenCv { k: [e[0], e[1], e[4], e[5], e[6], e[7]], p: [e[2], e[3]] },
            "OPENCV_FISHEYE" => Lens::Fisheye { k: [e[0], e[1], e[2], e[3]] },
            "SIMPLE_RADIAL_FISHEYE" => Lens::Fisheye { k: [e[0], 0.0, 0.0, 0.0] },
            "RADIAL_FISHEYE" => Lens::Fisheye { k: [e[0], e[1], 0.0, 0.0] },
            "THIN_PRISM_FISHEYE" => {
                Lens::ThinPrismFisheye { k: [e[0], e[1], e[4], e[5]], p: [e[2], e[3]], s: [e[6], e[7]] }
            }
            _ => unreachable!("parameter_count knows the model"),
        };
        Ok(ColmapIntrinsics { fx, fy, cx, cy, lens: lens.simplified() })
    }

    /// Where the ray with normalized coordinates (u, v) lands in the image (pixel centers at +0.5).
    pub fn project(&self, u: f64, v: f64) -> (f64, f64) {
        let (x, y) = self.lens.distort(u, v);
        (self.fx * x + self.cx, self.fy * y + self.cy)
    }

    /// The normalized coordinates of the ray imaged at pixel position (px, py); None where the
    /// lens model cannot be inverted there.
    pub fn unproject(&self, px: f64, py: f64) -> Option<(f64, f64)> {
        self.lens.undistort((px - self.cx) / self.fx, (py - self.cy) / self.fy)
    }
}

impl Lens {
    /// A lens whose coefficients are all zero is a pinhole.
    fn simplified(self) -> Lens {
        let zero = match self {
            Lens::Pinhole => true,
            Lens::Radial { k1, k2 } => k1 == 0.0 && k2 == 0.0,
            Lens::OpenCv { k, p } => k.iter().chain(&p).all(|&c| c == 0.0),
            // a fisheye with zero coefficients is still equidistant, not a pinhole
            Lens::Fisheye { .. } | Lens::ThinPrismFisheye { .. } => false,
        };
        if zero {
            Lens::Pinhole
        } else {
            self
        }
    }

    pub fn is_pinhole(&self) -> bool {
        *self == Lens::Pinhole
    }

    /// The distorted normalized coordinates of the ray (u, v).
    pub fn distort(&self, u: f64, v: f64) -> (f64, f64) {
        match *self {
            Lens::Pinhole => (u, v),
            Lens::Radial { k1, k2 } => {
                let r2 = u * u + v * v;
                let f = 1.0 + r2 * (k1 + k2 * r2);
                (u * f, v * f)
            }
            Lens::OpenCv { k, p } => {
                let r2 = u * u + v * v;
                let radial =
                    (1.0 + r2 * (k[0] + r2 * (k[1] + r2 * k[2]))) / (1.0 + r2 * (k[3] + r2 * (k[4] + r2 * k[5])));
                tangential(u * radial, v * radial, u, v, p)
            }
            Lens::Fisheye { k } => equidistant(u, v, k),
            Lens::ThinPrismFisheye { k, p, s } => {
                let (a, b) = equidistant(u, v, [0.0; 4]);
                let r2 = a * a + b * b;
                let radial = 1.0 + r2 * (k[0] + r2 * (k[1] + r2 * (k[2] + r2 * k[3])));
                let (x, y) = tangential(a * radial, b * radial, a, b, p);
                (x + s[0] * r2, y + s[1] * r2)
            }
        }
    }

    /// The ray (u, v) that `distort` maps to (x, y): Newton's method on the 2x2 system with a
    /// central-difference Jacobian, from (x, y) itself. None when it does not converge to 1e-12
    /// (beyond the lens's usable field of view, where the model folds back).
    pub fn undistort(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        if self.is_pinhole() {
            return Some((x, y));
        }
        let (mut u, mut v) = (x, y);
        for _ in 0..100 {
            let (fx, fy) = self.distort(u, v);
            let (ex, ey) = (fx - x, fy - y);
            let h = 1e-7 * (1.0 + u.abs().max(v.abs()));
            let (a1, b1) = self.distort(u + h, v);
            let (a0, b0) = self.distort(u - h, v);
            let (c1, d1) = self.distort(u, v + h);
            let (c0, d0) = self.distort(u, v - h);
            let (j00, j10) = ((a1 - a0) / (2.0 * h), (b1 - b0) / (2.0 * h));
            let (j01, j11) = ((c1 - c0) / (2.0 * h), (d1 - d0) / (2.0 * h));
            let det = j00 * j11 - j01 * j10;
            if !det.is_finite() || det.abs() < 1e-12 {
                return None;
            }
            let du = (j11 * ex - j01 * ey) / det;
            let dv = (j00 * ey - j10 * ex) / det;
            u -= du;
            v -= dv;
            if !(u.is_finite() && v.is_finite()) {
                return None;
            }
            if du.abs().max(dv.abs()) < 1e-12 * (1.0 + u.abs().max(v.abs())) {
                let (fx, fy) = self.distort(u, v);
                return ((fx - x).abs().max((fy - y).abs()) < 1e-9).then_some((u, v));
            }
        }
        None
    }
}

/// Adds the tangential terms of (u, v) (before radial scaling) to the radially scaled (x, y).
fn tangential(x: f64, y: f64, u: f64, v: f64, p: [f64; 2]) -> (f64, f64) {
    let (u2, v2, uv) = (u * u, v * v, u * v);
    let r2 = u2 + v2;
    (x + 2.0 * p[0] * uv + p[1] * (r2 + 2.0 * u2), y + 2.0 * p[1] * uv + p[0] * (r2 + 2.0 * v2))
}

/// The Kannala-Brandt fisheye: the ray at angle theta from the axis is imaged at radius
/// theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8).
fn equidistant(u: f64, v: f64, k: [f64; 4]) -> (f64, f64) {
    let r = (u * u + v * v).sqrt();
    if r <= f64::EPSILON {
        return (u, v);
    }
    let theta = r.atan();
    let t2 = theta * theta;
    let thetad = theta * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))));
    (u * thetad / r, v * thetad / r)
}
