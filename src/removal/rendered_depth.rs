//! Which rendered depth the removal reads: the expected depth (the blend of every Gaussian's
//! depth along the ray) or the median depth (the depth of the Gaussian that takes the
//! transmittance to one half). Stage 3 anchors its depth prior to it, the photo-consistent hole
//! depth starts from it, and the color transfer checks its sources against it.
//!
//! Neither serves the built-in fill on every capture. Where a surface is a thin, noisy shell of
//! Gaussians (the statue's lawn) the expected depth scatters in front of it and the completed
//! depth lies in front of the lawn. On a glossy surface (the cup's desk) the training puts the
//! reflections behind it, and the expected depth follows them: 4-10 % behind the desk's plane on
//! the cup composites, where the median depth and the capture's sparse points lie on it. The photos
//! agree best at the reflections' depth, and there the color transfer lends the never-seen
//! footprint the desk beside it, which the built-in fill needs more than the true surface
//! (bench/JOURNAL.md, 2026-12-04). The captured photos tell the two apart: the
//! photo-consistency the hole depth's correction measures (`photo_depth::DepthScale`, the color
//! variance across the views that saw a completed point) is lower under the depth the photos
//! agree with. On the real-photo bench (bench/JOURNAL.md, 2026-12-02) it was lower under the
//! median depth on statue-two-of-three (0.0016 against 0.0020; held out 21.10 -> 22.20 dB) and
//! under the expected depth on the cups (0.0092 against 0.0173; the median depth cost them
//! 0.8-1.0 dB) and on statue-one (0.0016 against 0.0017, where the two score alike). Inpaintings
//! that agree across views want the true surface instead: the photos of the background as
//! `--inpainted`, without the transfer, scored 0.9-2.4 dB higher on statue-one and the cups
//! forced to the median depth.
//!
//! `Auto` runs stages 2 to 3b under both (the hull too judges in the depth the views read: in the
//! expected depth the median's completions on statue-two-of-three scored 0.00202, not 0.00162)
//! and keeps the one with the lower mean cost, weighted by the pixels it scored; it needs the
//! photos and the photo-consistent hole depth. Stages 3 and 3b run first on the views with the
//! largest holes (`judged_views`); where those decide (`decisive`), the other views are completed
//! under the chosen depth alone. Each view's completion depends on that view alone, so the
//! views kept are those a forced run of the chosen depth gives.

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
    /// The views the costs pool (`judged_views`; every view where the judged ones did not decide,
    /// or a depth was forced; none where no cost was measured).
    pub judged_views: usize,
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

/// The views `Auto` completes under both depths first: those with the most hole pixels, which
/// weigh the most in the pooled cost (`PhotoCost::of`). Where their costs part clearly
/// (`DECISIVE_RATIO`) the other views are completed under the chosen depth only: on the speed
/// bench's statue (25 views) that leaves out the losing depth's completion and photo depth of 17
/// views, on the cups (67 views) of 59.
pub const JUDGED_VIEWS: usize = 8;

/// The judged views decide when the lower cost is at most this share of the higher. On the
/// real-photo bench the eight views' costs stood at 0.84 of each other (statue-one, whose 25
/// views pool to 0.99), 0.47 (statue-two-of-three; 0.88 pooled), 0.79 and 0.46 (the cups; 0.70
/// and 0.65 pooled) and 0.71 on the speed bench's statue (0.76 pooled), each on the side of all
/// its views, but at 0.85 statue-one's eight would have chosen the median depth where its 25
/// choose the expected one (bench/JOURNAL.md, 2026-12-03, 08:33). Where they do not decide,
/// every view is completed under both and the choice is the one of all the views.
pub const DECISIVE_RATIO: f64 = 0.8;

/// Whether the costs of the judged views decide the choice (`DECISIVE_RATIO`).
pub fn decisive(expected: Option<PhotoCost>, median: Option<PhotoCost>) -> bool {
    match (expected, median) {
        (Some(e), Some(m)) => e.cost.min(m.cost) <= DECISIVE_RATIO * e.cost.max(m.cost),
        _ => false,
    }
}

/// The `JUDGED_VIEWS` views of `holes` (each view's hole pixels) with the most hole pixels, in
/// their order, and the other views.
pub fn judged_views(holes: &[usize]) -> (Vec<usize>, Vec<usize>) {
    let mut by_size: Vec<usize> = (0..holes.len()).collect();
    by_size.sort_by_key(|&i| (std::cmp::Reverse(holes[i]), i));
    let mut judged = vec![false; holes.len()];
    for &i in by_size.iter().take(JUDGED_VIEWS) {
        judged[i] = true;
    }
    (0..holes.len()).partition(|&i| judged[i])
}

/// Stages 2 to 3b of `remove` for `selection` under the rendered depth `--rendered-depth` names,
/// or under both for `Auto` where the photos and the photo-consistent hole depth can judge them
/// (the masks of both then from one render of each view; the judged views completed under both
/// first, `judged_views`): the views of the one kept, and the choice.
pub(super) fn stage_in_chosen_depth<'a>(
    inputs: &StageInputs<'a>,
    selection: &Selection,
    clock: &mut StageClock,
    progress: Progress,
) -> Result<(Staged<'a>, DepthChoice)> {
    let opts = inputs.opts;
    let photo_depth = opts.stages.complete && inputs.photo_depth_runs();
    let wanted = if opts.stages.complete { opts.rendered_depth } else { RenderedDepth::Expected };
    let all: Vec<usize> = (0..inputs.cameras.len()).collect();
    let cost = |staged: &Staged, at: &[usize]| PhotoCost::of(at.iter().map(|&i| &staged.views[i].report));
    let choice = |chosen, expected, median, judged, note: Option<&str>| DepthChoice {
        chosen,
        expected,
        median,
        judged_views: judged,
        note: note.map(str::to_string),
    };
    if wanted != RenderedDepth::Auto || !photo_depth {
        let median = wanted == RenderedDepth::Median;
        let (masked, _) = draw_masks(inputs, selection, median, false, progress)?;
        clock.lap("masks");
        let mut staged = hull_views(inputs, selection.clone(), masked, median, clock, progress)?;
        complete_views_at(inputs, &mut staged, &all, median, clock, progress)?;
        let c = cost(&staged, &all);
        let n = if c.is_some() { all.len() } else { 0 };
        return Ok(match wanted {
            RenderedDepth::Median => (staged, choice(wanted, None, c, n, None)),
            RenderedDepth::Expected => (staged, choice(wanted, c, None, n, None)),
            RenderedDepth::Auto => {
                let note = "no photos or no photo-consistent hole depth to judge by: the expected depth";
                (staged, choice(RenderedDepth::Expected, None, None, 0, Some(note)))
            }
        });
    }
    let (masked, median_masked) = draw_masks(inputs, selection, false, true, progress)?;
    clock.lap("masks");
    let mut by_expected = hull_views(inputs, selection.clone(), masked, false, clock, progress)?;
    let holes: Vec<usize> = by_expected.views.iter().map(|v| v.masked.hole.iter().filter(|&&h| h).count()).collect();
    let (judged, rest) = judged_views(&holes);
    complete_views_at(inputs, &mut by_expected, &judged, false, clock, progress)?;
    let median_masked = median_masked.expect("drawn in both depths");
    let by_median = hull_views(inputs, selection.clone(), median_masked, true, clock, progress).and_then(|mut s| {
        complete_views_at(inputs, &mut s, &judged, true, clock, progress)?;
        Ok(s)
    });
    let mut by_median = match by_median {
        Ok(s) => s,
        // the expected depth's views stand; the median depth's failure is the report's
        Err(e) => return median_failed(inputs, by_expected, &judged, &rest, e, clock, progress),
    };
    let (mut expected, mut median) = (cost(&by_expected, &judged), cost(&by_median, &judged));
    let mut judged_count = judged.len();
    if !rest.is_empty() && !decisive(expected, median) {
        complete_views_at(inputs, &mut by_expected, &rest, false, clock, progress)?;
        if let Err(e) = complete_views_at(inputs, &mut by_median, &rest, true, clock, progress) {
            return median_failed(inputs, by_expected, &all, &[], e, clock, progress);
        }
        (expected, median, judged_count) = (cost(&by_expected, &all), cost(&by_median, &all), all.len());
    }
    let chosen = choose(expected, median);
    let mut staged = if chosen == RenderedDepth::Median { by_median } else { by_expected };
    if judged_count < all.len() {
        complete_views_at(inputs, &mut staged, &rest, chosen == RenderedDepth::Median, clock, progress)?;
    }
    Ok((staged, choice(chosen, expected, median, judged_count, None)))
}

/// `Auto`'s expected depth kept after the median depth failed with `error`: its views `rest`
/// completed too (`judged` were), and the choice that says so.
fn median_failed<'a>(
    inputs: &StageInputs<'a>,
    mut by_expected: Staged<'a>,
    judged: &[usize],
    rest: &[usize],
    error: anyhow::Error,
    clock: &mut StageClock,
    progress: Progress,
) -> Result<(Staged<'a>, DepthChoice)> {
    complete_views_at(inputs, &mut by_expected, rest, false, clock, progress)?;
    let expected = PhotoCost::of(judged.iter().chain(rest).map(|&i| &by_expected.views[i].report));
    let note = format!("the median depth failed, the expected depth kept: {error:#}");
    let choice = DepthChoice {
        chosen: RenderedDepth::Expected,
        expected,
        median: None,
        judged_views: judged.len() + rest.len(),
        note: Some(note),
    };
    Ok((by_expected, choice))
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

/// Stage 1b on the views stage 2 `masked` for `selection`, every render's depth the median one
/// (`median_depth`) or the expected one: the Gaussians left inside the objects go with them
/// (`selection` grows) and the holes are drawn again without them. No view is completed yet
/// (`complete_views_at`).
fn hull_views<'a>(
    inputs: &StageInputs<'a>,
    mut selection: Selection,
    mut masked: Vec<MaskedView>,
    median_depth: bool,
    clock: &mut StageClock,
    progress: Progress,
) -> Result<Staged<'a>> {
    let StageInputs { gpu, scene, labels, cameras, photos, opts, .. } = *inputs;
    let mut labelled = in_depth(median_depth, progress);
    let progress: Progress = &mut labelled;
    let holes = hole_config(opts, median_depth);
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
    let views: Vec<EditedView> = masked
        .into_iter()
        .enumerate()
        .map(|(i, m)| EditedView::new(&cameras[i], photos.get(i).map(|p| p.as_slice()), m))
        .collect();
    Ok(Staged { views, selection, left_inside })
}

/// Stages 3 and 3b (unless removal only) on the views `at` of `staged`: completion and the
/// photo-consistent hole depth, in the depth the views' renders hold (`median_depth` says which,
/// for the progress). Each view's result depends on that view alone, whichever others run with it.
fn complete_views_at(
    inputs: &StageInputs,
    staged: &mut Staged,
    at: &[usize],
    median_depth: bool,
    clock: &mut StageClock,
    progress: Progress,
) -> Result<()> {
    let StageInputs { cameras, photos, opts, completer, .. } = *inputs;
    if !opts.stages.complete || at.is_empty() {
        return Ok(());
    }
    let mut labelled = in_depth(median_depth, progress);
    let progress: Progress = &mut labelled;
    // 3. completion, 3b. the hole depth the captured photos agree on
    let transfer_follows = !photos.is_empty() && opts.stages.transfer;
    complete_views(&mut staged.views, at, completer, transfer_follows, progress)?;
    clock.lap("complete");
    if inputs.photo_depth_runs() {
        correct_depths(&mut staged.views, at, cameras, completer, progress);
        clock.lap("photo_depth");
    }
    Ok(())
}

/// `progress` that says which depth a stage reads: `Auto` runs stages 1b to 3b under both.
fn in_depth(median_depth: bool, progress: Progress<'_>) -> impl FnMut(&str, usize, usize) + '_ {
    move |stage: &str, done, total| match median_depth {
        true => progress(&format!("{stage} (median depth)"), done, total),
        false => progress(stage, done, total),
    }
}
