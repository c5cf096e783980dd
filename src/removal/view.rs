//! One edited view as the removal's stages fill it in: stage 2 gives its renders and hole, stage 3
//! its completion, 3c the pixels that took a photo's color, 4b its consensus verdict. Each stage
//! reads and writes these fields (and the view's line of the report) instead of a vector of its
//! own per stage.

use super::complete::leftover_colors::{disagreeing_transfers, unlike_invention};
use super::complete::photo_depth::DepthScale;
use super::complete::rectify::Intrinsics;
use super::complete::source_views::SourceView;
use super::complete::{depth::PriorSpace, Completed, ViewInputs};
use super::consensus::ViewConsensus;
use super::select::MaskedView;
use crate::scene::exposure::ColorAffine;
use crate::scene::Camera;

pub struct EditedView<'a> {
    pub camera: &'a Camera,
    /// The captured photo (planar RGB); None when the caller gave no photos (no color transfer,
    /// no photo-consistent depth).
    pub photo: Option<&'a [f32]>,
    /// Stage 2: renders before and after deletion, the hole, the part to synthesize.
    pub masked: MaskedView,
    /// Stage 3: the inpainted image and completed depth (None: removal only).
    pub completed: Option<Completed>,
    /// Stage 3c: the hole pixels that took a photo's color, or the leftovers' render where no
    /// photo lent one (`take_leftover_colors`); None: no transfer ran.
    pub transferred: Option<Vec<bool>>,
    /// The photo's colors as an affine map of the original render's (identity without a photo).
    pub photo_colors: ColorAffine,
    pub report: ViewReport,
}

/// What the report says of one edited view (`views` in report.json; empty without completion).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct ViewReport {
    pub view: String,
    pub hole_pixels: usize,
    /// Pixels synthesized, the covered ones that look through a gap included.
    pub fill_pixels: usize,
    /// The depth prior's affine fit: its space, scale, shift, pixels and residual.
    pub depth_space: Option<PriorSpace>,
    pub scale: f64,
    pub shift: f64,
    pub fit_pixels: usize,
    pub fit_rms: f64,
    /// Covered hole pixels that look through a gap past the surrounding surfaces.
    pub see_through_pixels: usize,
    /// Fill pixels that took the farther plane the Gaussians left after removal cover them with.
    pub farther_covered_pixels: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hole_depth_scale: Option<DepthScale>,
    /// Fill pixels no photo lent a color that took the render of the Gaussians left behind the
    /// objects (`EditedView::take_leftover_colors`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub leftover_color_pixels: Option<usize>,
    /// Transferred colors refused for disagreeing with the render of the Gaussians left behind
    /// the objects, which they took instead (`complete::leftover_colors`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refused_transfer_pixels: Option<usize>,
    /// Fill pixels no photo lent a color that kept the invention because the render of the
    /// Gaussians left behind the objects departs from it (`complete::leftover_colors`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub invention_kept_pixels: Option<usize>,
    /// Fill pixels that took the depth of the Gaussians left behind the objects
    /// (`complete::leftover_depth`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub leftover_depth_pixels: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub transferred_pixels: Option<usize>,
    /// Fill pixels left to the Gaussians behind the removed objects (`MaskedView::patch_pixels`).
    pub fill_pixels_without_patch: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub consensus: Option<ViewConsensus>,
}

impl<'a> EditedView<'a> {
    pub fn new(camera: &'a Camera, photo: Option<&'a [f32]>, masked: MaskedView) -> EditedView<'a> {
        let report = ViewReport { view: camera.name.clone(), ..Default::default() };
        let photo_colors = photo.map_or(ColorAffine::IDENTITY, |photo| fit_photo_colors(&masked, photo));
        EditedView { camera, photo, masked, completed: None, transferred: None, photo_colors, report }
    }

    /// What completion reads of this view after stage 2.
    pub fn completion_inputs(&self) -> ViewInputs<'_> {
        let (m, camera) = (&self.masked, self.camera);
        ViewInputs {
            width: camera.width as usize,
            height: camera.height as usize,
            intrinsics: Intrinsics::from(camera),
            rgb: &m.after_removal.rgb,
            alpha: &m.after_removal.alpha,
            expected_depth: &m.after_removal.depth,
            front_depth: Some(&m.before.depth),
            fill: &m.fill,
            hole: &m.hole,
        }
    }

    /// Stage 3's result, which every later stage reads.
    pub fn completion(&self) -> &Completed {
        self.completed.as_ref().expect("the stages after completion run only after it")
    }

    /// Takes stage 3's result: the fill grows by the pixels that look through a gap, and the
    /// report records the depth prior's fit.
    pub fn set_completed(&mut self, completed: Completed) {
        let m = &mut self.masked;
        let count = |v: &[bool]| v.iter().filter(|&&x| x).count();
        self.report.see_through_pixels = count(&completed.fill) - count(&m.fill);
        self.report.farther_covered_pixels = completed.farther_covered;
        m.fill.clone_from(&completed.fill);
        self.report.hole_pixels = count(&m.hole);
        self.report.fill_pixels = count(&m.fill);
        self.report.depth_space = completed.space;
        self.report.scale = completed.scale;
        self.report.shift = completed.shift;
        self.report.fit_pixels = completed.fit_pixels;
        self.report.fit_rms = completed.residual;
        self.completed = Some(completed);
    }

    /// This view as a source of captured colors for the others (needs its photo): its photo, read
    /// off the objects' footprint where the original render (with the objects) is opaque at the
    /// right depth.
    pub fn source(&self) -> Option<SourceView<'_>> {
        let m = &self.masked;
        Some(SourceView {
            camera: self.camera,
            photo: self.photo?,
            hole: &m.footprint,
            depth: &m.before.depth,
            alpha: &m.before.alpha,
            photo_colors: self.photo_colors,
        })
    }

    /// After the color transfer: the fill pixels no photo lent a color, where the Gaussians left
    /// behind the objects cover them (`MaskedView::leftovers_cover`) and their render looks like the
    /// invention on average (`leftover_colors::unlike_invention`), take that render (in the
    /// photo's colors, as the transferred ones are) instead of the inpainter's invention, and
    /// count as not invented. The leftovers were trained by every view that saw around the
    /// object, so they are one invention for all views, where each view's inpainter makes its
    /// own: on the cup composite the exemplar filled the desk under the box with a dark blob that
    /// no two views agreed on (held-out masked PSNR 25.22 -> 25.81 dB, LPIPS 0.183 -> 0.187;
    /// the synth rooms -0.06 to +0.01 dB). So do the covered pixels whose transferred colors
    /// disagree with the leftovers' render on average (`leftover_colors`). Returns the pixels
    /// taken where no photo lent a color, those whose transferred color was refused, and those
    /// that kept the invention because the leftovers' render departs from it.
    pub fn take_leftover_colors(&mut self) -> LeftoverColors {
        let (Some(completed), Some(transferred)) = (self.completed.as_mut(), self.transferred.as_mut()) else {
            return LeftoverColors::default();
        };
        let leftovers = &self.masked.after_removal;
        let n = leftovers.alpha.len();
        let covered = |p: usize| self.masked.fill[p] && self.masked.leftovers_cover(p);
        let mut in_photo_colors = vec![0f32; 3 * n];
        for p in (0..n).filter(|&p| covered(p)) {
            let rgb = self.photo_colors.apply_pixel([0, 1, 2].map(|c| leftovers.rgb[c * n + p] as f64));
            for c in 0..3 {
                in_photo_colors[c * n + p] = (rgb[c] as f32).clamp(0.0, 1.0);
            }
        }
        let w = self.camera.width as usize;
        let with = |transfer: bool| -> Vec<bool> { (0..n).map(|p| covered(p) && transferred[p] == transfer).collect() };
        let disagreeing = disagreeing_transfers(&completed.rgb, &in_photo_colors, &with(true), w, n / w);
        let unlike = unlike_invention(&completed.rgb, &in_photo_colors, &with(false), w, n / w);
        let mut counts = LeftoverColors::default();
        for p in (0..n).filter(|&p| covered(p)) {
            if transferred[p] && !disagreeing[p] {
                continue;
            }
            if !transferred[p] && unlike[p] {
                counts.invention_kept += 1;
                continue;
            }
            for c in 0..3 {
                completed.rgb[c * n + p] = in_photo_colors[c * n + p];
            }
            if transferred[p] {
                counts.refused += 1;
            } else {
                transferred[p] = true;
                counts.taken += 1;
            }
        }
        counts
    }

    /// The fill pixels no photo's color reached: what the inpainter invented.
    pub fn invented(&self) -> Vec<bool> {
        let fill = &self.masked.fill;
        match &self.transferred {
            Some(t) => fill.iter().zip(t).map(|(&f, &t)| f && !t).collect(),
            None => fill.clone(),
        }
    }
}

/// The affine map from the original render's colors to the photo's (`ColorAffine::fit`, a 3x3
/// matrix and bias), over the pixels off the hole where the render is opaque: a phone changes
/// exposure and white balance from shot to shot, and the scene holds their consensus. On the
/// cup capture the full matrix beat a per-channel gain and bias by 0.3 dB masked PSNR.
fn fit_photo_colors(m: &MaskedView, photo: &[f32]) -> ColorAffine {
    let known: Vec<bool> = m.hole.iter().zip(&m.before.alpha).map(|(&hole, &a)| !hole && a > 0.99).collect();
    ColorAffine::fit(&m.before.rgb, photo, Some(&known))
}

/// What `EditedView::take_leftover_colors` did, in fill pixels the leftovers cover.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LeftoverColors {
    /// No photo lent a color; the leftovers' render replaced the invention.
    pub taken: usize,
    /// The transferred color disagreed with the leftovers' render, which replaced it.
    pub refused: usize,
    /// No photo lent a color; the leftovers' render departs from the invention, which stays.
    pub invention_kept: usize,
}
