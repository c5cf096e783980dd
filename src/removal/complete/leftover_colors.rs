//! The colors of the Gaussians left behind a removed object, against the colors the transfer
//! brought and against the inpainter's invention.
//!
//! A transferred color is one other view's photo at the completed surface point: where that
//! point is off the surface by a pixel's parallax, where the surface shines back differently
//! towards that view, or where that view saw another surface there (the tumbler's rim beside the
//! cup composite's box), the view's target takes a blotch that no other view agrees with. The
//! leftovers, where they cover the pixel, were trained by every view that saw the surface: their
//! render is blurred, but its local mean is the surface's. So a transferred color is refused
//! where the mean of the transferred colors around it departs from the mean of the leftovers'
//! render over the same pixels by more than `MAX_DISAGREEMENT` in some channel; the pixel takes
//! the leftovers' render instead (`EditedView::take_leftover_colors`).
//!
//! Where no photo lent a color, the leftovers' render stands in for the invention only where it
//! looks like what the invention continues from around the hole: their window mean within
//! `MAX_UNLIKE_INVENTION` of the invention's. The leftovers are not always the surface behind the
//! object: on a statue composite the lawn's Gaussians behind the box, which the training views
//! hardly saw past it, rendered a brown and red smear (the box's edges had pulled their colors)
//! that every view's target then kept (held-out masked PSNR 18.86 dB, LPIPS 0.589; with this
//! check 20.70 / 0.317). On the cup composite they were the desk, seen around the box.
//!
//! Means over a window, not single pixels: a texture the leftovers blurred (the synth rooms'
//! checkerboards, the desk's grain) departs from them pixel by pixel but not on average.

use crate::image_ops::{box_count, box_sum};

/// Window radius (pixels) of the two means.
pub const WINDOW_RADIUS: usize = 2;

/// Largest departure (in any channel, colors in [0, 1]) of the transferred colors' window mean
/// from the leftovers'. Held-out masked PSNR / LPIPS on the cup composites (cup-one,
/// cup-two-of-three) and masked PSNR on the synth rooms (one / two-of-three / three-of-four),
/// each scene on one training: without the check 25.81 / 0.187, 26.64 / 0.159, 25.95 / 26.13 /
/// 26.20; at 0.15 26.48 / 0.182, 26.98 / 0.155, 25.94 / 26.12 / 26.17; at 0.1 26.58 / 0.188,
/// 26.59 / 0.170, 25.92 / 26.00 / 26.08; at 0.05 the synth rooms 25.70 / 25.28 / 25.89. Pixel by
/// pixel instead of window means, at 0.1 cup-one scored 26.70 / 0.197 and the synth rooms
/// 25.43 / 24.37 / 25.54, at 0.2 cup-one 26.50 / 0.181 and the synth rooms 25.80 / 25.21 / 26.05:
/// the leftovers blur the checkerboards.
pub const MAX_DISAGREEMENT: f32 = 0.15;

/// Largest departure (in any channel) of the leftovers' window mean from the invention's, where
/// no photo lent a color, for the leftovers' render to replace the invention. Held-out masked PSNR
/// / LPIPS, statue-one and cup-one each on one training: without the check 18.86 / 0.589 and
/// 26.48 / 0.182; at 0.15 statue-one 20.03 / 0.407; at 0.08 20.70 / 0.317 and 26.50 / 0.179; at
/// 0.05 20.66 / 0.315 and 26.39 / 0.178; at 0 (the inventions everywhere) 20.58 / 0.313 and
/// 25.99 / 0.176. Taking the render instead where two other views saw the leftovers' point gave
/// 20.61 / 0.315 and 26.47 / 0.175.
pub const MAX_UNLIKE_INVENTION: f32 = 0.08;

/// The pixels whose transferred color is refused: of the `compared` pixels (transferred, and
/// covered by the leftovers), those where the mean of `transferred` (planar RGB) over the
/// compared pixels of the (2 WINDOW_RADIUS + 1)^2 window around them departs from the mean of
/// `leftovers` (planar RGB, the leftovers' render in the same colors) over the same pixels by
/// more than MAX_DISAGREEMENT in some channel.
pub fn disagreeing_transfers(
    transferred: &[f32],
    leftovers: &[f32],
    compared: &[bool],
    w: usize,
    h: usize,
) -> Vec<bool> {
    window_means_depart(transferred, leftovers, compared, w, h, MAX_DISAGREEMENT)
}

/// The pixels whose leftovers' render does not replace the invention: of the `compared` pixels
/// (invented, and covered by the leftovers), those where the window means of `invented` and
/// `leftovers` (planar RGB, in the same colors) depart by more than MAX_UNLIKE_INVENTION in some
/// channel, as `disagreeing_transfers` measures.
pub fn unlike_invention(invented: &[f32], leftovers: &[f32], compared: &[bool], w: usize, h: usize) -> Vec<bool> {
    window_means_depart(invented, leftovers, compared, w, h, MAX_UNLIKE_INVENTION)
}

/// Of the `compared` pixels, those where the means of `a` and `b` over the compared pixels of
/// the window around them differ by more than `max` in some channel.
fn window_means_depart(a: &[f32], b: &[f32], compared: &[bool], w: usize, h: usize, max: f32) -> Vec<bool> {
    let n = w * h;
    // the difference of the two means is the mean of the difference: one window sum
    let difference: Vec<f32> = (0..3 * n).map(|i| if compared[i % n] { a[i] - b[i] } else { 0.0 }).collect();
    let count = box_count(compared, w, h, WINDOW_RADIUS);
    let sum = box_sum(&difference, w, h, 3, WINDOW_RADIUS);
    (0..n).map(|p| compared[p] && (0..3).any(|c| (sum[c * n + p] / count[p] as f32).abs() > max)).collect()
}
