//! Instance, validation messenger, device choice and the persistent-memory allocator.
//!
//! Teardown order (docs/ARCHITECTURE.md, "Errors, ownership, tests"): wait idle → everything
//! in the release queue → allocator → device → messenger → instance.

use super::release::ReleaseQueue;
use super::VkError;
use ash::vk;
use ash::{ext, khr};
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use std::ffi::{c_void, CStr, CString};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Arc, Mutex};

/// How to create a [`Context`].
#[derive(Clone, Debug, Default)]
pub struct ContextDesc {
    /// Enable `VK_LAYER_KHRONOS_validation` with synchronization validation.
    pub validation: bool,
    /// Device override: a decimal index into the device list or a case-insensitive substring
    /// of the device name. Falls back to `VOXGI_DEVICE` when `None`.
    pub device: Option<String>,
    /// Extra instance extensions (e.g. surface extensions for a window).
    pub instance_extensions: Vec<&'static CStr>,
    /// Ask for `VK_KHR_swapchain`.
    pub swapchain: bool,
}

/// Messages the validation layers sent, counted by severity. Tests assert both counts are 0.
#[derive(Debug, Default)]
pub struct ValidationLog {
    pub errors: AtomicU32,
    pub warnings: AtomicU32,
    messages: Mutex<Vec<String>>,
}

impl ValidationLog {
    pub fn error_count(&self) -> u32 {
        self.errors.load(Ordering::SeqCst)
    }
    pub fn warning_count(&self) -> u32 {
        self.warnings.load(Ordering::SeqCst)
    }
    /// Errors plus warnings: what a test must see as zero.
    pub fn total(&self) -> u32 {
        self.error_count() + self.warning_count()
    }
    /// A copy of every recorded message (errors and warnings), oldest first.
    pub fn messages(&self) -> Vec<String> {
        self.messages.lock().map(|m| m.clone()).unwrap_or_default()
    }
    fn record(&self, severity: vk::DebugUtilsMessageSeverityFlagsEXT, text: String) {
        if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
            self.errors.fetch_add(1, Ordering::SeqCst);
            log::error!("{text}");
        } else {
            self.warnings.fetch_add(1, Ordering::SeqCst);
            log::warn!("{text}");
        }
        if let Ok(mut m) = self.messages.lock() {
            m.push(text);
        }
    }
}

/// What the whole life of a [`Context`] left behind, teardown included: the validation
/// messages (also those raised while destroying the device and instance, e.g. objects never
/// destroyed) and the GPU memory never freed. Tests and `--validate` fail unless it is clean.
#[derive(Clone, Debug, Default)]
pub struct TeardownReport {
    /// Every validation message, oldest first.
    pub validation_messages: Vec<String>,
    /// Names of GPU memory allocations (persistent buffers, images, graph arenas) never freed.
    pub leaked_allocations: Vec<String>,
}

impl TeardownReport {
    /// No validation message and no leaked allocation.
    pub fn is_clean(&self) -> bool {
        self.validation_messages.is_empty() && self.leaked_allocations.is_empty()
    }

    /// One line per problem: the validation messages, then one line per leaked allocation.
    pub fn problems(&self) -> Vec<String> {
        let leaks = self
            .leaked_allocations
            .iter()
            .map(|n| format!("GPU memory `{n}` was never freed (leak)"));
        self.validation_messages
            .iter()
            .cloned()
            .chain(leaks)
            .collect()
    }
}

impl std::fmt::Display for TeardownReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.problems().join("\n---\n"))
    }
}

/// Limits and properties the rest of the renderer needs.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    pub name: String,
    pub device_type: vk::PhysicalDeviceType,
    pub api_version: u32,
    /// Nanoseconds per timestamp tick.
    pub timestamp_period_ns: f32,
    pub timestamp_valid_bits: u32,
    pub max_sampler_anisotropy: f32,
    pub non_coherent_atom_size: u64,
    /// Largest storage-buffer binding range (128 MiB on lavapipe).
    pub max_storage_buffer_range: u32,
    /// Largest side of a 2D image (16384 on lavapipe and desktop drivers).
    pub max_image_dimension_2d: u32,
    /// `maxViewportDimensions`: the largest viewport, width and height (16384 on lavapipe).
    pub max_viewport_dimensions: [u32; 2],
    /// Size of the largest device-local memory heap: what all resources together may take.
    pub device_local_heap_bytes: u64,
    /// `maxMemoryAllocationSize` (Vulkan 1.1, `VkPhysicalDeviceMaintenance3Properties`): the
    /// largest single allocation the driver promises to make (2 GiB on lavapipe).
    pub max_memory_allocation_bytes: u64,
    /// `maxBufferSize` (Vulkan 1.3, `VkPhysicalDeviceMaintenance4Properties`): the largest
    /// buffer the driver creates (4 GiB − 1 on lavapipe).
    pub max_buffer_bytes: u64,
    /// The Vulkan 1.1 feature `multiview` (enabled when present): one draw renders several
    /// views into the layers of its attachments (`gl_ViewIndex`); stereo uses it for a
    /// one-pass G-buffer of both eyes, and falls back to two passes without it.
    pub multiview: bool,
    /// `VkPhysicalDeviceDriverProperties::driverID` (Vulkan 1.2): which driver this is
    /// (`MESA_LLVMPIPE` for lavapipe).
    pub driver_id: vk::DriverId,
    /// `VkPhysicalDeviceDriverProperties::driverInfo`: the driver's version text (lavapipe:
    /// `Mesa 22.3.6 (LLVM 15.0.6)`).
    pub driver_info: String,
}

pub struct Context {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    pub physical_device: vk::PhysicalDevice,
    pub device: ash::Device,
    pub queue: vk::Queue,
    pub queue_family: u32,
    pub info: DeviceInfo,
    pub push_descriptor: khr::push_descriptor::Device,
    /// Present when the loader offers `VK_EXT_debug_utils`: labels for RenderDoc and object
    /// names (the device-level functions; ash 0.38 loads them apart from the instance's).
    pub debug_utils: Option<ext::debug_utils::Device>,
    pub validation: Arc<ValidationLog>,
    /// Where dropped GPU objects wait until the GPU is done with them; also owns the
    /// allocator and the table of live allocations (see `release.rs`).
    pub(super) release: Arc<ReleaseQueue>,
    pub(super) upload_pool: Mutex<vk::CommandPool>,
    messenger: vk::DebugUtilsMessengerEXT,
    /// The instance-level functions of `VK_EXT_debug_utils`: the messenger's.
    debug_utils_instance: Option<ext::debug_utils::Instance>,
}

/// Device features voxgi needs, each with the reason shown to the user when it is missing.
const REQUIRED_FEATURES: &[(&str, &str)] = &[
    (
        "geometryShader",
        "layered voxelization picks the 3D-texture layer in a geometry shader",
    ),
    (
        "logicOp",
        "binary voxelization ORs 128-bit columns with a logic op",
    ),
    (
        "fragmentStoresAndAtomics",
        "voxelization stores from fragment shaders",
    ),
    (
        "samplerAnisotropy",
        "textures are sampled with anisotropic filtering",
    ),
];

fn feature_enabled(f: &vk::PhysicalDeviceFeatures, name: &str) -> bool {
    match name {
        "geometryShader" => f.geometry_shader == vk::TRUE,
        "logicOp" => f.logic_op == vk::TRUE,
        "fragmentStoresAndAtomics" => f.fragment_stores_and_atomics == vk::TRUE,
        "samplerAnisotropy" => f.sampler_anisotropy == vk::TRUE,
        _ => false,
    }
}

/// The instance layers and extensions a context enables: validation (with debug utils) when
/// asked for, debug utils where available (object names), and the caller's extensions.
struct InstanceLayers {
    layers: Vec<*const i8>,
    extensions: Vec<*const i8>,
    debug_utils_available: bool,
}

/// Checks that what `desc` asks of the instance exists and lists it (the pointers are to
/// `'static` names: the validation layer's, ash's extension names, and `desc`'s).
fn instance_layers(entry: &ash::Entry, desc: &ContextDesc) -> Result<InstanceLayers, VkError> {
    // SAFETY: the entry holds the loaded Vulkan library (ash 0.38 marks the call unsafe).
    let available_ext: Vec<CString> =
        unsafe { entry.enumerate_instance_extension_properties(None) }
            .map_err(VkError::vk("enumerate instance extensions"))?
            .iter()
            // SAFETY: extension_name is a NUL-terminated array filled by the loader.
            .map(|p| unsafe { CStr::from_ptr(p.extension_name.as_ptr()) }.to_owned())
            .collect();
    let has_ext = |name: &CStr| available_ext.iter().any(|e| e.as_c_str() == name);
    let debug_utils_available = has_ext(ext::debug_utils::NAME);

    let mut layers: Vec<*const i8> = Vec::new();
    let validation_layer = c"VK_LAYER_KHRONOS_validation";
    if desc.validation {
        // SAFETY: the entry holds the loaded Vulkan library.
        let layer_present = unsafe { entry.enumerate_instance_layer_properties() }
            .map_err(VkError::vk("enumerate instance layers"))?
            .iter()
            // SAFETY: layer_name is a NUL-terminated array filled by the loader.
            .any(|l| unsafe { CStr::from_ptr(l.layer_name.as_ptr()) } == validation_layer);
        if !layer_present {
            return Err(VkError::MissingValidationLayer);
        }
        if !debug_utils_available {
            return Err(VkError::MissingInstanceExtension(
                "VK_EXT_debug_utils".into(),
            ));
        }
        layers.push(validation_layer.as_ptr());
    }

    let mut extensions: Vec<*const i8> = Vec::new();
    if debug_utils_available {
        extensions.push(ext::debug_utils::NAME.as_ptr());
    }
    for e in &desc.instance_extensions {
        if !has_ext(e) {
            return Err(VkError::MissingInstanceExtension(
                e.to_string_lossy().into(),
            ));
        }
        extensions.push(e.as_ptr());
    }
    Ok(InstanceLayers {
        layers,
        extensions,
        debug_utils_available,
    })
}

/// The logical device with one queue of `queue_family` and the features voxgi uses
/// (multiview where the device has it; the swapchain extension for a window).
fn create_device(
    instance: &ash::Instance,
    physical_device: vk::PhysicalDevice,
    queue_family: u32,
    info: &DeviceInfo,
    desc: &ContextDesc,
) -> Result<ash::Device, vk::Result> {
    let priorities = [1.0f32];
    let queue_info = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(queue_family)
        .queue_priorities(&priorities)];
    let features = vk::PhysicalDeviceFeatures::default()
        .geometry_shader(true)
        .logic_op(true)
        .fragment_stores_and_atomics(true)
        .sampler_anisotropy(true)
        .independent_blend(true)
        // Out-of-range buffer reads return zero instead of faulting: the ray tests rely on
        // it only as a safety net, and the validation layers check every access anyway.
        .robust_buffer_access(desc.validation);
    // maintenance4 is mandatory in Vulkan 1.3; shaderc's SPIR-V 1.6 relies on it (LocalSizeId).
    let mut features13 = vk::PhysicalDeviceVulkan13Features::default()
        .dynamic_rendering(true)
        .synchronization2(true)
        .maintenance4(true);
    let mut features12 = vk::PhysicalDeviceVulkan12Features::default().host_query_reset(true);
    // Optional: stereo renders both eyes' G-buffer in one pass with it.
    let mut features11 = vk::PhysicalDeviceVulkan11Features::default().multiview(info.multiview);
    let mut device_ext: Vec<*const i8> = vec![khr::push_descriptor::NAME.as_ptr()];
    if desc.swapchain {
        device_ext.push(khr::swapchain::NAME.as_ptr());
    }
    let device_info = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queue_info)
        .enabled_features(&features)
        .enabled_extension_names(&device_ext)
        .push_next(&mut features13)
        .push_next(&mut features12)
        .push_next(&mut features11);
    // SAFETY: physical_device comes from this instance; all pointers refer to live locals.
    unsafe { instance.create_device(physical_device, &device_info, None) }
}

impl Context {
    pub fn new(desc: &ContextDesc) -> Result<Self, VkError> {
        // SAFETY: loads the system Vulkan loader; the returned Entry keeps the library alive.
        let entry = unsafe { ash::Entry::load() }.map_err(|e| VkError::NoLoader(e.to_string()))?;
        let InstanceLayers {
            layers,
            extensions,
            debug_utils_available,
        } = instance_layers(&entry, desc)?;

        let app_name = c"voxgi";
        let app_info = vk::ApplicationInfo::default()
            .application_name(app_name)
            .application_version(vk::make_api_version(0, 0, 1, 0))
            .engine_name(app_name)
            .api_version(vk::API_VERSION_1_3);
        let enabled_validation_features =
            [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        let mut validation_features = vk::ValidationFeaturesEXT::default()
            .enabled_validation_features(&enabled_validation_features);
        let validation = Arc::new(ValidationLog::default());
        let mut instance_messenger_info = messenger_info(&validation);
        let mut instance_info = vk::InstanceCreateInfo::default()
            .application_info(&app_info)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions);
        if desc.validation {
            // The chained messenger info also reports what vkCreateInstance and
            // vkDestroyInstance find (e.g. a surface never destroyed), outside the lifetime of
            // the messenger created below.
            instance_info = instance_info
                .push_next(&mut validation_features)
                .push_next(&mut instance_messenger_info);
        }
        // SAFETY: every pointer in instance_info refers to locals that outlive this call; the
        // chained messenger's user data points into `validation`, which the Context keeps
        // until after it destroys the instance.
        let instance = unsafe { entry.create_instance(&instance_info, None) }
            .map_err(VkError::vk("create the Vulkan instance"))?;

        let debug_utils =
            debug_utils_available.then(|| ext::debug_utils::Instance::new(&entry, &instance));
        let mut messenger = vk::DebugUtilsMessengerEXT::null();
        if let (true, Some(du)) = (desc.validation, debug_utils.as_ref()) {
            // SAFETY: the user data points into the Arc held by the Context (`validation`),
            // which outlives the messenger: Drop destroys the messenger first.
            let created =
                unsafe { du.create_debug_utils_messenger(&messenger_info(&validation), None) };
            messenger = created.map_err(|r| {
                // SAFETY: nothing was created from the instance yet.
                unsafe { instance.destroy_instance(None) };
                VkError::vk("create the debug messenger")(r)
            })?;
        }

        // Undoes the instance and messenger when a later step fails (the device, where it
        // exists, is destroyed first by the caller).
        let release_instance = |e: VkError| {
            // SAFETY: nothing else created from the instance is alive: every failure path
            // below destroys what it made (device, allocator) before calling this.
            unsafe {
                if let Some(du) = &debug_utils {
                    if messenger != vk::DebugUtilsMessengerEXT::null() {
                        du.destroy_debug_utils_messenger(messenger, None);
                    }
                }
                instance.destroy_instance(None);
            }
            e
        };
        let (physical_device, queue_family, info) =
            pick_device(&instance, desc.device.clone(), desc.swapchain)
                .map_err(release_instance)?;
        log::info!(
            "using Vulkan device: {} ({:?})",
            info.name,
            info.device_type
        );
        let device = create_device(&instance, physical_device, queue_family, &info, desc)
            .map_err(|r| release_instance(VkError::vk("create the logical device")(r)))?;
        let release_device = |e: VkError| {
            // SAFETY: the device is idle and nothing created from it is alive.
            unsafe { device.destroy_device(None) };
            release_instance(e)
        };
        // SAFETY: the queue family and index 0 were requested in device_info.
        let queue = unsafe { device.get_device_queue(queue_family, 0) };

        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device,
            // Leaks are logged at shutdown (the default; `AllocatorDebugSettings` is
            // non-exhaustive since gpu-allocator 0.26).
            debug_settings: gpu_allocator::AllocatorDebugSettings::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        })
        .map_err(|e| release_device(VkError::Allocation(e.to_string())))?;

        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(queue_family)
            .flags(vk::CommandPoolCreateFlags::TRANSIENT);
        // SAFETY: device is valid; the pool is destroyed in Drop.
        let upload_pool = match unsafe { device.create_command_pool(&pool_info, None) } {
            Ok(pool) => pool,
            Err(r) => {
                drop(allocator);
                return Err(release_device(VkError::vk(
                    "create the upload command pool",
                )(r)));
            }
        };

        let push_descriptor = khr::push_descriptor::Device::new(&instance, &device);
        let debug_utils_device = debug_utils
            .is_some()
            .then(|| ext::debug_utils::Device::new(&instance, &device));
        let release = ReleaseQueue::new(device.clone(), allocator);
        Ok(Self {
            entry,
            instance,
            physical_device,
            device,
            queue,
            queue_family,
            info,
            push_descriptor,
            debug_utils: debug_utils_device,
            debug_utils_instance: debug_utils,
            validation,
            release,
            upload_pool: Mutex::new(upload_pool),
            messenger,
        })
    }

    /// Blocks until the GPU is idle, then destroys the objects dropped while it was busy.
    pub fn wait_idle(&self) -> Result<(), VkError> {
        let submitted = self.release.submitted();
        // SAFETY: the device is valid for the lifetime of self.
        unsafe { self.device.device_wait_idle() }.map_err(VkError::vk("wait for the device"))?;
        self.release.mark_completed(submitted);
        Ok(())
    }

    /// Destroys the context and reports what its whole life left behind: every validation
    /// message, including those raised while destroying the device and instance (objects
    /// never destroyed, wrong destruction order), and the GPU memory never freed. Checking
    /// the messages before teardown misses those; tests and `--validate` check this instead.
    ///
    /// Objects dropped before this call are destroyed here (after the device went idle);
    /// memory of an object still alive (kept past `finish`, or `mem::forget`) is a leak.
    pub fn finish(self) -> TeardownReport {
        let _ = self.wait_idle();
        let leaked_allocations = self.release.live_allocations.names();
        let log = Arc::clone(&self.validation);
        drop(self);
        TeardownReport {
            validation_messages: log.messages(),
            leaked_allocations,
        }
    }

    /// Dropped GPU objects (one batch per owner) still waiting for a submission that may use
    /// them to complete; 0 when nothing was dropped while frames were in flight.
    pub fn pending_releases(&self) -> usize {
        self.release.pending()
    }

    /// GPU memory this context holds now: the sizes of the allocations handed out (buffers,
    /// images, the graph's transient arenas) and not yet freed, objects waiting in the release
    /// queue included. Not the allocator's block sizes: the memory the renderer asked for.
    pub fn allocated_bytes(&self) -> u64 {
        self.release.live_allocations.total_bytes()
    }

    /// Gives a Vulkan object a name visible in validation messages and RenderDoc.
    pub fn set_name<T: vk::Handle>(&self, object: T, name: &str) {
        let Some(du) = &self.debug_utils else { return };
        let Ok(cname) = CString::new(name) else {
            return;
        };
        let info = vk::DebugUtilsObjectNameInfoEXT::default()
            .object_handle(object)
            .object_name(&cname);
        // SAFETY: object is a live handle of this device; naming failure is harmless.
        let _ = unsafe { du.set_debug_utils_object_name(&info) };
    }

    /// Size of the device's largest device-local memory heap: an upper bound on any one
    /// resource set, checked before allocating large ones (voxel grids).
    pub fn largest_device_local_heap_bytes(&self) -> u64 {
        self.info.device_local_heap_bytes
    }

    /// Memory properties of the chosen device (for the graph's transient arenas).
    pub fn memory_properties(&self) -> vk::PhysicalDeviceMemoryProperties {
        // SAFETY: physical_device belongs to instance.
        unsafe {
            self.instance
                .get_physical_device_memory_properties(self.physical_device)
        }
    }
}

impl Drop for Context {
    fn drop(&mut self) {
        // SAFETY: teardown in dependency order. After the wait, the release queue destroys
        // every object dropped so far and then the allocator, and refuses later releases (an
        // object still alive leaks, and the validation layer reports it when the device goes).
        unsafe {
            let _ = self.device.device_wait_idle();
            self.release.close();
            if let Ok(pool) = self.upload_pool.lock() {
                self.device.destroy_command_pool(*pool, None);
            }
            self.device.destroy_device(None);
            if let Some(du) = &self.debug_utils_instance {
                if self.messenger != vk::DebugUtilsMessengerEXT::null() {
                    du.destroy_debug_utils_messenger(self.messenger, None);
                }
            }
            self.instance.destroy_instance(None);
        }
    }
}

/// The messenger settings: warnings and errors of every type, recorded into `log`.
fn messenger_info(log: &Arc<ValidationLog>) -> vk::DebugUtilsMessengerCreateInfoEXT<'static> {
    vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(
            vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
        )
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(debug_callback))
        .user_data(Arc::as_ptr(log) as *mut c_void)
}

unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT,
    user: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: the layer passes valid callback data; `user` points to the ValidationLog of the
    // Context, alive until the messenger is destroyed.
    let (log_sink, text) = unsafe {
        let log_sink = &*(user as *const ValidationLog);
        let msg = if data.is_null() || (*data).p_message.is_null() {
            String::from("(no message)")
        } else {
            CStr::from_ptr((*data).p_message)
                .to_string_lossy()
                .into_owned()
        };
        (log_sink, msg)
    };
    log_sink.record(severity, text);
    vk::FALSE
}

fn device_name(props: &vk::PhysicalDeviceProperties) -> String {
    // SAFETY: device_name is a NUL-terminated array filled by the driver.
    unsafe { CStr::from_ptr(props.device_name.as_ptr()) }
        .to_string_lossy()
        .into_owned()
}

fn type_rank(t: vk::PhysicalDeviceType) -> u32 {
    match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    }
}

/// Why a device cannot run voxgi, or `None` when it can; also returns the queue family.
fn check_device(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    swapchain: bool,
) -> Result<u32, String> {
    // SAFETY: pd was enumerated from instance.
    let props = unsafe { instance.get_physical_device_properties(pd) };
    if props.api_version < vk::API_VERSION_1_3 {
        return Err(format!(
            "supports Vulkan {}.{}, voxgi needs 1.3 (update the driver)",
            vk::api_version_major(props.api_version),
            vk::api_version_minor(props.api_version)
        ));
    }
    // SAFETY: as above.
    let features = unsafe { instance.get_physical_device_features(pd) };
    for (name, why) in REQUIRED_FEATURES {
        if !feature_enabled(&features, name) {
            return Err(format!("lacks the feature `{name}` ({why})"));
        }
    }
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
    let mut f12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut f2 = vk::PhysicalDeviceFeatures2::default()
        .push_next(&mut f13)
        .push_next(&mut f12);
    // SAFETY: as above; the chain points to live locals.
    unsafe { instance.get_physical_device_features2(pd, &mut f2) };
    if f13.dynamic_rendering != vk::TRUE {
        return Err("lacks the Vulkan 1.3 feature `dynamicRendering`".into());
    }
    if f13.synchronization2 != vk::TRUE {
        return Err("lacks the Vulkan 1.3 feature `synchronization2`".into());
    }
    if f13.maintenance4 != vk::TRUE {
        return Err("lacks the Vulkan 1.3 feature `maintenance4`".into());
    }
    if f12.host_query_reset != vk::TRUE {
        return Err("lacks the Vulkan 1.2 feature `hostQueryReset`".into());
    }
    // SAFETY: as above.
    let exts = unsafe { instance.enumerate_device_extension_properties(pd) }
        .map_err(|e| format!("cannot list extensions ({e})"))?;
    let has = |n: &CStr| {
        exts.iter()
            // SAFETY: extension_name is NUL-terminated.
            .any(|e| unsafe { CStr::from_ptr(e.extension_name.as_ptr()) } == n)
    };
    if !has(khr::push_descriptor::NAME) {
        return Err("lacks the extension `VK_KHR_push_descriptor`".into());
    }
    if swapchain && !has(khr::swapchain::NAME) {
        return Err("lacks the extension `VK_KHR_swapchain`".into());
    }
    if props.limits.timestamp_compute_and_graphics != vk::TRUE {
        return Err("cannot write timestamps on graphics and compute queues".into());
    }
    // SAFETY: as above.
    let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    let want = vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE;
    families
        .iter()
        .position(|f| f.queue_flags.contains(want) && f.timestamp_valid_bits > 0)
        .map(|i| i as u32)
        .ok_or_else(|| "has no queue with graphics, compute and timestamps".into())
}

fn pick_device(
    instance: &ash::Instance,
    override_name: Option<String>,
    swapchain: bool,
) -> Result<(vk::PhysicalDevice, u32, DeviceInfo), VkError> {
    // SAFETY: instance is valid.
    let devices = unsafe { instance.enumerate_physical_devices() }
        .map_err(VkError::vk("enumerate physical devices"))?;
    if devices.is_empty() {
        return Err(VkError::NoDevice {
            report: "no Vulkan device found".into(),
        });
    }
    let wanted = override_name.or_else(|| std::env::var("VOXGI_DEVICE").ok());
    let mut report = String::new();
    let mut candidates = Vec::new();
    for (i, &pd) in devices.iter().enumerate() {
        // SAFETY: pd was enumerated from instance.
        let props = unsafe { instance.get_physical_device_properties(pd) };
        let name = device_name(&props);
        let selected_by_user = wanted.as_deref().map(|w| {
            w.parse::<usize>().map(|idx| idx == i).unwrap_or(false)
                || name.to_lowercase().contains(&w.to_lowercase())
        });
        match check_device(instance, pd, swapchain) {
            Ok(family) => {
                report.push_str(&format!(
                    "  [{i}] {name} ({:?}): usable\n",
                    props.device_type
                ));
                if selected_by_user != Some(false) {
                    candidates.push((type_rank(props.device_type), i, pd, family, props));
                }
            }
            Err(why) => report.push_str(&format!(
                "  [{i}] {name} ({:?}): {why}\n",
                props.device_type
            )),
        }
    }
    candidates.sort_by_key(|c| (c.0, c.1));
    let Some((_, _, pd, family, props)) = candidates.into_iter().next() else {
        return Err(match wanted {
            Some(w) => VkError::DeviceNotFound { wanted: w, report },
            None => VkError::NoDevice { report },
        });
    };
    // SAFETY: pd is valid.
    let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    let mut maintenance3 = vk::PhysicalDeviceMaintenance3Properties::default();
    let mut maintenance4 = vk::PhysicalDeviceMaintenance4Properties::default();
    let mut driver = vk::PhysicalDeviceDriverProperties::default();
    let mut props2 = vk::PhysicalDeviceProperties2::default()
        .push_next(&mut maintenance3)
        .push_next(&mut maintenance4)
        .push_next(&mut driver);
    // SAFETY: pd is valid; props2 chains live output structs (Vulkan 1.1 core; the driver
    // properties are Vulkan 1.2 core, and voxgi requires 1.3).
    unsafe { instance.get_physical_device_properties2(pd, &mut props2) };
    // SAFETY: pd is valid.
    let memory = unsafe { instance.get_physical_device_memory_properties(pd) };
    let info = DeviceInfo {
        name: device_name(&props),
        device_type: props.device_type,
        api_version: props.api_version,
        timestamp_period_ns: props.limits.timestamp_period,
        timestamp_valid_bits: families[family as usize].timestamp_valid_bits,
        max_sampler_anisotropy: props.limits.max_sampler_anisotropy,
        non_coherent_atom_size: props.limits.non_coherent_atom_size,
        max_storage_buffer_range: props.limits.max_storage_buffer_range,
        max_image_dimension_2d: props.limits.max_image_dimension2_d,
        max_viewport_dimensions: props.limits.max_viewport_dimensions,
        device_local_heap_bytes: largest_device_local_heap(&memory),
        max_memory_allocation_bytes: maintenance3.max_memory_allocation_size,
        max_buffer_bytes: maintenance4.max_buffer_size,
        multiview: has_multiview(instance, pd),
        driver_id: driver.driver_id,
        // SAFETY: driver_info is a NUL-terminated array filled by the driver.
        driver_info: unsafe { CStr::from_ptr(driver.driver_info.as_ptr()) }
            .to_string_lossy()
            .into_owned(),
    };
    Ok((pd, family, info))
}

/// Whether `pd` has the Vulkan 1.1 feature `multiview` (optional: stereo falls back to two
/// passes without it).
fn has_multiview(instance: &ash::Instance, pd: vk::PhysicalDevice) -> bool {
    let mut f11 = vk::PhysicalDeviceVulkan11Features::default();
    let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut f11);
    // SAFETY: pd is a physical device of this instance; the chain points to a live local.
    unsafe { instance.get_physical_device_features2(pd, &mut f2) };
    f11.multiview == vk::TRUE
}

/// Size of the largest device-local heap of `memory` (0 when none is device-local).
fn largest_device_local_heap(memory: &vk::PhysicalDeviceMemoryProperties) -> u64 {
    memory.memory_heaps[..memory.memory_heap_count as usize]
        .iter()
        .filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL))
        .map(|h| h.size)
        .max()
        .unwrap_or(0)
}

/// One line per Vulkan device: index, name, type, and whether voxgi can use it (and why not).
pub fn describe_devices() -> Result<String, VkError> {
    // SAFETY: loads the system Vulkan loader; the Entry outlives the instance below.
    let entry = unsafe { ash::Entry::load() }.map_err(|e| VkError::NoLoader(e.to_string()))?;
    let app_info = vk::ApplicationInfo::default().api_version(vk::API_VERSION_1_3);
    let info = vk::InstanceCreateInfo::default().application_info(&app_info);
    // SAFETY: info points to live locals.
    let instance = unsafe { entry.create_instance(&info, None) }
        .map_err(VkError::vk("create the Vulkan instance"))?;
    let result = pick_device(&instance, None, false);
    // SAFETY: nothing else was created from this instance.
    let devices = unsafe { instance.enumerate_physical_devices() }.unwrap_or_default();
    let mut report = String::new();
    for (i, &pd) in devices.iter().enumerate() {
        // SAFETY: pd was enumerated from instance.
        let props = unsafe { instance.get_physical_device_properties(pd) };
        let status = match check_device(&instance, pd, false) {
            Ok(_) => "usable".to_owned(),
            Err(why) => why,
        };
        report.push_str(&format!(
            "[{i}] {} ({:?}): {status}\n",
            device_name(&props),
            props.device_type
        ));
    }
    if let Ok((_, _, chosen)) = result {
        report.push_str(&format!("default choice: {}\n", chosen.name));
    }
    // SAFETY: no child objects exist.
    unsafe { instance.destroy_instance(None) };
    Ok(report)
}
