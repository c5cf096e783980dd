//! Image metrics of removal results: PSNR and SSIM over a mask, the mask's bounding box, or the
//! full image (planar RGB in [0, 1]).

use crate::train::loss::reference;

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
}

/// Evaluates `renders` (planar RGB, one per camera) against `data`'s ground truth; None when the
/// dataset has no `gt_background/` (not a synth dataset).
pub fn synth_metrics(
    data: &std::path::Path,
    cameras: &[crate::scene::Camera],
    renders: &[Vec<f32>],
    removed_labels: &[u8],
) -> anyhow::Result<Option<SynthMetrics>> {
    use crate::train::dataset::{find_image, load_rgb};
    let (gt_dir, mask_dir) = (data.join("gt_background"), data.join("object_mask"));
    if !gt_dir.is_dir() || !mask_dir.is_dir() {
        return Ok(None);
    }
    let mut m = SynthMetrics::default();
    for (cam, render) in cameras.iter().zip(renders) {
        let (w, h) = (cam.width as usize, cam.height as usize);
        let gt_path = find_image(&gt_dir, &cam.name)
            .ok_or_else(|| anyhow::anyhow!("{}: no ground truth for {}", gt_dir.display(), cam.name))?;
        let (gw, gh, gt) = load_rgb(&gt_path)?;
        if (gw as usize, gh as usize) != (w, h) {
            anyhow::bail!("{}: {gw}x{gh}, but the render is {w}x{h}", gt_path.display());
        }
        let mask_path = find_image(&mask_dir, &cam.name)
            .ok_or_else(|| anyhow::anyhow!("{}: no object mask for {}", mask_dir.display(), cam.name))?;
        let labels = image::open(&mask_path)?.to_luma8().into_raw();
        let mask: Vec<bool> = labels.iter().map(|l| removed_labels.contains(l)).collect();
        let Some(p) = masked_psnr(render, &gt, &mask) else { continue };
        m.masked_psnr += p;
        m.masked_ssim += masked_ssim(render, &gt, &mask, w, h).unwrap_or(0.0);
        m.full_psnr += masked_psnr(render, &gt, &vec![true; w * h]).unwrap();
        m.views += 1;
    }
    if m.views > 0 {
        let n = m.views as f64;
        m.masked_psnr /= n;
        m.masked_ssim /= n;
        m.full_psnr /= n;
    }
    Ok(Some(m))
}

/// Depth error of completed depth maps in their fill regions against a `cogeo synth` dataset's
/// object-free depth (`depth_background/`): (AbsRel, RMSE) over all fill pixels of all views; None
/// when the dataset has no such depth or no pixel was filled.
pub fn synth_depth_error(
    data: &std::path::Path,
    cameras: &[crate::scene::Camera],
    depths: &[Vec<f32>],
    fills: &[Vec<bool>],
) -> anyhow::Result<Option<(f64, f64)>> {
    let dir = data.join("depth_background");
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
