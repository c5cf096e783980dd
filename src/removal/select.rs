//! Stages 1 and 2 of removal: which Gaussians go, and where each edited view needs new content.
//!
//! 1. Selection: the Gaussians whose `label` (from `cogeo tag`) is one of the chosen labels go.
//! 2. Hole masks: per edited view, M = pixels where the removed Gaussians carried more than
//!    `hole_threshold` of the pixel's blending weight in the original render (their weight is
//!    splatted as a one-channel feature), dilated by `dilate` pixels. The pixels to synthesize are
//!    all of M except where a kept object (a remaining Gaussian with a nonzero label) covers it
//!    (alpha after removal at least `keep_alpha`, mostly the object's weight): that object stays as
//!    it is. The background Gaussians left behind a removed object are no reason to keep a pixel's
//!    render: few views constrained them, and keeping their render left the bench's far floor blurred
//!    (held-out seen-elsewhere PSNR 0.5-1.1 dB lower, commit `2239581`). Completion adds the
//!    object-covered pixels that look through a gap past the surrounding surfaces
//!    (`complete::depth::see_through`).

use crate::gpu::Gpu;
use crate::image_ops::{bounding_box, dilate, including, Rect};
use crate::removal::refine::window_camera;
use crate::render::reach::{reaching, reaching_tiles, render_subset};
use crate::render::reference::project;
use crate::render::{RenderSettings, SceneRenderer, TILE};
use crate::scene::{Camera, GaussianScene};
use anyhow::{bail, Result};

/// Which Gaussians carry a chosen label.
pub fn select(labels: &[u8], chosen: &[u8]) -> Vec<bool> {
    labels.iter().map(|l| chosen.contains(l)).collect()
}

/// Stage 1: the Gaussians to remove and the scene without them.
#[derive(Clone)]
pub struct Selection {
    /// Per input Gaussian: true when it is removed.
    pub removed: Vec<bool>,
    pub count: usize,
    /// The remaining Gaussians, in their input order.
    pub background: GaussianScene,
    /// Per remaining Gaussian: true when it belongs to a kept object (a nonzero label).
    pub kept_objects: Vec<bool>,
}

/// Stage 1: selects the Gaussians of the `chosen` labels; fails when none or all of them go.
pub fn select_gaussians(scene: &GaussianScene, labels: &[u8], chosen: &[u8]) -> Result<Selection> {
    let removed = select(labels, chosen);
    let count = removed.iter().filter(|&&r| r).count();
    if count == 0 {
        bail!("no Gaussian carries label(s) {:?}", chosen);
    }
    let keep: Vec<bool> = removed.iter().map(|&r| !r).collect();
    let background = scene.subset(&keep);
    if background.is_empty() {
        bail!("removing label(s) {:?} leaves no Gaussian", chosen);
    }
    let kept_objects = labels.iter().zip(&removed).filter(|(_, &r)| !r).map(|(&l, _)| l != 0).collect();
    Ok(Selection { removed, count, background, kept_objects })
}

/// Which depth planes a `ViewRenderer` gives (`rendered_depth.rs`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DepthPlanes {
    /// The expected depth as `Rendered::depth`.
    Expected,
    /// The median depth as `Rendered::depth`.
    Median,
    /// The expected depth as `Rendered::depth` and the median one as `Rendered::median`.
    Both,
}

/// Renders RGB, alpha, depth and (with `marked`) the marked Gaussians' weight; made by `removal`,
/// the scene after a removal from the same walk too (`render_window_tiles_both`).
pub struct ViewRenderer<'s> {
    gpu: &'s Gpu,
    scene: &'s GaussianScene,
    /// The marked Gaussians' weight, one per Gaussian; None without `marked`. Made by `removal`:
    /// 1 a removed Gaussian, 2 a kept object's (`RenderSettings::after_removal`).
    feature: Option<Vec<f32>>,
    /// Whether `feature` marks a removal (`removal`).
    marks_removal: bool,
    renderer: SceneRenderer,
    /// `render_window`'s: the Gaussians that can reach the window, uploaded for it.
    window_renderer: Option<SceneRenderer>,
    /// The scene's learnt SH bands (`GaussianScene::learnt_sh_degree`), all a window's part needs.
    learnt_sh_degree: u32,
    planes: DepthPlanes,
}

/// One render of a view (planar RGB, alpha, depth; the marked Gaussians' weight, zero where none
/// were marked).
#[derive(Clone)]
pub struct Rendered {
    pub rgb: Vec<f32>,
    pub alpha: Vec<f32>,
    /// The expected depth, or the median depth where the renderer was made to read it.
    pub depth: Vec<f32>,
    pub weight: Vec<f32>,
    /// The median depth beside the expected one (`DepthPlanes::Both`); empty otherwise.
    pub median: Vec<f32>,
}

impl<'s> ViewRenderer<'s> {
    pub fn new(
        gpu: &'s Gpu,
        scene: &'s GaussianScene,
        marked: Option<&[bool]>,
        planes: DepthPlanes,
    ) -> Result<ViewRenderer<'s>> {
        let feature: Option<Vec<f32>> = marked.map(|r| r.iter().map(|&x| x as u8 as f32).collect());
        Self::with_feature(gpu, scene, feature, false, planes)
    }

    /// The renderer of `scene` before and after the removal of `selection`
    /// (`render_window_tiles_both`): the removed Gaussians' weight in the original, the kept
    /// objects' after removal.
    pub fn removal(
        gpu: &'s Gpu,
        scene: &'s GaussianScene,
        selection: &Selection,
        planes: DepthPlanes,
    ) -> Result<ViewRenderer<'s>> {
        // `kept_objects` runs over the remaining Gaussians, in their input order
        let mut kept = selection.kept_objects.iter();
        let feature = selection
            .removed
            .iter()
            .map(|&r| match r {
                true => 1.0,
                false => 2.0 * *kept.next().expect("a kept flag per remaining Gaussian") as u8 as f32,
            })
            .collect();
        Self::with_feature(gpu, scene, Some(feature), true, planes)
    }

    fn with_feature(
        gpu: &'s Gpu,
        scene: &'s GaussianScene,
        feature: Option<Vec<f32>>,
        marks_removal: bool,
        planes: DepthPlanes,
    ) -> Result<ViewRenderer<'s>> {
        let renderer = SceneRenderer::new(gpu, scene, feature.as_deref().map(|f| (f, 1)))?;
        let learnt_sh_degree = scene.learnt_sh_degree();
        Ok(ViewRenderer {
            gpu,
            scene,
            feature,
            marks_removal,
            renderer,
            window_renderer: None,
            learnt_sh_degree,
            planes,
        })
    }

    pub fn render(&mut self, camera: &Camera, background: [f32; 3]) -> Result<Rendered> {
        let features = self.feature.is_some();
        Ok(draw(&mut self.renderer, features, false, self.planes, camera, background, None)?.0)
    }

    /// `render` of a small part of a view (`refine::window_camera`), on a CPU device from only the
    /// Gaussians that can reach it (`render::reach`): the same image, bit for bit, without
    /// projecting and sorting the whole scene. On the statue `images_2` the hull's and the masks'
    /// 325 window renders took a fifth to a third of its Gaussians and 9.9 s in place of 11.0 s, the
    /// cull and upload on the host included (bench/JOURNAL.md, 2026-12-03, 06:31). A GPU should
    /// sort the whole scene in less time than an upload through a staging buffer takes (not
    /// measured: no GPU was lent), so it renders the window from the whole scene.
    pub fn render_window(&mut self, camera: &Camera, background: [f32; 3]) -> Result<Rendered> {
        self.render_window_tiles(camera, background, None)
    }

    /// `render_window` of only the marked tiles of the window (`RenderSettings::only_tiles`); the
    /// others come out empty.
    pub fn render_window_tiles(
        &mut self,
        camera: &Camera,
        background: [f32; 3],
        only_tiles: Option<Vec<bool>>,
    ) -> Result<Rendered> {
        Ok(self.draw_window(camera, background, only_tiles, false)?.0)
    }

    /// The tiles `only_tiles` marks of a window (`render_window_tiles`) before and after the
    /// removal (`removal`'s renderer only), from one walk over the original's tile lists: each the
    /// same bits as a render of its own scene (the hull's redraws on the statue `images_2`: 4.6-5.0
    /// -> 4.2-4.3 s, the same scene.ply).
    pub fn render_window_tiles_both(
        &mut self,
        camera: &Camera,
        background: [f32; 3],
        only_tiles: Option<Vec<bool>>,
    ) -> Result<(Rendered, Rendered)> {
        assert!(self.marks_removal, "render_window_tiles_both needs the renderer `removal` makes");
        let (before, after) = self.draw_window(camera, background, only_tiles, true)?;
        Ok((before, after.expect("rendered after removal")))
    }

    fn draw_window(
        &mut self,
        camera: &Camera,
        background: [f32; 3],
        only_tiles: Option<Vec<bool>>,
        both: bool,
    ) -> Result<(Rendered, Option<Rendered>)> {
        let (features, planes) = (self.feature.is_some(), self.planes);
        if !self.gpu.info().is_cpu() {
            return draw(&mut self.renderer, features, both, planes, camera, background, only_tiles);
        }
        let near = RenderSettings::default().near as f64;
        let keep = match &only_tiles {
            Some(tiles) => reaching_tiles(self.scene, camera, near, tiles),
            None => reaching(self.scene, camera, near),
        };
        if !keep.contains(&true) {
            return draw(&mut self.renderer, features, both, planes, camera, background, only_tiles);
        }
        let part = render_subset(self.scene, &keep, self.learnt_sh_degree);
        let feature: Option<Vec<f32>> =
            self.feature.as_ref().map(|f| f.iter().zip(&keep).filter(|(_, &k)| k).map(|(&v, _)| v).collect());
        let feature = feature.as_deref().map(|f| (f, 1));
        let renderer = match &mut self.window_renderer {
            Some(r) => {
                r.upload(self.gpu, &part, feature)?;
                r
            }
            none => none.insert(SceneRenderer::new(self.gpu, &part, feature)?),
        };
        draw(renderer, features, both, planes, camera, background, only_tiles)
    }

    /// `render` of `window` of the view only (`refine::window_camera`: the whole view's pixels,
    /// up to the float rounding of the moved principal point), the rest of the image `outside`'s
    /// colors, alpha and depth: for a scene that differs from `outside`'s only by Gaussians the
    /// window holds every pixel of. The marked Gaussians' weight is the window's, zero outside.
    pub fn render_within(
        &mut self,
        camera: &Camera,
        window: Rect,
        background: [f32; 3],
        outside: &Rendered,
    ) -> Result<Rendered> {
        let part = self.render_window(&window_camera(camera, window), background)?;
        let mut whole = Rendered {
            rgb: outside.rgb.clone(),
            alpha: outside.alpha.clone(),
            depth: outside.depth.clone(),
            weight: vec![0.0; outside.alpha.len()],
            median: outside.median.clone(),
        };
        whole.paste(window, &part, camera.width as usize);
        Ok(whole)
    }
}

/// One render through `renderer` with the marked Gaussians' weight (`features`) and the depth
/// planes `planes`, of the tiles `only_tiles` marks (`RenderSettings::only_tiles`) or all; with
/// `after_removal`, the scene after the removal its feature marks too (`ViewRenderer::removal`).
fn draw(
    renderer: &mut SceneRenderer,
    features: bool,
    after_removal: bool,
    planes: DepthPlanes,
    camera: &Camera,
    background: [f32; 3],
    only_tiles: Option<Vec<bool>>,
) -> Result<(Rendered, Option<Rendered>)> {
    let median_depth = planes != DepthPlanes::Expected;
    let settings =
        RenderSettings { background, features, median_depth, only_tiles, after_removal, ..Default::default() };
    let o = renderer.render(camera, &settings)?;
    let after = o.after_removal.map(|a| {
        let (depth, median) = depth_and_median(planes, a.expected_depth, a.median_depth);
        Rendered { rgb: a.rgb, alpha: a.alpha, depth, weight: a.kept_weight, median }
    });
    let weight = if features { o.features } else { vec![0.0; o.alpha.len()] };
    let (depth, median) = depth_and_median(planes, o.expected_depth, o.median_depth);
    Ok((Rendered { rgb: o.rgb, alpha: o.alpha, depth, weight, median }, after))
}

/// `Rendered::depth` and `Rendered::median` from a render's expected and median depth planes.
fn depth_and_median(planes: DepthPlanes, expected: Vec<f32>, median: Vec<f32>) -> (Vec<f32>, Vec<f32>) {
    match planes {
        DepthPlanes::Expected => (expected, Vec::new()),
        DepthPlanes::Median => (median, Vec::new()),
        DepthPlanes::Both => (expected, median),
    }
}

impl Rendered {
    /// Puts `part`, a render of `window` of this `w` pixels wide view, in its place.
    pub fn paste(&mut self, window: Rect, part: &Rendered, w: usize) {
        self.paste_where(window, part, w, |_| true)
    }

    /// `paste` of the part's pixels in the tiles `tiles` marks (row-major over the part's 16 x 16
    /// pixel tiles, `RenderSettings::only_tiles`).
    pub fn paste_tiles(&mut self, window: Rect, part: &Rendered, w: usize, tiles: &[bool]) {
        let (pw, t) = (window.width(), TILE as usize);
        let tiles_x = pw.div_ceil(t);
        self.paste_where(window, part, w, |k| tiles[(k / pw / t) * tiles_x + (k % pw) / t])
    }

    /// `paste` of the part's pixels `k` for which `take(k)`.
    fn paste_where(&mut self, window: Rect, part: &Rendered, w: usize, take: impl Fn(usize) -> bool) {
        let (n, pn) = (self.alpha.len(), part.alpha.len());
        for k in (0..pn).filter(|&k| take(k)) {
            let p = window.pixel(k, w);
            for c in 0..3 {
                self.rgb[c * n + p] = part.rgb[c * pn + k];
            }
            self.alpha[p] = part.alpha[k];
            self.depth[p] = part.depth[k];
            self.weight[p] = part.weight[k];
            if !part.median.is_empty() {
                self.median[p] = part.median[k];
            }
        }
    }

    /// Does a kept object cover pixel `p` of this render after removal: alpha at least
    /// `keep_alpha`, at least half of it the kept objects' weight?
    pub fn kept_object_covers(&self, p: usize, keep_alpha: f32) -> bool {
        self.alpha[p] >= keep_alpha && self.weight[p] >= KEPT_OBJECT_SHARE * self.alpha[p]
    }
}

/// The share of a covered pixel's weight that makes it a kept object's.
const KEPT_OBJECT_SHARE: f32 = 0.5;

/// How far (relative) the Gaussians left behind a removed object may lie in front of the completed
/// surface where they cover a fill pixel, for that pixel to become a patch Gaussian. Where they lie
/// farther in front, the completion is the doubtful one: on the bench, planes continued past a
/// floor's crease put the wall's pixels 25-30 % behind the wall, and their patch Gaussians were
/// floaters (score 113 -> 189 on three-of-four with them, 119 without).
pub const LEFTOVER_IN_FRONT: f32 = 0.06;

impl MaskedView {
    /// Of a view drawn with `DepthPlanes::Both`, the same view reading the median depth; this one
    /// keeps the expected depth alone.
    pub fn take_median_twin(&mut self) -> MaskedView {
        let take = |r: &mut Rendered| {
            assert_eq!(r.median.len(), r.depth.len(), "the median depth was not rendered");
            std::mem::take(&mut r.median)
        };
        // moved out before the clone, so that it copies no median plane
        let (before, after_removal) = (take(&mut self.before), take(&mut self.after_removal));
        let mut twin = self.clone();
        (twin.before.depth, twin.after_removal.depth) = (before, after_removal);
        twin
    }

    /// The fill pixels that become patch Gaussians at the completed `depth`: all of them except
    /// those that Gaussians left behind a removed object cover (alpha at least `keep_alpha`) more
    /// than `LEFTOVER_IN_FRONT` in front of that depth. Their colors still come from the
    /// completion; the refinement recolors what covers them.
    pub fn patch_pixels(&self, depth: &[f32]) -> Vec<bool> {
        let a = &self.after_removal;
        (0..self.fill.len())
            .map(|p| self.fill[p] && !(self.leftovers_cover(p) && a.depth[p] < depth[p] * (1.0 - LEFTOVER_IN_FRONT)))
            .collect()
    }

    /// Do the Gaussians left after removal cover pixel `p` (alpha at least `keep_alpha`)? In the
    /// fill these are the Gaussians left behind the objects, whose depth (`leftover_depth`) and
    /// place in the patch (`patch_pixels`) the later stages weigh by this one rule.
    pub fn leftovers_cover(&self, p: usize) -> bool {
        self.after_removal.alpha[p] >= self.keep_alpha
    }

    /// The depth the render after removal shows where the leftovers cover the pixel
    /// (`leftovers_cover`), 0 elsewhere: what `complete::leftover_depth` weighs against the
    /// completed depth.
    pub fn leftover_depth(&self) -> Vec<f32> {
        let a = &self.after_removal;
        (0..a.depth.len()).map(|p| if self.leftovers_cover(p) { a.depth[p] } else { 0.0 }).collect()
    }
}

/// The dilated hole of one view from the removed weight and alpha of the original render.
pub fn hole_mask(weight: &[f32], alpha: &[f32], w: usize, h: usize, threshold: f32, radius: f32) -> Vec<bool> {
    let raw: Vec<bool> = weight.iter().zip(alpha).map(|(&wt, &a)| wt > 0.02 && wt > threshold * a.max(1e-6)).collect();
    dilate(&raw, w, h, radius)
}

/// How stage 2 draws the holes.
pub struct HoleConfig {
    /// Share of a pixel's weight the removed Gaussians must carry for it to be in the hole.
    pub threshold: f32,
    /// Hole dilation in pixels.
    pub dilate: f32,
    /// Hole pixels a kept object covers with at least this alpha keep their render.
    pub keep_alpha: f32,
    pub background: [f32; 3],
    /// The renders' depth planes: the expected or the median depth, or both (`rendered_depth.rs`).
    pub depth: DepthPlanes,
}

/// Stage 2 for one edited view.
#[derive(Clone)]
pub struct MaskedView {
    /// Original render: RGB, and the alpha and depth (`HoleConfig::depth`) that color transfer
    /// checks; its `weight` is the removed Gaussians'.
    pub before: Rendered,
    /// Render right after deleting the Gaussians (the input of completion); its `weight` is the
    /// kept objects' (in the hole and around it; zero where the deletion changed nothing).
    pub after_removal: Rendered,
    /// Dilated hole M.
    pub hole: Vec<bool>,
    /// The part of M to synthesize.
    pub fill: Vec<bool>,
    /// The objects' own footprint with a 1-pixel margin for their anti-aliased edges: where color
    /// transfer must not read this view (the dilated hole would hide background other views saw).
    pub footprint: Vec<bool>,
    /// The alpha at which the render after removal covers a pixel: a hole pixel a kept object
    /// covers keeps its render (stage 2); a fill pixel the Gaussians left behind the removed ones
    /// cover lets them compete with the completion (`leftovers_cover`).
    pub keep_alpha: f32,
}

/// Stage 2: renders every view before and after deletion and draws its hole.
pub fn hole_masks(
    gpu: &Gpu,
    scene: &GaussianScene,
    selection: &Selection,
    cameras: &[Camera],
    cfg: &HoleConfig,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Vec<MaskedView>> {
    let (mut original, mut remaining) = view_renderers(gpu, scene, selection, cfg.depth)?;
    let mut views = Vec::new();
    for (i, cam) in cameras.iter().enumerate() {
        let (w, h) = (cam.width as usize, cam.height as usize);
        let before = original.render(cam, cfg.background)?;
        let hole = hole_mask(&before.weight, &before.alpha, w, h, cfg.threshold, cfg.dilate);
        // The render after the deletion differs from the original only where the removed
        // Gaussians blended: it is rendered over their pixels' box, the rest is the original's
        // (the masks stage on the statue `images_2` 5.0 -> 3.8 s). A removed Gaussian that ends
        // a pixel's blending without blending there changes that pixel by less than the
        // transmittance left, 1e-4. The kept objects' weight is only read in the hole, which
        // the box takes in too (the dilation reaches past the blended pixels).
        let touched: Vec<bool> = (0..w * h).map(|p| before.weight[p] > 0.0 || hole[p]).collect();
        let after_removal = match bounding_box(&touched, w) {
            Some(window) => remaining.render_within(cam, window, cfg.background, &before)?,
            None => remaining.render(cam, cfg.background)?,
        };
        let (fill, footprint) = fill_and_footprint(&before, &after_removal, &hole, cfg, w, h);
        views.push(MaskedView { before, after_removal, hole, fill, footprint, keep_alpha: cfg.keep_alpha });
        progress(i + 1, cameras.len());
    }
    Ok(views)
}

/// The renderers of stage 2: the original scene with the removed Gaussians' weight, and the
/// scene after removal with the kept objects' weight. A scene without kept objects needs no
/// weight of theirs: the feature blend was 40 % of a render on the statue (`Rendered::weight` is
/// then zero everywhere).
fn view_renderers<'s>(
    gpu: &'s Gpu,
    scene: &'s GaussianScene,
    selection: &'s Selection,
    planes: DepthPlanes,
) -> Result<(ViewRenderer<'s>, ViewRenderer<'s>)> {
    let original = ViewRenderer::new(gpu, scene, Some(&selection.removed), planes)?;
    let kept = selection.kept_objects.iter().any(|&k| k).then_some(&selection.kept_objects[..]);
    Ok((original, ViewRenderer::new(gpu, &selection.background, kept, planes)?))
}

/// The part of a `w` x `h` view's `hole` to synthesize (all of it but where a kept object covers
/// it in the render `after_removal`) and the objects' own footprint (from the removed weight of
/// the render `before`): stage 2's masks beside the hole.
fn fill_and_footprint(
    before: &Rendered,
    after_removal: &Rendered,
    hole: &[bool],
    cfg: &HoleConfig,
    w: usize,
    h: usize,
) -> (Vec<bool>, Vec<bool>) {
    let fill = (0..w * h).map(|p| hole[p] && !after_removal.kept_object_covers(p, cfg.keep_alpha)).collect();
    (fill, hole_mask(&before.weight, &before.alpha, w, h, cfg.threshold, 1.0))
}

/// Stage 2 again, for `selection` after the Gaussians `taken` (of `scene`; the selection `masked`
/// was drawn for kept them) joined the removed ones, as the hull (`hull.rs`) does round after
/// round: the views `hole_masks` draws for `selection`, rendered only where `taken` can blend
/// (the tiles `splat_tiles` marks in the window `splat_window` gives, grown by the hole's
/// dilation), the rest kept from `masked`. Elsewhere neither render changes. (On the statue
/// `images_2` each of the hull's three rounds drew every view again in 5.6 s; in windows of a
/// quarter of the view, 2.1-2.7 s; the hull's six rounds, three under each rendered depth, took
/// 10.5 s with whole windows and 8.5 s with their tiles, bench/JOURNAL.md, 2026-12-04, 17:43.)
#[allow(clippy::too_many_arguments)]
pub fn redraw_hole_masks(
    gpu: &Gpu,
    scene: &GaussianScene,
    selection: &Selection,
    taken: &[bool],
    cameras: &[Camera],
    cfg: &HoleConfig,
    masked: &mut [MaskedView],
    progress: &mut dyn FnMut(usize, usize),
) -> Result<()> {
    let mut renderer = ViewRenderer::removal(gpu, scene, selection, cfg.depth)?;
    let grow = cfg.dilate.max(0.0).ceil() as usize + 1;
    for (i, (cam, view)) in cameras.iter().zip(masked.iter_mut()).enumerate() {
        let (w, h) = (cam.width as usize, cam.height as usize);
        if let Some((window, tiles)) = splat_tiles(scene, taken, cam, grow) {
            let part_camera = window_camera(cam, window);
            let (before, after) =
                renderer.render_window_tiles_both(&part_camera, cfg.background, Some(tiles.clone()))?;
            view.before.paste_tiles(window, &before, w, &tiles);
            view.after_removal.paste_tiles(window, &after, w, &tiles);
            let before = &view.before;
            view.hole = hole_mask(&before.weight, &before.alpha, w, h, cfg.threshold, cfg.dilate);
            (view.fill, view.footprint) = fill_and_footprint(before, &view.after_removal, &view.hole, cfg, w, h);
        }
        progress(i + 1, cameras.len());
    }
    Ok(())
}

/// The pixels of `camera`'s view where the `marked` Gaussians of `scene` can blend: the box of
/// their supports (`splat_boxes`), or None.
pub fn splat_window(scene: &GaussianScene, marked: &[bool], camera: &Camera) -> Option<Rect> {
    bounding(splat_boxes(scene, marked, camera))
}

/// `splat_window` grown by `grow` pixels, and the tiles of it (16 x 16 pixels, row-major,
/// `RenderSettings::only_tiles`) that the supports of the `marked` Gaussians, each grown by
/// `grow` pixels too, reach; None where none can blend. In the hull's rounds on the statue
/// `images_2` the tiles were half of the window's pixels (the supports' own pixels a third).
pub fn splat_tiles(scene: &GaussianScene, marked: &[bool], camera: &Camera, grow: usize) -> Option<(Rect, Vec<bool>)> {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let boxes: Vec<Rect> = splat_boxes(scene, marked, camera).map(|b| b.grown(grow, grow, w, h)).collect();
    // (growing each box and then taking their bounds is growing the bounds: the window holds them)
    let window = bounding(boxes.iter().copied())?;
    let t = TILE as usize;
    let tiles_x = window.width().div_ceil(t);
    let mut tiles = vec![false; tiles_x * window.height().div_ceil(t)];
    for b in boxes {
        let (x0, x1, y0, y1) = (b.x0 - window.x0, b.x1 - window.x0, b.y0 - window.y0, b.y1 - window.y0);
        for ty in y0 / t..=(y1 - 1) / t {
            tiles[ty * tiles_x + x0 / t..=ty * tiles_x + (x1 - 1) / t].fill(true);
        }
    }
    Some((window, tiles))
}

/// The bounding rectangle of `boxes` (each taken in by its corner pixels), or None for none.
fn bounding(boxes: impl Iterator<Item = Rect>) -> Option<Rect> {
    boxes.fold(None, |r, b| Some(including(Some(including(r, b.x0, b.y0)), b.x1 - 1, b.y1 - 1)))
}

/// Per `marked` Gaussian of `scene` that can blend in `camera`'s view, the pixels where it can:
/// its support (`ProjectedGaussian::support`) and a pixel more for float32 rounding, clamped to
/// the view.
fn splat_boxes<'a>(
    scene: &'a GaussianScene,
    marked: &'a [bool],
    camera: &'a Camera,
) -> impl Iterator<Item = Rect> + 'a {
    let near = RenderSettings::default().near as f64;
    let (w, h) = (camera.width as f64, camera.height as f64);
    (0..scene.len()).filter(|&i| marked[i]).filter_map(move |i| {
        let [x0, x1, y0, y1] = project(scene, i, camera, near, 0).and_then(|g| g.support())?;
        // pixel (px, py) is sampled at its centre (px + 0.5, py + 0.5)
        let (px0, px1) = ((x0 - 0.5).floor() - 1.0, (x1 - 0.5).ceil() + 1.0);
        let (py0, py1) = ((y0 - 0.5).floor() - 1.0, (y1 - 0.5).ceil() + 1.0);
        if px1 < 0.0 || py1 < 0.0 || px0 > w - 1.0 || py0 > h - 1.0 {
            return None;
        }
        // the corners' pixels, inclusive
        let (x1, y1) = (px1.min(w - 1.0) as usize, py1.min(h - 1.0) as usize);
        Some(Rect { x0: px0.max(0.0) as usize, y0: py0.max(0.0) as usize, x1: x1 + 1, y1: y1 + 1 })
    })
}
