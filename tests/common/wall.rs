//! A textured wall at z = `WALL_Z` seen by cameras looking along +z from the plane z = 0: the
//! closed form that the multi-view stages (photo-consistent depth, the leftovers' depth) are
//! checked against. Every photo is rendered from the wall's color function exactly.

use cogeo::removal::complete::source_views::SourceView;
use cogeo::scene::exposure::ColorAffine;
use cogeo::scene::Camera;

pub const WALL_Z: f64 = 5.0;

/// A camera at (x, y, 0) looking along +z (image y down), 60 degrees wide.
pub fn camera(name: &str, w: usize, h: usize, x: f64, y: f64) -> Camera {
    Camera::look_at(name, w as u32, h as u32, 60.0, [x, y, 0.0], [x, y, WALL_Z], [0.0, -1.0, 0.0])
}

/// The wall's color at a point of it: sinusoids a few pixels in period.
pub fn color(p: [f64; 3]) -> [f64; 3] {
    let tau = std::f64::consts::TAU;
    let s = (tau * p[0] / 0.36).sin() * (tau * p[1] / 0.5).cos();
    [0.5 + 0.3 * s, 0.5 - 0.2 * (tau * (p[0] + p[1]) / 0.7).sin(), 0.4 + 0.1 * s]
}

/// Each camera's photo of the wall (planar RGB).
pub fn photos(cams: &[Camera]) -> Vec<Vec<f32>> {
    cams.iter()
        .map(|c| {
            let (w, h) = (c.width as usize, c.height as usize);
            let mut photo = vec![0f32; 3 * w * h];
            for p in 0..w * h {
                let (u, v) = ((p % w) as f64 + 0.5, (p / w) as f64 + 0.5);
                // the camera looks along +z: the wall point under a pixel, in the world
                let (x, y) = ((u - c.cx) / c.fx * WALL_Z, (v - c.cy) / c.fy * WALL_Z);
                let ctr = c.center();
                let r = c.rotation;
                let pt = [0, 1, 2].map(|k| ctr[k] + r[0][k] * x + r[1][k] * y + r[2][k] * WALL_Z);
                assert!((pt[2] - WALL_Z).abs() < 1e-9);
                let rgb = color(pt);
                for k in 0..3 {
                    photo[k * w * h + p] = rgb[k] as f32;
                }
            }
            photo
        })
        .collect()
}

/// A target camera at the origin and three sources 1.5 to the side, above and below it, with
/// their photos of the wall and, as sources, no hole and the wall's depth, fully opaque.
pub struct Rig {
    pub cams: [Camera; 4],
    pub photos: Vec<Vec<f32>>,
    /// The photos as `interleave_rgb` stores them (the multi-view stages read them so).
    pub interleaved: Vec<Vec<[f32; 3]>>,
    no_hole: Vec<bool>,
    depth: Vec<f32>,
    alpha: Vec<f32>,
}

impl Rig {
    pub fn new(w: usize, h: usize) -> Rig {
        let cam = |name: &str, x: f64, y: f64| camera(name, w, h, x, y);
        let cams = [cam("t", 0.0, 0.0), cam("a", 1.5, 0.0), cam("b", -1.5, 0.5), cam("c", 0.3, -1.5)];
        let photos = photos(&cams);
        let interleaved = photos.iter().map(|p| cogeo::image_ops::interleave_rgb(p, w * h)).collect();
        let (no_hole, depth, alpha) = (vec![false; w * h], vec![WALL_Z as f32; w * h], vec![1.0; w * h]);
        Rig { cams, photos, interleaved, no_hole, depth, alpha }
    }

    /// Every camera as a source of its photo, the photos' colors the scene's.
    pub fn sources(&self) -> Vec<SourceView<'_>> {
        self.cams
            .iter()
            .zip(&self.photos)
            .map(|(camera, photo)| SourceView {
                camera,
                photo,
                hole: &self.no_hole,
                depth: &self.depth,
                alpha: &self.alpha,
                photo_colors: ColorAffine::IDENTITY,
            })
            .collect()
    }

    /// Whether the wall point under the target's pixel `p` lies inside at least two sources' images.
    pub fn seen_twice(&self, p: usize) -> bool {
        let w = self.cams[0].width as usize;
        let pt = self.cams[0].pixel_point(p % w, p / w, WALL_Z);
        self.cams[1..].iter().filter(|s| s.project_to_image(pt).is_some()).count() >= 2
    }
}
