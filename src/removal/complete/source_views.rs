//! The edited views as the other views see them (`SourceView`: photo, hole, original depth and
//! alpha), and the geometry both photo-consistent depth and color transfer ask of them: a pixel's
//! world point, where a point lands in a view, and whether that view saw it.

use crate::scene::exposure::ColorAffine;
use crate::scene::Camera;

/// One edited view as the other views see it.
pub struct SourceView<'a> {
    pub camera: &'a Camera,
    /// The captured image (planar RGB in [0, 1]).
    pub photo: &'a [f32],
    /// The dilated hole: the removed objects may cover these pixels in the photo.
    pub hole: &'a [bool],
    /// Expected depth and alpha of the original render (with the objects).
    pub depth: &'a [f32],
    pub alpha: &'a [f32],
    /// The photo's colors as an affine map of the scene's (what the original render shows):
    /// its exposure and white balance, which the color transfer takes out.
    pub photo_colors: ColorAffine,
}

/// World point of pixel `p` (center, row-major index) of `camera` at view depth `z`.
pub fn back_project(camera: &Camera, p: usize, z: f64) -> [f64; 3] {
    let w = camera.width as usize;
    camera.pixel_point(p % w, p / w, z)
}

/// Where `world` lands in source `s`: image position, pixel index and view depth; None when it
/// is behind the camera or outside the image.
pub fn project(s: &SourceView, world: [f64; 3]) -> Option<(f64, f64, usize, f64)> {
    let (x, y, z) = s.camera.project_to_image(world)?;
    Some((x, y, y as usize * s.camera.width as usize + x as usize, z))
}

/// Where source `s` saw `world`, as the transfer asks (off its hole, where its original render
/// is opaque and at the point's depth within `tolerance`, relative): the image position, or None.
pub fn sees(s: &SourceView, world: [f64; 3], tolerance: f64) -> Option<(f64, f64)> {
    let (x, y, q, z) = project(s, world)?;
    let d = s.depth[q] as f64;
    (!s.hole[q] && s.alpha[q] > 0.5 && (z - d).abs() <= tolerance * d).then_some((x, y))
}
