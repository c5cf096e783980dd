//! cogeo: a Vulkan-native 3D Gaussian Splatting engine (render, train, tag, remove objects).
//!
//! Modules map onto the pipeline: `gpu` (device, memory, pipelines), `sort` (GPU radix sort and
//! prefix scan), `render` (forward passes and their CPU reference), `scene` (Gaussians, PLY,
//! cameras, COLMAP, datasets), `train` (optimization), `tag` (object labels per Gaussian, the
//! paper's first stage), then `removal` (the later stages in order: selection and hole masks,
//! completion, fusion and pruning, refinement), `pipeline` (the train -> tag -> remove -> eval
//! command lines), `eval` (metrics), `synth` (datasets with exact ground truth). Helpers:
//! `config` (every config struct's defaults come from its flags), `planes` (the plane model of
//! inverse depth), `image_ops` (resizing, masks), `io` (image files), `flag_values` (flag
//! parsers), `onnx` (user-supplied models), `parallel` (independent CPU work over the cores), `rng`
//! (seeded random numbers). The command line lives
//! in the binary (src/cli).

// Per-channel and per-row index loops read as the formulas they implement (c[ch] += w * color[ch]).
#![allow(clippy::needless_range_loop)]

pub mod config;
pub mod eval;
pub mod flag_values;
pub mod gpu;
pub mod image_ops;
pub mod io;
pub mod onnx;
pub mod parallel;
pub mod planes;
pub mod pipeline;
pub mod removal;
pub mod render;
pub mod rng;
pub mod scene;
pub mod sort;
pub mod synth;
pub mod tag;
pub mod train;

/// SPIR-V of every `shaders/glsl/*/*.comp` (and the compare-and-swap variants), compiled by build.rs.
pub mod shaders {
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
}
