//! The tiled GPU rasterizer against the dense f64 CPU reference (render::reference) on seeded random
//! scenes: odd image sizes, Gaussians behind the camera, huge and tiny Gaussians, opacity near 1/255
//! and near 1, SH degrees 0..3 and 32-channel features.

mod common;

use cogeo::render::reference::{render_reference, ReferenceImage};
use cogeo::render::{BlendLayout, Rasterizer, RenderOutput, RenderSettings, SceneBuffers, SceneRenderer};
use cogeo::scene::{Camera, GaussianScene};
use common::{gpu, random_features, random_scene, test_camera, SceneMix};

const TOL: f64 = 1e-4;

struct Errors {
    color: f64,
    alpha: f64,
    depth_rel: f64,
    features: f64,
    compared: usize,
    ambiguous: usize,
    lit: usize,
}

fn compare(gpu_out: &RenderOutput, reference: &ReferenceImage) -> Errors {
    let hw = (gpu_out.width * gpu_out.height) as usize;
    let mut e = Errors { color: 0.0, alpha: 0.0, depth_rel: 0.0, features: 0.0, compared: 0, ambiguous: 0, lit: 0 };
    let d = gpu_out.feature_dim as usize;
    for i in 0..hw {
        if reference.ambiguous[i] {
            e.ambiguous += 1;
            continue;
        }
        e.compared += 1;
        if reference.alpha[i] > 0.01 {
            e.lit += 1;
        }
        for c in 0..3 {
            e.color = e.color.max((gpu_out.rgb[c * hw + i] as f64 - reference.rgb[c * hw + i]).abs());
        }
        e.alpha = e.alpha.max((gpu_out.alpha[i] as f64 - reference.alpha[i]).abs());
        if reference.alpha[i] > 0.0 {
            let r = reference.expected_depth[i];
            e.depth_rel = e.depth_rel.max((gpu_out.expected_depth[i] as f64 - r).abs() / r.abs().max(1e-6));
            let m = reference.median_depth[i];
            e.depth_rel = e.depth_rel.max((gpu_out.median_depth[i] as f64 - m).abs() / m.abs().max(1e-6));
            let acc = reference.depth[i];
            e.depth_rel = e.depth_rel.max((gpu_out.depth[i] as f64 - acc).abs() / acc.abs().max(1e-3));
        }
        for c in 0..d {
            e.features = e.features.max((gpu_out.features[c * hw + i] as f64 - reference.features[c * hw + i]).abs());
        }
    }
    e
}

fn check(scene: &GaussianScene, camera: &Camera, features: Option<(&[f32], usize)>, background: [f32; 3], label: &str) {
    let g = gpu();
    let buffers = SceneBuffers::upload(&g, scene, features).unwrap();
    let mut raster = Rasterizer::new(&g).unwrap();
    let settings = RenderSettings { background, features: features.is_some(), ..Default::default() };
    let plain = raster.render(&buffers, camera, &settings).unwrap();
    assert!(plain.median_depth.is_empty(), "{label}: a median depth nobody asked for");
    // the median depth is a variant of blend.comp of its own: everything else stays bit for bit
    let out = raster.render(&buffers, camera, &RenderSettings { median_depth: true, ..settings }).unwrap();
    assert!(out.rgb == plain.rgb && out.alpha == plain.alpha && out.expected_depth == plain.expected_depth);
    assert!(out.n_contrib == plain.n_contrib && out.final_t == plain.final_t && out.features == plain.features);
    let reference = render_reference(scene, camera, background.map(|v| v as f64), 0.01, scene.sh_degree, features);
    let e = compare(&out, &reference);
    let hw = (camera.width * camera.height) as usize;
    println!(
        "{label}: {}x{}, {} intersections, max err color {:.2e} alpha {:.2e} depth(rel) {:.2e} features {:.2e}; \
         {} ambiguous of {hw} pixels, {} lit",
        camera.width,
        camera.height,
        out.num_intersections,
        e.color,
        e.alpha,
        e.depth_rel,
        e.features,
        e.ambiguous,
        e.lit
    );
    assert!(
        e.ambiguous * 100 <= hw,
        "{label}: too many ambiguous pixels ({} of {hw}): the test would be vacuous",
        e.ambiguous
    );
    assert!(
        e.lit * 4 >= e.compared,
        "{label}: only {} of {} pixels are lit; the scene does not exercise blending",
        e.lit,
        e.compared
    );
    assert!(e.color <= TOL, "{label}: color error {:.3e}", e.color);
    assert!(e.alpha <= TOL, "{label}: alpha error {:.3e}", e.alpha);
    assert!(e.depth_rel <= TOL, "{label}: relative depth error {:.3e}", e.depth_rel);
    assert!(e.features <= TOL, "{label}: feature error {:.3e}", e.features);
}

#[test]
fn conformance_sh_degrees_and_odd_sizes() {
    let sizes = [(70, 45), (33, 17), (128, 96), (161, 80)];
    for degree in 0..=3u32 {
        let (w, h) = sizes[degree as usize];
        let scene = random_scene(100 + degree as u64, degree, SceneMix::default());
        check(&scene, &test_camera(w, h), None, [0.1, 0.2, 0.3], &format!("SH degree {degree}"));
    }
}

#[test]
fn conformance_32_channel_features() {
    let scene = random_scene(7, 1, SceneMix::default());
    let f = random_features(8, scene.len(), 32);
    check(&scene, &test_camera(75, 53), Some((&f, 32)), [0.0, 0.0, 0.0], "32 features");
}

#[test]
fn conformance_more_than_32_features_and_16() {
    let scene = random_scene(9, 0, SceneMix { normal: 120, ..Default::default() });
    let f = random_features(10, scene.len(), 40);
    check(&scene, &test_camera(48, 40), Some((&f, 40)), [1.0, 1.0, 1.0], "40 features");
    let f = random_features(11, scene.len(), 16);
    check(&scene, &test_camera(48, 40), Some((&f, 16)), [1.0, 1.0, 1.0], "16 features");
}

/// One feature per Gaussian blends inside the color pass (blend.comp's ONE_FEATURE), not in
/// blend_features: the same reference, and a 0/1 marker as the removal's hole masks use it.
#[test]
fn conformance_one_feature_blends_with_the_color() {
    let scene = random_scene(13, 1, SceneMix::default());
    let f = random_features(14, scene.len(), 1);
    check(&scene, &test_camera(75, 53), Some((&f, 1)), [0.2, 0.1, 0.0], "1 feature");
    let marker: Vec<f32> = (0..scene.len()).map(|i| (i % 3 == 0) as u8 as f32).collect();
    check(&scene, &test_camera(64, 48), Some((&marker, 1)), [0.0, 0.0, 0.0], "0/1 marker");
}

#[test]
fn conformance_dense_opaque_scene_terminates_early() {
    // many opaque Gaussians: most pixels reach T < 1e-4 and stop early
    let mix = SceneMix { normal: 0, tiny: 0, huge: 0, behind: 5, faint: 10, opaque: 600 };
    let scene = random_scene(21, 2, mix);
    check(&scene, &test_camera(96, 64), None, [0.5, 0.5, 0.5], "dense opaque");
}

#[test]
fn conformance_huge_gaussians_cover_every_tile() {
    let mix = SceneMix { normal: 20, tiny: 0, huge: 40, behind: 0, faint: 0, opaque: 0 };
    let scene = random_scene(31, 3, mix);
    check(&scene, &test_camera(100, 70), None, [0.0, 0.0, 0.0], "huge");
}

#[test]
fn everything_behind_the_camera_renders_background() {
    let mix = SceneMix { normal: 0, tiny: 0, huge: 0, behind: 50, faint: 0, opaque: 0 };
    let scene = random_scene(41, 1, mix);
    let g = gpu();
    let buffers = SceneBuffers::upload(&g, &scene, None).unwrap();
    let mut raster = Rasterizer::new(&g).unwrap();
    let bg = [0.25, 0.5, 0.75];
    let out = raster
        .render(&buffers, &test_camera(40, 30), &RenderSettings { background: bg, ..Default::default() })
        .unwrap();
    assert_eq!(out.num_intersections, 0);
    let hw = 40 * 30;
    for (c, &b) in bg.iter().enumerate() {
        assert!(out.rgb[c * hw..(c + 1) * hw].iter().all(|&v| v == b));
    }
    assert!(out.alpha.iter().all(|&a| a == 0.0));
}

#[test]
fn rendering_is_deterministic_across_calls_and_buffer_reuse() {
    let scene = random_scene(51, 2, SceneMix::default());
    let g = gpu();
    let buffers = SceneBuffers::upload(&g, &scene, None).unwrap();
    let mut raster = Rasterizer::new(&g).unwrap();
    let a = raster.render(&buffers, &test_camera(64, 64), &RenderSettings::default()).unwrap();
    // a different size in between forces reallocation of the image buffers
    raster.render(&buffers, &test_camera(200, 150), &RenderSettings::default()).unwrap();
    let b = raster.render(&buffers, &test_camera(64, 64), &RenderSettings::default()).unwrap();
    assert_eq!(a.rgb, b.rgb);
    assert_eq!(a.n_contrib, b.n_contrib);
}

#[test]
fn every_blend_layout_renders_the_same_bits() {
    // blend.comp and blend_features.comp give each invocation a column of 1..16 pixels (render::BlendLayout::for_device picks per
    // device); every pixel makes the same decisions in any layout, so every output is bit-identical
    // to the device's own layout, which the tests above check against the f64 reference. Odd sizes
    // leave partial tiles and columns; the dense opaque mix stops pixels early at different points.
    let g = gpu();
    let mixes = [SceneMix::default(), SceneMix { normal: 0, tiny: 0, huge: 0, behind: 5, faint: 10, opaque: 600 }];
    for (k, mix) in mixes.into_iter().enumerate() {
        let scene = random_scene(61 + k as u64, 2, mix);
        // 40 channels: a 32-channel pass (rows capped by its accumulators) and an 8-channel one
        let features = random_features(71 + k as u64, scene.len(), 40);
        let buffers = SceneBuffers::upload(&g, &scene, Some((&features, 40))).unwrap();
        let cam = test_camera(83, 37);
        let settings =
            RenderSettings { background: [0.2, 0.3, 0.4], features: true, median_depth: true, ..Default::default() };
        let reference = Rasterizer::new(&g).unwrap().render(&buffers, &cam, &settings).unwrap();
        assert!(reference.alpha.iter().any(|&a| a > 0.5), "scene {k} renders nothing");
        for rows in [1, 2, 4, 8, 16] {
            let layout = BlendLayout { forward_rows: rows, ..BlendLayout::PIXEL };
            let out = Rasterizer::with_layout(&g, layout).unwrap().render(&buffers, &cam, &settings).unwrap();
            assert_eq!(out.rgb, reference.rgb, "scene {k}, {rows} rows: color");
            assert_eq!(out.alpha, reference.alpha, "scene {k}, {rows} rows: alpha");
            assert_eq!(out.expected_depth, reference.expected_depth, "scene {k}, {rows} rows: depth");
            assert_eq!(out.median_depth, reference.median_depth, "scene {k}, {rows} rows: median depth");
            assert_eq!(out.n_contrib, reference.n_contrib, "scene {k}, {rows} rows: contributors");
            assert_eq!(out.features, reference.features, "scene {k}, {rows} rows: features");
        }
    }
}

#[test]
fn a_scene_renders_the_bands_it_learnt_with_the_same_bits() {
    // SceneRenderer renders at most `learnt_sh_degree`: a degree-3 scene whose bands above the
    // first are zero (a training under 2000 iterations) must give the same bits as the full
    // degree-3 evaluation, which the tests above check against the f64 reference
    let g = gpu();
    let mut scene = random_scene(91, 3, SceneMix::default());
    let k = scene.sh_coeffs();
    for g3 in scene.sh.chunks_exact_mut(3 * k) {
        g3[3 * 4..].iter_mut().for_each(|c| *c = 0.0); // bands 2 and 3
    }
    assert_eq!(scene.learnt_sh_degree(), 1);
    let cam = test_camera(83, 37);
    let settings = RenderSettings { background: [0.2, 0.3, 0.4], ..Default::default() };
    let buffers = SceneBuffers::upload(&g, &scene, None).unwrap();
    let full = Rasterizer::new(&g).unwrap().render(&buffers, &cam, &settings).unwrap();
    let learnt = SceneRenderer::new(&g, &scene, None).unwrap().render(&cam, &settings).unwrap();
    assert!(full.alpha.iter().any(|&a| a > 0.5), "the scene renders nothing");
    assert_eq!(learnt.rgb, full.rgb);
    assert_eq!(learnt.alpha, full.alpha);
    assert_eq!(learnt.expected_depth, full.expected_depth);
    // and a band that is not zero is rendered: degree 1 differs from the DC band alone
    let dc = RenderSettings { sh_degree: Some(0), ..settings.clone() };
    assert_ne!(Rasterizer::new(&g).unwrap().render(&buffers, &cam, &dc).unwrap().rgb, full.rgb);
}

#[test]
fn only_the_marked_tiles_are_blended_with_the_whole_renders_bits() {
    // RenderSettings::only_tiles: a marked tile's pixels are the whole render's, bit for bit, in
    // blend.comp's variants (one feature with the median depth) and in blend_features.comp (40
    // channels); an unmarked tile is left empty (the background, alpha 0, no feature)
    let g = gpu();
    let scene = random_scene(131, 2, SceneMix::default());
    let cam = test_camera(83, 37); // 6 x 3 tiles, the last column and row partial
    let (tiles_x, tiles_y) = (83usize.div_ceil(16), 37usize.div_ceil(16));
    let marked: Vec<bool> = (0..tiles_x * tiles_y).map(|t| (t * 7) % 3 != 0).collect();
    let tile_of = |p: usize| (p / 83 / 16) * tiles_x + (p % 83) / 16;
    let background = [0.2, 0.3, 0.4];
    for channels in [1usize, 40] {
        let features = random_features(137, scene.len(), channels);
        let buffers = SceneBuffers::upload(&g, &scene, Some((&features, channels))).unwrap();
        let mut raster = Rasterizer::new(&g).unwrap();
        let settings = RenderSettings { background, features: true, median_depth: true, ..Default::default() };
        let whole = raster.render(&buffers, &cam, &settings).unwrap();
        let only = RenderSettings { only_tiles: Some(marked.clone()), ..settings.clone() };
        let part = raster.render(&buffers, &cam, &only).unwrap();
        let hw = 83 * 37;
        let lit = (0..hw).filter(|&p| !marked[tile_of(p)] && whole.alpha[p] > 0.1).count();
        assert!(lit > 100, "{channels} channels: the unmarked tiles show too little ({lit} pixels)");
        for p in 0..hw {
            let planes = |o: &RenderOutput| {
                let mut v = vec![o.alpha[p], o.expected_depth[p], o.median_depth[p], o.final_t[p]];
                v.extend((0..3).map(|c| o.rgb[c * hw + p]));
                v.extend((0..channels).map(|c| o.features[c * hw + p]));
                v
            };
            if marked[tile_of(p)] {
                assert_eq!(planes(&part), planes(&whole), "{channels} channels, pixel {p}");
            } else {
                let rgb: Vec<f32> = (0..3).map(|c| part.rgb[c * hw + p]).collect();
                assert_eq!((part.alpha[p], rgb), (0.0, background.to_vec()), "{channels} channels, pixel {p}");
                assert!((0..channels).all(|c| part.features[c * hw + p] == 0.0), "{channels} channels, pixel {p}");
            }
        }
        // the next render without a mask blends every tile again
        assert_eq!(raster.render(&buffers, &cam, &settings).unwrap().rgb, whole.rgb);
    }
    // a mask for another image size is refused
    let buffers = SceneBuffers::upload(&g, &scene, None).unwrap();
    let wrong = RenderSettings { only_tiles: Some(vec![true; 4]), ..Default::default() };
    let err = Rasterizer::new(&g).unwrap().render(&buffers, &cam, &wrong).unwrap_err();
    assert!(err.to_string().contains("18"), "{err}");
}

/// Fails on the first element where two planes differ in their bits, saying where and how many do.
fn same_bits<T: Copy + PartialEq + std::fmt::Debug>(got: &[T], want: &[T], what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: plane sizes");
    let differ: Vec<usize> = (0..got.len()).filter(|&i| got[i] != want[i]).collect();
    if let Some(&i) = differ.first() {
        panic!("{what}: {} elements differ, the first at {i}: {:?} against {:?}", differ.len(), got[i], want[i]);
    }
}

#[test]
fn the_render_after_removal_is_that_scenes_own_render_bit_for_bit() {
    // RenderSettings::after_removal: one walk over the original's tile lists blends the scene less
    // the removed Gaussians (feature 1) beside it, the kept objects' weight (feature 2) as its
    // feature; each state must be, bit for bit, the render of its own scene with its own 0/1
    // marker (the hull's redraws read both), in every blend layout, whole or in marked tiles, read
    // back directly or through a staging buffer
    let g = gpu();
    let mixes = [SceneMix::default(), SceneMix { normal: 60, tiny: 0, huge: 2, behind: 5, faint: 10, opaque: 500 }];
    let cam = test_camera(83, 37);
    let hw = 83 * 37;
    let (tiles_x, tiles_y) = (83usize.div_ceil(16), 37usize.div_ceil(16));
    let marked: Vec<bool> = (0..tiles_x * tiles_y).map(|t| (t * 5) % 3 != 1).collect();
    for (k, mix) in mixes.into_iter().enumerate() {
        let scene = random_scene(151 + k as u64, 2, mix);
        let removed: Vec<bool> = (0..scene.len()).map(|i| (i * 7 + k) % 3 == 0).collect();
        let kept_object: Vec<bool> = (0..scene.len()).map(|i| !removed[i] && i % 5 == 1).collect();
        let code: Vec<f32> =
            (0..scene.len()).map(|i| if removed[i] { 1.0 } else { 2.0 * kept_object[i] as u8 as f32 }).collect();
        let removed_marker: Vec<f32> = removed.iter().map(|&r| r as u8 as f32).collect();
        let keep: Vec<bool> = removed.iter().map(|&r| !r).collect();
        let after_scene = scene.subset(&keep);
        let kept_marker: Vec<f32> =
            (0..scene.len()).filter(|&i| keep[i]).map(|i| kept_object[i] as u8 as f32).collect();
        let both = SceneBuffers::upload(&g, &scene, Some((&code, 1))).unwrap();
        let original = SceneBuffers::upload(&g, &scene, Some((&removed_marker, 1))).unwrap();
        let after = SceneBuffers::upload(&g, &after_scene, Some((&kept_marker, 1))).unwrap();
        for only_tiles in [None, Some(marked.clone())] {
            let settings = RenderSettings {
                background: [0.2, 0.3, 0.4],
                features: true,
                median_depth: true,
                only_tiles,
                ..Default::default()
            };
            let mut raster = Rasterizer::new(&g).unwrap();
            let want_before = raster.render(&original, &cam, &settings).unwrap();
            let want_after = raster.render(&after, &cam, &settings).unwrap();
            // the two scenes differ: the test can tell the states apart
            let differ = (0..hw).filter(|&p| want_before.alpha[p] != want_after.alpha[p]).count();
            assert!(differ > 200, "mix {k}: the removal changes only {differ} pixels");
            assert!(want_before.features.iter().any(|&f| f > 0.5) && want_after.features.iter().any(|&f| f > 0.5));
            let dual = RenderSettings { after_removal: true, ..settings.clone() };
            // the last through a staging buffer, as a discrete GPU reads the planes back
            for (rows, staged) in [(1, false), (4, false), (16, false), (16, true)] {
                let layout = BlendLayout { forward_rows: rows, ..BlendLayout::PIXEL };
                let mut raster = Rasterizer::with_layout(&g, layout).unwrap();
                raster.stage_readbacks(staged);
                let out = raster.render(&both, &cam, &dual).unwrap();
                let at = format!("mix {k}, {rows} rows, staged {staged}, tiles {}", settings.only_tiles.is_some());
                same_bits(&out.rgb, &want_before.rgb, &format!("{at}: color"));
                same_bits(&out.alpha, &want_before.alpha, &format!("{at}: alpha"));
                same_bits(&out.expected_depth, &want_before.expected_depth, &format!("{at}: depth"));
                same_bits(&out.median_depth, &want_before.median_depth, &format!("{at}: median depth"));
                same_bits(&out.n_contrib, &want_before.n_contrib, &format!("{at}: contributors"));
                same_bits(&out.features, &want_before.features, &format!("{at}: removed weight"));
                let a = out.after_removal.expect("rendered after removal");
                same_bits(&a.rgb, &want_after.rgb, &format!("{at}: color after removal"));
                same_bits(&a.alpha, &want_after.alpha, &format!("{at}: alpha after removal"));
                same_bits(&a.expected_depth, &want_after.expected_depth, &format!("{at}: depth after removal"));
                same_bits(&a.median_depth, &want_after.median_depth, &format!("{at}: median depth after removal"));
                same_bits(&a.kept_weight, &want_after.features, &format!("{at}: kept objects' weight"));
            }
        }
    }
    // the states need the one feature that marks the removal
    let scene = random_scene(157, 0, SceneMix::default());
    let buffers = SceneBuffers::upload(&g, &scene, None).unwrap();
    let wrong = RenderSettings { after_removal: true, ..Default::default() };
    let err = Rasterizer::new(&g).unwrap().render(&buffers, &cam, &wrong).unwrap_err();
    assert!(err.to_string().contains("after removal"), "{err}");
}
