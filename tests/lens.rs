//! The COLMAP lens models (scene/lens.rs): each model's inverse against its forward map, and the
//! forward maps against closed forms.

use cogeo::scene::lens::{ColmapIntrinsics, Lens};

/// Every supported model with realistic coefficients (a phone's radial, an action camera's fisheye).
fn models() -> Vec<(&'static str, Vec<f64>)> {
    vec![
        ("SIMPLE_RADIAL", vec![600.0, 504.0, 283.5, 0.033]),
        ("SIMPLE_RADIAL", vec![600.0, 504.0, 283.5, -0.12]),
        ("RADIAL", vec![600.0, 504.0, 283.5, -0.1, 0.02]),
        ("OPENCV", vec![610.0, 605.0, 500.0, 290.0, -0.08, 0.01, 0.001, -0.0015]),
        ("FULL_OPENCV", vec![610.0, 605.0, 500.0, 290.0, -0.08, 0.01, 0.001, -0.0015, 0.002, 0.05, 0.001, 0.0005]),
        ("OPENCV_FISHEYE", vec![420.0, 421.0, 504.0, 283.5, 0.05, -0.01, 0.002, -0.0005]),
        ("SIMPLE_RADIAL_FISHEYE", vec![420.0, 504.0, 283.5, 0.04]),
        ("RADIAL_FISHEYE", vec![420.0, 504.0, 283.5, 0.04, -0.006]),
        (
            "THIN_PRISM_FISHEYE",
            vec![420.0, 421.0, 504.0, 283.5, 0.03, -0.004, 0.0008, -0.0006, 0.001, -0.0002, 0.0007, -0.0004],
        ),
    ]
}

#[test]
fn each_model_inverts_its_distortion_to_a_thousandth_of_a_pixel() {
    let (w, h) = (1008.0, 567.0);
    for (model, params) in models() {
        let k = ColmapIntrinsics::from_colmap(model, &params, "test").unwrap();
        assert!(!k.lens.is_pinhole(), "{model}");
        let mut worst = 0f64;
        // every 8th pixel of the frame, corners and edges included
        for py in (0..=567).step_by(9) {
            for px in (0..=1008).step_by(8) {
                let (x, y) = (px as f64 * w / 1008.0, py as f64 * h / 567.0);
                let (u, v) = k.unproject(x, y).unwrap_or_else(|| panic!("{model}: no inverse at ({x}, {y})"));
                let (bx, by) = k.project(u, v);
                worst = worst.max((bx - x).hypot(by - y));
            }
        }
        assert!(worst < 1e-3, "{model} {params:?}: round trip off by {worst:e} px");
        // and the distortion is real: the corner moves by pixels
        let (u, v) = k.unproject(0.0, 0.0).unwrap();
        let pinhole = (k.fx * u + k.cx, k.fy * v + k.cy);
        assert!(pinhole.0.hypot(pinhole.1) > 1.0, "{model}: the corner does not move");
    }
}

#[test]
fn forward_maps_match_closed_forms() {
    // SIMPLE_RADIAL: x = u (1 + k r^2)
    let k = ColmapIntrinsics::from_colmap("SIMPLE_RADIAL", &[500.0, 320.0, 240.0, 0.1], "t").unwrap();
    let (u, v) = (0.3, -0.2);
    let f = 1.0 + 0.1 * (0.09 + 0.04);
    let (x, y) = k.project(u, v);
    assert!((x - (500.0 * u * f + 320.0)).abs() < 1e-9 && (y - (500.0 * v * f + 240.0)).abs() < 1e-9);
    // OPENCV_FISHEYE with zero coefficients is the equidistant projection: radius = f atan(r)
    let k =
        ColmapIntrinsics::from_colmap("OPENCV_FISHEYE", &[400.0, 400.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], "t").unwrap();
    let (x, y) = k.project(1.0, 0.0);
    assert!((x - 400.0 * std::f64::consts::FRAC_PI_4).abs() < 1e-9 && y.abs() < 1e-12);
    // OPENCV tangential: p1 moves a point on the x axis along y by p1 r^2 (x = u, v = 0)
    let k = ColmapIntrinsics::from_colmap("OPENCV", &[1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.01, 0.0], "t").unwrap();
    let (x, y) = k.project(0.5, 0.0);
    assert!((x - 0.5).abs() < 1e-12 && (y - 0.01 * 0.25).abs() < 1e-12);
    // a radial model with zero coefficients is a pinhole
    let k = ColmapIntrinsics::from_colmap("RADIAL", &[500.0, 320.0, 240.0, 0.0, 0.0], "t").unwrap();
    assert_eq!(k.lens, Lens::Pinhole);
}

#[test]
fn bad_parameter_lists_are_refused_naming_the_model() {
    let e = ColmapIntrinsics::from_colmap("OPENCV", &[1.0, 1.0, 0.0, 0.0], "cameras.txt:3").unwrap_err().to_string();
    assert!(e.contains("cameras.txt:3") && e.contains("OPENCV takes 8 parameters, got 4"), "{e}");
    let e = ColmapIntrinsics::from_colmap("FOV", &[1.0, 1.0, 0.0, 0.0, 0.5], "c").unwrap_err().to_string();
    assert!(e.contains("unsupported camera model \"FOV\""), "{e}");
    let e = ColmapIntrinsics::from_colmap("SIMPLE_RADIAL", &[1.0, 0.0, 0.0, f64::NAN], "c").unwrap_err().to_string();
    assert!(e.contains("non-finite"), "{e}");
}
