//! Depth-guided color transfer between the edited views. A hole pixel of view i is
//! back-projected at its completed depth; where a training view saw that surface point (outside
//! that view's hole, at the depth that view's original render has there; view i itself first,
//! then the others), the point's color is taken from that view's captured image instead of being
//! invented. Only a good depth puts the point where another view really saw it, so this is where
//! depth guidance pays off in color, not just in geometry.

use super::source_views::{back_project, sees, SourceView};
use crate::image_ops::{
    bounding_box, box_count, box_max, box_sum, distance_within, sample_bilinear, sample_lanczos3_rgb,
};
use crate::scene::exposure::ColorAffine;
use crate::scene::Camera;

/// Colors found for the fill pixels of one target view.
pub struct Transfer {
    /// Planar RGB, valid where `found`.
    pub rgb: Vec<f32>,
    pub found: Vec<bool>,
}

/// Local color matching's window half-width, as a share of the image width (8 pixels at 200):
/// wide enough to hold a ring of the hole's own-photo pixels beside the ones it corrects.
const LOCAL_MATCH_SPAN: f64 = 1.0 / 25.0;
/// A pixel whose own and other colors differ by more than this in a channel shows a misregistered
/// edge, not a tint, and does not count in local color matching (synth two-of-three: masked PSNR
/// 20.28 dB counting every pixel, 20.34 with this; the cup composite 25.29 and 25.21).
const LOCAL_MATCH_MAX_DIFFERENCE: f64 = 0.2;
/// Own-photo range check: another view's color for a hole pixel, matched locally, must lie in
/// each channel within the range of the target's own-photo colors within OWN_RANGE_SPAN of the
/// image width, widened by OWN_RANGE_MARGIN, where at least OWN_RANGE_MIN_PIXELS such colors are
/// known. The window is wide so that a textured surface shows its whole palette in it: at 30
/// pixels of 160 the synth scenes keep their masked PSNR within 0.25 dB, at 6 one lost 0.4 dB;
/// 0.2 and 0.25 of the width score alike on every bench scene, 0.15 cost synth two-of-three
/// 0.2 dB more (measured with the check before local matching).
const OWN_RANGE_SPAN: f64 = 0.2;
const OWN_RANGE_MARGIN: f64 = 0.05;
const OWN_RANGE_MIN_PIXELS: u32 = 3;
/// Most points around the hole that match one source's colors to the target's (`source_offsets`),
/// and the fewest that may.
const SOURCE_MATCH_POINTS: usize = 1000;
const SOURCE_MATCH_MIN_POINTS: usize = 20;

/// Transfers colors into the `fill` pixels (the pipeline passes the whole hole) of view `target`
/// (camera, completed depth) from the `sources` (all edited views, `sources[target]` the target's
/// own). A source qualifies when the point projects inside it, off its hole, where its original
/// render is opaque (alpha > 0.5) and at the point's depth within `tolerance` (relative). The
/// target's own photo comes first: in the dilation ring and wherever else the removed objects did
/// not cover the pixel in the capture, it holds the surface's color itself, not resampled from
/// another viewpoint (held-out seen-elsewhere PSNR +0.05 to +0.15 dB on the bench scenes). Then
/// the nearest qualifying camera wins. Photos are sampled with Lanczos-3.
///
/// Another view's color is refused (the pixel left for invention) where it falls outside the
/// colors the target's own photo shows around the hole (`refuse_outside_own_range`): there the
/// point landed, in that view, on something else than the surface the target sees, such as the
/// removed object's own edge in a photo taken where its silhouette was a little wider than the
/// hole (the cup's desk took the removed boxes' colors in a 2-4 pixel band inside the hole,
/// errors up to 0.4: masked PSNR 21.68 -> 23.45 dB, LPIPS 0.063 -> 0.036 on the cup's
/// two-of-three composite).
///
/// Another view's photo differs from the target's in exposure, white balance and the light the
/// surface sends its way, so its colors are matched to the target's three times (cup composite,
/// masked PSNR 24.44 -> 25.21 dB, LPIPS 0.043 -> 0.038 with the first and last; without them, a
/// patchwork of the sources' tints):
/// - globally, through the inverse of the source's photo colors and then the target's
///   (`SourceView::photo_colors`), as --exposure training's maps would;
/// - per source, by the median difference between the two photos over the points around the
///   hole that both saw (`source_offsets`; cup-one's held-out masked PSNR 25.98 -> 27.12 dB,
///   LPIPS 0.152 -> 0.129);
/// - locally, by the mean difference between the target's own photo and the other sources over
///   the pixels where both saw the surface (the ring around the objects), within a window of
///   LOCAL_MATCH_SPAN of the image width: a normalized convolution, so that it fades where no
///   own pixel is near.
pub fn transfer(
    target: usize,
    camera: &Camera,
    depth: &[f32],
    fill: &[bool],
    sources: &[SourceView],
    tolerance: f64,
) -> Transfer {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let n = w * h;
    let center = camera.center();
    // the target itself first, then the others by distance of their camera centers to the target's
    let mut order: Vec<usize> = (0..sources.len()).collect();
    let dist = |j: usize| {
        if j == target {
            return -1.0;
        }
        let c = sources[j].camera.center();
        (0..3).map(|k| (c[k] - center[k]).powi(2)).sum::<f64>()
    };
    order.sort_by(|&a, &b| dist(a).total_cmp(&dist(b)));
    let to_target: Vec<ColorAffine> = sources
        .iter()
        .map(|s| {
            s.photo_colors.inverse().map_or(ColorAffine::IDENTITY, |back| sources[target].photo_colors.after(&back))
        })
        .collect();
    let offsets = source_offsets(target, camera, fill, sources, &to_target, tolerance);
    // per pixel, the target's own photo where it saw the point and the nearest other source's
    let (mut own, mut other) = (vec![None::<[f64; 3]>; n], vec![None::<[f64; 3]>; n]);
    for p in (0..n).filter(|&p| fill[p] && depth[p] > 0.0 && depth[p].is_finite()) {
        let world = back_project(camera, p, depth[p] as f64);
        for &j in &order {
            let s = &sources[j];
            let Some((x, y)) = sees(s, world, tolerance) else { continue };
            let (sw, sh) = (s.camera.width as usize, s.camera.height as usize);
            // Lanczos, not bilinear: a transferred checkerboard keeps its edges (held-out
            // seen-elsewhere PSNR +0.3 dB on the bench scenes)
            let rgb = sample_lanczos3_rgb(s.photo, sw, sh, x, y).map(f64::from);
            if j == target {
                own[p] = Some(rgb);
            } else {
                let matched = to_target[j].apply_pixel(rgb);
                other[p] = Some(std::array::from_fn(|c| matched[c] + offsets[j][c]));
                break;
            }
        }
    }
    let radius = (w as f64 * LOCAL_MATCH_SPAN).round().max(1.0) as usize;
    let offset = local_offset(&own, &other, w, h, radius);
    // after local matching (a refused pixel has no own color, so it never counted in the offset)
    let span = (w as f64 * OWN_RANGE_SPAN).round().max(1.0) as usize;
    refuse_outside_own_range(&own, &mut other, &offset, w, h, span);
    let mut out = Transfer { rgb: vec![0.0; 3 * n], found: vec![false; n] };
    for p in 0..n {
        let rgb = match (own[p], other[p]) {
            (Some(rgb), _) => rgb,
            (None, Some(rgb)) => std::array::from_fn(|c| rgb[c] + offset[c * n + p] as f64),
            (None, None) => continue,
        };
        // clamped, as Lanczos may ring at steps
        for c in 0..3 {
            out.rgb[c * n + p] = (rgb[c] as f32).clamp(0.0, 1.0);
        }
        out.found[p] = true;
    }
    out
}

/// Per source (by index; zero for the `target` itself and where too few points say), the median
/// difference, channel by channel, between the target's own photo and the source's photo matched
/// globally (`to_target`) over surface points around the `hole` that both saw: the target's
/// pixels within LOCAL_MATCH_SPAN of the image width of the hole, off it, at its original render's
/// depth, at most SOURCE_MATCH_POINTS of them spread evenly. A fill pixel takes its color from
/// whichever source saw its point, and the views that see a removed object's footprint past its
/// sides are far from the target: the glossy desk of the cup composite looked up to 0.15 darker
/// or 0.07 lighter from them than from the target, a patchwork across the footprint that local
/// matching (which sees only the nearest source, in the hole's thin ring of own pixels) missed.
fn source_offsets(
    target: usize,
    camera: &Camera,
    hole: &[bool],
    sources: &[SourceView],
    to_target: &[ColorAffine],
    tolerance: f64,
) -> Vec<[f64; 3]> {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let n = w * h;
    let own = &sources[target];
    let reach = (w as f64 * LOCAL_MATCH_SPAN).max(1.0) as f32;
    let distance = distance_within(hole, w, h, reach);
    let around: Vec<usize> = (0..n)
        .filter(|&p| !hole[p] && !own.hole[p] && distance[p] <= reach && own.alpha[p] > 0.5 && own.depth[p] > 0.0)
        .collect();
    let step = around.len().div_ceil(SOURCE_MATCH_POINTS).max(1);
    let points: Vec<([f64; 3], [f64; 3])> = around
        .iter()
        .step_by(step)
        .map(|&p| {
            let color = std::array::from_fn(|c| own.photo[c * n + p] as f64);
            (back_project(camera, p, own.depth[p] as f64), color)
        })
        .collect();
    let offset = |j: usize| -> [f64; 3] {
        let s = &sources[j];
        let (sw, sh) = (s.camera.width as usize, s.camera.height as usize);
        let mut diffs: [Vec<f64>; 3] = Default::default();
        for (world, color) in &points {
            let Some((x, y)) = sees(s, *world, tolerance) else { continue };
            let seen =
                to_target[j].apply_pixel(std::array::from_fn(|c| sample_bilinear(s.photo, sw, sh, c, x, y) as f64));
            let d: [f64; 3] = std::array::from_fn(|c| color[c] - seen[c]);
            // a misregistered edge, not a tint (as in local matching)
            if d.iter().all(|v| v.abs() <= LOCAL_MATCH_MAX_DIFFERENCE) {
                (0..3).for_each(|c| diffs[c].push(d[c]));
            }
        }
        if diffs[0].len() < SOURCE_MATCH_MIN_POINTS {
            return [0.0; 3];
        }
        std::array::from_fn(|c| {
            let v = &mut diffs[c];
            let mid = v.len() / 2;
            *v.select_nth_unstable_by(mid, f64::total_cmp).1
        })
    };
    (0..sources.len()).map(|j| if j == target { [0.0; 3] } else { offset(j) }).collect()
}

/// Clears each `other` color that, once matched locally (plus `offset`, planar RGB), has a
/// channel outside [min - OWN_RANGE_MARGIN, max + OWN_RANGE_MARGIN] of the `own` colors within
/// the (2 `radius` + 1)^2 window around it, where that window holds at least
/// OWN_RANGE_MIN_PIXELS own colors (elsewhere the own photo says nothing and the other color
/// stays). Matched, since a tint between the photos is not another surface.
fn refuse_outside_own_range(
    own: &[Option<[f64; 3]>],
    other: &mut [Option<[f64; 3]>],
    offset: &[f32],
    w: usize,
    h: usize,
    radius: usize,
) {
    let n = w * h;
    let known: Vec<bool> = own.iter().map(|o| o.is_some()).collect();
    if !known.contains(&true) {
        return;
    }
    // planes of own colors (missing: -inf) and of their negations, for the window's max and min
    let mut planes = vec![f32::NEG_INFINITY; 6 * n];
    for p in 0..n {
        if let Some(rgb) = own[p] {
            for c in 0..3 {
                planes[c * n + p] = rgb[c] as f32;
                planes[(3 + c) * n + p] = -rgb[c] as f32;
            }
        }
    }
    let extremes = box_max(&planes, w, h, 6, radius);
    let counts = box_count(&known, w, h, radius);
    for p in 0..n {
        let Some(rgb) = other[p] else { continue };
        if own[p].is_some() || counts[p] < OWN_RANGE_MIN_PIXELS {
            continue;
        }
        let outside = (0..3).any(|c| {
            let (lo, hi) = (-extremes[(3 + c) * n + p] as f64, extremes[c * n + p] as f64);
            let matched = rgb[c] + offset[c * n + p] as f64;
            matched < lo - OWN_RANGE_MARGIN || matched > hi + OWN_RANGE_MARGIN
        });
        if outside {
            other[p] = None;
        }
    }
}

/// Per pixel (planar RGB), the mean of `own - other` over the pixels within the window of
/// half-width 2 `radius` (two box passes: a tent) where both are known and differ by at most
/// LOCAL_MATCH_MAX_DIFFERENCE, weighted by the tent; 0 where no such pixel is near. Computed only
/// where it is read, the pixels with another view's color and none of their own (0 elsewhere):
/// the box passes run over those pixels' box grown by 2 `radius`, which holds every pixel their
/// sums reach, so the sums are the whole image's, term for term.
fn local_offset(own: &[Option<[f64; 3]>], other: &[Option<[f64; 3]>], w: usize, h: usize, radius: usize) -> Vec<f32> {
    let n = w * h;
    let mut out = vec![0f32; 3 * n];
    let read: Vec<bool> = (0..n).map(|p| own[p].is_none() && other[p].is_some()).collect();
    let Some(b) = bounding_box(&read, w) else { return out };
    let win = b.grown(2 * radius, 2 * radius, w, h);
    let (ww, wh) = (win.width(), win.height());
    let (wn, at) = (ww * wh, |k: usize| win.pixel(k, w));
    // three difference planes and a weight plane
    let mut diff = vec![0f32; 4 * wn];
    for k in 0..wn {
        if let (Some(a), Some(b)) = (own[at(k)], other[at(k)]) {
            if (0..3).any(|c| (a[c] - b[c]).abs() > LOCAL_MATCH_MAX_DIFFERENCE) {
                continue;
            }
            for c in 0..3 {
                diff[c * wn + k] = (a[c] - b[c]) as f32;
            }
            diff[3 * wn + k] = 1.0;
        }
    }
    let sums = box_sum(&box_sum(&diff, ww, wh, 4, radius), ww, wh, 4, radius);
    for k in (0..wn).filter(|&k| read[at(k)] && sums[3 * wn + k] > 0.5) {
        for c in 0..3 {
            out[c * n + at(k)] = sums[c * wn + k] / sums[3 * wn + k];
        }
    }
    out
}

/// What one edited view invented (its fill pixels that no photo showed), for the views completed
/// after it.
pub struct Invention<'a> {
    pub camera: &'a Camera,
    /// The view's completed image and depth.
    pub rgb: Vec<f32>,
    pub depth: Vec<f32>,
    pub invented: Vec<bool>,
}

/// One invention per surface point: the `fill` pixels of a view (camera, completed depth) whose
/// surface point an earlier view invented (`inventions`, nearest camera first) take that view's
/// color, so that the views agree where no photo says what is there instead of each inventing
/// its own (which fusion and refinement would average into a blur). A point qualifies where it
/// lands on an invented pixel at that view's completed depth within `tolerance` (relative).
pub fn borrow_inventions(
    camera: &Camera,
    depth: &[f32],
    fill: &[bool],
    inventions: &[Invention],
    tolerance: f64,
) -> Transfer {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let mut out = Transfer { rgb: vec![0.0; 3 * w * h], found: vec![false; w * h] };
    let center = camera.center();
    let mut order: Vec<&Invention> = inventions.iter().collect();
    let dist = |c: [f64; 3]| (0..3).map(|k| (c[k] - center[k]).powi(2)).sum::<f64>();
    order.sort_by(|a, b| dist(a.camera.center()).total_cmp(&dist(b.camera.center())));
    for p in (0..w * h).filter(|&p| fill[p] && depth[p] > 0.0 && depth[p].is_finite()) {
        let world = back_project(camera, p, depth[p] as f64);
        for inv in &order {
            let Some((x, y, z)) = inv.camera.project_to_image(world) else { continue };
            let (iw, ih) = (inv.camera.width as usize, inv.camera.height as usize);
            let q = y as usize * iw + x as usize;
            let d = inv.depth[q] as f64;
            if !inv.invented[q] || (z - d).abs() > tolerance * d {
                continue;
            }
            for (c, v) in sample_lanczos3_rgb(&inv.rgb, iw, ih, x, y).into_iter().enumerate() {
                out.rgb[c * w * h + p] = v.clamp(0.0, 1.0);
            }
            out.found[p] = true;
            break;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The local color offset against its closed form: the mean of own - other over the pairs
    /// that qualify, each weighted by the tent of two box passes cut at the image's borders (per
    /// axis, the count of window centres within `radius` of both pixels), computed only where
    /// another view's color stands without an own one.
    #[test]
    fn local_offset_is_the_tent_weighted_mean_difference_where_it_is_read() {
        let (w, h, radius) = (40usize, 30usize, 3usize);
        let mut rng = crate::rng::Rng::new(5);
        let mut color = |base: f64| -> [f64; 3] { std::array::from_fn(|_| base + 0.15 * rng.uniform()) };
        let (mut own, mut other) = (vec![None; w * h], vec![None; w * h]);
        for y in 0..h {
            for x in 0..w {
                let p = y * w + x;
                // the pairs lie up to 2 radius left of the first pixel that reads them
                if x < 20 {
                    own[p] = Some(color(0.3));
                }
                if x >= 14 && y >= 4 {
                    // a few pairs differ by more than LOCAL_MATCH_MAX_DIFFERENCE and do not count
                    other[p] = Some(color(if (x * y) % 11 == 0 { 0.6 } else { 0.35 }));
                }
            }
        }
        let offset = local_offset(&own, &other, w, h, radius);
        let reach = |a: usize, b: usize, dim: usize| {
            (0..dim).filter(|&m| m.abs_diff(a) <= radius && m.abs_diff(b) <= radius).count() as f64
        };
        let mut checked = 0;
        for p in 0..w * h {
            let (px, py) = (p % w, p / w);
            let read = own[p].is_none() && other[p].is_some();
            let (mut sum, mut weight) = ([0f64; 3], 0f64);
            for q in 0..w * h {
                let (Some(a), Some(b)) = (own[q], other[q]) else { continue };
                if (0..3).any(|c| (a[c] - b[c]).abs() > LOCAL_MATCH_MAX_DIFFERENCE) {
                    continue;
                }
                let k = reach(px, q % w, w) * reach(py, q / w, h);
                for c in 0..3 {
                    sum[c] += k * (a[c] - b[c]);
                }
                weight += k;
            }
            for c in 0..3 {
                let want = if read && weight > 0.5 { sum[c] / weight } else { 0.0 };
                let got = offset[c * w * h + p] as f64;
                assert!((got - want).abs() < 1e-5, "({px}, {py}) channel {c}: {got} against {want}");
            }
            checked += (read && weight > 0.5) as usize;
        }
        assert!(checked > 50, "only {checked} pixels with an offset");
    }

    /// Own colors on the left half (a gray ramp 0.40..0.50); other colors on the right half:
    /// within the ramp's range plus the margin they stay, outside it in any channel they go, and
    /// beyond the window's reach of the own pixels they stay whatever they are. The window of
    /// x = 21 holds own x 16..19 (0.484..0.50).
    #[test]
    fn other_colors_outside_the_own_photos_range_nearby_are_refused() {
        let (w, h, radius) = (40usize, 10usize, 5usize);
        let mut own = vec![None; w * h];
        for y in 0..h {
            for x in 0..20 {
                let g = 0.40 + 0.10 * x as f64 / 19.0;
                own[y * w + x] = Some([g, g, g]);
            }
        }
        let at = |x: usize| 5 * w + x;
        let mut other = vec![None; w * h];
        other[at(3)] = Some([0.9, 0.9, 0.9]); // the own photo's pixel wins anyway: untouched
        other[at(21)] = Some([0.42, 0.46, 0.50]); // red below 0.484 - 0.05: refused
        other[at(22)] = Some([0.46, 0.47, 0.52]); // within range: kept
        other[at(23)] = Some([0.46, 0.47, 0.60]); // blue above max + margin: refused
        other[at(30)] = Some([0.9, 0.1, 0.1]); // no own pixel within 5: kept
        refuse_outside_own_range(&own, &mut other, &vec![0.0; 3 * w * h], w, h, radius);
        assert_eq!(other[at(3)], Some([0.9, 0.9, 0.9]));
        assert_eq!(other[at(21)], None);
        assert_eq!(other[at(22)], Some([0.46, 0.47, 0.52]));
        assert_eq!(other[at(23)], None);
        assert_eq!(other[at(30)], Some([0.9, 0.1, 0.1]));
        // matched locally first: a blue tint of 0.1 between the photos, taken off, keeps x = 23
        let mut tinted = vec![None; w * h];
        tinted[at(23)] = Some([0.46, 0.47, 0.60]);
        let mut offset = vec![0f32; 3 * w * h];
        offset[2 * w * h..].fill(-0.1);
        refuse_outside_own_range(&own, &mut tinted, &offset, w, h, radius);
        assert_eq!(tinted[at(23)], Some([0.46, 0.47, 0.60]));
    }
}
