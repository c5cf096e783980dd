//! Vulkan compute engine: instance and device selection, memory, pipelines, command recording with
//! per-pass timestamps. Every buffer is reached by shaders through its device address, which is what
//! lets a scene exceed a driver's per-binding storage-buffer limit (128 MiB on lavapipe).

pub mod bandwidth;
mod buffer;
mod commands;
mod pipeline;

pub use buffer::{Buffer, MemoryKind, Readback};
pub use commands::{PassTiming, Recorder};
pub use pipeline::ComputePipeline;

use anyhow::{anyhow, bail, Context, Result};
use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use std::ffi::{c_void, CStr};
use std::mem::ManuallyDrop;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

/// What the engine needs to know about the selected device.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    pub index: usize,
    pub name: String,
    pub device_type: String,
    pub api_version: String,
    pub driver: String,
    pub subgroup_size: u32,
    pub max_shared_memory: u32,
    pub max_storage_buffer_range: u32,
    pub max_workgroup_count: [u32; 3],
    pub max_memory_allocation: u64,
    pub device_local_memory: u64,
    pub timestamp_period_ns: f32,
    pub timestamps: bool,
    pub float_atomic_add: bool,
    pub buffer_device_address: bool,
}

impl DeviceInfo {
    /// A CPU implementation (lavapipe): passes that pick a shape per device (blend layout, loss run,
    /// lane-serial sort and scan) take their CPU shapes here.
    pub fn is_cpu(&self) -> bool {
        self.device_type == device_type_name(vk::PhysicalDeviceType::CPU)
    }

    pub fn summary(&self) -> String {
        format!(
            "[{}] {} ({}, Vulkan {}, {}): subgroup {}, shared memory {} KiB, storage binding {} MiB, \
             max allocation {} MiB, device memory {} MiB, float atomic add {}, buffer device address {}",
            self.index,
            self.name,
            self.device_type,
            self.api_version,
            self.driver,
            self.subgroup_size,
            self.max_shared_memory / 1024,
            self.max_storage_buffer_range / (1024 * 1024),
            self.max_memory_allocation / (1024 * 1024),
            self.device_local_memory / (1024 * 1024),
            if self.float_atomic_add { "yes" } else { "no" },
            if self.buffer_device_address { "yes" } else { "no" },
        )
    }
}

/// Validation messages collected by the debug messenger (warnings and errors only).
type MessageLog = Mutex<Vec<String>>;

pub(crate) struct GpuShared {
    pub(crate) instance: ash::Instance,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT, *mut MessageLog)>,
    pub(crate) device: ash::Device,
    pub(crate) queue: vk::Queue,
    /// The queue's family: each `Recorder` makes its own command pool of it.
    pub(crate) queue_family: u32,
    pub(crate) allocator: ManuallyDrop<Mutex<Allocator>>,
    pub(crate) info: DeviceInfo,
    /// Serializes queue submission (Vulkan requires external synchronization of the queue).
    pub(crate) submit_lock: Mutex<()>,
    /// Host round trips so far: each a point where the host waits for the device.
    pub(crate) round_trips: RoundTripCounters,
    /// Bytes of buffers alive now, and the most this context may hold (the device's local memory,
    /// or less when the user set a limit; `memory_limit_set` says which).
    pub(crate) memory_in_use: AtomicU64,
    pub(crate) memory_limit: u64,
    pub(crate) memory_limit_set: bool,
}

/// Counts of the host's waits on the device, so benches can report them per iteration.
#[derive(Default)]
pub(crate) struct RoundTripCounters {
    pub(crate) submits: AtomicU64,
    pub(crate) readbacks: AtomicU64,
}

/// Host round trips counted since the context was made: `submits` (each submission waits for its
/// fence) and `readbacks` (device data copied to the host; on a discrete GPU each is a submission of
/// its own as well, and a `Readback` of several buffers counts one).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RoundTrips {
    pub submits: u64,
    pub readbacks: u64,
}

impl std::ops::Sub for RoundTrips {
    type Output = RoundTrips;
    fn sub(self, earlier: RoundTrips) -> RoundTrips {
        RoundTrips { submits: self.submits - earlier.submits, readbacks: self.readbacks - earlier.readbacks }
    }
}

// SAFETY: the raw message-log pointer is owned by GpuShared and only read under its Mutex; the
// queue, the one Vulkan handle here that needs external synchronization, is behind `submit_lock`
// (command pools are each Recorder's own).
unsafe impl Send for GpuShared {}
unsafe impl Sync for GpuShared {}

/// A selected Vulkan device; cheap to clone (shared handle).
#[derive(Clone)]
pub struct Gpu {
    pub(crate) shared: Arc<GpuShared>,
}

/// How to pick a device: `None` picks the best (discrete, then integrated, then virtual, then CPU).
#[derive(Clone, Debug, Default)]
pub struct DeviceChoice {
    /// Device index as listed by `cogeo devices`, or a case-insensitive substring of its name.
    pub selector: Option<String>,
    /// Enable the Khronos validation layer (also `COGEO_VALIDATE=1`).
    pub validate: bool,
    /// Use at most this many MiB of device memory (a GPU shared with other jobs; also
    /// `COGEO_MAX_DEVICE_MEMORY_MIB`). None: all of the device's local memory.
    pub memory_limit_mib: Option<f64>,
}

impl DeviceChoice {
    /// Selector from `--device` or else `COGEO_DEVICE`; validation from `COGEO_VALIDATE=1`.
    pub fn from_env(selector: Option<String>) -> Self {
        let selector = selector.or_else(|| std::env::var("COGEO_DEVICE").ok().filter(|s| !s.is_empty()));
        let validate = std::env::var("COGEO_VALIDATE").map(|v| v == "1" || v == "true").unwrap_or(false);
        let memory_limit_mib = std::env::var("COGEO_MAX_DEVICE_MEMORY_MIB").ok().and_then(|v| v.parse().ok());
        DeviceChoice { selector, validate, memory_limit_mib }
    }
}

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    let message = if data.is_null() || (*data).p_message.is_null() {
        "(no message)".to_string()
    } else {
        CStr::from_ptr((*data).p_message).to_string_lossy().into_owned()
    };
    let text = format!("{severity:?}: {message}");
    eprintln!("vulkan validation: {text}");
    if let Some(log) = (user as *const MessageLog).as_ref() {
        if let Ok(mut v) = log.lock() {
            v.push(text);
        }
    }
    vk::FALSE
}

fn device_type_name(t: vk::PhysicalDeviceType) -> &'static str {
    match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => "discrete GPU",
        vk::PhysicalDeviceType::INTEGRATED_GPU => "integrated GPU",
        vk::PhysicalDeviceType::VIRTUAL_GPU => "virtual GPU",
        vk::PhysicalDeviceType::CPU => "CPU",
        _ => "other",
    }
}

fn device_type_rank(t: vk::PhysicalDeviceType) -> u32 {
    match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    }
}

fn create_instance(entry: &ash::Entry, validate: bool) -> Result<ash::Instance> {
    let app = vk::ApplicationInfo::default()
        .application_name(c"cogeo")
        .engine_name(c"cogeo")
        .api_version(vk::API_VERSION_1_2);
    let available_ext = unsafe { entry.enumerate_instance_extension_properties(None)? };
    let has_ext = |name: &CStr| available_ext.iter().any(|e| e.extension_name_as_c_str() == Ok(name));
    let mut extensions = Vec::new();
    let mut flags = vk::InstanceCreateFlags::empty();
    // MoltenVK (Apple) is only enumerated with the portability extension.
    if has_ext(ash::khr::portability_enumeration::NAME) {
        extensions.push(ash::khr::portability_enumeration::NAME.as_ptr());
        flags |= vk::InstanceCreateFlags::ENUMERATE_PORTABILITY_KHR;
    }
    let mut layers = Vec::new();
    if validate {
        let available = unsafe { entry.enumerate_instance_layer_properties()? };
        if !available.iter().any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER)) {
            bail!(
                "COGEO_VALIDATE=1 but the Khronos validation layer is not installed \
                 (Debian/Ubuntu: apt-get install vulkan-validationlayers)"
            );
        }
        layers.push(VALIDATION_LAYER.as_ptr());
        if !has_ext(ash::ext::debug_utils::NAME) {
            bail!("validation requested but VK_EXT_debug_utils is not available");
        }
        extensions.push(ash::ext::debug_utils::NAME.as_ptr());
    }
    let info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_extension_names(&extensions)
        .enabled_layer_names(&layers)
        .flags(flags);
    unsafe { entry.create_instance(&info, None) }.context("vkCreateInstance failed")
}

fn query_info(instance: &ash::Instance, pd: vk::PhysicalDevice, index: usize) -> DeviceInfo {
    unsafe {
        let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
        let mut maint3 = vk::PhysicalDeviceMaintenance3Properties::default();
        let mut driver = vk::PhysicalDeviceDriverProperties::default();
        let mut props2 = vk::PhysicalDeviceProperties2::default()
            .push_next(&mut subgroup)
            .push_next(&mut maint3)
            .push_next(&mut driver);
        instance.get_physical_device_properties2(pd, &mut props2);
        let props = props2.properties;

        let mut atomic_float = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default();
        let mut v12 = vk::PhysicalDeviceVulkan12Features::default();
        let exts = instance.enumerate_device_extension_properties(pd).unwrap_or_default();
        let has_atomic_ext =
            exts.iter().any(|e| e.extension_name_as_c_str() == Ok(ash::ext::shader_atomic_float::NAME));
        let mut features2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut v12);
        if has_atomic_ext {
            features2 = features2.push_next(&mut atomic_float);
        }
        instance.get_physical_device_features2(pd, &mut features2);
        let float_atomic_add = has_atomic_ext && atomic_float.shader_buffer_float32_atomic_add == vk::TRUE;
        let buffer_device_address = v12.buffer_device_address == vk::TRUE;

        let mem = instance.get_physical_device_memory_properties(pd);
        let device_local_memory = mem.memory_heaps[..mem.memory_heap_count as usize]
            .iter()
            .filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL))
            .map(|h| h.size)
            .sum();
        let qf = instance.get_physical_device_queue_family_properties(pd);
        let timestamps =
            qf.iter().any(|q| q.queue_flags.contains(vk::QueueFlags::COMPUTE) && q.timestamp_valid_bits > 0);
        let v = props.api_version;
        DeviceInfo {
            index,
            name: props.device_name_as_c_str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default(),
            device_type: device_type_name(props.device_type).to_string(),
            api_version: format!(
                "{}.{}.{}",
                vk::api_version_major(v),
                vk::api_version_minor(v),
                vk::api_version_patch(v)
            ),
            driver: driver.driver_info_as_c_str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default(),
            subgroup_size: subgroup.subgroup_size,
            max_shared_memory: props.limits.max_compute_shared_memory_size,
            max_storage_buffer_range: props.limits.max_storage_buffer_range,
            max_workgroup_count: props.limits.max_compute_work_group_count,
            max_memory_allocation: maint3.max_memory_allocation_size,
            device_local_memory,
            timestamp_period_ns: props.limits.timestamp_period,
            timestamps,
            float_atomic_add,
            buffer_device_address,
        }
    }
}

/// The Vulkan loader, loaded once per process and never unloaded, with one bare instance that is
/// never destroyed, so that the drivers stay loaded too (the loader unloads them with a process's
/// last instance). On a lent H200, `tests/gradients.rs` (contexts created and dropped on 8 test
/// threads) segfaulted as a test thread exited, in code no longer mapped: read as that thread's
/// exit destructors pointing into a library unloaded when another thread dropped the last
/// context (bench/JOURNAL.md, second GPU run). A context per `Gpu::new` stays.
fn vulkan() -> Result<&'static ash::Entry> {
    static LOADER: std::sync::OnceLock<std::result::Result<ash::Entry, String>> = std::sync::OnceLock::new();
    let loaded = LOADER.get_or_init(|| {
        let entry = unsafe { ash::Entry::load() }.map_err(|e| e.to_string())?;
        // kept, never destroyed (ash::Instance has no Drop); where it fails, the caller's own
        // instance fails the same way and says why
        let _keep_drivers_loaded = create_instance(&entry, false);
        Ok(entry)
    });
    loaded.as_ref().map_err(|e| {
        anyhow!(
            "cannot load the Vulkan loader (libvulkan.so.1): {e}; Debian/Ubuntu: apt-get install libvulkan1 mesa-vulkan-drivers"
        )
    })
}

/// Lists every Vulkan device with its limits (for `cogeo devices`).
pub fn list_devices() -> Result<Vec<DeviceInfo>> {
    let entry = vulkan()?;
    let instance = create_instance(entry, false)?;
    let pds = unsafe { instance.enumerate_physical_devices()? };
    let infos = pds.iter().enumerate().map(|(i, &pd)| query_info(&instance, pd, i)).collect();
    unsafe { instance.destroy_instance(None) };
    Ok(infos)
}

impl Gpu {
    /// Creates the compute context on the chosen (or best) device.
    pub fn new(choice: &DeviceChoice) -> Result<Gpu> {
        let entry = vulkan()?;
        let instance = create_instance(entry, choice.validate)?;
        let debug = if choice.validate {
            let log: *mut MessageLog = Box::into_raw(Box::new(Mutex::new(Vec::new())));
            let loader = ash::ext::debug_utils::Instance::new(entry, &instance);
            let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
                .message_severity(
                    vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
                )
                .message_type(
                    vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                        | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                        | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
                )
                .pfn_user_callback(Some(debug_callback))
                .user_data(log as *mut c_void);
            let messenger = unsafe { loader.create_debug_utils_messenger(&info, None)? };
            Some((loader, messenger, log))
        } else {
            None
        };

        let pds = unsafe { instance.enumerate_physical_devices()? };
        if pds.is_empty() {
            bail!("no Vulkan device found; for the CPU install Mesa lavapipe (apt-get install mesa-vulkan-drivers)");
        }
        let infos: Vec<DeviceInfo> = pds.iter().enumerate().map(|(i, &pd)| query_info(&instance, pd, i)).collect();
        let index = match &choice.selector {
            Some(sel) => {
                if let Ok(i) = sel.parse::<usize>() {
                    if i >= infos.len() {
                        bail!("--device {i}: only {} Vulkan device(s) found (see `cogeo devices`)", infos.len());
                    }
                    i
                } else {
                    let lower = sel.to_lowercase();
                    infos.iter().position(|d| d.name.to_lowercase().contains(&lower)).ok_or_else(|| {
                        anyhow!(
                            "--device {sel:?}: no device name contains it; devices: {}",
                            infos.iter().map(|d| d.name.as_str()).collect::<Vec<_>>().join(", ")
                        )
                    })?
                }
            }
            None => {
                let types: Vec<_> =
                    pds.iter().map(|&pd| unsafe { instance.get_physical_device_properties(pd) }.device_type).collect();
                (0..infos.len())
                    .filter(|&i| infos[i].buffer_device_address)
                    .min_by_key(|&i| device_type_rank(types[i]))
                    .ok_or_else(|| anyhow!("no Vulkan device supports buffer device address (Vulkan 1.2)"))?
            }
        };
        let info = infos[index].clone();
        if !info.buffer_device_address {
            bail!("device {} does not support buffer device address, which cogeo requires", info.name);
        }
        let physical_device = pds[index];

        let qf = unsafe { instance.get_physical_device_queue_family_properties(physical_device) };
        let queue_family = qf
            .iter()
            .position(|q| q.queue_flags.contains(vk::QueueFlags::COMPUTE))
            .ok_or_else(|| anyhow!("device {} has no compute queue", info.name))? as u32;

        let exts = unsafe { instance.enumerate_device_extension_properties(physical_device)? };
        let has_ext = |name: &CStr| exts.iter().any(|e| e.extension_name_as_c_str() == Ok(name));
        let mut device_exts = Vec::new();
        if info.float_atomic_add {
            device_exts.push(ash::ext::shader_atomic_float::NAME.as_ptr());
        }
        if has_ext(c"VK_KHR_portability_subset") {
            device_exts.push(c"VK_KHR_portability_subset".as_ptr());
        }
        let supported = unsafe { instance.get_physical_device_features(physical_device) };
        let features = vk::PhysicalDeviceFeatures::default()
            .shader_int64(supported.shader_int64 == vk::TRUE)
            .shader_float64(supported.shader_float64 == vk::TRUE);
        let mut v12 =
            vk::PhysicalDeviceVulkan12Features::default().buffer_device_address(true).scalar_block_layout(true);
        let mut atomic_float =
            vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default().shader_buffer_float32_atomic_add(true);
        let priorities = [1.0f32];
        let queue_info =
            [vk::DeviceQueueCreateInfo::default().queue_family_index(queue_family).queue_priorities(&priorities)];
        let mut device_info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queue_info)
            .enabled_extension_names(&device_exts)
            .enabled_features(&features)
            .push_next(&mut v12);
        if info.float_atomic_add {
            device_info = device_info.push_next(&mut atomic_float);
        }
        let device = unsafe { instance.create_device(physical_device, &device_info, None) }
            .with_context(|| format!("vkCreateDevice failed on {}", info.name))?;
        let queue = unsafe { device.get_device_queue(queue_family, 0) };
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device,
            debug_settings: Default::default(),
            buffer_device_address: true,
            allocation_sizes: Default::default(),
        })
        .context("cannot create the GPU memory allocator")?;

        let memory_limit = match choice.memory_limit_mib {
            Some(mib) => ((mib.max(0.0) * (1 << 20) as f64) as u64).min(info.device_local_memory),
            None => info.device_local_memory,
        };
        Ok(Gpu {
            shared: Arc::new(GpuShared {
                instance,
                debug,
                device,
                queue,
                queue_family,
                allocator: ManuallyDrop::new(Mutex::new(allocator)),
                info,
                submit_lock: Mutex::new(()),
                round_trips: RoundTripCounters::default(),
                memory_in_use: AtomicU64::new(0),
                memory_limit,
                memory_limit_set: choice.memory_limit_mib.is_some(),
            }),
        })
    }

    pub fn info(&self) -> &DeviceInfo {
        &self.shared.info
    }

    pub fn device(&self) -> &ash::Device {
        &self.shared.device
    }

    /// Submissions and readbacks so far (subtract two readings for a span of work).
    pub fn round_trips(&self) -> RoundTrips {
        let c = &self.shared.round_trips;
        RoundTrips { submits: c.submits.load(Ordering::Relaxed), readbacks: c.readbacks.load(Ordering::Relaxed) }
    }

    /// Validation messages (warnings and errors) seen so far; empty without validation.
    pub fn validation_messages(&self) -> Vec<String> {
        match &self.shared.debug {
            Some((_, _, log)) => unsafe { (**log).lock().unwrap().clone() },
            None => Vec::new(),
        }
    }

    /// Whether the validation layer is active in this context.
    pub fn validating(&self) -> bool {
        self.shared.debug.is_some()
    }

    /// Waits until the device is idle.
    pub fn wait_idle(&self) -> Result<()> {
        let _guard = self.shared.submit_lock.lock().unwrap();
        unsafe { self.shared.device.device_wait_idle()? };
        Ok(())
    }
}

impl Drop for GpuShared {
    fn drop(&mut self) {
        unsafe {
            let _ = self.device.device_wait_idle();
            ManuallyDrop::drop(&mut self.allocator);
            self.device.destroy_device(None);
            if let Some((loader, messenger, log)) = self.debug.take() {
                loader.destroy_debug_utils_messenger(messenger, None);
                drop(Box::from_raw(log));
            }
            self.instance.destroy_instance(None);
        }
    }
}

/// Splits a 1D workgroup count into a grid within the device's per-dimension limit; shaders
/// linearize it again with `linear_group_id()` and bounds-check.
pub fn dispatch_1d(groups: u32) -> [u32; 3] {
    const MAX_X: u32 = 65535;
    if groups <= MAX_X {
        [groups.max(1), 1, 1]
    } else {
        [MAX_X, groups.div_ceil(MAX_X), 1]
    }
}
