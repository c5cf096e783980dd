//! The capture files a synth dataset is written as: a COLMAP text model (sparse/0) and the same
//! cameras and points as a nerfstudio `transforms.json` with `sparse_pc.ply`.

use super::{qvec_from_rotation, SynthConfig, ViewRender};
use crate::io::write_atomic;
use crate::rng::Rng;
use crate::scene::colmap::Point3D;
use crate::scene::lens::Lens;
use crate::scene::Camera;
use anyhow::Result;
use std::io::Write;
use std::path::Path;

/// Writes the COLMAP text model (sparse/0) of the views, with sparse points sampled from the
/// training views' surfaces with SfM-like noise; returns those points.
pub(super) fn write_colmap(
    cfg: &SynthConfig,
    cameras: &[Camera],
    renders: &[ViewRender],
    train: &[usize],
    out: &Path,
    rng: &mut Rng,
) -> Result<Vec<Point3D>> {
    let c0 = &cameras[0];
    let (w, h) = (cfg.width, cfg.height);
    let cams = match cfg.lens() {
        Lens::Pinhole => format!("# Camera list\n1 PINHOLE {w} {h} {} {} {} {}\n", c0.fx, c0.fy, c0.cx, c0.cy),
        _ => {
            let [k1, k2, p1, p2] = cfg.distortion;
            format!("# Camera list\n1 OPENCV {w} {h} {} {} {} {} {k1} {k2} {p1} {p2}\n", c0.fx, c0.fy, c0.cx, c0.cy)
        }
    };
    write_atomic(&out.join("sparse/0/cameras.txt"), |w| w.write_all(cams.as_bytes()).map_err(Into::into))?;
    write_images(cameras, |_| 1, out)?;
    // sparse points: surface points seen by training views, with SfM-like noise
    let hw = (cfg.width * cfg.height) as usize;
    let mut points = Vec::new();
    for &t in train {
        for _ in 0..cfg.points_per_view.max(4) {
            let p = (rng.next_u64() % hw as u64) as usize;
            let pt = renders[t].points[p];
            let noise = 0.01;
            let rgb = [0, 1, 2].map(|c| crate::io::to_u8(renders[t].rgb[c * hw + p]));
            let xyz = [0, 1, 2].map(|a| pt[a] + noise * rng.normal());
            points.push(Point3D { xyz, rgb });
        }
    }
    write_points(&points, out)?;
    Ok(points)
}

/// Writes a COLMAP text model (sparse/0) with one PINHOLE camera per image, as the cameras are
/// (each with its own size and intrinsics), and `points`.
pub(super) fn write_pinhole_model(cameras: &[Camera], points: &[Point3D], out: &Path) -> Result<()> {
    let mut cams = String::from("# Camera list: CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]\n");
    for (i, c) in cameras.iter().enumerate() {
        cams += &format!("{} PINHOLE {} {} {} {} {} {}\n", i + 1, c.width, c.height, c.fx, c.fy, c.cx, c.cy);
    }
    write_atomic(&out.join("sparse/0/cameras.txt"), |w| w.write_all(cams.as_bytes()).map_err(Into::into))?;
    write_images(cameras, |i| i + 1, out)?;
    write_points(points, out)
}

/// images.txt: each camera's pose, with the camera id `camera_id(index)`.
fn write_images(cameras: &[Camera], camera_id: impl Fn(usize) -> usize, out: &Path) -> Result<()> {
    let mut images =
        String::from("# Image list: IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME, then an empty points line\n");
    for (i, cam) in cameras.iter().enumerate() {
        let q = qvec_from_rotation(&cam.rotation);
        let t = cam.translation;
        let id = camera_id(i);
        images += &format!(
            "{} {} {} {} {} {} {} {} {id} {}.png\n\n",
            i + 1,
            q[0],
            q[1],
            q[2],
            q[3],
            t[0],
            t[1],
            t[2],
            cam.name
        );
    }
    write_atomic(&out.join("sparse/0/images.txt"), |w| w.write_all(images.as_bytes()).map_err(Into::into))
}

/// points3D.txt without tracks.
fn write_points(points: &[Point3D], out: &Path) -> Result<()> {
    let mut text = String::from("# 3D point list: POINT3D_ID X Y Z R G B ERROR TRACK[]\n");
    for (id, p) in points.iter().enumerate() {
        let ([x, y, z], [r, g, b]) = (p.xyz, p.rgb);
        text += &format!("{} {x} {y} {z} {r} {g} {b} 0.5\n", id + 1);
    }
    write_atomic(&out.join("sparse/0/points3D.txt"), |w| w.write_all(text.as_bytes()).map_err(Into::into))
}

/// The transform `ns-process-data` applies to a COLMAP world (x and y swapped, z flipped); the
/// synth writes it as `applied_transform` so that a reader must undo it.
const APPLIED: [[f64; 4]; 3] = [[0.0, 1.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.0, 0.0, -1.0, 0.0]];

/// Writes the same capture as a nerfstudio `transforms.json` (OpenGL camera axes, the world moved
/// by `APPLIED`) with its points in `sparse_pc.ply`.
pub(super) fn write_transforms(cfg: &SynthConfig, cameras: &[Camera], points: &[Point3D], out: &Path) -> Result<()> {
    let rotate = |v: [f64; 3]| [0, 1, 2].map(|row| (0..3).map(|c| APPLIED[row][c] * v[c]).sum::<f64>());
    let apply = |p: [f64; 3]| {
        let r = rotate(p);
        [0, 1, 2].map(|row| r[row] + APPLIED[row][3])
    };
    let frames: Vec<serde_json::Value> = cameras
        .iter()
        .map(|cam| {
            // camera-to-world in OpenGL axes: the columns of R^T (the rows of R), y and z negated,
            // then moved by APPLIED
            let r = &cam.rotation;
            let cols = [rotate(r[0]), rotate(r[1].map(|v| -v)), rotate(r[2].map(|v| -v))];
            let c = apply(cam.center());
            let m: Vec<[f64; 4]> = (0..3).map(|row| [cols[0][row], cols[1][row], cols[2][row], c[row]]).collect();
            serde_json::json!({
                "file_path": format!("images/{}.png", cam.name),
                "transform_matrix": [m[0], m[1], m[2], [0.0, 0.0, 0.0, 1.0]],
            })
        })
        .collect();
    let c0 = &cameras[0];
    let [k1, k2, p1, p2] = cfg.distortion;
    let json = serde_json::json!({
        "camera_model": "OPENCV",
        "fl_x": c0.fx, "fl_y": c0.fy, "cx": c0.cx, "cy": c0.cy, "w": cfg.width, "h": cfg.height,
        "k1": k1, "k2": k2, "p1": p1, "p2": p2,
        "applied_transform": APPLIED,
        "ply_file_path": "sparse_pc.ply",
        "frames": frames,
    });
    let text = serde_json::to_string_pretty(&json)?;
    write_atomic(&out.join("transforms.json"), |w| w.write_all(text.as_bytes()).map_err(Into::into))?;
    let mut ply = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n",
        points.len()
    );
    for p in points {
        let [x, y, z] = apply(p.xyz);
        ply += &format!("{x} {y} {z} {} {} {}\n", p.rgb[0], p.rgb[1], p.rgb[2]);
    }
    write_atomic(&out.join("sparse_pc.ply"), |w| w.write_all(ply.as_bytes()).map_err(Into::into))
}
