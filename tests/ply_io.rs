//! PLY reading and writing: bit-exact round trips, any property order, ascii, extra properties, and
//! clear errors for broken files.

mod common;

use cogeo::scene::ply::{encode_ply, read_ply, read_ply_from, write_ply};
use cogeo::scene::{ExtraProperty, GaussianScene, PlyType};
use common::{random_scene, shared_data, SceneMix};

fn with_extras(mut scene: GaussianScene) -> GaussianScene {
    let n = scene.len();
    for c in 0..16 {
        scene.extras.push(ExtraProperty {
            name: format!("f_obj_{c}"),
            ty: PlyType::F32,
            values: (0..n).map(|i| ((i * 31 + c * 7) as f32 * 0.173).sin() as f64).collect(),
        });
    }
    scene.extras.push(ExtraProperty {
        name: "label".into(),
        ty: PlyType::U8,
        values: (0..n).map(|i| (i % 5) as f64).collect(),
    });
    scene.extras.push(ExtraProperty {
        name: "id".into(),
        ty: PlyType::I32,
        values: (0..n).map(|i| i as f64 - 7.0).collect(),
    });
    scene.extras.push(ExtraProperty {
        name: "w".into(),
        ty: PlyType::F64,
        values: (0..n).map(|i| 1.0 / (i as f64 + 3.0)).collect(),
    });
    scene
}

fn bits(scene: &GaussianScene) -> Vec<u32> {
    let mut v: Vec<u32> = Vec::new();
    v.extend(scene.means.iter().flatten().map(|x| x.to_bits()));
    v.extend(scene.normals.iter().flatten().map(|x| x.to_bits()));
    v.extend(scene.log_scales.iter().flatten().map(|x| x.to_bits()));
    v.extend(scene.quats.iter().flatten().map(|x| x.to_bits()));
    v.extend(scene.opacity_logits.iter().map(|x| x.to_bits()));
    v.extend(scene.sh.iter().map(|x| x.to_bits()));
    v
}

#[test]
fn binary_round_trip_is_bit_exact_for_every_sh_degree_with_extras() {
    let dir = tempdir();
    for degree in 0..=3 {
        let scene = with_extras(random_scene(degree as u64, degree, SceneMix::default()));
        let path = dir.join(format!("s{degree}.ply"));
        write_ply(&scene, &path).unwrap();
        let back = read_ply(&path).unwrap();
        assert_eq!(back.sh_degree, degree);
        assert_eq!(bits(&scene), bits(&back));
        assert_eq!(scene.extras, back.extras);
        // and writing again gives the same bytes
        assert_eq!(std::fs::read(&path).unwrap(), encode_ply(&back));
    }
}

/// Re-encodes a scene's PLY in another property order and format, by hand.
fn reorder_ascii(scene: &GaussianScene) -> String {
    let bytes = encode_ply(scene);
    let text_end = bytes.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    let header = std::str::from_utf8(&bytes[..text_end]).unwrap();
    let props: Vec<(String, String)> = header
        .lines()
        .filter(|l| l.starts_with("property"))
        .map(|l| {
            let w: Vec<&str> = l.split_whitespace().collect();
            (w[1].to_string(), w[2].to_string())
        })
        .collect();
    // decode rows
    let sizes: Vec<usize> = props
        .iter()
        .map(|(t, _)| match t.as_str() {
            "uchar" => 1,
            "double" => 8,
            _ => 4,
        })
        .collect();
    let stride: usize = sizes.iter().sum();
    let body = &bytes[text_end..];
    let order: Vec<usize> = (0..props.len()).rev().collect(); // reversed property order
    let mut out = format!("ply\nformat ascii 1.0\ncomment reordered\nelement vertex {}\n", scene.len());
    for &j in &order {
        out += &format!("property {} {}\n", props[j].0, props[j].1);
    }
    out += "end_header\n";
    for i in 0..scene.len() {
        let row = &body[i * stride..(i + 1) * stride];
        let mut offs = 0;
        let mut vals = vec![String::new(); props.len()];
        for (j, (t, _)) in props.iter().enumerate() {
            let b = &row[offs..offs + sizes[j]];
            vals[j] = match t.as_str() {
                "uchar" => b[0].to_string(),
                "double" => format!("{:?}", f64::from_le_bytes(b.try_into().unwrap())),
                "int" => i32::from_le_bytes(b.try_into().unwrap()).to_string(),
                _ => format!("{:?}", f32::from_le_bytes(b.try_into().unwrap())),
            };
            offs += sizes[j];
        }
        let line: Vec<&str> = order.iter().map(|&j| vals[j].as_str()).collect();
        out += &line.join(" ");
        out += "\n";
    }
    out
}

#[test]
fn ascii_and_any_property_order_read_identically() {
    let scene = with_extras(random_scene(77, 2, SceneMix { normal: 50, ..Default::default() }));
    let text = reorder_ascii(&scene);
    let back = read_ply_from(&mut std::io::Cursor::new(text.as_bytes()), "reordered.ply").unwrap();
    assert_eq!(bits(&scene), bits(&back));
    // extras keep their values (their order follows the file)
    for e in &scene.extras {
        let b = back.extras.iter().find(|x| x.name == e.name).expect("extra property kept");
        assert_eq!(b.values, e.values);
        assert_eq!(b.ty, e.ty);
    }
}

#[test]
fn guitar_round_trip_reproduces_the_file_byte_for_byte() {
    let Some(path) = shared_data("splats/guitar.ply") else {
        return;
    };
    let scene = read_ply(&path).unwrap();
    assert_eq!(scene.len(), 90_854);
    assert_eq!(scene.sh_degree, 3);
    scene.validate("guitar").unwrap();
    assert_eq!(encode_ply(&scene), std::fs::read(&path).unwrap());
}

fn err(bytes: &[u8]) -> String {
    format!("{:#}", read_ply_from(&mut std::io::Cursor::new(bytes), "bad.ply").unwrap_err())
}

#[test]
fn broken_files_give_clear_errors() {
    let scene = random_scene(3, 1, SceneMix { normal: 20, ..Default::default() });
    let good = encode_ply(&scene);
    let e = err(&good[..good.len() - 10]);
    assert!(e.contains("bad.ply") && e.contains("truncated"), "{e}");
    let e = err(b"hello\n");
    assert!(e.contains("not a PLY"), "{e}");
    let e = err(b"ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nend_header\n");
    assert!(e.contains("missing required property"), "{e}");
    let e = err(b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n");
    assert!(e.contains("end_header"), "{e}");
    let header_end = good.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    let text = String::from_utf8(good[..header_end].to_vec()).unwrap();
    let e = err(text.replace("f_rest_8", "f_rest_99").as_bytes());
    assert!(e.contains("f_rest"), "{e}");

    // NaN and zero quaternions are caught by validation, naming the Gaussian
    let mut nan = scene.clone();
    nan.log_scales[4][1] = f32::NAN;
    let e = format!("{:#}", nan.validate("nan.ply").unwrap_err());
    assert!(e.contains("nan.ply") && e.contains("Gaussian 4"), "{e}");
    let mut zq = scene.clone();
    zq.quats[2] = [0.0; 4];
    let e = format!("{:#}", zq.validate("zq.ply").unwrap_err());
    assert!(e.contains("zero-norm"), "{e}");
    let e = format!("{:#}", GaussianScene::default().validate("empty.ply").unwrap_err());
    assert!(e.contains("no Gaussians"), "{e}");
}

fn tempdir() -> std::path::PathBuf {
    let name = std::thread::current().name().unwrap_or("t").replace("::", "_");
    common::scratch_dir(&format!("ply-{name}"))
}
