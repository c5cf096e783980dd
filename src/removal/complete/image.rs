//! Small image operations of the completion stage on planar float images (channel after channel,
//! width * height each): resizing, cropping, mask dilation and feathering, and harmonic filling.
//! These run once per view on the host; nothing here is per-iteration work.

/// Bilinear resize of a planar image with `channels` planes (pixel centers aligned, edges clamped).
pub fn resize_bilinear(src: &[f32], w: usize, h: usize, channels: usize, nw: usize, nh: usize) -> Vec<f32> {
    let mut out = vec![0f32; nw * nh * channels];
    let (sx, sy) = (w as f32 / nw as f32, h as f32 / nh as f32);
    for y in 0..nh {
        let fy = ((y as f32 + 0.5) * sy - 0.5).clamp(0.0, (h - 1) as f32);
        let (y0, ty) = (fy.floor() as usize, fy.fract());
        let y1 = (y0 + 1).min(h - 1);
        for x in 0..nw {
            let fx = ((x as f32 + 0.5) * sx - 0.5).clamp(0.0, (w - 1) as f32);
            let (x0, tx) = (fx.floor() as usize, fx.fract());
            let x1 = (x0 + 1).min(w - 1);
            for c in 0..channels {
                let p = &src[c * w * h..(c + 1) * w * h];
                let top = p[y0 * w + x0] * (1.0 - tx) + p[y0 * w + x1] * tx;
                let bottom = p[y1 * w + x0] * (1.0 - tx) + p[y1 * w + x1] * tx;
                out[c * nw * nh + y * nw + x] = top * (1.0 - ty) + bottom * ty;
            }
        }
    }
    out
}

/// Nearest-neighbour resize of a mask.
pub fn resize_mask(src: &[bool], w: usize, h: usize, nw: usize, nh: usize) -> Vec<bool> {
    (0..nw * nh)
        .map(|i| {
            let (x, y) = (i % nw, i / nw);
            src[(y * h / nh) * w + x * w / nw]
        })
        .collect()
}

/// A pixel rectangle [x0, x1) x [y0, y1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rect {
    pub x0: usize,
    pub y0: usize,
    pub x1: usize,
    pub y1: usize,
}

impl Rect {
    pub fn width(&self) -> usize {
        self.x1 - self.x0
    }
    pub fn height(&self) -> usize {
        self.y1 - self.y0
    }
}

/// Bounding box of the set pixels, or None for an empty mask.
pub fn bounding_box(mask: &[bool], w: usize) -> Option<Rect> {
    let mut r: Option<Rect> = None;
    for (i, _) in mask.iter().enumerate().filter(|(_, &m)| m) {
        let (x, y) = (i % w, i / w);
        r = Some(match r {
            None => Rect { x0: x, y0: y, x1: x + 1, y1: y + 1 },
            Some(r) => Rect { x0: r.x0.min(x), y0: r.y0.min(y), x1: r.x1.max(x + 1), y1: r.y1.max(y + 1) },
        });
    }
    r
}

/// Copies a rectangle out of a planar image.
pub fn crop(src: &[f32], w: usize, h: usize, channels: usize, r: Rect) -> Vec<f32> {
    let mut out = Vec::with_capacity(r.width() * r.height() * channels);
    for c in 0..channels {
        for y in r.y0..r.y1 {
            out.extend_from_slice(&src[c * w * h + y * w + r.x0..c * w * h + y * w + r.x1]);
        }
    }
    out
}

/// Euclidean distance (in pixels) from every pixel to the nearest set pixel of `mask` (two-pass
/// chamfer with 3x3 weights 1 and sqrt 2: within 8 % of the true distance). Infinity for an empty mask.
pub fn distance_to(mask: &[bool], w: usize, h: usize) -> Vec<f32> {
    let mut d: Vec<f32> = mask.iter().map(|&m| if m { 0.0 } else { f32::INFINITY }).collect();
    let s2 = std::f32::consts::SQRT_2;
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let mut v = d[i];
            if x > 0 {
                v = v.min(d[i - 1] + 1.0);
            }
            if y > 0 {
                v = v.min(d[i - w] + 1.0);
                if x > 0 {
                    v = v.min(d[i - w - 1] + s2);
                }
                if x + 1 < w {
                    v = v.min(d[i - w + 1] + s2);
                }
            }
            d[i] = v;
        }
    }
    for y in (0..h).rev() {
        for x in (0..w).rev() {
            let i = y * w + x;
            let mut v = d[i];
            if x + 1 < w {
                v = v.min(d[i + 1] + 1.0);
            }
            if y + 1 < h {
                v = v.min(d[i + w] + 1.0);
                if x + 1 < w {
                    v = v.min(d[i + w + 1] + s2);
                }
                if x > 0 {
                    v = v.min(d[i + w - 1] + s2);
                }
            }
            d[i] = v;
        }
    }
    d
}

/// Grows a mask by `radius` pixels (a disc).
pub fn dilate(mask: &[bool], w: usize, h: usize, radius: f32) -> Vec<bool> {
    if radius <= 0.0 {
        return mask.to_vec();
    }
    distance_to(mask, w, h).iter().map(|&d| d <= radius).collect()
}

/// A soft version of `mask`: 1 inside, falling smoothly to 0 at `radius` pixels outside.
pub fn feather(mask: &[bool], w: usize, h: usize, radius: f32) -> Vec<f32> {
    distance_to(mask, w, h)
        .iter()
        .map(|&d| {
            if radius <= 0.0 {
                return if d == 0.0 { 1.0 } else { 0.0 };
            }
            let t = (1.0 - d / radius).clamp(0.0, 1.0);
            t * t * (3.0 - 2.0 * t)
        })
        .collect()
}

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
    for c in 0..channels {
        let plane = &values[c * w * h..(c + 1) * w * h];
        let filled = fill_plane(plane, known, w, h);
        out[c * w * h..(c + 1) * w * h].copy_from_slice(&filled);
    }
    out
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
    let unknown: Vec<usize> = (0..w * h).filter(|&i| !known[i]).collect();
    // over-relaxed Gauss-Seidel; Neumann (mirror) boundary at the image border
    let omega = 1.8;
    for _ in 0..400 {
        let mut change = 0f64;
        for &i in &unknown {
            let (px, py) = (i % w, i / w);
            let (mut sum, mut n) = (0f64, 0f64);
            if px > 0 {
                sum += x[i - 1];
                n += 1.0;
            }
            if px + 1 < w {
                sum += x[i + 1];
                n += 1.0;
            }
            if py > 0 {
                sum += x[i - w];
                n += 1.0;
            }
            if py + 1 < h {
                sum += x[i + w];
                n += 1.0;
            }
            let new = x[i] + omega * (sum / n - x[i]);
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

    #[test]
    fn distance_and_dilation() {
        let (w, h) = (21, 21);
        let mut m = vec![false; w * h];
        m[10 * w + 10] = true;
        let d = distance_to(&m, w, h);
        assert_eq!(d[10 * w + 13], 3.0);
        assert!((d[13 * w + 13] - 3.0 * std::f32::consts::SQRT_2).abs() < 1e-5);
        let grown = dilate(&m, w, h, 2.0);
        assert_eq!(grown.iter().filter(|&&v| v).count(), 13); // the radius-2 chamfer disc
        let soft = feather(&m, w, h, 4.0);
        assert_eq!(soft[10 * w + 10], 1.0);
        assert_eq!(soft[10 * w + 15], 0.0);
        assert!(soft[10 * w + 12] > 0.0 && soft[10 * w + 12] < 1.0);
    }

    #[test]
    fn resize_keeps_constants_and_crops_roundtrip() {
        let img = vec![0.25f32; 2 * 10 * 8];
        let r = resize_bilinear(&img, 10, 8, 2, 17, 5);
        assert!(r.iter().all(|&v| (v - 0.25).abs() < 1e-7));
        let ramp: Vec<f32> = (0..10 * 8).map(|i| i as f32).collect();
        let rect = Rect { x0: 2, y0: 1, x1: 5, y1: 3 };
        assert_eq!(crop(&ramp, 10, 8, 1, rect), vec![12.0, 13.0, 14.0, 22.0, 23.0, 24.0]);
    }
}
