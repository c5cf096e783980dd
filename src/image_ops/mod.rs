//! Small image operations on planar float images (channel after channel, width * height each) and
//! pixel masks: cropping, distances, connected components, mask dilation and feathering, box
//! filters; resizing and sampling are in sample.rs. Removal and evaluation use them once per view
//! on the host; nothing here is per-iteration work.

mod sample;
pub use sample::*;

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

    /// The index, in a `w` pixels wide image, of this rectangle's `k`-th pixel (row-major):
    /// pixel `k` of a crop (`crop`) back in the image it was cut from.
    pub fn pixel(&self, k: usize, w: usize) -> usize {
        (self.y0 + k / self.width()) * w + self.x0 + k % self.width()
    }

    /// This rectangle grown by `mx` pixels left and right and `my` up and down, clamped to a
    /// w x h image.
    pub fn grown(&self, mx: usize, my: usize, w: usize, h: usize) -> Rect {
        Rect {
            x0: self.x0.saturating_sub(mx),
            y0: self.y0.saturating_sub(my),
            x1: (self.x1 + mx).min(w),
            y1: (self.y1 + my).min(h),
        }
    }

    /// This rectangle widened to a multiple of `k` pixels (to the right, then to the left where
    /// it meets the edge of a `w` pixels wide image), or as wide as the image where that is less.
    pub fn widened_to_multiple(&self, k: usize, w: usize) -> Rect {
        let width = self.width().next_multiple_of(k).min(w);
        let x1 = (self.x0 + width).min(w);
        Rect { x0: x1 - width, x1, ..*self }
    }
}

/// The smallest rectangle holding `r` (if any) and pixel (x, y).
pub fn including(r: Option<Rect>, x: usize, y: usize) -> Rect {
    match r {
        None => Rect { x0: x, y0: y, x1: x + 1, y1: y + 1 },
        Some(r) => Rect { x0: r.x0.min(x), y0: r.y0.min(y), x1: r.x1.max(x + 1), y1: r.y1.max(y + 1) },
    }
}

/// Bounding box of the set pixels, or None for an empty mask.
pub fn bounding_box(mask: &[bool], w: usize) -> Option<Rect> {
    mask.iter().enumerate().filter(|(_, &m)| m).fold(None, |r, (i, _)| Some(including(r, i % w, i / w)))
}

/// Copies a rectangle out of a planar image (`channels` planes of `w` x `h`), or out of a mask or
/// label map with `channels` 1.
pub fn crop<T: Copy>(src: &[T], w: usize, h: usize, channels: usize, r: Rect) -> Vec<T> {
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
///
/// Each pass takes a row's three neighbours in the row before it (after it, going back) in one
/// loop the compiler vectorizes, then its neighbour along the row in a scan: the minimum over the
/// same candidates as a pixel-by-pixel pass, so the same values.
pub fn distance_to(mask: &[bool], w: usize, h: usize) -> Vec<f32> {
    let mut d: Vec<f32> = mask.iter().map(|&m| if m { 0.0 } else { f32::INFINITY }).collect();
    if w == 0 {
        return d;
    }
    for y in 0..h {
        let (done, rest) = d.split_at_mut(y * w);
        let row = &mut rest[..w];
        if y > 0 {
            from_next_row(row, &done[(y - 1) * w..]);
        }
        for x in 1..w {
            row[x] = row[x].min(row[x - 1] + 1.0);
        }
    }
    for y in (0..h).rev() {
        let (rest, done) = d.split_at_mut((y + 1) * w);
        let row = &mut rest[y * w..];
        if y + 1 < h {
            from_next_row(row, &done[..w]);
        }
        for x in (0..w - 1).rev() {
            row[x] = row[x].min(row[x + 1] + 1.0);
        }
    }
    d
}

/// One chamfer step from the row `next` beside `row` (the one above it or below it): each pixel
/// the nearer of itself and its three neighbours there.
fn from_next_row(row: &mut [f32], next: &[f32]) {
    let (w, s2) = (row.len(), std::f32::consts::SQRT_2);
    let next = &next[..w];
    row[0] = row[0].min(next[0] + 1.0);
    if w > 1 {
        row[0] = row[0].min(next[1] + s2);
        row[w - 1] = row[w - 1].min(next[w - 1] + 1.0).min(next[w - 2] + s2);
    }
    for x in 1..w.saturating_sub(1) {
        row[x] = row[x].min(next[x] + 1.0).min(next[x - 1] + s2).min(next[x + 1] + s2);
    }
}

/// The 8-connected components of the set pixels of `mask`, each as its pixel indices in scan
/// order of discovery; components in the order of their first pixel.
pub fn components(mask: &[bool], w: usize, h: usize) -> Vec<Vec<usize>> {
    let mut seen = vec![false; w * h];
    let mut out = Vec::new();
    for start in 0..w * h {
        if !mask[start] || seen[start] {
            continue;
        }
        seen[start] = true;
        let mut comp = vec![start];
        let mut next = 0;
        while next < comp.len() {
            let (x, y) = ((comp[next] % w) as isize, (comp[next] / w) as isize);
            next += 1;
            for (dx, dy) in [(-1, -1), (0, -1), (1, -1), (-1, 0), (1, 0), (-1, 1), (0, 1), (1, 1)] {
                let (nx, ny) = (x + dx, y + dy);
                if nx < 0 || ny < 0 || nx >= w as isize || ny >= h as isize {
                    continue;
                }
                let j = ny as usize * w + nx as usize;
                if mask[j] && !seen[j] {
                    seen[j] = true;
                    comp.push(j);
                }
            }
        }
        out.push(comp);
    }
    out
}

/// `distance_to` where it is at most `radius`, infinity elsewhere. Only the mask's bounding box
/// grown by the radius can be reached that near (a chamfer step moves at most a pixel along each
/// axis and costs at least 1), so the distance runs there: the same values, without a pass over
/// the whole image for a small mask.
pub fn distance_within(mask: &[bool], w: usize, h: usize, radius: f32) -> Vec<f32> {
    let mut out = vec![f32::INFINITY; w * h];
    let Some(b) = bounding_box(mask, w) else { return out };
    let reach = radius.max(0.0).ceil() as usize + 1;
    let win = b.grown(reach, reach, w, h);
    let (ww, wh) = (win.width(), win.height());
    let local = crop(mask, w, h, 1, win);
    for (k, d) in distance_to(&local, ww, wh).into_iter().enumerate() {
        if d <= radius {
            out[win.pixel(k, w)] = d;
        }
    }
    out
}

/// Grows a mask by `radius` pixels (a disc): the pixels within `radius` of it by `distance_to`.
pub fn dilate(mask: &[bool], w: usize, h: usize, radius: f32) -> Vec<bool> {
    if radius <= 0.0 {
        return mask.to_vec();
    }
    distance_within(mask, w, h, radius).iter().map(|&d| d <= radius).collect()
}

/// A soft version of `mask`: 1 inside, falling smoothly to 0 at `radius` pixels outside.
pub fn feather(mask: &[bool], w: usize, h: usize, radius: f32) -> Vec<f32> {
    distance_within(mask, w, h, radius.max(0.0))
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

/// Sums of `img` (`channels` planes of `w` x `h`) over the (2r+1)^2 window around each pixel,
/// the window cut at the borders: sums, not means, so that a weight plane blurred alongside
/// gives normalized convolution (blur of values over blur of weights).
pub fn box_sum(img: &[f32], w: usize, h: usize, channels: usize, r: usize) -> Vec<f32> {
    let n = w * h;
    let mut rows = vec![0f32; channels * n];
    for c in 0..channels {
        for y in 0..h {
            let line = &img[c * n + y * w..c * n + (y + 1) * w];
            for x in 0..w {
                rows[c * n + y * w + x] = line[x.saturating_sub(r)..=(x + r).min(w - 1)].iter().sum();
            }
        }
    }
    let mut out = vec![0f32; channels * n];
    for c in 0..channels {
        for y in 0..h {
            for x in 0..w {
                out[c * n + y * w + x] =
                    (y.saturating_sub(r)..=(y + r).min(h - 1)).map(|v| rows[c * n + v * w + x]).sum();
            }
        }
    }
    out
}

/// How many `mask` pixels lie in the (2r+1)^2 window around each pixel, the window cut at the
/// borders: `box_sum` of the mask, through an integral image (linear whatever `r`).
pub fn box_count(mask: &[bool], w: usize, h: usize, r: usize) -> Vec<u32> {
    // integral[(y + 1) * (w + 1) + x + 1] = the mask pixels in [0, x] x [0, y]
    let mut integral = vec![0u32; (w + 1) * (h + 1)];
    for y in 0..h {
        let mut row = 0;
        for x in 0..w {
            row += mask[y * w + x] as u32;
            integral[(y + 1) * (w + 1) + x + 1] = integral[y * (w + 1) + x + 1] + row;
        }
    }
    let mut out = vec![0u32; w * h];
    for y in 0..h {
        let (y0, y1) = (y.saturating_sub(r), (y + r + 1).min(h));
        for x in 0..w {
            let (x0, x1) = (x.saturating_sub(r), (x + r + 1).min(w));
            let at = |yy: usize, xx: usize| integral[yy * (w + 1) + xx];
            out[y * w + x] = at(y1, x1) + at(y0, x0) - at(y0, x1) - at(y1, x0);
        }
    }
    out
}

/// The mean of the `mask` pixels of `img` (`channels` planes of `w` x `h`) in the (2r+1)^2 window
/// around each `mask` pixel (normalized convolution: `box_sum` of the masked image over
/// `box_count` of the mask); 0 off the mask.
///
/// The sums run over the mask's bounding box grown by `r` only: a mask pixel's window (rows and
/// columns within `r` of it) lies inside it, so each of its sums adds the same values in the same
/// order as over the whole image (a surface's inventions cover a small part of a view).
pub fn masked_box_mean(img: &[f32], mask: &[bool], w: usize, h: usize, channels: usize, r: usize) -> Vec<f32> {
    let n = w * h;
    let mut out = vec![0.0; channels * n];
    let Some(b) = bounding_box(mask, w) else { return out };
    let win = b.grown(r, r, w, h);
    let (ww, wh, wn) = (win.width(), win.height(), win.width() * win.height());
    let local_mask = crop(mask, w, h, 1, win);
    let mut masked = crop(img, w, h, channels, win);
    masked.iter_mut().enumerate().filter(|(i, _)| !local_mask[i % wn]).for_each(|(_, v)| *v = 0.0);
    let (sums, counts) = (box_sum(&masked, ww, wh, channels, r), box_count(&local_mask, ww, wh, r));
    for i in (0..channels * wn).filter(|&i| local_mask[i % wn]) {
        out[(i / wn) * n + win.pixel(i % wn, w)] = sums[i] / counts[i % wn] as f32;
    }
    out
}

/// Maxima of `img` (`channels` planes of `w` x `h`) over the (2r+1)^2 window around each pixel,
/// the window cut at the borders; `f32::NEG_INFINITY` marks a missing value (and is the result
/// where the window holds none). Minima: negate in and out. Linear in the pixels whatever `r`.
pub fn box_max(img: &[f32], w: usize, h: usize, channels: usize, r: usize) -> Vec<f32> {
    let n = w * h;
    let mut rows = vec![0f32; channels * n];
    for c in 0..channels {
        for y in 0..h {
            let at = c * n + y * w..c * n + (y + 1) * w;
            sliding_max(&img[at.clone()], r, &mut rows[at]);
        }
    }
    let mut out = vec![0f32; channels * n];
    let (mut column, mut result) = (vec![0f32; h], vec![0f32; h]);
    for c in 0..channels {
        for x in 0..w {
            for y in 0..h {
                column[y] = rows[c * n + y * w + x];
            }
            sliding_max(&column, r, &mut result);
            for y in 0..h {
                out[c * n + y * w + x] = result[y];
            }
        }
    }
    out
}

/// The maximum over [i - r, i + r] of `v`, for each i, cut at the ends (van Herk / Gil-Werman):
/// padded with r missing values at each end, every window is 2r+1 long and spans at most two
/// blocks of that length, so its maximum is that of the running maximum of the first block from
/// the right (from the window's start) and of the second from the left (up to its end).
fn sliding_max(v: &[f32], r: usize, out: &mut [f32]) {
    let k = 2 * r + 1;
    let mut padded = vec![f32::NEG_INFINITY; v.len() + 2 * r];
    padded[r..r + v.len()].copy_from_slice(v);
    let m = padded.len();
    let (mut from_left, mut from_right) = (padded.clone(), padded);
    for i in 1..m {
        if i % k != 0 {
            from_left[i] = from_left[i].max(from_left[i - 1]);
        }
    }
    for i in (0..m - 1).rev() {
        if i % k != k - 1 {
            from_right[i] = from_right[i].max(from_right[i + 1]);
        }
    }
    for (i, o) in out.iter_mut().enumerate() {
        *o = from_right[i].max(from_left[i + 2 * r]);
    }
}

/// Concatenates planar RGB images of one height side by side, 2-pixel white gaps, into RGB8.
pub fn hstack_rgb8(images: &[&[f32]], w: usize, h: usize) -> (u32, u32, Vec<u8>) {
    let gap = 2;
    let total_w = images.len() * w + (images.len() - 1) * gap;
    let mut out = vec![255u8; total_w * h * 3];
    for (k, img) in images.iter().enumerate() {
        let x0 = k * (w + gap);
        for y in 0..h {
            for x in 0..w {
                for c in 0..3 {
                    out[(y * total_w + x0 + x) * 3 + c] = crate::io::to_u8(img[c * w * h + y * w + x]);
                }
            }
        }
    }
    (total_w as u32, h as u32, out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn widened_rectangles_keep_their_pixels_and_stay_in_the_image() {
        let w = 30;
        for x0 in 0..w {
            for x1 in x0 + 1..=w {
                let r = Rect { x0, y0: 2, x1, y1: 5 };
                let v = r.widened_to_multiple(4, w);
                assert!(v.x0 <= x0 && v.x1 >= x1 && v.x1 <= w, "{r:?} -> {v:?}");
                assert_eq!((v.y0, v.y1), (2, 5));
                // a multiple of 4 where the image allows it, and no wider than needed
                let want = (x1 - x0).div_ceil(4) * 4;
                assert_eq!(v.width(), want.min(w), "{r:?} -> {v:?}");
                // grown to the right first
                assert_eq!(v.x0, x0.min(w - v.width()), "{r:?} -> {v:?}");
            }
        }
    }

    #[test]
    fn box_sum_counts_the_window_cut_at_the_borders() {
        // a plane of ones gives each pixel the size of its window; one channel of index values
        // gives the closed-form sum over the window
        let (w, h, r) = (7usize, 5usize, 2usize);
        let mut img = vec![1f32; w * h];
        img.extend((0..w * h).map(|p| p as f32));
        let s = box_sum(&img, w, h, 2, r);
        for y in 0..h {
            for x in 0..w {
                let (xs, ys) = (x.saturating_sub(r)..=(x + r).min(w - 1), y.saturating_sub(r)..=(y + r).min(h - 1));
                assert_eq!(s[y * w + x], (xs.clone().count() * ys.clone().count()) as f32);
                let want: usize = ys.flat_map(|v| xs.clone().map(move |u| v * w + u)).sum();
                assert_eq!(s[w * h + y * w + x], want as f32);
            }
        }
    }

    #[test]
    fn box_count_is_the_box_sum_of_the_mask() {
        let (w, h) = (11usize, 7usize);
        let mut rng = crate::rng::Rng::new(5);
        let mask: Vec<bool> = (0..w * h).map(|_| rng.uniform() < 0.4).collect();
        let plane: Vec<f32> = mask.iter().map(|&m| m as u32 as f32).collect();
        for r in [0usize, 1, 3, 6, 20] {
            let want = box_sum(&plane, w, h, 1, r);
            let got = box_count(&mask, w, h, r);
            assert!(got.iter().zip(&want).all(|(&g, &s)| g as f32 == s), "r {r}");
        }
    }

    #[test]
    fn box_max_is_the_maximum_over_the_window_cut_at_the_borders() {
        // against the window scanned directly, with missing values, for radii from 0 to past the image
        let (w, h) = (13usize, 9usize);
        let mut rng = crate::rng::Rng::new(7);
        let img: Vec<f32> = (0..2 * w * h)
            .map(|_| if rng.uniform() < 0.6 { f32::NEG_INFINITY } else { rng.uniform() as f32 })
            .collect();
        for r in [0usize, 1, 2, 3, 5, 14] {
            let got = box_max(&img, w, h, 2, r);
            for c in 0..2 {
                for y in 0..h {
                    for x in 0..w {
                        let (xs, ys) =
                            (x.saturating_sub(r)..=(x + r).min(w - 1), y.saturating_sub(r)..=(y + r).min(h - 1));
                        let img = &img;
                        let want = ys
                            .flat_map(|v| xs.clone().map(move |u| img[c * w * h + v * w + u]))
                            .fold(f32::NEG_INFINITY, f32::max);
                        assert_eq!(got[c * w * h + y * w + x], want, "r {r} channel {c} ({x}, {y})");
                    }
                }
            }
        }
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
    fn masked_box_mean_in_the_masks_box_equals_the_whole_images() {
        let mut rng = crate::rng::Rng::new(5);
        for trial in 0..60 {
            let (w, h, channels) = (5 + rng.below(40), 4 + rng.below(30), 1 + trial % 3);
            let img: Vec<f32> = (0..channels * w * h).map(|_| rng.uniform() as f32).collect();
            // a blob somewhere, sometimes at a border, or nothing
            let (cx, cy, rad) = (rng.below(w) as f64, rng.below(h) as f64, 4.0 * rng.uniform());
            let mask: Vec<bool> = (0..w * h)
                .map(|p| trial % 10 != 0 && ((p % w) as f64 - cx).hypot((p / w) as f64 - cy) <= rad)
                .collect();
            let r = rng.below(6);
            let n = w * h;
            // the whole image's normalized convolution, as before the crop
            let masked: Vec<f32> = (0..channels * n).map(|i| if mask[i % n] { img[i] } else { 0.0 }).collect();
            let (sums, counts) = (box_sum(&masked, w, h, channels, r), box_count(&mask, w, h, r));
            let want: Vec<f32> =
                (0..channels * n).map(|i| if mask[i % n] { sums[i] / counts[i % n] as f32 } else { 0.0 }).collect();
            let got = masked_box_mean(&img, &mask, w, h, channels, r);
            assert!(got.iter().zip(&want).all(|(a, b)| a.to_bits() == b.to_bits()), "trial {trial}");
        }
    }

    /// The chamfer pixel by pixel, as `distance_to` was written first.
    fn chamfer_pixel_by_pixel(mask: &[bool], w: usize, h: usize) -> Vec<f32> {
        let mut d: Vec<f32> = mask.iter().map(|&m| if m { 0.0 } else { f32::INFINITY }).collect();
        let s2 = std::f32::consts::SQRT_2;
        for i in 0..w * h {
            let (x, y) = (i % w, i / w);
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
        for i in (0..w * h).rev() {
            let (x, y) = (i % w, i / w);
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
        d
    }

    #[test]
    fn distance_row_by_row_equals_the_pixel_by_pixel_chamfer() {
        let mut rng = crate::rng::Rng::new(3);
        for trial in 0..200 {
            let (w, h) = (1 + rng.below(40), 1 + rng.below(30));
            let density = [0.0, 0.003, 0.02, 0.2, 0.9][trial % 5];
            let m: Vec<bool> = (0..w * h).map(|_| rng.uniform() < density).collect();
            let (got, want) = (distance_to(&m, w, h), chamfer_pixel_by_pixel(&m, w, h));
            assert!(got.iter().zip(&want).all(|(a, b)| a.to_bits() == b.to_bits()), "trial {trial}: {w} x {h}");
        }
    }

    #[test]
    fn distance_and_dilation_in_the_masks_box_equal_the_whole_images() {
        // random sparse masks, some touching the border, against the distance over the whole image
        let mut rng = crate::rng::Rng::new(7);
        for trial in 0..40 {
            let (w, h) = (30 + trial % 7, 25 + trial % 5);
            let density = [0.002, 0.01, 0.05][trial % 3];
            let m: Vec<bool> = (0..w * h).map(|_| rng.uniform() < density).collect();
            for radius in [0.0f32, 0.5, 1.0, 1.5, 2.0, 3.7, 6.0, 11.0] {
                let whole = distance_to(&m, w, h);
                let near: Vec<f32> = whole.iter().map(|&d| if d <= radius { d } else { f32::INFINITY }).collect();
                let within = distance_within(&m, w, h, radius);
                assert!(
                    within.iter().zip(&near).all(|(a, b)| a.to_bits() == b.to_bits()),
                    "trial {trial}, radius {radius}"
                );
                let grown: Vec<bool> = whole.iter().map(|&d| d <= radius).collect();
                if radius > 0.0 {
                    assert_eq!(dilate(&m, w, h, radius), grown, "trial {trial}, radius {radius}");
                }
            }
        }
    }

    #[test]
    fn components_join_diagonal_neighbours_and_keep_apart_the_rest() {
        // 6 x 4:  X . . . . X
        //         . X . . . X
        //         . . . . . .
        //         . . . X . .
        let (w, h) = (6, 4);
        let set = [0, 5, 7, 11, 21];
        let mask: Vec<bool> = (0..w * h).map(|i| set.contains(&i)).collect();
        let mut parts = components(&mask, w, h);
        parts.iter_mut().for_each(|p| p.sort());
        assert_eq!(parts, vec![vec![0, 7], vec![5, 11], vec![21]]);
        assert!(components(&vec![false; w * h], w, h).is_empty());
    }
}
