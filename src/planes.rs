//! Planes in inverse depth over the image: the surface model that completion (the depth prior,
//! the exemplar's surfaces, rectification) and fusion (each patch Gaussian's orientation) share.
//! In a pinhole view the inverse depth of a plane is affine in pixel coordinates, so a plane is
//! three numbers fitted to (x, y, 1/d) with no intrinsics needed: by least squares, robustly
//! around one pixel (`local_plane`), or several at once by sequential RANSAC (`fit_planes`).

use crate::rng::Rng;

/// A plane as its inverse depth over the image: disparity = a x + b y + c at pixel center (x, y).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    pub a: f64,
    pub b: f64,
    pub c: f64,
}

impl Plane {
    pub fn disparity(&self, x: f64, y: f64) -> f64 {
        self.a * x + self.b * y + self.c
    }

    /// Relative disparity residual of pixel `i` (of a w-wide image) with disparity `d`.
    pub fn residual(&self, i: usize, w: usize, d: f64) -> f64 {
        let (x, y) = center(i, w);
        (self.disparity(x, y) - d).abs() / d
    }

    /// Tukey's biweight of pixel `i` with disparity `d` for a robust refit of this plane: the
    /// relative residual on the scale of PLANE_TOLERANCE, 0 beyond it.
    pub fn tukey_weight(&self, i: usize, w: usize, d: f64) -> f64 {
        let r = self.residual(i, w, d) / PLANE_TOLERANCE;
        if r < 1.0 {
            (1.0 - r * r).powi(2)
        } else {
            0.0
        }
    }
}

pub fn center(i: usize, w: usize) -> (f64, f64) {
    ((i % w) as f64 + 0.5, (i / w) as f64 + 0.5)
}

/// Relative disparity tolerance of plane membership (trained scenes render depth with a few
/// percent of noise).
pub const PLANE_TOLERANCE: f64 = 0.03;
const RANSAC_TRIALS: usize = 256;
/// Points a RANSAC trial counts between its checks of whether it can still win.
const COUNT_CHUNK: usize = 512;

/// Solves the N x N system m z = r (Gaussian elimination with partial pivoting); None if singular
/// (a pivot below 1e-12 of the largest entry).
pub fn solve<const N: usize>(mut m: [[f64; N]; N], mut r: [f64; N]) -> Option<[f64; N]> {
    let scale = m.iter().flatten().fold(0f64, |s, v| s.max(v.abs()));
    if scale == 0.0 {
        return None;
    }
    for col in 0..N {
        let p = (col..N).max_by(|&a, &b| m[a][col].abs().total_cmp(&m[b][col].abs()))?;
        if m[p][col].abs() < 1e-12 * scale {
            return None;
        }
        m.swap(col, p);
        r.swap(col, p);
        for row in col + 1..N {
            let f = m[row][col] / m[col][col];
            for k in col..N {
                m[row][k] -= f * m[col][k];
            }
            r[row] -= f * r[col];
        }
    }
    let mut z = [0f64; N];
    for row in (0..N).rev() {
        let s: f64 = (row + 1..N).map(|k| m[row][k] * z[k]).sum();
        z[row] = (r[row] - s) / m[row][row];
    }
    Some(z)
}

/// Least-squares plane through the pixels `idx`, each weighted by `weight` (centered coordinates
/// for conditioning).
pub fn least_squares(idx: &[usize], disp: &[f32], w: usize, weight: impl Fn(usize) -> f64) -> Option<Plane> {
    let n: f64 = idx.iter().map(|&i| weight(i)).sum();
    if idx.len() < 3 || n <= 0.0 {
        return None;
    }
    let (mx, my) = idx.iter().fold((0.0, 0.0), |(sx, sy), &i| {
        let (x, y) = center(i, w);
        (sx + weight(i) * x / n, sy + weight(i) * y / n)
    });
    let mut m = [[0f64; 3]; 3];
    let mut r = [0f64; 3];
    for &i in idx {
        let (x, y) = center(i, w);
        let (row, k) = ([x - mx, y - my, 1.0], weight(i));
        for j in 0..3 {
            for l in 0..3 {
                m[j][l] += k * row[j] * row[l];
            }
            r[j] += k * row[j] * disp[i] as f64;
        }
    }
    let [a, b, c] = solve(m, r)?;
    Some(Plane { a, b, c: c - a * mx - b * my })
}

/// The plane of the surface at pixel (x, y): a robust fit of the disparity in the window of
/// `radius` around it. It starts from the pixels within 10 % of the center's disparity (a depth
/// edge in the window does not pull it) and is refitted three times with Tukey weights on the
/// relative residual (scale `PLANE_TOLERANCE`). None with fewer than 6 pixels with a disparity or
/// a degenerate window. Per-pixel depths scatter by a percent or two; the plane does not, so the
/// surface's orientation comes from it.
pub fn local_plane(disp: &[f32], w: usize, h: usize, x: usize, y: usize, radius: usize) -> Option<Plane> {
    let valid = |i: usize| disp[i] > 0.0 && disp[i].is_finite();
    let center_disp = disp[y * w + x] as f64;
    if !valid(y * w + x) {
        return None;
    }
    let idx: Vec<usize> = (y.saturating_sub(radius)..(y + radius + 1).min(h))
        .flat_map(|yy| (x.saturating_sub(radius)..(x + radius + 1).min(w)).map(move |xx| yy * w + xx))
        .filter(|&i| valid(i))
        .collect();
    if idx.len() < 6 {
        return None;
    }
    let near = |i: usize| (((disp[i] as f64 - center_disp).abs() / center_disp) < 0.1) as u8 as f64;
    let mut plane = least_squares(&idx, disp, w, near)?;
    for _ in 0..3 {
        plane = least_squares(&idx, disp, w, |i| plane.tukey_weight(i, w, disp[i] as f64))?;
    }
    Some(plane)
}

/// The largest `x` >= 0 for which `x / d` (rounded, as f64 division rounds) is at most `tol`
/// (`d` > 0, `tol` >= 0): the rounded quotient grows with `x`, so for every `x` >= 0 (and NaN)
/// `x <= bound` holds exactly when `x / d <= tol` does. Starts from `tol * d` and steps by ulps.
fn within_after_division(d: f64, tol: f64) -> f64 {
    let mut x = tol * d;
    while x > 0.0 && x / d > tol {
        x = x.next_down();
    }
    while (x.next_up() / d) <= tol {
        x = x.next_up();
    }
    x
}

/// How many of the points (`xs`, `ys`, disparity `ds`) lie within their `bounds` of plane `p`
/// (`within_after_division`): a RANSAC trial's count, most of the fit's time. Where the CPU has
/// AVX2 the same loop is compiled for it too, twice as wide; the same operations in IEEE
/// arithmetic (no fused multiply-add), so the same count.
fn count_within(p: &Plane, xs: &[f64], ys: &[f64], ds: &[f64], bounds: &[f64]) -> usize {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2, checked just above
        return unsafe { count_within_avx2(p, xs, ys, ds, bounds) };
    }
    count_within_portable(p, xs, ys, ds, bounds)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn count_within_avx2(p: &Plane, xs: &[f64], ys: &[f64], ds: &[f64], bounds: &[f64]) -> usize {
    count_within_portable(p, xs, ys, ds, bounds)
}

#[inline(always)]
fn count_within_portable(p: &Plane, xs: &[f64], ys: &[f64], ds: &[f64], bounds: &[f64]) -> usize {
    let n = xs.len().min(ys.len()).min(ds.len()).min(bounds.len());
    let (xs, ys, ds, bounds) = (&xs[..n], &ys[..n], &ds[..n], &bounds[..n]);
    (0..n).map(|k| ((p.disparity(xs[k], ys[k]) - ds[k]).abs() <= bounds[k]) as usize).sum()
}

/// Sequential RANSAC: up to `max_planes` planes, each supported by at least `min_inliers` of the
/// pixels where `sample` holds (disparity `disp`, relative tolerance `tol`); each plane is refitted
/// by least squares on the core of its inliers, which are then taken out for the next one.
/// Deterministic.
pub fn fit_planes(
    disp: &[f32],
    sample: &[bool],
    w: usize,
    tol: f64,
    max_planes: usize,
    min_inliers: usize,
    seed: u64,
) -> Vec<Plane> {
    let mut pts: Vec<usize> = (0..disp.len()).filter(|&i| sample[i] && disp[i] > 0.0 && disp[i].is_finite()).collect();
    let mut rng = Rng::new(seed);
    let mut planes = Vec::new();
    let inliers = |p: &Plane, pts: &[usize]| -> Vec<usize> {
        pts.iter().copied().filter(|&i| p.residual(i, w, disp[i] as f64) <= tol).collect()
    };
    while planes.len() < max_planes && pts.len() >= min_inliers.max(3) {
        // the points' centers and disparities side by side: a trial's count is then a loop over
        // flat arrays, without the index's division per point (Plane::residual's arithmetic, so
        // the same counts)
        let xs: Vec<f64> = pts.iter().map(|&i| center(i, w).0).collect();
        let ys: Vec<f64> = pts.iter().map(|&i| center(i, w).1).collect();
        let ds: Vec<f64> = pts.iter().map(|&i| disp[i] as f64).collect();
        // each point's largest residual within the tolerance: a trial's count then compares
        // without the division per point and trial (half of the fit's time), the same counts
        let bounds: Vec<f64> = ds.iter().map(|&d| within_after_division(d, tol)).collect();
        let mut best: Option<(usize, Plane)> = None;
        for _ in 0..RANSAC_TRIALS {
            let pick = [rng.below(pts.len()), rng.below(pts.len()), rng.below(pts.len())];
            if pick[0] == pick[1] || pick[1] == pick[2] || pick[0] == pick[2] {
                continue;
            }
            let mut m = [[0f64; 3]; 3];
            let mut r = [0f64; 3];
            for (row, &k) in pick.iter().enumerate() {
                let (x, y) = center(pts[k], w);
                m[row] = [x, y, 1.0];
                r[row] = disp[pts[k]] as f64;
            }
            let Some([a, b, c]) = solve(m, r) else { continue };
            let p = Plane { a, b, c };
            // counted a chunk at a time, the trial dropped once even all the points left could
            // not lift it above the best so far (only a larger count replaces the best)
            let to_beat = best.as_ref().map(|(bn, _)| *bn);
            let mut n = 0;
            for start in (0..pts.len()).step_by(COUNT_CHUNK) {
                let end = (start + COUNT_CHUNK).min(pts.len());
                n += count_within(&p, &xs[start..end], &ys[start..end], &ds[start..end], &bounds[start..end]);
                if to_beat.is_some_and(|bn| n + (pts.len() - end) <= bn) {
                    break;
                }
            }
            if to_beat.is_none_or(|bn| n > bn) {
                best = Some((n, p));
            }
        }
        let Some((n, p)) = best else { break };
        if n < min_inliers {
            break;
        }
        // refit by least squares on the core of the inliers (residual within 3x their median):
        // points of a neighbouring plane near the crease lie within the tolerance too and would
        // tilt the fit
        let mut p = p;
        for _ in 0..4 {
            let inl = inliers(&p, &pts);
            let mut rs: Vec<f64> = inl.iter().map(|&i| p.residual(i, w, disp[i] as f64)).collect();
            rs.sort_by(|a, b| a.total_cmp(b));
            let cut = (3.0 * rs[rs.len() / 2]).max(1e-7);
            let core: Vec<usize> = inl.into_iter().filter(|&i| p.residual(i, w, disp[i] as f64) <= cut).collect();
            p = least_squares(&core, disp, w, |_| 1.0).unwrap_or(p);
        }
        let own = inliers(&p, &pts);
        if own.len() < min_inliers {
            break;
        }
        planes.push(p);
        pts.retain(|&i| p.residual(i, w, disp[i] as f64) > tol);
    }
    planes
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The count compiled for AVX2 and the portable one agree with the plain filter.
    #[test]
    fn the_counts_agree_whichever_loop_runs() {
        let mut rng = Rng::new(13);
        for trial in 0..50 {
            let n = rng.below(3000);
            let xs: Vec<f64> = (0..n).map(|_| (rng.below(500) as f64) + 0.5).collect();
            let ys: Vec<f64> = (0..n).map(|_| (rng.below(400) as f64) + 0.5).collect();
            let p = Plane { a: 1e-4 * rng.normal(), b: 1e-4 * rng.normal(), c: 0.1 + rng.uniform() };
            // scattered about the plane by 6 % (normal): about 40 % within the 3 % tolerance
            let ds: Vec<f64> = (0..n)
                .map(|k| (p.disparity(xs[k], ys[k]) * (1.0 + 0.06 * rng.normal())).abs().max(1e-3) as f32 as f64)
                .collect();
            let bounds: Vec<f64> = ds.iter().map(|&d| within_after_division(d, PLANE_TOLERANCE)).collect();
            let want = (0..n).filter(|&k| (p.disparity(xs[k], ys[k]) - ds[k]).abs() / ds[k] <= PLANE_TOLERANCE).count();
            assert_eq!(count_within(&p, &xs, &ys, &ds, &bounds), want, "trial {trial}");
            assert_eq!(count_within_portable(&p, &xs, &ys, &ds, &bounds), want, "trial {trial}");
            assert!(n < 100 || (want > 0 && want < n), "trial {trial}: the points should lie on both sides");
        }
    }

    /// The bound must give the division's verdict bit for bit: at the bound and the ulps on either
    /// side of it (where the two forms could part), and at residuals drawn across the tolerance.
    #[test]
    fn the_bound_agrees_with_the_division_at_every_residual() {
        let mut rng = Rng::new(11);
        let mut at_edge = 0;
        for k in 0..20_000 {
            // disparities as the renders give them (f32), over several decades
            let d = (10f64.powf(4.0 * rng.uniform() - 2.0) as f32) as f64;
            let tol = if k % 2 == 0 { PLANE_TOLERANCE } else { 0.2 * rng.uniform() };
            let bound = within_after_division(d, tol);
            assert!(bound / d <= tol, "d {d} tol {tol}: the bound {bound} is outside");
            assert!(bound.next_up() / d > tol, "d {d} tol {tol}: the bound {bound} is not the largest");
            let mut xs = vec![bound.next_down(), bound, bound.next_up(), tol * d, 0.0, f64::NAN, f64::INFINITY];
            xs.extend((0..8).map(|_| 2.0 * tol * d * rng.uniform()));
            for x in xs {
                assert_eq!(x <= bound, x / d <= tol, "d {d} tol {tol} residual {x}");
            }
            at_edge += (tol * d != bound) as usize;
        }
        // the product alone is off by an ulp for a share of the disparities: the check is not idle
        assert!(at_edge > 100, "tol * d was the bound at all but {at_edge} of 20000 disparities");
    }
}
