//! Gaussian scenes (CPU side, structure of arrays), INRIA PLY I/O and cameras.

pub mod builtin;
pub mod camera;
pub mod colmap;
pub mod dataset;
pub mod exposure;
pub mod lens;
pub mod ply;
pub mod undistort;
pub mod pose_check;
pub mod transforms;

pub use camera::Camera;

use anyhow::{bail, Result};

/// A scalar type a PLY property can have.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlyType {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

/// A per-Gaussian property the scene does not interpret (identity features, labels, ...), kept so
/// that reading and writing a PLY loses nothing. Values are held as f64, which represents every
/// value of every PLY scalar type exactly.
#[derive(Clone, Debug, PartialEq)]
pub struct ExtraProperty {
    pub name: String,
    pub ty: PlyType,
    pub values: Vec<f64>,
}

/// A 3D Gaussian scene with parameters stored before activation (conventions.md).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GaussianScene {
    pub means: Vec<[f32; 3]>,
    /// nx, ny, nz of the INRIA layout (zeros in practice; kept for exact round trips).
    pub normals: Vec<[f32; 3]>,
    /// log sigma per axis.
    pub log_scales: Vec<[f32; 3]>,
    /// (w, x, y, z), not normalized.
    pub quats: Vec<[f32; 4]>,
    /// logit of opacity.
    pub opacity_logits: Vec<f32>,
    /// Stored SH degree (0..=3).
    pub sh_degree: u32,
    /// SH coefficients, [gaussian][basis k][channel c], K = (sh_degree + 1)^2 bases.
    pub sh: Vec<f32>,
    pub extras: Vec<ExtraProperty>,
}

/// The stored (pre-sigmoid) opacity of an opacity `p` in (0, 1).
pub fn logit(p: f64) -> f32 {
    (p / (1.0 - p)).ln() as f32
}

// Real spherical-harmonics basis constants (INRIA order): SH_C0 turns a DC coefficient into color
// (rgb = 0.5 + SH_C0 * dc), the others scale the bands of degree 1..3.
pub const SH_C0: f64 = 0.28209479177387814;
pub const SH_C1: f64 = 0.4886025119029199;
pub const SH_C2: [f64; 5] =
    [1.0925484305920792, -1.0925484305920792, 0.31539156525252005, -1.0925484305920792, 0.5462742152960396];
pub const SH_C3: [f64; 7] = [
    -0.5900435899266435,
    2.890611442640554,
    -0.4570457994644658,
    0.3731763325901154,
    -0.4570457994644658,
    1.445305721320277,
    -0.5900435899266435,
];

/// The highest SH degree cogeo reads, trains and renders (the shaders implement degrees 0..=3).
pub const MAX_SH_DEGREE: u32 = 3;

/// SH coefficients per channel for a degree.
pub fn sh_coeffs(degree: u32) -> usize {
    ((degree + 1) * (degree + 1)) as usize
}

impl GaussianScene {
    pub fn len(&self) -> usize {
        self.means.len()
    }

    pub fn is_empty(&self) -> bool {
        self.means.is_empty()
    }

    pub fn sh_coeffs(&self) -> usize {
        sh_coeffs(self.sh_degree)
    }

    /// The highest SH degree with a nonzero coefficient: the bands training reached (it grows
    /// one band per `--sh-band-every` iterations, 1000 by default, and leaves the others exactly
    /// zero).
    pub fn learnt_sh_degree(&self) -> u32 {
        let k = self.sh_coeffs();
        (1..=self.sh_degree)
            .rev()
            .find(|&d| {
                let band = sh_coeffs(d - 1)..sh_coeffs(d);
                self.sh.chunks_exact(3 * k).any(|g| g[3 * band.start..3 * band.end].iter().any(|&c| c != 0.0))
            })
            .unwrap_or(0)
    }

    /// Appends one Gaussian (normal 0, no extra properties). `sh` holds its 3 x `sh_coeffs()`
    /// coefficients as `self.sh` stores them: basis function b's r, g, b at 3b..3b + 3.
    pub fn push(&mut self, mean: [f32; 3], log_scales: [f32; 3], quat: [f32; 4], opacity_logit: f32, sh: &[f32]) {
        assert_eq!(sh.len(), 3 * self.sh_coeffs(), "SH coefficients of one Gaussian at degree {}", self.sh_degree);
        self.means.push(mean);
        self.normals.push([0.0; 3]);
        self.log_scales.push(log_scales);
        self.quats.push(quat);
        self.opacity_logits.push(opacity_logit);
        self.sh.extend_from_slice(sh);
    }

    /// Checks what rendering needs: at least one Gaussian, finite parameters, non-zero quaternions.
    /// `what` names the source in the error (usually the file path).
    pub fn validate(&self, what: &str) -> Result<()> {
        if self.is_empty() {
            bail!("{what}: the scene has no Gaussians");
        }
        let n = self.len();
        let k = self.sh_coeffs();
        if self.log_scales.len() != n
            || self.quats.len() != n
            || self.opacity_logits.len() != n
            || self.sh.len() != n * k * 3
        {
            bail!("{what}: attribute arrays disagree in length");
        }
        for i in 0..n {
            let finite = self.means[i].iter().all(|v| v.is_finite())
                && self.log_scales[i].iter().all(|v| v.is_finite())
                && self.quats[i].iter().all(|v| v.is_finite())
                && self.opacity_logits[i].is_finite()
                && self.sh[i * k * 3..(i + 1) * k * 3].iter().all(|v| v.is_finite());
            if !finite {
                bail!("{what}: Gaussian {i} has a NaN or infinite parameter");
            }
            let q = self.quats[i];
            if q.iter().map(|v| v * v).sum::<f32>() == 0.0 {
                bail!("{what}: Gaussian {i} has a zero-norm rotation quaternion");
            }
        }
        Ok(())
    }

    /// The Gaussians whose `keep` flag is set, in order, extra properties included.
    pub fn subset(&self, keep: &[bool]) -> GaussianScene {
        let k = self.sh_coeffs() * 3;
        let idx: Vec<usize> = (0..self.len()).filter(|&i| keep[i]).collect();
        GaussianScene {
            means: idx.iter().map(|&i| self.means[i]).collect(),
            normals: idx.iter().map(|&i| self.normals.get(i).copied().unwrap_or([0.0; 3])).collect(),
            log_scales: idx.iter().map(|&i| self.log_scales[i]).collect(),
            quats: idx.iter().map(|&i| self.quats[i]).collect(),
            opacity_logits: idx.iter().map(|&i| self.opacity_logits[i]).collect(),
            sh_degree: self.sh_degree,
            sh: idx.iter().flat_map(|&i| self.sh[i * k..(i + 1) * k].iter().copied()).collect(),
            extras: self
                .extras
                .iter()
                .map(|e| ExtraProperty {
                    name: e.name.clone(),
                    ty: e.ty,
                    values: idx.iter().map(|&i| e.values[i]).collect(),
                })
                .collect(),
        }
    }

    /// Writes the parameters of `part` (a `subset(keep)` of this scene, changed since) back over
    /// the Gaussians `keep` selects; normals and extra properties stay.
    pub fn set_subset(&mut self, keep: &[bool], part: &GaussianScene) {
        let k = self.sh_coeffs() * 3;
        assert_eq!(part.sh_degree, self.sh_degree, "set_subset: SH degrees differ");
        for (j, i) in (0..self.len()).filter(|&i| keep[i]).enumerate() {
            self.means[i] = part.means[j];
            self.log_scales[i] = part.log_scales[j];
            self.quats[i] = part.quats[j];
            self.opacity_logits[i] = part.opacity_logits[j];
            self.sh[i * k..(i + 1) * k].copy_from_slice(&part.sh[j * k..(j + 1) * k]);
        }
    }

    /// Appends `other`'s Gaussians (same SH degree). Extra properties `other` lacks get 0 for its
    /// Gaussians; properties only `other` has are dropped.
    pub fn append(&mut self, other: &GaussianScene) -> Result<()> {
        if other.sh_degree != self.sh_degree {
            bail!("cannot append a scene of SH degree {} to one of degree {}", other.sh_degree, self.sh_degree);
        }
        self.means.extend_from_slice(&other.means);
        self.normals.resize(self.means.len() - other.len(), [0.0; 3]);
        self.normals.extend((0..other.len()).map(|i| other.normals.get(i).copied().unwrap_or([0.0; 3])));
        self.log_scales.extend_from_slice(&other.log_scales);
        self.quats.extend_from_slice(&other.quats);
        self.opacity_logits.extend_from_slice(&other.opacity_logits);
        self.sh.extend_from_slice(&other.sh);
        for e in &mut self.extras {
            match other.extras.iter().find(|o| o.name == e.name) {
                Some(o) => e.values.extend_from_slice(&o.values),
                None => e.values.resize(e.values.len() + other.len(), 0.0),
            }
        }
        Ok(())
    }

    /// The extra properties `{prefix}0..{prefix}{D-1}` as an N x D row-major matrix, if present.
    pub fn feature_matrix(&self, prefix: &str) -> Option<(Vec<f32>, usize)> {
        let mut columns = Vec::new();
        while let Some(p) = self.extras.iter().find(|e| e.name == format!("{prefix}{}", columns.len())) {
            columns.push(p);
        }
        if columns.is_empty() {
            return None;
        }
        let d = columns.len();
        let mut out = vec![0f32; self.len() * d];
        for (c, col) in columns.iter().enumerate() {
            for (i, v) in col.values.iter().enumerate() {
                out[i * d + c] = *v as f32;
            }
        }
        Some((out, d))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two degree-3 Gaussians: all zero above DC is degree 0; one nonzero coefficient in a band
    /// (any Gaussian, any channel) makes that band learnt.
    #[test]
    fn learnt_sh_degree_is_the_highest_band_with_a_nonzero_coefficient() {
        let k = sh_coeffs(3);
        let mut scene = GaussianScene { sh_degree: 3, sh: vec![0.0; 2 * 3 * k], ..Default::default() };
        scene.sh[0] = 0.7;
        scene.sh[3 * k] = -0.2;
        assert_eq!(scene.learnt_sh_degree(), 0);
        // second Gaussian, basis 5 (band 2), blue
        scene.sh[3 * k + 3 * 5 + 2] = 1e-7;
        assert_eq!(scene.learnt_sh_degree(), 2);
        // first Gaussian, basis 15 (band 3), red
        scene.sh[3 * 15] = -0.1;
        assert_eq!(scene.learnt_sh_degree(), 3);
        let dc_only = GaussianScene { sh_degree: 0, sh: vec![0.5; 3], ..Default::default() };
        assert_eq!(dc_only.learnt_sh_degree(), 0);
    }
}
