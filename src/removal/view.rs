//! One edited view as the removal's stages fill it in: stage 2 gives its renders and hole, stage 3
//! its completion, 3c the pixels that took a photo's color, 4b its consensus verdict. Each stage
//! reads and writes these fields (and the view's line of the report) instead of a vector of its
//! own per stage.

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
    /// Stage 3c: the hole pixels that took a photo's color; None: no transfer ran.
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
            name: &camera.name,
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
