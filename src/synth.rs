//! `cogeo synth`: procedural datasets with exact ground truth, ray-cast on the CPU and independent of
//! the Gaussian renderer. A closed room (textured floor, cylindrical brick wall, noisy ceiling) holds
//! 1..8 Lambertian objects (boxes, spheres, cylinders, tori) that occlude each other and the room.
//! Writes a COLMAP text model, `images/`, instance maps `object_mask/` (0 = background, q = object q),
//! and the removal ground truth: each view without objects (`gt_background/`), depth with and
//! without objects (`depth/`, `depth_background/`, EXR, camera z), and `unseen_mask/` marking
//! background that no training view sees.

use crate::io::{write_atomic, write_exr, write_png, write_png_rgb};
use crate::rng::Rng;
use crate::scene::Camera;
use crate::train::dataset::is_test_view;
use anyhow::{bail, Context, Result};
use std::io::Write;
use std::path::Path;

type V3 = [f64; 3];

fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn norm(a: V3) -> V3 {
    scale(a, 1.0 / dot(a, a).sqrt())
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, clap::ValueEnum)]
pub enum Rig {
    /// Cameras on a 40-degree arc in front of the objects (SPIn-NeRF-like captures).
    Forward,
    /// Cameras all around the objects.
    Orbit,
}

#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub enum Shape {
    Box,
    Sphere,
    Cylinder,
    Torus,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct Object {
    /// Instance label in the masks (1-based).
    pub label: u8,
    pub shape: Shape,
    pub center: V3,
    /// Half extent (box), radius (sphere, cylinder), ring radius (torus).
    pub size: f64,
    pub albedo: V3,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct SynthConfig {
    pub width: u32,
    pub height: u32,
    pub views: usize,
    pub objects: usize,
    pub rig: Rig,
    pub seed: u64,
    /// Sparse points sampled from each training view for the COLMAP model.
    pub points_per_view: usize,
    /// Also write the ground truth of removing just these objects (`without_<labels>/`); empty:
    /// only the all-objects-removed ground truth.
    pub gt_without: Vec<u8>,
    /// Color samples per pixel side: each pixel's color is the mean of `supersample`^2 rays on a
    /// regular grid over its area (a camera integrates light over the pixel; 1 = the pixel center
    /// only, which aliases fine texture differently in every view). Depth, labels and points stay
    /// at the pixel center.
    pub supersample: u32,
}

/// Where a synth dataset keeps the ground truth of removing `labels`: the scene ray-cast without
/// exactly those objects (`images`), its depth, and the never-seen mask of its surface.
pub struct GroundTruth {
    pub images: std::path::PathBuf,
    pub depth: std::path::PathBuf,
    pub unseen: std::path::PathBuf,
    /// False when only the all-objects-removed ground truth exists although some objects stay:
    /// objects kept behind removed ones then differ from the truth.
    pub exact: bool,
}

/// Name of the subset ground-truth folder, e.g. `without_1-2`.
pub fn subset_dir_name(labels: &[u8]) -> String {
    let mut l = labels.to_vec();
    l.sort();
    l.dedup();
    format!("without_{}", l.iter().map(|v| v.to_string()).collect::<Vec<_>>().join("-"))
}

/// The ground truth of removing `labels` from the synth dataset `data`.
pub fn ground_truth(data: &Path, labels: &[u8]) -> GroundTruth {
    let sub = data.join(subset_dir_name(labels));
    if sub.is_dir() {
        return GroundTruth {
            images: sub.join("images"),
            depth: sub.join("depth"),
            unseen: sub.join("unseen_mask"),
            exact: true,
        };
    }
    // every object removed: the background ground truth is exact
    let objects = std::fs::read_to_string(data.join("synth.json"))
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .and_then(|m| {
            m["objects"].as_array().map(|a| a.iter().filter_map(|o| o["label"].as_u64()).collect::<Vec<_>>())
        });
    let exact = objects.is_some_and(|all| all.iter().all(|l| labels.contains(&(*l as u8))));
    GroundTruth {
        images: data.join("gt_background"),
        depth: data.join("depth_background"),
        unseen: data.join("unseen_mask"),
        exact,
    }
}

const ROOM_RADIUS: f64 = 6.0;
const ROOM_HEIGHT: f64 = 4.0;
const LIGHT: V3 = [0.48, -0.36, 0.8];

impl Object {
    /// Signed distance from p to the object's surface.
    fn sdf(&self, p: V3) -> f64 {
        let q = sub(p, self.center);
        let s = self.size;
        match self.shape {
            Shape::Sphere => dot(q, q).sqrt() - s,
            Shape::Box => {
                let d = q.map(|v| v.abs() - s);
                let outside = d.map(|v| v.max(0.0));
                dot(outside, outside).sqrt() + d[0].max(d[1]).max(d[2]).min(0.0)
            }
            Shape::Cylinder => {
                // vertical, radius s, half height 1.2 s
                let r = (q[0] * q[0] + q[1] * q[1]).sqrt() - s;
                let h = q[2].abs() - 1.2 * s;
                let outside = (r.max(0.0).powi(2) + h.max(0.0).powi(2)).sqrt();
                outside + r.max(h).min(0.0)
            }
            Shape::Torus => {
                // standing upright in the x-z plane, ring radius s, tube 0.35 s
                let ring = (q[0] * q[0] + q[2] * q[2]).sqrt() - s;
                (ring * ring + q[1] * q[1]).sqrt() - 0.35 * s
            }
        }
    }
}

/// Deterministic value noise in [0, 1].
fn hash(x: i64, y: i64, seed: u64) -> f64 {
    let mut h = (x as u64).wrapping_mul(0x9E3779B97F4A7C15) ^ (y as u64).wrapping_mul(0xC2B2AE3D27D4EB4F) ^ seed;
    h ^= h >> 29;
    h = h.wrapping_mul(0xBF58476D1CE4E5B9);
    h ^= h >> 32;
    (h >> 11) as f64 / (1u64 << 53) as f64
}

fn value_noise(u: f64, v: f64, seed: u64) -> f64 {
    let (x0, y0) = (u.floor(), v.floor());
    let (fx, fy) = (u - x0, v - y0);
    let (sx, sy) = (fx * fx * (3.0 - 2.0 * fx), fy * fy * (3.0 - 2.0 * fy));
    let (x0, y0) = (x0 as i64, y0 as i64);
    let a = hash(x0, y0, seed) * (1.0 - sx) + hash(x0 + 1, y0, seed) * sx;
    let b = hash(x0, y0 + 1, seed) * (1.0 - sx) + hash(x0 + 1, y0 + 1, seed) * sx;
    a * (1.0 - sy) + b * sy
}

/// Noise at several frequencies.
fn fractal_noise(u: f64, v: f64, seed: u64) -> f64 {
    (0..4).map(|o| value_noise(u * (1 << o) as f64, v * (1 << o) as f64, seed + o) / (1 << o) as f64).sum::<f64>()
        / 1.875
}

/// What a ray hits: distance along the ray, point, normal, albedo, object label (0 = room).
struct Hit {
    t: f64,
    point: V3,
    normal: V3,
    albedo: V3,
    label: u8,
}

fn room_hit(o: V3, d: V3, seed: u64) -> Hit {
    let mut best = (f64::INFINITY, 0);
    if d[2] < -1e-12 {
        best = best.min_by_t((-o[2] / d[2], 1)); // floor z = 0
    }
    if d[2] > 1e-12 {
        best = best.min_by_t(((ROOM_HEIGHT - o[2]) / d[2], 2)); // ceiling
    }
    // cylinder wall x^2 + y^2 = R^2 (we are inside: take the far root)
    let a = d[0] * d[0] + d[1] * d[1];
    if a > 1e-12 {
        let b = o[0] * d[0] + o[1] * d[1];
        let c = o[0] * o[0] + o[1] * o[1] - ROOM_RADIUS * ROOM_RADIUS;
        let disc = b * b - a * c;
        if disc >= 0.0 {
            best = best.min_by_t(((-b + disc.sqrt()) / a, 3));
        }
    }
    let (t, which) = best;
    let p = add(o, scale(d, t));
    let (normal, albedo) = match which {
        1 => {
            let check = (((p[0] / 0.5).floor() + (p[1] / 0.5).floor()) as i64).rem_euclid(2) == 0;
            let n = fractal_noise(p[0] * 3.0, p[1] * 3.0, seed);
            let base = if check { [0.82, 0.78, 0.7] } else { [0.32, 0.36, 0.45] };
            ([0.0, 0.0, 1.0], base.map(|c| c * (0.8 + 0.4 * n)))
        }
        2 => {
            let n = fractal_noise(p[0] * 1.5, p[1] * 1.5, seed + 7);
            ([0.0, 0.0, -1.0], [0.6 + 0.3 * n, 0.62 + 0.3 * n, 0.68 + 0.25 * n])
        }
        _ => {
            // bricks on the wall: u along the circumference, v up
            let u = p[1].atan2(p[0]) * ROOM_RADIUS / 0.6;
            let v = p[2] / 0.3;
            let row = v.floor();
            let uu = u + if (row as i64).rem_euclid(2) == 0 { 0.0 } else { 0.5 };
            let mortar = (uu - uu.floor()) < 0.06 || (v - row) < 0.1;
            let n = fractal_noise(u * 2.0, v * 2.0, seed + 13);
            let brick =
                [0.62 + 0.2 * hash(uu.floor() as i64, row as i64, seed), 0.33, 0.26].map(|c| c * (0.85 + 0.3 * n));
            (norm([-p[0], -p[1], 0.0]), if mortar { [0.78, 0.76, 0.72] } else { brick })
        }
    };
    Hit { t, point: p, normal, albedo, label: 0 }
}

trait MinByT {
    fn min_by_t(self, other: (f64, u8)) -> (f64, u8);
}
impl MinByT for (f64, u8) {
    fn min_by_t(self, other: (f64, u8)) -> (f64, u8) {
        if other.0 > 1e-9 && other.0 < self.0 {
            other
        } else {
            self
        }
    }
}

/// Sphere tracing against the objects, up to `t_max`.
fn object_hit(o: V3, d: V3, objects: &[Object], t_max: f64, seed: u64) -> Option<Hit> {
    if objects.is_empty() {
        return None;
    }
    let sdf = |p: V3| objects.iter().map(|ob| (ob.sdf(p), ob)).min_by(|a, b| a.0.partial_cmp(&b.0).unwrap()).unwrap();
    let mut t = 1e-4;
    for _ in 0..256 {
        let p = add(o, scale(d, t));
        let (dist, ob) = sdf(p);
        if dist < 1e-5 * (1.0 + t) {
            let e = 1e-5;
            let g = |axis: usize| {
                let mut a = p;
                let mut b = p;
                a[axis] += e;
                b[axis] -= e;
                ob.sdf(a) - ob.sdf(b)
            };
            let n = norm([g(0), g(1), g(2)]);
            let rel = sub(p, ob.center);
            let tex = 0.9
                + 0.2 * fractal_noise(rel[0] * 4.0 + rel[2] * 3.0, rel[1] * 4.0 - rel[2] * 2.0, seed + ob.label as u64);
            return Some(Hit { t, point: p, normal: n, albedo: ob.albedo.map(|c| c * tex), label: ob.label });
        }
        t += dist;
        if t > t_max {
            return None;
        }
    }
    None
}

fn trace(o: V3, d: V3, objects: &[Object], seed: u64) -> Hit {
    let room = room_hit(o, d, seed);
    object_hit(o, d, objects, room.t, seed).unwrap_or(room)
}

fn shade(h: &Hit) -> V3 {
    let l = norm(LIGHT);
    let lambert = dot(h.normal, l).max(0.0);
    h.albedo.map(|c| (c * (0.4 + 0.6 * lambert)).clamp(0.0, 1.0))
}

/// Per-view renders of one configuration of the scene.
pub struct ViewRender {
    pub rgb: Vec<f32>,
    /// Camera-frame z of the surface at each pixel center.
    pub depth: Vec<f32>,
    pub points: Vec<V3>,
    pub labels: Vec<u8>,
}

/// Ray-casts one camera: depth, label and surface point at each pixel center, color as the mean of
/// `supersample`^2 rays spread evenly over the pixel (1: the center ray only).
pub fn render_view(cam: &Camera, objects: &[Object], seed: u64, supersample: u32) -> ViewRender {
    let s = supersample.max(1);
    let (w, h) = (cam.width as usize, cam.height as usize);
    let center = cam.center();
    let r = cam.rotation;
    let rows: Vec<ViewRender> = {
        use rayon::prelude::*;
        (0..h)
            .into_par_iter()
            .map(|y| {
                let mut out = ViewRender {
                    rgb: vec![0.0; 3 * w],
                    depth: vec![0.0; w],
                    points: Vec::with_capacity(w),
                    labels: vec![0; w],
                };
                let ray = |px: f64, py: f64| {
                    let cx = (px - cam.cx) / cam.fx;
                    let cy = (py - cam.cy) / cam.fy;
                    // camera ray (cx, cy, 1) to world: R^T
                    let dc = [cx, cy, 1.0];
                    norm([
                        r[0][0] * dc[0] + r[1][0] * dc[1] + r[2][0] * dc[2],
                        r[0][1] * dc[0] + r[1][1] * dc[1] + r[2][1] * dc[2],
                        r[0][2] * dc[0] + r[1][2] * dc[1] + r[2][2] * dc[2],
                    ])
                };
                for x in 0..w {
                    let hit = trace(center, ray(x as f64 + 0.5, y as f64 + 0.5), objects, seed);
                    let c = if s == 1 {
                        shade(&hit)
                    } else {
                        let mut sum = [0.0; 3];
                        for sy in 0..s {
                            for sx in 0..s {
                                let px = x as f64 + (sx as f64 + 0.5) / s as f64;
                                let py = y as f64 + (sy as f64 + 0.5) / s as f64;
                                sum = add(sum, shade(&trace(center, ray(px, py), objects, seed)));
                            }
                        }
                        scale(sum, 1.0 / (s * s) as f64)
                    };
                    for ch in 0..3 {
                        out.rgb[ch * w + x] = c[ch] as f32;
                    }
                    out.depth[x] = cam.to_camera(hit.point)[2] as f32;
                    out.points.push(hit.point);
                    out.labels[x] = hit.label;
                }
                out
            })
            .collect()
    };
    let mut out = ViewRender {
        rgb: vec![0.0; 3 * w * h],
        depth: Vec::with_capacity(w * h),
        points: Vec::with_capacity(w * h),
        labels: Vec::with_capacity(w * h),
    };
    for (y, row) in rows.into_iter().enumerate() {
        for ch in 0..3 {
            out.rgb[ch * w * h + y * w..ch * w * h + (y + 1) * w].copy_from_slice(&row.rgb[ch * w..(ch + 1) * w]);
        }
        out.depth.extend(row.depth);
        out.points.extend(row.points);
        out.labels.extend(row.labels);
    }
    out
}

/// The objects of a configuration: non-overlapping, resting on the floor near the center.
pub fn make_objects(count: usize, rng: &mut Rng) -> Vec<Object> {
    let palette = [
        [0.85, 0.2, 0.18],
        [0.2, 0.65, 0.3],
        [0.2, 0.35, 0.85],
        [0.9, 0.75, 0.15],
        [0.7, 0.3, 0.8],
        [0.15, 0.75, 0.8],
        [0.95, 0.5, 0.2],
        [0.55, 0.55, 0.55],
    ];
    let shapes = [Shape::Box, Shape::Sphere, Shape::Cylinder, Shape::Torus];
    let mut objects: Vec<Object> = Vec::new();
    let mut attempts = 0;
    while objects.len() < count && attempts < 10_000 {
        attempts += 1;
        let shape = shapes[(objects.len() + rng.next_u64() as usize % 2) % 4];
        let size = rng.range(0.3, 0.5);
        let (x, y) = (rng.range(-1.5, 1.5), rng.range(-1.0, 1.0));
        let extent = match shape {
            Shape::Torus => 1.35 * size,
            Shape::Cylinder => 1.2 * size,
            _ => size,
        };
        let center = [x, y, extent];
        if objects
            .iter()
            .any(|o| ((o.center[0] - x).powi(2) + (o.center[1] - y).powi(2)).sqrt() < o.size * 1.4 + size * 1.4 + 0.1)
        {
            continue;
        }
        let label = objects.len() as u8 + 1;
        objects.push(Object { label, shape, center, size, albedo: palette[objects.len() % palette.len()] });
    }
    objects
}

/// The camera rig: `views` cameras looking at the objects.
pub fn make_cameras(cfg: &SynthConfig) -> Vec<Camera> {
    (0..cfg.views)
        .map(|i| {
            let f = i as f64 / cfg.views as f64;
            let (angle, radius, height) = match cfg.rig {
                Rig::Forward => (
                    -std::f64::consts::FRAC_PI_2 + (f - 0.5) * 0.7,
                    4.2 + 0.3 * (i % 3) as f64,
                    1.4 + 0.25 * (i % 2) as f64,
                ),
                Rig::Orbit => (f * std::f64::consts::TAU, 4.0, 1.5 + 0.4 * (i % 2) as f64),
            };
            let eye = [radius * angle.cos(), radius * angle.sin(), height];
            Camera::look_at(
                &format!("view_{i:03}"),
                cfg.width,
                cfg.height,
                55.0,
                eye,
                [0.0, 0.0, 0.45],
                [0.0, 0.0, 1.0],
            )
        })
        .collect()
}

/// COLMAP quaternion (w, x, y, z) of a rotation matrix.
pub fn qvec_from_rotation(r: &[[f64; 3]; 3]) -> [f64; 4] {
    let trace = r[0][0] + r[1][1] + r[2][2];
    let q = if trace > 0.0 {
        let s = 0.5 / (trace + 1.0).sqrt();
        [0.25 / s, (r[2][1] - r[1][2]) * s, (r[0][2] - r[2][0]) * s, (r[1][0] - r[0][1]) * s]
    } else if r[0][0] > r[1][1] && r[0][0] > r[2][2] {
        let s = 2.0 * (1.0 + r[0][0] - r[1][1] - r[2][2]).sqrt();
        [(r[2][1] - r[1][2]) / s, 0.25 * s, (r[0][1] + r[1][0]) / s, (r[0][2] + r[2][0]) / s]
    } else if r[1][1] > r[2][2] {
        let s = 2.0 * (1.0 + r[1][1] - r[0][0] - r[2][2]).sqrt();
        [(r[0][2] - r[2][0]) / s, (r[0][1] + r[1][0]) / s, 0.25 * s, (r[1][2] + r[2][1]) / s]
    } else {
        let s = 2.0 * (1.0 + r[2][2] - r[0][0] - r[1][1]).sqrt();
        [(r[1][0] - r[0][1]) / s, (r[0][2] + r[2][0]) / s, (r[1][2] + r[2][1]) / s, 0.25 * s]
    };
    let sign = if q[0] < 0.0 { -1.0 } else { 1.0 };
    q.map(|v| v * sign)
}

/// Generates the dataset into `out` (created; must be empty or absent).
pub fn generate(cfg: &SynthConfig, out: &Path, progress: &dyn Fn(usize, usize)) -> Result<Vec<Object>> {
    if cfg.objects == 0 || cfg.objects > 8 {
        bail!("--objects must be 1..8, got {}", cfg.objects);
    }
    if cfg.views < 2 || cfg.width < 8 || cfg.height < 8 {
        bail!("need at least 2 views of at least 8x8 pixels");
    }
    if out.exists() && std::fs::read_dir(out)?.next().is_some() {
        bail!("{}: output folder is not empty", out.display());
    }
    if cfg.gt_without.iter().any(|&l| l == 0 || l as usize > cfg.objects) {
        bail!("--gt-without: labels must be 1..={}", cfg.objects);
    }
    let subset_dir = (!cfg.gt_without.is_empty()).then(|| subset_dir_name(&cfg.gt_without));
    let mut folders: Vec<String> =
        ["images", "object_mask", "gt_background", "depth", "depth_background", "unseen_mask", "sparse/0"]
            .map(String::from)
            .to_vec();
    if let Some(d) = &subset_dir {
        folders.extend(["images", "depth", "unseen_mask"].map(|f| format!("{d}/{f}")));
    }
    for sub in &folders {
        std::fs::create_dir_all(out.join(sub))
            .with_context(|| format!("{}: cannot create", out.join(sub).display()))?;
    }
    let mut rng = Rng::new(cfg.seed);
    let objects = make_objects(cfg.objects, &mut rng);
    if objects.len() < cfg.objects {
        bail!("could not place {} non-overlapping objects", cfg.objects);
    }
    let cameras = make_cameras(cfg);
    let mut with_objects = Vec::new();
    let mut background = Vec::new();
    let mut without_subset = Vec::new();
    let kept: Vec<Object> = objects.iter().filter(|o| !cfg.gt_without.contains(&o.label)).cloned().collect();
    for (i, cam) in cameras.iter().enumerate() {
        with_objects.push(render_view(cam, &objects, cfg.seed, cfg.supersample));
        background.push(render_view(cam, &[], cfg.seed, cfg.supersample));
        if subset_dir.is_some() {
            without_subset.push(render_view(cam, &kept, cfg.seed, cfg.supersample));
        }
        progress(i + 1, 2 * cameras.len());
    }
    let train: Vec<usize> = (0..cameras.len()).filter(|&i| !is_test_view(i)).collect();
    for (i, cam) in cameras.iter().enumerate() {
        let (w, h) = (cfg.width, cfg.height);
        let name = &cam.name;
        let v = &with_objects[i];
        let b = &background[i];
        write_png_rgb(&out.join(format!("images/{name}.png")), w, h, &v.rgb)?;
        write_png_rgb(&out.join(format!("gt_background/{name}.png")), w, h, &b.rgb)?;
        write_png(&out.join(format!("object_mask/{name}.png")), w, h, image::ColorType::L8, &v.labels)?;
        write_exr(&out.join(format!("depth/{name}.exr")), w, h, &[("Y", &v.depth)])?;
        write_exr(&out.join(format!("depth_background/{name}.exr")), w, h, &[("Y", &b.depth)])?;
        // background never seen: its surface point is visible (not behind an object) in no training view
        let unseen = never_seen(&b.points, &cameras, &train, &with_objects);
        write_png(&out.join(format!("unseen_mask/{name}.png")), w, h, image::ColorType::L8, &unseen)?;
        if let Some(d) = &subset_dir {
            let s = &without_subset[i];
            write_png_rgb(&out.join(format!("{d}/images/{name}.png")), w, h, &s.rgb)?;
            write_exr(&out.join(format!("{d}/depth/{name}.exr")), w, h, &[("Y", &s.depth)])?;
            let unseen = never_seen(&s.points, &cameras, &train, &with_objects);
            write_png(&out.join(format!("{d}/unseen_mask/{name}.png")), w, h, image::ColorType::L8, &unseen)?;
        }
        progress(cameras.len() + i + 1, 2 * cameras.len());
    }
    write_colmap(cfg, &cameras, &with_objects, &train, out, &mut rng)?;
    let meta = serde_json::json!({ "config": cfg, "objects": objects, "test_views": (0..cameras.len()).filter(|&i| is_test_view(i)).collect::<Vec<_>>() });
    let text = serde_json::to_string_pretty(&meta)?;
    write_atomic(&out.join("synth.json"), |w| w.write_all(text.as_bytes()).map_err(Into::into))?;
    Ok(objects)
}

/// 255 where the surface point of a pixel is visible in no training view of the full scene.
fn never_seen(points: &[V3], cameras: &[Camera], train: &[usize], with_objects: &[ViewRender]) -> Vec<u8> {
    points
        .iter()
        .map(|&point| {
            let seen = train.iter().any(|&t| {
                let tc = &cameras[t];
                let pc = tc.to_camera(point);
                if pc[2] <= 1e-6 {
                    return false;
                }
                let u = tc.fx * pc[0] / pc[2] + tc.cx;
                let vv = tc.fy * pc[1] / pc[2] + tc.cy;
                if u < 0.0 || vv < 0.0 || u >= tc.width as f64 || vv >= tc.height as f64 {
                    return false;
                }
                let q = vv as usize * tc.width as usize + u as usize;
                (with_objects[t].depth[q] as f64 - pc[2]).abs() <= 0.02 * pc[2]
            });
            if seen {
                0
            } else {
                255
            }
        })
        .collect()
}

fn write_colmap(
    cfg: &SynthConfig,
    cameras: &[Camera],
    renders: &[ViewRender],
    train: &[usize],
    out: &Path,
    rng: &mut Rng,
) -> Result<()> {
    let c0 = &cameras[0];
    let cams =
        format!("# Camera list\n1 PINHOLE {} {} {} {} {} {}\n", cfg.width, cfg.height, c0.fx, c0.fy, c0.cx, c0.cy);
    write_atomic(&out.join("sparse/0/cameras.txt"), |w| w.write_all(cams.as_bytes()).map_err(Into::into))?;
    let mut images =
        String::from("# Image list: IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME, then an empty points line\n");
    for (i, cam) in cameras.iter().enumerate() {
        let q = qvec_from_rotation(&cam.rotation);
        let t = cam.translation;
        images +=
            &format!("{} {} {} {} {} {} {} {} 1 {}.png\n\n", i + 1, q[0], q[1], q[2], q[3], t[0], t[1], t[2], cam.name);
    }
    write_atomic(&out.join("sparse/0/images.txt"), |w| w.write_all(images.as_bytes()).map_err(Into::into))?;
    // sparse points: surface points seen by training views, with SfM-like noise
    let hw = (cfg.width * cfg.height) as usize;
    let mut points = String::from("# 3D point list: POINT3D_ID X Y Z R G B ERROR TRACK[]\n");
    let mut id = 1;
    for &t in train {
        for _ in 0..cfg.points_per_view.max(4) {
            let p = (rng.next_u64() % hw as u64) as usize;
            let pt = renders[t].points[p];
            let noise = 0.01;
            let rgb: Vec<u8> = (0..3).map(|c| crate::io::to_u8(renders[t].rgb[c * hw + p])).collect();
            points += &format!(
                "{id} {} {} {} {} {} {} 0.5\n",
                pt[0] + noise * rng.normal(),
                pt[1] + noise * rng.normal(),
                pt[2] + noise * rng.normal(),
                rgb[0],
                rgb[1],
                rgb[2]
            );
            id += 1;
        }
    }
    write_atomic(&out.join("sparse/0/points3D.txt"), |w| w.write_all(points.as_bytes()).map_err(Into::into))?;
    Ok(())
}
