//! Harmonic filling: the smooth interpolant of known pixels over unknown ones, the built-in
//! inpainter's fill and the completion of depth inside a hole.

/// Fills the pixels where `known` is false with the harmonic interpolant of the known ones (the
/// solution of Laplace's equation with the known pixels as boundary values), for each of `channels`
/// planes. Solved coarse to fine: each level is initialized from the next coarser one and then
/// solved by multigrid V-cycles (red-black Gauss-Seidel smoothing), to a largest change of 1e-6 per
/// sweep.
/// Affine functions are harmonic, so affine data are reproduced exactly (inverse depth of a plane,
/// a linear color ramp).
/// Unknown pixels with no known pixel at all get 0. Deterministic.
pub fn harmonic_fill(values: &[f32], known: &[bool], w: usize, h: usize, channels: usize) -> Vec<f32> {
    let mut out = values.to_vec();
    if known.iter().all(|&k| k) {
        return out;
    }
    if !known.iter().any(|&k| k) {
        for (i, v) in out.iter_mut().enumerate() {
            if !known[i % (w * h)] {
                *v = 0.0;
            }
        }
        return out;
    }
    // the grids depend on the mask alone: built once, shared by the planes
    let pyramid = Pyramid::new(known, w, h);
    // the planes are independent: one thread each (the result does not depend on the threads)
    std::thread::scope(|scope| {
        let pyramid = &pyramid;
        let jobs: Vec<_> = out
            .chunks_mut(w * h)
            .take(channels)
            .map(|plane| {
                scope.spawn(move || {
                    let filled = pyramid.fill(plane, 0);
                    plane.copy_from_slice(&filled);
                })
            })
            .collect();
        for job in jobs {
            job.join().expect("harmonic fill thread panicked");
        }
    });
    out
}

/// An unknown pixel and the indices of its neighbours inside the image.
struct Stencil {
    at: u32,
    neighbours: [u32; 4],
    count: u32,
}

/// One level of the masked Laplace problem: for each unknown pixel i, the sum over its in-image
/// neighbours j of (x_j - x_i) equals b_i (0 on the finest level); known pixels hold their values
/// (the data on the finest level, a zero correction on the coarser ones). The image border is a
/// mirror (Neumann): a pixel there has fewer neighbours.
struct Level {
    w: usize,
    h: usize,
    /// each unknown pixel with its in-image neighbours, gathered once: the sweeps are the whole
    /// cost, and a division per pixel for its coordinates was most of theirs. The red pixels
    /// ((x + y) even) come first, then the black ones: a sweep in this order is red-black
    /// Gauss-Seidel, whose pixels within a colour do not wait on each other (in raster order each
    /// waited on its left neighbour's new value, a chain of dependent adds). On the statue
    /// `images_2` the finest stages' 1131 solves took 6.7 s of the cores' time, not 13.4 s, in as
    /// many V-cycles (7.35 against 7.47 on average).
    stencils: Vec<Stencil>,
}

/// The in-image 4-neighbours of pixel i of a w x h image, in the order left, right, up, down.
fn neighbours(i: usize, w: usize, h: usize) -> impl Iterator<Item = usize> {
    let (x, y) = (i % w, i / w);
    [(x > 0, i.wrapping_sub(1)), (x + 1 < w, i + 1), (y > 0, i.wrapping_sub(w)), (y + 1 < h, i + w)]
        .into_iter()
        .filter_map(|(inside, j)| inside.then_some(j))
}

impl Level {
    fn new(unknown: &[bool], w: usize, h: usize) -> Level {
        let red = |i: usize| (i % w + i / w).is_multiple_of(2);
        let stencils = (0..w * h)
            .filter(|&i| unknown[i] && red(i))
            .chain((0..w * h).filter(|&i| unknown[i] && !red(i)))
            .map(|i| {
                let mut s = Stencil { at: i as u32, neighbours: [0; 4], count: 0 };
                for j in neighbours(i, w, h) {
                    s.neighbours[s.count as usize] = j as u32;
                    s.count += 1;
                }
                s
            })
            .collect();
        Level { w, h, stencils }
    }

    /// One red-black Gauss-Seidel sweep (`stencils`; neighbours summed left, right, up, down); the
    /// largest change.
    fn sweep(&self, x: &mut [f64], b: &[f64]) -> f64 {
        let mut change = 0f64;
        for s in &self.stencils {
            let i = s.at as usize;
            let mut sum = 0f64;
            for &j in &s.neighbours[..s.count as usize] {
                sum += x[j as usize];
            }
            // a quarter is the same number as the division by 4 exactly (a power of two), and
            // cheaper; the pixels with fewer neighbours are the border's few
            let new = if s.count == 4 { (sum - b[i]) * 0.25 } else { (sum - b[i]) / s.count as f64 };
            change = change.max((new - x[i]).abs());
            x[i] = new;
        }
        change
    }

    /// b - A x at the unknown pixels, into `r` (its other entries untouched).
    fn residual(&self, x: &[f64], b: &[f64], r: &mut [f64]) {
        for s in &self.stencils {
            let i = s.at as usize;
            let sum: f64 = s.neighbours[..s.count as usize].iter().map(|&j| x[j as usize] - x[i]).sum();
            r[i] = b[i] - sum;
        }
    }

    /// The next coarser level, or None when this one is small enough to solve by sweeps alone.
    /// A 2x2 block is unknown only if all four of its pixels are (those past the image's edge
    /// count as unknown): a block that held a known pixel and went free would let the coarse
    /// correction float away from that pixel's value, and along a thin unknown strip (one pixel
    /// wide beside known ones) the corrections overshot until the cup's fills diverged. Pixels
    /// by the known ones are left to the sweeps, which settle them quickly.
    fn coarser(&self, unknown: &[bool]) -> Option<(Level, Vec<bool>)> {
        if self.w <= 8 || self.h <= 8 {
            return None;
        }
        let (cw, ch) = (self.w.div_ceil(2), self.h.div_ceil(2));
        let coarse: Vec<bool> = (0..cw * ch)
            .map(|c| {
                let (cx, cy) = (c % cw, c / cw);
                [(0, 0), (1, 0), (0, 1), (1, 1)].iter().all(|&(dx, dy)| {
                    let (x, y) = (2 * cx + dx, 2 * cy + dy);
                    x >= self.w || y >= self.h || unknown[y * self.w + x]
                })
            })
            .collect();
        Some((Level::new(&coarse, cw, ch), coarse))
    }

    /// The coarse correction's value at fine pixel i: bilinear between the centers of the four
    /// nearest coarse blocks (weights 9, 3, 3, 1 sixteenths), each clamped into the coarse grid.
    fn prolong(&self, coarse: &[f64], cw: usize, ch: usize, i: usize) -> f64 {
        let (x, y) = (i % self.w, i / self.w);
        let (cx, cy) = (x / 2, y / 2);
        // the neighbouring block on the side of the pixel within its block
        let nx = if x % 2 == 0 { cx.saturating_sub(1) } else { (cx + 1).min(cw - 1) };
        let ny = if y % 2 == 0 { cy.saturating_sub(1) } else { (cy + 1).min(ch - 1) };
        let at = |x: usize, y: usize| coarse[y * cw + x];
        (9.0 * at(cx, cy) + 3.0 * at(nx, cy) + 3.0 * at(cx, ny) + at(nx, ny)) / 16.0
    }
}

/// Gauss-Seidel sweeps before and after each coarse correction.
const SMOOTHING_SWEEPS: usize = 2;
/// V-cycles at most; they stop earlier once a sweep changes no pixel by more than TOLERANCE.
const MAX_CYCLES: usize = 60;
const TOLERANCE: f64 = 1e-6;
/// The coarsest level (at most 8 pixels across one way) is swept until it changes by less than
/// a hundredth of TOLERANCE, at most this many times.
const COARSEST_SWEEPS: usize = 1000;

/// A V-cycle's work space for one level and the next coarser one: the level's residual, its sums
/// over the blocks (the coarser level's right-hand side) and the coarser level's correction.
/// Reused from cycle to cycle: fresh zeroed images each cycle showed as the kernel clearing pages
/// (5 % of a `--no-refine` statue removal's samples, beside the sweeps' 27 %).
struct Scratch {
    residual: Vec<f64>,
    rhs: Vec<f64>,
    correction: Vec<f64>,
}

/// One V-cycle on `levels[0]` for A x = b: smooth, solve the residual's equation on the coarser
/// level (the residual summed over each block: the stencil there spans twice the distance, so
/// it is four times the fine one's), add the correction, smooth again. `scratch[k]` is the work
/// space of `levels[k]` and `levels[k + 1]`. Returns the last sweep's largest change.
fn v_cycle(levels: &[Level], scratch: &mut [Scratch], x: &mut [f64], b: &[f64]) -> f64 {
    let level = &levels[0];
    let Some(coarse) = levels.get(1) else {
        let mut change = 0.0;
        for _ in 0..COARSEST_SWEEPS {
            change = level.sweep(x, b);
            if change < TOLERANCE * 1e-2 {
                break;
            }
        }
        return change;
    };
    for _ in 0..SMOOTHING_SWEEPS {
        level.sweep(x, b);
    }
    let (Scratch { residual: r, rhs: cb, correction: e }, below) = scratch.split_first_mut().unwrap();
    // (only the unknown pixels' entries of the residual are written and read)
    level.residual(x, b, r);
    cb.fill(0.0);
    for s in &level.stencils {
        let i = s.at as usize;
        cb[(i / level.w / 2) * coarse.w + (i % level.w) / 2] += r[i];
    }
    // (a known block's entry is never read: its correction stays 0)
    e.fill(0.0);
    v_cycle(&levels[1..], below, e, cb);
    for s in &level.stencils {
        let i = s.at as usize;
        x[i] += level.prolong(e, coarse.w, coarse.h, i);
    }
    let mut change = 0.0;
    for _ in 0..SMOOTHING_SWEEPS {
        change = level.sweep(x, b);
    }
    change
}

/// One resolution of the coarse-to-fine solve: its known pixels (at the first, the mask; at each
/// next, the 2x2 blocks that hold a known pixel) and its multigrid levels.
struct Stage {
    w: usize,
    h: usize,
    known: Vec<bool>,
    levels: Vec<Level>,
}

/// The grids of one mask, every stage down to one at most 8 pixels across one way. They depend on
/// the mask alone, so the planes of a fill share them.
struct Pyramid {
    stages: Vec<Stage>,
}

impl Pyramid {
    fn new(known: &[bool], w: usize, h: usize) -> Pyramid {
        let mut stages = vec![Stage::new(known.to_vec(), w, h)];
        loop {
            let last = stages.last().unwrap();
            let (w, h) = (last.w, last.h);
            if w <= 8 || h <= 8 {
                break;
            }
            let (cw, ch) = (w.div_ceil(2), h.div_ceil(2));
            let coarse: Vec<bool> = (0..cw * ch)
                .map(|c| {
                    let (cx, cy) = (c % cw, c / cw);
                    [(0, 0), (1, 0), (0, 1), (1, 1)].iter().any(|&(dx, dy)| {
                        let (px, py) = (2 * cx + dx, 2 * cy + dy);
                        px < w && py < h && last.known[py * w + px]
                    })
                })
                .collect();
            stages.push(Stage::new(coarse, cw, ch));
        }
        Pyramid { stages }
    }

    /// The fill of stage `d`'s `values` (one plane).
    fn fill(&self, values: &[f32], d: usize) -> Vec<f32> {
        let Stage { w, h, ref known, ref levels } = self.stages[d];
        // initial guess: from the next coarser stage (2x2 averages of the known pixels)
        let mut x: Vec<f64> = if d + 1 < self.stages.len() {
            let (cw, ch) = (w.div_ceil(2), h.div_ceil(2));
            let mut cv = vec![0f32; cw * ch];
            for cy in 0..ch {
                for cx in 0..cw {
                    let (mut sum, mut n) = (0f32, 0);
                    for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                        let (px, py) = (2 * cx + dx, 2 * cy + dy);
                        if px < w && py < h && known[py * w + px] {
                            sum += values[py * w + px];
                            n += 1;
                        }
                    }
                    if n > 0 {
                        cv[cy * cw + cx] = sum / n as f32;
                    }
                }
            }
            let coarse = self.fill(&cv, d + 1);
            (0..w * h)
                .map(|i| if known[i] { values[i] as f64 } else { coarse[(i / w / 2) * cw + (i % w) / 2] as f64 })
                .collect()
        } else {
            let mean = values.iter().zip(known).filter(|(_, &k)| k).map(|(&v, _)| v as f64).sum::<f64>()
                / known.iter().filter(|&&k| k).count() as f64;
            (0..w * h).map(|i| if known[i] { values[i] as f64 } else { mean }).collect()
        };
        // then multigrid V-cycles: Gauss-Seidel alone removes the initial guess's smooth error only
        // over hundreds of sweeps (over-relaxed, it stopped at its cap of 400 on the statue's holes
        // at 504x378: 190 ms a view for the three color planes; the completion stage 6.3 -> 3.6 s)
        let mut scratch: Vec<Scratch> = levels
            .windows(2)
            .map(|pair| Scratch {
                residual: vec![0f64; pair[0].w * pair[0].h],
                rhs: vec![0f64; pair[1].w * pair[1].h],
                correction: vec![0f64; pair[1].w * pair[1].h],
            })
            .collect();
        let b = vec![0f64; w * h];
        for _ in 0..MAX_CYCLES {
            if v_cycle(levels, &mut scratch, &mut x, &b) < TOLERANCE {
                break;
            }
        }
        x.into_iter().map(|v| v as f32).collect()
    }
}

impl Stage {
    fn new(known: Vec<bool>, w: usize, h: usize) -> Stage {
        let mut unknown: Vec<bool> = known.iter().map(|&k| !k).collect();
        let mut levels = vec![Level::new(&unknown, w, h)];
        while let Some((next, coarse)) = levels.last().unwrap().coarser(&unknown) {
            levels.push(next);
            unknown = coarse;
        }
        Stage { w, h, known, levels }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn harmonic_fill_reproduces_an_affine_function() {
        let (w, h) = (40, 30);
        let f = |x: usize, y: usize| 0.3 + 0.01 * x as f32 - 0.02 * y as f32;
        let values: Vec<f32> = (0..w * h).map(|i| f(i % w, i / w)).collect();
        let known: Vec<bool> =
            (0..w * h).map(|i| !((10..25).contains(&(i % w)) && (5..22).contains(&(i / w)))).collect();
        let masked: Vec<f32> = values.iter().zip(&known).map(|(&v, &k)| if k { v } else { 9.0 }).collect();
        let filled = harmonic_fill(&masked, &known, w, h, 1);
        let err = filled.iter().zip(&values).map(|(a, b)| (a - b).abs()).fold(0f32, f32::max);
        assert!(err < 1e-4, "max error {err}");
    }

    /// Gaussian elimination in f64 of the fill's linear system: for each unknown pixel, its
    /// value times its in-image neighbour count equals the sum of those neighbours.
    fn direct_solve(values: &[f32], known: &[bool], w: usize, h: usize) -> Vec<(usize, f64)> {
        let unknown: Vec<usize> = (0..w * h).filter(|&i| !known[i]).collect();
        let index = |i: usize| unknown.iter().position(|&u| u == i);
        let n = unknown.len();
        let mut a = vec![vec![0f64; n + 1]; n];
        for (row, &i) in unknown.iter().enumerate() {
            for j in neighbours(i, w, h) {
                a[row][row] += 1.0;
                match index(j) {
                    Some(col) => a[row][col] -= 1.0,
                    None => a[row][n] += values[j] as f64,
                }
            }
        }
        for col in 0..n {
            let pivot = (col..n).max_by(|&p, &q| a[p][col].abs().total_cmp(&a[q][col].abs())).unwrap();
            a.swap(col, pivot);
            for row in 0..n {
                if row != col {
                    let factor = a[row][col] / a[col][col];
                    for k in col..=n {
                        a[row][k] -= factor * a[col][k];
                    }
                }
            }
        }
        unknown.iter().enumerate().map(|(row, &i)| (i, a[row][n] / a[row][row])).collect()
    }

    /// The largest difference between the fill and the direct solve over the pixels where
    /// `hole` holds, with data that are not harmonic (so nothing is exact by accident); known
    /// pixels must come back unchanged.
    fn error_against_direct_solve(w: usize, h: usize, hole: impl Fn(usize, usize) -> bool) -> (f64, usize) {
        let f = |x: usize, y: usize| (x as f32 * 0.37).sin() + 0.5 * (y as f32 * 0.21).cos() + 0.01 * (x * y) as f32;
        let known: Vec<bool> = (0..w * h).map(|i| !hole(i % w, i / w)).collect();
        let values: Vec<f32> = (0..w * h).map(|i| if known[i] { f(i % w, i / w) } else { 7.0 }).collect();
        let filled = harmonic_fill(&values, &known, w, h, 1);
        assert!(known.iter().zip(&filled).zip(&values).all(|((&k, a), b)| !k || a == b), "known pixels moved");
        let exact = direct_solve(&values, &known, w, h);
        (exact.iter().map(|&(i, v)| (filled[i] as f64 - v).abs()).fold(0f64, f64::max), exact.len())
    }

    /// A disc touching the left border (mirror boundary there), a block on the top edge and a
    /// lone pixel.
    #[test]
    fn harmonic_fill_matches_a_direct_solve() {
        let (err, n) = error_against_direct_solve(41, 29, |x, y| {
            let (dx, dy) = (x as f64 - 4.0, y as f64 - 14.0);
            dx * dx + dy * dy <= 64.0 || ((25..37).contains(&x) && y < 9) || (x, y) == (30, 22)
        });
        assert!(n > 250, "{n} unknown pixels");
        assert!(err < 1e-5, "max difference from the direct solve {err}");
    }

    /// Thin unknown shapes, where a coarse grid that sees a block as free although it holds a
    /// known pixel overshoots: a one-pixel ring around a known island, a staircase line, a comb
    /// of one-pixel teeth, a two-pixel strip along the bottom edge.
    #[test]
    fn harmonic_fill_matches_a_direct_solve_on_thin_holes() {
        let (err, n) = error_against_direct_solve(48, 36, |x, y| {
            let ring = (x == 4 || x == 14) && (4..=14).contains(&y) || (y == 4 || y == 14) && (4..=14).contains(&x);
            let stairs = (20..44).contains(&x) && y == 2 + (x - 20) / 2;
            let comb = (20..44).contains(&x) && ((y == 18) || (x % 3 == 0 && (18..30).contains(&y)));
            ring || stairs || comb || y >= 34
        });
        assert!(n > 250, "{n} unknown pixels");
        assert!(err < 1e-5, "max difference from the direct solve {err}");
    }

    /// Masks of every kind at sizes the direct solve cannot reach: a few scattered known pixels
    /// (a depth prior's sky), random discs, one-pixel strips, images 1 to 9 pixels on a side. The
    /// fill obeys the maximum principle (every value within the known values' range) and each
    /// unknown pixel is the mean of its in-image neighbours to 1e-5: a diverging or stalled
    /// solve fails one or the other.
    #[test]
    fn harmonic_fill_is_the_mean_of_its_neighbours_on_random_masks() {
        let mut rng = crate::rng::Rng::new(7);
        for case in 0..24 {
            let (w, h) = if case % 4 == 3 {
                (1 + rng.below(9), 1 + rng.below(60))
            } else {
                (20 + rng.below(180), 20 + rng.below(140))
            };
            let mut known: Vec<bool> = match case % 3 {
                0 => (0..w * h).map(|_| rng.below(100) == 0).collect(),
                1 => vec![true; w * h],
                _ => (0..w * h).map(|i| i % w != w / 2 && (i / w) % 7 != 3).collect(),
            };
            if case % 3 == 1 {
                for _ in 0..1 + rng.below(5) {
                    let (cx, cy, r) = (rng.below(w) as f64, rng.below(h) as f64, 1.0 + rng.below(30) as f64);
                    for (i, k) in known.iter_mut().enumerate() {
                        let (dx, dy) = ((i % w) as f64 - cx, (i / w) as f64 - cy);
                        *k &= dx * dx + dy * dy > r * r;
                    }
                }
            }
            if !known.contains(&true) {
                known[rng.below(w * h)] = true;
            }
            let values: Vec<f32> = (0..w * h).map(|_| rng.uniform() as f32).collect();
            let filled = harmonic_fill(&values, &known, w, h, 1);
            let (lo, hi) = (0..w * h)
                .filter(|&i| known[i])
                .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), i| (lo.min(values[i]), hi.max(values[i])));
            for i in (0..w * h).filter(|&i| !known[i]) {
                let v = filled[i];
                assert!(v >= lo - 1e-5 && v <= hi + 1e-5, "case {case} ({w}x{h}): {v} outside [{lo}, {hi}]");
                let around: Vec<f32> = neighbours(i, w, h).map(|j| filled[j]).collect();
                if around.is_empty() {
                    continue;
                }
                let mean = around.iter().sum::<f32>() / around.len() as f32;
                assert!(
                    (v - mean).abs() < 1e-5,
                    "case {case} ({w}x{h}): pixel {i} is {v}, its neighbours' mean {mean}"
                );
            }
        }
    }
}
