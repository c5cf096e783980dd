//! Per-view label maps O(u) in {0..Q} (0 = background), from either
//! - an instance-mask folder: one 8-bit PNG per view named like the view's image, pixel value q =
//!   object q (what `cogeo synth` writes to `object_mask/`, and Gaussian Grouping's `object_mask/`); or
//! - per-object binary mask folders (SPIn-NeRF `label/` style): a folder holding one subfolder per
//!   object, each with one mask per view, nonzero = object. Objects are numbered 1..Q in the sorted
//!   order of the subfolder names, the same for every view; where masks overlap, the later object wins.
//!
//! Masks whose size differs from the view's image are resized with nearest-neighbour sampling.

use crate::scene::dataset::{find_image, View};
use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};

/// Label value for pixels that carry no supervision (ignored by the losses).
pub const IGNORE: u8 = 255;

pub struct LabelMaps {
    /// Number of object labels Q (classes are 0..=Q).
    pub num_objects: usize,
    /// Object names, index q-1 (subfolder names, or "object q").
    pub names: Vec<String>,
    /// One map per requested view, width * height, row-major.
    pub maps: Vec<Vec<u8>>,
}

impl LabelMaps {
    pub fn classes(&self) -> usize {
        self.num_objects + 1
    }
}

/// A mask or label image's bytes as one 8-bit channel at `width` x `height` (nearest-neighbour
/// resized when its own size differs). `what` names the file in errors.
pub fn decode_mask(data: &[u8], what: &str, width: u32, height: u32) -> Result<Vec<u8>> {
    let (w, h, mask) = decode_mask_as_stored(data, what)?;
    Ok(crate::image_ops::resize_nearest_u8(&mask, w, h, width, height))
}

/// A mask or label image's bytes as one 8-bit channel at its own size: (width, height, pixels).
fn decode_mask_as_stored(data: &[u8], what: &str) -> Result<(u32, u32, Vec<u8>)> {
    let img = crate::io::decode_image(data, what)?.to_luma8();
    let (w, h) = img.dimensions();
    if w == 0 || h == 0 {
        bail!("{what}: the mask is empty ({w}x{h})");
    }
    Ok((w, h, img.into_raw()))
}

fn mask_path(dir: &Path, view: &str) -> Result<PathBuf> {
    find_image(dir, view).with_context(|| format!("{}: no mask for view {view} (expected {view}.png)", dir.display()))
}

/// Subfolders of `dir` that hold files, sorted by name; empty when `dir` holds mask files directly.
fn object_folders(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("{}: cannot read mask folder", dir.display()))?
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.is_dir())
        .collect();
    dirs.sort();
    Ok(dirs)
}

/// Loads the label maps of `views` (their cameras' names are the image stems) from `dir`,
/// detecting the layout: subfolders = per-object binary masks, otherwise instance maps. Masks are
/// drawn on the stored photos: each is brought into its view's frame (undistorted, resized).
pub fn load(dir: &Path, views: &[&View]) -> Result<LabelMaps> {
    if !dir.is_dir() {
        bail!("{}: mask folder not found", dir.display());
    }
    let stem = |v: &View| v.camera.name.clone();
    let read_gray = |path: &Path, v: &View| -> Result<Vec<u8>> {
        let data = std::fs::read(path).with_context(|| format!("{}: cannot read mask", path.display()))?;
        let (w, h, mask) = decode_mask_as_stored(&data, &path.display().to_string())?;
        Ok(v.label_map(&mask, w, h))
    };
    let folders = object_folders(dir)?;
    if folders.is_empty() {
        let mut maps = Vec::new();
        let mut max = 0u8;
        for v in views {
            let m = read_gray(&mask_path(dir, &stem(v))?, v)?;
            max = max.max(m.iter().copied().filter(|&v| v != IGNORE).max().unwrap_or(0));
            maps.push(m);
        }
        let q = max as usize;
        return Ok(LabelMaps { num_objects: q, names: (1..=q).map(|i| format!("object {i}")).collect(), maps });
    }
    if folders.len() > 254 {
        bail!("{}: {} object folders; at most 254 objects are supported", dir.display(), folders.len());
    }
    let mut maps = Vec::new();
    for v in views {
        let mut map = vec![0u8; (v.camera.width * v.camera.height) as usize];
        for (q, f) in folders.iter().enumerate() {
            let m = read_gray(&mask_path(f, &stem(v))?, v)?;
            for (o, v) in map.iter_mut().zip(m) {
                if v != 0 {
                    *o = q as u8 + 1;
                }
            }
        }
        maps.push(map);
    }
    let names = folders.iter().map(|f| f.file_name().unwrap().to_string_lossy().to_string()).collect();
    Ok(LabelMaps { num_objects: folders.len(), names, maps })
}

/// A distinct color per label (0 = dark gray background), for label-map images.
pub fn label_color(label: u8) -> [u8; 3] {
    if label == 0 {
        return [40, 40, 40];
    }
    // golden-ratio hue steps, full saturation
    let h = (label as f64 * 0.618_033_988_75).fract() * 6.0;
    let x = 1.0 - ((h % 2.0) - 1.0).abs();
    let (r, g, b) = match h as u32 {
        0 => (1.0, x, 0.0),
        1 => (x, 1.0, 0.0),
        2 => (0.0, 1.0, x),
        3 => (0.0, x, 1.0),
        4 => (x, 0.0, 1.0),
        _ => (1.0, 0.0, x),
    };
    [r, g, b].map(|v: f64| (55.0 + 200.0 * v) as u8)
}

/// Intersection over union per class 0..classes over all pixels of all maps (pixels labelled IGNORE
/// in `truth` skipped), and their mean over the classes present in either prediction or truth.
pub fn iou(pred: &[Vec<u8>], truth: &[Vec<u8>], classes: usize) -> (Vec<Option<f64>>, f64) {
    let mut inter = vec![0u64; classes];
    let mut union = vec![0u64; classes];
    for (p, t) in pred.iter().zip(truth) {
        for (&a, &b) in p.iter().zip(t) {
            if b == IGNORE {
                continue;
            }
            let (a, b) = (a as usize, b as usize);
            if a == b && a < classes {
                inter[a] += 1;
                union[a] += 1;
            } else {
                if a < classes {
                    union[a] += 1;
                }
                if b < classes {
                    union[b] += 1;
                }
            }
        }
    }
    let per: Vec<Option<f64>> =
        (0..classes).map(|c| (union[c] > 0).then(|| inter[c] as f64 / union[c] as f64)).collect();
    let present: Vec<f64> = per.iter().flatten().copied().collect();
    let mean = if present.is_empty() { 0.0 } else { present.iter().sum::<f64>() / present.len() as f64 };
    (per, mean)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn iou_counts_by_hand() {
        // truth: 0 0 1 1 ; pred: 0 1 1 1  -> class 0: 1/2, class 1: 2/3
        let (per, mean) = iou(&[vec![0, 1, 1, 1]], &[vec![0, 0, 1, 1]], 2);
        assert_eq!(per, vec![Some(0.5), Some(2.0 / 3.0)]);
        assert!((mean - (0.5 + 2.0 / 3.0) / 2.0).abs() < 1e-15);
        // ignored pixels do not count
        let (per, _) = iou(&[vec![1, 1]], &[vec![IGNORE, 1]], 2);
        assert_eq!(per, vec![None, Some(1.0)]);
    }

    #[test]
    fn label_colors_are_distinct() {
        let colors: Vec<[u8; 3]> = (0..=16).map(label_color).collect();
        for i in 0..colors.len() {
            for j in 0..i {
                assert_ne!(colors[i], colors[j], "labels {i} and {j} share a color");
            }
        }
    }
}
