//! cogeo: a Vulkan-native 3D Gaussian Splatting engine (render, train, tag, remove objects).
//!
//! Modules map onto the pipeline: `gpu` (device, memory, pipelines), `render` (forward passes and
//! their CPU reference), `scene` (Gaussians, PLY, cameras), `train` (optimization), `tag` (object labels per Gaussian),
//! `demo` (the built-in default scene).

pub mod demo;
pub mod gpu;
pub mod io;
pub mod render;
pub mod scene;
pub mod synth;
pub mod tag;
pub mod train;

/// SPIR-V of every `shaders/glsl/*.comp`, compiled by build.rs.
pub mod shaders {
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
}
