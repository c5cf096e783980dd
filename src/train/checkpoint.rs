//! Training checkpoints: `checkpoint/` holds scene.ply, the Adam moments (moments.bin: per group,
//! length as u64 then m and v as little-endian f32) and state.json (step, config). The folder is
//! and, when training learns exposure maps, exposure.json (the maps; their Adam moments start over
//! on resume, at the decayed rate). The folder is written as `checkpoint.tmp/` and swapped in by renames, so a kill at any point leaves either the
//! previous or the new checkpoint complete.

use super::trainer::{TrainConfig, Trainer};
use crate::scene::{ply, GaussianScene};
use anyhow::{bail, Context, Result};
use std::io::Write;
use std::path::{Path, PathBuf};

#[derive(serde::Serialize, serde::Deserialize)]
struct State {
    step: u32,
    config: TrainConfig,
}

fn dirs(out: &Path) -> (PathBuf, PathBuf, PathBuf) {
    (out.join("checkpoint"), out.join("checkpoint.tmp"), out.join("checkpoint.old"))
}

pub fn save(trainer: &Trainer, out: &Path) -> Result<()> {
    let (dir, tmp, old) = dirs(out);
    let _ = std::fs::remove_dir_all(&tmp);
    std::fs::create_dir_all(&tmp).with_context(|| format!("{}: cannot create", tmp.display()))?;
    let written = write_files(trainer, &tmp);
    if written.is_err() {
        let _ = std::fs::remove_dir_all(&tmp); // a full disk: the previous checkpoint stays alone
    }
    written?;
    // swap: checkpoint -> checkpoint.old, checkpoint.tmp -> checkpoint, drop the old one
    let _ = std::fs::remove_dir_all(&old);
    if dir.exists() {
        std::fs::rename(&dir, &old)?;
    }
    std::fs::rename(&tmp, &dir)?;
    let _ = std::fs::remove_dir_all(&old);
    Ok(())
}

fn write_files(trainer: &Trainer, tmp: &Path) -> Result<()> {
    ply::write_ply(&trainer.download_scene()?, &tmp.join("scene.ply"))?;
    let moments = trainer.moments_host()?;
    crate::io::write_atomic(&tmp.join("moments.bin"), |w| {
        for (m, v) in &moments {
            w.write_all(&(m.len() as u64).to_le_bytes())?;
            w.write_all(bytemuck::cast_slice(m))?;
            w.write_all(bytemuck::cast_slice(v))?;
        }
        Ok(())
    })?;
    if let Some(e) = trainer.exposure_file()? {
        e.write(&tmp.join("exposure.json"))?;
    }
    let state = serde_json::to_string_pretty(&State { step: trainer.step, config: trainer.cfg.clone() })?;
    crate::io::write_atomic(&tmp.join("state.json"), |w| w.write_all(state.as_bytes()).map_err(Into::into))
}

/// A loaded checkpoint: the scene, the step it reached, and the optimizer moments.
pub struct Checkpoint {
    pub scene: GaussianScene,
    pub step: u32,
    pub config: TrainConfig,
    pub moments: Vec<(Vec<f32>, Vec<f32>)>,
    pub exposures: Option<crate::scene::exposure::Exposures>,
}

/// Loads the newest complete checkpoint in `out` (`checkpoint/`, or `checkpoint.old/` when a kill
/// came between the two renames), or None.
pub fn load(out: &Path) -> Result<Option<Checkpoint>> {
    let (dir, _, old) = dirs(out);
    let dir = if dir.join("state.json").exists() {
        dir
    } else if old.join("state.json").exists() {
        old
    } else {
        return Ok(None);
    };
    let state: State = serde_json::from_str(&std::fs::read_to_string(dir.join("state.json"))?)
        .with_context(|| format!("{}: corrupt checkpoint state", dir.display()))?;
    let scene = ply::read_ply(&dir.join("scene.ply"))?;
    let bytes =
        std::fs::read(dir.join("moments.bin")).with_context(|| format!("{}: cannot read moments", dir.display()))?;
    let mut moments = Vec::new();
    let mut pos = 0;
    while pos < bytes.len() {
        if pos + 8 > bytes.len() {
            bail!("{}: truncated moments.bin", dir.display());
        }
        let n = u64::from_le_bytes(bytes[pos..pos + 8].try_into().unwrap()) as usize;
        pos += 8;
        if n > (bytes.len() - pos) / 8 {
            bail!("{}: truncated moments.bin (a group claims {n} moments)", dir.display());
        }
        let m: Vec<f32> = bytemuck::pod_collect_to_vec(&bytes[pos..pos + 4 * n]);
        let v: Vec<f32> = bytemuck::pod_collect_to_vec(&bytes[pos + 4 * n..pos + 8 * n]);
        pos += 8 * n;
        moments.push((m, v));
    }
    let exposure_path = dir.join("exposure.json");
    let exposures =
        exposure_path.exists().then(|| crate::scene::exposure::Exposures::read(&exposure_path)).transpose()?;
    Ok(Some(Checkpoint { scene, step: state.step, config: state.config, moments, exposures }))
}
