//! The surfaces around a hole. The background next to a removed object is mostly a few planes
//! (floor, walls, a table top). In a pinhole view the inverse depth of a plane is affine in pixel
//! coordinates, so planes (crate::planes) are found by RANSAC on (x, y, 1/d) of the known pixels in a band around
//! the hole, with no intrinsics needed. They serve twice:
//! - the built-in depth prior continues each plane into the hole, and where planes meet it keeps
//!   the one the band shows in front (a floor meets a wall at a crease that a smooth interpolant
//!   would round off). Which one that is, the band says per pair of planes: the nearer for a
//!   bench top before the hedge behind it, the farther for the bench's top and front face at
//!   their convex edge; where it does not say, the nearer, so that a background layer never
//!   covers a nearer surface running into the hole (tests/surface_continuation.rs); and a plane
//!   continues only where it lies behind the removed objects (`Surfaces::behind`);
//! - depth-guided color: each pixel to synthesize is filled from the known pixels of its own
//!   surface only (`fill_by_surface`), so floor texture does not bleed into the wall.

use super::harmonic::harmonic_fill;
use crate::image_ops::{bounding_box, crop, dilate, Rect};
use crate::planes::{center, fit_planes, least_squares, Plane, PLANE_TOLERANCE};

/// Relative disparity tolerance of the surface labels that guide color. Looser than the fit's: the
/// rendered depth of a textured surface (grass) scatters by more than 3 %, and a label only
/// chooses which known pixels lend texture.
pub const LABEL_TOLERANCE: f64 = 0.1;
/// Most planes found around one hole. Behind the statue of the shared statue capture a hole
/// meets the hedge's far plane, the lawn, the pedestal's face and top, and a path crossing behind
/// the statue. With three the path, the smallest, was left out: the rows behind the statue took
/// a membrane of the lawn and the hedge, and the color transfer a dark block across the path in
/// every view; with four the pedestal's top gave way and took the lawn's colors; five and eight
/// continue the path and keep the top. Hand runs on the real-photo bench, three -> five (masked
/// PSNR / LPIPS): statue-one 21.36 / 0.374 -> 21.27 / 0.314, statue-two-of-three 22.11 / 0.309
/// -> 22.12 / 0.310, cup-one 26.76 / 0.152 -> 26.81 / 0.160, cup-two-of-three 27.41 / 0.118 ->
/// 27.68 / 0.114 (eight: 27.44 / 0.117; bench/JOURNAL.md, 2026-12-02); on the bench's own
/// trainings, with the two changes before it, its rows moved by at most 0.08 dB and 0.018 LPIPS
/// (RESULTS.md): within what a training changes.
const MAX_PLANES: usize = 5;
const MIN_REFIT_PIXELS: usize = 12;
/// A plane with less than this share of the band continues into the hole only where it runs into
/// it (`detached`): on its own a small plane is as often a stretch of texture or a kept object's
/// face a few pixels off the hole as the bench top that enters it.
const SMALL_PLANE_SHARE: f64 = 0.15;
/// How much of the hole's rim (the band pixels within RIM_WIDTH of it) a small plane must hold to
/// run into the hole. On the synth room two-of-three the small planes held 1-3 % of the rim or
/// 6-15 %; the first cost masked PSNR (20.62 -> 20.24 dB when they continued, 20.38 with this
/// rule); the bench top of tests/surface_continuation.rs holds more.
const SMALL_PLANE_RIM_SHARE: f64 = 0.04;
const RIM_WIDTH: f32 = 1.5;
/// How far (relative depth) in front of a removed object a plane continued over it may lie
/// (`Surfaces::behind`): where the object met the surface it stood on, the two depths agree, and
/// the rendered depth of an object's rim blends it with what lies behind.
pub const BEHIND_TOLERANCE: f64 = 0.05;

/// The planes around one hole and which of them is seen where they meet.
#[derive(Clone, Debug)]
pub struct Surfaces {
    pub planes: Vec<Plane>,
    /// Per pair of planes, which one the band shows where both could be: 1, the nearer (a bench
    /// top in front of the hedge behind it); -1, the farther (the bench's top and its front face
    /// meeting at a convex edge); 0, the band does not say: then the nearer, since a farther
    /// layer must never cover a nearer surface that runs into the hole. Row-major, planes x
    /// planes; empty: the nearer everywhere.
    order: Vec<i8>,
    /// The planes that may continue into the hole (bit set): after `refit_near`, those with
    /// pixels of their own around that part of the hole.
    present: u32,
    /// Plausible disparities (from the band): a plane continued beyond them is not used.
    lo: f64,
    hi: f64,
}

impl Surfaces {
    /// The visible plane at pixel `i` and its disparity.
    pub fn visible(&self, i: usize, w: usize) -> Option<(usize, f64)> {
        self.visible_among(i, w, u32::MAX)
    }

    /// The visible plane at pixel `i` among the planes in the bit set `candidates`.
    pub fn visible_among(&self, i: usize, w: usize, candidates: u32) -> Option<(usize, f64)> {
        let (x, y) = center(i, w);
        let mut best: Option<(usize, f64)> = None;
        let candidates = candidates & self.present;
        for (s, p) in self.planes.iter().enumerate().filter(|(s, _)| candidates & (1 << s) != 0) {
            let d = p.disparity(x, y);
            if !(d >= self.lo && d <= self.hi) {
                continue;
            }
            let better = match best {
                None => true,
                Some((b, bd)) => (d > bd) == self.nearer_shown(s, b),
            };
            if better {
                best = Some((s, d));
            }
        }
        best
    }

    /// The planes (bit set) that lie behind `front` (the removed objects' depth per pixel, if
    /// known) at pixel `i`, within BEHIND_TOLERANCE; every plane where it is unknown or not
    /// positive. A removed object hid only
    /// what lay behind it: a kept object's face flanking the hole, continued as a plane, would
    /// lie in front of it. On the synth room two-of-three a kept cylinder's face continued over
    /// the hole in views 10-15 (10 % of their fill pixels' depth more than 10 % off, the
    /// cylinder's blue pasted over the floor); with this rule 2-5 %. Paired runs (journal,
    /// 2026-11-27): masked PSNR / LPIPS there 25.35 / 0.012 -> 25.48 / 0.012, statue-one 22.12 /
    /// 0.097 -> 22.57 / 0.080, statue-two-of-three 22.84 / 0.053 -> 23.99 / 0.075, the cup
    /// within 0.06 dB.
    pub fn behind(&self, i: usize, w: usize, front: Option<&[f32]>) -> u32 {
        let Some(front) = front.map(|f| f[i]).filter(|&d| d > 0.0 && d.is_finite()) else {
            return u32::MAX;
        };
        let (x, y) = center(i, w);
        let limit = (1.0 + BEHIND_TOLERANCE) / front as f64;
        self.planes.iter().enumerate().filter(|(_, p)| p.disparity(x, y) <= limit).fold(0, |b, (s, _)| b | 1 << s)
    }

    /// Stops the planes that stand in front of the removed objects from continuing into the hole
    /// (`present`): those more than a quarter of whose pixels beside the `hole` (4-neighbours,
    /// on the plane within LABEL_TOLERANCE of their disparity `disp`) are `in_front` of the
    /// objects (`depth::in_front_of_removed`). There the hole's edge is the plane's silhouette
    /// over the objects, not a surface running under or behind them, which meets or passes
    /// behind the objects' depth all along the edge. A kept object's face in front, continued as
    /// a plane, may still pass behind the objects where it tilts away (`behind` lets it in
    /// there): on the statue at 504x378 the statue's plane (a third to nine tenths of its pixels
    /// beside the hole in front of the box) took crosses and bars of the lawn's hole between its
    /// flanks in 9 of 25 views, and the exemplar filled them with the statue's bronze.
    pub fn stop_in_front(&mut self, disp: &[f32], in_front: &[bool], hole: &[bool], w: usize) {
        let n = self.planes.len().min(32);
        let (mut edge, mut front) = (vec![0usize; n], vec![0usize; n]);
        for q in beside_pixels(hole, w) {
            if let Some(s) = self.member_within(q, w, disp[q] as f64, LABEL_TOLERANCE) {
                if s < n {
                    edge[s] += 1;
                    front[s] += in_front[q] as usize;
                }
            }
        }
        for s in (0..n).filter(|&s| 4 * front[s] > edge[s]) {
            self.present &= !(1 << s);
        }
    }

    /// Whether plane `s` may continue into the hole (`present`; see `stop_in_front`).
    pub fn continues(&self, s: usize) -> bool {
        s < 32 && self.present & (1 << s) != 0
    }

    /// Whether, where planes `s` and `t` overlap, the nearer of them is shown.
    pub fn nearer_shown(&self, s: usize, t: usize) -> bool {
        self.order.get(s * self.planes.len() + t) != Some(&-1)
    }

    /// The pairwise `order` the band's `members` (pixel, plane it lies on) show: for each pixel
    /// and each other plane plausible there and with pixels of its own nearby (`support`), whether
    /// the pixel's own plane is the nearer one. A pair takes the order at least 80 % of its votes
    /// agree on.
    fn pair_orders(&self, members: &[(usize, usize)], support: &[u32], disp: &[f32], w: usize) -> Vec<i8> {
        let n = self.planes.len();
        let mut nearer = vec![[0usize; 2]; n * n];
        for &(i, m) in members {
            let (x, y) = center(i, w);
            let own = disp[i] as f64;
            for (k, p) in self.planes.iter().enumerate().filter(|&(k, _)| k != m && support[i] & (1 << k) != 0) {
                let d = p.disparity(x, y);
                if d >= self.lo && d <= self.hi {
                    let vote = (own > d) as usize;
                    nearer[m * n + k][vote] += 1;
                    nearer[k * n + m][vote] += 1;
                }
            }
        }
        nearer
            .iter()
            .map(|&[far, near]| {
                let all = (far + near).max(1) as f64;
                if near as f64 >= 0.8 * all && near >= 4 {
                    1
                } else if far as f64 >= 0.8 * all && far >= 4 {
                    -1
                } else {
                    0
                }
            })
            .collect()
    }

    /// A plane whose own pixels (`members`) lie, at their median, within twice PLANE_TOLERANCE of
    /// a plane with at least as many pixels.
    fn redundant(&self, members: &[(usize, usize)], disp: &[f32], w: usize) -> Option<usize> {
        let count = |k: usize| members.iter().filter(|m| m.1 == k).count();
        let n = self.planes.len();
        (0..n).find(|&k| {
            (0..n).filter(|&j| j != k && count(j) >= count(k)).any(|j| {
                let mut r: Vec<f64> = members
                    .iter()
                    .filter(|m| m.1 == k)
                    .map(|&(i, _)| self.planes[j].residual(i, w, disp[i] as f64))
                    .collect();
                if r.is_empty() {
                    return true;
                }
                r.sort_by(f64::total_cmp);
                r[r.len() / 2] < 2.0 * PLANE_TOLERANCE
            })
        })
    }

    /// A plane with less than SMALL_PLANE_SHARE of the `band` pixels that holds less than
    /// SMALL_PLANE_RIM_SHARE of the hole's `rim`: it does not run into the hole.
    fn detached(&self, members: &[(usize, usize)], band: usize, rim: &[bool]) -> Option<usize> {
        let rim_pixels = rim.iter().filter(|&&r| r).count() as f64;
        (0..self.planes.len()).find(|&k| {
            let own = members.iter().filter(|m| m.1 == k).count() as f64;
            let touching = members.iter().filter(|m| m.1 == k && rim[m.0]).count() as f64;
            own < SMALL_PLANE_SHARE * band as f64 && touching < SMALL_PLANE_RIM_SHARE * rim_pixels
        })
    }

    /// The plane pixel `i` with disparity `d` lies on (the best fitting within tolerance).
    pub fn member(&self, i: usize, w: usize, d: f64) -> Option<usize> {
        self.member_within(i, w, d, PLANE_TOLERANCE)
    }

    fn member_within(&self, i: usize, w: usize, d: f64, tolerance: f64) -> Option<usize> {
        if d <= 0.0 || !d.is_finite() {
            return None;
        }
        self.planes
            .iter()
            .enumerate()
            .map(|(s, p)| (s, p.residual(i, w, d)))
            .filter(|&(_, r)| r <= tolerance)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(s, _)| s)
    }

    /// `labels`, except that each `fill` pixel takes the plane seen there among those that
    /// flank it (`visible_among`, `flanking`) and lie behind the removed objects (`front`, their
    /// depth per pixel, if known: `behind`): its completed depth blends the plane with the render
    /// near the fill's edge and may lie off it.
    pub fn fill_labels(&self, depth: &[f32], fill: &[bool], front: Option<&[f32]>, w: usize) -> Vec<u8> {
        let mut labels = self.labels(depth, w);
        let flanks = flanking(&self.flank_labels(depth, w), fill, w, labels.len() / w);
        for (i, l) in labels.iter_mut().enumerate().filter(|(i, _)| fill[*i]) {
            *l = self.visible_among(i, w, flanks[i] & self.behind(i, w, front)).map_or(0, |(s, _)| s as u8 + 1);
        }
        labels
    }

    /// These surfaces, each plane refitted to its own pixels in the band around `region` (one
    /// part of a hole): those within LABEL_TOLERANCE of it that fit it best, then three Tukey
    /// reweightings (scale PLANE_TOLERANCE). A plane with fewer than MIN_REFIT_PIXELS of its
    /// pixels in that band does not continue into this part (one piece of a curved wall fitted
    /// around another hole would cover this one's own).
    pub fn refit_near(&self, disp: &[f32], known: &[bool], region: &[bool], w: usize, h: usize) -> Surfaces {
        let in_band = band_around(disp, known, region, w, h);
        let band: Vec<usize> = (0..w * h).filter(|&i| in_band[i]).collect();
        let mut out = self.clone();
        for (s, plane) in out.planes.iter_mut().enumerate() {
            let own: Vec<usize> = band
                .iter()
                .copied()
                .filter(|&i| self.member_within(i, w, disp[i] as f64, LABEL_TOLERANCE) == Some(s))
                .collect();
            if own.len() < MIN_REFIT_PIXELS {
                out.present &= !(1 << s);
                continue;
            }
            let mut fit = *plane;
            for _ in 0..3 {
                match least_squares(&own, disp, w, |i| fit.tukey_weight(i, w, disp[i] as f64)) {
                    Some(p) => fit = p,
                    None => break,
                }
            }
            *plane = fit;
        }
        out
    }

    /// As `labels`, within FLANK_TOLERANCE: which plane a pixel supports as a flank of a hole.
    pub fn flank_labels(&self, depth: &[f32], w: usize) -> Vec<u8> {
        self.labels_within(depth, w, FLANK_TOLERANCE)
    }

    /// Per pixel, 1 + the plane the depth `depth` lies on, or 0.
    pub fn labels(&self, depth: &[f32], w: usize) -> Vec<u8> {
        self.labels_within(depth, w, LABEL_TOLERANCE)
    }

    /// `labels` at the one pixel `i` (row width `w`) whose depth is `depth`.
    pub fn label_at(&self, i: usize, w: usize, depth: f32) -> u8 {
        self.label_within(i, w, depth, LABEL_TOLERANCE)
    }

    /// Per pixel, 1 + the plane within `tolerance` (relative disparity) of the depth, or 0.
    fn labels_within(&self, depth: &[f32], w: usize, tolerance: f64) -> Vec<u8> {
        depth.iter().enumerate().map(|(i, &d)| self.label_within(i, w, d, tolerance)).collect()
    }

    /// `labels_within` at the one pixel `i`.
    fn label_within(&self, i: usize, w: usize, depth: f32, tolerance: f64) -> u8 {
        self.member_within(i, w, 1.0 / depth as f64, tolerance).map_or(0, |s| s as u8 + 1)
    }
}

/// Known pixels looked at beyond the edge of the unknown region, in each direction, and how far
/// (relative disparity) from a plane they may scatter and still continue it into the region:
/// looser than LABEL_TOLERANCE, since it only says whether the plane goes on, not whose colors
/// a pixel takes.
const FLANK_DEPTH: usize = 3;
const FLANK_TOLERANCE: f64 = 0.2;

/// Per `unknown` pixel, the bit set of the planes that flank it (`labels`: 1 + plane of the known
/// pixels, 0 none): a plane whose known pixels lie just beyond the unknown region on both sides
/// along the pixel's row or column, or on one side along each (a corner). A plane continues into
/// a hole between its own pixels, not past them: the side of a statue's pedestal, seen only below
/// the hole, must not cover the lawn above it.
pub fn flanking(labels: &[u8], unknown: &[bool], w: usize, h: usize) -> Vec<u32> {
    let pixels: Vec<usize> = (0..w * h).filter(|&i| unknown[i]).collect();
    let mut out = vec![0u32; w * h];
    for (&i, bits) in pixels.iter().zip(flanking_at(labels, unknown, &pixels, w, h)) {
        out[i] = bits;
    }
    out
}

/// `flanking` of the unknown pixels `pixels` only, in their order.
pub fn flanking_at(labels: &[u8], unknown: &[bool], pixels: &[usize], w: usize, h: usize) -> Vec<u32> {
    // the planes of the first FLANK_DEPTH known pixels from pixel (x, y) stepping (dx, dy)
    let side = |x: usize, y: usize, dx: isize, dy: isize| {
        let (mut x, mut y, mut seen, mut bits) = (x as isize, y as isize, 0, 0u32);
        loop {
            (x, y) = (x + dx, y + dy);
            if x < 0 || y < 0 || x >= w as isize || y >= h as isize || seen == FLANK_DEPTH {
                return bits;
            }
            let i = y as usize * w + x as usize;
            if !unknown[i] {
                seen += 1;
                if labels[i] > 0 {
                    bits |= 1 << (labels[i] - 1);
                }
            }
        }
    };
    pixels
        .iter()
        .map(|&i| {
            let (x, y) = (i % w, i / w);
            let (l, r, u, d) = (side(x, y, -1, 0), side(x, y, 1, 0), side(x, y, 0, -1), side(x, y, 0, 1));
            (l & r) | (u & d) | ((l | r) & (u | d))
        })
        .collect()
}

/// The pixels outside the `hole` beside it (a 4-neighbour in it), row-major; row width `w`. Only
/// the hole's bounding box grown by a pixel can hold them: the depth prior asks this for each
/// part of its unknown region (about 20 per view on the statue `images_2`), where whole-image
/// passes took 19-24 ms of the 60-80 ms its loop over the parts spent per view, 8-9 ms so.
pub fn beside_pixels(hole: &[bool], w: usize) -> Vec<usize> {
    let Some(b) = bounding_box(hole, w) else { return Vec::new() };
    let r = b.grown(1, 1, w, hole.len() / w);
    (0..r.width() * r.height()).map(|k| r.pixel(k, w)).filter(|&q| beside(q, hole, w)).collect()
}

/// Whether pixel `q` lies outside the `hole` beside it (a 4-neighbour in it); row width `w`.
fn beside(q: usize, hole: &[bool], w: usize) -> bool {
    let (x, y, h) = (q % w, q / w, hole.len() / w);
    !hole[q]
        && ((x > 0 && hole[q - 1])
            || (x + 1 < w && hole[q + 1])
            || (y > 0 && hole[q - w])
            || (y + 1 < h && hole[q + w]))
}

/// The band around `hole` whose surfaces continue into it: the known pixels with a finite
/// positive disparity within 0.3 sqrt(hole pixels) of it (4 to 48 pixels).
fn band_around(disp: &[f32], known: &[bool], hole: &[bool], w: usize, h: usize) -> Vec<bool> {
    let near = dilate(hole, w, h, band_radius(hole.iter().filter(|&&m| m).count()));
    (0..w * h).map(|i| known[i] && !hole[i] && near[i] && disp[i] > 0.0 && disp[i].is_finite()).collect()
}

/// The width of the band around a hole of `holes` pixels.
fn band_radius(holes: usize) -> f32 {
    (0.3 * (holes as f32).sqrt()).clamp(4.0, 48.0)
}

/// Finds the surfaces around the `hole` from the disparity `disp` of the `known` pixels within a
/// band around it: up to MAX_PLANES planes of at least 5 % of the band (a bench top entering the
/// hole from one side is that small), a plane dropped when a larger one explains its pixels
/// nearly as well (`redundant`) or when it is small and does not run into the hole (`detached`),
/// then the pairwise visibility order (`pair_orders`), each plane competing only near its own
/// pixels. Planes that this order would show where the band says
/// another surface is are dropped (a plane fitted to a nearby object's face must not cover the
/// hole).
pub fn surfaces_around(disp: &[f32], known: &[bool], hole: &[bool], w: usize, h: usize, seed: u64) -> Surfaces {
    let holes = hole.iter().filter(|&&m| m).count();
    let empty = Surfaces { planes: Vec::new(), order: Vec::new(), present: u32::MAX, lo: 0.0, hi: 0.0 };
    if holes == 0 {
        return empty;
    }
    let band = band_around(disp, known, hole, w, h);
    let in_band: Vec<usize> = (0..w * h).filter(|&i| band[i]).collect();
    if in_band.len() < 12 {
        return empty;
    }
    let min_inliers = (in_band.len() / 20).max(12);
    let planes = fit_planes(disp, &band, w, PLANE_TOLERANCE, MAX_PLANES, min_inliers, seed);
    let (lo, hi) =
        in_band.iter().fold((f64::INFINITY, 0f64), |(lo, hi), &i| (lo.min(disp[i] as f64), hi.max(disp[i] as f64)));
    let mut s = Surfaces { planes, order: Vec::new(), present: u32::MAX, lo: 0.5 * lo, hi: 2.0 * hi };
    let radius = band_radius(holes);
    let rim: Vec<bool> = band.iter().zip(dilate(hole, w, h, RIM_WIDTH)).map(|(&b, near)| b && near).collect();
    loop {
        let members: Vec<(usize, usize)> =
            in_band.iter().filter_map(|&i| s.member(i, w, disp[i] as f64).map(|m| (i, m))).collect();
        // a plane that another, larger one explains nearly as well is a second piece of the same
        // curved surface (a cylindrical wall around two holes): drop it, or the two would compete
        // for the same pixels wherever their pieces are refitted
        if let Some(k) = s.redundant(&members, disp, w) {
            s.planes.remove(k);
            continue;
        }
        if let Some(k) = s.detached(&members, in_band.len(), &rim) {
            s.planes.remove(k);
            continue;
        }
        // a plane competes for a pixel only near its own pixels: planes are finite (a bench's
        // front face does not go on past the bench's end)
        let mut support = vec![0u32; w * h];
        for k in 0..s.planes.len() {
            let mut own = vec![false; w * h];
            members.iter().filter(|m| m.1 == k).for_each(|&(i, _)| own[i] = true);
            for (bits, near) in support.iter_mut().zip(dilate(&own, w, h, radius)) {
                if near {
                    *bits |= 1 << k;
                }
            }
        }
        s.order = s.pair_orders(&members, &support, disp, w);
        // the share of the band pixels each plane is shown at that really lie on it
        let mut shown = vec![0usize; s.planes.len()];
        let mut right = vec![0usize; s.planes.len()];
        for &(i, m) in &members {
            if let Some((v, _)) = s.visible_among(i, w, support[i]) {
                shown[v] += 1;
                right[v] += (v == m) as usize;
            }
        }
        let worst = (0..s.planes.len())
            .filter(|&k| shown[k] > 0)
            .map(|k| (k, right[k] as f64 / shown[k] as f64))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        match worst {
            Some((k, share)) if share < 0.5 => {
                s.planes.remove(k);
                s.order.clear();
            }
            _ => return s,
        }
    }
}

/// The window the built-in inpainters work in: the fill's bounding box grown by its own size (at
/// least 16 pixels) on every side, clamped to the image.
pub fn fill_window(b: Rect, w: usize, h: usize) -> Rect {
    b.grown(b.width().max(16), b.height().max(16), w, h)
}

/// Which known pixels of a surface the membrane of `fill_by_surface` takes as its boundary values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Boundary {
    /// Every one.
    EveryKnownPixel,
    /// Those of the surface's typical colors (`typical_colors`).
    TypicalColors,
}

/// A surface's known pixel is atypical when one of its channels lies more than this many robust
/// standard deviations (1.4826 times the median absolute deviation) from the surface's median.
const ATYPICAL_SIGMAS: f32 = 4.0;
/// Atypical pixels are left out only while they are at most this share of the surface's known
/// pixels: a few stray colors, not one of the colors of a two-tone texture (a checkerboard's,
/// half of them; bricks' mortar). On statue-two-of-three the share of a surface's known pixels
/// that were atypical was 5 % at the median over the views' surfaces, 8 % at the 90th percentile.
const ATYPICAL_SHARE: f32 = 0.15;

/// The `known` pixels of the planar `channels`-channel `image` (n pixels) less the atypical ones
/// (`ATYPICAL_SIGMAS`), where those are at most `ATYPICAL_SHARE` of them.
///
/// A surface's label comes from depth, and the rendered depth at a surface's border can fit its
/// plane where the colors are a nearer object's: the white rim of the statue's pedestal, where it
/// stands on the lawn, took the lawn's label. Texture synthesis picks its patches by similarity
/// and passes them over; a membrane takes its values from the nearest boundary, and a handful of
/// such pixels beside a hole painted a white glow over a third of it. On the real-photo bench the
/// harmonic fill went from 16.88 to 21.53 dB masked PSNR on statue-one and from 19.77 to 22.51 on
/// statue-two-of-three (bench/JOURNAL.md, 2026-12-02).
pub fn typical_colors(image: &[f32], known: &[bool], n: usize, channels: usize) -> Vec<bool> {
    let pixels: Vec<usize> = (0..n).filter(|&p| known[p]).collect();
    if pixels.is_empty() {
        return known.to_vec();
    }
    let median = |v: &mut Vec<f32>| {
        let k = v.len() / 2;
        *v.select_nth_unstable_by(k, |a, b| a.total_cmp(b)).1
    };
    let mut deviation = vec![0.0f32; n];
    for c in 0..channels {
        let plane = &image[c * n..(c + 1) * n];
        let mut values: Vec<f32> = pixels.iter().map(|&p| plane[p]).collect();
        let m = median(&mut values);
        let mut spread: Vec<f32> = values.iter().map(|v| (v - m).abs()).collect();
        let sigma = 1.4826 * median(&mut spread);
        for &p in &pixels {
            let d = (plane[p] - m).abs();
            // a constant channel (sigma 0) makes every other value atypical, and the share decides
            let z = if d == 0.0 { 0.0 } else { d / sigma };
            deviation[p] = deviation[p].max(z);
        }
    }
    let atypical = pixels.iter().filter(|&&p| deviation[p] > ATYPICAL_SIGMAS).count();
    if atypical == 0 || atypical as f32 > ATYPICAL_SHARE * pixels.len() as f32 {
        return known.to_vec();
    }
    (0..n).map(|p| known[p] && deviation[p] <= ATYPICAL_SIGMAS).collect()
}

/// Fills the `fill` pixels of the planar `channels`-channel `image` (w x h): a pixel labelled with
/// surface s (`labels`, 0 = none) takes the harmonic interpolant of the known pixels of surface s
/// only (those `boundary` keeps); unlabelled ones that of all known pixels. Worked in a window
/// around the fill (`fill_window`).
pub fn fill_by_surface(
    image: &[f32],
    fill: &[bool],
    labels: &[u8],
    w: usize,
    h: usize,
    channels: usize,
    boundary: Boundary,
) -> Vec<f32> {
    fill_by_surface_within(image, fill, labels, (w, h), channels, boundary, SurfaceWindow::Fill)
}

/// Where `fill_by_surface_within` solves each surface's membrane.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SurfaceWindow {
    /// `fill_window`: the fill's bounding box grown by its own size.
    Fill,
    /// The fill's bounding box grown by this many pixels: a surface's known pixels farther out
    /// are no boundary values. Where only the fill's edge needs the membrane, this costs a
    /// fraction of the fill window's solve, which spans nine times the box's area, most of it
    /// unknown to any one surface.
    Margin(usize),
}

/// `fill_by_surface` with each surface's membrane solved in `window`.
pub fn fill_by_surface_within(
    image: &[f32],
    fill: &[bool],
    labels: &[u8],
    (w, h): (usize, usize),
    channels: usize,
    boundary: Boundary,
    window: SurfaceWindow,
) -> Vec<f32> {
    let known: Vec<bool> = fill.iter().map(|&m| !m).collect();
    let mut out = harmonic_fill(image, &known, w, h, channels);
    let Some(b) = bounding_box(fill, w) else { return out };
    let win = match window {
        SurfaceWindow::Fill => fill_window(b, w, h),
        SurfaceWindow::Margin(m) => b.grown(m, m, w, h),
    };
    let (cw, ch) = (win.width(), win.height());
    let at = |x: usize, y: usize| (win.y0 + y) * w + win.x0 + x;
    let window = crop(image, w, h, channels, win);
    let surfaces = labels.iter().copied().max().unwrap_or(0);
    for s in 1..=surfaces {
        let targets = (0..cw * ch).filter(|&k| fill[at(k % cw, k / cw)] && labels[at(k % cw, k / cw)] == s).count();
        let known_s: Vec<bool> =
            (0..cw * ch).map(|k| !fill[at(k % cw, k / cw)] && labels[at(k % cw, k / cw)] == s).collect();
        if targets == 0 || !known_s.iter().any(|&k| k) {
            continue;
        }
        let known_s = match boundary {
            Boundary::EveryKnownPixel => known_s,
            Boundary::TypicalColors => typical_colors(&window, &known_s, cw * ch, channels),
        };
        let filled = harmonic_fill(&window, &known_s, cw, ch, channels);
        for k in 0..cw * ch {
            let p = at(k % cw, k / cw);
            if fill[p] && labels[p] == s {
                for c in 0..channels {
                    out[c * w * h + p] = filled[c * cw * ch + k];
                }
            }
        }
    }
    out
}

#[cfg(test)]
#[path = "surfaces_tests.rs"]
mod tests;
