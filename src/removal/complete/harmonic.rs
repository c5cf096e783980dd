//! Harmonic filling: the smooth interpolant of known pixels over unknown ones, the built-in
//! inpainter's fill and the completion of depth inside a hole.

/// Fills the pixels where `known` is false with the harmonic interpolant of the known ones (the
/// solution of Laplace's equation with the known pixels as boundary values), for each of `channels`
/// planes. Solved coarse to fine: each level is initialized from the next coarser one and relaxed
/// with Gauss-Seidel, so large holes converge in a few hundred sweeps. Affine functions are harmonic,
/// so affine data are reproduced exactly (inverse depth of a plane, a linear color ramp).
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
    // the planes are independent: one thread each (the result does not depend on the threads)
    std::thread::scope(|scope| {
        let jobs: Vec<_> = out
            .chunks_mut(w * h)
            .take(channels)
            .map(|plane| {
                scope.spawn(move || {
                    let filled = fill_plane(plane, known, w, h);
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

fn fill_plane(values: &[f32], known: &[bool], w: usize, h: usize) -> Vec<f32> {
    // initial guess: from the next coarser level (2x2 averages of the known pixels)
    let mut x: Vec<f64> = if w > 8 && h > 8 {
        let (cw, ch) = (w.div_ceil(2), h.div_ceil(2));
        let mut cv = vec![0f32; cw * ch];
        let mut ck = vec![false; cw * ch];
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
                    ck[cy * cw + cx] = true;
                }
            }
        }
        let coarse = fill_plane(&cv, &ck, cw, ch);
        (0..w * h)
            .map(|i| if known[i] { values[i] as f64 } else { coarse[(i / w / 2) * cw + (i % w) / 2] as f64 })
            .collect()
    } else {
        let mean = values.iter().zip(known).filter(|(_, &k)| k).map(|(&v, _)| v as f64).sum::<f64>()
            / known.iter().filter(|&&k| k).count() as f64;
        (0..w * h).map(|i| if known[i] { values[i] as f64 } else { mean }).collect()
    };
    // each unknown pixel with its in-image neighbours, gathered once: the sweeps below are the
    // whole cost, and a division per pixel for its coordinates was most of theirs
    let unknown: Vec<Stencil> = (0..w * h)
        .filter(|&i| !known[i])
        .map(|i| {
            let (px, py) = (i % w, i / w);
            let mut s = Stencil { at: i as u32, neighbours: [0; 4], count: 0 };
            for (inside, j) in
                [(px > 0, i.wrapping_sub(1)), (px + 1 < w, i + 1), (py > 0, i.wrapping_sub(w)), (py + 1 < h, i + w)]
            {
                if inside {
                    s.neighbours[s.count as usize] = j as u32;
                    s.count += 1;
                }
            }
            s
        })
        .collect();
    // over-relaxed Gauss-Seidel; Neumann (mirror) boundary at the image border
    let omega = 1.8;
    for _ in 0..400 {
        let mut change = 0f64;
        for s in &unknown {
            let i = s.at as usize;
            // summed in the order left, right, up, down, as the stencil was built
            let mut sum = 0f64;
            for &j in &s.neighbours[..s.count as usize] {
                sum += x[j as usize];
            }
            let new = x[i] + omega * (sum / s.count as f64 - x[i]);
            change = change.max((new - x[i]).abs());
            x[i] = new;
        }
        if change < 1e-6 {
            break;
        }
    }
    x.into_iter().map(|v| v as f32).collect()
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
}
