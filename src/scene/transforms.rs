//! nerfstudio / instant-ngp `transforms.json`, the capture format Polycam, Record3D, KIRI and
//! `ns-process-data` write: intrinsics for the whole file or per frame (`fl_x`, `fl_y`, `cx`,
//! `cy`, `w`, `h`, or instant-ngp's `camera_angle_x`), optional distortion (`k1`, `k2`, `k3`,
//! `k4`, `p1`, `p2`; `camera_model` OPENCV or OPENCV_FISHEYE), one camera-to-world
//! `transform_matrix` per frame in OpenGL axes (x right, y up, looking down -z), and an optional
//! `applied_transform` (the 3x4 transform nerfstudio applied to the original world), which is
//! undone so that poses and points come back in the world they were captured in. Sparse points come
//! from `ply_file_path` when it is there; otherwise the scene starts from random points in the
//! region the cameras look at.
//!
//! The result is the same model a COLMAP capture gives (colmap.rs), so every command reads either.

use super::camera::{pose_from_camera_to_world, Camera};
use super::colmap::{ColmapModel, Point3D};
use super::lens::{ColmapIntrinsics, Lens};
use crate::rng::Rng;
use anyhow::{anyhow, bail, Context, Result};
use glam::{DMat4, DVec3};
use serde_json::Value;
use std::path::Path;

/// The file name `load` looks for in a capture folder.
pub const FILE_NAME: &str = "transforms.json";

/// Random starting points when the file names no point cloud.
const RANDOM_POINTS: usize = 100_000;

/// Reads `dir/transforms.json`.
pub fn read_transforms(dir: &Path) -> Result<ColmapModel> {
    let path = dir.join(FILE_NAME);
    let text = std::fs::read_to_string(&path).with_context(|| format!("{}: cannot read", path.display()))?;
    let json: Value = serde_json::from_str(&text).map_err(|e| anyhow!("{}: not valid JSON: {e}", path.display()))?;
    parse_transforms(&json, dir, &path.display().to_string())
}

/// A number field of `obj` (the frame first, then the file's top level), or None when absent.
fn number(frame: &Value, top: &Value, key: &str, what: &str) -> Result<Option<f64>> {
    for v in [&frame[key], &top[key]] {
        if v.is_null() {
            continue;
        }
        let x = v.as_f64().ok_or_else(|| anyhow!("{what}: field {key:?} is not a number"))?;
        if !x.is_finite() {
            bail!("{what}: field {key:?} is not finite");
        }
        return Ok(Some(x));
    }
    Ok(None)
}

/// A 4x4 (or 3x4) row-major matrix field.
fn matrix(v: &Value, key: &str, what: &str) -> Result<DMat4> {
    let rows = v.as_array().ok_or_else(|| anyhow!("{what}: field {key:?} is not a 4x4 matrix"))?;
    if rows.len() != 4 && rows.len() != 3 {
        bail!("{what}: field {key:?} has {} rows, not 4 (or 3)", rows.len());
    }
    let mut m = [[0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]];
    for (r, row) in rows.iter().enumerate() {
        let row = row
            .as_array()
            .filter(|a| a.len() == 4)
            .ok_or_else(|| anyhow!("{what}: field {key:?}: a row is not 4 numbers"))?;
        for (c, x) in row.iter().enumerate() {
            m[r][c] = x
                .as_f64()
                .filter(|x| x.is_finite())
                .ok_or_else(|| anyhow!("{what}: field {key:?}: not a finite number"))?;
        }
    }
    // rows as written; glam stores columns
    Ok(DMat4::from_cols_array_2d(&m).transpose())
}

/// The intrinsics and lens of `frame` (frame fields override the file's).
fn intrinsics(frame: &Value, top: &Value, what: &str) -> Result<(u32, u32, ColmapIntrinsics)> {
    let get = |k: &str| number(frame, top, k, what);
    let side = |k: &str| -> Result<u32> {
        let v = get(k)?.ok_or_else(|| anyhow!("{what}: missing field {k:?} (image width/height)"))?;
        if v < 1.0 || v > crate::io::MAX_IMAGE_SIDE as f64 || v.fract() != 0.0 {
            bail!("{what}: field {k:?} = {v} is not an image size in 1..={}", crate::io::MAX_IMAGE_SIDE);
        }
        Ok(v as u32)
    };
    let (w, h) = (side("w")?, side("h")?);
    let fx = match (get("fl_x")?, get("camera_angle_x")?) {
        (Some(f), _) => f,
        (None, Some(a)) => 0.5 * w as f64 / (0.5 * a).tan(),
        (None, None) => bail!("{what}: missing field \"fl_x\" (or \"camera_angle_x\")"),
    };
    let fy = match (get("fl_y")?, get("camera_angle_y")?) {
        (Some(f), _) => f,
        (None, Some(a)) => 0.5 * h as f64 / (0.5 * a).tan(),
        (None, None) => fx,
    };
    let (cx, cy) = (get("cx")?.unwrap_or(w as f64 / 2.0), get("cy")?.unwrap_or(h as f64 / 2.0));
    let c = |k: &str| -> Result<f64> { Ok(get(k)?.unwrap_or(0.0)) };
    let model = frame["camera_model"].as_str().or(top["camera_model"].as_str()).unwrap_or("OPENCV");
    let params: Vec<f64> = match model {
        "OPENCV" | "PINHOLE" | "SIMPLE_PINHOLE" => {
            // nerfstudio's radial polynomial runs to k4 r^8, which no COLMAP model has
            if c("k4")? != 0.0 {
                bail!("{what}: field \"k4\" (a radial r^8 term) is only supported with OPENCV_FISHEYE");
            }
            vec![fx, fy, cx, cy, c("k1")?, c("k2")?, c("p1")?, c("p2")?, c("k3")?, 0.0, 0.0, 0.0]
        }
        "OPENCV_FISHEYE" => vec![fx, fy, cx, cy, c("k1")?, c("k2")?, c("k3")?, c("k4")?],
        other => bail!("{what}: field \"camera_model\" = {other:?} (supported: OPENCV, OPENCV_FISHEYE, PINHOLE)"),
    };
    let colmap_model = if model == "OPENCV_FISHEYE" { "OPENCV_FISHEYE" } else { "FULL_OPENCV" };
    Ok((w, h, ColmapIntrinsics::from_colmap(colmap_model, &params, what)?))
}

/// Builds the model from the parsed file; `dir` holds it (for `ply_file_path`).
pub fn parse_transforms(json: &Value, dir: &Path, what: &str) -> Result<ColmapModel> {
    let frames = json["frames"].as_array().ok_or_else(|| anyhow!("{what}: missing field \"frames\" (a list)"))?;
    if frames.is_empty() {
        bail!("{what}: field \"frames\" is empty");
    }
    // world = applied * original world: undone with its inverse (a rigid 3x4, possibly with a scale)
    let undo = match &json["applied_transform"] {
        Value::Null => None,
        v => {
            let applied = matrix(v, "applied_transform", what)?;
            if applied.determinant().abs() < 1e-12 {
                bail!("{what}: field \"applied_transform\" is singular");
            }
            Some(applied.inverse())
        }
    };
    let mut views: Vec<(Camera, Lens)> = Vec::new();
    for (i, frame) in frames.iter().enumerate() {
        let at = format!("{what}: frames[{i}]");
        let file = frame["file_path"].as_str().ok_or_else(|| anyhow!("{at}: missing field \"file_path\""))?;
        let name = Path::new(file)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .filter(|s| !s.is_empty())
            .ok_or_else(|| anyhow!("{at}: field \"file_path\" names no file"))?;
        let (w, h, k) = intrinsics(frame, json, &at)?;
        let c2w = undo.unwrap_or(DMat4::IDENTITY) * matrix(&frame["transform_matrix"], "transform_matrix", &at)?;
        // OpenGL camera axes (y up, looking down -z) to COLMAP's (y down, looking down +z); a
        // scaled applied_transform leaves scaled axes, normalized here
        let axes = [c2w.x_axis.truncate(), -c2w.y_axis.truncate(), -c2w.z_axis.truncate()];
        let scale = axes[0].length();
        let axes = axes.map(|a| if scale > 0.0 { a / scale } else { a });
        let c2w_rotation = [0, 1, 2].map(|row| [axes[0][row], axes[1][row], axes[2][row]]);
        let (rotation, translation) = pose_from_camera_to_world(c2w_rotation, c2w.w_axis.truncate().to_array());
        let camera = Camera {
            name,
            width: w,
            height: h,
            fx: k.fx,
            fy: k.fy,
            cx: k.cx,
            cy: k.cy,
            rotation,
            translation,
            whole_view: None,
        };
        camera.check(&at)?;
        views.push((camera, k.lens));
    }
    views.sort_by(|a, b| a.0.name.cmp(&b.0.name));
    if let Some(w) = views.windows(2).find(|w| w[0].0.name == w[1].0.name) {
        bail!("{what}: two frames name the image {:?}", w[0].0.name);
    }
    let mut warnings = Vec::new();
    let points = match json["ply_file_path"].as_str() {
        Some(p) => {
            let ply =
                crate::scene::ply::read_point_cloud(&dir.join(p)).with_context(|| format!("{what}: ply_file_path"))?;
            ply_points(&ply, undo.as_ref())
        }
        None => {
            warnings.push(format!(
                "{what}: no \"ply_file_path\": starting from {RANDOM_POINTS} random points where the cameras look"
            ));
            random_points(&views.iter().map(|v| v.0.clone()).collect::<Vec<_>>())
        }
    };
    let (cameras, lenses) = views.into_iter().unzip();
    Ok(ColmapModel { cameras, lenses, points, warnings })
}

/// The points of a point-cloud PLY (x, y, z and red, green, blue), back in the original world.
fn ply_points(ply: &crate::scene::GaussianScene, undo: Option<&DMat4>) -> Vec<Point3D> {
    let color = |name: &str| ply.extras.iter().find(|e| e.name == name).map(|e| &e.values);
    let (r, g, b) = (color("red"), color("green"), color("blue"));
    ply.means
        .iter()
        .enumerate()
        .map(|(i, m)| {
            let p = DVec3::new(m[0] as f64, m[1] as f64, m[2] as f64);
            let xyz = undo.map_or(p, |u| u.transform_point3(p)).to_array();
            let c = |v: Option<&Vec<f64>>| v.map_or(128, |v| v[i].clamp(0.0, 255.0) as u8);
            Point3D { xyz, rgb: [c(r), c(g), c(b)] }
        })
        .collect()
}

/// Random gray points in the cube around the point the cameras look at (the least-squares meeting
/// point of their optical axes), half as wide as the median camera distance to it.
fn random_points(cameras: &[Camera]) -> Vec<Point3D> {
    // sum over cameras of (I - d d^T) (x - c) = 0
    let (mut m, mut rhs) = ([[0.0f64; 3]; 3], [0.0f64; 3]);
    for cam in cameras {
        let c = cam.center();
        let d = cam.rotation[2]; // the optical axis in world coordinates (third row of R)
        for i in 0..3 {
            for j in 0..3 {
                let p = (i == j) as u8 as f64 - d[i] * d[j];
                m[i][j] += p;
                rhs[i] += p * c[j];
            }
        }
    }
    let target = crate::planes::solve(m, rhs).unwrap_or_else(|| {
        let n = cameras.len() as f64;
        [0, 1, 2].map(|a| cameras.iter().map(|c| c.center()[a]).sum::<f64>() / n)
    });
    let mut dist: Vec<f64> = cameras
        .iter()
        .map(|c| {
            let e = c.center();
            ((e[0] - target[0]).powi(2) + (e[1] - target[1]).powi(2) + (e[2] - target[2]).powi(2)).sqrt()
        })
        .collect();
    dist.sort_by(|a, b| a.total_cmp(b));
    let half = 0.5 * dist[dist.len() / 2].max(1e-3);
    let mut rng = Rng::new(0);
    (0..RANDOM_POINTS)
        .map(|_| {
            let xyz = [0, 1, 2].map(|a| target[a] + rng.range(-half, half));
            let v = (rng.uniform() * 255.0) as u8;
            Point3D { xyz, rgb: [v, v, v] }
        })
        .collect()
}
