//! Scoring a `Trainer`'s scene against views (held-out or training): raw and exposure-fitted
//! PSNR and SSIM, or the raw PSNR alone where that is all a caller reads.

use super::Trainer;
use crate::eval::render_psnr;
use crate::render::RenderSettings;
use crate::scene::dataset::View;
use crate::scene::exposure::ColorAffine;
use crate::train::loss::reference as loss_ref;
use anyhow::Result;

/// Mean image metrics of views against their photos: raw (the render as it is) and with each
/// view's exposure map fitted by least squares on all its pixels (12 numbers against thousands of
/// pixels), which scores the scene without its views' exposure differences.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Metrics {
    pub psnr: f64,
    pub ssim: f64,
    pub psnr_exposure_fitted: f64,
    pub ssim_exposure_fitted: f64,
    pub views: usize,
}

impl Trainer {
    /// How `evaluate` and `mean_psnr` render: the training's background, the current SH degree.
    fn evaluation_settings(&self) -> RenderSettings {
        RenderSettings {
            background: self.cfg.background,
            sh_degree: Some(self.active_sh_degree()),
            ..Default::default()
        }
    }

    /// The mean over `views` of `evaluate`'s raw PSNR alone: without SSIM and the exposure-fitted
    /// scores, whose CPU work was most of the time of the removal's two evaluations.
    pub fn mean_psnr(&mut self, views: &[View]) -> Result<f64> {
        let settings = self.evaluation_settings();
        let mut sum = 0.0;
        for v in views {
            sum += render_psnr(&self.raster.render(&self.scene, &v.camera, &settings)?.rgb, &v.image);
        }
        Ok(if views.is_empty() { 0.0 } else { sum / views.len() as f64 })
    }

    /// Renders `views` and compares them with their images: mean PSNR and SSIM.
    pub fn evaluate(&mut self, views: &[View]) -> Result<Metrics> {
        let mut metrics = Metrics { views: views.len(), ..Default::default() };
        if views.is_empty() {
            return Ok(metrics);
        }
        let settings = self.evaluation_settings();
        let n = views.len() as f64;
        for v in views {
            let out = self.raster.render(&self.scene, &v.camera, &settings)?;
            let (w, h) = (out.width as usize, out.height as usize);
            let clamped: Vec<f32> = out.rgb.iter().map(|&c| c.clamp(0.0, 1.0)).collect();
            let fitted = ColorAffine::fitted_render(&clamped, &v.image, None);
            for (rgb, psnr, ssim) in [
                (&clamped, &mut metrics.psnr, &mut metrics.ssim),
                (&fitted, &mut metrics.psnr_exposure_fitted, &mut metrics.ssim_exposure_fitted),
            ] {
                *psnr += render_psnr(rgb, &v.image) / n;
                let x: Vec<f64> = rgb.iter().map(|&c| c.clamp(0.0, 1.0) as f64).collect();
                let y: Vec<f64> = v.image.iter().map(|&c| c as f64).collect();
                *ssim += loss_ref::ssim(&x, &y, w, h, None) / n;
            }
        }
        Ok(metrics)
    }
}
