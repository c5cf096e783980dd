//! `cogeo synth` anti-aliasing: a pixel rendered with N x N color rays must equal the mean of the
//! N x N pixels it covers in a render N times finer with one ray each (the same camera with its
//! intrinsics scaled), and one ray per pixel must stay the plain pixel-center render.

use cogeo::rng::Rng;
use cogeo::synth::{make_cameras, make_objects, render_view, Rig, SynthConfig};

fn config() -> SynthConfig {
    SynthConfig {
        width: 40,
        height: 30,
        views: 8,
        objects: 3,
        rig: Rig::Forward,
        seed: 5,
        points_per_view: 10,
        gt_without: Vec::new(),
        supersample: 3,
        distortion: [0.0; 4],
        exposure_jitter: 0.0,
    }
}

#[test]
fn supersampled_pixels_are_box_filtered_finer_pixels() {
    let cfg = config();
    let objects = make_objects(cfg.objects, &mut Rng::new(cfg.seed));
    let n = cfg.supersample as usize;
    let mut compared = 0usize;
    let mut mismatched = 0usize;
    let mut textured = 0usize;
    for cam in make_cameras(&cfg).iter().take(2) {
        let (w, h) = (cam.width as usize, cam.height as usize);
        let coarse = render_view(cam, &objects, cfg.seed, cfg.supersample);
        let fine_cam = cam.resized(cam.width * n as u32, cam.height * n as u32);
        let fine = render_view(&fine_cam, &objects, cfg.seed, 1);
        let center = render_view(cam, &objects, cfg.seed, 1);
        // depth and labels do not depend on the color sampling
        assert_eq!(coarse.labels, center.labels);
        assert_eq!(coarse.depth, center.depth);
        let (fw, fh) = (w * n, h * n);
        for c in 0..3 {
            for y in 0..h {
                for x in 0..w {
                    let mut sum = 0.0f64;
                    let (mut lo, mut hi) = (f32::MAX, f32::MIN);
                    for sy in 0..n {
                        for sx in 0..n {
                            let v = fine.rgb[c * fw * fh + (y * n + sy) * fw + x * n + sx];
                            sum += v as f64;
                            lo = lo.min(v);
                            hi = hi.max(v);
                        }
                    }
                    let got = coarse.rgb[c * w * h + y * w + x] as f64;
                    compared += 1;
                    // the scaled camera's rays differ from the sub-pixel rays by rounding only,
                    // which can move a sample across a texture edge now and then
                    if (got - sum / (n * n) as f64).abs() > 1e-5 {
                        mismatched += 1;
                    }
                    if hi - lo > 0.1 {
                        textured += 1;
                    }
                }
            }
        }
    }
    assert!(textured > compared / 20, "too few pixels with sub-pixel detail ({textured}) to test the filter");
    assert!(mismatched * 500 <= compared, "{mismatched} of {compared} supersampled values differ from the box filter");
}

#[test]
fn one_ray_per_pixel_is_the_pixel_center_render() {
    let cfg = config();
    let objects = make_objects(cfg.objects, &mut Rng::new(cfg.seed));
    let cam = &make_cameras(&cfg)[1];
    let (w, h) = (cam.width as usize, cam.height as usize);
    let one = render_view(cam, &objects, cfg.seed, 1);
    // the pixel-center ray of a 3x finer camera is its middle sub-pixel
    let fine = render_view(&cam.resized(cam.width * 3, cam.height * 3), &objects, cfg.seed, 1);
    let mut differ = 0;
    for c in 0..3 {
        for y in 0..h {
            for x in 0..w {
                let a = one.rgb[c * w * h + y * w + x];
                let b = fine.rgb[c * 9 * w * h + (3 * y + 1) * 3 * w + 3 * x + 1];
                if (a - b).abs() > 1e-5 {
                    differ += 1;
                }
            }
        }
    }
    assert!(differ * 500 <= 3 * w * h, "{differ} center samples differ");
}
