//! Pinhole cameras in the OpenCV/COLMAP frame (+x right, +y down, +z forward), and INRIA cameras.json.

use anyhow::{bail, Context, Result};
use std::path::Path;

#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Image name without extension (output files are `<name>.png`).
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
    /// World-to-camera rotation, row-major.
    pub rotation: [[f64; 3]; 3],
    /// World-to-camera translation.
    pub translation: [f64; 3],
    /// Where this camera sees a window of a larger view (the refinement's windows): that view's
    /// size. The focal lengths and principal point are the view's, moved by the window's corner,
    /// and the projection clamps its perspective Jacobian to the whole view's field of view
    /// (conventions.md), so the window's pixels render exactly as in the whole view. None: the
    /// camera is a whole view.
    pub whole_view: Option<(u32, u32)>,
}

pub use crate::io::MAX_IMAGE_SIDE;

impl Camera {
    /// Checks what every pass assumes of a loaded camera: a size in 1..=MAX_IMAGE_SIDE, positive
    /// finite focal lengths, and a finite pose whose rotation is orthonormal. `what` names the
    /// camera's source in the error.
    pub fn check(&self, what: &str) -> Result<()> {
        let side = 1..=MAX_IMAGE_SIDE;
        if !side.contains(&self.width) || !side.contains(&self.height) {
            bail!("{what}: image size {}x{} outside 1..={MAX_IMAGE_SIDE} per side", self.width, self.height);
        }
        if !(self.fx.is_finite() && self.fy.is_finite() && self.fx > 0.0 && self.fy > 0.0) {
            bail!("{what}: focal lengths must be positive and finite (fx {}, fy {})", self.fx, self.fy);
        }
        if !(self.cx.is_finite() && self.cy.is_finite()) {
            bail!("{what}: principal point ({}, {}) is not finite", self.cx, self.cy);
        }
        let r = &self.rotation;
        if !r.iter().flatten().chain(&self.translation).all(|v| v.is_finite()) {
            bail!("{what}: the pose has a NaN or infinite value (a zero quaternion?)");
        }
        let max_error = (0..3)
            .flat_map(|i| (0..3).map(move |j| (i, j)))
            .map(|(i, j)| {
                let dot: f64 = (0..3).map(|k| r[i][k] * r[j][k]).sum();
                (dot - if i == j { 1.0 } else { 0.0 }).abs()
            })
            .fold(0.0, f64::max);
        let det = r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1]) - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0])
            + r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]);
        if max_error > 1e-3 || det < 0.0 {
            bail!("{what}: the rotation is not a rotation (R R^T off identity by {max_error:.2e}, det {det:.3})");
        }
        Ok(())
    }

    /// Camera center in world coordinates: -R^T t.
    pub fn center(&self) -> [f64; 3] {
        let r = &self.rotation;
        let t = &self.translation;
        [
            -(r[0][0] * t[0] + r[1][0] * t[1] + r[2][0] * t[2]),
            -(r[0][1] * t[0] + r[1][1] * t[1] + r[2][1] * t[2]),
            -(r[0][2] * t[0] + r[1][2] * t[1] + r[2][2] * t[2]),
        ]
    }

    /// World point to camera coordinates.
    pub fn to_camera(&self, p: [f64; 3]) -> [f64; 3] {
        let r = &self.rotation;
        let t = &self.translation;
        [
            r[0][0] * p[0] + r[0][1] * p[1] + r[0][2] * p[2] + t[0],
            r[1][0] * p[0] + r[1][1] * p[1] + r[1][2] * p[2] + t[1],
            r[2][0] * p[0] + r[2][1] * p[1] + r[2][2] * p[2] + t[2],
        ]
    }

    /// World point of pixel (x, y)'s center at view depth `z`: x_w = R^T (x_c - t).
    pub fn pixel_point(&self, x: usize, y: usize, z: f64) -> [f64; 3] {
        self.image_point(x as f64 + 0.5, y as f64 + 0.5, z)
    }

    /// World point at the continuous image position (x, y) (pixel centers at +0.5, as
    /// `project_to_image` returns them) and view depth z.
    pub fn image_point(&self, x: f64, y: f64, z: f64) -> [f64; 3] {
        let pc = [(x - self.cx) / self.fx * z, (y - self.cy) / self.fy * z, z];
        let d = [pc[0] - self.translation[0], pc[1] - self.translation[1], pc[2] - self.translation[2]];
        let r = &self.rotation;
        [
            r[0][0] * d[0] + r[1][0] * d[1] + r[2][0] * d[2],
            r[0][1] * d[0] + r[1][1] * d[1] + r[2][1] * d[2],
            r[0][2] * d[0] + r[1][2] * d[1] + r[2][2] * d[2],
        ]
    }

    /// Where world point `p` lands in the image: (x, y) in pixels and its view depth; None when it
    /// is behind the camera or outside the image.
    pub fn project_to_image(&self, p: [f64; 3]) -> Option<(f64, f64, f64)> {
        self.camera_point_to_image(self.to_camera(p))
    }

    /// `project_to_image` of a point already in camera coordinates.
    pub fn camera_point_to_image(&self, pc: [f64; 3]) -> Option<(f64, f64, f64)> {
        let (x, y, lands) = self.camera_point_landing(pc);
        lands.then_some((x, y, pc[2]))
    }

    /// `camera_point_to_image` without a branch, for loops the compiler vectorizes: the image
    /// point (x, y) and whether the point lands there (in front of the camera, inside the image);
    /// x and y mean nothing where it does not.
    #[inline(always)]
    pub fn camera_point_landing(&self, pc: [f64; 3]) -> (f64, f64, bool) {
        let x = self.fx * pc[0] / pc[2] + self.cx;
        let y = self.fy * pc[1] / pc[2] + self.cy;
        let lands = pc[2] > 1e-6 && x >= 0.0 && y >= 0.0 && x < self.width as f64 && y < self.height as f64;
        (x, y, lands)
    }

    /// The pixel `p` lands in: its row-major index and the view depth; None when it is behind
    /// the camera or outside the image.
    pub fn pixel_of(&self, p: [f64; 3]) -> Option<(usize, f64)> {
        let (x, y, z) = self.project_to_image(p)?;
        Some((y as usize * self.width as usize + x as usize, z))
    }

    /// tan of half the field of view along x and y (of the whole view, for a window of one).
    pub fn tan_half_fov(&self) -> (f64, f64) {
        let (w, h) = self.whole_view.unwrap_or((self.width, self.height));
        (0.5 * w as f64 / self.fx, 0.5 * h as f64 / self.fy)
    }

    /// The same camera for an image resized to width x height (intrinsics scaled per axis).
    pub fn resized(&self, width: u32, height: u32) -> Camera {
        let sx = width as f64 / self.width as f64;
        let sy = height as f64 / self.height as f64;
        let whole_view = self.whole_view.map(|(w, h)| ((w as f64 * sx).round() as u32, (h as f64 * sy).round() as u32));
        Camera {
            width,
            height,
            fx: self.fx * sx,
            fy: self.fy * sy,
            cx: self.cx * sx,
            cy: self.cy * sy,
            whole_view,
            ..self.clone()
        }
    }

    /// A camera at `eye` looking at `target` with `up` pointing roughly up in the image (-y).
    pub fn look_at(
        name: &str,
        width: u32,
        height: u32,
        fov_x_deg: f64,
        eye: [f64; 3],
        target: [f64; 3],
        up: [f64; 3],
    ) -> Camera {
        let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
        let norm = |a: [f64; 3]| {
            let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
            [a[0] / l, a[1] / l, a[2] / l]
        };
        let cross = |a: [f64; 3], b: [f64; 3]| {
            [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
        };
        let z = norm(sub(target, eye));
        let x = norm(cross(z, up)); // right, when y points down
        let y = cross(z, x);
        let rotation = [x, y, z];
        let translation = [
            -(x[0] * eye[0] + x[1] * eye[1] + x[2] * eye[2]),
            -(y[0] * eye[0] + y[1] * eye[1] + y[2] * eye[2]),
            -(z[0] * eye[0] + z[1] * eye[1] + z[2] * eye[2]),
        ];
        let fx = 0.5 * width as f64 / (0.5 * fov_x_deg.to_radians()).tan();
        Camera {
            name: name.to_string(),
            width,
            height,
            fx,
            fy: fx,
            cx: width as f64 / 2.0,
            cy: height as f64 / 2.0,
            rotation,
            translation,
            whole_view: None,
        }
    }
}

/// Rotation matrix of a quaternion (w, x, y, z), normalized first: COLMAP's world-to-camera
/// rotation, and a Gaussian's rotation.
pub fn rotation_from_qvec(q: [f64; 4]) -> [[f64; 3]; 3] {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    let (w, x, y, z) = (q[0] / n, q[1] / n, q[2] / n, q[3] / n);
    [
        [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y)],
        [2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x)],
        [2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)],
    ]
}

#[derive(serde::Deserialize, serde::Serialize)]
struct JsonCamera {
    #[serde(default)]
    id: i64,
    img_name: String,
    width: u32,
    height: u32,
    position: [f64; 3],
    rotation: [[f64; 3]; 3],
    fx: f64,
    fy: f64,
}

/// Reads INRIA `cameras.json`: camera-to-world rotation and camera center, principal point centered.
pub fn read_cameras_json(path: &Path) -> Result<Vec<Camera>> {
    let data = std::fs::read(path).with_context(|| format!("{}: cannot read", path.display()))?;
    parse_cameras_json(&data, &path.display().to_string())
}

/// The world-to-camera rotation and translation (`Camera`'s pose) of a camera whose
/// camera-to-world rotation (OpenCV axes) is `c2w` and whose center is `center`: R^T and -R^T c.
pub fn pose_from_camera_to_world(c2w: [[f64; 3]; 3], center: [f64; 3]) -> ([[f64; 3]; 3], [f64; 3]) {
    let r = c2w;
    let rotation = [[r[0][0], r[1][0], r[2][0]], [r[0][1], r[1][1], r[2][1]], [r[0][2], r[1][2], r[2][2]]];
    let c = center;
    let translation = [0, 1, 2].map(|a| -(rotation[a][0] * c[0] + rotation[a][1] * c[1] + rotation[a][2] * c[2]));
    (rotation, translation)
}

/// `read_cameras_json` on the file's bytes (`what` names it in errors).
pub fn parse_cameras_json(data: &[u8], what: &str) -> Result<Vec<Camera>> {
    let list: Vec<JsonCamera> =
        serde_json::from_slice(data).with_context(|| format!("{what}: not an INRIA cameras.json"))?;
    if list.is_empty() {
        bail!("{what}: no cameras");
    }
    list.into_iter()
        .map(|c| {
            let (rotation, translation) = pose_from_camera_to_world(c.rotation, c.position);
            let camera = Camera {
                name: c.img_name,
                width: c.width,
                height: c.height,
                fx: c.fx,
                fy: c.fy,
                cx: c.width as f64 / 2.0,
                cy: c.height as f64 / 2.0,
                rotation,
                translation,
                whole_view: None,
            };
            camera.check(&format!("{what}: camera {:?}", camera.name))?;
            Ok(camera)
        })
        .collect()
}

/// Writes INRIA `cameras.json` (atomically).
pub fn write_cameras_json(cameras: &[Camera], path: &Path) -> Result<()> {
    let text = encode_cameras_json(cameras)?;
    crate::io::write_atomic(path, |w| {
        use std::io::Write;
        w.write_all(text.as_bytes()).map_err(Into::into)
    })
}

/// The text of INRIA `cameras.json` for `cameras`.
pub fn encode_cameras_json(cameras: &[Camera]) -> Result<String> {
    let list: Vec<JsonCamera> = cameras
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let r = c.rotation;
            JsonCamera {
                id: i as i64,
                img_name: c.name.clone(),
                width: c.width,
                height: c.height,
                position: c.center(),
                rotation: [[r[0][0], r[1][0], r[2][0]], [r[0][1], r[1][1], r[2][1]], [r[0][2], r[1][2], r[2][2]]],
                fx: c.fx,
                fy: c.fy,
            }
        })
        .collect();
    Ok(serde_json::to_string_pretty(&list)?)
}
/// Resizes every camera to `width` x `height` (intrinsics scaled); with only one of them given,
/// the other follows each camera's aspect ratio; with neither, the cameras are returned as they are.
pub fn resize_cameras(cameras: Vec<Camera>, width: Option<u32>, height: Option<u32>) -> Result<Vec<Camera>> {
    if width == Some(0) || height == Some(0) {
        bail!("--width and --height must be positive");
    }
    Ok(cameras
        .into_iter()
        .map(|c| match (width, height) {
            (None, None) => c,
            (Some(w), Some(h)) => c.resized(w, h),
            (Some(w), None) => {
                let h = ((c.height as f64 * w as f64 / c.width as f64).round() as u32).max(1);
                c.resized(w, h)
            }
            (None, Some(h)) => {
                let w = ((c.width as f64 * h as f64 / c.height as f64).round() as u32).max(1);
                c.resized(w, h)
            }
        })
        .collect())
}
