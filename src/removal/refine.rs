//! Stage 5 of removal: geometry-regularized refinement of the fused scene against the completed
//! images of the edited views. Loss (1 - 0.2) L1 + 0.2 (1 - SSIM) (the training loss). The first
//! `frozen_fraction` of the iterations train only color (SH) and opacity; the rest also move
//! geometry, each Gaussian's per-step update of each geometry tensor clipped to Euclidean norm
//! `trust_radius` (train/adam.rs `record_clipped`), so no Gaussian jumps. The colors learn at
//! `COLOR_LR_GAIN` and the scales and rotations at `SHAPE_LR_GAIN` times training's rate: the
//! refinement is short, and the Gaussians left behind the objects must change color, not just
//! settle. For the same reason the hole's pixels weigh `HOLE_WEIGHT` times the others.
//!
//! The trust region was first one bound on each whole tensor's step; over the bench scenes' 20k
//! Gaussians a radius of 0.01 let each Gaussian move about 1/20 of an Adam step (scales 1/100),
//! so the geometry half barely changed anything, and the bound tightened as scenes grew. Bounding
//! each Gaussian instead raised held-out seen-elsewhere PSNR by 0.5 dB on scenes two and three.

use crate::eval::render_psnr;
use crate::gpu::Gpu;
use crate::image_ops::{bounding_box, crop, including, Rect};
use crate::render::reach::reaches;
use crate::render::RenderSettings;
use crate::scene::dataset::{Dataset, View};
use crate::scene::{Camera, GaussianScene};
use crate::train::trainer::{Frozen, IterateAverage, Motion, TrainConfig, Trainer};
use anyhow::Result;

/// The refinement's SH learning rates as a multiple of training's. On the bench scenes 150
/// iterations at 1, 4, 8 and 16 times training's rate gave held-out seen-elsewhere PSNR 24.51,
/// 25.00, 25.07 and 25.15 dB (scene one); 8 keeps the steps small against a color's range.
pub const COLOR_LR_GAIN: f32 = 8.0;

/// The refinement's scale and rotation learning rates as a multiple of training's. Held-out
/// seen-elsewhere PSNR on bench scenes two / three, median of three refinement seeds: 26.53 /
/// 26.79 dB at 1, 26.72 / 26.95 at 2, 26.83 / 26.97 at 4; 2 keeps the shapes' steps small.
pub const SHAPE_LR_GAIN: f32 = 2.0;

/// Loss weight of a hole pixel relative to the rest of its view. Outside the hole the target is
/// the scene's own render, an anchor that only keeps the background; the hole's pixels, 6-18 %
/// of a view on the bench scenes, are the ones carrying news (the captured colors transferred from other views). In
/// the plain weighted mean the anchor outweighs them on every Gaussian the two share, such as the
/// background behind an object that some views saw and others did not. Held-out seen-elsewhere
/// PSNR on bench scenes one / two / three at 1, 2, 4 and 8: 27.86 / 26.72 / 26.95, 28.17 /
/// 27.01 / 27.24, 28.27 / 27.14 / 27.38, 28.23 / 27.18 / 27.42 dB, the outside unchanged within
/// 0.1 dB (refinement seeds 1 and 2 on three: 26.65 -> 26.98, 26.97 -> 27.38 at 4); twice the
/// iterations at 1 reach 27.07 / 27.14 (two / three), at 4 27.30 / 27.48. The statue's background
/// against its original render: 43.7 dB at 1, 41.4 at 4.
pub const HOLE_WEIGHT: f32 = 4.0;

/// Pixels kept around each view's hole and patch in the refinement's window (`refine_window`).
/// Outside its hole a view's target is the scene's own render, which only anchors the
/// Gaussians there; the pixels far from every hole anchor Gaussians that nothing else moves.
/// Paired held-out masked PSNR at 16 and 32 against whole views: synth two-of-three 20.32 /
/// 20.32 / 20.34, three-of-four 20.03 / 20.04 / 20.05, one 20.35 / 20.35 / 20.37, composited
/// statue 24.18 / 24.17 / 24.16, composited cup 25.35 / 25.28 / 25.20 dB; the statue `images_2`
/// refinement stage 57 / 62 / 92 s. Later (code `833a23e`), 8 against 16 on six paired sets:
/// synth one 26.00 / 26.00, two-of-three 26.31 / 26.28, composited cup 20.49 / 20.38 and 22.77 /
/// 22.74, statue 22.74 / 22.71 and 24.22 / 24.21 dB (LPIPS within 0.001); the statue
/// `images_2` refinement stage 15.3 / 16.6 / 15.6 s against 16.1 / 17.8 / 16.7. 8 px is still
/// beyond the SSIM window's 5 px radius.
pub const WINDOW_MARGIN: u32 = 8;

/// The refinement's iterations (one view each) on scenes of up to DEFAULT_ITERS / MIN_PASSES
/// views: the paper's 150, set on scenes of 14 to 25 views (6 to 11 passes over them).
pub const DEFAULT_ITERS: u32 = 150;

/// Passes over the views the default refinement makes at least (`RefineConfig::iterations`). At
/// 150 iterations the cup composites' 67 views were refined 2.2 times each, and their held-out
/// renders kept a patchwork of the views' fills. Held-out masked PSNR / LPIPS at 150, 300 and
/// 402 iterations (6 passes): cup-one 25.90 / 0.200, 26.13 / 0.200, 26.37 / 0.182;
/// cup-two-of-three 27.07 / 0.141, 27.68 / 0.144, 27.62 / 0.139. The statue's 25 views keep 150
/// (at 300 statue-one scored 20.18 / 0.346 against 20.30 / 0.348), and so does the `remove`
/// speed goal measured on it.
pub const MIN_PASSES: u32 = 6;

/// Which moving Gaussians learn view-dependent color by default: all. Held-out masked PSNR /
/// LPIPS with `all`, `kept` (the patch view-independent) and `none` (bench/JOURNAL.md,
/// 2026-12-01): statue-one 20.93 / 0.246, 21.00 / 0.259, 21.01 / 0.259; statue-two-of-three
/// 21.75 / 0.250, 21.78 / 0.257, 21.79 / 0.257; cup-one 26.79 / 0.189, 26.89 / 0.192, 26.83 /
/// 0.178; cup-two-of-three 28.65 / 0.119, 28.70 / 0.121, 28.70 / 0.124. Averaging the views'
/// fills gains at most 0.1 dB and costs LPIPS on three scenes of four. On
/// cup-one at 1200 iterations the patch view-independent still fell to 25.63 / 0.199 (25.55 /
/// 0.204 with all), so view dependence is not what the longer refinement overfits with.
pub const VIEW_DEPENDENCE: ViewDependence = ViewDependence::All;

/// Weight of the coverage term by default: none. On statue-two-of-three's composite, held out,
/// mask pixels rendered darker than 0.6 of the truth (2.4 % of them) carried 23 % of the squared
/// error: the patch lay where the views' completions put the surface farthest (a point floating in
/// front of any other view's completion is dropped) and held gaps there, the black background
/// showing through. At 0.1 masked PSNR / LPIPS went 21.10 / 0.334 -> 21.73 / 0.328 (at 1, on
/// every fill pixel, 21.84 / 0.382, and those pixels' share of the error 10 %), but statue-one
/// went 21.38 / 0.419 -> 21.43 / 0.440 (never-seen LPIPS 0.411 -> 0.432, over 0.7 of the
/// harmonic fill's 0.607 in the bench table) and cup-one 27.21 / 0.156 -> 27.16 / 0.158
/// (bench/JOURNAL.md, 2026-12-02).
pub const COVERAGE_WEIGHT: f32 = 0.0;

/// Where the coverage term draws by default (`RefineConfig::coverage_on`): the pixels the color
/// loss leaves out, where nothing else asks the patch to cover. On the transferred pixels at
/// weight 1 the cups' held-out masked PSNR rose by 0.08-0.38 dB at each removal seed (cup-one
/// 27.13 / 27.39 / 27.14 -> 27.46 / 27.47 / 27.52): there the refinement had fitted its targets
/// at alpha 0.94-0.96 with brighter colors, which other directions do not share. But masked
/// LPIPS rose by 0.005-0.011 on the cups and statue-one, the harmonic fill and nearest-copy moved
/// with the full pipeline, and the statue's PSNR moved by 0.01-0.03 dB (bench/JOURNAL.md,
/// 2026-12-04, 04:58).
pub const COVERAGE_ON: CoverageOn = CoverageOn::LeftOut;

/// Passes over the views whose iterates the refinement averages by default (`RefineConfig::
/// average_passes`): one, so that every view pulls the result once. It steps one view at a time
/// at a constant rate, and where the views' targets disagree (each view's own fill of the hole)
/// it ended where the last views pulled it: a removal's seed, which draws the view order, moved
/// held-out masked PSNR by up to 1.2 dB (cup-two-of-three, seeds 0 / 1 / 2: 28.17 / 28.04 /
/// 27.01). Where they agree, or only one view weighs a Gaussian (the inventions the consensus
/// leaves to their owners), the mean of the last pass is the last step, and the grain stays.
/// Masked PSNR / LPIPS without and with the mean of the last pass (bench/JOURNAL.md,
/// 2026-12-03, 21:47): cup-one seeds 0 / 1 / 2 27.10 / 0.146, 27.19 / 0.147, 26.77 / 0.155 ->
/// 27.13 / 0.144, 27.39 / 0.149, 27.16 / 0.145; cup-two-of-three seed 2 27.01 / 0.150 -> 28.24 /
/// 0.131; statue-one 21.41 / 0.352 -> 21.40 / 0.350; statue-two-of-three 22.06 / 0.299 -> 22.08 /
/// 0.296. The mean of the last two passes blurred the statue's inventions (statue-one 21.36 /
/// 0.371).
pub const AVERAGE_PASSES: f32 = 1.0;

/// Refinement settings: the one home of their defaults, also `cogeo remove`'s flags.
#[derive(Clone, Debug, serde::Serialize, clap::Args)]
pub struct RefineConfig {
    /// Refinement iterations (the first half with geometry frozen), one view each. Default: 150,
    /// or 6 per view with more than 25 views (`DEFAULT_ITERS`, `MIN_PASSES`), so that each view
    /// is refined about as often as on the scenes the default was set on.
    #[arg(id = "refine-iters", long = "refine-iters")]
    pub iters: Option<u32>,
    /// Share of the iterations with geometry frozen.
    #[arg(skip = 0.5)]
    pub frozen_fraction: f32,
    /// Trust region of the second half: each Gaussian's per-step update of its position, of its
    /// log-scales and of its rotation is clipped to this Euclidean norm.
    #[arg(long, default_value_t = 0.01)]
    pub trust_radius: f32,
    /// Set by the removal from its own `background` (`RemoveOptions::refine_config`).
    #[arg(skip)]
    #[serde(skip)]
    pub background: [f32; 3],
    /// Set by the removal from its own `seed`.
    #[arg(skip)]
    #[serde(skip)]
    pub seed: u64,
    /// Refinement learning rate of the colors (SH coefficients) as a multiple of training's
    /// (`TrainConfig::color_lr_gain`). Adam moves a coefficient by about its rate per step, so at
    /// training's rate the short refinement cannot recolor the Gaussians left behind the objects.
    #[arg(id = "refine-color-lr-gain", long = "refine-color-lr-gain", default_value_t = COLOR_LR_GAIN)]
    pub color_lr_gain: f32,
    /// Refinement learning rate of the Gaussians' scales and rotations as a multiple of
    /// training's (`TrainConfig::shape_lr_gain`): in the short second half the patch's
    /// footprint-sized ellipses must take the shape of the surface's texture, not just settle.
    #[arg(id = "refine-shape-lr-gain", long = "refine-shape-lr-gain", default_value_t = SHAPE_LR_GAIN)]
    pub shape_lr_gain: f32,
    /// Weight of the refinement's coverage term (>= 0; 0, the default, leaves it out): each
    /// view's fill pixels whose color the loss does not weigh (the inventions the consensus left
    /// to their owners) are drawn toward full opacity, about as strongly as a color error of this
    /// size draws a hole pixel (`coverage_gradients`). There the patch, fused from other views'
    /// pixels, can leave gaps through which the background shows (`COVERAGE_WEIGHT`).
    #[arg(
        id = "refine-coverage-weight",
        long = "refine-coverage-weight",
        default_value_t = COVERAGE_WEIGHT,
        value_parser = crate::flag_values::parse_weight
    )]
    pub coverage_weight: f32,
    /// Which of a view's hole pixels the coverage term (`--refine-coverage-weight` above 0) draws
    /// toward full opacity.
    #[arg(id = "refine-coverage-on", long = "refine-coverage-on", value_enum, default_value_t = COVERAGE_ON)]
    pub coverage_on: CoverageOn,
    /// Refinement loss weight of each view's hole pixels relative to its other pixels (>= 0;
    /// `loss_weights`). Outside the hole the target is the scene's own render, which only anchors
    /// the background; the hole is a tenth or so of a view and carries the colors the other views
    /// captured.
    #[arg(
        id = "refine-hole-weight",
        long = "refine-hole-weight",
        default_value_t = HOLE_WEIGHT,
        value_parser = crate::flag_values::parse_weight,
        allow_negative_numbers = true
    )]
    pub hole_weight: f32,
    /// Each view is refined over its window only: the bounding box of its hole and of the patch
    /// Gaussians' centres it sees, grown by this many pixels (`refine_window`). Pixels farther out
    /// anchor Gaussians that no hole moves, and rendering them was most of a refinement
    /// iteration's cost on a real capture.
    #[arg(id = "refine-margin", long = "refine-margin", default_value_t = WINDOW_MARGIN)]
    pub margin: u32,
    /// Refine over every view's whole frame instead of its window.
    #[arg(id = "refine-whole-views", long = "refine-whole-views")]
    pub whole_views: bool,
    /// Let every Gaussian the refined views show move (ablation). By default only the patch
    /// Gaussians and the Gaussians whose centre some view's hole shows do (`movable_gaussians`);
    /// the rest of the scene renders unchanged, as trained on the photos.
    #[arg(id = "refine-all-gaussians", long = "refine-all-gaussians")]
    pub all_gaussians: bool,
    /// Which moving Gaussians may learn view-dependent color (SH bands above the first) in the
    /// refinement; the others keep their higher bands as they are (`Motion::ViewIndependent`).
    /// A patch of one color for every direction cannot show each view its own fill, but it averages
    /// the views' inventions where they disagree: on the real composites `kept` and `none` raised
    /// held-out masked PSNR by up to 0.1 dB and blurred the texture (`VIEW_DEPENDENCE`).
    #[arg(
        id = "refine-view-dependence",
        long = "refine-view-dependence",
        value_enum,
        default_value_t = VIEW_DEPENDENCE
    )]
    pub view_dependence: ViewDependence,
    /// The refined scene is the mean of the parameters over the last this many passes over the
    /// views (>= 0; at most all the iterations; 0 keeps the last step's): the refinement steps one
    /// view at a time, and where the views' fills disagree the last step leans to the last views
    /// (`AVERAGE_PASSES`).
    #[arg(
        id = "refine-average-passes",
        long = "refine-average-passes",
        default_value_t = AVERAGE_PASSES,
        value_parser = crate::flag_values::parse_weight
    )]
    pub average_passes: f32,
}

/// Which of the refinement's moving Gaussians step their SH bands above the first.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, clap::ValueEnum)]
pub enum ViewDependence {
    /// All of them.
    All,
    /// The scene's own only: the patch Gaussians (zero higher bands from the fusion) keep one
    /// color for every direction.
    Kept,
    /// None: every moving Gaussian keeps the higher bands it has.
    None,
}

/// The hole pixels the coverage term draws toward full opacity (`coverage_gradients`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, clap::ValueEnum)]
pub enum CoverageOn {
    /// Those whose color the loss does not weigh: the inventions the consensus left to their
    /// owners.
    LeftOut,
    /// The fill pixels that took a photo's color: background some other view saw, where the
    /// patch and the Gaussians left behind the objects can otherwise fit their targets at
    /// partial opacity with brighter colors, a trade other directions do not share.
    Transferred,
    /// Every fill pixel.
    Fill,
}

crate::default_from_flags!(RefineConfig);

impl RefineConfig {
    /// The iterations over `views` views: `iters` where given, else DEFAULT_ITERS or MIN_PASSES
    /// per view, whichever is more.
    pub fn iterations(&self, views: usize) -> u32 {
        let per_view = u32::try_from(views).unwrap_or(u32::MAX).saturating_mul(MIN_PASSES);
        self.iters.unwrap_or(DEFAULT_ITERS.max(per_view))
    }

    /// Of `iters` iterations over `views` views, the last ones whose parameters are averaged:
    /// `average_passes` passes, at most all of them.
    pub fn averaged_iterations(&self, iters: u32, views: usize) -> u32 {
        ((self.average_passes as f64 * views as f64).round() as u32).min(iters)
    }
}

#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct RefineReport {
    pub iters: u32,
    pub frozen_iters: u32,
    /// The last iterations whose parameters the refined scene averages (`AVERAGE_PASSES`).
    pub averaged_iters: u32,
    /// Mean PSNR of the edited views against their targets before and after, over the views'
    /// windows (`refine_window`) unless the whole views were refined. The removal measures the
    /// after on its final renders of the views (`window_psnr`), which show the windows as the
    /// refinement renders them: a render of every view less.
    pub psnr_before: f64,
    pub psnr_after: Option<f64>,
    /// The Gaussians some view shows, the ones the refinement renders (`seen_by_any`).
    pub gaussians_refined: usize,
    /// Of those, the ones it moved (`movable_gaussians`; all of them with `--refine-all-gaussians`).
    pub gaussians_moved: usize,
}

/// The Gaussians the refinement may move: the last `patch` of `scene` (the new ones) and every
/// other whose centre projects into the hole of one of the views (`cameras`, `holes` of the
/// cameras' whole images), such as those training left behind the removed objects. The others
/// hold still: most of their footprint lies outside every hole, where the refinement's target is
/// the scene's own render, so they need only keep it. Yet Adam moves a parameter by about its
/// learning rate per step whatever its gradient's size, and at the refinement's raised rates
/// every Gaussian the windows showed drifted: on the composited cup the refinement ended 3 dB
/// further from its own targets than it began, and the held-out views lost 0.6 dB outside the
/// masks. Moving also those whose footprint reaches a hole pixel within two deviations let them
/// drift again (cup 0.2 dB outside, statue 0.07 dB in the masks; bench/JOURNAL.md, 2026-11-27).
pub fn movable_gaussians(
    scene: &GaussianScene,
    cameras: &[Camera],
    holes: &[&[bool]],
    patch: usize,
    view_dependence: ViewDependence,
) -> Vec<Motion> {
    let first_patch = scene.len() - patch;
    let in_a_hole = |i: usize| {
        let m = scene.means[i].map(f64::from);
        cameras.iter().zip(holes).any(|(cam, hole)| cam.pixel_of(m).is_some_and(|(q, _)| hole[q]))
    };
    let (kept, new) = match view_dependence {
        ViewDependence::All => (Motion::Free, Motion::Free),
        ViewDependence::Kept => (Motion::Free, Motion::ViewIndependent),
        ViewDependence::None => (Motion::ViewIndependent, Motion::ViewIndependent),
    };
    let mut movable: Vec<Motion> =
        (0..scene.len()).map(|i| if i >= first_patch { new } else { Motion::Held }).collect();
    crate::parallel::for_each_item(&mut movable, &mut |_, _| {}, |i, m| {
        if *m == Motion::Held && in_a_hole(i) {
            *m = kept;
        }
    });
    movable
}

/// Per view, the coverage term's gradient by the rendered alpha (`RefineConfig::coverage_weight`):
/// at the pixels `drawn` (`CoverageOn`), -`weight` times the hole weight over the sum of the
/// view's `masks` (the color loss's weights, `loss_weights`: its normalization), so that such a
/// pixel left uncovered costs about what a color error of `weight` costs in a hole pixel that
/// counts in full; 0 elsewhere. With a hole weight of 0 the gradient is 0 too.
pub fn coverage_gradients(masks: &[Vec<f32>], drawn: &[Vec<bool>], hole_weight: f32, weight: f32) -> Vec<Vec<f32>> {
    masks
        .iter()
        .zip(drawn)
        .map(|(mask, drawn)| {
            let sum: f64 = mask.iter().map(|&w| w as f64).sum();
            let g = -(weight as f64 * hole_weight as f64 / sum.max(1.0)) as f32;
            drawn.iter().map(|&d| if d { g } else { 0.0 }).collect()
        })
        .collect()
}

/// Per view, the pixels `on` names: of its `fill` (`MaskedView::fill`), those that took a photo's
/// color (`transferred`; none where no transfer ran), or all; or those whose color weight in `mask`
/// is zero (a weight is zero only where the consensus left an invention to its owners, all in
/// the fill, or in the whole hole with a hole weight of 0).
pub fn coverage_pixels(on: CoverageOn, mask: &[f32], fill: &[bool], transferred: Option<&[bool]>) -> Vec<bool> {
    match (on, transferred) {
        (CoverageOn::LeftOut, _) => mask.iter().map(|&m| m == 0.0).collect(),
        (CoverageOn::Fill, _) => fill.to_vec(),
        (CoverageOn::Transferred, Some(t)) => fill.iter().zip(t).map(|(&f, &t)| f && t).collect(),
        (CoverageOn::Transferred, None) => vec![false; fill.len()],
    }
}

/// The part of `camera`'s view the refinement needs: the bounding box of its `hole` and of the
/// `patch` Gaussians' centres in front of it, grown by `margin` pixels within the image and widened
/// to a multiple of `loss::VECTOR_WIDTH` pixels where the image is wide enough. None when the view
/// sees neither.
pub fn refine_window(camera: &Camera, hole: &[bool], patch: &[[f32; 3]], margin: u32) -> Option<Rect> {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let mut b = bounding_box(hole, w);
    for m in patch {
        if let Some((x, y, _)) = camera.project_to_image(m.map(f64::from)) {
            b = Some(including(b, x as usize, y as usize));
        }
    }
    // the loss moves vec4s only along rows of whole vec4s: on llvmpipe it took 24.6 ms at 215 x 256
    // pixels against 14.2 ms at 216 x 256 (median of 15), and the statue's windows are that size,
    // where an iteration took 147 ms
    let vector = crate::train::loss::VECTOR_WIDTH as usize;
    b.map(|r| r.grown(margin as usize, margin as usize, w, h).widened_to_multiple(vector, w))
}

/// Mean PSNR (renders clamped to [0, 1]) of whole-view `renders` against the views' `targets`
/// (whole views too), over each view's refinement `window` where it has one.
pub fn window_psnr(renders: &[Vec<f32>], targets: &[&[f32]], cameras: &[Camera], windows: &[Option<Rect>]) -> f64 {
    let psnr = |i: usize| {
        let (w, h) = (cameras[i].width as usize, cameras[i].height as usize);
        match windows[i] {
            Some(win) => render_psnr(&crop(&renders[i], w, h, 3, win), &crop(targets[i], w, h, 3, win)),
            None => render_psnr(&renders[i], targets[i]),
        }
    };
    (0..renders.len()).map(psnr).sum::<f64>() / renders.len().max(1) as f64
}

/// `camera` seeing only `window` of its image: the same pose and focal lengths, the principal
/// point moved by the window's corner, the projection's clamp the whole view's
/// (`Camera::whole_view`), so the window's pixels render as in the whole view.
pub fn window_camera(camera: &Camera, window: Rect) -> Camera {
    Camera {
        width: window.width() as u32,
        height: window.height() as u32,
        cx: camera.cx - window.x0 as f64,
        cy: camera.cy - window.y0 as f64,
        whole_view: Some(camera.whole_view.unwrap_or((camera.width, camera.height))),
        ..camera.clone()
    }
}

/// Each view's per-pixel loss weights: `hole_weight` inside its hole, 1 outside, times its
/// consensus weight where there is one (consensus.rs; 0 leaves an invented pixel out).
pub fn loss_weights(holes: &[&[bool]], consensus: Option<Vec<Vec<f32>>>, hole_weight: f32) -> Vec<Vec<f32>> {
    let mut weights = consensus.unwrap_or_else(|| holes.iter().map(|h| vec![1.0; h.len()]).collect());
    for (w, hole) in weights.iter_mut().zip(holes) {
        assert_eq!(w.len(), hole.len(), "a view's consensus weights and hole differ in size");
        for (w, _) in w.iter_mut().zip(hole.iter()).filter(|(_, &inside)| inside) {
            *w *= hole_weight;
        }
    }
    weights
}

/// Refines `scene` towards `targets` (planar RGB per camera), each pixel's loss weighted by
/// `masks` where given (`loss_weights`); only the Gaussians `movable` marks move where it is given.
/// `extent` scales the position learning rate as in training.
#[allow(clippy::too_many_arguments)]
pub fn refine(
    gpu: &Gpu,
    scene: &GaussianScene,
    cameras: &[Camera],
    targets: Vec<Vec<f32>>,
    masks: Option<&[Vec<f32>]>,
    alpha_gradients: Option<&[Vec<f32>]>,
    movable: Option<&[Motion]>,
    extent: f64,
    cfg: &RefineConfig,
    mut progress: impl FnMut(u32),
) -> Result<(GaussianScene, RefineReport)> {
    let train: Vec<View> = cameras
        .iter()
        .zip(targets)
        .map(|(c, image)| View {
            camera: c.clone(),
            image,
            path: format!("<completed {}>", c.name).into(),
            undistortion: None,
        })
        .collect();
    let data = Dataset { train, test: Vec::new(), points: Vec::new(), extent, warnings: Vec::new(), pose_check: None };
    let iters = cfg.iterations(cameras.len());
    let tcfg = TrainConfig {
        iters: iters.max(1),
        sh_degree: scene.sh_degree,
        densify: false,
        seed: cfg.seed,
        background: cfg.background,
        color_lr_gain: cfg.color_lr_gain,
        shape_lr_gain: cfg.shape_lr_gain,
        ..Default::default()
    };
    // only the Gaussians some view shows: the rest get no gradient (see `seen_by_any`)
    let seen = seen_by_any(scene, cameras, 0.5 * RenderSettings::default().near as f64);
    let all = seen.iter().all(|&s| s) || !seen.iter().any(|&s| s);
    let part = if all { None } else { Some(scene.subset(&seen)) };
    let mut t = Trainer::new(gpu, &data, part.as_ref().unwrap_or(scene), tcfg)?;
    // the bands the scene learnt, from the first step. A scene trained for fewer than
    // `--sh-band-every` iterations (1000) has learnt only the DC band; rendering and stepping its
    // zero bands as well made a refinement iteration dearer than a training one, and 150
    // iterations from zero added nothing (removal bench scenes and real composites within 0.1 dB
    // either way)
    t.fixed_sh_degree = Some(scene.learnt_sh_degree());
    if let Some(m) = masks {
        t.set_loss_masks(m)?;
    }
    if let Some(g) = alpha_gradients {
        t.set_alpha_gradients(g)?;
    }
    let moved = match movable {
        Some(movable) => {
            assert_eq!(movable.len(), scene.len(), "a movable flag per Gaussian");
            let of_part: Vec<Motion> = movable.iter().zip(&seen).filter(|(_, &s)| s || all).map(|(&m, _)| m).collect();
            t.set_movable(&of_part)?;
            of_part.iter().filter(|&&m| m != Motion::Held).count()
        }
        None => t.num_gaussians() as usize,
    };
    let psnr_before = t.mean_psnr(&data.train)?;
    let frozen_iters = ((iters as f32) * cfg.frozen_fraction.clamp(0.0, 1.0)).round() as u32;
    let averaged_iters = cfg.averaged_iterations(iters, cameras.len());
    let mut average = (averaged_iters > 0).then(|| IterateAverage::new(&t)).transpose()?;
    while t.step < iters {
        if t.step < frozen_iters {
            t.frozen = Frozen::geometry();
            t.trust_radius = None;
        } else {
            t.frozen = Frozen::default();
            t.trust_radius = Some(cfg.trust_radius);
        }
        t.iterate(&data, false)?;
        progress(t.step);
        if let Some(average) = average.as_mut().filter(|_| t.step + averaged_iters > iters) {
            average.add(&t)?;
        }
    }
    if let Some(average) = &average {
        average.apply(&mut t)?;
    }
    let refined = t.download_scene()?;
    // no densification: Gaussians keep their order, so the extra properties (labels) carry over
    let out = match part {
        Some(_) => {
            let mut out = scene.clone();
            out.set_subset(&seen, &refined);
            out
        }
        None if refined.len() == scene.len() => GaussianScene { extras: scene.extras.clone(), ..refined },
        None => refined,
    };
    let shown = seen.iter().filter(|&&s| s).count();
    let report = RefineReport {
        iters,
        frozen_iters,
        averaged_iters: average.as_ref().map_or(0, IterateAverage::count),
        psnr_before,
        psnr_after: None,
        gaussians_refined: shown,
        gaussians_moved: moved,
    };
    Ok((out, report))
}

/// The Gaussians any of `cameras` can show: a superset of what the renderer bins into their
/// images (`render::reach::reaches`). Any other Gaussian touches no pixel of any view, so it gets
/// no gradient, its Adam moments stay zero and it never moves, and it adds nothing to any render
/// (the renderer's sorts are stable, so the others keep their order): refining without it is the
/// same refinement, less its projection, sorting and Adam step every iteration. Refining views
/// over windows around the holes leaves out most of a scene.
pub fn seen_by_any(scene: &GaussianScene, cameras: &[Camera], near: f64) -> Vec<bool> {
    (0..scene.len()).map(|i| cameras.iter().any(|cam| reaches(scene, i, cam, near))).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two views of 2x2 pixels: the hole's pixels weigh `hole_weight` times their consensus
    /// weight (an invented pixel left out stays out), the others keep theirs; without a consensus
    /// every pixel starts at 1.
    #[test]
    fn hole_pixels_weigh_more_and_left_out_pixels_stay_out() {
        let holes = [[true, true, false, false], [false, true, false, true]];
        let holes: Vec<&[bool]> = holes.iter().map(|h| &h[..]).collect();
        let consensus = vec![vec![1.0, 0.0, 1.0, 0.0], vec![1.0, 1.0, 1.0, 1.0]];
        let weights = loss_weights(&holes, Some(consensus), 4.0);
        assert_eq!(weights, vec![vec![4.0, 0.0, 1.0, 0.0], vec![1.0, 4.0, 1.0, 4.0]]);
        let plain = loss_weights(&holes, None, 2.5);
        assert_eq!(plain, vec![vec![2.5, 2.5, 1.0, 1.0], vec![1.0, 2.5, 1.0, 2.5]]);
    }

    /// The coverage term's gradient: at the pixels drawn, the weight times the hole weight over
    /// the view's weight sum (the color loss's normalization), negative (coverage rewarded).
    #[test]
    fn coverage_pulls_the_drawn_pixels_by_the_color_loss_normalization() {
        let holes = [[true, true, false, false]];
        let holes: Vec<&[bool]> = holes.iter().map(|h| &h[..]).collect();
        let masks = loss_weights(&holes, Some(vec![vec![0.0, 1.0, 1.0, 1.0]]), 4.0);
        assert_eq!(masks, vec![vec![0.0, 4.0, 1.0, 1.0]]);
        let left_out = vec![coverage_pixels(CoverageOn::LeftOut, &masks[0], &[true, true, false, false], None)];
        assert_eq!(left_out, vec![vec![true, false, false, false]]);
        let g = coverage_gradients(&masks, &left_out, 4.0, 0.5);
        assert_eq!(g, vec![vec![-0.5 * 4.0 / 6.0, 0.0, 0.0, 0.0]]);
        let both = vec![vec![true, true, false, false]];
        let none = coverage_gradients(&[vec![0.0, 0.0, 1.0, 1.0]], &both, 4.0, 0.5);
        assert_eq!(none, vec![vec![-1.0, -1.0, 0.0, 0.0]], "the sum 2: 0.5 x 4 / 2");
        let tiny = coverage_gradients(&[vec![0.0, 0.5]], &[vec![true, false]], 4.0, 0.5);
        assert_eq!(tiny, vec![vec![-2.0, 0.0]], "a weight sum under 1 counts as 1");
    }

    /// The pixels each choice draws: the transferred ones only inside the fill, none without a
    /// transfer; the whole fill; the ones the color loss leaves out wherever they are.
    #[test]
    fn coverage_pixels_follow_the_choice() {
        let mask = [0.0, 4.0, 4.0, 1.0];
        let fill = [true, true, false, false];
        let transferred = [false, true, true, false];
        let on = |c| coverage_pixels(c, &mask, &fill, Some(&transferred));
        assert_eq!(on(CoverageOn::Transferred), vec![false, true, false, false]);
        assert_eq!(on(CoverageOn::Fill), vec![true, true, false, false]);
        assert_eq!(on(CoverageOn::LeftOut), vec![true, false, false, false]);
        assert_eq!(coverage_pixels(CoverageOn::Transferred, &mask, &fill, None), vec![false; 4]);
    }

    /// The default refines 150 iterations up to 25 views and 6 per view beyond (the cup
    /// composites' 67: 402); a count given on the command line is taken as it is, 0 included.
    #[test]
    fn iterations_grow_with_the_views_unless_given() {
        let default = RefineConfig::default();
        assert_eq!(default.iters, None);
        let counts: Vec<u32> = [1, 14, 25, 26, 67].iter().map(|&v| default.iterations(v)).collect();
        assert_eq!(counts, vec![150, 150, 150, 156, 402]);
        for given in [0, 10, 150] {
            let cfg = RefineConfig { iters: Some(given), ..RefineConfig::default() };
            assert_eq!(cfg.iterations(67), given);
        }
    }
}
