//! Command recording: dispatches separated by compute barriers, with an optional GPU timestamp after
//! each named pass, submitted and waited on as one unit.

use super::{Buffer, ComputePipeline, Gpu};
use anyhow::{Context, Result};
use ash::vk;

/// GPU time of one recorded pass (summed when a pass name repeats), and the bytes it reads and
/// writes in device memory where its owner knows them (0: not stated), so a bench can put the
/// pass's throughput next to the device's copy bandwidth.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PassTiming {
    pub pass: String,
    pub ms: f64,
    pub bytes: u64,
}

impl PassTiming {
    /// Bytes moved per second, in GB/s (None when the bytes are not stated or no time was measured).
    pub fn gbps(&self) -> Option<f64> {
        (self.bytes > 0 && self.ms > 0.0).then(|| self.bytes as f64 / (self.ms * 1e6))
    }
}

const MAX_TIMESTAMPS: u32 = 256;

pub struct Recorder {
    gpu: Gpu,
    /// The recorder's own command pool: recording into buffers of one pool must be externally
    /// synchronized, so that threads record at once (the transfer's views) each in its own.
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
    query_pool: Option<vk::QueryPool>,
    /// Pass name and bytes moved for each timestamp after the first.
    labels: Vec<(String, u64)>,
    pending_barrier: bool,
}

impl Recorder {
    pub fn new(gpu: &Gpu) -> Result<Recorder> {
        Self::with_timestamps(gpu, false)
    }

    /// A recorder that writes a timestamp after every `mark`ed pass (when the device supports them).
    pub fn with_timestamps(gpu: &Gpu, timestamps: bool) -> Result<Recorder> {
        let s = &gpu.shared;
        let device = &s.device;
        let pool = unsafe {
            device.create_command_pool(
                &vk::CommandPoolCreateInfo::default()
                    .queue_family_index(s.queue_family)
                    .flags(vk::CommandPoolCreateFlags::TRANSIENT),
                None,
            )?
        };
        // from here on, Drop releases whatever was made if a later step fails
        let mut r = Recorder {
            gpu: gpu.clone(),
            pool,
            cmd: vk::CommandBuffer::null(),
            fence: vk::Fence::null(),
            query_pool: None,
            labels: Vec::new(),
            pending_barrier: false,
        };
        r.cmd = unsafe {
            device.allocate_command_buffers(
                &vk::CommandBufferAllocateInfo::default()
                    .command_pool(pool)
                    .level(vk::CommandBufferLevel::PRIMARY)
                    .command_buffer_count(1),
            )?[0]
        };
        r.fence = unsafe { device.create_fence(&vk::FenceCreateInfo::default(), None)? };
        unsafe {
            device.begin_command_buffer(
                r.cmd,
                &vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
            )?
        };
        if timestamps && s.info.timestamps {
            let pool = unsafe {
                device.create_query_pool(
                    &vk::QueryPoolCreateInfo::default()
                        .query_type(vk::QueryType::TIMESTAMP)
                        .query_count(MAX_TIMESTAMPS),
                    None,
                )?
            };
            r.query_pool = Some(pool);
            unsafe {
                device.cmd_reset_query_pool(r.cmd, pool, 0, MAX_TIMESTAMPS);
                device.cmd_write_timestamp(r.cmd, vk::PipelineStageFlags::TOP_OF_PIPE, pool, 0);
            }
        }
        Ok(r)
    }

    fn device(&self) -> &ash::Device {
        &self.gpu.shared.device
    }

    /// Makes every earlier write (shader or transfer) visible to every later read or write.
    fn barrier_if_needed(&mut self) {
        if !self.pending_barrier {
            return;
        }
        let barrier = [vk::MemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::TRANSFER_WRITE)
            .dst_access_mask(
                vk::AccessFlags::SHADER_READ
                    | vk::AccessFlags::SHADER_WRITE
                    | vk::AccessFlags::TRANSFER_READ
                    | vk::AccessFlags::TRANSFER_WRITE,
            )];
        let stages = vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER;
        unsafe {
            self.device().cmd_pipeline_barrier(
                self.cmd,
                stages,
                stages,
                vk::DependencyFlags::empty(),
                &barrier,
                &[],
                &[],
            )
        };
        self.pending_barrier = false;
    }

    /// Records a dispatch of `groups` workgroups; push constants are the bytes of `push`.
    pub fn dispatch<P: bytemuck::Pod>(&mut self, pipeline: &ComputePipeline, push: &P, groups: [u32; 3]) {
        self.barrier_if_needed();
        let bytes = bytemuck::bytes_of(push);
        assert!(bytes.len() as u32 <= super::pipeline::PUSH_CONSTANT_BYTES, "push constants too large");
        unsafe {
            let d = self.device();
            d.cmd_bind_pipeline(self.cmd, vk::PipelineBindPoint::COMPUTE, pipeline.pipeline);
            d.cmd_push_constants(self.cmd, pipeline.layout, vk::ShaderStageFlags::COMPUTE, 0, bytes);
            d.cmd_dispatch(self.cmd, groups[0], groups[1], groups[2]);
        }
        self.pending_barrier = true;
    }

    /// Fills `bytes` bytes from `offset` with the 32-bit `value`.
    pub fn fill(&mut self, buffer: &Buffer, offset: u64, bytes: u64, value: u32) {
        self.barrier_if_needed();
        unsafe { self.device().cmd_fill_buffer(self.cmd, buffer.buffer, offset, bytes.next_multiple_of(4), value) };
        self.pending_barrier = true;
    }

    pub fn copy(&mut self, src: &Buffer, dst: &Buffer, bytes: u64) {
        self.copy_region(src, 0, dst, 0, bytes);
    }

    pub fn copy_region(&mut self, src: &Buffer, src_offset: u64, dst: &Buffer, dst_offset: u64, bytes: u64) {
        self.barrier_if_needed();
        let region = [vk::BufferCopy::default().src_offset(src_offset).dst_offset(dst_offset).size(bytes)];
        unsafe { self.device().cmd_copy_buffer(self.cmd, src.buffer, dst.buffer, &region) };
        self.pending_barrier = true;
    }

    /// Ends the pass named `label`: its time is everything recorded since the previous mark.
    pub fn mark(&mut self, label: &str) {
        self.mark_moved(label, 0);
    }

    /// As `mark`, for a pass that reads and writes `bytes` of device memory in all.
    pub fn mark_moved(&mut self, label: &str, bytes: u64) {
        let Some(pool) = self.query_pool else { return };
        let index = self.labels.len() as u32 + 1;
        if index >= MAX_TIMESTAMPS {
            return;
        }
        unsafe { self.device().cmd_write_timestamp(self.cmd, vk::PipelineStageFlags::BOTTOM_OF_PIPE, pool, index) };
        self.labels.push((label.to_string(), bytes));
    }

    /// Submits, waits, and returns the time of each marked pass (same names summed, in first-seen order).
    pub fn submit_and_wait(self) -> Result<Vec<PassTiming>> {
        let s = self.gpu.shared.clone();
        let device = &s.device;
        unsafe {
            device.end_command_buffer(self.cmd)?;
            let cmds = [self.cmd];
            let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
            {
                let _guard = s.submit_lock.lock().unwrap();
                device.queue_submit(s.queue, &submit, self.fence).context("vkQueueSubmit failed")?;
            }
            s.round_trips.submits.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            device
                .wait_for_fences(&[self.fence], true, u64::MAX)
                .context("GPU work failed (device lost or timeout)")?;
        }
        let mut timings: Vec<PassTiming> = Vec::new();
        if let Some(pool) = self.query_pool {
            let n = self.labels.len() + 1;
            let mut stamps = vec![0u64; n];
            unsafe {
                device.get_query_pool_results(
                    pool,
                    0,
                    &mut stamps,
                    vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
                )?
            };
            let period = s.info.timestamp_period_ns as f64;
            for (i, (label, bytes)) in self.labels.iter().enumerate() {
                let ms = stamps[i + 1].saturating_sub(stamps[i]) as f64 * period * 1e-6;
                match timings.iter_mut().find(|t| &t.pass == label) {
                    Some(t) => {
                        t.ms += ms;
                        t.bytes += bytes;
                    }
                    None => timings.push(PassTiming { pass: label.clone(), ms, bytes: *bytes }),
                }
            }
        }
        Ok(timings)
    }
}

impl Drop for Recorder {
    fn drop(&mut self) {
        let s = &self.gpu.shared;
        unsafe {
            // If the work was submitted it has completed (submit_and_wait waits); if it failed to submit,
            // make sure nothing is still pending before freeing.
            if self.fence != vk::Fence::null() {
                let _ = s.device.wait_for_fences(&[self.fence], true, 0);
                s.device.destroy_fence(self.fence, None);
            }
            if let Some(pool) = self.query_pool {
                s.device.destroy_query_pool(pool, None);
            }
            s.device.destroy_command_pool(self.pool, None); // frees its command buffer
        }
    }
}
