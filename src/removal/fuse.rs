//! Stage 4 of removal: the completed depth of every edited view, inside its hole, becomes new
//! Gaussians, and sparse background outliers near them are pruned.
//!
//! Back-projection: each hole pixel (every `stride`-th in x and y) at its completed depth z becomes a
//! point colored from the inpainted image, with footprint z * stride / f (the pixel's size at that
//! depth). Its Gaussian is a flat ellipse on the completed surface covering the pixel there (the
//! plane fitted to the completed depth around it gives the orientation): a floor seen at a grazing
//! angle gets Gaussians stretched along it, as its pixels are, with no gaps between rows and no
//! thickness above it when seen from elsewhere.
//! Multi-view consistency: a point is dropped when, seen from another edited view, it lands inside
//! that view's hole more than `tolerance` (relative) in front of that view's completed depth, i.e.
//! it would float in front of the surface another view completed. Points behind it are only
//! occluded there and are kept. Free space: a point is also dropped when another view sees past it,
//! i.e. it lands outside that view's hole more than `free_space_tolerance` in front of the surface
//! that view renders there; the photo of that view shows a farther surface through the point.
//! One owner per surface point: views are taken largest fill first, and
//! a point is dropped where an earlier view completed the same surface and kept its own point there
//! (`FuseConfig::one_owner`).
//! Points that still fall in one voxel (the median footprint) are merged: position and color
//! averaged, the shape of the first.
//!
//! Pruning of sparse background outliers near the patch is in prune.rs.

use super::prune::{prune_mask, PruneSettings};
use crate::planes::local_plane;
use crate::removal::complete::depth;
use crate::scene::{Camera, GaussianScene, SH_C0};
use kiddo::{KdTree, SquaredEuclidean};
use std::collections::HashMap;

/// Initial opacity of the new Gaussians when no refinement follows: the patch must cover the
/// hole on its own.
pub const UNREFINED_OPACITY: f32 = 0.9;

/// How the new Gaussians behind the removed objects are made.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Fill {
    /// CoGeo-GS: back-project the completed depth of every view, fuse, prune (fuse.rs).
    #[default]
    Depth,
    /// Baseline (Gaussian-Grouping-style): each removed Gaussian is replaced by a copy of its
    /// nearest remaining Gaussian, at its own position.
    NearestCopy,
}

/// Stage 4's result.
pub struct Patched {
    /// The background with the new Gaussians appended (and pruned Gaussians gone).
    pub scene: GaussianScene,
    /// Fusion statistics and the patch size, for the report.
    pub report: serde_json::Value,
    pub pruned: usize,
    /// The pruning criteria used, when pruning ran.
    pub prune: Option<super::prune::PruneConfig>,
    /// Per view (`Fill::Depth`), the pixels whose back-projected point was kept: the surface
    /// points the view owns in the patch. Empty for the nearest-copy fill.
    pub owned: Vec<Vec<bool>>,
    /// The new Gaussians: the last `added` of `scene`.
    pub added: usize,
}

/// Stage 4: adds new Gaussians behind the removed objects to `background`. `Fill::Depth`
/// back-projects and fuses the completed `views`, then (with `prune`) removes sparse background
/// outliers near the patch, by `prune_settings` (distances not given follow the patch spacing).
/// `Fill::NearestCopy` copies the nearest remaining Gaussian
/// to each of `removed_means`.
pub fn patch_scene(
    background: GaussianScene,
    fill: Fill,
    views: &[FuseView],
    removed_means: &[[f32; 3]],
    cfg: &FuseConfig,
    prune: bool,
    prune_settings: &PruneSettings,
) -> anyhow::Result<Patched> {
    let mut scene = background;
    if fill == Fill::NearestCopy {
        let patch = nearest_copies(&scene, removed_means);
        scene.append(&patch)?;
        let report = serde_json::json!({ "fill": "nearest-copy", "patch_gaussians": patch.len() });
        return Ok(Patched { scene, report, pruned: 0, prune: None, owned: Vec::new(), added: patch.len() });
    }
    let (points, stats, owned) = fuse_points(views, cfg);
    let patch = patch_gaussians(&points, scene.sh_degree, cfg.opacity);
    let (mut pruned, mut prune_used) = (0, None);
    if prune && !patch.is_empty() {
        let cfg = prune_settings.resolve(|| {
            let mut fp: Vec<f64> = points.iter().map(|p| p.footprint).collect();
            fp.sort_by(|a, b| a.total_cmp(b));
            fp[fp.len() / 2]
        });
        let mask = prune_mask(&scene.means, &patch.means, &cfg);
        pruned = mask.iter().filter(|&&p| p).count();
        let keep: Vec<bool> = mask.iter().map(|&p| !p).collect();
        scene = scene.subset(&keep);
        prune_used = Some(cfg);
    }
    scene.append(&patch)?;
    let report = serde_json::json!({ "stats": stats, "patch_gaussians": patch.len() });
    Ok(Patched { scene, report, pruned, prune: prune_used, owned, added: patch.len() })
}

/// One edited view's completion.
pub struct FuseView<'a> {
    pub camera: &'a Camera,
    /// Inpainted planar RGB.
    pub rgb: &'a [f32],
    /// Completed camera-z depth.
    pub depth: &'a [f32],
    pub fill: &'a [bool],
}

/// Fusion settings: the one home of their defaults, also `cogeo remove`'s flags.
#[derive(Clone, Debug, serde::Serialize, clap::Args)]
pub struct FuseConfig {
    /// Sample every Nth hole pixel in x and y for new Gaussians.
    #[arg(long, default_value_t = 1)]
    pub stride: usize,
    /// Relative depth disagreement that counts as floating in front of another view's completion.
    #[arg(skip = 0.03)]
    pub tolerance: f32,
    /// Relative depth by which a point may lie in front of the surface another view renders outside
    /// its hole before it counts as seen through (free space) and is dropped. Looser than
    /// `tolerance`: it is measured against a trained scene's rendered depth, not a completion. A
    /// view's completed depth that is too near (a real scene's expected depth is pulled toward the
    /// camera by faint Gaussians in front of its surfaces) otherwise left points floating over what
    /// other views saw: smudges of the desk's colors on the composited cup (on one training of it
    /// masked PSNR 25.35 -> 26.46 dB with the check, on another 0.2 dB; synth and statue scenes
    /// within 0.03 dB).
    #[arg(skip = 0.05)]
    pub free_space_tolerance: f32,
    /// Initial opacity of the new Gaussians when the refinement follows (without it they start at
    /// `UNREFINED_OPACITY`, `RemoveOptions::fuse_config`). They start mostly transparent: where the
    /// Gaussians the capture left behind an object lie on the completed surface (trained by every
    /// view that saw it there, so consistent across views), the refinement raises a patch
    /// Gaussian's opacity only as far as the views' targets ask, and the leftovers keep showing
    /// through elsewhere. At 0.9 the one-owner fills covered them from the start, and a held-out
    /// view showed the owners' grain a pixel or two off and in their own exposures. Held-out masked
    /// PSNR / LPIPS (cached trainings, by hand) at 0.9, 0.5, 0.3 and 0.15: cup-one 26.50 / 0.179,
    /// 26.66 / 0.181, 26.83 / 0.184, 26.88 / 0.187; cup-two-of-three 27.11 / 0.151 and at 0.3
    /// 27.42 / 0.153; statue-one 20.70 / 0.317, 20.70 / 0.316, 20.72 / 0.318; synth rooms one /
    /// two-of-three / three-of-four 25.94 / 26.19 / 26.18 and at 0.3 25.93 / 26.15 / 26.29.
    #[arg(skip = 0.3)]
    pub opacity: f32,
    /// Each surface point of the fill is made from one view only: the views are taken in order of
    /// their fill size, and a point is dropped when a view earlier in that order completed the same
    /// surface there (its fill, within `tolerance` of its depth) and kept its own point there.
    /// Without it every view's points were kept and merged per voxel, so the patch held layers of
    /// nearly coincident Gaussians whose colors the render averaged (commit `43b8697`: held-out
    /// masked PSNR 0.3-1.0 dB and seen-elsewhere PSNR 1.0-1.5 dB lower).
    #[arg(skip = true)]
    pub one_owner: bool,
    /// Make each new Gaussian a sphere of its pixel's size (the earlier patch, for ablation) instead
    /// of a flat ellipse on the completed surface covering the pixel's footprint there
    /// (`surface_steps`).
    #[arg(id = "round-patch", long = "round-patch", action = clap::ArgAction::SetFalse)]
    pub surfels: bool,
}

crate::default_from_flags!(FuseConfig);

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatchPoint {
    pub position: [f64; 3],
    pub rgb: [f32; 3],
    pub footprint: f64,
    /// The sampled pixel's footprint on the completed surface: the world-space steps across it in
    /// x and in y on the plane fitted there (`surface_steps`); None where no plane fits.
    pub steps: Option<[[f64; 3]; 2]>,
    /// The edge of the voxel cell the point was merged in (`fuse_points`): the point stands for
    /// the surface within it, so its Gaussian spans at least that much (`cell_steps`).
    pub cell: f64,
}

#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct FuseStats {
    pub sampled: usize,
    pub inconsistent: usize,
    /// Points dropped because a view earlier in the order completed that surface (`one_owner`).
    pub owned_elsewhere: usize,
    pub merged_into: usize,
}

/// Views by fill size, largest first (ties by index).
fn owner_order(views: &[FuseView]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..views.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse(views[i].fill.iter().filter(|&&f| f).count()));
    order
}

/// Does `o` own the surface point `p`: it lands in o's fill within `tolerance` of o's depth, at a
/// pixel whose own point `o` kept (`kept`, on the sampling grid of `stride`)? An owner whose point
/// there was dropped as inconsistent owns nothing: counting it left holes in the patch where
/// neither view's point survived (the background showed through as dark specks).
fn owns(o: &FuseView, kept: &[bool], stride: usize, p: [f64; 3], tolerance: f32) -> bool {
    let Some((q, z)) = o.camera.pixel_of(p) else { return false };
    let w = o.camera.width as usize;
    let (x, y) = (q % w, q / w);
    let sampled = (y - y % stride) * w + (x - x % stride);
    o.fill[q] && kept[sampled] && (z - o.depth[q] as f64).abs() <= o.depth[q] as f64 * tolerance as f64
}

/// Does a point at camera depth `z` over pixel `q` of view `o` float: in front of o's completed
/// surface inside o's fill, or in front of the surface o renders outside it (o sees past it)?
/// Outside pixels with no depth (nothing rendered there) say nothing.
fn floats_in(o: &FuseView, q: usize, z: f64, cfg: &FuseConfig) -> bool {
    let tolerance = if o.fill[q] { cfg.tolerance } else { cfg.free_space_tolerance };
    let surface = o.depth[q] as f64;
    surface > 0.0 && z < surface * (1.0 - tolerance as f64)
}

/// Back-projects, checks consistency across views and merges. Also returns, per view, the pixels
/// whose point was kept.
pub fn fuse_points(views: &[FuseView], cfg: &FuseConfig) -> (Vec<PatchPoint>, FuseStats, Vec<Vec<bool>>) {
    let mut stats = FuseStats::default();
    let stride = cfg.stride.max(1);
    let mut points = Vec::new();
    let order = if cfg.one_owner { owner_order(views) } else { (0..views.len()).collect() };
    // per view, the sampled pixels whose point was kept
    let mut kept: Vec<Vec<bool>> = views.iter().map(|v| vec![false; v.fill.len()]).collect();
    for (rank, &vi) in order.iter().enumerate() {
        let v = &views[vi];
        let (w, h) = (v.camera.width as usize, v.camera.height as usize);
        let hw = w * h;
        let disparity: Vec<f32> = if cfg.surfels { depth::disparity(v.depth) } else { Vec::new() };
        for y in (0..h).step_by(stride) {
            for x in (0..w).step_by(stride) {
                let i = y * w + x;
                let z = v.depth[i] as f64;
                if !v.fill[i] || z <= 0.0 || !z.is_finite() {
                    continue;
                }
                stats.sampled += 1;
                let p = v.camera.pixel_point(x, y, z);
                let floats = views
                    .iter()
                    .enumerate()
                    .any(|(vj, o)| vj != vi && o.camera.pixel_of(p).is_some_and(|(q, z)| floats_in(o, q, z, cfg)));
                if floats {
                    stats.inconsistent += 1;
                    continue;
                }
                if cfg.one_owner
                    && order[..rank].iter().any(|&vj| owns(&views[vj], &kept[vj], stride, p, cfg.tolerance))
                {
                    stats.owned_elsewhere += 1;
                    continue;
                }
                kept[vi][i] = true;
                let footprint = z * stride as f64 / v.camera.fx.min(v.camera.fy);
                let steps = if cfg.surfels { surface_steps(v, &disparity, x, y, stride, footprint) } else { None };
                let rgb = [v.rgb[i], v.rgb[hw + i], v.rgb[2 * hw + i]];
                points.push(PatchPoint { position: p, rgb, footprint, steps, cell: footprint });
            }
        }
    }
    if points.is_empty() {
        return (points, stats, kept);
    }
    let mut fp: Vec<f64> = points.iter().map(|p| p.footprint).collect();
    fp.sort_by(|a, b| a.total_cmp(b));
    let voxel = fp[fp.len() / 2];
    // merge per voxel, in first-seen order (deterministic)
    let mut cells: HashMap<[i64; 3], usize> = HashMap::new();
    let mut sums: Vec<(PatchPoint, f64)> = Vec::new();
    for p in &points {
        let key = p.position.map(|c| (c / voxel).floor() as i64);
        match cells.get(&key) {
            Some(&k) => {
                let (s, n) = &mut sums[k];
                for a in 0..3 {
                    s.position[a] += p.position[a];
                    s.rgb[a] += p.rgb[a];
                }
                s.footprint = s.footprint.max(p.footprint);
                *n += 1.0;
            }
            None => {
                cells.insert(key, sums.len());
                sums.push((*p, 1.0));
            }
        }
    }
    let merged: Vec<PatchPoint> = sums
        .into_iter()
        .map(|(s, n)| PatchPoint {
            position: s.position.map(|c| c / n),
            rgb: s.rgb.map(|c| c / n as f32),
            footprint: s.footprint,
            steps: s.steps.map(|steps| cell_steps(steps, voxel)),
            cell: voxel,
        })
        .collect();
    stats.merged_into = merged.len();
    (merged, stats, kept)
}

/// A merged point's surface steps, each at least the cell's edge `cell` long (its direction kept).
/// The cell is the median footprint, so a surface nearer than most of the patch (a pedestal's
/// top under a removed statue, with the lawn behind it) merges several pixels into each cell;
/// with one pixel's steps its Gaussian covered a third of the cell, and the surface rendered as
/// a grating of stripes with the Gaussians behind it showing between them.
fn cell_steps(steps: [[f64; 3]; 2], cell: f64) -> [[f64; 3]; 2] {
    steps.map(|d| {
        let length = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        if length > 0.0 && length < cell {
            d.map(|c| c * cell / length)
        } else {
            d
        }
    })
}

/// Window radius (pixels) of the local plane that orients a patch Gaussian.
const PLANE_RADIUS: usize = 3;

/// The world-space steps across sample (x, y) of view `v`, one pixel wide in x and in y (times
/// `stride`), on the plane fitted to the completed depth around it (`planes::local_plane`,
/// robust to a depth edge in its window): the sample's footprint on the surface. The neighbours'
/// own depths scatter by a percent or two, which on a floor seen at a grazing angle is the whole
/// depth difference between rows: differences of them tilted a quarter of the bench's floor
/// Gaussians by more than 37 degrees (10 % by more than 69); the fitted plane tilted 10 % of them by
/// more than 28. A step longer than 8 footprints (a surface seen almost edge-on) is shortened to
/// that. None where no plane fits there or the steps are (nearly) parallel.
fn surface_steps(
    v: &FuseView,
    disparity: &[f32],
    x: usize,
    y: usize,
    stride: usize,
    footprint: f64,
) -> Option<[[f64; 3]; 2]> {
    let (w, h) = (v.camera.width as usize, v.camera.height as usize);
    let plane = local_plane(disparity, w, h, x, y, PLANE_RADIUS)?;
    let at = |px: f64, py: f64| -> Option<glam::DVec3> {
        let d = plane.disparity(px, py);
        (d > 0.0).then(|| glam::DVec3::from(v.camera.image_point(px, py, 1.0 / d)))
    };
    let (cx, cy) = (x as f64 + 0.5, y as f64 + 0.5);
    let limit = 8.0 * footprint;
    let clip = |d: glam::DVec3| if d.length() > limit { d * (limit / d.length()) } else { d };
    let sx = clip((at(cx + 0.5, cy)? - at(cx - 0.5, cy)?) * stride as f64);
    let sy = clip((at(cx, cy + 0.5)? - at(cx, cy - 0.5)?) * stride as f64);
    (sx.cross(sy).length() > 1e-3 * sx.length() * sy.length()).then_some([sx.to_array(), sy.to_array()])
}

/// A flat Gaussian on the surface spanned by the steps `[sx, sy]`: covariance
/// k^2 (sx sx^T + sy sy^T) in the surface (its axes from the closed-form eigenvectors of that 2x2
/// form), and a tenth of its smaller size across it. Returns (log scales, quaternion w x y z).
fn surfel_shape(steps: [[f64; 3]; 2], k: f64) -> ([f32; 3], [f32; 4]) {
    let (sx, sy) = (glam::DVec3::from(steps[0]), glam::DVec3::from(steps[1]));
    let n = sx.cross(sy).normalize();
    let e1 = sx.normalize();
    let e2 = n.cross(e1);
    // the form in the (e1, e2) basis: sx = (|sx|, 0), sy = (sy.e1, sy.e2)
    let (a, b1, b2) = (sx.length(), sy.dot(e1), sy.dot(e2));
    let (m11, m12, m22) = (a * a + b1 * b1, b1 * b2, b2 * b2);
    let theta = 0.5 * (2.0 * m12).atan2(m11 - m22);
    let mid = 0.5 * (m11 + m22);
    let rad = (0.25 * (m11 - m22).powi(2) + m12 * m12).sqrt();
    let (l1, l2) = (mid + rad, (mid - rad).max(1e-12 * mid));
    let u1 = theta.cos() * e1 + theta.sin() * e2;
    let u2 = n.cross(u1);
    let q = glam::DQuat::from_mat3(&glam::DMat3::from_cols(u1, u2, n));
    let (s1, s2) = (k * l1.sqrt(), k * l2.sqrt());
    ([s1.ln() as f32, s2.ln() as f32, (0.1 * s2).ln() as f32], [q.w as f32, q.x as f32, q.y as f32, q.z as f32])
}

/// The patch as Gaussians: flat ellipses on the surface where the point has surface steps
/// (`FuseConfig::surfels`), else spheres of the footprint; high opacity, the color in SH band 0.
pub fn patch_gaussians(points: &[PatchPoint], sh_degree: u32, opacity: f32) -> GaussianScene {
    let k = crate::scene::sh_coeffs(sh_degree);
    let mut s = GaussianScene { sh_degree, ..Default::default() };
    let logit = (opacity / (1.0 - opacity)).ln();
    for p in points {
        let (log_scales, quat) = match p.steps {
            Some(steps) => surfel_shape(steps, 0.6),
            None => ([(p.footprint.max(p.cell).max(1e-6) * 0.6).ln() as f32; 3], [1.0, 0.0, 0.0, 0.0]),
        };
        let mut sh = vec![0.0; 3 * k];
        for c in 0..3 {
            sh[c] = ((p.rgb[c] as f64 - 0.5) / SH_C0) as f32;
        }
        s.push(p.position.map(|v| v as f32), log_scales, quat, logit, &sh);
    }
    s
}

/// The Gaussian-Grouping-style fill used as a baseline: one new Gaussian at each removed
/// Gaussian's position, copying every other attribute (scale, rotation, opacity, color) from its
/// nearest remaining Gaussian. No depth, no inpainted colors: the refinement that follows has to
/// do the rest.
pub fn nearest_copies(remaining: &GaussianScene, removed_means: &[[f32; 3]]) -> GaussianScene {
    let mut out = GaussianScene { sh_degree: remaining.sh_degree, ..Default::default() };
    if remaining.is_empty() {
        return out;
    }
    let mut tree: KdTree<f64, 3> = KdTree::new();
    for (i, p) in remaining.means.iter().enumerate() {
        tree.add(&p.map(|v| v as f64), i as u64);
    }
    let k = remaining.sh_coeffs() * 3;
    for p in removed_means {
        let j = tree.nearest_one::<SquaredEuclidean>(&p.map(|v| v as f64)).item as usize;
        out.push(
            *p,
            remaining.log_scales[j],
            remaining.quats[j],
            remaining.opacity_logits[j],
            &remaining.sh[j * k..(j + 1) * k],
        );
    }
    out
}

#[cfg(test)]
#[path = "fuse_tests.rs"]
mod tests;
