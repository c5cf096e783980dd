//! The ray caster of `cogeo synth`: a closed room (textured floor, cylindrical brick wall, noisy
//! ceiling) and Lambertian objects (boxes, spheres, cylinders, tori), shaded by one directional
//! light, traced exactly per ray on the CPU. It shares nothing with the Gaussian renderer, so the
//! images it makes are an independent ground truth.

use crate::scene::lens::Lens;
use crate::scene::Camera;

pub(crate) type V3 = [f64; 3];

pub(super) fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
pub(super) fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub(super) fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
pub(super) fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
pub(super) fn cross(a: V3, b: V3) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
pub(super) fn norm(a: V3) -> V3 {
    scale(a, 1.0 / dot(a, a).sqrt())
}

#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Shape {
    Box,
    Sphere,
    Cylinder,
    Torus,
}

impl Shape {
    /// Half the height of an object of this shape and `size` standing upright (`Object::sdf`).
    pub fn half_height(self, size: f64) -> f64 {
        match self {
            Shape::Box | Shape::Sphere => size,
            Shape::Cylinder => 1.2 * size,
            Shape::Torus => 1.35 * size,
        }
    }

    /// The radius of the circle around its footprint (a box's half diagonal; the torus stands in
    /// the x-z plane, so its ring spans 1.35 size along x).
    pub fn footprint_radius(self, size: f64) -> f64 {
        match self {
            Shape::Box => size * std::f64::consts::SQRT_2,
            Shape::Sphere | Shape::Cylinder => size,
            Shape::Torus => 1.35 * size,
        }
    }
}

#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Object {
    /// Instance label in the masks (1-based).
    pub label: u8,
    pub shape: Shape,
    pub center: V3,
    /// Half extent (box), radius (sphere, cylinder), ring radius (torus).
    pub size: f64,
    pub albedo: V3,
}

const ROOM_RADIUS: f64 = 6.0;
const ROOM_HEIGHT: f64 = 4.0;
const LIGHT: V3 = [0.48, -0.36, 0.8];

impl Object {
    /// Signed distance from p to the object's surface.
    pub fn sdf(&self, p: V3) -> f64 {
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
pub(super) struct Hit {
    pub t: f64,
    pub point: V3,
    normal: V3,
    albedo: V3,
    pub label: u8,
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
pub(super) fn object_hit(o: V3, d: V3, objects: &[Object], t_max: f64, seed: u64) -> Option<Hit> {
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

pub(super) fn shade(h: &Hit) -> V3 {
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
    render_view_through(cam, Lens::Pinhole, objects, seed, supersample)
}

/// `render_view` through a camera with `lens`: each pixel position's ray is the one the lens
/// images there (the lens model inverted, scene/lens.rs), as a real photo's is.
pub fn render_view_through(cam: &Camera, lens: Lens, objects: &[Object], seed: u64, supersample: u32) -> ViewRender {
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
                    let (cx, cy) = lens
                        .undistort((px - cam.cx) / cam.fx, (py - cam.cy) / cam.fy)
                        .expect("the synth's lens inverts across the image");
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
