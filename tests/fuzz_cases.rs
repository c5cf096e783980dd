//! Regression tests from fuzzing (bench/fuzz.rs): every minimized input kept in tests/fuzz_cases/
//! replays without a panic and within the allocation bound, and the hostile inputs found by
//! reading the parsers (counts that claim more than the file holds, counts whose byte size
//! overflows, sizes past the limits, non-finite poses) get one clear error each, at once.

#[path = "../bench/fuzz_seeds.rs"]
mod fuzz_seeds;
#[path = "../bench/fuzz_targets.rs"]
mod fuzz_targets;

use fuzz_targets::{allocation_bound, run_one, Family, Outcome, Seeds, FAMILIES};

/// Runs `input` through the family's parser: it must not panic and must stay within the
/// allocation bound; returns the error message (None when accepted).
fn check(family: Family, input: &[u8], seeds: &Seeds) -> Option<String> {
    let (outcome, peak) = run_one(family, input, seeds);
    assert!(
        peak <= allocation_bound(input.len()),
        "{}: {peak} bytes in one allocation for a {}-byte input",
        family.name(),
        input.len()
    );
    match outcome {
        Outcome::Accepted => None,
        Outcome::Rejected(m) => Some(m),
        Outcome::Panic(m) => panic!("{}: the parser panicked: {m}", family.name()),
    }
}

fn rejected(family: Family, input: &[u8], seeds: &Seeds, expect: &str) {
    let message = check(family, input, seeds).unwrap_or_else(|| panic!("{}: accepted a bad input", family.name()));
    assert!(message.contains(expect), "{}: expected an error about {expect:?}, got {message:?}", family.name());
}

#[test]
fn the_allocation_check_can_fail() {
    // the tracking allocator sees a large request, so the bound above is a real check
    fuzz_targets::reset_largest();
    let big = vec![1u8; 64 << 20];
    assert!(fuzz_targets::largest() >= big.len());
    assert!(big.len() > allocation_bound(1000));
}

#[test]
fn every_seed_is_accepted() {
    let seeds = Seeds::new();
    for family in FAMILIES {
        for (i, seed) in seeds.of(family).iter().enumerate() {
            if let Some(m) = check(family, &seed.bytes, &seeds) {
                panic!("{} seed {i} is rejected: {m}", family.name());
            }
        }
    }
}

#[test]
fn kept_fuzz_findings_replay_cleanly() {
    let seeds = Seeds::new();
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_cases");
    let mut replayed = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let family = FAMILIES
            .into_iter()
            .find(|f| name.starts_with(&format!("{}-", f.name())))
            .unwrap_or_else(|| panic!("{name}: file name must start with a family name"));
        let input = std::fs::read(&path).unwrap();
        if let Some(m) = check(family, &input, &seeds) {
            assert!(!m.trim().is_empty(), "{name}: empty error message");
        }
        replayed += 1;
    }
    assert!(replayed > 0, "no cases in {}", dir.display());
}

fn ply_header(format: &str, count: &str) -> Vec<u8> {
    let mut h = format!("ply\nformat {format} 1.0\nelement vertex {count}\n");
    for p in ["x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "opacity", "scale_0", "scale_1", "scale_2"] {
        h += &format!("property float {p}\n");
    }
    for p in ["rot_0", "rot_1", "rot_2", "rot_3"] {
        h += &format!("property float {p}\n");
    }
    h += "end_header\n";
    h.into_bytes()
}

#[test]
fn a_ply_claiming_2_pow_40_vertices_fails_at_the_end_of_its_data() {
    let seeds = Seeds::new();
    let mut binary = ply_header("binary_little_endian", "1099511627776");
    binary.extend(std::iter::repeat_n(0u8, 14 * 4 * 3)); // three vertices of data
    rejected(Family::Ply, &binary, &seeds, "truncated PLY");
    let mut ascii = ply_header("ascii", "1099511627776");
    ascii.extend_from_slice(b"0 0 0 0 0 0 0 0 0 0 1 0 0 0\n");
    rejected(Family::Ply, &ascii, &seeds, "file ends in vertex 1 of 1099511627776");
    rejected(Family::Ply, &ply_header("ascii", "-1"), &seeds, "bad element count");
    rejected(Family::Ply, &ply_header("ascii", "18446744073709551616"), &seeds, "bad element count");
}

#[test]
fn a_ply_with_a_nan_or_a_zero_rotation_is_named() {
    let seeds = Seeds::new();
    let mut nan = ply_header("ascii", "1");
    nan.extend_from_slice(b"0 nan 0 0 0 0 0 0 0 0 1 0 0 0\n");
    rejected(Family::Ply, &nan, &seeds, "Gaussian 0 has a NaN or infinite parameter");
    let mut zero = ply_header("ascii", "1");
    zero.extend_from_slice(b"0 0 0 0 0 0 0 0 0 0 0 0 0 0\n");
    rejected(Family::Ply, &zero, &seeds, "zero-norm rotation");
}

/// A COLMAP input of the fuzz families: the first byte picks the file (0 cameras, 1 images, 2
/// points3D) that `body` replaces; the other two are valid.
fn colmap(part: u8, body: &[u8]) -> Vec<u8> {
    std::iter::once(part).chain(body.iter().copied()).collect()
}

#[test]
fn colmap_counts_are_checked_against_the_bytes_that_follow() {
    let seeds = Seeds::new();
    let huge = u64::MAX.to_le_bytes();
    rejected(Family::ColmapBin, &colmap(0, &huge), &seeds, "claims 18446744073709551615 entries");
    rejected(Family::ColmapBin, &colmap(2, &(1u64 << 40).to_le_bytes()), &seeds, "claims 1099511627776 entries");
    // an image whose 2D-point count times 24 bytes overflows
    let mut image = 1u64.to_le_bytes().to_vec();
    image.extend_from_slice(&1i32.to_le_bytes());
    for v in [1.0f64, 0.0, 0.0, 0.0, 0.0, 0.0, 4.0] {
        image.extend_from_slice(&v.to_le_bytes());
    }
    image.extend_from_slice(&1i32.to_le_bytes());
    image.extend_from_slice(b"a.png\0");
    image.extend_from_slice(&(1u64 << 62).to_le_bytes());
    rejected(Family::ColmapBin, &colmap(1, &image), &seeds, "claims 4611686018427387904 entries");
}

#[test]
fn colmap_cameras_and_poses_are_validated() {
    let seeds = Seeds::new();
    let cam = |line: &str| colmap(0, line.as_bytes());
    rejected(Family::ColmapText, &cam("1 PINHOLE 64 48 60 60 nan 24\n"), &seeds, "invalid intrinsics");
    rejected(Family::ColmapText, &cam("1 PINHOLE 64 48 inf 60 32 24\n"), &seeds, "invalid intrinsics");
    rejected(Family::ColmapText, &cam("1 PINHOLE 4294967297 48 60 60 32 24\n"), &seeds, "outside 1..=32768");
    rejected(
        Family::ColmapText,
        &cam("1 PINHOLE 64 48 60 60 32 24\n1 PINHOLE 64 48 60 60 32 24\n"),
        &seeds,
        "appears twice",
    );
    let images = |q: &str| colmap(1, format!("1 {q} 0 0 4 1 a.png\n\n").as_bytes());
    rejected(Family::ColmapText, &images("0 0 0 0"), &seeds, "NaN or infinite");
    rejected(
        Family::ColmapText,
        &images("1 0 0 0").iter().chain(b"2 1 0 0 0 0 0 4 1 a.png\n\n").copied().collect::<Vec<_>>(),
        &seeds,
        "appears twice",
    );
    rejected(Family::ColmapText, &colmap(2, b"1 0 inf 0 1 2 3\n"), &seeds, "unparsable point");
}

#[test]
fn cameras_json_rejects_what_the_renderer_cannot_use() {
    let seeds = Seeds::new();
    let camera = |size: &str, rotation: &str, fx: &str| {
        format!(
            r#"[{{"id": 0, "img_name": "v", {size}, "position": [0, 0, -4], "rotation": {rotation}, "fx": {fx}, "fy": 50}}]"#
        )
        .into_bytes()
    };
    let identity = "[[1, 0, 0], [0, 1, 0], [0, 0, 1]]";
    assert_eq!(check(Family::CamerasJson, &camera(r#""width": 64, "height": 48"#, identity, "50"), &seeds), None);
    rejected(Family::CamerasJson, &camera(r#""width": 0, "height": 48"#, identity, "50"), &seeds, "outside 1..=32768");
    rejected(
        Family::CamerasJson,
        &camera(r#""width": 64, "height": 40000"#, identity, "50"),
        &seeds,
        "outside 1..=32768",
    );
    rejected(Family::CamerasJson, &camera(r#""width": 64, "height": 48"#, identity, "-5"), &seeds, "focal lengths");
    let scaled = "[[2, 0, 0], [0, 2, 0], [0, 0, 2]]";
    rejected(Family::CamerasJson, &camera(r#""width": 64, "height": 48"#, scaled, "50"), &seeds, "not a rotation");
    let mirrored = "[[-1, 0, 0], [0, 1, 0], [0, 0, 1]]";
    rejected(Family::CamerasJson, &camera(r#""width": 64, "height": 48"#, mirrored, "50"), &seeds, "not a rotation");
}

#[test]
fn a_mask_claiming_a_huge_size_is_refused_before_decoding() {
    let seeds = Seeds::new();
    let mut png = seeds.of(Family::MaskImage)[0].bytes.clone();
    png[16..20].copy_from_slice(&100_000u32.to_be_bytes()); // IHDR width
    let crc = {
        let mut c = !0u32;
        for &b in &png[12..29] {
            c ^= b as u32;
            for _ in 0..8 {
                c = if c & 1 != 0 { (c >> 1) ^ 0xedb8_8320 } else { c >> 1 };
            }
        }
        !c
    };
    png[29..33].copy_from_slice(&crc.to_be_bytes());
    rejected(Family::MaskImage, &png, &seeds, "mask.png: cannot decode image");
}

#[test]
fn flag_values_say_what_is_wrong() {
    let seeds = Seeds::new();
    let labels = |s: &str| std::iter::once(1u8).chain(s.bytes()).collect::<Vec<_>>();
    let rgb = |s: &str| std::iter::once(0u8).chain(s.bytes()).collect::<Vec<_>>();
    rejected(Family::FlagValues, &labels("1,300"), &seeds, "label 300 is out of range");
    rejected(Family::FlagValues, &labels("0"), &seeds, "background");
    rejected(Family::FlagValues, &labels("255"), &seeds, "out of range");
    rejected(Family::FlagValues, &labels("1,,2"), &seeds, "expected an object label");
    rejected(Family::FlagValues, &rgb("nan,0,0"), &seeds, "in [0, 1]");
    rejected(Family::FlagValues, &rgb("0.5,0.5"), &seeds, "three values");
    let weight = |s: &str| std::iter::once(2u8).chain(s.bytes()).collect::<Vec<_>>();
    rejected(Family::FlagValues, &weight("-1"), &seeds, "finite number >= 0, got \"-1\"");
    rejected(Family::FlagValues, &weight("inf"), &seeds, "finite number >= 0");
    rejected(Family::FlagValues, &weight("four"), &seeds, "expected a number >= 0, got \"four\"");
    assert_eq!(check(Family::FlagValues, &labels("1, 2,254"), &seeds), None);
    assert_eq!(check(Family::FlagValues, &weight("0"), &seeds), None);
    assert_eq!(check(Family::FlagValues, &weight(" 4.5"), &seeds), None);
}

#[test]
fn prompt_embeddings_must_be_finite_and_of_one_length() {
    let seeds = Seeds::new();
    rejected(Family::PromptJson, br#"{"statue": [1, 2], "bench": [1]}"#, &seeds, "different or zero length");
    // past f32's range: the JSON reader refuses it (exact float reading, `float_roundtrip`)
    rejected(Family::PromptJson, br#"{"statue": [1e300, 2], "bench": [1, 2]}"#, &seeds, "number out of range");
    rejected(Family::PromptJson, br#"{"statue": [1, 2]}"#, &seeds, "no embedding for prompt \"bench\"");
}

#[test]
fn a_real_mask_at_the_deflate_limit_still_decodes() {
    // an all-background 4000x3000 mask compresses about 1000:1, close to what deflate allows; the
    // decoder's allocation limit (2048 bytes per file byte + 16 MiB) must still let it through
    let (w, h) = (4000u32, 3000u32);
    use image::codecs::png::{CompressionType, FilterType, PngEncoder};
    use image::ImageEncoder;
    let mut png = std::io::Cursor::new(Vec::new());
    PngEncoder::new_with_quality(&mut png, CompressionType::Best, FilterType::NoFilter)
        .write_image(&vec![0u8; (w * h) as usize], w, h, image::ExtendedColorType::L8)
        .unwrap();
    let png = png.into_inner();
    assert!(png.len() * 500 < (w * h) as usize, "{} bytes: not compressed enough to test the limit", png.len());
    let map = cogeo::tag::labels::decode_mask(&png, "black.png", w, h).unwrap();
    assert_eq!(map.len(), (w * h) as usize);
    assert!(map.iter().all(|&v| v == 0));
}
