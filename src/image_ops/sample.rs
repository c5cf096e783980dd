//! Resizing and sampling of planar float images (channel after channel, width * height each):
//! bilinear and Lanczos-3 at any point, one channel or three at once, and the nearest-pixel
//! resizes of label maps and masks.

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

/// The four pixels a bilinear sample at (x, y) blends (row-major indices of (x0, y0), (x1, y0),
/// (x0, y1), (x1, y1), clamped to the edge pixels) and its fractions: what the samplers below
/// share, so that they give the same bits.
struct BilinearTaps {
    at: [usize; 4],
    fx: f32,
    fy: f32,
}

impl BilinearTaps {
    #[inline]
    fn new(w: usize, h: usize, x: f64, y: f64) -> BilinearTaps {
        let (x, y) = ((x - 0.5).clamp(0.0, (w - 1) as f64), (y - 0.5).clamp(0.0, (h - 1) as f64));
        // the floor of a non-negative value is its truncation: `as` gives it without the call to
        // libm's floor that `f64::floor` is on a baseline x86-64 build
        let (x0, y0) = (x as usize, y as usize);
        let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
        let (fx, fy) = ((x - x0 as f64) as f32, (y - y0 as f64) as f32);
        BilinearTaps { at: [y0 * w + x0, y0 * w + x1, y1 * w + x0, y1 * w + x1], fx, fy }
    }

    /// The sample of the values `v` at the four pixels, in `at`'s order.
    #[inline]
    fn blend(&self, v: [f32; 4]) -> f32 {
        let (fx, fy) = (self.fx, self.fy);
        (1.0 - fy) * ((1.0 - fx) * v[0] + fx * v[1]) + fy * ((1.0 - fx) * v[2] + fx * v[3])
    }
}

/// Channel `c` of the planar image `img` (w x h) at the continuous point (x, y), pixel (px, py)
/// centered at (px + 0.5, py + 0.5): bilinear, clamped to the edge pixels.
pub fn sample_bilinear(img: &[f32], w: usize, h: usize, c: usize, x: f64, y: f64) -> f32 {
    let taps = BilinearTaps::new(w, h, x, y);
    taps.blend(taps.at.map(|q| img[c * w * h + q]))
}

/// The planar RGB `img` of `n` pixels as one [r, g, b] per pixel, for `sample_bilinear_pixels`.
pub fn interleave_rgb(img: &[f32], n: usize) -> Vec<[f32; 3]> {
    (0..n).map(|i| [img[i], img[n + i], img[2 * n + i]]).collect()
}

/// `sample_bilinear` of the three channels of an image stored as one [r, g, b] per pixel
/// (`interleave_rgb`), the taps and weights found once: the same arithmetic, so the same bits,
/// with a sample's four pixels in two cache lines instead of six (the photo-consistent depth
/// samples every view ~130 times per hole pixel).
#[inline]
pub fn sample_bilinear_pixels(img: &[[f32; 3]], w: usize, h: usize, x: f64, y: f64) -> [f32; 3] {
    let taps = BilinearTaps::new(w, h, x, y);
    let v = taps.at.map(|q| img[q]);
    std::array::from_fn(|ch| taps.blend(v.map(|p| p[ch])))
}

/// The Lanczos kernel with a = 3: sinc(t) sinc(t / 3) for |t| < 3, else 0.
fn lanczos3(t: f64) -> f64 {
    if t.abs() < 1e-9 {
        1.0
    } else if t.abs() >= 3.0 {
        0.0
    } else {
        let a = std::f64::consts::PI * t;
        3.0 * a.sin() * (a / 3.0).sin() / (a * a)
    }
}

/// The 6 x 6 taps of a Lanczos-3 sample at (x, y): each column's and row's pixel (clamped to the
/// image) and kernel weight; shared by the samplers below, so that they give the same bits.
struct Lanczos3Taps {
    xs: [usize; 6],
    ys: [usize; 6],
    kx: [f64; 6],
    ky: [f64; 6],
}

impl Lanczos3Taps {
    #[inline]
    fn new(w: usize, h: usize, x: f64, y: f64) -> Lanczos3Taps {
        let (x, y) = (x - 0.5, y - 0.5);
        let (x0, y0) = (x.floor() as isize, y.floor() as isize);
        Lanczos3Taps {
            xs: std::array::from_fn(|i| (x0 + i as isize - 2).clamp(0, w as isize - 1) as usize),
            ys: std::array::from_fn(|j| (y0 + j as isize - 2).clamp(0, h as isize - 1) as usize),
            kx: std::array::from_fn(|i| lanczos3(x - (x0 + i as isize - 2) as f64)),
            ky: std::array::from_fn(|j| lanczos3(y - (y0 + j as isize - 2) as f64)),
        }
    }
}

/// Channel `c` of the planar image `img` (w x h) at the continuous point (x, y), pixel centers at
/// (px + 0.5, py + 0.5): Lanczos-3 (6 x 6 taps, weights normalized, edges clamped). Exact at pixel
/// centers, and much sharper than bilinear between them: bilinear halfway between two pixels
/// averages them, which loses a quarter of a checkerboard's contrast at 4 pixels per square. It may
/// overshoot the neighbours' range slightly (ringing at steps).
pub fn sample_lanczos3(img: &[f32], w: usize, h: usize, c: usize, x: f64, y: f64) -> f32 {
    let t = Lanczos3Taps::new(w, h, x, y);
    let plane = &img[c * w * h..(c + 1) * w * h];
    let (mut sum, mut weight) = (0.0, 0.0);
    for (&yy, wy) in t.ys.iter().zip(&t.ky) {
        for (&xx, wx) in t.xs.iter().zip(&t.kx) {
            sum += wx * wy * plane[yy * w + xx] as f64;
            weight += wx * wy;
        }
    }
    (sum / weight) as f32
}

/// `sample_lanczos3` of the three channels of the planar RGB `img` at once: the kernel's 12
/// weights (24 sines) computed once, not per channel; each channel's sum in the same order, so the
/// same bits.
pub fn sample_lanczos3_rgb(img: &[f32], w: usize, h: usize, x: f64, y: f64) -> [f32; 3] {
    let t = Lanczos3Taps::new(w, h, x, y);
    let n = w * h;
    let (mut sum, mut weight) = ([0.0f64; 3], 0.0);
    for (&yy, wy) in t.ys.iter().zip(&t.ky) {
        for (&xx, wx) in t.xs.iter().zip(&t.kx) {
            let q = yy * w + xx;
            for (c, s) in sum.iter_mut().enumerate() {
                *s += wx * wy * img[c * n + q] as f64;
            }
            weight += wx * wy;
        }
    }
    sum.map(|s| (s / weight) as f32)
}

/// One byte per pixel (a label map) resized by the nearest pixel, pixel centers to pixel centers.
pub fn resize_nearest_u8(src: &[u8], w: u32, h: u32, nw: u32, nh: u32) -> Vec<u8> {
    if (w, h) == (nw, nh) {
        return src.to_vec();
    }
    let mut out = vec![0u8; (nw * nh) as usize];
    for y in 0..nh {
        let sy = (((y as f64 + 0.5) * h as f64 / nh as f64) as u32).min(h - 1);
        for x in 0..nw {
            let sx = (((x as f64 + 0.5) * w as f64 / nw as f64) as u32).min(w - 1);
            out[(y * nw + x) as usize] = src[(sy * w + sx) as usize];
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image_ops::{crop, Rect};

    /// The three-channel samplers give each channel's `sample_bilinear` (`sample_lanczos3`)
    /// exactly, edges included.
    #[test]
    fn three_channel_samplers_are_the_per_channel_ones() {
        let (w, h) = (7, 5);
        let img: Vec<f32> = (0..3 * w * h).map(|i| ((i * 37 % 101) as f32) / 101.0).collect();
        let pixels = interleave_rgb(&img, w * h);
        let mut rng = crate::rng::Rng::new(3);
        for _ in 0..500 {
            let (x, y) = (rng.uniform() * (w as f64 + 2.0) - 1.0, rng.uniform() * (h as f64 + 2.0) - 1.0);
            // the interleaved image's sampler, bit for bit each channel's
            let rgb = sample_bilinear_pixels(&pixels, w, h, x, y);
            for (c, &v) in rgb.iter().enumerate() {
                assert_eq!(v.to_bits(), sample_bilinear(&img, w, h, c, x, y).to_bits(), "({x}, {y}) channel {c}");
            }
            // the three-channel Lanczos, bit for bit each channel's
            let lanczos = sample_lanczos3_rgb(&img, w, h, x, y);
            for (c, &v) in lanczos.iter().enumerate() {
                assert_eq!(v.to_bits(), sample_lanczos3(&img, w, h, c, x, y).to_bits(), "({x}, {y}) channel {c}");
            }
        }
    }

    #[test]
    fn lanczos_is_exact_at_centers_and_sharper_than_bilinear() {
        // a sinusoid along x with a period of 8 pixels, sampled at pixel centers
        let (w, h) = (32, 4);
        let f = |x: f64| 0.5 + 0.4 * (2.0 * std::f64::consts::PI * x / 8.0).cos();
        let img: Vec<f32> = (0..w * h).map(|i| f((i % w) as f64 + 0.5) as f32).collect();
        let (mut lanczos, mut bilinear) = (0f64, 0f64);
        for k in 0..=64 {
            // interior points, away from the clamped edges
            let x = 10.0 + k as f64 * 12.0 / 64.0;
            let truth = f(x);
            lanczos = lanczos.max((sample_lanczos3(&img, w, h, 0, x, 2.0) as f64 - truth).abs());
            bilinear = bilinear.max((sample_bilinear(&img, w, h, 0, x, 2.0) as f64 - truth).abs());
            if (x - x.floor() - 0.5).abs() < 1e-12 {
                assert!((sample_lanczos3(&img, w, h, 0, x, 2.0) as f64 - truth).abs() < 1e-6, "exact at {x}");
            }
        }
        // bilinear halfway loses 1 - cos(pi / 8) of the amplitude: 0.4 * 0.076 = 0.030
        assert!(bilinear > 0.025, "bilinear error {bilinear}");
        assert!(lanczos < 0.1 * bilinear, "lanczos error {lanczos} vs bilinear {bilinear}");
        // constants stay constant, also at the clamped edges
        let flat = vec![0.3f32; w * h];
        for (x, y) in [(0.1, 0.2), (31.9, 3.9), (7.3, 1.7)] {
            assert!((sample_lanczos3(&flat, w, h, 0, x, y) - 0.3).abs() < 1e-6);
        }
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
