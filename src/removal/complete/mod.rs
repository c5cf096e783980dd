//! Stage 3 of removal, depth-guided completion of one view: RGB inpainting of the hole, then depth
//! in two stages (scale anchoring of a monocular prior, then detail refinement in the hole). The
//! completed depth guides the color in turn: the built-in inpainter fills each background plane
//! from that plane's pixels only.
//!
//! - `inpaint`: the built-in inpainters (exemplar texture synthesis, harmonic fill), a
//!   LaMa-contract ONNX model, or the user's own inpainted views.
//! - `exemplar`: PatchMatch exemplar inpainting on the GPU, guided by the surfaces.
//! - `edge_tone`: the exemplar's inventions shifted to the tone of the colors around them.
//! - `invention_contrast`: their texture's contrast lowered where it is random, their level
//!   taken up from the known colors beside them.
//! - `depth`: least-squares scale/shift anchoring, the built-in and Depth Anything priors, the
//!   farther plane where the Gaussians left after removal show it, the edge-aware model-free
//!   refinement.
//! - `diffusion`: the masked DDIM loop of a depth-inpainting denoiser (ONNX).
//! - `harmonic`: the harmonic fill (smooth interpolation into a hole) of colors and depth.
//! - `surfaces`: the background planes around a hole, for the depth prior and for keeping each
//!   surface's colors on it.
//! - `rectify`: a plane's pixels on a regular grid in the plane, where the exemplar copies
//!   texture with its period under perspective.
//! - `regions`: a surface's regions of different color continued straight through the hole
//!   before the exemplar copies texture into each.
//! - `leftover_depth`: the depth of the Gaussians left behind the objects, where the photos
//!   agree on it better than on the completed one.
//! - `photo_depth`: the hole depth's scale that makes the other views agree on its colors.
//! - `transfer`: colors of the completed surface from the other views that saw it.
//! - `source_views`: the edited views as the other views see them, for both of those.

pub mod depth;
pub mod diffusion;
pub mod edge_tone;
pub mod invention_contrast;
pub mod exemplar;
pub mod harmonic;
pub mod inpaint;
pub mod leftover_depth;
pub mod photo_depth;
pub mod rectify;
pub mod regions;
pub mod source_views;
pub mod surfaces;
pub mod transfer;

use crate::gpu::Gpu;
use crate::image_ops::interleave_rgb;
use crate::parallel::for_each_item;
use crate::planes::Plane;
use crate::scene::Camera;
use anyhow::{Context, Result};
use depth::{DepthContract, DepthPrior, DepthView, PriorSpace};
use diffusion::OnnxDenoiser;
pub use inpaint::BuiltInInpainter;
use inpaint::Inpainter;
use leftover_depth::prefer_leftover_depth;
use photo_depth::{correct_hole_depth, DepthScale};
use rectify::Intrinsics;
use source_views::SourceView;
use std::path::PathBuf;
use transfer::{borrow_inventions, transfer, Invention, Transfer};

/// How far (relative) a view's original depth may be from a point's for that view to count as
/// having seen it when the hole's depth is corrected by photo-consistency.
const PHOTO_DEPTH_TOLERANCE: f64 = 0.05;

/// The same for a view to lend its color to a hole pixel. Looser: the original render's depth is
/// an alpha-weighted mean, which beside a kept object's rim or on a floor rendered by wide
/// Gaussians sits in front of the surface the photo shows. On two-of-three, 27 % of the hole
/// pixels other views saw found no source at 5 %; two thirds of those had a view that failed only
/// this test, half of them by less than 8 %. At 10 % its seen-elsewhere PSNR rose 0.8 dB
/// (commit `4e35174`).
const TRANSFER_TOLERANCE: f64 = 0.10;

/// Completion settings: the one home of their defaults, also `cogeo remove`'s flags. The models
/// they name are loaded by `Completer::load`.
#[derive(Clone, Debug, clap::Args)]
pub struct CompletionConfig {
    /// The built-in inpainter: exemplar (texture copied patch by patch from around the hole, each
    /// background surface from itself; PatchMatch on the GPU) or harmonic (a smooth membrane fill,
    /// the ablation). Ignored with --inpaint-model or --inpainted.
    #[arg(long, value_enum, default_value_t)]
    pub inpainter: BuiltInInpainter,
    /// ONNX inpainting model with the LaMa contract (image [1,3,512,512] in [0,1] and mask
    /// [1,1,512,512], 1 = hole, in; RGB out), instead of the built-in inpainter.
    #[arg(long, conflicts_with = "inpainted")]
    pub inpaint_model: Option<PathBuf>,
    /// Bring your own inpainting: a folder of inpainted training views named like the images (the
    /// output of LaMa, Stable Diffusion, an image editor, ...), used as the RGB completion of those
    /// views exactly inside the holes; depth, color transfer, fusion and refinement run unchanged.
    /// Inpaint at least the removed objects' masks, dilated a few pixels (a previous run's `mask/`
    /// shows the region cogeo fills). Views of another size are resized. They are in their photos'
    /// colors; with `--exposure` they are taken into the scene's colors as the photos are.
    #[arg(long)]
    pub inpainted: Option<PathBuf>,
    /// ONNX monocular depth model (see --depth-contract). Default: the built-in prior (harmonic
    /// completion of the rendered inverse depth from the hole boundary).
    #[arg(long)]
    pub depth_model: Option<PathBuf>,
    /// Contract of --depth-model: depth-anything-v2 (ImageNet-normalized RGB, sides multiples of 14,
    /// affine-invariant disparity out) or depth-anything3 (504x504 in, depth out).
    #[arg(long, value_enum, default_value_t)]
    pub depth_contract: DepthContract,
    /// ONNX depth-inpainting denoiser run as a masked DDIM loop (inputs sample, timestep, alpha_bar,
    /// image, mask; output the predicted noise). Default: built-in edge-aware refinement.
    #[arg(long)]
    pub depth_refiner: Option<PathBuf>,
    /// Sweeps of the built-in edge-aware depth refinement (0 = keep the anchored depth).
    #[arg(long, default_value_t = 60)]
    pub depth_sweeps: usize,
    /// DDIM steps of --depth-refiner.
    #[arg(long, default_value_t = 20)]
    pub diffusion_steps: usize,
    /// Ablation: no depth prior; new Gaussians are placed at the depth rendered after removal, and
    /// the built-in inpainter fills without the background planes.
    #[arg(id = "no-depth-guidance", long = "no-depth-guidance", action = clap::ArgAction::SetFalse)]
    pub depth_guidance: bool,
    /// Keep each hole's completed depth as it is (ablation). By default, before the color
    /// transfer and the fusion, it is corrected by photo-consistency: where two or more other
    /// views saw the hole's surface, the depth at which their photos agree on its color (one
    /// factor per hole, then per pixel within 3 % of it). Runs with --no-transfer too.
    #[arg(id = "no-photo-depth", long = "no-photo-depth", action = clap::ArgAction::SetFalse)]
    pub photo_depth: bool,
    /// One invention per surface point: complete the views one after another, the one with the
    /// most to invent first, each taking the colors an earlier view invented for the same
    /// surface point (at its completed depth) and inventing only what none did, so that fusion
    /// and refinement do not average several inventions. Off by default: a borrowed color lands
    /// where the lender's completed depth puts it, so one view's depth error reaches the others
    /// (on the real-photo bench masked PSNR moved by -0.44 to +0.27 dB and LPIPS by -0.015 to
    /// +0.060; the synth rooms lost 0.7-8.9 dB). Needs the color transfer.
    #[arg(long)]
    pub share_inventions: bool,
    /// Contrast kept of the grain of the exemplar's texture (what each pixel adds to its 3 x 3
    /// mean) where no photo saw the background and the surface's texture does not repeat (0-1).
    /// 1 keeps it sharp; lower trades sharpness for error against the unseen truth, since grass
    /// copied from elsewhere falls where the real grass does not (invention_contrast.rs).
    #[arg(long, default_value_t = 0.85, value_parser = invention_contrast::parse_contrast)]
    pub invention_contrast: f32,
    /// Contrast kept of the structure of those inventions (0-1): what their 3 x 3 means add to
    /// their surface's mean within 12 px, the clumps of the copied patches. 0 leaves the local
    /// mean and the grain; 1 with `--invention-contrast 1` keeps the copy as it is.
    #[arg(long, default_value_t = 0.0, value_parser = invention_contrast::parse_contrast)]
    pub invention_structure: f32,
    /// Feathering radius (pixels) of the soft mask that blends aligned prior and rendered depth.
    #[arg(long, default_value_t = 4.0)]
    pub soft_radius: f32,
}

crate::default_from_flags!(CompletionConfig);

/// The models and settings of completion.
pub struct Completer {
    pub inpainter: Inpainter,
    pub prior: DepthPrior,
    pub refiner: Option<OnnxDenoiser>,
    /// Feathering radius of M_soft in pixels.
    pub soft_radius: f32,
    /// Sweeps of the model-free edge-aware refinement.
    pub refine_sweeps: usize,
    /// DDIM steps of the learned refiner.
    pub diffusion_steps: usize,
    /// Use the depth prior at all (`false`: the ablation without depth guidance, which takes the
    /// depth rendered after removal as it is).
    pub depth_guidance: bool,
    /// Correct each hole's depth by photo-consistency across the views before the color
    /// transfer and the fusion (`photo_depth`; `false`: the ablation).
    pub photo_depth: bool,
    /// Views take the colors earlier views invented for the same surface point (`transfer_colors`;
    /// `false`, the default: each view invents its own).
    pub share_inventions: bool,
    /// Contrast kept of the exemplar's random inventions, by scale (`invention_contrast`).
    pub invention_contrast: invention_contrast::Contrast,
    /// The transfer's texture fills (`texture_view`) of independent views (no shared
    /// inventions, a built-in inpainter) run on all cores, so that one view's host work (the
    /// rectification, the inventions' contrast) overlaps another's dispatches: on a lent H200
    /// this half of the stage, one view after another, was half of a removal's time; on lavapipe
    /// (2 cores) the speed scene's stage went 10.1 / 11.7 -> 7.8 / 9.2 s in two pairs
    /// (bench/JOURNAL.md, 2026-12-03; slower there when the fill had less host work). Same
    /// result; `false` runs them one after another (tests compare the two).
    pub views_in_parallel: bool,
    pub seed: u64,
}

/// The inputs of one view.
pub struct ViewInputs<'a> {
    /// The view's name (its camera's), for errors.
    pub name: &'a str,
    pub width: usize,
    pub height: usize,
    /// The view's camera intrinsics (for the planes in 3D).
    pub intrinsics: Intrinsics,
    /// Render of the scene after removal (planar RGB).
    pub rgb: &'a [f32],
    pub alpha: &'a [f32],
    pub expected_depth: &'a [f32],
    /// Expected depth of the render before removal, if known: the completed surfaces lie behind
    /// the removed objects.
    pub front_depth: Option<&'a [f32]>,
    /// Pixels to synthesize.
    pub fill: &'a [bool],
    /// The dilated hole (excluded from the depth fit).
    pub hole: &'a [bool],
}

/// What completion produced for one view.
pub struct Completed {
    /// The pixels synthesized: the view's fill, plus the covered hole pixels that looked through
    /// a gap to the far background (`depth::see_through`).
    pub fill: Vec<bool>,
    pub rgb: Vec<f32>,
    pub depth: Vec<f32>,
    /// Per pixel, 1 + the index of the background plane its completed depth lies on, or 0
    /// (surfaces.rs); all 0 without depth guidance.
    pub surfaces: Vec<u8>,
    /// Those planes.
    pub planes: Vec<Plane>,
    pub scale: f64,
    pub shift: f64,
    pub space: Option<PriorSpace>,
    pub fit_pixels: usize,
    pub residual: f64,
    /// The exemplar's texture is still owed: `rgb` holds the harmonic fill of the hole, and the
    /// color transfer synthesizes the texture of whatever it does not find in the photos.
    pub texture_pending: bool,
    /// Fill pixels that took a farther plane where the Gaussians left after removal cover them
    /// there (`depth::defer_to_covering`).
    pub farther_covered: usize,
}

impl Completed {
    /// A completion with no depth guidance behind it: no planes, the prior's fit the identity.
    pub fn unguided(fill: Vec<bool>, rgb: Vec<f32>, depth: Vec<f32>) -> Completed {
        let n = fill.len();
        Completed {
            fill,
            rgb,
            depth,
            surfaces: vec![0; n],
            planes: Vec::new(),
            scale: 1.0,
            shift: 0.0,
            space: None,
            fit_pixels: 0,
            residual: 0.0,
            texture_pending: false,
            farther_covered: 0,
        }
    }
}

impl Completer {
    /// Loads the models `cfg` names (before any GPU work, so a bad path fails at once).
    /// `views` names the edited views and gives their sizes, for `--inpainted`.
    pub fn load(gpu: &Gpu, cfg: &CompletionConfig, seed: u64, views: &[(String, (u32, u32))]) -> Result<Completer> {
        let inpainter = match (&cfg.inpaint_model, &cfg.inpainted) {
            (Some(p), _) => Inpainter::onnx(p)?,
            (None, Some(dir)) => {
                let names: Vec<String> = views.iter().map(|v| v.0.clone()).collect();
                let sizes: Vec<(u32, u32)> = views.iter().map(|v| v.1).collect();
                Inpainter::provided(dir, &names, &sizes)?
            }
            (None, None) => match cfg.inpainter {
                BuiltInInpainter::Exemplar => Inpainter::Exemplar(Box::new(exemplar::ExemplarFill::new(gpu, seed)?)),
                BuiltInInpainter::Harmonic => Inpainter::Harmonic,
            },
        };
        Ok(Completer {
            inpainter,
            prior: match &cfg.depth_model {
                Some(p) => DepthPrior::onnx(p, cfg.depth_contract)?,
                None => DepthPrior::BuiltIn,
            },
            refiner: cfg.depth_refiner.as_deref().map(OnnxDenoiser::load).transpose()?,
            soft_radius: cfg.soft_radius,
            refine_sweeps: cfg.depth_sweeps,
            diffusion_steps: cfg.diffusion_steps,
            depth_guidance: cfg.depth_guidance,
            photo_depth: cfg.photo_depth,
            share_inventions: cfg.share_inventions,
            invention_contrast: invention_contrast::Contrast {
                grain: cfg.invention_contrast,
                structure: cfg.invention_structure,
            },
            views_in_parallel: true,
            seed,
        })
    }

    /// Stage 3: completes every edited view (view i gets index i, which seeds its diffusion noise).
    /// With `transfer_follows` (the color transfer runs next) the built-in exemplar leaves its
    /// texture to the transfer's own fill of what the photos do not give: a first fill of the whole
    /// hole would be overwritten there, pixel for pixel (`Completed::texture_pending`).
    ///
    /// Views are independent. Where completing one is host work only (the built-in depth
    /// prior, no learned refiner, no inpainting before the surfaces are known, and no exemplar
    /// pass: the harmonic inpainter, or the exemplar leaving its texture to the transfer) they run
    /// on all cores; otherwise one after another (the models take one call at a time; the
    /// transfer's `views_in_parallel` runs GPU fills at once). Either way view i's result
    /// depends only on view i.
    pub fn complete_views(
        &self,
        views: &[ViewInputs],
        transfer_follows: bool,
        progress: &mut dyn FnMut(usize, usize),
    ) -> Result<Vec<Completed>> {
        let views: Vec<(usize, &ViewInputs)> = views.iter().enumerate().collect();
        self.complete_views_at(&views, transfer_follows, progress)
    }

    /// `complete_views` of some of the views, each with its index among all the views (so its
    /// result is the one it gets among them), as `correct_depths` takes them.
    pub fn complete_views_at(
        &self,
        views: &[(usize, &ViewInputs)],
        transfer_follows: bool,
        progress: &mut dyn FnMut(usize, usize),
    ) -> Result<Vec<Completed>> {
        let complete = |k: usize| {
            let (index, v) = views[k];
            self.complete_view(v, index, transfer_follows).with_context(|| format!("completing view {}", v.name))
        };
        if !self.host_only(transfer_follows) {
            let mut out = Vec::with_capacity(views.len());
            for i in 0..views.len() {
                out.push(complete(i)?);
                progress(i + 1, views.len());
            }
            return Ok(out);
        }
        let mut out: Vec<Option<Result<Completed>>> = (0..views.len()).map(|_| None).collect();
        for_each_item(&mut out, progress, |i, c| *c = Some(complete(i)));
        out.into_iter().map(|c| c.expect("every view ran")).collect()
    }

    /// Whether `complete_view` runs on the host alone (see `complete_views`).
    fn host_only(&self, texture_later: bool) -> bool {
        self.depth_guidance
            && matches!(self.prior, DepthPrior::BuiltIn)
            && self.refiner.is_none()
            && match self.inpainter {
                Inpainter::Harmonic => true,
                Inpainter::Exemplar(_) => texture_later,
                Inpainter::Onnx(_) | Inpainter::Provided { .. } => false,
            }
    }

    /// Stage 3b, photo-consistent hole depth: per view, first the fill pixels where the
    /// `leftovers` (`MaskedView::leftover_depth`: the render after removal's depth where the
    /// Gaussians left behind the objects cover the pixel, 0 elsewhere) make
    /// the other views' photos agree better take that depth (`leftover_depth`), then the depth of
    /// the whole `hole` is corrected so that the other views' photos (`sources`, one per view)
    /// agree on its colors (`photo_depth`). It runs before the color transfer and the fusion, and
    /// without the transfer too, since both place points by this depth. Views are independent
    /// (the sources hold the original renders), so they run on all cores; `completed` holds some
    /// of the views, each with its index (`cameras`, `sources`, `holes` and `leftovers` hold
    /// every view). Returns per completed view the factor found and the pixels that took the
    /// leftover depth. The pipeline calls it when `photo_depth` is set.
    pub fn correct_depths(
        &self,
        cameras: &[Camera],
        sources: &[SourceView],
        holes: &[&[bool]],
        leftovers: &[Vec<f32>],
        completed: &mut [(usize, Completed)],
        progress: &mut dyn FnMut(usize, usize),
    ) -> Vec<(DepthScale, usize)> {
        let mut views: Vec<(usize, &mut Completed, (DepthScale, usize))> =
            completed.iter_mut().map(|(i, c)| (*i, c, (DepthScale::unchanged(), 0))).collect();
        let photos: Vec<Vec<[f32; 3]>> = sources.iter().map(|s| interleave_rgb(s.photo, s.photo.len() / 3)).collect();
        for_each_item(&mut views, progress, |_, (i, c, (scale, taken))| {
            let i = *i;
            *taken = prefer_leftover_depth(i, &cameras[i], c, &leftovers[i], sources, &photos, PHOTO_DEPTH_TOLERANCE);
            let (depth, hole) = (&mut c.depth, holes[i]);
            *scale = correct_hole_depth(i, &cameras[i], depth, hole, sources, &photos, PHOTO_DEPTH_TOLERANCE);
        });
        views.into_iter().map(|(_, _, found)| found).collect()
    }

    /// Stage 3c, depth-guided color transfer over the whole `hole` of every view (covered pixels
    /// render background that few views constrained): pixels whose completed surface point another
    /// view saw take that view's captured color (`sources`, one per view); with
    /// `share_inventions`, fill pixels whose surface point an earlier view invented take that
    /// invention (`transfer::borrow_inventions`); what is left of the completion's fill (its view's
    /// fill and see-through pixels) is inpainted again, now from those colors too. Returns, per
    /// view, the pixels transferred from photos.
    pub fn transfer_colors(
        &self,
        cameras: &[Camera],
        sources: &[SourceView],
        holes: &[&[bool]],
        completed: &mut [Completed],
        progress: &mut dyn FnMut(usize, usize),
    ) -> Result<Vec<Vec<bool>>> {
        let n = completed.len();
        // the captured colors each view finds are independent of the other views' finds: in
        // parallel, the first half of the stage's progress
        let mut found: Vec<Option<Transfer>> = (0..n).map(|_| None).collect();
        for_each_item(&mut found, &mut |d, _| progress(d, 2 * n), |i, t| {
            *t = Some(transfer(i, &cameras[i], &completed[i].depth, holes[i], sources, TRANSFER_TOLERANCE));
        });
        let found: Vec<Transfer> = found.into_iter().map(|t| t.expect("every view ran")).collect();
        let independent =
            !self.share_inventions && matches!(self.inpainter, Inpainter::Harmonic | Inpainter::Exemplar(_));
        if independent && self.views_in_parallel {
            // each view fills from its own image and found colors alone (`views_in_parallel`)
            let mut views: Vec<(&mut Completed, Option<Result<()>>)> =
                completed.iter_mut().map(|c| (c, None)).collect();
            for_each_item(&mut views, &mut |d, _| progress(n + d, 2 * n), |i, (c, done)| {
                *done = Some(self.texture_view(i, &cameras[i], &found[i], None, holes[i], c).map(|_| ()));
            });
            for (_, done) in views {
                done.expect("every view ran")?;
            }
        } else {
            // with shared inventions the view with the most left to invent goes first: it invents once
            // for the views after it (without them the views are independent)
            let mut order: Vec<usize> = (0..completed.len()).collect();
            if self.share_inventions {
                let left = |i: usize| completed[i].fill.iter().zip(&found[i].found).filter(|(&f, &t)| f && !t).count();
                order.sort_by_key(|&i| std::cmp::Reverse(left(i)));
            }
            let mut inventions: Vec<Invention> = Vec::new();
            for (done, i) in order.into_iter().enumerate() {
                progress(n + done + 1, 2 * n);
                let shared = self.share_inventions.then_some(&inventions[..]);
                let invented = self.texture_view(i, &cameras[i], &found[i], shared, holes[i], &mut completed[i])?;
                if self.share_inventions {
                    let c = &completed[i];
                    inventions.push(Invention {
                        camera: &cameras[i],
                        rgb: c.rgb.clone(),
                        depth: c.depth.clone(),
                        invented,
                    });
                }
            }
        }
        Ok(found.into_iter().map(|t| t.found).collect())
    }

    /// The second half of stage 3c for view `i`: its fill takes the colors `t` found in the photos
    /// and, with `inventions` (`share_inventions`), those earlier views invented for the same
    /// surface points; the rest of the fill is inpainted again from them. Returns the pixels the
    /// view itself invents.
    fn texture_view(
        &self,
        i: usize,
        camera: &Camera,
        t: &Transfer,
        inventions: Option<&[Invention]>,
        hole: &[bool],
        c: &mut Completed,
    ) -> Result<Vec<bool>> {
        let (w, h) = (camera.width as usize, camera.height as usize);
        let mut known = t.found.clone();
        let mut image = c.rgb.clone();
        let invented: Vec<bool> = (0..w * h).map(|p| c.fill[p] && !t.found[p]).collect();
        let shared = inventions.map(|inv| borrow_inventions(camera, &c.depth, &invented, inv, TRANSFER_TOLERANCE));
        for u in [Some(t), shared.as_ref()].into_iter().flatten() {
            for p in (0..w * h).filter(|&p| u.found[p]) {
                known[p] = true;
                for ch in 0..3 {
                    image[ch * w * h + p] = u.rgb[ch * w * h + p];
                }
            }
        }
        if known.iter().any(|&k| k) || c.texture_pending {
            let rest: Vec<bool> = (0..w * h).map(|p| c.fill[p] && !known[p]).collect();
            // captured and shared colors are sources now; the rest of the hole's render still is not
            let found_or_fill: Vec<bool> = (0..w * h).map(|p| c.fill[p] || known[p]).collect();
            let avoid = leftover(hole, &found_or_fill);
            let k = Intrinsics::from(camera);
            let disparity = depth::disparity(&c.depth);
            let guide = (&c.surfaces[..], &disparity[..], &c.planes[..], &k);
            let (rgb, repeats) = self.inpainter.inpaint_again(i, &image, &rest, &avoid, guide, w, h)?;
            c.rgb = rgb;
            // the exemplar's copied texture: it keeps the brightness of where it was copied from
            // (edge_tone.rs), a random texture's copy is not the truth's, and beside the known
            // colors the points are mostly ones a photo saw (invention_contrast.rs)
            if let Some(repeats) = repeats {
                let lends: Vec<bool> = (0..w * h).map(|p| !rest[p] && !avoid[p]).collect();
                edge_tone::match_edge_tone(&mut c.rgb, &rest, &lends, &c.surfaces, w, h);
                let (known, contrast) = ((&image[..], &lends[..]), self.invention_contrast);
                invention_contrast::temper(&mut c.rgb, &rest, known, &c.surfaces, &repeats, contrast, w, h);
            }
            c.texture_pending = false;
        }
        Ok(invented)
    }

    /// Completes one view, its texture included.
    pub fn complete(&self, v: &ViewInputs, index: usize) -> Result<Completed> {
        self.complete_view(v, index, false)
    }

    /// Completes one view; with `texture_later` the exemplar's texture is left to the color
    /// transfer (`complete_views`).
    fn complete_view(&self, v: &ViewInputs, index: usize, texture_later: bool) -> Result<Completed> {
        let (w, h) = (v.width, v.height);
        // The first fill serves the ablation without depth, a learned depth prior (which reads the
        // image) and the learned or provided inpaintings (kept as they are); the built-in ones
        // fill again below once the surfaces are known, and the built-in prior never reads it.
        let first_needed = !self.depth_guidance
            || matches!(self.prior, DepthPrior::Onnx(..))
            || matches!(self.inpainter, Inpainter::Onnx(_) | Inpainter::Provided { .. });
        let rgb = if first_needed { self.inpainter.inpaint_view(index, v.rgb, v.fill, w, h)? } else { v.rgb.to_vec() };
        // rendered depth is trusted where the remaining scene covers the pixel, outside the hole
        let valid: Vec<bool> = (0..w * h).map(|i| !v.hole[i] && !v.fill[i] && v.alpha[i] > 0.5).collect();
        if !self.depth_guidance {
            // ablation: the rendered depth where defined, else the mean background depth
            let covered: Vec<f32> =
                v.expected_depth.iter().zip(&valid).filter(|(_, &ok)| ok).map(|(&d, _)| d).collect();
            let mean = if covered.is_empty() { 1.0 } else { covered.iter().sum::<f32>() / covered.len() as f32 };
            let depth = (0..w * h).map(|i| if v.alpha[i] > 0.05 { v.expected_depth[i] } else { mean }).collect();
            return Ok(Completed::unguided(v.fill.to_vec(), rgb, depth));
        }
        let view = DepthView {
            width: w,
            height: h,
            image: &rgb,
            render_depth: v.expected_depth,
            valid: &valid,
            front_depth: v.front_depth,
        };
        let (prior, space) = self.prior.predict(&view)?;
        let mut anchored = depth::anchor(&view, &prior, space, v.fill, self.soft_radius)?;
        // covered hole pixels that look past the surfaces around the hole are synthesized too
        let through = depth::see_through(&view, &prior, &anchored, v.hole, v.fill, depth::SEE_THROUGH_RATIO);
        let fill: Vec<bool> = v.fill.iter().zip(&through).map(|(&f, &t)| f || t).collect();
        let mut inpainted_again = None;
        if through.iter().any(|&t| t) {
            anchored = depth::anchor(&view, &prior, space, &fill, self.soft_radius)?;
            if first_needed {
                inpainted_again = Some(self.inpainter.inpaint_view(index, v.rgb, &fill, w, h)?);
            }
        }
        let rgb = inpainted_again.unwrap_or(rgb);
        let covered: Vec<bool> = (0..w * h).map(|i| v.alpha[i] > 0.5 && !through[i]).collect();
        // depth guides color: the planes around the fill, and which of them each pixel lies on
        let disparity = depth::disparity(&anchored.depth);
        let around: Vec<bool> = (0..w * h).map(|i| !fill[i] && covered[i]).collect();
        let mut planes = surfaces::surfaces_around(&disparity, &around, &fill, w, h, depth::PLANE_SEED);
        if let Some(front) = v.front_depth {
            let in_front = depth::in_front_of_removed(v.expected_depth, front, &around, &fill, w, h);
            planes.stop_in_front(&disparity, &in_front, &fill, w);
        }
        let mut labels = planes.fill_labels(&anchored.depth, &fill, v.front_depth, w);
        // but not in front of what the Gaussians left after removal show on a farther plane
        let farther_covered =
            depth::defer_to_covering(&planes, v.expected_depth, v.alpha, &fill, &mut labels, &mut anchored.depth, w);
        let disparity = if farther_covered > 0 { depth::disparity(&anchored.depth) } else { disparity };
        // the built-in inpainter fills again, surface by surface; a learned or provided
        // inpainting is kept, since it sees more than a surface label. The exemplar's texture
        // waits for the transfer when one follows: until then the depth's edge-aware refinement,
        // which moves only pixels on no continued plane, sees the harmonic fill of the whole hole
        // (what the surface-wise fill gives those pixels; its per-surface passes over the window
        // cost more than the exemplar at 504x378), without the edges of an invented texture.
        let texture_pending = texture_later && matches!(self.inpainter, Inpainter::Exemplar(_));
        let rgb = match &self.inpainter {
            Inpainter::Harmonic => {
                surfaces::fill_by_surface(v.rgb, &fill, &labels, w, h, 3, surfaces::Boundary::TypicalColors)
            }
            Inpainter::Exemplar(_) if texture_pending => {
                let known: Vec<bool> = fill.iter().map(|&f| !f).collect();
                harmonic::harmonic_fill(v.rgb, &known, w, h, 3)
            }
            Inpainter::Exemplar(e) => {
                let avoid = leftover(v.hole, &fill);
                e.fill_rectified(v.rgb, &fill, &avoid, &labels, Some(&disparity), &planes.planes, &v.intrinsics, w, h)?
                    .rgb
            }
            Inpainter::Onnx(_) | Inpainter::Provided { .. } => rgb,
        };
        let depth = match &self.refiner {
            Some(den) => diffusion::masked_ddim(
                &anchored.depth,
                &fill,
                &rgb,
                w,
                h,
                self.diffusion_steps,
                self.seed ^ index as u64,
                den,
            )?,
            None => {
                // covered pixels keep the depth of the Gaussians that cover them (seen from other
                // views), and pixels on a continued plane keep the plane's (the diffusion's
                // edge weights pulled a bench top's depth 3-10 % off its plane next to the hedge
                // behind it: tests/surface_continuation.rs); only the interpolated part follows
                // the image's edges
                let free: Vec<bool> = (0..w * h).map(|i| fill[i] && !covered[i] && labels[i] == 0).collect();
                depth::refine_edge_aware(&anchored.depth, &rgb, &free, w, h, self.refine_sweeps)
            }
        };
        Ok(Completed {
            fill,
            rgb,
            depth,
            surfaces: labels,
            planes: planes.planes,
            scale: anchored.scale,
            shift: anchored.shift,
            space: Some(space),
            fit_pixels: anchored.fit_pixels,
            residual: anchored.residual,
            texture_pending,
            farther_covered,
        })
    }
}

/// The hole pixels that keep the render of the Gaussians left behind the objects (not `fill`):
/// kept, but no texture source, since few views or none constrained those Gaussians.
fn leftover(hole: &[bool], fill: &[bool]) -> Vec<bool> {
    hole.iter().zip(fill).map(|(&m, &f)| m && !f).collect()
}
