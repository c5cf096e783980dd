//! `cogeo eval`: scores a folder of renders against a folder of ground-truth images inside masks,
//! with the synth-only extras when the `cogeo synth` dataset is given.

use super::models::{FidFeatures, Lpips, NetworkInput};
use super::{bbox_scores, floater_score, frechet_distance, full_scores, leftover_fraction, mask_scores, Scores};
use crate::scene::dataset::{find_image, load_rgb};
use crate::scene::undistort::Undistortion;
use anyhow::{anyhow, bail, Context, Result};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// Which region the headline numbers use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Protocol {
    /// Mean over the mask's pixels.
    Mask,
    /// The crop to the mask's bounding box (SPIn-NeRF).
    Bbox,
    /// The whole image.
    Full,
}

/// The thresholds of the synth-only scores: the one home of their defaults, also `cogeo eval`'s
/// flags.
#[derive(Clone, Debug, clap::Args)]
pub struct SynthThresholds {
    /// Floater threshold, relative to the true depth.
    #[arg(long, default_value_t = 0.05)]
    pub tau: f64,
    /// Leftover score margin: a mask pixel counts as leftover when the render is closer to the
    /// image with the objects than to the ground truth by more than this mean RGB difference.
    #[arg(long, default_value_t = 0.05)]
    pub leftover_margin: f32,
}

crate::default_from_flags!(SynthThresholds);

#[derive(Clone, Debug)]
pub struct EvalConfig {
    pub renders: PathBuf,
    pub gt: PathBuf,
    pub masks: PathBuf,
    /// Mask values that count; empty: every nonzero value.
    pub labels: Vec<u8>,
    pub protocol: Protocol,
    /// A `cogeo synth` dataset: never-seen / seen-elsewhere subsets, leftover score, depth error
    /// and floaters.
    pub data: Option<PathBuf>,
    /// Rendered depth (camera z), `<name>.exr` per view, for the depth error.
    pub depth: Option<PathBuf>,
    /// The edited scene, for the floater score.
    pub scene: Option<PathBuf>,
    /// Floater distance threshold, relative to the true depth.
    pub tau: f64,
    /// Leftover score: RGB distance margin.
    pub leftover_margin: f32,
    pub lpips: Option<PathBuf>,
    pub lpips_input: NetworkInput,
    /// The LPIPS network's smallest accepted side (images are upsampled, crops grown to it).
    pub lpips_min_side: usize,
    pub fid: Option<PathBuf>,
    pub fid_input: NetworkInput,
    /// Score each render after mapping it through the affine color map (scene::exposure) fitted
    /// to the ground truth on the pixels outside the mask: the view's exposure, which a scene
    /// trained on photos of varying exposure cannot know, leaves the score.
    pub fit_exposure: bool,
}

/// The undistortion of each view of a capture whose lens is not a pinhole, by view name: the
/// synth's ground truth, masks and photos are stored in the photos' frame, the renders in the
/// undistorted pinhole frame (scene/undistort.rs).
type Frames = std::collections::HashMap<String, Undistortion>;

fn capture_frames(data: &Path) -> Result<Frames> {
    let model = crate::scene::dataset::read_capture(data)?;
    let mut frames = Frames::new();
    for (camera, lens) in model.cameras.iter().zip(&model.lenses).filter(|(_, l)| !l.is_pinhole()) {
        frames.insert(camera.name.clone(), Undistortion::new(camera, *lens, &camera.name)?);
    }
    Ok(frames)
}

/// Whether an image of `size` read beside a `w` x `h` render is in the photo's frame of
/// `frame` (the photo's size), to be undistorted into the render's.
fn photo_frame(frame: Option<&Undistortion>, size: (u32, u32), w: u32, h: u32) -> Option<&Undistortion> {
    frame.filter(|u| size == u.source && (u.pinhole.width, u.pinhole.height) == (w, h))
}

/// A label image (one byte per pixel) in a `w` x `h` render's frame: as stored, or undistorted
/// when stored in the photo's frame of `frame`.
pub(super) fn load_labels(path: &Path, w: u32, h: u32, frame: Option<&Undistortion>) -> Result<Vec<u8>> {
    let img = crate::io::read_image(path)?.to_luma8();
    match photo_frame(frame, img.dimensions(), w, h) {
        Some(u) => Ok(u.labels(img.as_raw())),
        None if img.dimensions() == (w, h) => Ok(img.into_raw()),
        None => bail!("{}: mask is {}x{}, the render is {w}x{h}", path.display(), img.width(), img.height()),
    }
}

fn load_mask(path: &Path, labels: &[u8], w: u32, h: u32, frame: Option<&Undistortion>) -> Result<Vec<bool>> {
    let raw = load_labels(path, w, h, frame)?;
    Ok(raw.iter().map(|&v| if labels.is_empty() { v != 0 } else { labels.contains(&v) }).collect())
}

/// An RGB image in a `w` x `h` render's frame: as stored, or undistorted when stored in the
/// photo's frame of `frame`.
pub(super) fn load_same_size(
    path: &Path,
    w: u32,
    h: u32,
    what: &str,
    frame: Option<&Undistortion>,
) -> Result<Vec<f32>> {
    let (iw, ih, img) = load_rgb(path)?;
    match photo_frame(frame, (iw, ih), w, h) {
        Some(u) => Ok(u.rgb(&img)),
        None if (iw, ih) == (w, h) => Ok(img),
        None => bail!("{}: {what} is {iw}x{ih}, the render is {w}x{h}", path.display()),
    }
}

fn image_stems(dir: &Path) -> Result<Vec<String>> {
    let mut stems: Vec<String> = std::fs::read_dir(dir)
        .with_context(|| format!("{}: cannot read the folder", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.extension()
                .and_then(|e| e.to_str())
                .is_some_and(|e| ["png", "jpg", "jpeg"].contains(&e.to_lowercase().as_str()))
        })
        .filter_map(|p| p.file_stem().and_then(|s| s.to_str()).map(str::to_string))
        .collect();
    stems.sort();
    stems.dedup();
    if stems.is_empty() {
        bail!("{}: no PNG/JPEG images", dir.display());
    }
    Ok(stems)
}

fn mean_of(values: impl Iterator<Item = f64>) -> Option<f64> {
    let v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

fn mean_scores(s: &[Option<Scores>]) -> Value {
    let present: Vec<&Scores> = s.iter().flatten().collect();
    if present.is_empty() {
        return Value::Null;
    }
    json!({
        "psnr": mean_of(present.iter().map(|x| x.psnr)),
        "ssim": mean_of(present.iter().map(|x| x.ssim)),
        "views": present.len(),
    })
}

fn not_computed(why: &str) -> Value {
    json!(format!("not computed ({why})"))
}

/// Runs the evaluation; returns the metrics JSON.
pub fn evaluate(cfg: &EvalConfig) -> Result<Value> {
    let mut lpips =
        cfg.lpips.as_deref().map(|p| Lpips::load(p, cfg.lpips_input.clone(), cfg.lpips_min_side)).transpose()?;
    let mut fid = cfg.fid.as_deref().map(|p| FidFeatures::load(p, cfg.fid_input.clone())).transpose()?;
    let stems = image_stems(&cfg.renders)?;
    // the synth ground truth of removing exactly the masked objects (all of them without --labels)
    let truth = cfg.data.as_ref().map(|d| {
        let labels = if cfg.labels.is_empty() { (1..=255).collect::<Vec<u8>>() } else { cfg.labels.clone() };
        crate::synth::ground_truth(d, &labels)
    });
    // a synth capture through a lens: its ground truth is undistorted like its photos were
    let frames = match &cfg.data {
        Some(d) => capture_frames(d)?,
        None => Frames::new(),
    };
    let mut views = Vec::new();
    let (mut m_mask, mut m_bbox, mut m_full, mut m_unseen, mut m_seen) = (vec![], vec![], vec![], vec![], vec![]);
    let mut m_outside = vec![];
    let mut leftovers = vec![];
    // LPIPS per region: full, bbox, mask, never seen, seen elsewhere
    let mut lp: [Vec<f64>; 5] = Default::default();
    const LP_REGIONS: [&str; 5] = ["full", "bbox", "mask", "never_seen", "seen_elsewhere"];
    let (mut feat_r, mut feat_g) = (vec![], vec![]);
    let (mut d_rel, mut d_sq, mut d_n) = (0f64, 0f64, 0usize);
    for stem in &stems {
        let rpath = find_image(&cfg.renders, stem).unwrap();
        let (w, h, mut render) = load_rgb(&rpath)?;
        let (wu, hu) = (w as usize, h as usize);
        let gpath = find_image(&cfg.gt, stem)
            .ok_or_else(|| anyhow!("{}: no ground truth image for render {stem}", cfg.gt.display()))?;
        let frame = frames.get(stem.as_str());
        let gt = load_same_size(&gpath, w, h, "ground truth", frame)?;
        let mpath = find_image(&cfg.masks, stem)
            .ok_or_else(|| anyhow!("{}: no mask for render {stem}", cfg.masks.display()))?;
        let mask = load_mask(&mpath, &cfg.labels, w, h, frame)?;
        if cfg.fit_exposure {
            let known: Vec<bool> = mask.iter().map(|&m| !m).collect();
            render = crate::scene::exposure::ColorAffine::fitted_render(&render, &gt, Some(&known));
        }
        let (sm, sb, sf) = (
            mask_scores(&render, &gt, &mask, wu, hu),
            bbox_scores(&render, &gt, &mask, wu, hu),
            full_scores(&render, &gt, wu, hu),
        );
        let mut subsets: Option<(Vec<bool>, Vec<bool>)> = None;
        let outside: Vec<bool> = mask.iter().map(|&m| !m).collect();
        let so = mask_scores(&render, &gt, &outside, wu, hu);
        let mut view = json!({ "name": stem, "mask_pixels": mask.iter().filter(|&&m| m).count(), "mask": sm, "bbox": sb, "full": sf, "outside": so });
        m_outside.push(so);
        m_mask.push(sm);
        m_bbox.push(sb);
        m_full.push(sf);
        if let (Some(data), Some(truth)) = (&cfg.data, &truth) {
            let upath = truth.unseen.join(format!("{stem}.png"));
            let unseen = load_mask(&upath, &[], w, h, frame)?;
            let inside: Vec<bool> = mask.iter().zip(&unseen).map(|(&m, &u)| m && u).collect();
            let elsewhere: Vec<bool> = mask.iter().zip(&unseen).map(|(&m, &u)| m && !u).collect();
            let (su, se) = (mask_scores(&render, &gt, &inside, wu, hu), mask_scores(&render, &gt, &elsewhere, wu, hu));
            view["never_seen"] = json!(su);
            view["seen_elsewhere"] = json!(se);
            m_unseen.push(su);
            m_seen.push(se);
            subsets = Some((inside, elsewhere));
            let ipath = find_image(&data.join("images"), stem)
                .ok_or_else(|| anyhow!("{}: no image {stem} (with the objects)", data.join("images").display()))?;
            let with_objects = load_same_size(&ipath, w, h, "image", frame)?;
            let left = leftover_fraction(&render, &with_objects, &gt, &mask, cfg.leftover_margin);
            view["leftover"] = json!(left);
            leftovers.extend(left);
            if let Some(ddir) = &cfg.depth {
                let dpath = ddir.join(format!("{stem}.exr"));
                let (dw, dh, depth) = crate::io::read_exr_channel(&dpath, None)?;
                let tpath = truth.depth.join(format!("{stem}.exr"));
                let (tw, th, truth) = crate::io::read_exr_channel(&tpath, None)?;
                if (dw, dh) != (w, h) || (tw, th) != (w, h) {
                    bail!("{} / {}: depth size differs from the render's {w}x{h}", dpath.display(), tpath.display());
                }
                for i in (0..mask.len()).filter(|&i| mask[i] && truth[i] > 0.0 && depth[i] > 0.0) {
                    let e = depth[i] as f64 - truth[i] as f64;
                    d_rel += e.abs() / truth[i] as f64;
                    d_sq += e * e;
                    d_n += 1;
                }
            }
        }
        if let Some(l) = &mut lpips {
            let mut values = [
                Some(l.distance(&render, &gt, wu, hu)?),
                l.bbox(&render, &gt, &mask, wu, hu)?,
                l.masked(&render, &gt, &mask, wu, hu)?,
                None,
                None,
            ];
            if let Some((never, elsewhere)) = &subsets {
                values[3] = l.masked(&render, &gt, never, wu, hu)?;
                values[4] = l.masked(&render, &gt, elsewhere, wu, hu)?;
            }
            for (k, v) in values.iter().enumerate() {
                if let Some(v) = v {
                    view[format!("lpips_{}", LP_REGIONS[k])] = json!(v);
                    lp[k].push(*v);
                }
            }
        }
        if let Some(f) = &mut fid {
            feat_r.push(f.features(&render, wu, hu)?);
            feat_g.push(f.features(&gt, wu, hu)?);
        }
        views.push(view);
    }
    let headline = match cfg.protocol {
        Protocol::Mask => mean_scores(&m_mask),
        Protocol::Bbox => mean_scores(&m_bbox),
        Protocol::Full => mean_scores(&m_full),
    };
    let no_data = "no --data synth dataset given";
    let mut out = json!({
        "renders": cfg.renders,
        "gt": cfg.gt,
        "masks": cfg.masks,
        "labels": cfg.labels,
        "protocol": cfg.protocol,
        "exposure": if cfg.fit_exposure { "fitted per view on the pixels outside the mask" } else { "raw" },
        "synth_ground_truth": truth.as_ref().map(|t| json!({ "images": t.images, "exact": t.exact })),
        "headline": headline,
        "mask": mean_scores(&m_mask),
        "bbox": mean_scores(&m_bbox),
        "full": mean_scores(&m_full),
        // the scene's own quality: every pixel outside the mask, which the removal must not change
        "outside": mean_scores(&m_outside),
        "never_seen": if cfg.data.is_some() { mean_scores(&m_unseen) } else { not_computed(no_data) },
        "seen_elsewhere": if cfg.data.is_some() { mean_scores(&m_seen) } else { not_computed(no_data) },
        "leftover": if cfg.data.is_some() { json!(mean_of(leftovers.into_iter())) } else { not_computed(no_data) },
        "views": views,
    });
    out["depth"] = match (&cfg.data, &cfg.depth) {
        (Some(_), Some(_)) if d_n > 0 => {
            json!({ "abs_rel": d_rel / d_n as f64, "rmse": (d_sq / d_n as f64).sqrt(), "pixels": d_n })
        }
        (Some(_), Some(_)) => not_computed("no mask pixel with valid depth"),
        _ => not_computed("needs --data and --depth"),
    };
    out["floaters"] = match (&cfg.data, &truth, &cfg.scene) {
        (Some(_), Some(_), Some(_)) if !frames.is_empty() => {
            not_computed("the true depth is in the distorted photos' frame")
        }
        (Some(data), Some(truth), Some(scene_path)) => {
            let scene = crate::scene::ply::read_ply(scene_path)?;
            let ds = crate::scene::dataset::load(data, "images", 1)?;
            let (mut cams, mut depths, mut regions) = (vec![], vec![], vec![]);
            for v in ds.train.iter().chain(&ds.test) {
                let c = &v.camera;
                // the true surface after the removal: kept objects included where the synth wrote
                // that configuration (a kept object behind a removed one is not a floater)
                let (_, _, d) = crate::io::read_exr_channel(&truth.depth.join(format!("{}.exr", c.name)), None)?;
                let mpath = find_image(&data.join("object_mask"), &c.name)
                    .ok_or_else(|| anyhow!("{}: no object mask for {}", data.join("object_mask").display(), c.name))?;
                regions.push(load_mask(&mpath, &cfg.labels, c.width, c.height, None)?);
                depths.push(d);
                cams.push(c.clone());
            }
            let (score, count) = floater_score(&scene, &cams, &depths, &regions, cfg.tau);
            json!({ "score": score, "gaussians": count, "tau": cfg.tau, "views": cams.len() })
        }
        _ => not_computed("needs --data and --scene"),
    };
    out["lpips"] = if lpips.is_some() {
        let mut v =
            json!({ "model": cfg.lpips, "input_scale": cfg.lpips_input.scale, "input_offset": cfg.lpips_input.offset });
        for (k, values) in lp.iter().enumerate() {
            let subset = k >= 3;
            v[LP_REGIONS[k]] = if subset && cfg.data.is_none() {
                not_computed(no_data)
            } else {
                json!(mean_of(values.iter().copied()))
            };
        }
        v
    } else {
        not_computed("no --lpips-model given")
    };
    out["fid"] = if fid.is_some() {
        match frechet_distance(&feat_r, &feat_g) {
            Some(d) => json!({ "value": d, "images": feat_r.len(), "model": cfg.fid }),
            None => not_computed("FID needs at least two images per set"),
        }
    } else {
        not_computed("no --fid-model given")
    };
    Ok(out)
}
