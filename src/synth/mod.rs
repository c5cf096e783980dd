//! `cogeo synth`: procedural datasets with exact ground truth, ray-cast on the CPU and independent of
//! the Gaussian renderer. A closed room (textured floor, cylindrical brick wall, noisy ceiling) holds
//! 1..8 Lambertian objects (boxes, spheres, cylinders, tori) that occlude each other and the room.
//! Writes a COLMAP text model, `images/`, instance maps `object_mask/` (0 = background, q = object q),
//! and the removal ground truth: each view without objects (`gt_background/`), depth with and
//! without objects (`depth/`, `depth_background/`, EXR, camera z), and `unseen_mask/` marking
//! background that no training view sees.

use crate::io::{write_atomic, write_exr, write_png, write_png_rgb};
use crate::rng::Rng;
use crate::scene::dataset::is_test_view;
use crate::scene::lens::Lens;
use crate::scene::Camera;
use anyhow::{bail, Context, Result};
use raycast::V3;
use std::io::Write;
use std::path::Path;

mod capture_files;
pub mod composite;
mod raycast;

pub use raycast::{render_view, render_view_through, Object, Shape, ViewRender};

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, clap::ValueEnum)]
pub enum Rig {
    /// Cameras on a 40-degree arc in front of the objects (SPIn-NeRF-like captures).
    Forward,
    /// Cameras all around the objects.
    Orbit,
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
    /// Lens distortion k1, k2, p1, p2 of every view (COLMAP's OPENCV model; all 0: a pinhole):
    /// the photos, masks and ground truth are ray-cast through it, and the model says OPENCV.
    pub distortion: [f64; 4],
    /// Each view's photos (images/ and its ground truth) are multiplied per channel by a gain
    /// drawn uniformly from [1 - x, 1 + x] (0: none), as a phone's exposure and white balance
    /// change from shot to shot; synth.json lists the gains (`exposure_gains`).
    pub exposure_jitter: f64,
}

impl SynthConfig {
    /// Each view's per-channel exposure gains (all 1 without jitter), from their own random
    /// stream so that everything else a seed makes stays the same.
    pub fn exposure_gains(&self) -> Vec<[f64; 3]> {
        let mut rng = Rng::new(self.seed ^ 0x6578_706f_7375_7265);
        (0..self.views).map(|_| std::array::from_fn(|_| 1.0 + self.exposure_jitter * rng.range(-1.0, 1.0))).collect()
    }

    /// The views' lens.
    pub fn lens(&self) -> Lens {
        let [k1, k2, p1, p2] = self.distortion;
        if self.distortion == [0.0; 4] {
            Lens::Pinhole
        } else {
            Lens::OpenCv { k: [k1, k2, 0.0, 0.0, 0.0, 0.0], p: [p1, p2] }
        }
    }
}

/// Relative depth agreement for a training view to have seen a surface point (exact depths).
const SEEN_TOLERANCE: f64 = 0.02;

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
        let center = [x, y, shape.half_height(size)];
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
    create_folders(out, subset_dir.as_deref())?;
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
    let lens = cfg.lens();
    let gains = cfg.exposure_gains();
    // what the view's camera records: the light through its exposure gains, saturating at white
    let photograph = |mut v: ViewRender, gain: [f64; 3]| {
        let hw = v.depth.len();
        for (c, g) in gain.iter().enumerate() {
            for x in &mut v.rgb[c * hw..(c + 1) * hw] {
                *x = (*x as f64 * g).min(1.0) as f32;
            }
        }
        v
    };
    for (i, cam) in cameras.iter().enumerate() {
        let shoot = |objects: &[Object]| {
            photograph(render_view_through(cam, lens, objects, cfg.seed, cfg.supersample), gains[i])
        };
        with_objects.push(shoot(&objects));
        background.push(shoot(&[]));
        if subset_dir.is_some() {
            without_subset.push(shoot(&kept));
        }
        progress(i + 1, 2 * cameras.len());
    }
    let train: Vec<usize> = (0..cameras.len()).filter(|&i| !is_test_view(i)).collect();
    let depths: Vec<&[f32]> = with_objects.iter().map(|v| &v.depth[..]).collect();
    let seen_by = |points: &[V3]| {
        let points: Vec<Option<V3>> = points.iter().copied().map(Some).collect();
        never_seen(&points, &cameras, lens, &train, &depths, SEEN_TOLERANCE, 0)
    };
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
        let unseen = seen_by(&b.points);
        write_png(&out.join(format!("unseen_mask/{name}.png")), w, h, image::ColorType::L8, &unseen)?;
        if let Some(d) = &subset_dir {
            let s = &without_subset[i];
            write_png_rgb(&out.join(format!("{d}/images/{name}.png")), w, h, &s.rgb)?;
            write_exr(&out.join(format!("{d}/depth/{name}.exr")), w, h, &[("Y", &s.depth)])?;
            let unseen = seen_by(&s.points);
            write_png(&out.join(format!("{d}/unseen_mask/{name}.png")), w, h, image::ColorType::L8, &unseen)?;
        }
        progress(cameras.len() + i + 1, 2 * cameras.len());
    }
    let points = capture_files::write_colmap(cfg, &cameras, &with_objects, &train, out, &mut rng)?;
    capture_files::write_transforms(cfg, &cameras, &points, out)?;
    let mut meta = serde_json::json!({ "config": cfg, "objects": objects, "test_views": (0..cameras.len()).filter(|&i| is_test_view(i)).collect::<Vec<_>>() });
    if cfg.exposure_jitter != 0.0 {
        meta["exposure_gains"] = serde_json::json!(gains);
    }
    let text = serde_json::to_string_pretty(&meta)?;
    write_atomic(&out.join("synth.json"), |w| w.write_all(text.as_bytes()).map_err(Into::into))?;
    Ok(objects)
}

/// The folders of a synth dataset in `out`, with those of the subset ground truth `subset_dir`.
fn create_folders(out: &Path, subset_dir: Option<&str>) -> Result<()> {
    let mut folders: Vec<String> =
        ["images", "object_mask", "gt_background", "depth", "depth_background", "unseen_mask", "sparse/0"]
            .map(String::from)
            .to_vec();
    if let Some(d) = subset_dir {
        folders.extend(["images", "depth", "unseen_mask"].map(|f| format!("{d}/{f}")));
    }
    for sub in &folders {
        std::fs::create_dir_all(out.join(sub))
            .with_context(|| format!("{}: cannot create", out.join(sub).display()))?;
    }
    Ok(())
}

/// 255 where the surface point of a pixel is visible in no training view of the full scene: no
/// training view's depth (`depths`, the scene with its objects) within `reach` pixels of where the
/// point lands is within `tolerance` (relative) of the point's own. Pixels without a point
/// (nothing there) are 0. A `reach` of 1 keeps a rendered depth's pixel steps from counting as
/// unseen where a view sees a surface at a grazing angle (one pixel there spans more depth than
/// the tolerance).
fn never_seen(
    points: &[Option<V3>],
    cameras: &[Camera],
    lens: Lens,
    train: &[usize],
    depths: &[&[f32]],
    tolerance: f64,
    reach: usize,
) -> Vec<u8> {
    points
        .iter()
        .map(|point| {
            let Some(point) = *point else { return 0 };
            let seen = train.iter().any(|&t| seen_in(&cameras[t], lens, depths[t], point, tolerance, reach));
            if seen {
                0
            } else {
                255
            }
        })
        .collect()
}

/// Whether camera `cam` (with `lens`) sees `point`: some pixel of `depth` (its view's depth, 0
/// where it shows nothing to match) within `reach` pixels of where the point lands is within
/// `tolerance` (relative) of the point's view depth.
fn seen_in(cam: &Camera, lens: Lens, depth: &[f32], point: V3, tolerance: f64, reach: usize) -> bool {
    let Some((q, z)) = pixel_through(cam, lens, point) else { return false };
    let (w, h) = (cam.width as usize, cam.height as usize);
    let (x, y) = (q % w, q / w);
    let rows = y.saturating_sub(reach)..(y + reach + 1).min(h);
    rows.into_iter().any(|yy| {
        let cols = x.saturating_sub(reach)..(x + reach + 1).min(w);
        cols.into_iter().any(|xx| (depth[yy * w + xx] as f64 - z).abs() <= tolerance * z)
    })
}

/// The pixel (row-major index) that camera `cam` with `lens` images `point` at, and its view depth.
fn pixel_through(cam: &Camera, lens: Lens, point: V3) -> Option<(usize, f64)> {
    let pc = cam.to_camera(point);
    if pc[2] <= 1e-6 {
        return None;
    }
    let (x, y) = lens.distort(pc[0] / pc[2], pc[1] / pc[2]);
    let (px, py) = (cam.fx * x + cam.cx, cam.fy * y + cam.cy);
    let inside = px >= 0.0 && py >= 0.0 && px < cam.width as f64 && py < cam.height as f64;
    inside.then(|| (py as usize * cam.width as usize + px as usize, pc[2]))
}
