//! Stage 1b of removal: the background Gaussians the tagging left inside the removed objects.
//!
//! The tagging votes each Gaussian's label from the views' label maps; on a real capture some of
//! an object's Gaussians lose the vote (a red smudge and a pale box-shaped shell on the cup
//! composite, leftover 0.10 against 0.01 on another training of it) and stay after removal, where
//! every later stage takes them for the background. Such a Gaussian lies inside the objects'
//! visual hull: every view that sees it after removal sees it through a hole. That alone does not
//! set it apart: the surface the object stood on runs under its footprint, and the floor
//! Gaussians there are in the hole in every view too (taking them cost the synth rooms 0.6-1.6 dB
//! masked PSNR, the fill then had to replace them), and so is the floor that only the hole shows
//! behind an object. But these lie on the surfaces around the hole (their planes in inverse
//! depth, `complete::surfaces`) or behind them, and a leftover of the object stands in front of
//! them: the ray past an object's top meets the floor far behind it.
//!
//! So a background Gaussian goes with the objects when, among the views that frame its centre
//! and see it after removal (not more than VISIBLE_TOLERANCE behind the render's depth there),
//! at least `share` see it inside the hole (at least MIN_VIEWS of them), and in fewer than half
//! of those its depth lies on or behind a plane of the surfaces around that view's hole (within
//! `surface_tolerance` relative disparity; only the planes that lie behind the removed objects
//! there, `Surfaces::behind`: a kept object's face in front of them says nothing). Leftovers on
//! an object's near side hide those on its far side, so the holes are drawn again without the
//! ones found and the far side judged then, up to ROUNDS times.

use super::select::{redraw_hole_masks, select_gaussians, HoleConfig, MaskedView, Selection};
use crate::gpu::Gpu;
use crate::planes::Plane;
use crate::removal::complete::surfaces::{surfaces_around, Surfaces};
use crate::scene::{Camera, GaussianScene};
use anyhow::Result;

/// How the background Gaussians left inside the removed objects are found: the one home of its
/// defaults, also `cogeo remove`'s flags.
#[derive(Clone, Debug, serde::Serialize, clap::Args)]
pub struct HullConfig {
    /// A background Gaussian that at least this share of the views seeing it after removal see
    /// inside their hole, and that does not lie on the surfaces around the hole, was left inside
    /// the removed objects by the tagging and goes with them; 0 keeps every background Gaussian.
    #[arg(long = "hull-share", default_value_t = 0.9)]
    pub share: f32,
    /// Relative disparity within which a Gaussian lies on a plane around a view's hole (the floor
    /// under an object's footprint), which keeps it, as lying behind one does.
    #[arg(long = "hull-surface-tolerance", default_value_t = 0.05)]
    pub surface_tolerance: f64,
}

crate::default_from_flags!(HullConfig);

/// Fewest views that must see a Gaussian after removal for it to be judged (fewer say too little
/// about where it lies).
const MIN_VIEWS: usize = 3;
/// How far (relative) behind the render after removal a Gaussian's centre may lie and count as
/// seen: its own splat is part of that render, whose expected depth blends it with what lies
/// behind and in front.
const VISIBLE_TOLERANCE: f64 = 0.05;
/// Most rounds of judging and drawing the holes again.
const ROUNDS: usize = 3;
/// Seed of the planes' RANSAC (the completion's own, so both find the same surfaces).
const PLANE_SEED: u64 = crate::removal::complete::depth::PLANE_SEED;

/// The surfaces around one view's hole, fitted to the render after removal outside it.
struct ViewSurfaces {
    surfaces: Surfaces,
    width: usize,
}

impl ViewSurfaces {
    fn of(view: &MaskedView, camera: &Camera) -> Option<ViewSurfaces> {
        if !view.hole.iter().any(|&m| m) {
            return None;
        }
        let (w, h) = (camera.width as usize, camera.height as usize);
        let a = &view.after_removal;
        let known: Vec<bool> = (0..w * h).map(|p| !view.hole[p] && a.alpha[p] > 0.5 && a.depth[p] > 0.0).collect();
        let disp: Vec<f32> = (0..w * h).map(|p| if known[p] { 1.0 / a.depth[p] } else { 0.0 }).collect();
        Some(ViewSurfaces { surfaces: surfaces_around(&disp, &known, &view.hole, w, h, PLANE_SEED), width: w })
    }

    /// Does depth `z` at image point (x, y), pixel `p`, lie on or behind one of the planes that
    /// lie behind the removed objects there (`front`, their depth per pixel; `Surfaces::behind`),
    /// within `tolerance`? (At the point itself, not its pixel's center: across a pixel a floor's
    /// disparity changes by a few percent in a small view.)
    fn on_or_behind_a_plane(&self, x: f64, y: f64, p: usize, z: f64, front: &[f32], tolerance: f64) -> bool {
        let (d, behind) = (1.0 / z, self.surfaces.behind(p, self.width, Some(front)));
        let planes = self.surfaces.planes.iter().enumerate().filter(|&(s, _)| s < 32 && behind & (1 << s) != 0);
        planes.map(|(_, plane): (usize, &Plane)| plane.disparity(x, y)).any(|pd| pd >= d * (1.0 - tolerance))
    }
}

/// Per Gaussian of `scene`: true for the background Gaussians (`labels` 0, not `removed`) that
/// lie inside the removed objects (module comment), judged from the views' `masked` renders.
pub fn leftovers_inside(
    scene: &GaussianScene,
    labels: &[u8],
    removed: &[bool],
    cameras: &[Camera],
    masked: &[MaskedView],
    cfg: &HullConfig,
) -> Vec<bool> {
    let mut inside = vec![false; scene.len()];
    if cfg.share <= 0.0 {
        return inside;
    }
    // each view's planes are a RANSAC fit of its own: the views' fits spread over the cores
    let mut surfaces: Vec<Option<ViewSurfaces>> = masked.iter().map(|_| None).collect();
    crate::parallel::for_each_item(&mut surfaces, &mut |_, _| {}, |k, s| {
        *s = ViewSurfaces::of(&masked[k], &cameras[k])
    });
    let judge = |i: usize| {
        let m = scene.means[i].map(f64::from);
        let (mut seen, mut in_hole, mut on_surface) = (0usize, 0usize, 0usize);
        for ((cam, view), around) in cameras.iter().zip(masked).zip(&surfaces) {
            let Some((x, y, z)) = cam.project_to_image(m) else { continue };
            let p = y as usize * cam.width as usize + x as usize;
            let rendered = view.after_removal.depth[p] as f64;
            let visible = rendered > 0.0 && z <= rendered * (1.0 + VISIBLE_TOLERANCE);
            if !visible {
                continue;
            }
            seen += 1;
            if view.hole[p] {
                in_hole += 1;
                let tolerance = cfg.surface_tolerance;
                let on = |s: &ViewSurfaces| s.on_or_behind_a_plane(x, y, p, z, &view.before.depth, tolerance);
                on_surface += around.as_ref().is_some_and(on) as usize;
            }
        }
        seen >= MIN_VIEWS && in_hole as f32 >= cfg.share * seen as f32 && 2 * on_surface < in_hole
    };
    let mut candidates: Vec<(usize, bool)> =
        (0..scene.len()).filter(|&i| labels[i] == 0 && !removed[i]).map(|i| (i, false)).collect();
    crate::parallel::for_each_item(&mut candidates, &mut |_, _| {}, |_, c| c.1 = judge(c.0));
    for (i, goes) in candidates {
        inside[i] = goes;
    }
    inside
}

/// Stage 1b: removes from `selection` (of the `chosen` labels in `labels`) the background
/// Gaussians left inside the removed objects and draws the holes (`masked`, stage 2 of
/// `selection`) again without them, round after round (module comment). Returns how many it took.
#[allow(clippy::too_many_arguments)]
pub fn remove_leftovers_inside(
    gpu: &Gpu,
    scene: &GaussianScene,
    labels: &[u8],
    chosen: &[u8],
    cameras: &[Camera],
    holes: &HoleConfig,
    cfg: &HullConfig,
    selection: &mut Selection,
    masked: &mut [MaskedView],
    progress: &mut dyn FnMut(usize, usize),
) -> Result<usize> {
    let mut relabelled = labels.to_vec();
    let mut taken = 0;
    for _ in 0..ROUNDS {
        let inside = leftovers_inside(scene, &relabelled, &selection.removed, cameras, masked, cfg);
        let found = inside.iter().filter(|&&g| g).count();
        if found == 0 {
            break;
        }
        taken += found;
        inside.iter().zip(&mut relabelled).filter(|(&g, _)| g).for_each(|(_, l)| *l = chosen[0]);
        *selection = select_gaussians(scene, &relabelled, chosen)?;
        redraw_hole_masks(gpu, scene, selection, &inside, cameras, holes, masked, progress)?;
    }
    Ok(taken)
}
