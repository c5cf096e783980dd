//! Depth completion of one view, stage 1 (scale anchoring) and the model-free stage 2.
//!
//! A monocular prior D_mono is only known up to an affine map (in disparity for Depth Anything V2,
//! in depth for Depth Anything 3). It is anchored to the scene's rendered depth D_render by least
//! squares on the background (pixels outside the dilated hole that the scene covers):
//! `(a, b) = argmin sum (a x + b - y)^2` in the space the prior is affine in; then
//! `D_anchor = M_soft D_align + (1 - M_soft) D_render` with the softly dilated hole mask M_soft.
//!
//! Priors (`DepthPrior`):
//! - `BuiltIn`: the rendered depth outside the hole where the remaining Gaussians cover the pixel.
//!   Elsewhere (the whole hole: the Gaussians left behind a removed object are rarely constrained),
//!   the planes found around that region (surfaces.rs: RANSAC on inverse depth, which is affine in
//!   pixel coordinates for a plane) continued into it, the one in front where they meet; where no
//!   plane is plausible, the harmonic completion of the rendered inverse depth from the region's
//!   boundary (which also reproduces a single plane exactly).
//! - `DepthAnythingV2`: input `image` [1, 3, H, W] ImageNet-normalized RGB with H and W multiples of
//!   14 (the view resized to the nearest such size, longer side at most 518), output [1, H, W] (or
//!   [1, 1, H, W]) affine-invariant disparity, fitted in disparity.
//! - `DepthAnything3`: input [1, 3, 504, 504] ImageNet-normalized RGB, output [1, 504, 504] (or
//!   [1, 1, 504, 504]) depth, fitted in depth.
//!
//! Either model may name its single input and output as it likes.

use super::harmonic::harmonic_fill;
use super::surfaces::{beside_pixels, flanking_at, surfaces_around, Surfaces};
use crate::image_ops::{components, feather, resize_bilinear};
use crate::onnx::{Model, Tensor};
use anyhow::{bail, Result};
use std::path::Path;

/// Least-squares scale and shift: argmin over (a, b) of sum over `select` of (a x + b - y)^2, in f64.
/// None when fewer than two selected pixels or x is constant over them.
pub fn fit_scale_shift(x: &[f32], y: &[f32], select: &[bool]) -> Option<(f64, f64)> {
    let (mut n, mut sx, mut sy, mut sxx, mut sxy) = (0f64, 0f64, 0f64, 0f64, 0f64);
    for i in 0..x.len() {
        if select[i] {
            let (a, b) = (x[i] as f64, y[i] as f64);
            n += 1.0;
            sx += a;
            sy += b;
            sxx += a * a;
            sxy += a * b;
        }
    }
    if n < 2.0 {
        return None;
    }
    // centered normal equations (better conditioned than the raw ones)
    let (mx, my) = (sx / n, sy / n);
    let var = sxx / n - mx * mx;
    if var <= 1e-12 * (mx * mx).max(1e-30) {
        return None;
    }
    let a = (sxy / n - mx * my) / var;
    Some((a, my - a * mx))
}

/// The space a prior is affine-invariant in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum PriorSpace {
    Disparity,
    Depth,
}

/// How much nearer than the removed objects a pixel beside the hole lies when it stands in front
/// of them (`in_front_of_removed`).
pub const IN_FRONT_RATIO: f32 = 0.9;
/// The window (radius in pixels) over which the render before removal says how far the removed
/// objects were beside a pixel: wider than the hole's dilation, so that it reaches the objects.
const IN_FRONT_RADIUS: usize = 8;
/// Hole pixels within this relative depth of a pixel beside the hole show its own surface before
/// removal (the dilation's ring, or a surface running on under the objects): they say nothing of
/// how far the objects were.
const SAME_SURFACE: f32 = 0.05;

/// The `known` pixels beside the `hole` (4-neighbours) that stand in front of the removed
/// objects: their rendered depth lies nearer than IN_FRONT_RATIO times the median depth that the
/// render before removal (`front_depth`) had over the hole within IN_FRONT_RADIUS, leaving out the
/// hole pixels that showed the pixel's own surface (within SAME_SURFACE of its depth). Such as the
/// statue beside a box on the lawn behind it; not the ground at the box's foot, which meets the
/// box's depth there.
pub fn in_front_of_removed(
    render_depth: &[f32],
    front_depth: &[f32],
    known: &[bool],
    hole: &[bool],
    w: usize,
    h: usize,
) -> Vec<bool> {
    let mut out = vec![false; w * h];
    let mut depths = Vec::new();
    let r = IN_FRONT_RADIUS;
    for q in beside_pixels(hole, w).into_iter().filter(|&q| known[q] && render_depth[q] > 0.0) {
        let (x, y) = (q % w, q / w);
        let own = render_depth[q];
        depths.clear();
        for yy in y.saturating_sub(r)..=(y + r).min(h - 1) {
            for i in yy * w + x.saturating_sub(r)..=yy * w + (x + r).min(w - 1) {
                let d = front_depth[i];
                if hole[i] && d > 0.0 && d.is_finite() && (d - own).abs() > SAME_SURFACE * own {
                    depths.push(d);
                }
            }
        }
        if depths.is_empty() {
            continue;
        }
        let mid = depths.len() / 2;
        let median = *depths.select_nth_unstable_by(mid, f32::total_cmp).1;
        out[q] = own < IN_FRONT_RATIO * median;
    }
    out
}

/// Which ONNX depth contract a model follows.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize, clap::ValueEnum)]
pub enum DepthContract {
    /// Depth Anything V2: sides multiple of 14, affine-invariant disparity out.
    #[default]
    DepthAnythingV2,
    /// Depth Anything 3: 504 x 504 in, depth out.
    DepthAnything3,
}

pub enum DepthPrior {
    BuiltIn,
    Onnx(Box<Model>, DepthContract),
}

/// RANSAC seed of the plane fits (fixed: completion is deterministic).
pub const PLANE_SEED: u64 = 0x5eed_91a2;

const IMAGENET_MEAN: [f32; 3] = [0.485, 0.456, 0.406];
const IMAGENET_STD: [f32; 3] = [0.229, 0.224, 0.225];

/// The Depth Anything V2 input size for a w x h view: both sides multiples of 14, the longer at most
/// 518, the aspect ratio kept as closely as the multiples allow.
pub fn dav2_size(w: usize, h: usize) -> (usize, usize) {
    let scale = (518.0 / w.max(h) as f64).min(1.0);
    let snap = |v: usize| (((v as f64 * scale) / 14.0).round() as usize).max(1) * 14;
    (snap(w), snap(h))
}

/// Everything a prior may look at.
pub struct DepthView<'a> {
    pub width: usize,
    pub height: usize,
    /// The completed RGB (planar).
    pub image: &'a [f32],
    /// Expected depth rendered from the scene after removal.
    pub render_depth: &'a [f32],
    /// Where the rendered depth is trustworthy for the fit (covered, outside the hole).
    pub valid: &'a [bool],
    /// Expected depth rendered before removal, if known: the planes continued into the hole lie
    /// behind it (`Surfaces::behind`), since the removed objects hid only what lay behind them.
    pub front_depth: Option<&'a [f32]>,
}

impl DepthPrior {
    pub fn onnx(path: &Path, contract: DepthContract) -> Result<DepthPrior> {
        let model = Model::load(path)?;
        if model.input_names().len() != 1 || model.output_names().is_empty() {
            bail!(
                "{}: a depth model needs one input and an output, it has inputs {:?} and outputs {:?}",
                path.display(),
                model.input_names(),
                model.output_names()
            );
        }
        Ok(DepthPrior::Onnx(Box::new(model), contract))
    }

    pub fn name(&self) -> String {
        match self {
            DepthPrior::BuiltIn => "built-in harmonic inverse depth".into(),
            DepthPrior::Onnx(m, c) => format!("onnx {:?} {}", c, m.path().display()),
        }
    }

    /// The prior for a view at full resolution and the space it is affine in.
    pub fn predict(&self, v: &DepthView) -> Result<(Vec<f32>, PriorSpace)> {
        let (w, h) = (v.width, v.height);
        match self {
            DepthPrior::BuiltIn => {
                // only depth outside the hole is known: the Gaussians left behind a removed object
                // were seen by few views or none, and trusting their depth put the patch
                // Gaussians where they float (floater score 436 -> 1, 1159 -> 40, 197 -> 143 on
                // the bench scenes), and labelled a statue's hole with the trees' surface
                let known: Vec<bool> = (0..w * h).map(|i| v.valid[i] && v.render_depth[i] > 0.0).collect();
                let disparity: Vec<f32> =
                    (0..w * h).map(|i| if known[i] { 1.0 / v.render_depth[i] } else { 0.0 }).collect();
                let mut filled = harmonic_fill(&disparity, &known, w, h, 1);
                // the planes around each unknown part continue into it between their own pixels
                // (`flanking`), meeting at creases; the harmonic interpolant stays where no plane
                // is plausible
                let known_depth: Vec<f32> =
                    (0..w * h).map(|i| if known[i] { v.render_depth[i] } else { 0.0 }).collect();
                let unknown: Vec<bool> = known.iter().map(|&k| !k).collect();
                let surfaces = surfaces_around(&disparity, &known, &unknown, w, h, PLANE_SEED);
                for part in components(&unknown, w, h) {
                    // each part of the hole takes the planes refitted to their pixels around it:
                    // a curved surface (a cylindrical wall) fits one plane only near where it
                    // was fitted (`Surfaces::refit_near`)
                    let mut region = vec![false; w * h];
                    part.iter().for_each(|&i| region[i] = true);
                    let mut near = surfaces.refit_near(&disparity, &known, &region, w, h);
                    if let Some(front) = v.front_depth {
                        let in_front = in_front_of_removed(v.render_depth, front, &known, &region, w, h);
                        near.stop_in_front(&disparity, &in_front, &region, w);
                    }
                    let flanks = flanking_at(&near.flank_labels(&known_depth, w), &unknown, &part, w, h);
                    for (&i, &flank) in part.iter().zip(&flanks) {
                        if let Some((_, d)) = near.visible_among(i, w, flank & near.behind(i, w, v.front_depth)) {
                            filled[i] = d as f32;
                        }
                    }
                }
                Ok((filled, PriorSpace::Disparity))
            }
            DepthPrior::Onnx(model, contract) => {
                let (iw, ih) = match contract {
                    DepthContract::DepthAnythingV2 => dav2_size(w, h),
                    DepthContract::DepthAnything3 => (504, 504),
                };
                let mut input = resize_bilinear(v.image, w, h, 3, iw, ih);
                for c in 0..3 {
                    for x in &mut input[c * iw * ih..(c + 1) * iw * ih] {
                        *x = (*x - IMAGENET_MEAN[c]) / IMAGENET_STD[c];
                    }
                }
                let name = model.input_names()[0].clone();
                let out = model.run(&[(&name, &Tensor::new(vec![1, 3, ih as i64, iw as i64], input))])?;
                let o = &out[0];
                if o.data.len() != iw * ih {
                    bail!("{}: depth output has shape {:?}, expected [1, {ih}, {iw}]", model.path().display(), o.shape);
                }
                let space = match contract {
                    DepthContract::DepthAnythingV2 => PriorSpace::Disparity,
                    DepthContract::DepthAnything3 => PriorSpace::Depth,
                };
                Ok((resize_bilinear(&o.data, iw, ih, 1, w, h), space))
            }
        }
    }
}

/// The anchored depth of one view and how the fit went.
#[derive(Clone, Debug)]
pub struct Anchored {
    pub depth: Vec<f32>,
    pub scale: f64,
    pub shift: f64,
    pub space: PriorSpace,
    /// Background pixels used for the fit.
    pub fit_pixels: usize,
    /// RMS of the fit residual over them (in the prior's space).
    pub residual: f64,
}

/// 1 / depth per pixel; 0 where the depth is not positive (unknown).
pub fn disparity(depth: &[f32]) -> Vec<f32> {
    depth.iter().map(|&d| if d > 0.0 { 1.0 / d } else { 0.0 }).collect()
}

/// Stage 1: fits `prior` to the rendered depth on `v.valid` and blends it in over the hole with a
/// mask feathered over `soft_radius` pixels.
pub fn anchor(v: &DepthView, prior: &[f32], space: PriorSpace, hole: &[bool], soft_radius: f32) -> Result<Anchored> {
    let (w, h) = (v.width, v.height);
    let target: Vec<f32> = match space {
        PriorSpace::Disparity => disparity(v.render_depth),
        PriorSpace::Depth => v.render_depth.to_vec(),
    };
    let select: Vec<bool> = (0..w * h).map(|i| v.valid[i] && v.render_depth[i] > 0.0).collect();
    let fit_pixels = select.iter().filter(|&&s| s).count();
    // a prior that already is the render outside the hole (the built-in one) needs no fit, and
    // where the render is constant there (a wall faced squarely, a table seen from straight
    // above) no fit exists
    let is_the_render =
        || fit_pixels >= 2 && (0..w * h).filter(|&i| select[i]).all(|i| prior[i] == target[i] && target[i].is_finite());
    let (a, b) = match fit_scale_shift(prior, &target, &select) {
        Some(fit) => fit,
        None if is_the_render() => (1.0, 0.0),
        None => bail!("depth anchoring: the prior is constant or fewer than 2 background pixels are covered"),
    };
    let residual =
        ((0..w * h).filter(|&i| select[i]).map(|i| (a * prior[i] as f64 + b - target[i] as f64).powi(2)).sum::<f64>()
            / fit_pixels as f64)
            .sqrt();
    // smallest background depth seen: aligned disparities are clamped so depth stays positive
    let min_depth = (0..w * h).filter(|&i| select[i]).map(|i| v.render_depth[i]).fold(f32::INFINITY, f32::min);
    let soft = feather(hole, w, h, soft_radius);
    let depth = (0..w * h)
        .map(|i| {
            let aligned = a * prior[i] as f64 + b;
            let d_align = match space {
                PriorSpace::Disparity => 1.0 / aligned.max(1e-6),
                PriorSpace::Depth => aligned.max(0.05 * min_depth as f64),
            } as f32;
            let render = if v.render_depth[i] > 0.0 { v.render_depth[i] } else { d_align };
            soft[i] * d_align + (1.0 - soft[i]) * render
        })
        .collect();
    Ok(Anchored { depth, scale: a, shift: b, space, fit_pixels, residual })
}

/// How much farther than the aligned prior the render inside the hole must lie to be looking
/// through a gap (`see_through`).
pub const SEE_THROUGH_RATIO: f32 = 1.25;

/// The covered hole pixels (`hole` and not `fill`) whose rendered depth lies more than `ratio`
/// times farther than the prior aligned by `anchored`'s scale and shift: the surfaces around the
/// hole continue in front of what the remaining Gaussians show there. Behind a removed object the
/// near ground is often missing (no view saw it), and rays reach the far background instead.
pub fn see_through(
    v: &DepthView,
    prior: &[f32],
    anchored: &Anchored,
    hole: &[bool],
    fill: &[bool],
    ratio: f32,
) -> Vec<bool> {
    let (a, b) = (anchored.scale, anchored.shift);
    (0..v.width * v.height)
        .map(|i| {
            if !hole[i] || fill[i] || v.render_depth[i] <= 0.0 {
                return false;
            }
            let aligned = a * prior[i] as f64 + b;
            let d_align = match anchored.space {
                PriorSpace::Disparity if aligned > 0.0 => 1.0 / aligned,
                PriorSpace::Depth if aligned > 0.0 => aligned,
                _ => return false, // the prior puts the surface at infinity or behind the camera
            };
            v.render_depth[i] as f64 > ratio as f64 * d_align
        })
        .collect()
}

/// The alpha from which the Gaussians left after removal count as covering a fill pixel
/// (`defer_to_covering`).
pub const COVERED_ALPHA: f32 = 0.9;

/// Fill pixels where the Gaussians left after removal cover the view (alpha at least
/// COVERED_ALPHA, rendered depth `render_depth`) on one of the `surfaces`' planes, while the
/// completion (`labels`, `depth`) put a surface nearer there by more than SEE_THROUGH_RATIO (the
/// render looks past it, as in `see_through`), take that plane instead: its label and its depth.
/// Those Gaussians were fitted to the other views' photos, which saw that plane there, through
/// where the nearer surface would have been. On the statue a pedestal's side and the statue's
/// above it, both flanking the hole, continued as one plane over the lawn that the other views saw
/// beside them (a white and grey block in the hole; there the render lay 1.1-1.9 times farther
/// than the chosen plane, median 1.8). A bench top continued under a removed box is left alone:
/// no view saw past it, and nothing covers it there. The ratio keeps two planes of one surface
/// apart: the cup composite's hazy desk was fitted by two planes, and its render lay 1.1-1.5
/// times farther than the chosen one (median 1.2). Returns how many pixels changed.
pub fn defer_to_covering(
    surfaces: &Surfaces,
    render_depth: &[f32],
    alpha: &[f32],
    fill: &[bool],
    labels: &mut [u8],
    depth: &mut [f32],
    w: usize,
) -> usize {
    let mut changed = 0;
    for i in (0..fill.len()).filter(|&i| fill[i] && alpha[i] >= COVERED_ALPHA) {
        // the plane the covering Gaussians' depth lies on (labelled only here: a few fill pixels)
        let plane = surfaces.label_at(i, w, render_depth[i]);
        if plane == 0 || plane == labels[i] || !surfaces.continues(plane as usize - 1) {
            continue;
        }
        let (x, y) = ((i % w) as f64 + 0.5, (i / w) as f64 + 0.5);
        // the surface the completion chose: the labelled plane's, else the completed depth
        let chosen = match labels[i] {
            0 => depth[i] as f64,
            l => 1.0 / surfaces.planes[l as usize - 1].disparity(x, y),
        };
        if !(chosen > 0.0 && render_depth[i] as f64 > SEE_THROUGH_RATIO as f64 * chosen) {
            continue;
        }
        let d = surfaces.planes[plane as usize - 1].disparity(x, y);
        if d > 0.0 {
            labels[i] = plane;
            depth[i] = (1.0 / d) as f32;
            changed += 1;
        }
    }
    changed
}

/// Model-free stage 2: edge-aware diffusion of the anchored depth inside the hole, guided by the
/// completed image. Each hole pixel repeatedly becomes the average of its 8 neighbours weighted by
/// exp(-|I_p - I_q|^2 / (2 sigma^2)), in inverse depth (where planes are affine); pixels outside the
/// hole are fixed, so the result meets the background exactly at the hole boundary and depth edges
/// follow color edges inside it.
pub fn refine_edge_aware(depth: &[f32], image: &[f32], hole: &[bool], w: usize, h: usize, iters: usize) -> Vec<f32> {
    let sigma2 = 2.0 * 0.08f32 * 0.08;
    let mut x: Vec<f32> = depth.iter().map(|&d| 1.0 / d.max(1e-6)).collect();
    let cells: Vec<usize> = (0..w * h).filter(|&i| hole[i]).collect();
    let hw = w * h;
    for _ in 0..iters {
        for &i in &cells {
            let (px, py) = ((i % w) as i64, (i / w) as i64);
            let (mut sum, mut wsum) = (0f32, 0f32);
            for dy in -1..=1i64 {
                for dx in -1..=1i64 {
                    let (qx, qy) = (px + dx, py + dy);
                    if (dx == 0 && dy == 0) || qx < 0 || qy < 0 || qx >= w as i64 || qy >= h as i64 {
                        continue;
                    }
                    let q = qy as usize * w + qx as usize;
                    let diff: f32 = (0..3).map(|c| (image[c * hw + i] - image[c * hw + q]).powi(2)).sum();
                    let wt = (-diff / sigma2).exp() * if dx != 0 && dy != 0 { 0.7 } else { 1.0 };
                    sum += wt * x[q];
                    wsum += wt;
                }
            }
            if wsum > 1e-12 {
                x[i] = sum / wsum;
            }
        }
    }
    x.into_iter().map(|v| 1.0 / v.max(1e-6)).collect()
}
