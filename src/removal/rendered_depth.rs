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

use super::view::ViewReport;
use super::{Progress, Staged};
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

impl RenderedDepth {
    /// Whether stage 2 must render the median depth too.
    pub fn needs_median(self) -> bool {
        self != RenderedDepth::Expected
    }
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

/// Stages 2 to 3b (`run`, given whether to read the median depth) under the rendered depth
/// `wanted` names, or under both for `Auto` where `photo_depth` (the photos and the
/// photo-consistent hole depth) can judge them; the views of the one kept, and the choice.
pub(super) fn stage_in_chosen_depth<'a>(
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
