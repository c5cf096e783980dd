//! `cogeo synth --composite-into CAPTURE`: a removal benchmark on real photos with exact ground
//! truth. Virtual objects (the synth's boxes and cylinders, with its texture and shading) stand on
//! the capture's supporting surface, found in the trained original scene's depth (ground.rs);
//! each is ray-cast into every photo and composited only where it is nearer than that scene's
//! depth. The photos themselves are then the ground truth of removing every object, and the
//! folder has the synth's layout, so `cogeo remove`, `cogeo eval --data` and the removal bench
//! score it as they score a synth room: images/, object_mask/, gt_background/ (the photos as
//! loaded: undistorted and downscaled), depth/ and depth_background/ (EXR, camera z; the original
//! scene's rendered depth, 0 where it is empty), unseen_mask/ (background that no training view
//! sees past the objects), optional without_<labels>/, a COLMAP text model (one PINHOLE camera
//! per image; its points are the capture's, less those the objects stand on or hide from the
//! training views, and points on the objects) and synth.json.

mod ground;

use super::raycast::{object_hit, shade, Object, V3};
use super::{never_seen, seen_in, subset_dir_name};
use crate::gpu::Gpu;
use crate::io::{write_atomic, write_exr, write_png, write_png_rgb};
use crate::render::{RenderSettings, SceneRenderer};
use crate::rng::Rng;
use crate::scene::colmap::Point3D;
use crate::scene::dataset::{self, is_test_view};
use crate::scene::lens::Lens;
use crate::scene::Camera;
use anyhow::{bail, Context, Result};
pub use ground::Ground;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The composite's settings (`cogeo synth --composite-into`).
#[derive(Clone, Debug, serde::Serialize)]
pub struct CompositeConfig {
    /// The real capture (COLMAP model or transforms.json, and its photos).
    pub capture: PathBuf,
    pub images: String,
    pub downscale: u32,
    /// The capture's scene trained without the objects: its depth says where the surfaces are.
    pub scene: PathBuf,
    pub objects: usize,
    pub seed: u64,
    /// Rays per pixel side for the objects' colors and coverage.
    pub supersample: u32,
    pub gt_without: Vec<u8>,
    /// Object half extent as a fraction of the median camera distance to what the capture looks at.
    pub object_size: f64,
    /// Darkening of the surface right around each object's footprint (0: none).
    pub contact_shadow: f64,
    /// Sparse points of the COLMAP model: the capture's own structure-from-motion points (those
    /// the objects do not swallow) plus points on the objects at the density that sampling this
    /// many points on the training views' composited depth gives; a capture with fewer than
    /// `MIN_CAPTURE_POINTS` points gets this many points of the composited depth instead.
    pub points: usize,
    /// An earlier composite's synth.json whose ground and objects are used instead of placing
    /// new ones (`read_placement`).
    pub placement: Option<PathBuf>,
}

/// One photo of the capture with the original scene's depth there.
struct CaptureView {
    camera: Camera,
    photo: Vec<f32>,
    /// Camera z of the original scene's surface; infinite where the render is empty.
    depth: Vec<f32>,
}

/// One view with some of the objects composited in.
struct Composited {
    rgb: Vec<f32>,
    /// Camera z of the nearest surface, infinite where there is none.
    depth: Vec<f32>,
    labels: Vec<u8>,
    /// Pixels where one object stands in front of another.
    overlaps: usize,
}

/// What `composite` placed.
pub struct CompositeSummary {
    pub objects: Vec<Object>,
    pub ground: Ground,
    pub views: usize,
    /// Views in which one object stands partly behind another.
    pub views_with_overlap: usize,
    /// Capture sparse points left out because the objects hide them (`hidden_by_objects`).
    pub points_hidden: usize,
}

/// The camera-z (median) depth of the original scene, treated as empty below this alpha.
const COVERED_ALPHA: f32 = 0.5;
/// Relative depth agreement for a background point to count as seen by a training view: looser
/// than the synth's 2 % since both depths are renders of Gaussians.
const SEEN_TOLERANCE: f64 = 0.03;
/// Pixels around where a background point lands in a training view whose depth may show it
/// (`never_seen`): the cup's desk, seen at a grazing angle through depths rendered at one depth
/// per pixel, came out never-seen in streaks along its grain between seen pixels
/// (bench/JOURNAL.md, 2026-11-30).
const SEEN_REACH: usize = 1;
/// A capture with at least this many sparse points hands them to the composite's model (below
/// it, e.g. a transforms.json without `sparse_pc.ply`, the composited depth is sampled).
const MIN_CAPTURE_POINTS: usize = 1000;
/// A capture point within this fraction of an object's size of its surface (or inside it) is
/// dropped: the object stands on it or hides it from every view.
const SWALLOWED: f64 = 0.1;
/// Training views a structure-from-motion point needs: it is triangulated from two.
const MIN_TRIANGULATING_VIEWS: usize = 2;

/// Composites the objects into the capture and writes the benchmark folder `out` (created; must
/// be empty or absent).
pub fn composite(
    gpu: &Gpu,
    cfg: &CompositeConfig,
    out: &Path,
    progress: &dyn Fn(&str, usize, usize),
) -> Result<CompositeSummary> {
    if cfg.objects == 0 || cfg.objects > 4 {
        bail!("--objects must be 1..4 with --composite-into, got {}", cfg.objects);
    }
    if cfg.gt_without.iter().any(|&l| l == 0 || l as usize > cfg.objects) {
        bail!("--gt-without: labels must be 1..={}", cfg.objects);
    }
    if !(cfg.object_size > 0.0 && cfg.object_size < 0.5) {
        bail!("--object-size must be in (0, 0.5), got {}", cfg.object_size);
    }
    if out.exists() && std::fs::read_dir(out)?.next().is_some() {
        bail!("{}: output folder is not empty", out.display());
    }
    let data = dataset::load(&cfg.capture, &cfg.images, cfg.downscale)?;
    let count = data.train.len() + data.test.len();
    let (mut train, mut test) = (data.train.into_iter(), data.test.into_iter());
    let data_points = data.points;
    let loaded: Vec<dataset::View> =
        (0..count).map(|i| if is_test_view(i) { test.next() } else { train.next() }.expect("split")).collect();
    let scene = crate::scene::ply::read_ply(&cfg.scene)?;
    let mut renderer = SceneRenderer::new(gpu, &scene, None)?;
    let mut views = Vec::with_capacity(count);
    for (i, v) in loaded.into_iter().enumerate() {
        let r = renderer.render(&v.camera, &RenderSettings { median_depth: true, ..Default::default() })?;
        // the median depth: the cup's desk is many faint Gaussians whose expected depth lay near
        // the objects from 3.3 object half sizes in front of it (grazing views) to 16 behind,
        // which cut the objects into fragments and let views see footprints through the cuts
        // (bench/JOURNAL.md, 2026-11-30, 03:14)
        let depth = r
            .median_depth
            .iter()
            .zip(&r.alpha)
            .map(|(&z, &a)| if a > COVERED_ALPHA && z > 0.0 { z } else { f32::INFINITY })
            .collect();
        views.push(CaptureView { camera: v.camera, photo: v.image, depth });
        progress("depth", i + 1, count);
    }
    let cameras: Vec<Camera> = views.iter().map(|v| v.camera.clone()).collect();
    let mut rng = Rng::new(cfg.seed);
    let sparse: Vec<V3> = data_points.iter().map(|p| p.xyz).collect();
    let (ground, objects) = match &cfg.placement {
        Some(path) => read_placement(path, cfg.objects)?,
        None => place(cfg, &views, &cameras, &sparse, &mut rng)?,
    };
    let kept: Vec<Object> = objects.iter().filter(|o| !cfg.gt_without.contains(&o.label)).cloned().collect();
    let subset_dir = (!cfg.gt_without.is_empty()).then(|| subset_dir_name(&cfg.gt_without));
    let mut with_objects = Vec::with_capacity(count);
    let mut without_subset = Vec::new();
    for (i, v) in views.iter().enumerate() {
        with_objects.push(composite_view(v, &ground, &objects, cfg));
        if subset_dir.is_some() {
            without_subset.push(composite_view(v, &ground, &kept, cfg));
        }
        progress("composite", i + 1, count);
    }
    let train_views: Vec<usize> = (0..count).filter(|&i| !is_test_view(i)).collect();
    // what each training view shows of the ground truth being classified: its composited depth,
    // 0 (matching no point) where an object absent from that truth covers it. By depth alone the
    // desk under a small box counted as seen where a view showed the box's side within the
    // tolerance of it.
    let depths_showing = |absent: &dyn Fn(u8) -> bool| -> Vec<Vec<f32>> {
        let show =
            |c: &Composited| c.depth.iter().zip(&c.labels).map(|(&z, &l)| if absent(l) { 0.0 } else { z }).collect();
        with_objects.iter().map(show).collect()
    };
    fn slices(depths: &[Vec<f32>]) -> Vec<&[f32]> {
        depths.iter().map(|d| &d[..]).collect()
    }
    let showing_background = depths_showing(&|l| l != 0);
    let background_depths = slices(&showing_background);
    // only with a subset ground truth: a copy of every view's depth is 66 MB on the cup
    let showing_subset = subset_dir.is_some().then(|| depths_showing(&|l| cfg.gt_without.contains(&l)));
    let subset_depths = showing_subset.as_deref().map(slices);
    let surface_points = |cam: &Camera, depth: &[f32]| -> Vec<Option<V3>> {
        let w = cam.width as usize;
        depth.iter().enumerate().map(|(p, &z)| z.is_finite().then(|| cam.pixel_point(p % w, p / w, z as f64))).collect()
    };
    super::create_folders(out, subset_dir.as_deref())?;
    let finite_or_zero = |d: &[f32]| d.iter().map(|&z| if z.is_finite() { z } else { 0.0 }).collect::<Vec<f32>>();
    for (i, (v, c)) in views.iter().zip(&with_objects).enumerate() {
        let (w, h, name) = (v.camera.width, v.camera.height, &v.camera.name);
        write_png_rgb(&out.join(format!("images/{name}.png")), w, h, &c.rgb)?;
        write_png_rgb(&out.join(format!("gt_background/{name}.png")), w, h, &v.photo)?;
        write_png(&out.join(format!("object_mask/{name}.png")), w, h, image::ColorType::L8, &c.labels)?;
        write_exr(&out.join(format!("depth/{name}.exr")), w, h, &[("Y", &finite_or_zero(&c.depth))])?;
        write_exr(&out.join(format!("depth_background/{name}.exr")), w, h, &[("Y", &finite_or_zero(&v.depth))])?;
        let points = surface_points(&v.camera, &v.depth);
        let unseen =
            never_seen(&points, &cameras, Lens::Pinhole, &train_views, &background_depths, SEEN_TOLERANCE, SEEN_REACH);
        write_png(&out.join(format!("unseen_mask/{name}.png")), w, h, image::ColorType::L8, &unseen)?;
        if let (Some(d), Some(subset_depths)) = (&subset_dir, &subset_depths) {
            let s = &without_subset[i];
            write_png_rgb(&out.join(format!("{d}/images/{name}.png")), w, h, &s.rgb)?;
            write_exr(&out.join(format!("{d}/depth/{name}.exr")), w, h, &[("Y", &finite_or_zero(&s.depth))])?;
            let points = surface_points(&v.camera, &s.depth);
            let unseen =
                never_seen(&points, &cameras, Lens::Pinhole, &train_views, subset_depths, SEEN_TOLERANCE, SEEN_REACH);
            write_png(&out.join(format!("{d}/unseen_mask/{name}.png")), w, h, image::ColorType::L8, &unseen)?;
        }
        progress("write", i + 1, count);
    }
    let (points, points_hidden) = if data_points.len() >= MIN_CAPTURE_POINTS {
        // a composite trained from points sampled on the capture's rendered depth (which scatters
        // in front of and behind a fuzzy surface) rendered the cup's desk blurred and streaked:
        // held-out PSNR 25.3 against the capture's own training's 26.3; from the capture's points
        // and the objects' 26.6 (bench/JOURNAL.md, 2026-11-29, 13:38)
        let swallowed = |p: V3| {
            let local = ground.to_local(p);
            objects.iter().any(|o| o.sdf(local) < SWALLOWED * o.size)
        };
        let capture_depths: Vec<&[f32]> = views.iter().map(|v| &v.depth[..]).collect();
        let hidden = hidden_by_objects(&data_points, &cameras, &train_views, &capture_depths, &background_depths);
        let mut points: Vec<Point3D> =
            data_points.iter().zip(&hidden).filter(|(p, &h)| !h && !swallowed(p.xyz)).map(|(p, _)| p.clone()).collect();
        let on_objects = |c: &Composited, p: usize| c.labels[p] != 0;
        points.extend(sparse_points(&views, &with_objects, &train_views, cfg.points, &on_objects, &mut rng));
        (points, hidden.iter().filter(|&&h| h).count())
    } else {
        (sparse_points(&views, &with_objects, &train_views, cfg.points, &|_, _| true, &mut rng), 0)
    };
    super::capture_files::write_pinhole_model(&cameras, &points, out)?;
    let views_with_overlap = with_objects.iter().filter(|c| c.overlaps >= 20).count();
    let world: Vec<serde_json::Value> = objects
        .iter()
        .map(|o| {
            serde_json::json!({ "label": o.label, "center": ground.to_world(o.center), "size": o.size * ground.unit })
        })
        .collect();
    let meta = serde_json::json!({
        "composite": cfg, "ground": ground, "objects": objects, "objects_world": world,
        "test_views": (0..count).filter(|&i| is_test_view(i)).collect::<Vec<_>>(),
        "views_with_one_object_behind_another": views_with_overlap,
        "capture_points_hidden_by_objects": points_hidden,
    });
    let text = serde_json::to_string_pretty(&meta)?;
    write_atomic(&out.join("synth.json"), |w| w.write_all(text.as_bytes()).map_err(Into::into))?;
    Ok(CompositeSummary { objects, ground, views: count, views_with_overlap, points_hidden })
}

/// The capture's sparse points that a capture with the objects standing in it could not have:
/// seen (`seen_in`) by fewer of the training views than MIN_TRIANGULATING_VIEWS, or than saw it
/// without the objects where that is fewer, with the objects in them (`composite_depths`: the
/// composited depths, 0 where an object covers the pixel) than without (`capture_depths`).
/// Structure from motion found these points in photos of the scene without the objects, and
/// kept, they start the composite's training with Gaussians of the true colours behind the
/// objects where no training view sees: a leak of the ground truth into the never-seen region for
/// every removal that keeps the Gaussians left behind the objects (nearest-copy, removal only).
/// Points the capture's own depths do not confirm (their noise off the rendered surface) are
/// kept: the objects took nothing from them.
fn hidden_by_objects(
    points: &[Point3D],
    cameras: &[Camera],
    train: &[usize],
    capture_depths: &[&[f32]],
    composite_depths: &[&[f32]],
) -> Vec<bool> {
    let seen_by = |depths: &[&[f32]], p: V3| {
        train.iter().filter(|&&t| seen_in(&cameras[t], Lens::Pinhole, depths[t], p, SEEN_TOLERANCE, SEEN_REACH)).count()
    };
    let mut hidden = vec![false; points.len()];
    crate::parallel::for_each_item(&mut hidden, &mut |_, _| {}, |i, h| {
        let p = points[i].xyz;
        let without = seen_by(capture_depths, p);
        *h = without > 0 && seen_by(composite_depths, p) < without.min(MIN_TRIANGULATING_VIEWS);
    });
    hidden
}

/// The ground and objects of an earlier composite's synth.json (`placement`), which must hold
/// `count` objects labelled 1..=count.
pub fn read_placement(path: &Path, count: usize) -> Result<(Ground, Vec<Object>)> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("{}: cannot read the placement", path.display()))?;
    let meta: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("{}: not a JSON file", path.display()))?;
    let field =
        |name: &str| meta.get(name).cloned().with_context(|| format!("{}: no \"{name}\" field", path.display()));
    let ground: Ground = serde_json::from_value(field("ground")?)
        .with_context(|| format!("{}: \"ground\" is not a composite's ground frame", path.display()))?;
    let objects: Vec<Object> = serde_json::from_value(field("objects")?)
        .with_context(|| format!("{}: \"objects\" is not a list of composite objects", path.display()))?;
    if objects.len() != count {
        bail!("{}: holds {} objects, --objects says {count}", path.display(), objects.len());
    }
    if objects.iter().enumerate().any(|(i, o)| o.label as usize != i + 1) {
        bail!("{}: \"objects\" must be labelled 1..={count} in order", path.display());
    }
    Ok((ground, objects))
}

/// Finds the supporting plane and places the objects on it.
fn place(
    cfg: &CompositeConfig,
    views: &[CaptureView],
    cameras: &[Camera],
    sparse: &[V3],
    rng: &mut Rng,
) -> Result<(Ground, Vec<Object>)> {
    let depths: Vec<&[f32]> = views.iter().map(|v| &v.depth[..]).collect();
    let focus = ground::focus(cameras, &depths).with_context(|| {
        format!("{}: the trained scene renders no surface in the views' centers", cfg.scene.display())
    })?;
    let distance = |p: V3, q: V3| ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
    let mut distances: Vec<f64> = cameras.iter().map(|c| distance(c.center(), focus)).collect();
    distances.sort_by(f64::total_cmp);
    let median = distances[distances.len() / 2];
    // the surfaces around the focus: the capture's sparse points (structure from motion is
    // exact on textured surfaces, where a briefly trained scene's depth is noisy), or without
    // enough of them, about 200k points of the rendered depth
    let mut points: Vec<V3> = sparse.iter().copied().filter(|&p| distance(p, focus) < 0.9 * median).collect();
    let from_depth = points.len() < 1000;
    let pixels: usize = views.iter().map(|v| v.depth.len()).sum();
    let stride = ((pixels as f64 / 200_000.0).sqrt().ceil() as usize).max(1);
    for v in views.iter().filter(|_| from_depth) {
        let w = v.camera.width as usize;
        for y in (0..v.camera.height as usize).step_by(stride) {
            for x in (0..w).step_by(stride) {
                let z = v.depth[y * w + x];
                if z.is_finite() {
                    let p = v.camera.pixel_point(x, y, z as f64);
                    if distance(p, focus) < 0.9 * median {
                        points.push(p);
                    }
                }
            }
        }
    }
    let tolerance = 0.01 * median;
    let centers: Vec<V3> = cameras.iter().map(|c| c.center()).collect();
    let (n, offset) = ground::supporting_plane(&points, tolerance, &centers, rng).with_context(|| {
        format!("{}: the trained scene shows too few surface points around the capture's focus", cfg.scene.display())
    })?;
    let unit = cfg.object_size * median / 0.4;
    let ground = ground::ground_frame(n, offset, focus, unit);
    let local: Vec<V3> = points.iter().map(|&p| ground.to_local(p)).collect();
    let rules = ground::PlacementRules {
        ground: &ground,
        local_points: &local,
        cameras,
        depths: &depths,
        radius: 0.6 * median / unit,
    };
    let objects = ground::place_objects(cfg.objects, &rules, rng).map_err(|r| {
        anyhow::anyhow!(
            "could not place {} objects on the supporting plane (normal {:.3?}, from {} {}): candidates \
             refused {} times as overlapping another object, {} times as not bare and flat, {} times as \
             hidden or outside most views; try another --seed, fewer --objects or a smaller --object-size",
            cfg.objects,
            n,
            points.len(),
            if from_depth { "points of the trained scene's depth" } else { "sparse points" },
            r.overlapping,
            r.not_bare,
            r.out_of_view
        )
    })?;
    Ok((ground, objects))
}

/// Ray-casts `objects` into one view: each pixel's color is the mean over `supersample`^2 rays of
/// the object's shaded color where the ray meets an object before the original scene's surface,
/// else the photo (darkened near the footprints by the contact shadow); label and depth come
/// from the center ray.
fn composite_view(v: &CaptureView, ground: &Ground, objects: &[Object], cfg: &CompositeConfig) -> Composited {
    use rayon::prelude::*;
    let cam = &v.camera;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let s = cfg.supersample.max(1);
    let origin = ground.to_local(cam.center());
    let r = cam.rotation;
    // the ray through image position (px, py) in local coordinates, and the length of its
    // camera-space direction (x, y, 1): camera z times that is the distance along the ray
    let ray = |px: f64, py: f64| {
        let dc = [(px - cam.cx) / cam.fx, (py - cam.cy) / cam.fy, 1.0];
        let len = (dc[0] * dc[0] + dc[1] * dc[1] + 1.0).sqrt();
        let world = [0, 1, 2].map(|a| (r[0][a] * dc[0] + r[1][a] * dc[1] + r[2][a] * dc[2]) / len);
        (ground.direction_to_local(world), len)
    };
    let seed = cfg.seed;
    // per object, the others: what a ray that meets it may meet further on
    let others: Vec<Vec<Object>> =
        objects.iter().map(|o| objects.iter().filter(|p| p.label != o.label).cloned().collect()).collect();
    // one image row: colors, depth, labels, pixels where one object stands before another
    type Row = (Vec<[f32; 3]>, Vec<f32>, Vec<u8>, usize);
    let rows: Vec<Row> = (0..h)
        .into_par_iter()
        .map(|y| {
            let mut row = (vec![[0f32; 3]; w], vec![f32::INFINITY; w], vec![0u8; w], 0usize);
            for x in 0..w {
                let p = y * w + x;
                let scene_z = v.depth[p] as f64;
                let photo = [0, 1, 2].map(|c| v.photo[c * w * h + p] as f64);
                let photo = match cfg.contact_shadow > 0.0 && scene_z.is_finite() {
                    true => {
                        let q = ground.to_local(cam.pixel_point(x, y, scene_z));
                        photo.map(|c| c * shadow_factor(q, objects, cfg.contact_shadow))
                    }
                    false => photo,
                };
                // the first of `among` that the ray through (px, py) meets before the scene's surface
                let hit_among = |px: f64, py: f64, among: &[Object]| {
                    let (d, len) = ray(px, py);
                    let t_max = if scene_z.is_finite() { scene_z * len / ground.unit } else { 1e9 };
                    object_hit(origin, d, among, t_max, seed)
                };
                let mut sum = [0.0; 3];
                for sy in 0..s {
                    for sx in 0..s {
                        let (px, py) =
                            (x as f64 + (sx as f64 + 0.5) / s as f64, y as f64 + (sy as f64 + 0.5) / s as f64);
                        let c = hit_among(px, py, objects).map_or(photo, |hit| shade(&hit));
                        sum = [0, 1, 2].map(|k| sum[k] + c[k]);
                    }
                }
                row.0[x] = sum.map(|c| (c / (s * s) as f64) as f32);
                let (cx, cy) = (x as f64 + 0.5, y as f64 + 0.5);
                if let Some(hit) = hit_among(cx, cy, objects) {
                    row.1[x] = cam.to_camera(ground.to_world(hit.point))[2] as f32;
                    row.2[x] = hit.label;
                    // another object further along the same ray: one stands behind the other here
                    let k = objects.iter().position(|o| o.label == hit.label).expect("a hit names its object");
                    if hit_among(cx, cy, &others[k]).is_some() {
                        row.3 += 1;
                    }
                } else {
                    row.1[x] = scene_z as f32;
                }
            }
            row
        })
        .collect();
    let mut out =
        Composited { rgb: vec![0.0; 3 * w * h], depth: Vec::with_capacity(w * h), labels: Vec::new(), overlaps: 0 };
    for (y, (rgb, depth, labels, overlaps)) in rows.into_iter().enumerate() {
        for (x, c) in rgb.iter().enumerate() {
            for k in 0..3 {
                out.rgb[k * w * h + y * w + x] = c[k];
            }
        }
        out.depth.extend(depth);
        out.labels.extend(labels);
        out.overlaps += overlaps;
    }
    out
}

/// The contact shadow's factor at local point `q`: darkest right at an object's footprint,
/// fading over about half the object's size outwards and upwards.
fn shadow_factor(q: V3, objects: &[Object], strength: f64) -> f64 {
    objects.iter().fold(1.0, |f, o| {
        let reach = o.shape.footprint_radius(o.size);
        let d = (((q[0] - o.center[0]).powi(2) + (q[1] - o.center[1]).powi(2)).sqrt() - reach).max(0.0);
        let up = q[2].max(0.0);
        f * (1.0 - strength * (-(d / (0.6 * o.size)).powi(2) - (up / (0.3 * o.size)).powi(2)).exp())
    })
}

/// Sparse points for the COLMAP model: `count` surface points of the training views' composited
/// depth (the objects included, as structure from motion would find them), with their colors;
/// only those the pixel test `keep` passes (the sampled count of the others is left out).
fn sparse_points(
    views: &[CaptureView],
    composited: &[Composited],
    train: &[usize],
    count: usize,
    keep: &dyn Fn(&Composited, usize) -> bool,
    rng: &mut Rng,
) -> Vec<Point3D> {
    let mut points = Vec::with_capacity(count);
    let per_view = count.div_ceil(train.len().max(1));
    for &t in train {
        let (cam, c) = (&views[t].camera, &composited[t]);
        let (w, hw) = (cam.width as usize, c.depth.len());
        let mut taken = 0;
        for _ in 0..per_view * 4 {
            let p = rng.below(hw);
            if taken == per_view || !c.depth[p].is_finite() {
                continue;
            }
            taken += 1;
            if !keep(c, p) {
                continue;
            }
            let xyz = cam.pixel_point(p % w, p / w, c.depth[p] as f64);
            let rgb = [0, 1, 2].map(|k| crate::io::to_u8(c.rgb[k * hw + p]));
            points.push(Point3D { xyz, rgb });
        }
    }
    points
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Camera-z depth of the ground z = 0 through each pixel of `cam`, 0 where the ray meets the
    /// box [-0.5, 0.5]^2 x [0, 1] first (`boxed`) or never meets the ground.
    fn ground_depth(cam: &Camera, boxed: bool) -> Vec<f32> {
        let (w, h) = (cam.width as usize, cam.height as usize);
        let eye = cam.pixel_point(0, 0, 0.0);
        (0..w * h)
            .map(|p| {
                let far = cam.pixel_point(p % w, p / w, 1.0);
                let d = [far[0] - eye[0], far[1] - eye[1], far[2] - eye[2]];
                if d[2] >= 0.0 {
                    return 0.0;
                }
                let t_ground = -eye[2] / d[2];
                // slab test against the box
                let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
                for (a, (lo, hi)) in [(-0.5, 0.5), (-0.5, 0.5), (0.0, 1.0)].into_iter().enumerate() {
                    let (u, v) = ((lo - eye[a]) / d[a], (hi - eye[a]) / d[a]);
                    t0 = t0.max(u.min(v));
                    t1 = t1.min(u.max(v));
                }
                if boxed && t0 <= t1 && t0 < t_ground {
                    return 0.0;
                }
                t_ground as f32 // camera z, since `far` is at camera z 1
            })
            .collect()
    }

    /// Three cameras on one side of a unit box on the ground: the ground point right behind the box
    /// is hidden from all of them and the points beside and in front of it are not; a point off
    /// every surface (structure from motion's noise) is kept, since the box took nothing from it.
    #[test]
    fn points_the_box_hides_from_the_training_views_are_left_out() {
        let cameras: Vec<Camera> = [-1.0, 0.0, 1.0]
            .iter()
            .map(|&x| Camera::look_at("c", 96, 96, 60.0, [x, -5.0, 2.0], [0.0, 0.0, 0.3], [0.0, 0.0, 1.0]))
            .collect();
        let without: Vec<Vec<f32>> = cameras.iter().map(|c| ground_depth(c, false)).collect();
        let with: Vec<Vec<f32>> = cameras.iter().map(|c| ground_depth(c, true)).collect();
        let capture: Vec<&[f32]> = without.iter().map(|d| &d[..]).collect();
        let composite: Vec<&[f32]> = with.iter().map(|d| &d[..]).collect();
        let point = |xyz: [f64; 3]| Point3D { xyz, rgb: [0; 3] };
        let points = [
            point([0.0, 0.9, 0.0]),  // behind the box from every camera
            point([1.6, 0.0, 0.0]),  // beside it
            point([0.0, -1.5, 0.0]), // in front of it
            point([0.0, 2.0, 0.5]),  // in the air: no depth confirms it
        ];
        let hidden = hidden_by_objects(&points, &cameras, &[0, 1, 2], &capture, &composite);
        assert_eq!(hidden, [true, false, false, false]);
        // with only the middle camera training, the point behind the box is still hidden, and one
        // camera suffices for the point in front
        let hidden = hidden_by_objects(&points, &cameras, &[1], &capture, &composite);
        assert_eq!(hidden, [true, false, false, false]);
    }
}
