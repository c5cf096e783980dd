//! Per-view exposure: the affine color map y = A x + b (A 3x3, b 3) from the scene's colors (what a
//! render shows) to what one view's camera recorded. Phones change exposure and white balance from
//! shot to shot; `cogeo train --exposure` learns one map per training view (train/exposure.rs) and
//! writes them to `exposure.json`, so that the scene keeps one set of colors and the removal can
//! take a source photo's pixels back into them (`to_scene`). Held-out views have no learned map:
//! `fit` finds theirs from pixels whose color is known (the f64 twin of the GPU passes, too).

use anyhow::{anyhow, bail, Context, Result};
use std::path::Path;

/// y = m x + b per pixel; m row-major.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ColorAffine {
    pub matrix: [[f64; 3]; 3],
    pub bias: [f64; 3],
}

impl Default for ColorAffine {
    fn default() -> Self {
        ColorAffine::IDENTITY
    }
}

impl ColorAffine {
    pub const IDENTITY: ColorAffine =
        ColorAffine { matrix: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], bias: [0.0; 3] };

    /// A per-channel gain (a white-balance and exposure change), no bias.
    pub fn gains(g: [f64; 3]) -> ColorAffine {
        let mut a = ColorAffine::IDENTITY;
        for c in 0..3 {
            a.matrix[c][c] = g[c];
        }
        a
    }

    /// The 12 parameters as the GPU keeps them: the matrix row-major, then the bias.
    pub fn to_params(&self) -> [f32; 12] {
        let mut p = [0.0; 12];
        for r in 0..3 {
            for c in 0..3 {
                p[3 * r + c] = self.matrix[r][c] as f32;
            }
            p[9 + r] = self.bias[r] as f32;
        }
        p
    }

    pub fn from_params(p: &[f32]) -> ColorAffine {
        let mut a = ColorAffine::IDENTITY;
        for r in 0..3 {
            for c in 0..3 {
                a.matrix[r][c] = p[3 * r + c] as f64;
            }
            a.bias[r] = p[9 + r] as f64;
        }
        a
    }

    pub fn apply_pixel(&self, x: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|r| (0..3).map(|c| self.matrix[r][c] * x[c]).sum::<f64>() + self.bias[r])
    }

    /// Applies the map to a planar RGB image.
    pub fn apply(&self, planar: &[f32]) -> Vec<f32> {
        let n = planar.len() / 3;
        let mut out = vec![0.0; planar.len()];
        for p in 0..n {
            let y = self.apply_pixel([planar[p] as f64, planar[n + p] as f64, planar[2 * n + p] as f64]);
            for c in 0..3 {
                out[c * n + p] = y[c] as f32;
            }
        }
        out
    }

    /// The inverse map (None when the matrix is singular).
    pub fn inverse(&self) -> Option<ColorAffine> {
        let m = &self.matrix;
        let cof = |r0: usize, r1: usize, c0: usize, c1: usize| m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0];
        let det = m[0][0] * cof(1, 2, 1, 2) - m[0][1] * cof(1, 2, 0, 2) + m[0][2] * cof(1, 2, 0, 1);
        if det.abs() < 1e-9 || !det.is_finite() {
            return None;
        }
        let adj = [
            [cof(1, 2, 1, 2), -cof(0, 2, 1, 2), cof(0, 1, 1, 2)],
            [-cof(1, 2, 0, 2), cof(0, 2, 0, 2), -cof(0, 1, 0, 2)],
            [cof(1, 2, 0, 1), -cof(0, 2, 0, 1), cof(0, 1, 0, 1)],
        ];
        let matrix = adj.map(|row| row.map(|v| v / det));
        let bias = std::array::from_fn(|r| -(0..3).map(|c| matrix[r][c] * self.bias[c]).sum::<f64>());
        Some(ColorAffine { matrix, bias })
    }

    /// `self` after `first`: x -> self(first(x)).
    pub fn after(&self, first: &ColorAffine) -> ColorAffine {
        let matrix = std::array::from_fn(|r| {
            std::array::from_fn(|c| (0..3).map(|k| self.matrix[r][k] * first.matrix[k][c]).sum())
        });
        ColorAffine { matrix, bias: self.apply_pixel(first.bias) }
    }

    /// The affine mean of `maps` (identity for none).
    pub fn mean(maps: &[ColorAffine]) -> ColorAffine {
        if maps.is_empty() {
            return ColorAffine::IDENTITY;
        }
        let n = maps.len() as f64;
        let mut m = ColorAffine { matrix: [[0.0; 3]; 3], bias: [0.0; 3] };
        for a in maps {
            for r in 0..3 {
                for c in 0..3 {
                    m.matrix[r][c] += a.matrix[r][c] / n;
                }
                m.bias[r] += a.bias[r] / n;
            }
        }
        m
    }

    /// Maps the colors of `scene` (every SH band; the bias goes to the DC term, which carries the
    /// renderer's +0.5) so that it renders `self(color)` wherever it rendered `color` (up to the
    /// renderer's clamp at 0).
    pub fn map_scene_colors(&self, scene: &mut crate::scene::GaussianScene) {
        use crate::scene::{sh_coeffs, SH_C0};
        let k = sh_coeffs(scene.sh_degree);
        for g in scene.sh.chunks_mut(3 * k) {
            for coeff in 0..k {
                let c = [0, 1, 2].map(|ch| g[3 * coeff + ch] as f64);
                let mapped: [f64; 3] = if coeff == 0 {
                    let color = self.apply_pixel(c.map(|v| SH_C0 * v + 0.5));
                    color.map(|v| (v - 0.5) / SH_C0)
                } else {
                    std::array::from_fn(|r| (0..3).map(|x| self.matrix[r][x] * c[x]).sum())
                };
                for ch in 0..3 {
                    g[3 * coeff + ch] = mapped[ch] as f32;
                }
            }
        }
    }

    /// `render` through the map `fit` finds from it to `photo` on the `known` pixels, clamped to
    /// [0, 1]: the render as the photo's exposure shows it (the held-out scores "exposure fitted").
    pub fn fitted_render(render: &[f32], photo: &[f32], known: Option<&[bool]>) -> Vec<f32> {
        let map = ColorAffine::fit(render, photo, known);
        map.apply(render).into_iter().map(|v| v.clamp(0.0, 1.0)).collect()
    }

    /// The least-squares map from `render` to `photo` (planar RGB) over the pixels where `known`
    /// (all when None), in f64: per channel, the normal equations of [x 1] w = y. Identity when
    /// fewer than 16 pixels count or the colors span too little to pin the map down.
    pub fn fit(render: &[f32], photo: &[f32], known: Option<&[bool]>) -> ColorAffine {
        let n = render.len() / 3;
        let mut ata = [[0f64; 4]; 4];
        let mut aty = [[0f64; 4]; 3];
        let mut count = 0usize;
        for p in (0..n).filter(|&p| known.is_none_or(|k| k[p])) {
            let a = [render[p] as f64, render[n + p] as f64, render[2 * n + p] as f64, 1.0];
            for i in 0..4 {
                for j in 0..4 {
                    ata[i][j] += a[i] * a[j];
                }
                for c in 0..3 {
                    aty[c][i] += a[i] * photo[c * n + p] as f64;
                }
            }
            count += 1;
        }
        if count < 16 {
            return ColorAffine::IDENTITY;
        }
        // a whisker of ridge toward identity keeps flat-colored views solvable
        let ridge = 1e-6 * count as f64;
        let mut out = ColorAffine::IDENTITY;
        for c in 0..3 {
            let mut m = ata;
            let mut rhs = aty[c];
            for i in 0..3 {
                m[i][i] += ridge;
                rhs[i] += ridge * if i == c { 1.0 } else { 0.0 };
            }
            let Some(w) = crate::planes::solve(m, rhs) else { return ColorAffine::IDENTITY };
            out.matrix[c] = [w[0], w[1], w[2]];
            out.bias[c] = w[3];
        }
        out
    }
}

/// One training view's learned map in `exposure.json`.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct ViewExposure {
    /// The camera's (image's) name.
    pub name: String,
    #[serde(flatten)]
    pub map: ColorAffine,
}

/// `exposure.json` of `cogeo train --exposure`: each training view's map from the scene's colors
/// to its photo.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct Exposures {
    pub views: Vec<ViewExposure>,
}

impl Exposures {
    pub fn get(&self, name: &str) -> Option<&ColorAffine> {
        self.views.iter().find(|v| v.name == name).map(|v| &v.map)
    }

    pub fn read(path: &Path) -> Result<Exposures> {
        let text = std::fs::read_to_string(path).with_context(|| format!("{}: cannot read", path.display()))?;
        let e: Exposures = serde_json::from_str(&text).map_err(|e| anyhow!("{}: {e}", path.display()))?;
        for v in &e.views {
            let finite = v.map.matrix.iter().flatten().chain(&v.map.bias).all(|x| x.is_finite());
            if !finite || v.map.inverse().is_none() {
                bail!("{}: view {:?}: the map is not finite or not invertible", path.display(), v.name);
            }
        }
        Ok(e)
    }

    pub fn write(&self, path: &Path) -> Result<()> {
        let text = serde_json::to_string_pretty(self)?;
        crate::io::write_atomic(path, |w| {
            use std::io::Write;
            w.write_all(text.as_bytes()).map_err(Into::into)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_and_composition_are_exact_and_fit_recovers_a_known_map() {
        let a =
            ColorAffine { matrix: [[1.1, 0.05, 0.0], [-0.02, 0.9, 0.03], [0.0, 0.1, 1.2]], bias: [0.02, -0.01, 0.03] };
        let id = a.after(&a.inverse().unwrap());
        for r in 0..3 {
            for c in 0..3 {
                assert!((id.matrix[r][c] - if r == c { 1.0 } else { 0.0 }).abs() < 1e-12);
            }
            assert!(id.bias[r].abs() < 1e-12);
        }
        // 200 pseudo-random colors through the map: the fit finds it back
        let n = 200;
        let mut render = vec![0f32; 3 * n];
        for (i, v) in render.iter_mut().enumerate() {
            *v = ((i * 7919 % 1000) as f32) / 1000.0;
        }
        let photo = a.apply(&render);
        let fit = ColorAffine::fit(&render, &photo, None);
        for r in 0..3 {
            for c in 0..3 {
                assert!((fit.matrix[r][c] - a.matrix[r][c]).abs() < 1e-4, "{fit:?}");
            }
            assert!((fit.bias[r] - a.bias[r]).abs() < 1e-4);
        }
        assert_eq!(ColorAffine::from_params(&a.to_params()).to_params(), a.to_params());
    }
}
