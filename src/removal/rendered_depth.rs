//! Which rendered depth the removal reads: the expected depth (the blend of every Gaussian's
//! depth along the ray) or the median depth (the depth of the Gaussian that takes the
//! transmittance to one half). Stage 3 anchors its depth prior to it, the photo-consistent hole
//! depth starts from it, and the color transfer checks its sources against it.
//!
//! Neither is right on every capture. Where a surface is a thin, noisy shell of Gaussians (the
//! statue's lawn) the expected depth scatters in front of it and the completed depth lies in
//! front of the lawn; where the capture's Gaussians sit in front of a smooth surface (the cup's
//! desk) the median depth loses the views' agreement. The captured photos tell them apart: the
//! photo-consistency the hole depth's correction measures (`photo_depth::DepthScale`, the color
//! variance across the views that saw a completed point) is lower under the depth the photos
//! agree with. On the real-photo bench (bench/JOURNAL.md, 2026-12-02) it was lower under the
//! median depth on statue-two-of-three (0.0016 against 0.0020; held out 21.10 -> 22.20 dB) and
//! under the expected depth on the cups (0.0092 against 0.0173; the median depth cost them
//! 0.8-1.0 dB) and on statue-one (0.0016 against 0.0017, where the two score alike).
//!
//! `Auto` runs stages 2 to 3b under both (the hull too judges in the depth the views read: in the
//! expected depth the median's completions on statue-two-of-three scored 0.00202, not 0.00162)
//! and keeps the one with the lower mean cost, weighted by the pixels it scored; it needs the
//! photos and the photo-consistent hole depth.

use super::complete::Completer;
use super::report::StageClock;
use super::select::{self, DepthPlanes, HoleConfig, MaskedView, Selection};
use super::view::{EditedView, ViewReport};
use super::{complete_views, correct_depths, hull, Progress, RemoveOptions};
use crate::gpu::Gpu;
use crate::scene::{Camera, GaussianScene};
use anyhow::Result;

/// The rendered depth the removal reads (`--rendered-depth`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum RenderedDepth {
    /// Complete under both, keep the one the captured photos agree with better (needs the
    /// photos and the photo-consistent hole depth; the expected depth without them).
    #[default]
    Auto,
    /// The expected depth: the Gaussians' depths along the ray, weighted by their blending.
    Expected,
    /// The median depth: the depth of the Gaussian that takes the transmittance to one half.
    Median,
}

/// What the report says of the choice (`rendered_depth` in report.json).
#[derive(Clone, Debug, serde::Serialize)]
pub struct DepthChoice {
    /// `expected` or `median`.
    pub chosen: RenderedDepth,
    /// The completions' photo-consistency under each depth tried (None: not tried, or nothing
    /// two views saw).
    pub expected: Option<PhotoCost>,
    pub median: Option<PhotoCost>,
    /// Why `Auto` did not compare both, or why the median depth dropped out.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

/// The photo-consistency of a removal's completions: the mean over the views' hole pixels that
/// two other views saw of their color variance after the depth correction, and those pixels.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct PhotoCost {
    pub cost: f64,
    pub pixels: usize,
}

impl PhotoCost {
    /// Pooled from the views' reports after stage 3b; None where no view scored a pixel.
    pub fn of<'r>(reports: impl IntoIterator<Item = &'r ViewReport>) -> Option<PhotoCost> {
        let (mut sum, mut pixels) = (0.0, 0);
        for s in reports.into_iter().filter_map(|r| r.hole_depth_scale) {
            if s.pixels > 0 && s.cost_after.is_finite() {
                sum += s.cost_after * s.pixels as f64;
                pixels += s.pixels;
            }
        }
        (pixels > 0).then(|| PhotoCost { cost: sum / pixels as f64, pixels })
    }
}

/// The depth `Auto` keeps: the median only where both were scored and its cost is strictly the
/// lower.
pub fn choose(expected: Option<PhotoCost>, median: Option<PhotoCost>) -> RenderedDepth {
    match (expected, median) {
        (Some(e), Some(m)) if m.cost < e.cost => RenderedDepth::Median,
        _ => RenderedDepth::Expected,
    }
}

/// Stages 2 to 3b of `remove` for `selection` under the rendered depth `--rendered-depth` names,
/// or under both for `Auto` where the photos and the photo-consistent hole depth can judge them
/// (the masks of both then from one render of each view): the views of the one kept, and the
/// choice.
pub(super) fn stage_in_chosen_depth<'a>(
    inputs: &StageInputs<'a>,
    selection: &Selection,
    clock: &mut StageClock,
    progress: Progress,
) -> Result<(Staged<'a>, DepthChoice)> {
    let opts = inputs.opts;
    let photo_depth = opts.stages.complete && inputs.photo_depth_runs();
    let wanted = if opts.stages.complete { opts.rendered_depth } else { RenderedDepth::Expected };
    let both = wanted == RenderedDepth::Auto && photo_depth;
    let mut median_masks = None;
    run_in_chosen_depth(
        wanted,
        photo_depth,
        &mut |median_depth, progress| {
            let masked = match median_masks.take() {
                Some(masked) if median_depth => masked,
                _ => {
                    let (masked, median) = draw_masks(inputs, selection, median_depth, both, progress)?;
                    median_masks = median;
                    masked
                }
            };
            clock.lap("masks");
            stage_views(inputs, selection.clone(), masked, median_depth, clock, progress)
        },
        progress,
    )
}

/// Stages 2 to 3b (`run`, given whether to read the median depth) under the rendered depth
/// `wanted` names, or under both for `Auto` where `photo_depth` (the photos and the
/// photo-consistent hole depth) can judge them; the views of the one kept, and the choice.
fn run_in_chosen_depth<'a>(
    wanted: RenderedDepth,
    photo_depth: bool,
    run: &mut dyn FnMut(bool, Progress) -> Result<Staged<'a>>,
    progress: Progress,
) -> Result<(Staged<'a>, DepthChoice)> {
    let cost = |staged: &Staged| PhotoCost::of(staged.views.iter().map(|v| &v.report));
    let choice = |chosen, expected, median, note: Option<&str>| DepthChoice {
        chosen,
        expected,
        median,
        note: note.map(str::to_string),
    };
    match wanted {
        RenderedDepth::Expected | RenderedDepth::Median => {
            let staged = run(wanted == RenderedDepth::Median, progress)?;
            let c = cost(&staged);
            let (expected, median) = if wanted == RenderedDepth::Median { (None, c) } else { (c, None) };
            Ok((staged, choice(wanted, expected, median, None)))
        }
        RenderedDepth::Auto if !photo_depth => {
            let staged = run(false, progress)?;
            let note = "no photos or no photo-consistent hole depth to judge by: the expected depth";
            Ok((staged, choice(RenderedDepth::Expected, None, None, Some(note))))
        }
        RenderedDepth::Auto => {
            let by_expected = run(false, progress)?;
            let expected = cost(&by_expected);
            match run(true, progress) {
                Ok(by_median) => {
                    let median = cost(&by_median);
                    let chosen = choose(expected, median);
                    let staged = if chosen == RenderedDepth::Median { by_median } else { by_expected };
                    Ok((staged, choice(chosen, expected, median, None)))
                }
                // the expected depth's views stand; the median depth's failure is the report's
                Err(e) => {
                    let note = format!("the median depth failed, the expected depth kept: {e:#}");
                    Ok((by_expected, choice(RenderedDepth::Expected, expected, None, Some(&note))))
                }
            }
        }
    }
}

/// What stages 2 to 3b read: `remove`'s arguments.
pub(super) struct StageInputs<'a> {
    pub gpu: &'a Gpu,
    pub scene: &'a GaussianScene,
    pub labels: &'a [u8],
    pub cameras: &'a [Camera],
    pub photos: &'a [Vec<f32>],
    pub opts: &'a RemoveOptions,
    pub completer: &'a Completer,
}

impl StageInputs<'_> {
    /// Whether stage 3b runs after completion: it needs the photos and the completer's photo depth.
    fn photo_depth_runs(&self) -> bool {
        !self.photos.is_empty() && self.completer.photo_depth
    }
}

/// The edited views after stage 3b, the selection the hull grew and the Gaussians it took.
pub(super) struct Staged<'a> {
    pub views: Vec<EditedView<'a>>,
    pub selection: Selection,
    pub left_inside: usize,
}

/// Stage 2 for `selection`, its renders' depth the median one (`median_depth`) or the expected
/// one; with `both`, in the expected depth and (second) in the median one too, from one render.
fn draw_masks(
    inputs: &StageInputs,
    selection: &Selection,
    median_depth: bool,
    both: bool,
    progress: Progress,
) -> Result<(Vec<MaskedView>, Option<Vec<MaskedView>>)> {
    let StageInputs { gpu, scene, cameras, opts, .. } = *inputs;
    let depth = if both { DepthPlanes::Both } else { depth_planes(median_depth) };
    let cfg = HoleConfig { depth, ..hole_config(opts, median_depth) };
    let mut masked = select::hole_masks(gpu, scene, selection, cameras, &cfg, &mut |d, t| progress("masks", d, t))?;
    let median = both.then(|| masked.iter_mut().map(MaskedView::take_median_twin).collect());
    Ok((masked, median))
}

/// The depth plane the renders give: the median (`median_depth`) or the expected depth.
fn depth_planes(median_depth: bool) -> DepthPlanes {
    if median_depth {
        DepthPlanes::Median
    } else {
        DepthPlanes::Expected
    }
}

/// How stage 2 draws the holes, its renders' depth the median one (`median_depth`) or the
/// expected one.
fn hole_config(opts: &RemoveOptions, median_depth: bool) -> HoleConfig {
    HoleConfig {
        threshold: opts.hole_threshold,
        dilate: opts.dilate,
        keep_alpha: opts.keep_alpha,
        background: opts.background,
        depth: depth_planes(median_depth),
    }
}

/// Stages 1b to 3b on the views stage 2 `masked` for `selection`, every render's depth the
/// median one (`median_depth`) or the expected one: the Gaussians left inside the objects (which
/// go with them, `selection` grows), then (unless removal only) completion and the
/// photo-consistent hole depth.
fn stage_views<'a>(
    inputs: &StageInputs<'a>,
    mut selection: Selection,
    mut masked: Vec<MaskedView>,
    median_depth: bool,
    clock: &mut StageClock,
    progress: Progress,
) -> Result<Staged<'a>> {
    let StageInputs { gpu, scene, labels, cameras, photos, opts, completer } = *inputs;
    // `Auto` runs these stages twice: the second run's progress says which depth it reads
    let mut labelled = |stage: &str, done, total| match median_depth {
        true => progress(&format!("{stage} (median depth)"), done, total),
        false => progress(stage, done, total),
    };
    let progress: Progress = &mut labelled;
    let holes = hole_config(opts, median_depth);
    // 1b. the background Gaussians the tagging left inside the objects go too (and the holes are
    // drawn again without them)
    let left_inside = hull::remove_leftovers_inside(
        gpu,
        scene,
        labels,
        &opts.labels,
        cameras,
        &holes,
        &opts.hull,
        &mut selection,
        &mut masked,
        &mut |d, t| progress("hull", d, t),
    )?;
    clock.lap("hull");
    let mut views: Vec<EditedView> = masked
        .into_iter()
        .enumerate()
        .map(|(i, m)| EditedView::new(&cameras[i], photos.get(i).map(|p| p.as_slice()), m))
        .collect();
    if opts.stages.complete {
        // 3. completion, 3b. the hole depth the captured photos agree on
        complete_views(&mut views, completer, !photos.is_empty() && opts.stages.transfer, progress)?;
        clock.lap("complete");
        if inputs.photo_depth_runs() {
            correct_depths(&mut views, cameras, completer, progress);
            clock.lap("photo_depth");
        }
    }
    Ok(Staged { views, selection, left_inside })
}
