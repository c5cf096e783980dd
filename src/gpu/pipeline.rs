//! Compute pipelines: one SPIR-V module, push constants only (all buffers are device addresses).

use super::{Gpu, GpuShared};
use anyhow::{Context, Result};
use ash::vk;
use std::sync::Arc;

/// Push-constant space every pipeline reserves (the Vulkan guaranteed minimum).
pub const PUSH_CONSTANT_BYTES: u32 = 128;

pub struct ComputePipeline {
    gpu: Arc<GpuShared>,
    pub(crate) pipeline: vk::Pipeline,
    pub(crate) layout: vk::PipelineLayout,
    pub name: &'static str,
}

impl ComputePipeline {
    /// Builds a pipeline from an embedded SPIR-V blob (see build.rs).
    pub fn new(gpu: &Gpu, name: &'static str, spirv: &[u8]) -> Result<ComputePipeline> {
        Self::specialized(gpu, name, spirv, &[])
    }

    /// As `new`, with the shader's specialization constants 0, 1, ... set to `constants` (u32 each),
    /// e.g. a work shape chosen per device.
    pub fn specialized(gpu: &Gpu, name: &'static str, spirv: &[u8], constants: &[u32]) -> Result<ComputePipeline> {
        let device = &gpu.shared.device;
        let words = ash::util::read_spv(&mut std::io::Cursor::new(spirv))
            .with_context(|| format!("shader {name}: invalid SPIR-V"))?;
        let module = unsafe { device.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&words), None)? };
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::COMPUTE)
            .offset(0)
            .size(PUSH_CONSTANT_BYTES)];
        let layout = unsafe {
            device
                .create_pipeline_layout(&vk::PipelineLayoutCreateInfo::default().push_constant_ranges(&ranges), None)?
        };
        let entries: Vec<vk::SpecializationMapEntry> = (0..constants.len() as u32)
            .map(|i| vk::SpecializationMapEntry::default().constant_id(i).offset(4 * i).size(4))
            .collect();
        let data: &[u8] = bytemuck::cast_slice(constants);
        let specialization = vk::SpecializationInfo::default().map_entries(&entries).data(data);
        let mut stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module)
            .name(c"main");
        if !constants.is_empty() {
            stage = stage.specialization_info(&specialization);
        }
        let info = [vk::ComputePipelineCreateInfo::default().stage(stage).layout(layout)];
        let result = unsafe { device.create_compute_pipelines(vk::PipelineCache::null(), &info, None) };
        unsafe { device.destroy_shader_module(module, None) };
        let pipeline =
            result.map_err(|(_, e)| e).with_context(|| format!("shader {name}: pipeline creation failed"))?[0];
        Ok(ComputePipeline { gpu: gpu.shared.clone(), pipeline, layout, name })
    }
}

impl Drop for ComputePipeline {
    fn drop(&mut self) {
        unsafe {
            self.gpu.device.destroy_pipeline(self.pipeline, None);
            self.gpu.device.destroy_pipeline_layout(self.layout, None);
        }
    }
}
