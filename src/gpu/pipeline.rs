//! Compute pipelines: one SPIR-V module, push constants only (all buffers are device addresses).
//!
//! A context builds each pipeline (a shader and its specialization constants) once and keeps it
//! until the device goes (`PipelineCache`): every `SceneRenderer` and `Rasterizer` made anew asks
//! for the same few, and lavapipe compiles a pipeline to machine code when it is made, 30 ms for
//! the blend. `cogeo remove` on the statue `images_2` made 356 pipelines, 42 of them the blend,
//! 1.96 s of compiling, where it compiles 29 now.

use super::{Gpu, GpuShared};
use anyhow::{Context, Result};
use ash::vk;
use std::collections::HashMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

/// Push-constant space every pipeline reserves (the Vulkan guaranteed minimum).
pub const PUSH_CONSTANT_BYTES: u32 = 128;

/// A pipeline the context's `PipelineCache` owns: it lives as long as the device.
pub struct ComputePipeline {
    /// Keeps the device (and the cache that owns the pipeline) alive while this is in use.
    _gpu: Arc<GpuShared>,
    pub(crate) pipeline: vk::Pipeline,
    pub(crate) layout: vk::PipelineLayout,
    pub name: &'static str,
}

/// The pipelines one context has built, by their SPIR-V and specialization constants, the whole
/// code a pipeline is made of: the same key is the same pipeline. Destroyed with the device.
#[derive(Default)]
pub(crate) struct PipelineCache {
    built: Mutex<HashMap<(Vec<u8>, Vec<u32>), (vk::Pipeline, vk::PipelineLayout)>>,
    /// Pipelines compiled so far (`Gpu::pipelines_built`).
    compiled: AtomicUsize,
}

impl PipelineCache {
    pub(crate) fn compiled(&self) -> usize {
        self.compiled.load(Ordering::Relaxed)
    }

    /// Destroys every pipeline built; the device must be idle and no `ComputePipeline` left.
    pub(crate) unsafe fn destroy(&mut self, device: &ash::Device) {
        for (_, (pipeline, layout)) in self.built.get_mut().unwrap().drain() {
            device.destroy_pipeline(pipeline, None);
            device.destroy_pipeline_layout(layout, None);
        }
    }
}

impl ComputePipeline {
    /// Builds a pipeline from an embedded SPIR-V blob (see build.rs).
    pub fn new(gpu: &Gpu, name: &'static str, spirv: &[u8]) -> Result<ComputePipeline> {
        Self::specialized(gpu, name, spirv, &[])
    }

    /// As `new`, with the shader's specialization constants 0, 1, ... set to `constants` (u32 each),
    /// e.g. a work shape chosen per device.
    pub fn specialized(gpu: &Gpu, name: &'static str, spirv: &[u8], constants: &[u32]) -> Result<ComputePipeline> {
        // held while building: two threads asking for one pipeline build it once
        let mut built = gpu.shared.pipelines.built.lock().unwrap();
        let key = (spirv.to_vec(), constants.to_vec());
        let (pipeline, layout) = match built.get(&key) {
            Some(&made) => made,
            None => {
                let made = build(gpu, name, spirv, constants)?;
                gpu.shared.pipelines.compiled.fetch_add(1, Ordering::Relaxed);
                built.insert(key, made);
                made
            }
        };
        Ok(ComputePipeline { _gpu: gpu.shared.clone(), pipeline, layout, name })
    }
}

/// Compiles the pipeline of `spirv` (shader `name`) with specialization constants `constants`.
fn build(gpu: &Gpu, name: &str, spirv: &[u8], constants: &[u32]) -> Result<(vk::Pipeline, vk::PipelineLayout)> {
    let device = &gpu.shared.device;
    let words = ash::util::read_spv(&mut std::io::Cursor::new(spirv))
        .with_context(|| format!("shader {name}: invalid SPIR-V"))?;
    let module = unsafe { device.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&words), None)? };
    let ranges = [vk::PushConstantRange::default()
        .stage_flags(vk::ShaderStageFlags::COMPUTE)
        .offset(0)
        .size(PUSH_CONSTANT_BYTES)];
    let layout = unsafe {
        device.create_pipeline_layout(&vk::PipelineLayoutCreateInfo::default().push_constant_ranges(&ranges), None)?
    };
    let entries: Vec<vk::SpecializationMapEntry> = (0..constants.len() as u32)
        .map(|i| vk::SpecializationMapEntry::default().constant_id(i).offset(4 * i).size(4))
        .collect();
    let data: &[u8] = bytemuck::cast_slice(constants);
    let specialization = vk::SpecializationInfo::default().map_entries(&entries).data(data);
    let mut stage =
        vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::COMPUTE).module(module).name(c"main");
    if !constants.is_empty() {
        stage = stage.specialization_info(&specialization);
    }
    let info = [vk::ComputePipelineCreateInfo::default().stage(stage).layout(layout)];
    let result = unsafe { device.create_compute_pipelines(vk::PipelineCache::null(), &info, None) };
    unsafe { device.destroy_shader_module(module, None) };
    let pipeline = match result {
        Ok(pipelines) => pipelines[0],
        Err((_, e)) => {
            unsafe { device.destroy_pipeline_layout(layout, None) };
            return Err(e).with_context(|| format!("shader {name}: pipeline creation failed"));
        }
    };
    Ok((pipeline, layout))
}
