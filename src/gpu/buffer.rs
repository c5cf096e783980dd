//! Storage buffers with device addresses, allocated through gpu-allocator.

use super::{Gpu, GpuShared};
use anyhow::{anyhow, Result};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;
use std::sync::atomic::Ordering;
use std::sync::Arc;

/// Where a buffer lives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MemoryKind {
    /// Device-local working memory (mapped as well where the device shares memory with the host).
    Device,
    /// Host-visible memory written by the CPU every frame (parameter blocks, staging uploads).
    Upload,
    /// Host-visible memory the GPU writes and the CPU reads back.
    Readback,
}

/// A storage buffer owned by its GPU context; freed on drop.
pub struct Buffer {
    gpu: Arc<GpuShared>,
    pub(crate) buffer: vk::Buffer,
    allocation: Option<Allocation>,
    size: u64,
    address: u64,
}

impl Buffer {
    /// Allocates `size` bytes (at least 4). Out-of-memory errors name the request and the device memory.
    pub fn new(gpu: &Gpu, name: &str, size: u64, kind: MemoryKind) -> Result<Buffer> {
        let shared = &gpu.shared;
        let size = size.max(4).next_multiple_of(4);
        let info = &shared.info;
        if size > info.max_memory_allocation {
            return Err(anyhow!(
                "buffer {name:?} needs {} MiB but {} allows at most {} MiB per allocation",
                size >> 20,
                info.name,
                info.max_memory_allocation >> 20
            ));
        }
        // the device's (or the user's) memory budget, checked before asking the driver, which on
        // lavapipe would take host memory until the machine swaps
        let in_use = shared.memory_in_use.fetch_add(size, Ordering::Relaxed);
        if in_use + size > shared.memory_limit {
            shared.memory_in_use.fetch_sub(size, Ordering::Relaxed);
            let limit = if shared.memory_limit_set {
                format!(
                    ", of which cogeo may use {:.2} MiB (--max-device-memory)",
                    shared.memory_limit as f64 / (1 << 20) as f64
                )
            } else {
                String::new()
            };
            return Err(anyhow!(
                "out of GPU memory: buffer {name:?} needs {:.2} MiB with {:.2} MiB already in use; {} has {} MiB of device memory{limit}",
                size as f64 / (1 << 20) as f64,
                in_use as f64 / (1 << 20) as f64,
                info.name,
                info.device_local_memory >> 20
            ));
        }
        let result = Self::create(gpu, name, size, kind);
        if result.is_err() {
            shared.memory_in_use.fetch_sub(size, Ordering::Relaxed);
        }
        result
    }

    fn create(gpu: &Gpu, name: &str, size: u64, kind: MemoryKind) -> Result<Buffer> {
        let shared = &gpu.shared;
        let info = &shared.info;
        let device = &shared.device;
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS
            | vk::BufferUsageFlags::TRANSFER_SRC
            | vk::BufferUsageFlags::TRANSFER_DST;
        let buffer = unsafe {
            device.create_buffer(
                &vk::BufferCreateInfo::default().size(size).usage(usage).sharing_mode(vk::SharingMode::EXCLUSIVE),
                None,
            )?
        };
        let mut requirements = unsafe { device.get_buffer_memory_requirements(buffer) };
        // Every buffer starts 16-byte aligned, whatever the driver asks for, so that passes reading
        // uvec4s or vec4s from a buffer's start (the sort's lane-serial shape, the loss's vec4
        // passes) can rely on it.
        requirements.alignment = requirements.alignment.max(16);
        let location = match kind {
            MemoryKind::Device => MemoryLocation::GpuOnly,
            MemoryKind::Upload => MemoryLocation::CpuToGpu,
            MemoryKind::Readback => MemoryLocation::GpuToCpu,
        };
        let allocation = shared.allocator.lock().unwrap().allocate(&AllocationCreateDesc {
            name,
            requirements,
            location,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                unsafe { device.destroy_buffer(buffer, None) };
                return Err(anyhow!(
                    "out of GPU memory: buffer {name:?} needs {} MiB; {} has {} MiB of device memory ({e})",
                    size >> 20,
                    info.name,
                    info.device_local_memory >> 20
                ));
            }
        };
        unsafe { device.bind_buffer_memory(buffer, allocation.memory(), allocation.offset())? };
        let address =
            unsafe { device.get_buffer_device_address(&vk::BufferDeviceAddressInfo::default().buffer(buffer)) };
        Ok(Buffer { gpu: shared.clone(), buffer, allocation: Some(allocation), size, address })
    }

    /// Allocates a device buffer of `size` bytes filled with zeros.
    pub fn zeroed(gpu: &Gpu, name: &str, size: u64) -> Result<Buffer> {
        let buffer = Buffer::new(gpu, name, size, MemoryKind::Device)?;
        let mut rec = super::Recorder::new(gpu)?;
        rec.fill(&buffer, 0, buffer.size(), 0);
        rec.submit_and_wait()?;
        Ok(buffer)
    }

    /// Allocates a device buffer holding `data`.
    pub fn from_slice<T: bytemuck::Pod>(gpu: &Gpu, name: &str, data: &[T]) -> Result<Buffer> {
        let buffer = Buffer::new(gpu, name, std::mem::size_of_val(data) as u64, MemoryKind::Device)?;
        buffer.upload(gpu, data)?;
        Ok(buffer)
    }

    pub fn size(&self) -> u64 {
        self.size
    }

    /// The device address shaders use to reach this buffer.
    pub fn address(&self) -> u64 {
        self.address
    }

    fn mapped(&self) -> Option<*mut u8> {
        self.allocation.as_ref().and_then(|a| a.mapped_ptr()).map(|p| p.as_ptr() as *mut u8)
    }

    /// Copies `data` to the start of the buffer: directly where the memory is host-visible, through a
    /// staging buffer otherwise. Waits for completion.
    pub fn upload<T: bytemuck::Pod>(&self, gpu: &Gpu, data: &[T]) -> Result<()> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        if bytes.len() as u64 > self.size {
            return Err(anyhow!("upload of {} bytes into a buffer of {} bytes", bytes.len(), self.size));
        }
        if bytes.is_empty() {
            return Ok(());
        }
        if let Some(ptr) = self.mapped() {
            unsafe { std::ptr::copy_nonoverlapping(bytes.as_ptr(), ptr, bytes.len()) };
            return Ok(());
        }
        let staging = Buffer::new(gpu, "staging upload", bytes.len() as u64, MemoryKind::Upload)?;
        let ptr = staging.mapped().ok_or_else(|| anyhow!("upload staging memory is not mapped"))?;
        unsafe { std::ptr::copy_nonoverlapping(bytes.as_ptr(), ptr, bytes.len()) };
        let mut rec = super::Recorder::new(gpu)?;
        rec.copy(&staging, self, bytes.len() as u64);
        rec.submit_and_wait()?;
        Ok(())
    }

    /// Reads back the first `count` elements. Waits for completion.
    pub fn download<T: bytemuck::Pod>(&self, gpu: &Gpu, count: usize) -> Result<Vec<T>> {
        self.download_at(gpu, 0, count)
    }

    /// Reads back `count` elements starting at element `first`. Waits for completion.
    pub fn download_at<T: bytemuck::Pod>(&self, gpu: &Gpu, first: u64, count: usize) -> Result<Vec<T>> {
        let mut out = vec![T::zeroed(); count];
        let offset = first * std::mem::size_of::<T>() as u64;
        Readback::default().read_into(gpu, &mut [(self, offset, bytemuck::cast_slice_mut(&mut out))])?;
        Ok(out)
    }

    /// Writes a plain-old-data value to a host-visible buffer (parameter blocks); no GPU work.
    pub fn write_pod<T: bytemuck::Pod>(&self, value: &T) -> Result<()> {
        let bytes = bytemuck::bytes_of(value);
        let ptr = self.mapped().ok_or_else(|| anyhow!("write_pod on a buffer that is not host-visible"))?;
        if bytes.len() as u64 > self.size {
            return Err(anyhow!("write_pod of {} bytes into a buffer of {} bytes", bytes.len(), self.size));
        }
        unsafe { std::ptr::copy_nonoverlapping(bytes.as_ptr(), ptr, bytes.len()) };
        Ok(())
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        self.gpu.memory_in_use.fetch_sub(self.size, Ordering::Relaxed);
        unsafe { self.gpu.device.destroy_buffer(self.buffer, None) };
        if let Some(a) = self.allocation.take() {
            let _ = self.gpu.allocator.lock().unwrap().free(a);
        }
    }
}

/// Reads several buffers back at once. A discrete GPU's device memory is not mapped: each read
/// goes through a staging buffer, a submission and a wait. A render's seven output planes read one
/// by one (`Buffer::download`) took seven of each, for windows of a few thousand pixels (the hull
/// and the hole masks render 300 of them). Here one staging buffer, kept and grown between calls,
/// takes every copy of one submission. Where the buffers are mapped (lavapipe, integrated GPUs)
/// each is copied directly.
#[derive(Default)]
pub struct Readback {
    staging: Option<Buffer>,
    /// Through the staging buffer even where the buffers are mapped (tests of that path).
    pub always_stage: bool,
}

impl Readback {
    /// Fills each `(buffer, offset, out)` with the `out.len()` bytes of `buffer` from byte
    /// `offset` on. Waits for completion.
    pub fn read_into(&mut self, gpu: &Gpu, parts: &mut [(&Buffer, u64, &mut [u8])]) -> Result<()> {
        if let Some((b, _, out)) = parts.iter().find(|(b, offset, out)| offset + out.len() as u64 > b.size) {
            return Err(anyhow!("download of {} bytes from a buffer of {} bytes", out.len(), b.size));
        }
        let mapped: Option<Vec<*mut u8>> = parts.iter().map(|(b, _, _)| b.mapped()).collect();
        if let (Some(mapped), false) = (mapped, self.always_stage) {
            for ((_, offset, out), ptr) in parts.iter_mut().zip(mapped).filter(|((_, _, out), _)| !out.is_empty()) {
                unsafe { std::ptr::copy_nonoverlapping(ptr.add(*offset as usize), out.as_mut_ptr(), out.len()) };
                gpu.shared.round_trips.readbacks.fetch_add(1, Ordering::Relaxed);
            }
            return Ok(());
        }
        // each part at a 16-byte aligned offset of the staging buffer
        let offsets: Vec<u64> = parts
            .iter()
            .scan(0u64, |next, (_, _, out)| {
                let at = *next;
                *next += (out.len() as u64).div_ceil(16) * 16;
                Some(at)
            })
            .collect();
        let total = parts.last().map_or(0, |(_, _, out)| offsets[parts.len() - 1] + out.len() as u64);
        if total == 0 {
            return Ok(());
        }
        if self.staging.as_ref().is_none_or(|s| s.size < total) {
            // exact the first time (a one-off read takes no more than it reads), then grown by
            // powers of two: a rasterizer's windows of every size follow one another
            let size = if self.staging.is_some() { total.next_power_of_two() } else { total };
            self.staging = None;
            self.staging = Some(Buffer::new(gpu, "readback staging", size, MemoryKind::Readback)?);
        }
        let staging = self.staging.as_ref().unwrap();
        let mut rec = super::Recorder::new(gpu)?;
        for ((src, offset, out), &at) in parts.iter().zip(&offsets) {
            if !out.is_empty() {
                rec.copy_region(src, *offset, staging, at, out.len() as u64);
            }
        }
        rec.submit_and_wait()?;
        gpu.shared.round_trips.readbacks.fetch_add(1, Ordering::Relaxed);
        let ptr = staging.mapped().ok_or_else(|| anyhow!("readback staging memory is not mapped"))?;
        for ((_, _, out), &at) in parts.iter_mut().zip(&offsets) {
            unsafe { std::ptr::copy_nonoverlapping(ptr.add(at as usize), out.as_mut_ptr(), out.len()) };
        }
        Ok(())
    }
}
