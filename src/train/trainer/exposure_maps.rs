//! Per-view exposure maps of a `Trainer` (train/exposure.rs owns the passes): setting, reading
//! and writing them, and moving their common part into the scene at the end of training.

use super::Trainer;
use crate::scene::exposure::{ColorAffine, Exposures, ViewExposure};
use crate::train::exposure::ViewExposures;
use anyhow::{bail, Result};

impl Trainer {
    /// Applies `maps` (one per training view, in the dataset's order) to the renders before the
    /// loss, learning them further when `learn` (the refinement of a removal passes the trained
    /// scene's, fixed).
    pub fn set_exposures(&mut self, maps: &[ColorAffine], learn: bool) -> Result<()> {
        let mut e = ViewExposures::new(&self.gpu, self.target_offsets.len(), Some(maps))?;
        e.learn = learn;
        e.model = self.cfg.exposure_model;
        self.exposure = Some(e);
        Ok(())
    }

    /// The training views' exposure maps, when there are any.
    pub fn exposures(&self) -> Result<Option<Vec<ColorAffine>>> {
        self.exposure.as_ref().map(|e| e.download()).transpose()
    }

    /// The training views' exposure maps by view name (exposure.json), when there are any.
    pub fn exposure_file(&self) -> Result<Option<Exposures>> {
        Ok(self.exposures()?.map(|maps| Exposures {
            views: self
                .view_names
                .iter()
                .zip(maps)
                .map(|(name, map)| ViewExposure { name: name.clone(), map })
                .collect(),
        }))
    }

    /// Moves the common part of the exposure maps into the scene: with M their mean, the scene's
    /// colors become M(color) and each map A_v becomes A_v M^-1, so every view renders through its
    /// map exactly as before while the maps average to identity and the scene, rendered without
    /// any, shows the views' common exposure. Training alone leaves that common part wherever the
    /// early steps put it: no image depends on it, and the pull toward identity is too weak to
    /// move it. Call at the end of training (the Adam moments of the colors are not remapped).
    pub fn settle_exposure_gauge(&mut self) -> Result<()> {
        let Some(maps) = self.exposures()? else { return Ok(()) };
        let mean = ColorAffine::mean(&maps);
        let Some(inverse) = mean.inverse() else { bail!("the exposure maps' mean is singular") };
        let mut scene = self.download_scene()?;
        mean.map_scene_colors(&mut scene);
        let keep: Vec<Option<usize>> = (0..scene.len()).map(Some).collect();
        self.replace_scene(&scene, &keep)?;
        let learn = self.exposure.as_ref().is_some_and(|e| e.learn);
        let settled: Vec<ColorAffine> = maps.iter().map(|a| a.after(&inverse)).collect();
        self.set_exposures(&settled, learn)
    }

    /// Continues learning the maps of `file` (a checkpoint's), matched to the training views by
    /// name (identity for a view it does not name).
    pub fn resume_exposures(&mut self, file: &Exposures) -> Result<()> {
        let maps: Vec<ColorAffine> =
            self.view_names.iter().map(|n| file.get(n).copied().unwrap_or(ColorAffine::IDENTITY)).collect();
        self.set_exposures(&maps, true)
    }

    /// The exposure maps' rate: `exposure_lr` decaying exponentially to a tenth.
    pub(super) fn exposure_lr(&self) -> f32 {
        (self.cfg.exposure_lr as f64 * 0.1f64.powf(self.progress())) as f32
    }
}
