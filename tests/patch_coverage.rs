//! Stage 4's patch covers a surface nearer than most of the patch without gaps, against the f64
//! reference renderer. One view completes a near wall (depth 2) beside a far one (depth 6) that
//! holds most of the fill's pixels. The fusion merges its points per voxel cell of the median
//! footprint (the far wall's pixel), so each cell of the near wall holds about 3 x 3 of its
//! pixels; a merged point's Gaussian once kept one pixel's size, and the near wall rendered as a
//! grating (the pedestal's top under the removed statue of the shared capture, with the dark
//! Gaussians behind it showing between the stripes).

use cogeo::removal::fuse::{fuse_points, patch_gaussians, FuseConfig, FuseView, UNREFINED_OPACITY};
use cogeo::render::reference::render_reference;
use cogeo::scene::Camera;

const SIZE: u32 = 48;
/// Columns of the near wall; the far wall takes the rest, so the median footprint is the far one.
const NEAR_COLUMNS: usize = 16;
const NEAR: f32 = 2.0;
const FAR: f32 = 6.0;

#[test]
fn a_near_surface_renders_without_gaps_between_its_merged_points() {
    let cam = Camera::look_at("v", SIZE, SIZE, 60.0, [0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]);
    let n = (SIZE * SIZE) as usize;
    let w = SIZE as usize;
    let depth: Vec<f32> = (0..n).map(|p| if p % w < NEAR_COLUMNS { NEAR } else { FAR }).collect();
    let rgb = vec![0.5f32; 3 * n];
    let fill = vec![true; n];
    let views = [FuseView { camera: &cam, rgb: &rgb, depth: &depth, fill: &fill }];
    let (points, stats, _) = fuse_points(&views, &FuseConfig::default());
    assert_eq!(stats.sampled, n);
    let near_points = points.iter().filter(|p| cam.to_camera(p.position)[2] < 3.0).count();
    // the near wall's 768 pixels merge about 9 to a cell
    println!("{} points ({near_points} on the near wall) from {n} pixels", points.len());
    assert!(near_points < 768 / 4, "{near_points} near points: the near pixels were not merged");

    let patch = patch_gaussians(&points, 0, UNREFINED_OPACITY);
    let image = render_reference(&patch, &cam, [0.0; 3], 0.01, 0, None);
    // inside the near wall, away from its edges (the image's border and the step to the far wall)
    let inner: Vec<f64> = (0..n)
        .filter(|&p| (3..NEAR_COLUMNS - 3).contains(&(p % w)) && (3..w - 3).contains(&(p / w)))
        .map(|p| image.alpha[p])
        .collect();
    let least = inner.iter().cloned().fold(f64::INFINITY, f64::min);
    let mean = inner.iter().sum::<f64>() / inner.len() as f64;
    println!("near wall alpha: least {least:.3}, mean {mean:.3}");
    // one pixel's Gaussian per cell left the near wall at alpha 0.23 between the cells (mean 0.39)
    assert!(least > 0.85, "a gap in the near wall: alpha {least:.3}");
    assert!(mean > 0.88, "the near wall is see-through: mean alpha {mean:.3}");
}
