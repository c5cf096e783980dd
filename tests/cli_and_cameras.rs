//! The `cogeo render` command end to end (validation layer on), its errors on bad input, and the
//! camera loaders (cameras.json, COLMAP text and binary, the shared statue capture).

mod common;

use cogeo::render::reference::render_reference;
use cogeo::scene::camera::{read_cameras_json, write_cameras_json};
use cogeo::scene::colmap::read_colmap;
use cogeo::scene::lens::Lens;
use cogeo::scene::ply::{encode_ply, write_ply};
use cogeo::scene::{Camera, GaussianScene};
use common::{random_scene, test_camera, SceneMix};
use std::path::{Path, PathBuf};
use std::process::Command;

fn tempdir(name: &str) -> PathBuf {
    common::scratch_dir(&format!("cli-{name}"))
}

fn cogeo(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_cogeo"))
        .args(args)
        .env("COGEO_VALIDATE", std::env::var("COGEO_VALIDATE").unwrap_or_else(|_| "1".into()))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!stderr.contains("vulkan validation:"), "validation messages:\n{stderr}");
    (out.status.code().unwrap_or(-1), stderr)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn render_writes_png_depth_and_alpha_that_match_the_reference() {
    let dir = tempdir("ok");
    let scene = random_scene(5, 2, SceneMix::default());
    let scene_path = dir.join("scene.ply");
    write_ply(&scene, &scene_path).unwrap();
    let mut cam_a = test_camera(70, 45);
    cam_a.name = "a".into();
    let mut cam_b = Camera::look_at("b", 50, 40, 50.0, [1.0, -0.5, -4.0], [0.0; 3], [0.0, -1.0, 0.0]);
    cam_b.cx = 25.0;
    cam_b.cy = 20.0;
    let cams_path = dir.join("cameras.json");
    write_cameras_json(&[cam_a.clone(), cam_b], &cams_path).unwrap();
    let out = dir.join("out");
    let (code, err) = cogeo(&[
        "render",
        "--scene",
        s(&scene_path),
        "--cameras",
        s(&cams_path),
        "--out",
        s(&out),
        "--depth",
        "--alpha",
        "--background",
        "0.2,0.4,0.6",
    ]);
    assert_eq!(code, 0, "{err}");
    for f in ["a.png", "b.png", "a_depth.exr", "a_alpha.png", "b_alpha.png", "b_depth.exr"] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    // the PNG holds the rendered colors, rounded to 8 bits
    let png = image::open(out.join("a.png")).unwrap().to_rgb8();
    assert_eq!(png.dimensions(), (70, 45));
    let reference = render_reference(&scene, &cam_a, [0.2, 0.4, 0.6], 0.01, 2, None);
    let hw = 70 * 45;
    let mut off = 0;
    for (i, p) in png.pixels().enumerate() {
        for c in 0..3 {
            let want = (reference.rgb[c * hw + i].clamp(0.0, 1.0) * 255.0).round();
            if (p[c] as f64 - want).abs() > 1.0 {
                off += 1;
            }
        }
    }
    assert!(off <= 3, "{off} PNG samples differ from the reference by more than one level");
    let (w, h, depth) = cogeo::io::read_exr_channel(&out.join("a_depth.exr"), None).unwrap();
    assert_eq!((w, h), (70, 45));
    let i = (0..hw).find(|&i| !reference.ambiguous[i] && reference.alpha[i] > 0.5).unwrap();
    assert!((depth[i] as f64 - reference.expected_depth[i]).abs() <= 1e-4 * reference.expected_depth[i]);
    // no temporary files left behind
    assert!(std::fs::read_dir(&out).unwrap().all(|e| !e.unwrap().file_name().to_string_lossy().ends_with(".tmp")));

    // --width alone keeps the aspect ratio and scales intrinsics
    let out2 = dir.join("out2");
    let (code, err) =
        cogeo(&["render", "--scene", s(&scene_path), "--cameras", s(&cams_path), "--out", s(&out2), "--width", "140"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(image::open(out2.join("a.png")).unwrap().to_rgb8().dimensions(), (140, 90));
}

/// Runs a render that must fail; checks a one-line error naming `needle` and an untouched --out.
fn expect_failure(args: &[&str], out: &Path, needle: &str) {
    let (code, err) = cogeo(args);
    assert_ne!(code, 0, "expected failure for {args:?}");
    let lines: Vec<&str> = err.lines().filter(|l| !l.trim().is_empty()).collect();
    let last = lines.last().copied().unwrap_or("");
    assert!(last.starts_with("error: ") && last.contains(needle), "unexpected error output for {args:?}:\n{err}");
    assert!(!out.exists() || std::fs::read_dir(out).unwrap().next().is_none(), "{} was written to", out.display());
}

#[test]
fn bad_inputs_fail_with_one_clear_line_and_write_nothing() {
    let dir = tempdir("bad");
    let out = dir.join("out");
    let good = random_scene(1, 1, SceneMix { normal: 30, ..Default::default() });
    let good_path = dir.join("good.ply");
    write_ply(&good, &good_path).unwrap();
    let cams = dir.join("cameras.json");
    write_cameras_json(&[test_camera(32, 32)], &cams).unwrap();

    expect_failure(
        &["render", "--scene", s(&dir.join("missing.ply")), "--cameras", s(&cams), "--out", s(&out)],
        &out,
        "missing.ply",
    );

    let bytes = encode_ply(&good);
    let truncated = dir.join("truncated.ply");
    std::fs::write(&truncated, &bytes[..bytes.len() - 100]).unwrap();
    expect_failure(&["render", "--scene", s(&truncated), "--cameras", s(&cams), "--out", s(&out)], &out, "truncated");

    let malformed = dir.join("malformed.ply");
    std::fs::write(
        &malformed,
        b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nend_header\n",
    )
    .unwrap();
    expect_failure(
        &["render", "--scene", s(&malformed), "--cameras", s(&cams), "--out", s(&out)],
        &out,
        "malformed.ply",
    );

    let mut nan = good.clone();
    nan.means[3][0] = f32::NAN;
    let nan_path = dir.join("nan.ply");
    write_ply(&nan, &nan_path).unwrap();
    expect_failure(&["render", "--scene", s(&nan_path), "--cameras", s(&cams), "--out", s(&out)], &out, "NaN");

    let mut zq = good.clone();
    zq.quats[0] = [0.0; 4];
    let zq_path = dir.join("zq.ply");
    write_ply(&zq, &zq_path).unwrap();
    expect_failure(&["render", "--scene", s(&zq_path), "--cameras", s(&cams), "--out", s(&out)], &out, "zero-norm");

    let empty_path = dir.join("empty.ply");
    write_ply(&GaussianScene::default(), &empty_path).unwrap();
    expect_failure(
        &["render", "--scene", s(&empty_path), "--cameras", s(&cams), "--out", s(&out)],
        &out,
        "no Gaussians",
    );

    let colmap = dir.join("colmap");
    std::fs::create_dir_all(&colmap).unwrap();
    std::fs::write(colmap.join("cameras.txt"), "1 EQUIRECTANGULAR 100 80 50 50 40\n").unwrap();
    std::fs::write(colmap.join("images.txt"), "1 1 0 0 0 0 0 4 1 a.png\n\n").unwrap();
    expect_failure(
        &["render", "--scene", s(&good_path), "--colmap", s(&colmap), "--out", s(&out)],
        &out,
        "EQUIRECTANGULAR",
    );

    expect_failure(
        &["render", "--scene", s(&good_path), "--cameras", s(&dir.join("nope.json")), "--out", s(&out)],
        &out,
        "nope.json",
    );
    let bad_json = dir.join("bad.json");
    std::fs::write(&bad_json, "{\"not\": \"a list\"}").unwrap();
    expect_failure(
        &["render", "--scene", s(&good_path), "--cameras", s(&bad_json), "--out", s(&out)],
        &out,
        "bad.json",
    );
    expect_failure(
        &["render", "--scene", s(&good_path), "--cameras", s(&cams), "--out", s(&out), "--features"],
        &out,
        "f_obj",
    );
    // a zero band interval is refused at the flag, by `run` as by the `train` it launches
    for cmd in ["train", "run"] {
        let mut args = vec![cmd, "--data", s(&dir), "--out", s(&out), "--sh-band-every", "0"];
        if cmd == "run" {
            args.extend(["--masks", s(&dir)]);
        }
        let (code, err) = cogeo(&args);
        assert!(code != 0 && err.contains("--sh-band-every") && err.contains("0 is not in 1.."), "{cmd}: {err}");
        assert!(!out.exists(), "{cmd} wrote {}", out.display());
    }
}

#[test]
fn cameras_json_round_trip() {
    let dir = tempdir("json");
    let cams: Vec<Camera> = (0..3)
        .map(|i| Camera::look_at(&format!("c{i}"), 64 + i, 48, 55.0, [i as f64, 0.5, -3.0], [0.0; 3], [0.0, -1.0, 0.0]))
        .collect();
    write_cameras_json(&cams, &dir.join("cameras.json")).unwrap();
    let back = read_cameras_json(&dir.join("cameras.json")).unwrap();
    for (a, b) in cams.iter().zip(&back) {
        assert_eq!((a.width, a.height, &a.name), (b.width, b.height, &b.name));
        for r in 0..3 {
            assert!((a.translation[r] - b.translation[r]).abs() < 1e-12);
            for c in 0..3 {
                assert!((a.rotation[r][c] - b.rotation[r][c]).abs() < 1e-12);
            }
        }
    }
}

/// Writes a COLMAP binary model equivalent to a text one and checks both read the same.
#[test]
fn colmap_binary_and_text_agree() {
    let dir = tempdir("colmap");
    let txt = dir.join("txt");
    let bin = dir.join("bin/sparse/0");
    std::fs::create_dir_all(&txt).unwrap();
    std::fs::create_dir_all(&bin).unwrap();
    std::fs::write(
        txt.join("cameras.txt"),
        "# c\n1 PINHOLE 640 480 500 510 320 240\n2 SIMPLE_RADIAL 320 240 300 160 120 0.01\n",
    )
    .unwrap();
    std::fs::write(
        txt.join("images.txt"),
        "# i\n2 0.9 0.1 0.2 0.3 1 2 3 2 b.jpg\n10 20 -1\n1 1 0 0 0 0 0 5 1 a.jpg\n\n",
    )
    .unwrap();
    std::fs::write(txt.join("points3D.txt"), "1 0.5 0.25 3 255 128 0 0.1 1 0\n").unwrap();

    let mut c = Vec::new();
    c.extend(2u64.to_le_bytes());
    for (id, model, w, h, params) in [
        (1i32, 1i32, 640u64, 480u64, vec![500.0, 510.0, 320.0, 240.0]),
        (2, 2, 320, 240, vec![300.0, 160.0, 120.0, 0.01]),
    ] {
        c.extend(id.to_le_bytes());
        c.extend(model.to_le_bytes());
        c.extend(w.to_le_bytes());
        c.extend(h.to_le_bytes());
        params.iter().for_each(|p: &f64| c.extend(p.to_le_bytes()));
    }
    std::fs::write(bin.join("cameras.bin"), c).unwrap();
    let mut im = Vec::new();
    im.extend(2u64.to_le_bytes());
    for (id, q, t, cam, name, npts) in [
        (2i32, [0.9, 0.1, 0.2, 0.3], [1.0, 2.0, 3.0], 2i32, "b.jpg", 1u64),
        (1, [1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 5.0], 1, "a.jpg", 0),
    ] {
        im.extend(id.to_le_bytes());
        q.iter().for_each(|v: &f64| im.extend(v.to_le_bytes()));
        t.iter().for_each(|v: &f64| im.extend(v.to_le_bytes()));
        im.extend(cam.to_le_bytes());
        im.extend(name.as_bytes());
        im.push(0);
        im.extend(npts.to_le_bytes());
        for _ in 0..npts {
            im.extend(10.0f64.to_le_bytes());
            im.extend(20.0f64.to_le_bytes());
            im.extend((-1i64).to_le_bytes());
        }
    }
    std::fs::write(bin.join("images.bin"), im).unwrap();
    let mut pts = Vec::new();
    pts.extend(1u64.to_le_bytes());
    pts.extend(1u64.to_le_bytes());
    [0.5f64, 0.25, 3.0].iter().for_each(|v| pts.extend(v.to_le_bytes()));
    pts.extend([255u8, 128, 0]);
    pts.extend(0.1f64.to_le_bytes());
    pts.extend(1u64.to_le_bytes());
    pts.extend(1i32.to_le_bytes());
    pts.extend(0i32.to_le_bytes());
    std::fs::write(bin.join("points3D.bin"), pts).unwrap();

    let a = read_colmap(&txt).unwrap();
    let b = read_colmap(&dir.join("bin")).unwrap();
    assert_eq!(a.cameras, b.cameras);
    assert_eq!(a.cameras.len(), 2);
    assert_eq!(a.cameras[0].name, "a"); // sorted by name
    assert_eq!((a.cameras[1].fx, a.cameras[1].fy, a.cameras[1].cx), (300.0, 300.0, 160.0));
    // the SIMPLE_RADIAL camera keeps its lens (undistorted on load, scene/undistort.rs)
    assert_eq!(a.lenses, b.lenses);
    assert_eq!(a.lenses, vec![Lens::Pinhole, Lens::Radial { k1: 0.01, k2: 0.0 }]);
    assert!(a.warnings.is_empty(), "{:?}", a.warnings);
    assert_eq!(b.points.len(), 1);
    assert_eq!(a.points[0].xyz, b.points[0].xyz);
    assert_eq!(a.points[0].rgb, [255, 128, 0]);
}

#[test]
fn statue_colmap_model_loads_and_points_project_into_the_views() {
    let Some(dir) = common::shared_data("statue") else {
        return;
    };
    let model = read_colmap(&dir).unwrap();
    assert_eq!(model.cameras.len(), 29);
    assert_eq!(model.points.len(), 15_881);
    let c0 = &model.cameras[0];
    assert_eq!((c0.name.as_str(), c0.width, c0.height), ("IMG_2707", 1008, 756));
    assert!((c0.fx - 740.325).abs() < 1e-3 && (c0.fy - 742.618).abs() < 1e-3);
    // images_2 halves the intrinsics
    let half = c0.resized(504, 378);
    assert!((half.fx - 370.1625).abs() < 1e-3);
    // the sparse points lie in front of the cameras and mostly inside the images
    for cam in &model.cameras {
        let mut inside = 0;
        for p in &model.points {
            let v = cam.to_camera(p.xyz);
            if v[2] > 0.0 {
                let u = cam.fx * v[0] / v[2] + cam.cx;
                let w = cam.fy * v[1] / v[2] + cam.cy;
                if u >= 0.0 && u < cam.width as f64 && w >= 0.0 && w < cam.height as f64 {
                    inside += 1;
                }
            }
        }
        assert!(inside * 2 > model.points.len(), "{}: only {inside} points project inside", cam.name);
    }
}

/// `render --builtin` writes the built-in scene and its cameras beside the renders; rendering
/// those files again gives the same pixels (the image is a function of scene and camera).
#[test]
fn render_builtin_writes_a_scene_that_renders_the_same_again() {
    let dir = tempdir("builtin");
    let (a, b) = (dir.join("a"), dir.join("b"));
    let (code, err) =
        cogeo(&["render", "--builtin", "--views", "2", "--width", "48", "--height", "32", "--out", s(&a)]);
    assert_eq!(code, 0, "{err}");
    let cams = read_cameras_json(&a.join("cameras.json")).unwrap();
    assert_eq!(cams.len(), 2);
    let (code, err) =
        cogeo(&["render", "--scene", s(&a.join("scene.ply")), "--cameras", s(&a.join("cameras.json")), "--out", s(&b)]);
    assert_eq!(code, 0, "{err}");
    for c in &cams {
        let first = image::open(a.join(format!("{}.png", c.name))).unwrap().to_rgb8();
        let again = image::open(b.join(format!("{}.png", c.name))).unwrap().to_rgb8();
        assert_eq!(first.dimensions(), (48, 32));
        assert!(first.pixels().any(|p| p.0 != [0, 0, 0]), "{}: empty render", c.name);
        assert_eq!(first, again);
    }
    // --builtin and --scene together are refused
    let (code, _) = cogeo(&["render", "--builtin", "--scene", s(&a.join("scene.ply")), "--out", s(&b)]);
    assert_ne!(code, 0);
    std::fs::remove_dir_all(&dir).ok();
}
