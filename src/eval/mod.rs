//! Image metrics of removal results: PSNR and SSIM over a mask, the mask's bounding box, or the
//! full image (planar RGB in [0, 1]).

pub mod folder;
pub mod image_metrics;
pub mod models;

use image_metrics as reference;

/// PSNR in f64 of a render, clamped to [0, 1] as it is displayed, against its image.
pub fn render_psnr(render: &[f32], image: &[f32]) -> f64 {
    let se: f64 = render.iter().zip(image).map(|(&a, &b)| (a.clamp(0.0, 1.0) as f64 - b as f64).powi(2)).sum();
    10.0 * (1.0 / (se / render.len() as f64).max(1e-12)).log10()
}

/// PSNR over the pixels where `mask` is set (all channels); None for an empty mask.
pub fn masked_psnr(a: &[f32], b: &[f32], mask: &[bool]) -> Option<f64> {
    let hw = mask.len();
    let channels = a.len() / hw;
    let (mut se, mut n) = (0f64, 0usize);
    for c in 0..channels {
        for i in (0..hw).filter(|&i| mask[i]) {
            se += (a[c * hw + i] as f64 - b[c * hw + i] as f64).powi(2);
            n += 1;
        }
    }
    (n > 0).then(|| 10.0 * (1.0 / (se / n as f64).max(1e-12)).log10())
}

/// Mean SSIM over the pixels where `mask` is set (the 11x11 Gaussian window of the training loss).
pub fn masked_ssim(a: &[f32], b: &[f32], mask: &[bool], width: usize, height: usize) -> Option<f64> {
    if !mask.iter().any(|&m| m) {
        return None;
    }
    let x: Vec<f64> = a.iter().map(|&v| v as f64).collect();
    let y: Vec<f64> = b.iter().map(|&v| v as f64).collect();
    let m: Vec<f64> = mask.iter().map(|&v| v as u8 as f64).collect();
    Some(reference::ssim(&x, &y, width, height, Some(&m)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn masked_psnr_counts_only_the_mask() {
        let a = vec![0.5f32; 3 * 4];
        let mut b = a.clone();
        b[0] = 0.6; // pixel 0, red
        b[3] = 1.0; // pixel 3 (outside the mask), red
        let mask = [true, true, false, false];
        // 6 samples, one off by 0.1: mse = 0.01 / 6
        let expect = 10.0 * (6.0f64 / 0.01).log10();
        assert!((masked_psnr(&a, &b, &mask).unwrap() - expect).abs() < 1e-4);
        assert_eq!(masked_psnr(&a, &b, &[false; 4]), None);
    }
}

/// Metrics of renders against a `cogeo synth` dataset's object-free ground truth
/// (`gt_background/`), inside the true silhouettes of the removed objects (`object_mask/`).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct SynthMetrics {
    pub views: usize,
    /// Mean over views of PSNR / SSIM inside the removed objects' silhouettes.
    pub masked_psnr: f64,
    pub masked_ssim: f64,
    /// Mean full-image PSNR.
    pub full_psnr: f64,
    /// Mean masked PSNR after each render is mapped through the affine color map fitted to its
    /// ground truth on the pixels outside the silhouettes (scene::exposure): the score without the
    /// held-out view's own exposure, which no scene trained on other photos knows. The fields
    /// above are raw.
    pub masked_psnr_exposure_fitted: f64,
}

/// Evaluates `renders` (planar RGB, one per camera) against `data`'s ground truth of removing
/// `removed_labels` (`synth::ground_truth`); None when `data` is not a synth dataset.
pub fn synth_metrics(
    data: &std::path::Path,
    cameras: &[crate::scene::Camera],
    frames: &[Option<&crate::scene::undistort::Undistortion>],
    renders: &[Vec<f32>],
    removed_labels: &[u8],
) -> anyhow::Result<Option<SynthMetrics>> {
    use crate::scene::dataset::find_image;
    let (gt_dir, mask_dir) = (crate::synth::ground_truth(data, removed_labels).images, data.join("object_mask"));
    if !gt_dir.is_dir() || !mask_dir.is_dir() {
        return Ok(None);
    }
    let mut m = SynthMetrics::default();
    for ((cam, render), frame) in cameras.iter().zip(renders).zip(frames) {
        let (w, h) = (cam.width as usize, cam.height as usize);
        let gt_path = find_image(&gt_dir, &cam.name)
            .ok_or_else(|| anyhow::anyhow!("{}: no ground truth for {}", gt_dir.display(), cam.name))?;
        // stored in the photos' frame: undistorted like the photo was
        let gt = folder::load_same_size(&gt_path, cam.width, cam.height, "ground truth", *frame)?;
        let mask_path = find_image(&mask_dir, &cam.name)
            .ok_or_else(|| anyhow::anyhow!("{}: no object mask for {}", mask_dir.display(), cam.name))?;
        let labels = folder::load_labels(&mask_path, cam.width, cam.height, *frame)?;
        let mask: Vec<bool> = labels.iter().map(|l| removed_labels.contains(l)).collect();
        let Some(p) = masked_psnr(render, &gt, &mask) else { continue };
        m.masked_psnr += p;
        let known: Vec<bool> = mask.iter().map(|&x| !x).collect();
        let fitted = crate::scene::exposure::ColorAffine::fitted_render(render, &gt, Some(&known));
        m.masked_psnr_exposure_fitted += masked_psnr(&fitted, &gt, &mask).unwrap_or(p);
        m.masked_ssim += masked_ssim(render, &gt, &mask, w, h).unwrap_or(0.0);
        m.full_psnr += masked_psnr(render, &gt, &vec![true; w * h]).unwrap();
        m.views += 1;
    }
    if m.views > 0 {
        let n = m.views as f64;
        m.masked_psnr /= n;
        m.masked_psnr_exposure_fitted /= n;
        m.masked_ssim /= n;
        m.full_psnr /= n;
    }
    Ok(Some(m))
}

/// Depth error of completed depth maps in their fill regions against a `cogeo synth` dataset's
/// true depth after removing `removed_labels`: (AbsRel, RMSE) over all fill pixels of all views;
/// None when the dataset has no such depth or no pixel was filled.
pub fn synth_depth_error(
    data: &std::path::Path,
    removed_labels: &[u8],
    cameras: &[crate::scene::Camera],
    depths: &[Vec<f32>],
    fills: &[Vec<bool>],
) -> anyhow::Result<Option<(f64, f64)>> {
    let dir = crate::synth::ground_truth(data, removed_labels).depth;
    if !dir.is_dir() {
        return Ok(None);
    }
    let (mut rel, mut sq, mut n) = (0f64, 0f64, 0usize);
    for ((cam, depth), fill) in cameras.iter().zip(depths).zip(fills) {
        if depth.is_empty() {
            continue;
        }
        let (w, h, gt) = crate::io::read_exr_channel(&dir.join(format!("{}.exr", cam.name)), None)?;
        if (w, h) != (cam.width, cam.height) {
            anyhow::bail!("{}: size differs from the view", dir.join(format!("{}.exr", cam.name)).display());
        }
        for i in (0..depth.len()).filter(|&i| fill[i] && gt[i] > 0.0) {
            let e = depth[i] as f64 - gt[i] as f64;
            rel += e.abs() / gt[i] as f64;
            sq += e * e;
            n += 1;
        }
    }
    Ok((n > 0).then(|| (rel / n as f64, (sq / n as f64).sqrt())))
}

/// PSNR and SSIM of one region.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Scores {
    pub psnr: f64,
    pub ssim: f64,
    pub pixels: usize,
}

/// Scores inside `mask` (mean over mask pixels; SSIM from full windows, averaged over the mask).
pub fn mask_scores(a: &[f32], b: &[f32], mask: &[bool], w: usize, h: usize) -> Option<Scores> {
    Some(Scores {
        psnr: masked_psnr(a, b, mask)?,
        ssim: masked_ssim(a, b, mask, w, h)?,
        pixels: mask.iter().filter(|&&m| m).count(),
    })
}

/// Scores on the crop to the mask's bounding box (the SPIn-NeRF protocol): every pixel of the crop
/// counts, and SSIM windows see only the crop.
pub fn bbox_scores(a: &[f32], b: &[f32], mask: &[bool], w: usize, h: usize) -> Option<Scores> {
    use crate::image_ops::{bounding_box, crop};
    let r = bounding_box(mask, w)?;
    let channels = a.len() / (w * h);
    let (ca, cb) = (crop(a, w, h, channels, r), crop(b, w, h, channels, r));
    full_scores(&ca, &cb, r.width(), r.height())
}

/// Scores over the whole image.
pub fn full_scores(a: &[f32], b: &[f32], w: usize, h: usize) -> Option<Scores> {
    mask_scores(a, b, &vec![true; w * h], w, h)
}

/// Share of `mask` pixels where the render is closer (mean absolute RGB difference) to the image
/// with the objects than to the object-free ground truth, by more than `margin`: what is left of
/// the removed objects. None for an empty mask.
pub fn leftover_fraction(
    render: &[f32],
    with_objects: &[f32],
    background: &[f32],
    mask: &[bool],
    margin: f32,
) -> Option<f64> {
    let hw = mask.len();
    let channels = render.len() / hw;
    let (mut left, mut n) = (0usize, 0usize);
    for i in (0..hw).filter(|&i| mask[i]) {
        let (mut d_obj, mut d_bg) = (0f32, 0f32);
        for c in 0..channels {
            let r = render[c * hw + i];
            d_obj += (r - with_objects[c * hw + i]).abs();
            d_bg += (r - background[c * hw + i]).abs();
        }
        let (d_obj, d_bg) = (d_obj / channels as f32, d_bg / channels as f32);
        // pixels where the object and the background look alike say nothing
        if (0..channels).map(|c| (with_objects[c * hw + i] - background[c * hw + i]).abs()).sum::<f32>()
            / (channels as f32)
            <= margin
        {
            continue;
        }
        n += 1;
        if d_obj + margin < d_bg {
            left += 1;
        }
    }
    Some(if n == 0 { 0.0 } else { left as f64 / n as f64 }).filter(|_| mask.iter().any(|&m| m))
}

/// Eigenvalues of a symmetric matrix (row-major n x n), cyclic Jacobi in f64.
pub fn symmetric_eigenvalues(m: &[f64], n: usize) -> Vec<f64> {
    let mut a = m.to_vec();
    for _sweep in 0..100 {
        let off: f64 = (0..n)
            .flat_map(|i| (0..n).filter(move |&j| j != i).map(move |j| (i, j)))
            .map(|(i, j)| a[i * n + j].powi(2))
            .sum();
        let diag: f64 = (0..n).map(|i| a[i * n + i].powi(2)).sum();
        if off <= 1e-30 * diag.max(1e-300) {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = a[p * n + q];
                if apq.abs() < 1e-300 {
                    continue;
                }
                let theta = (a[q * n + q] - a[p * n + p]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..n {
                    let (akp, akq) = (a[k * n + p], a[k * n + q]);
                    a[k * n + p] = c * akp - s * akq;
                    a[k * n + q] = s * akp + c * akq;
                }
                for k in 0..n {
                    let (apk, aqk) = (a[p * n + k], a[q * n + k]);
                    a[p * n + k] = c * apk - s * aqk;
                    a[q * n + k] = s * apk + c * aqk;
                }
            }
        }
    }
    (0..n).map(|i| a[i * n + i]).collect()
}

/// Fréchet distance between Gaussians fitted to two feature sets (rows = samples, the FID
/// formula): |mu_a - mu_b|^2 + tr(S_a) + tr(S_b) - 2 tr((S_a S_b)^(1/2)).
///
/// With centered data matrices A (n_a x D) and B (n_b x D), S_a = A^T A / (n_a - 1) and the nonzero
/// eigenvalues of S_a S_b are those of (A B^T)(A B^T)^T / ((n_a - 1)(n_b - 1)), an n_a x n_a
/// symmetric matrix: exact, and cheap when there are fewer images than feature dimensions (2048
/// for Inception). Needs at least two samples per set.
pub fn frechet_distance(a: &[Vec<f64>], b: &[Vec<f64>]) -> Option<f64> {
    let d = a.first()?.len();
    if a.len() < 2 || b.len() < 2 || a.iter().chain(b).any(|r| r.len() != d) {
        return None;
    }
    let center = |x: &[Vec<f64>]| {
        let mu: Vec<f64> = (0..d).map(|k| x.iter().map(|r| r[k]).sum::<f64>() / x.len() as f64).collect();
        let c: Vec<Vec<f64>> = x.iter().map(|r| r.iter().zip(&mu).map(|(v, m)| v - m).collect()).collect();
        (mu, c)
    };
    let ((mu_a, ca), (mu_b, cb)) = (center(a), center(b));
    let (na, nb) = ((a.len() - 1) as f64, (b.len() - 1) as f64);
    let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(p, q)| p * q).sum::<f64>();
    let mean_term: f64 = mu_a.iter().zip(&mu_b).map(|(p, q)| (p - q).powi(2)).sum();
    let tr_a: f64 = ca.iter().map(|r| dot(r, r)).sum::<f64>() / na;
    let tr_b: f64 = cb.iter().map(|r| dot(r, r)).sum::<f64>() / nb;
    // C = A B^T (n_a x n_b); M = C C^T / (na nb)
    let c: Vec<Vec<f64>> = ca.iter().map(|ra| cb.iter().map(|rb| dot(ra, rb)).collect()).collect();
    let n = ca.len();
    let mut m = vec![0f64; n * n];
    for i in 0..n {
        for j in 0..n {
            m[i * n + j] = dot(&c[i], &c[j]) / (na * nb);
        }
    }
    let tr_sqrt: f64 = symmetric_eigenvalues(&m, n).iter().map(|&e| e.max(0.0).sqrt()).sum();
    Some((mean_term + tr_a + tr_b - 2.0 * tr_sqrt).max(0.0))
}

/// Floaters: the opacity-weighted count of Gaussians that lie off the true surface by more than
/// `tau` (relative to the true depth) in every view where their center projects inside `regions`
/// (per view: a pixel mask, e.g. the removed objects' silhouettes) in front of the camera. A
/// Gaussian on the true background surface passes in the view that sees it; one floating in
/// front of it, or left inside an object's volume, fails in all of them.
pub fn floater_score(
    scene: &crate::scene::GaussianScene,
    cameras: &[crate::scene::Camera],
    true_depth: &[Vec<f32>],
    regions: &[Vec<bool>],
    tau: f64,
) -> (f64, usize) {
    let (mut score, mut count) = (0f64, 0usize);
    for (i, m) in scene.means.iter().enumerate() {
        let p = [m[0] as f64, m[1] as f64, m[2] as f64];
        let (mut inside, mut on_surface) = (false, false);
        for ((cam, depth), region) in cameras.iter().zip(true_depth).zip(regions) {
            let pc = cam.to_camera(p);
            if pc[2] <= 1e-6 {
                continue;
            }
            let u = cam.fx * pc[0] / pc[2] + cam.cx;
            let v = cam.fy * pc[1] / pc[2] + cam.cy;
            if u < 0.0 || v < 0.0 || u >= cam.width as f64 || v >= cam.height as f64 {
                continue;
            }
            let q = v as usize * cam.width as usize + u as usize;
            if !region[q] || depth[q] <= 0.0 {
                continue;
            }
            inside = true;
            if (pc[2] - depth[q] as f64).abs() <= tau * depth[q] as f64 {
                on_surface = true;
                break;
            }
        }
        if inside && !on_surface {
            score += 1.0 / (1.0 + (-scene.opacity_logits[i] as f64).exp());
            count += 1;
        }
    }
    (score, count)
}
