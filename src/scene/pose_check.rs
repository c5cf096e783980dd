//! Do a COLMAP model's poses agree with its images? The sparse points carry colors; under right
//! poses each point lands on a pixel of its own color in every view that sees it. This measures
//! that agreement for the rotations as stored and for their transposes, against chance (the same
//! points compared with unrelated pixels of the same images).
//!
//! Why the transpose: converting LLFF / NeRF poses to COLMAP text, it is easy to write the
//! camera-to-world rotation's quaternion next to the world-to-camera translation. Such a model
//! loads without complaint and its points even project inside the images, but training on it
//! converges to a blur (the shared statue capture is one: as stored, point colors are hardly
//! closer to the images than chance, 0.20 vs 0.23; with the rotations transposed, 0.05).

use crate::scene::colmap::Point3D;
use crate::scene::Camera;

/// Mean absolute color difference (RGB in [0, 1]) of the points against the images.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RotationCheck {
    /// Points against the pixel they project to, rotations as stored.
    pub stored: f64,
    /// The same with every rotation transposed (translation unchanged).
    pub transposed: f64,
    /// Points against unrelated pixels of the same images (what poses with no relation to the
    /// images would score).
    pub chance: f64,
    /// Point projections compared (as stored).
    pub samples: usize,
}

impl RotationCheck {
    /// The rotations are transposed: their transposes agree with the images far better than the
    /// stored ones, which do no better than chance.
    pub fn transposed_rotations(&self) -> bool {
        self.transposed < 0.6 * self.stored && self.transposed < 0.6 * self.chance && self.stored > 0.75 * self.chance
    }

    /// Neither reading of the poses agrees with the images.
    pub fn disagrees(&self) -> bool {
        self.stored > 0.75 * self.chance && self.transposed > 0.75 * self.chance
    }
}

fn transpose(r: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    [[r[0][0], r[1][0], r[2][0]], [r[0][1], r[1][1], r[2][1]], [r[0][2], r[1][2], r[2][2]]]
}

/// The camera with its rotation transposed and its translation kept.
pub fn with_transposed_rotation(c: &Camera) -> Camera {
    Camera { rotation: transpose(&c.rotation), ..c.clone() }
}

/// Compares up to `max_points` points with `images` (planar RGB in [0, 1], each of its camera's
/// size). None when the points carry no color information (all one color) or no point is seen.
pub fn check_rotations(
    cameras: &[Camera],
    images: &[Vec<f32>],
    points: &[Point3D],
    max_points: usize,
) -> Option<RotationCheck> {
    let first = points.first()?.rgb;
    if points.iter().all(|p| p.rgb == first) {
        return None;
    }
    let stride = points.len().div_ceil(max_points.max(1));
    let sample: Vec<&Point3D> = points.iter().step_by(stride).collect();
    let score = |transposed: bool| -> (f64, f64, usize) {
        let (mut err, mut chance, mut n) = (0f64, 0f64, 0usize);
        for (cam, img) in cameras.iter().zip(images) {
            let cam = if transposed { with_transposed_rotation(cam) } else { cam.clone() };
            let (w, h) = (cam.width as usize, cam.height as usize);
            if img.len() != 3 * w * h {
                continue;
            }
            for (k, p) in sample.iter().enumerate() {
                let x = cam.to_camera(p.xyz);
                if x[2] <= 1e-6 {
                    continue;
                }
                let (u, v) = (cam.fx * x[0] / x[2] + cam.cx, cam.fy * x[1] / x[2] + cam.cy);
                if !(u >= 0.0 && v >= 0.0 && u < w as f64 && v < h as f64) {
                    continue;
                }
                let at = v as usize * w + u as usize;
                // an unrelated pixel: a fixed scramble of the point index
                let other = (k.wrapping_mul(2_654_435_761) ^ (k >> 3)).wrapping_mul(40_503) % (w * h);
                for c in 0..3 {
                    let col = p.rgb[c] as f64 / 255.0;
                    err += (img[c * w * h + at] as f64 - col).abs();
                    chance += (img[c * w * h + other] as f64 - col).abs();
                }
                n += 1;
            }
        }
        let d = (3 * n.max(1)) as f64;
        (err / d, chance / d, n)
    };
    let (stored, chance, samples) = score(false);
    let (transposed, _, _) = score(true);
    (samples > 0).then_some(RotationCheck { stored, transposed, chance, samples })
}
