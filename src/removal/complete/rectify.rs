//! Plane rectification for the exemplar inpainter. Under perspective a receding floor's texture
//! shrinks with distance, so an image-space translation copies a checkerboard or a brick course
//! with the wrong period and phase. A background plane (surfaces.rs, disparity affine in pixel
//! coordinates) together with the camera's intrinsics is a plane in 3D; its pixels resampled onto a
//! regular grid in the plane's own coordinates show the texture at one scale everywhere, where a
//! translation is the right match. The exemplar synthesizes there and the result is sampled back
//! through the same homography.

use crate::image_ops::sample_bilinear;
use crate::planes::Plane;
use crate::scene::Camera;
use glam::{DVec2, DVec3};

/// Pinhole intrinsics in pixels; pixel (px, py) is evaluated at (px + 0.5, py + 0.5).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Intrinsics {
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
}

impl From<&Camera> for Intrinsics {
    fn from(c: &Camera) -> Intrinsics {
        Intrinsics { fx: c.fx, fy: c.fy, cx: c.cx, cy: c.cy }
    }
}

impl Intrinsics {
    /// The camera-space ray through image point (x, y), with z = 1.
    fn ray(&self, x: f64, y: f64) -> DVec3 {
        DVec3::new((x - self.cx) / self.fx, (y - self.cy) / self.fy, 1.0)
    }
}

/// The grid labels (`Rectified::labels`).
pub const ON_SURFACE: u8 = 1;
pub const OFF_SURFACE: u8 = 2;

/// Known texels sampled from pixels this many texels wide or more lend no texture: upsampled, the
/// far part of a floor is a blur that the hole would copy.
const BLURRY_FOOTPRINT: f64 = 1.5;

/// The share of a surface's fill pixels (in plane coordinates) at each end of each axis left out
/// of the box the grid is centred on (`trimmed_box`). The grid reaches past the box (by its own
/// size, or LOCAL_CONTEXT of it), so they stay in it unless they lie far off the rest; then the
/// image-space fill takes them (`Rectified::write_back`). On the synth room two-of-three fill
/// pixels by the wall's crease stretched the floor's grids: their texels grew, their sources fell
/// below their hole texels, and the floor was left to image-space translations (a checkerboard at
/// the wrong period).
/// Paired runs (journal, 2026-11-27): synth two-of-three 25.48 -> 26.14 dB masked PSNR,
/// statue-one masked LPIPS 0.080 -> 0.047; synth one unchanged on the whole, though two of its
/// views now fill the box's never-seen footprint with a smooth blob at every seed: their smaller
/// grid's coarsest pyramid level lends 2 source patches, and the layout from those persists
/// (journal, 2026-11-27, later). 1 % and 4 % did worse.
const BOX_TRIM: f64 = 0.02;

/// The context a grid holds around the hole's box on each side, as a share of the box, for a
/// texture that repeats: its distant periods are exact sources, and the exemplar's coarse levels
/// need several of them to lay the hole out in phase (a context of 0.4 cost the synth rooms 0.6
/// and 1.2 dB masked PSNR).
const PERIODIC_CONTEXT: f64 = 1.0;

/// The same for a texture that does not repeat (grass, leaves, gravel). Near the hole it has the
/// hole's light, grain and focus; a wide context reaches the far lawn, darker and blurrier, and
/// the vote averages both into a flat patch. On the statue composites (journal, 2026-11-28):
/// masked LPIPS 0.348 -> 0.273 and 0.398 -> 0.251, masked PSNR -0.0 and -0.9 dB.
const LOCAL_CONTEXT: f64 = 0.4;

/// How far a texture's autocorrelation must climb back from its lowest to a peak, in two
/// directions, to count as repeating (`repeats`).
const PERIODIC_REBOUND: f64 = 0.8;

/// Fewest texel pairs an autocorrelation is taken over (and fewest known texels to judge by).
const MIN_PAIRS: usize = 256;

/// Sample points per pixel side when writing back.
const SUB: usize = 3;

/// The largest rectified grid side; a larger plane region is sampled with coarser texels.
const MAX_GRID: usize = 256;

/// A plane's own 2D frame: the points X with q . X = 1 (camera space), origin at the point nearest
/// the camera, axes `e1` (the image x axis projected into the plane, or the view direction's
/// projection for a plane seen edge-on to it) and `e2` = n x e1.
#[derive(Clone, Copy, Debug)]
pub struct PlaneFrame {
    k: Intrinsics,
    q: DVec3,
    origin: DVec3,
    e1: DVec3,
    e2: DVec3,
}

impl PlaneFrame {
    /// The frame of `plane` (disparity a x + b y + c over the image) seen through `k`; None for a
    /// degenerate plane. Since 1/z = q . ray(x, y) = (q.x / fx) x + (q.y / fy) y + q.z - q.x cx / fx
    /// - q.y cy / fy, q follows from (a, b, c) directly.
    pub fn new(plane: &Plane, k: &Intrinsics) -> Option<PlaneFrame> {
        let q = DVec3::new(plane.a * k.fx, plane.b * k.fy, plane.c + plane.a * k.cx + plane.b * k.cy);
        let len2 = q.length_squared();
        if !(len2 > 0.0 && len2.is_finite()) {
            return None;
        }
        let n = q / len2.sqrt();
        let project = |axis: DVec3| axis - n * n.dot(axis);
        let along_x = project(DVec3::X);
        let e1 = if along_x.length() > 0.3 { along_x } else { project(DVec3::Z) }.normalize();
        Some(PlaneFrame { k: *k, q, origin: q / len2, e1, e2: n.cross(e1) })
    }

    /// Plane coordinates of image point (x, y); None where the ray misses the plane in front.
    pub fn to_plane(&self, x: f64, y: f64) -> Option<DVec2> {
        let r = self.k.ray(x, y);
        let disparity = self.q.dot(r);
        if !(disparity > 0.0 && disparity.is_finite()) {
            return None;
        }
        let p = r / disparity - self.origin;
        Some(DVec2::new(p.dot(self.e1), p.dot(self.e2)))
    }

    /// Image point of plane coordinates `uv`; None behind the camera.
    pub fn to_image(&self, uv: DVec2) -> Option<DVec2> {
        let p = self.origin + uv.x * self.e1 + uv.y * self.e2;
        if p.z <= 1e-9 * p.length() {
            return None;
        }
        Some(DVec2::new(self.k.fx * p.x / p.z + self.k.cx, self.k.fy * p.y / p.z + self.k.cy))
    }

    /// Side of the plane square one pixel at pixel center (x, y) covers (square root of the
    /// homography's Jacobian determinant).
    fn footprint(&self, x: f64, y: f64) -> Option<f64> {
        let (a, b, c) = (self.to_plane(x - 0.5, y)?, self.to_plane(x + 0.5, y)?, self.to_plane(x, y - 0.5)?);
        let d = self.to_plane(x, y + 0.5)?;
        let (du, dv) = (b - a, d - c);
        Some((du.x * dv.y - du.y * dv.x).abs().sqrt())
    }
}

/// One surface's pixels around a hole resampled onto a regular grid in its plane.
pub struct Rectified {
    pub w: usize,
    pub h: usize,
    /// Planar RGB; hole texels hold 0.
    pub image: Vec<f32>,
    /// Texels to synthesize: those on the surface's fill pixels.
    pub hole: Vec<bool>,
    /// Texels that lend no texture: on avoided pixels, and those off the surface (other
    /// surfaces, off the image).
    pub avoid: Vec<bool>,
    /// ON_SURFACE, or OFF_SURFACE for texels the surface's pixels do not cover: the exemplar's
    /// patch distance and vote skip those.
    pub labels: Vec<u8>,
    /// Whether the surface's known texture repeats (`repeats`): a periodic texture's continuation
    /// is in phase with the truth, a random one's is not (invention_contrast.rs).
    pub repeats: bool,
    frame: PlaneFrame,
    /// Plane coordinates of texel (0, 0)'s corner, and the texel side.
    corner: DVec2,
    texel: f64,
}

/// Rectifies the pixels labelled `label` (1 + the plane's index, as in `Surfaces::labels`) of the
/// planar RGB `image` (w x h) around its `fill` pixels of that label. The grid's texel is the
/// median footprint of those pixels (about one texel per hole pixel); it covers their plane box
/// grown on every side by PERIODIC_CONTEXT of its size where the texture repeats (`repeats`),
/// else by LOCAL_CONTEXT (at least 16 texels), at most MAX_GRID texels a side. None when no such
/// pixel maps onto the plane.
#[allow(clippy::too_many_arguments)]
pub fn rectify(
    frame: &PlaneFrame,
    image: &[f32],
    fill: &[bool],
    avoid: &[bool],
    labels: &[u8],
    label: u8,
    w: usize,
    h: usize,
) -> Option<Rectified> {
    let center = |i: usize| ((i % w) as f64 + 0.5, (i / w) as f64 + 0.5);
    let mine: Vec<usize> = (0..w * h).filter(|&i| fill[i] && labels[i] == label).collect();
    let mut feet: Vec<f64> = mine.iter().filter_map(|&i| frame.footprint(center(i).0, center(i).1)).collect();
    let uvs: Vec<DVec2> = mine.iter().filter_map(|&i| frame.to_plane(center(i).0, center(i).1)).collect();
    if feet.is_empty() || uvs.is_empty() {
        return None;
    }
    feet.sort_by(f64::total_cmp);
    // their box without stray pixels: a few pixels labelled this plane far off the rest (by the
    // crease of a floor and a wall) would stretch the grid and coarsen its texel until the hole
    // outweighs the sources
    let (lo, hi) = trimmed_box(&uvs);
    let mut texel = feet[feet.len() / 2];
    if !(texel > 0.0 && texel.is_finite() && (hi - lo).is_finite()) {
        return None; // a plane seen edge-on or at the horizon: nothing to rectify
    }
    let side = |extent: f64, texel: f64| ((extent / texel).ceil().min(1e9) as usize).saturating_add(1);
    // the hole's own box must fit with some context
    let hole_side = side((hi - lo).max_element(), texel);
    if hole_side > MAX_GRID / 2 {
        texel *= hole_side as f64 / (MAX_GRID / 2) as f64;
    }
    let surface = SurfacePixels { image, fill, avoid, labels, label, w, h };
    let grid = |context: f64| sample_grid(frame, &surface, (lo, hi), texel, context);
    let wide = grid(PERIODIC_CONTEXT);
    if repeats(&wide) {
        Some(Rectified { repeats: true, ..wide })
    } else {
        Some(grid(LOCAL_CONTEXT))
    }
}

/// Whether the grid's known texture repeats: along at least two of the axes and diagonals its
/// luma's autocorrelation climbs back by PERIODIC_REBOUND or more from its lowest so far to a peak
/// (a checkerboard swings from about -0.8 at half its period to +0.8 at its period, along both
/// axes). Grass and gravel only decay, with wiggles, and a drift of light over a lawn can make one
/// direction climb at a long lag: of the 173 rectified grids of the statue and cup composites none
/// climbed 0.8 in two directions (the cup's 122 measured at every second lag); of the synth rooms'
/// 55 floors and walls 48 did (journal, 2026-11-28).
fn repeats(g: &Rectified) -> bool {
    let n = g.w * g.h;
    let known: Vec<bool> = (0..n).map(|t| g.labels[t] == ON_SURFACE && !g.hole[t] && !g.avoid[t]).collect();
    let count = known.iter().filter(|&&k| k).count();
    if count < MIN_PAIRS {
        return false;
    }
    let luma: Vec<f64> = (0..n).map(|t| (g.image[t] + g.image[n + t] + g.image[2 * n + t]) as f64 / 3.0).collect();
    let mean = (0..n).filter(|&t| known[t]).map(|t| luma[t]).sum::<f64>() / count as f64;
    let luma: Vec<f64> = luma.iter().map(|&l| l - mean).collect();
    let max_lag = (g.w.min(g.h) / 2) as isize;
    let climbs = |&(dx, dy): &(isize, isize)| {
        let rho = |k: isize| autocorrelation(&luma, &known, g.w, g.h, k * dx, k * dy);
        let (mut lowest, mut before, mut at) = (f64::INFINITY, 1.0, rho(1));
        for k in 2..=max_lag {
            let (Some(r), Some(next)) = (at, rho(k)) else { return false };
            lowest = lowest.min(r);
            if r >= before && r >= next && r - lowest >= PERIODIC_REBOUND {
                return true;
            }
            (before, at) = (r, Some(next));
        }
        false
    };
    [(1, 0), (0, 1), (1, 1), (1, -1)].iter().filter(|d| climbs(d)).count() >= 2
}

/// The normalized autocorrelation of the mean-free `luma` at offset (ox, oy) over the pairs of
/// `known` texels; None with fewer than MIN_PAIRS pairs.
fn autocorrelation(luma: &[f64], known: &[bool], w: usize, h: usize, ox: isize, oy: isize) -> Option<f64> {
    let (mut sab, mut saa, mut sbb, mut pairs) = (0.0, 0.0, 0.0, 0usize);
    let (x0, x1) = ((-ox).max(0) as usize, (w as isize - ox.max(0)).max(0) as usize);
    let (y0, y1) = ((-oy).max(0) as usize, (h as isize - oy.max(0)).max(0) as usize);
    for y in y0..y1 {
        for x in x0..x1 {
            let a = y * w + x;
            let b = (a as isize + oy * w as isize + ox) as usize;
            if known[a] && known[b] {
                sab += luma[a] * luma[b];
                saa += luma[a] * luma[a];
                sbb += luma[b] * luma[b];
                pairs += 1;
            }
        }
    }
    (pairs >= MIN_PAIRS && saa > 0.0 && sbb > 0.0).then(|| sab / (saa * sbb).sqrt())
}

/// The arguments of `rectify` that `sample_grid` reads: the image and its per-pixel masks.
struct SurfacePixels<'a> {
    image: &'a [f32],
    fill: &'a [bool],
    avoid: &'a [bool],
    labels: &'a [u8],
    label: u8,
    w: usize,
    h: usize,
}

/// Resamples the surface's pixels onto a grid of `texel` in the plane: the box (lo, hi) grown by
/// `context` of its size (at least 16 texels) on every side, at most MAX_GRID texels a side.
fn sample_grid(
    frame: &PlaneFrame,
    surface: &SurfacePixels,
    (lo, hi): (DVec2, DVec2),
    texel: f64,
    context: f64,
) -> Rectified {
    let SurfacePixels { image, fill, avoid, labels, label, w, h } = *surface;
    let side = |extent: f64| ((extent / texel).ceil().min(1e9) as usize).saturating_add(1);
    let grid = |extent: f64| {
        let inner = side(extent);
        (inner + 2 * ((inner as f64 * context) as usize).max(16)).min(MAX_GRID)
    };
    let (gw, gh) = (grid(hi.x - lo.x), grid(hi.y - lo.y));
    let corner = (lo + hi) * 0.5 - DVec2::new(gw as f64, gh as f64) * (0.5 * texel);
    let n = gw * gh;
    let mut out = Rectified {
        w: gw,
        h: gh,
        image: vec![0.0; 3 * n],
        hole: vec![false; n],
        avoid: vec![true; n],
        labels: vec![OFF_SURFACE; n],
        repeats: false,
        frame: *frame,
        corner,
        texel,
    };
    let ours = |x: isize, y: isize| {
        x >= 0 && y >= 0 && (x as usize) < w && (y as usize) < h && labels[y as usize * w + x as usize] == label
    };
    for t in 0..n {
        let uv = corner + DVec2::new((t % gw) as f64 + 0.5, (t / gw) as f64 + 0.5) * texel;
        let Some(xy) = frame.to_image(uv) else { continue };
        let (px, py) = (xy.x.floor(), xy.y.floor());
        if !(px.abs() < 1e9 && py.abs() < 1e9 && ours(px as isize, py as isize)) {
            continue; // another surface or off the image
        }
        let p = py as usize * w + px as usize;
        out.labels[t] = ON_SURFACE;
        if fill[p] {
            (out.hole[t], out.avoid[t]) = (true, false);
            continue;
        }
        // a pixel much larger than a texel holds that texture blurred: context, but no source
        let coarse = frame.footprint(xy.x, xy.y).is_none_or(|f| f > BLURRY_FOOTPRINT * texel);
        out.avoid[t] = avoid[p] || coarse;
        // bilinear among the surface's known pixels, nearest where a neighbour is not one
        let (x0, y0) = ((xy.x - 0.5).floor() as isize, (xy.y - 0.5).floor() as isize);
        let corners = [(x0, y0), (x0 + 1, y0), (x0, y0 + 1), (x0 + 1, y0 + 1)];
        let usable = corners.iter().all(|&(x, y)| ours(x, y) && !fill[y as usize * w + x as usize]);
        for c in 0..3 {
            out.image[c * n + t] =
                if usable { sample_bilinear(image, w, h, c, xy.x, xy.y) } else { image[c * w * h + p] };
        }
    }
    out
}

/// The box of `uvs` (not empty) without the BOX_TRIM share at each end of each axis.
fn trimmed_box(uvs: &[DVec2]) -> (DVec2, DVec2) {
    let trim = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        let k = (BOX_TRIM * v.len() as f64) as usize;
        (v[k], v[v.len() - 1 - k])
    };
    let (ulo, uhi) = trim(uvs.iter().map(|p| p.x).collect());
    let (vlo, vhi) = trim(uvs.iter().map(|p| p.y).collect());
    (DVec2::new(ulo, vlo), DVec2::new(uhi, vhi))
}

impl Rectified {
    /// Writes the synthesized grid `filled` (planar RGB, w x h of the grid) back into `out` (the
    /// image, planar RGB, iw x ih) at the `fill` pixels labelled `label`, each the mean of
    /// bilinear samples at SUB x SUB points of the pixel; returns which pixels it wrote.
    #[allow(clippy::too_many_arguments)]
    pub fn write_back(
        &self,
        filled: &[f32],
        out: &mut [f32],
        fill: &[bool],
        labels: &[u8],
        label: u8,
        iw: usize,
        ih: usize,
    ) -> Vec<bool> {
        let (gw, gh) = (self.w, self.h);
        let mut written = vec![false; iw * ih];
        for p in (0..iw * ih).filter(|&p| fill[p] && labels[p] == label) {
            // the mean over SUB x SUB points of the pixel: a far pixel covers many texels
            let mut acc = [0f32; 3];
            let mut samples = 0;
            for k in 0..SUB * SUB {
                let x = (p % iw) as f64 + ((k % SUB) as f64 + 0.5) / SUB as f64;
                let y = (p / iw) as f64 + ((k / SUB) as f64 + 0.5) / SUB as f64;
                let Some(uv) = self.frame.to_plane(x, y) else { continue };
                let g = (uv - self.corner) / self.texel;
                if !(g.x >= 0.0 && g.y >= 0.0 && g.x <= gw as f64 && g.y <= gh as f64) {
                    continue; // off the grid: the image-space fill takes the pixel
                }
                for (c, a) in acc.iter_mut().enumerate() {
                    *a += sample_bilinear(filled, gw, gh, c, g.x, g.y);
                }
                samples += 1;
            }
            if samples == 0 {
                continue;
            }
            for (c, a) in acc.iter().enumerate() {
                out[c * iw * ih + p] = a / samples as f32;
            }
            written[p] = true;
        }
        written
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A floor plane y = 1 seen by a camera tilted down: the frame's maps invert each other and
    /// its disparity agrees with the plane's.
    #[test]
    fn plane_frame_round_trips_and_matches_the_planes_disparity() {
        let k = Intrinsics { fx: 80.0, fy: 80.0, cx: 48.0, cy: 36.0 };
        // y = 1 in camera space: 1/z = ray.y = (y - cy) / fy, so a = 1/fy, b... along image y
        let plane = Plane { a: 0.0, b: 1.0 / k.fy, c: -k.cy / k.fy };
        let f = PlaneFrame::new(&plane, &k).unwrap();
        for &(x, y) in &[(10.5, 50.5), (48.0, 40.0), (90.25, 71.5)] {
            let uv = f.to_plane(x, y).unwrap();
            let back = f.to_image(uv).unwrap();
            assert!((back.x - x).abs() < 1e-9 && (back.y - y).abs() < 1e-9, "{x},{y} -> {back}");
            // the 3D point is on y = 1 at depth 1 / disparity
            let z = 1.0 / plane.disparity(x, y);
            let p = f.origin + uv.x * f.e1 + uv.y * f.e2;
            assert!((p.y - 1.0).abs() < 1e-9 && (p.z - z).abs() < 1e-9 * z, "{p} vs z {z}");
        }
        // above the horizon the ray misses the floor
        assert!(f.to_plane(48.0, 30.0).is_none());
        // a pixel twice as far covers a square twice as wide (for this floor, footprint ~ z^2)
        let (z1, z2) = (1.0 / plane.disparity(48.0, 56.0), 1.0 / plane.disparity(48.0, 46.0));
        let ratio = f.footprint(48.0, 46.0).unwrap() / f.footprint(48.0, 56.0).unwrap();
        assert!((ratio / (z2 / z1).powf(1.5) - 1.0).abs() < 0.02, "ratio {ratio}, depths {z1} {z2}");
    }

    /// A 160 x 160 view of a plane facing the camera at depth 1 (one texel per pixel) with a
    /// 40 x 40 hole in the middle, its known pixels `texture(x, y)` (gray).
    fn facing_plane(texture: impl Fn(usize, usize) -> f32) -> Option<Rectified> {
        let (w, h) = (160, 160);
        let k = Intrinsics { fx: 100.0, fy: 100.0, cx: 80.0, cy: 80.0 };
        let frame = PlaneFrame::new(&Plane { a: 0.0, b: 0.0, c: 1.0 }, &k).unwrap();
        let fill: Vec<bool> =
            (0..w * h).map(|p| (60..100).contains(&(p % w)) && (60..100).contains(&(p / w))).collect();
        let mut image = vec![0f32; 3 * w * h];
        for p in (0..w * h).filter(|&p| !fill[p]) {
            for c in 0..3 {
                image[c * w * h + p] = texture(p % w, p / w);
            }
        }
        rectify(&frame, &image, &fill, &vec![false; w * h], &vec![1; w * h], 1, w, h)
    }

    /// A checkerboard (6-pixel squares) and bricks repeat; white noise, and grain under a drift
    /// of light across the plane (the lawn's case), do not. Repeating textures keep the wide
    /// context (the 40-texel hole box plus 40 a side), the others the local one (plus 16).
    #[test]
    fn repeating_textures_keep_the_wide_context_and_grain_takes_the_local_one() {
        let mut rng = crate::rng::Rng::new(7);
        let noise: Vec<f32> = (0..160 * 160).map(|_| rng.uniform() as f32).collect();
        let checker = |x: usize, y: usize| ((x / 6 + y / 6) % 2) as f32;
        // 16 x 6 bricks, each course offset by half a brick, 1-pixel mortar
        let bricks = |x: usize, y: usize| {
            let shift = if (y / 6).is_multiple_of(2) { 0 } else { 8 };
            if y.is_multiple_of(6) || (x + shift).is_multiple_of(16) {
                0.9
            } else {
                0.3
            }
        };
        let white = |x: usize, y: usize| noise[y * 160 + x];
        // grain: 3 x 3 means of the noise at half its amplitude, on a ramp of light that varies more
        let grain = |x: usize, y: usize| {
            let mut sum = 0.0;
            for (dx, dy) in (0..9).map(|i| (i % 3, i / 3)) {
                sum += noise[(y + dy).saturating_sub(1).min(159) * 160 + (x + dx).saturating_sub(1).min(159)];
            }
            0.5 * sum / 9.0 + 0.5 * (x + y) as f32 / 320.0
        };
        type Texture<'a> = &'a dyn Fn(usize, usize) -> f32;
        let cases: [(&str, Texture, bool); 4] = [
            ("checkerboard", &checker, true),
            ("bricks", &bricks, true),
            ("white noise", &white, false),
            ("grain", &grain, false),
        ];
        for (name, texture, periodic) in cases {
            let grid = facing_plane(texture).unwrap();
            assert_eq!(repeats(&grid), periodic, "{name}");
            assert_eq!(grid.repeats, periodic, "{name}: the grid's own flag");
            // the hole's box spans 40 texels (one per pixel) or 41 by rounding
            let inner = (grid.hole.iter().filter(|&&x| x).count() as f64).sqrt();
            let context = if periodic { inner } else { 16.0 }; // 0.4 x 40 is under the 16 minimum
            let expected = inner + 2.0 * context;
            assert!(
                (grid.w as f64 - expected).abs() <= 2.0 && (grid.h as f64 - expected).abs() <= 2.0,
                "{name}: grid {}x{}, expected about {expected}",
                grid.w,
                grid.h
            );
        }
    }
}
