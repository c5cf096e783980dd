//! The built-in texture-synthesizing inpainter, no weights: exemplar inpainting in the manner of
//! Wexler, Shechtman and Irani (2007), with the nearest-neighbour field found by PatchMatch
//! (Barnes et al. 2009), coarse to fine. Every pixel whose 7x7 patch touches the hole keeps the
//! source pixel whose patch (fully known, inside the crop) looks most like its own; each hole pixel
//! becomes the vote of what those patches put on it, and the two steps alternate. The completed
//! depth guides it: a source on another background surface than the target's (the planes of
//! `surfaces.rs`) pays a penalty larger than any color distance, so the floor continues the floor's
//! texture and the wall the wall's; and a source at another distance than the target pays for the
//! log ratio of the two, so that where no plane was found (a lawn) the fill still comes from its
//! own distance, not from a far, blurred background. Matches are translations; on a receding
//! floor the depth term prefers sources at the same distance (the same rows), where the texture
//! has the target's period. The coarsest level starts from the surface-wise harmonic fill.
//! `fill_rectified` goes further where the camera is known: each plane's pixels are synthesized
//! in that plane's own frame (rectify.rs), where the texture has one period everywhere; what is
//! left is synthesized in the image, each surface's regions (a path across a lawn) first continued
//! straight through the hole and each filled from itself (regions.rs).
//!
//! The GPU passes are `exemplar_nnf.comp` (one PatchMatch pass: propagation, random search, a
//! global jump) and `exemplar_vote.comp`; the pyramid and the hand-over between levels are host
//! work on small arrays. Deterministic: randomness is a hash of (seed, pass, pixel) and the
//! field is updated Jacobi-style.

use super::rectify::{rectify, Intrinsics, PlaneFrame};
use super::regions;
use super::surfaces::{self, fill_by_surface, Boundary};
use crate::gpu::{dispatch_1d, Buffer, ComputePipeline, Gpu, Recorder};
use crate::image_ops::{bounding_box, crop};
use crate::planes::Plane;
use crate::rng::Rng;
use crate::shaders;
use anyhow::Result;
use bytemuck::{Pod, Zeroable};

/// Patch radius (7x7 patches); RADIUS in exemplar.glsl.
pub const PATCH_RADIUS: usize = 3;
const HOLE: u32 = 1;
const SOURCE: u32 = 2;
const TARGET: u32 = 4;
/// Added to the patch distance (mean squared RGB difference, at most 1) of a source on another surface.
const LABEL_PENALTY: f32 = 1.0;
/// Added to the patch distance per squared log ratio of the source's and the target's disparity
/// (where both are known): a source at twice or half the target's distance pays 0.05, a large color
/// difference; one 10 % nearer or farther 0.0009, about what a good match differs by in color.
pub const DEPTH_WEIGHT: f32 = 0.1;
/// The vote's weight scale: exp(-(distance - best) / VOTE_SIGMA2). Small enough that only the
/// patches about as good as the best count: on a grainy texture (a lawn) the good patches differ
/// by more than 0.0005, and at that scale their average was a flat blob of the lawn's mean color
/// (the statue's fills on a training of 2026-11-28: masked LPIPS 0.473 at 0.0005, 0.348 here,
/// for 0.2 dB of masked PSNR; the synth rooms within 0.15 dB; journal, 2026-11-28).
const VOTE_SIGMA2: f32 = 0.00005;
/// Search-then-vote rounds on the coarsest level (which finds the layout), on the levels between
/// (which start from the coarser field and only refine it) and on the finest, and the
/// propagation steps of each round's passes. The finest level holds about two thirds of all
/// targets, and its field arrives refined twice already: a second round there cost the statue
/// `images_2` 2.4 s of its 7.8 s transfer stage and moved no bench set by more than 0.05 dB
/// masked PSNR or 0.002 LPIPS (journal, 2026-11-28). One round on the levels between cost synth
/// 0.15 dB and statue-two-of-three 0.014 LPIPS; three on the coarsest left a blob in the statue's
/// lawn (LPIPS 0.050 -> 0.155).
const ROUNDS_COARSEST: usize = 5;
const ROUNDS_FINER: usize = 2;
const ROUNDS_FINEST: usize = 1;
/// The random search's largest radius on the finer levels (the coarsest searches half its crop).
const FINER_RADIUS: u32 = 8;
const STEPS: [u32; 3] = [4, 2, 1];
/// The coarsest level: the hole's box at most this many pixels across.
const COARSEST_HOLE: usize = 12;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ExemplarPush {
    image: u64,
    info: u64,
    nnf_in: u64,
    dist_in: u64,
    nnf_out: u64,
    dist_out: u64,
    targets: u64,
    sources: u64,
    count: u32,
    num_sources: u32,
    width: u32,
    height: u32,
    step: u32,
    seed: u32,
    radius: u32,
    label_penalty: f32,
    depth_weight: f32,
    /// 1 where dist_in holds every target's distance to its nnf_in source on the current image.
    dist_known: u32,
    disparity: u64,
    packed: u64,
}

/// One level of the pyramid over the crop around the hole.
#[derive(Clone)]
struct Level {
    w: usize,
    h: usize,
    /// Planar RGB; hole pixels hold the current estimate.
    image: Vec<f32>,
    hole: Vec<bool>,
    /// Known pixels no source patch may contain.
    avoid: Vec<bool>,
    labels: Vec<u8>,
    /// 1 / depth per pixel (the hole's completed depth); 0 = unknown, or no depth guidance at all.
    disparity: Vec<f32>,
}

impl Level {
    /// HOLE / SOURCE / TARGET bits and the surface label (bits 8..15) of every pixel.
    fn info(&self) -> Vec<u32> {
        let (w, h, r) = (self.w, self.h, PATCH_RADIUS as isize);
        // summed-area tables answer "any hole (avoided) pixel in this window" in O(1)
        let table = |mask: &dyn Fn(usize) -> bool| {
            let mut sat = vec![0u32; (w + 1) * (h + 1)];
            for y in 0..h {
                for x in 0..w {
                    sat[(y + 1) * (w + 1) + x + 1] =
                        mask(y * w + x) as u32 + sat[y * (w + 1) + x + 1] + sat[(y + 1) * (w + 1) + x]
                            - sat[y * (w + 1) + x];
                }
            }
            sat
        };
        let (holes, unusable) = (table(&|i| self.hole[i]), table(&|i| self.hole[i] || self.avoid[i]));
        let count = |sat: &[u32], x0: isize, y0: isize, x1: isize, y1: isize| {
            let (x0, y0) = (x0.max(0) as usize, y0.max(0) as usize);
            let (x1, y1) = ((x1.min(w as isize - 1) + 1) as usize, (y1.min(h as isize - 1) + 1) as usize);
            sat[y1 * (w + 1) + x1] + sat[y0 * (w + 1) + x0] - sat[y0 * (w + 1) + x1] - sat[y1 * (w + 1) + x0]
        };
        (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as isize, (i / w) as isize);
                let inside = x >= r && y >= r && x + r < w as isize && y + r < h as isize;
                let touched = count(&holes, x - r, y - r, x + r, y + r) > 0;
                let usable = count(&unusable, x - r, y - r, x + r, y + r) == 0;
                let mut bits = (self.labels[i] as u32) << 8;
                if self.hole[i] {
                    bits |= HOLE;
                }
                if inside && usable {
                    bits |= SOURCE;
                }
                if touched {
                    bits |= TARGET;
                }
                bits
            })
            .collect()
    }

    /// The next coarser level: 2x2 blocks; a block is hole if any of its pixels is, its color the
    /// mean of its known pixels, its label its first pixel's.
    fn coarser(&self) -> Level {
        let (w, h) = (self.w.div_ceil(2), self.h.div_ceil(2));
        let (n, fine_n) = (w * h, self.w * self.h);
        let mut out = Level {
            w,
            h,
            image: vec![0.0; 3 * n],
            hole: vec![false; n],
            avoid: vec![false; n],
            labels: vec![0; n],
            disparity: if self.disparity.is_empty() { Vec::new() } else { vec![0.0; n] },
        };
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                let (mut known, mut with_depth) = (0, 0);
                for (fx, fy) in [(2 * x, 2 * y), (2 * x + 1, 2 * y), (2 * x, 2 * y + 1), (2 * x + 1, 2 * y + 1)] {
                    if fx >= self.w || fy >= self.h {
                        continue;
                    }
                    let f = fy * self.w + fx;
                    if let Some(&d) = self.disparity.get(f).filter(|&&d| d > 0.0) {
                        out.disparity[i] += d;
                        with_depth += 1;
                    }
                    out.hole[i] |= self.hole[f];
                    out.avoid[i] |= self.avoid[f];
                    if !self.hole[f] {
                        known += 1;
                        for c in 0..3 {
                            out.image[c * n + i] += self.image[c * fine_n + f];
                        }
                    }
                }
                for c in 0..3 {
                    out.image[c * n + i] /= known.max(1) as f32;
                }
                if with_depth > 0 {
                    out.disparity[i] /= with_depth as f32;
                }
                out.labels[i] = self.labels[2 * y * self.w + 2 * x];
            }
        }
        out
    }

    fn hole_extent(&self) -> usize {
        bounding_box(&self.hole, self.w).map_or(0, |r| r.width().max(r.height()))
    }
}

pub struct ExemplarFill {
    gpu: Gpu,
    nnf: ComputePipeline,
    vote: ComputePipeline,
    seed: u64,
}

/// What `fill_rectified` made: the filled image (planar RGB), and per surface label (1 + the
/// plane's index; 0 and planes it could not rectify: false) whether the plane's known texture
/// repeats (`rectify::Rectified::repeats`), which tells a continuation in phase with the truth
/// from a random copy (invention_contrast.rs).
pub struct RectifiedFill {
    pub rgb: Vec<f32>,
    pub repeats: [bool; 256],
}

impl ExemplarFill {
    pub fn new(gpu: &Gpu, seed: u64) -> Result<ExemplarFill> {
        Ok(ExemplarFill {
            gpu: gpu.clone(),
            nnf: ComputePipeline::new(gpu, "exemplar_nnf", shaders::EXEMPLAR_NNF)?,
            vote: ComputePipeline::new(gpu, "exemplar_vote", shaders::EXEMPLAR_VOTE)?,
            seed,
        })
    }

    /// Fills the `fill` pixels of the planar RGB `image` (w x h) with texture from the rest of the
    /// image around the hole; `labels` (0 = none) keep each surface's pixels on that surface.
    /// Pixels outside `fill` are returned unchanged.
    pub fn fill(&self, image: &[f32], fill: &[bool], labels: &[u8], w: usize, h: usize) -> Result<Vec<f32>> {
        self.fill_avoiding(image, fill, &vec![false; w * h], labels, None, w, h)
    }

    /// `fill_avoiding`, with the pixels of each background plane (label 1 + its index in
    /// `planes`, seen through `k`) synthesized in the plane's rectified frame from that plane's
    /// known pixels, so that a receding checkerboard keeps its period and phase. Pixels no plane
    /// takes (label 0, off their plane, or a plane whose grid has fewer source patches than hole
    /// texels) are synthesized in the image afterwards, with the planes' results as known pixels
    /// and `disparity` guiding them (`fill_avoiding`).
    #[allow(clippy::too_many_arguments)]
    pub fn fill_rectified(
        &self,
        image: &[f32],
        fill: &[bool],
        avoid: &[bool],
        labels: &[u8],
        disparity: Option<&[f32]>,
        planes: &[Plane],
        k: &Intrinsics,
        w: usize,
        h: usize,
    ) -> Result<RectifiedFill> {
        let mut out = image.to_vec();
        let mut rest = fill.to_vec();
        let mut repeats = [false; 256];
        for (s, plane) in planes.iter().enumerate().take(u8::MAX as usize) {
            let label = s as u8 + 1;
            let Some(frame) = PlaneFrame::new(plane, k) else { continue };
            let Some(grid) = rectify(&frame, image, fill, avoid, labels, label, w, h) else { continue };
            repeats[label as usize] = grid.repeats;
            let level = Level {
                w: grid.w,
                h: grid.h,
                image: Vec::new(),
                hole: grid.hole.clone(),
                avoid: grid.avoid.clone(),
                labels: grid.labels.clone(),
                disparity: Vec::new(),
            };
            let sources = level.info().iter().filter(|&&bits| bits & SOURCE != 0).count();
            if sources < grid.hole.iter().filter(|&&x| x).count() {
                // the plane's known pixels are too few or too scattered (its depth too noisy for
                // membership) to lend whole patches: the image-space synthesis below does better
                continue;
            }
            // every texel of the grid lies on the plane: no depth to tell surfaces apart
            let filled =
                self.fill_avoiding(&grid.image, &grid.hole, &grid.avoid, &grid.labels, None, grid.w, grid.h)?;
            let written = grid.write_back(&filled, &mut out, fill, labels, label, w, h);
            for (r, &done) in rest.iter_mut().zip(&written) {
                *r &= !done;
            }
        }
        if rest.iter().any(|&r| r) {
            // structure first here too: each surface's regions continued through what is left
            let split = regions::split_surfaces(&out, &rest, avoid, labels, &repeats, w, h);
            out = self.fill_avoiding(&out, &rest, avoid, &split, disparity, w, h)?;
        }
        Ok(RectifiedFill { rgb: out, repeats })
    }

    /// `fill`, taking no source patch that contains an `avoid` pixel: those stay as they are and
    /// still count in the patch distance of targets around them, but their texture is not copied.
    /// With `disparity` (1 / depth per pixel, the hole's completed; 0 = unknown) a source pays
    /// DEPTH_WEIGHT per squared log ratio of its disparity to the target's.
    #[allow(clippy::too_many_arguments)]
    pub fn fill_avoiding(
        &self,
        image: &[f32],
        fill: &[bool],
        avoid: &[bool],
        labels: &[u8],
        disparity: Option<&[f32]>,
        w: usize,
        h: usize,
    ) -> Result<Vec<f32>> {
        let mut out = image.to_vec();
        let Some(b) = bounding_box(fill, w) else { return Ok(out) };
        let win = surfaces::fill_window(b, w, h);
        let (cw, ch) = (win.width(), win.height());
        let at = |k: usize| win.pixel(k, w);
        let mut levels = vec![Level {
            w: cw,
            h: ch,
            image: crop(image, w, h, 3, win),
            hole: crop(fill, w, h, 1, win),
            avoid: crop(avoid, w, h, 1, win),
            labels: crop(labels, w, h, 1, win),
            disparity: disparity.map_or(Vec::new(), |d| crop(d, w, h, 1, win)),
        }];
        loop {
            let last = levels.last().unwrap();
            if last.hole_extent() <= COARSEST_HOLE || last.w.min(last.h) / 2 < 4 * PATCH_RADIUS + 2 {
                break;
            }
            let next = last.coarser();
            levels.push(next);
        }
        // the coarsest level starts from the surface-wise harmonic fill and a random field
        let coarsest = levels.last_mut().unwrap();
        // (avoided pixels are no boundary value either: the leftover's color would tint the hole)
        let unknown: Vec<bool> = coarsest.hole.iter().zip(&coarsest.avoid).map(|(&h, &a)| h || a).collect();
        // (every known pixel: it only starts the search, which then picks patches by similarity)
        let smooth = fill_by_surface(
            &coarsest.image,
            &unknown,
            &coarsest.labels,
            coarsest.w,
            coarsest.h,
            3,
            Boundary::EveryKnownPixel,
        );
        let n = coarsest.w * coarsest.h;
        for i in (0..n).filter(|&i| coarsest.hole[i]) {
            for c in 0..3 {
                coarsest.image[c * n + i] = smooth[c * n + i];
            }
        }
        let mut rng = Rng::new(self.seed ^ 0x5eed_e8e3);
        let mut field: Option<(Vec<u32>, usize)> = None; // the coarser level's field and width
        let mut synthesized = false;
        for li in (0..levels.len()).rev() {
            let level = &mut levels[li];
            let info = level.info();
            let sources: Vec<u32> = (0..info.len() as u32).filter(|&i| info[i as usize] & SOURCE != 0).collect();
            if sources.is_empty() {
                continue; // no fully known patch at this size: keep the estimate from below
            }
            let nnf = initial_field(level, &info, &sources, field.as_ref(), &mut rng);
            let coarsest = field.is_none();
            let rounds = match (coarsest, li) {
                (true, _) => ROUNDS_COARSEST,
                (false, 0) => ROUNDS_FINEST,
                (false, _) => ROUNDS_FINER,
            };
            let (image, nnf) = self.run_level(level, &info, &sources, nnf, coarsest, rounds)?;
            level.image = image;
            field = Some((nnf, level.w));
            synthesized = true;
            if li > 0 {
                // the finer level's hole starts from this level's estimate, upsampled
                let (fw, fh, lw) = (levels[li - 1].w, levels[li - 1].h, levels[li].w);
                let (fine_n, n) = (fw * fh, lw * levels[li].h);
                let coarse = levels[li].image.clone();
                let fine = &mut levels[li - 1];
                for f in (0..fine_n).filter(|&f| fine.hole[f]) {
                    let i = (f / fw / 2) * lw + (f % fw) / 2;
                    for c in 0..3 {
                        fine.image[c * fine_n + f] = coarse[c * n + i];
                    }
                }
            }
        }
        if !synthesized {
            // no fully known patch at any size (a hole filling its crop): the smooth fill
            return Ok(fill_by_surface(image, fill, labels, w, h, 3, Boundary::EveryKnownPixel));
        }
        let level0 = &levels[0];
        for k in (0..cw * ch).filter(|&k| level0.hole[k]) {
            for c in 0..3 {
                out[c * w * h + at(k)] = level0.image[c * cw * ch + k];
            }
        }
        Ok(out)
    }

    /// `rounds` of (PatchMatch passes, vote) on one level; returns its image and field.
    fn run_level(
        &self,
        level: &Level,
        info: &[u32],
        sources: &[u32],
        nnf: Vec<u32>,
        coarsest: bool,
        rounds: usize,
    ) -> Result<(Vec<f32>, Vec<u32>)> {
        let gpu = &self.gpu;
        let n = level.w * level.h;
        let targets: Vec<u32> = (0..n as u32).filter(|&i| info[i as usize] & TARGET != 0).collect();
        let holes: Vec<u32> = (0..n as u32).filter(|&i| info[i as usize] & HOLE != 0).collect();
        let image = Buffer::from_slice(gpu, "exemplar image", &level.image)?;
        let info_b = Buffer::from_slice(gpu, "exemplar info", info)?;
        let fields =
            [Buffer::from_slice(gpu, "exemplar field", &nnf)?, Buffer::from_slice(gpu, "exemplar field", &nnf)?];
        let zeros = vec![0f32; n];
        let dists = [
            Buffer::from_slice(gpu, "exemplar distance", &zeros)?,
            Buffer::from_slice(gpu, "exemplar distance", &zeros)?,
        ];
        let targets_b = Buffer::from_slice(gpu, "exemplar targets", &targets)?;
        let holes_b = Buffer::from_slice(gpu, "exemplar holes", &holes)?;
        let sources_b = Buffer::from_slice(gpu, "exemplar sources", sources)?;
        let packed = Buffer::from_slice(gpu, "exemplar packed image", &pack_rgb(&level.image, n))?;
        let disparity = match level.disparity.is_empty() {
            true => None,
            false => Some(Buffer::from_slice(gpu, "exemplar disparity", &level.disparity)?),
        };
        let push =
            |from: usize, list: &Buffer, count: usize, step: u32, seed: u32, scale: f32, known: bool| ExemplarPush {
                image: image.address(),
                info: info_b.address(),
                nnf_in: fields[from].address(),
                dist_in: dists[from].address(),
                nnf_out: fields[1 - from].address(),
                dist_out: dists[1 - from].address(),
                targets: list.address(),
                sources: sources_b.address(),
                count: count as u32,
                num_sources: sources.len() as u32,
                width: level.w as u32,
                height: level.h as u32,
                step,
                seed,
                radius: if coarsest { level.w.max(level.h) as u32 / 2 } else { FINER_RADIUS },
                label_penalty: scale,
                depth_weight: if disparity.is_some() { DEPTH_WEIGHT } else { 0.0 },
                dist_known: known as u32,
                disparity: disparity.as_ref().map_or(0, |b| b.address()),
                packed: packed.address(),
            };
        let mut rec = Recorder::new(gpu)?;
        let mut current = 0;
        if !coarsest {
            // the upsampled field votes the first estimate of this level (all distances 0: equal weights)
            rec.dispatch(
                &self.vote,
                &push(current, &holes_b, holes.len(), 0, 0, VOTE_SIGMA2, false),
                dispatch_1d(holes.len().div_ceil(64) as u32),
            );
        }
        let mut pass = 0u64;
        for _ in 0..rounds {
            for (pass_in_round, &step) in STEPS.iter().enumerate() {
                // the pass's hash seed: the run's seed folded to 32 bits, mixed with the pass number
                let pass32 = pass as u32;
                let seed =
                    (self.seed as u32 ^ (pass32 << 20)) ^ (self.seed >> 32) as u32 ^ pass32.wrapping_mul(0x9e37_79b9);
                rec.dispatch(
                    &self.nnf,
                    &push(current, &targets_b, targets.len(), step, seed, LABEL_PENALTY, pass_in_round > 0),
                    dispatch_1d(targets.len().div_ceil(64) as u32),
                );
                current = 1 - current;
                pass += 1;
            }
            rec.dispatch(
                &self.vote,
                &push(current, &holes_b, holes.len(), 0, 0, VOTE_SIGMA2, false),
                dispatch_1d(holes.len().div_ceil(64) as u32),
            );
        }
        rec.submit_and_wait()?;
        Ok((image.download(gpu, 3 * n)?, fields[current].download(gpu, n)?))
    }
}

/// The planar RGB `image` of `n` pixels as exemplar.glsl's pack_rgb words.
fn pack_rgb(image: &[f32], n: usize) -> Vec<u32> {
    let q = |v: f32| (v.clamp(0.0, 1.0) * 1023.0).round_ties_even() as u32;
    (0..n).map(|i| q(image[i]) | q(image[n + i]) << 10 | q(image[2 * n + i]) << 20).collect()
}

/// The first field of a level: from the coarser level's field (a source at coarse (sx, sy) maps
/// to fine (2 sx, 2 sy) plus the target's own parity) where that is a source here, else a random
/// source, of the target's surface where there is one.
fn initial_field(
    level: &Level,
    info: &[u32],
    sources: &[u32],
    coarser: Option<&(Vec<u32>, usize)>,
    rng: &mut Rng,
) -> Vec<u32> {
    let w = level.w;
    let mut by_label: Vec<Vec<u32>> = vec![Vec::new(); 256];
    for &s in sources {
        by_label[level.labels[s as usize] as usize].push(s);
    }
    let pick = |label: u8, rng: &mut Rng| {
        let same = &by_label[label as usize];
        let from = if label != 0 && !same.is_empty() { same } else { sources };
        from[(rng.next_u64() % from.len() as u64) as usize]
    };
    (0..info.len())
        .map(|i| {
            if info[i] & TARGET == 0 {
                return sources[0];
            }
            if let Some((field, cw)) = coarser {
                let (x, y) = (i % w, i / w);
                let c = (y / 2) * cw + x / 2;
                if c < field.len() {
                    let s = field[c] as usize;
                    let (sx, sy) = (2 * (s % cw) + x % 2, 2 * (s / cw) + y % 2);
                    if sx < w && sy < level.h && info[sy * w + sx] & SOURCE != 0 {
                        return (sy * w + sx) as u32;
                    }
                }
            }
            pick(level.labels[i], rng)
        })
        .collect()
}
