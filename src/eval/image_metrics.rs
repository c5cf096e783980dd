//! Image metric math in f64: SSIM (11x11 Gaussian window, sigma 1.5), L1, and the training loss
//! (1 - lambda) L1 + lambda (1 - SSIM) built from them. `cogeo eval` scores with it, and it is
//! the CPU twin the GPU loss of training is tested against.

fn window() -> [f64; 11] {
    let mut w = [0.0; 11];
    for (i, v) in w.iter_mut().enumerate() {
        let k = i as f64 - 5.0;
        *v = (-k * k / (2.0 * 1.5 * 1.5)).exp();
    }
    let s: f64 = w.iter().sum();
    w.map(|v| v / s)
}

fn blur(img: &[f64], width: usize, height: usize) -> Vec<f64> {
    let w = window();
    let mut tmp = vec![0.0; img.len()];
    let mut out = vec![0.0; img.len()];
    for y in 0..height {
        for x in 0..width {
            tmp[y * width + x] = (-5i64..=5)
                .filter_map(|k| {
                    let xx = x as i64 + k;
                    (0..width as i64).contains(&xx).then(|| w[(k + 5) as usize] * img[y * width + xx as usize])
                })
                .sum();
        }
    }
    for y in 0..height {
        for x in 0..width {
            out[y * width + x] = (-5i64..=5)
                .filter_map(|k| {
                    let yy = y as i64 + k;
                    (0..height as i64).contains(&yy).then(|| w[(k + 5) as usize] * tmp[yy as usize * width + x])
                })
                .sum();
        }
    }
    out
}

/// Mean SSIM over pixels and channels (planar channels), optionally weighted by a mask.
pub fn ssim(x: &[f64], y: &[f64], width: usize, height: usize, mask: Option<&[f64]>) -> f64 {
    let hw = width * height;
    let channels = x.len() / hw;
    let (c1, c2) = (0.01f64.powi(2), 0.03f64.powi(2));
    let mut total = 0.0;
    let mut weight = 0.0;
    for c in 0..channels {
        let xs = &x[c * hw..(c + 1) * hw];
        let ys = &y[c * hw..(c + 1) * hw];
        let sq = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(p, q)| p * q).collect::<Vec<_>>();
        let (mx, my) = (blur(xs, width, height), blur(ys, width, height));
        let (exx, eyy, exy) =
            (blur(&sq(xs, xs), width, height), blur(&sq(ys, ys), width, height), blur(&sq(xs, ys), width, height));
        for i in 0..hw {
            let sxx = exx[i] - mx[i] * mx[i];
            let syy = eyy[i] - my[i] * my[i];
            let sxy = exy[i] - mx[i] * my[i];
            let s = (2.0 * mx[i] * my[i] + c1) * (2.0 * sxy + c2)
                / ((mx[i] * mx[i] + my[i] * my[i] + c1) * (sxx + syy + c2));
            let m = mask.map_or(1.0, |m| m[i]);
            total += m * s;
            weight += m;
        }
    }
    total / weight
}

/// Mean absolute difference, optionally mask-weighted.
pub fn l1(x: &[f64], y: &[f64], width: usize, height: usize, mask: Option<&[f64]>) -> f64 {
    let hw = width * height;
    let (mut total, mut weight) = (0.0, 0.0);
    for (i, (a, b)) in x.iter().zip(y).enumerate() {
        let m = mask.map_or(1.0, |m| m[i % hw]);
        total += m * (a - b).abs();
        weight += m;
    }
    total / weight
}

/// (1 - lambda) L1 + lambda (1 - SSIM).
pub fn loss(x: &[f64], y: &[f64], width: usize, height: usize, mask: Option<&[f64]>, lambda: f64) -> f64 {
    (1.0 - lambda) * l1(x, y, width, height, mask) + lambda * (1.0 - ssim(x, y, width, height, mask))
}
