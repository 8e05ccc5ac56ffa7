//! The host's Vulkan, made the way an engine makes it: an instance with the window system's
//! surface extensions (and, when asked, the Khronos validation layer with a debug messenger
//! recording into a [`ValidationLog`]), the window's surface, a device that can present to
//! it with caveclod's features and `VK_KHR_swapchain`, its queue and a gpu-allocator. caveclod
//! only borrows them ([`Gpu::context`] wraps them with `Context::from_raw`).

use std::ffi::CStr;
use std::sync::{Arc, Mutex};

use caveclod_vulkan::ash::{self, khr, vk};
use caveclod_vulkan::gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use caveclod_vulkan::gpu_allocator::{AllocationSizes, AllocatorDebugSettings};
use caveclod_vulkan::{
    Context, DebugMessenger, DeviceFeatures, HostDevice, SharedAllocator, ValidationLog,
    API_VERSION, VALIDATION_LAYER,
};
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use winit::window::Window;

/// `map_err` for a Vulkan result: the call's name and the result code.
pub fn vk_err(call: &'static str) -> impl Fn(vk::Result) -> String {
    move |e| format!("{call}: {e}")
}

/// What the host owns; destroyed by [`Gpu::destroy`], in reverse order of creation.
pub struct Gpu {
    _entry: ash::Entry,
    pub instance: ash::Instance,
    messenger: Option<DebugMessenger>,
    /// Where the validation layer's messages go (empty when validation is off).
    pub log: Arc<ValidationLog>,
    /// The validation layer is enabled and its messages recorded.
    pub validation: bool,
    pub surface_loader: khr::surface::Instance,
    pub surface: vk::SurfaceKHR,
    pub physical_device: vk::PhysicalDevice,
    pub device: ash::Device,
    /// The queue family of `queue`: graphics, compute and presentation to `surface`.
    pub family: u32,
    pub queue: vk::Queue,
    pub allocator: SharedAllocator,
    /// caveclod's features enabled on `device`.
    pub enabled: DeviceFeatures,
    pub device_name: String,
}

/// A physical device that qualifies, with what the host will enable on it.
struct Candidate {
    physical_device: vk::PhysicalDevice,
    family: u32,
    kind: vk::PhysicalDeviceType,
    name: String,
    features: DeviceFeatures,
}

impl Gpu {
    /// Creates instance, messenger, surface, device, queue and allocator for `window`;
    /// `validation` asks for the Khronos layer (an error if it is not installed).
    pub fn new(window: &Window, validation: bool) -> Result<Self, String> {
        // SAFETY: loads the system's Vulkan loader; nothing else runs its code yet.
        let entry =
            unsafe { ash::Entry::load() }.map_err(|e| format!("loading the Vulkan loader: {e}"))?;
        let display = window
            .display_handle()
            .map_err(|e| format!("the window's display: {e}"))?
            .as_raw();
        let log = ValidationLog::new();
        let instance = create_instance(&entry, display, validation)?;
        let messenger = if validation {
            match DebugMessenger::new(&entry, &instance, log.clone()) {
                Ok(m) => Some(m),
                Err(e) => {
                    // SAFETY: nothing was created from the instance.
                    unsafe { instance.destroy_instance(None) };
                    return Err(format!("debug messenger: {e}"));
                }
            }
        } else {
            None
        };
        let surface_loader = khr::surface::Instance::new(&entry, &instance);
        let unwind_instance = |messenger: Option<DebugMessenger>| {
            if let Some(m) = messenger {
                m.destroy();
            }
            // SAFETY: everything created from the instance is destroyed.
            unsafe { instance.destroy_instance(None) };
        };
        let surface = match create_surface(&entry, &instance, window) {
            Ok(s) => s,
            Err(e) => {
                unwind_instance(messenger);
                return Err(e);
            }
        };
        let made = pick_device(&instance, &surface_loader, surface).and_then(|c| {
            let device = create_device(&instance, &c)?;
            // SAFETY: queue 0 of `c.family` was requested at device creation.
            let queue = unsafe { device.get_device_queue(c.family, 0) };
            match create_allocator(&instance, &device, c.physical_device) {
                Ok(a) => Ok((c, device, queue, a)),
                Err(e) => {
                    // SAFETY: nothing was created from the device.
                    unsafe { device.destroy_device(None) };
                    Err(e)
                }
            }
        });
        let (c, device, queue, allocator) = match made {
            Ok(m) => m,
            Err(e) => {
                // SAFETY: no swapchain was made from the surface.
                unsafe { surface_loader.destroy_surface(surface, None) };
                unwind_instance(messenger);
                return Err(e);
            }
        };
        Ok(Self {
            _entry: entry,
            instance,
            messenger,
            log,
            validation,
            surface_loader,
            surface,
            physical_device: c.physical_device,
            device,
            family: c.family,
            queue,
            allocator,
            enabled: c.features,
            device_name: c.name,
        })
    }

    /// caveclod's context over this device, recording into the host's validation log.
    pub fn context(&self) -> Result<Context, String> {
        let host = HostDevice {
            instance: self.instance.clone(),
            device: self.device.clone(),
            physical_device: self.physical_device,
            queue_family: self.family,
            queue: self.queue,
            allocator: Some(self.allocator.clone()),
            enabled: self.enabled,
        };
        // SAFETY: the handles are this host's live instance, device (created from
        // `physical_device` with `enabled`), queue of `family` (graphics + compute) and
        // allocator made for that device; the viewer destroys the context before any of
        // them, and submits from one thread only.
        let ctx = unsafe { Context::from_raw(host) }.map_err(|e| format!("caveclod: {e}"))?;
        Ok(if self.validation {
            ctx.with_validation_log(self.log.clone())
        } else {
            ctx
        })
    }

    /// A depth format without stencil the device can render into (`D16_UNORM` always
    /// can): egui's pipeline names no stencil attachment, so the rendering has none.
    pub fn depth_format(&self) -> Result<vk::Format, String> {
        let candidates = [vk::Format::D32_SFLOAT, vk::Format::D16_UNORM];
        candidates
            .into_iter()
            .find(|&f| {
                // SAFETY: the physical device belongs to the instance.
                let p = unsafe {
                    self.instance
                        .get_physical_device_format_properties(self.physical_device, f)
                };
                p.optimal_tiling_features
                    .contains(vk::FormatFeatureFlags::DEPTH_STENCIL_ATTACHMENT)
            })
            .ok_or_else(|| format!("{}: no depth attachment format", self.device_name))
    }

    /// Waits until the device is idle.
    pub fn wait_idle(&self) -> Result<(), String> {
        // SAFETY: the viewer submits from this thread only, so no submission races it.
        unsafe { self.device.device_wait_idle() }.map_err(vk_err("vkDeviceWaitIdle"))
    }

    /// Tears down what the host owns, in order: the allocator (refusing if someone still
    /// holds it or it still has allocations), the device, the surface, the messenger and
    /// the instance. Everything made from the device must be destroyed first.
    pub fn destroy(self) -> Result<(), String> {
        let mut problems = Vec::new();
        match Arc::try_unwrap(self.allocator) {
            Ok(a) => {
                let a = a.into_inner().unwrap_or_else(|p| p.into_inner());
                let report = a.generate_report();
                if !report.allocations.is_empty() {
                    problems.push(format!(
                        "{} allocations left: {:?}",
                        report.allocations.len(),
                        report
                            .allocations
                            .iter()
                            .map(|r| r.name.clone())
                            .collect::<Vec<_>>()
                    ));
                }
                drop(a);
            }
            Err(_) => problems.push("the allocator is still shared at teardown".to_string()),
        }
        // SAFETY: everything made from the device is destroyed (the caller's contract)
        // and the allocator has freed its memory.
        unsafe { self.device.destroy_device(None) };
        // SAFETY: the swapchain made from the surface is destroyed.
        unsafe { self.surface_loader.destroy_surface(self.surface, None) };
        if let Some(m) = self.messenger {
            m.destroy();
        }
        // SAFETY: the device, surface and messenger made from the instance are gone.
        unsafe { self.instance.destroy_instance(None) };
        if problems.is_empty() {
            Ok(())
        } else {
            Err(problems.join("; "))
        }
    }
}

/// A Vulkan 1.3 instance with the display's surface extensions, plus the validation layer
/// and `VK_EXT_debug_utils` when `validation`.
fn create_instance(
    entry: &ash::Entry,
    display: raw_window_handle::RawDisplayHandle,
    validation: bool,
) -> Result<ash::Instance, String> {
    let mut extensions = ash_window::enumerate_required_extensions(display)
        .map_err(vk_err("surface extensions"))?
        .to_vec();
    let layers = [VALIDATION_LAYER.as_ptr()];
    if validation {
        if !layer_installed(entry, VALIDATION_LAYER)? {
            return Err(format!(
                "validation asked for, but {} is not installed (Debian: vulkan-validationlayers)",
                VALIDATION_LAYER.to_string_lossy()
            ));
        }
        extensions.push(ash::ext::debug_utils::NAME.as_ptr());
    }
    let app = vk::ApplicationInfo::default()
        .application_name(c"caveclod viewer")
        .engine_name(c"caveclod viewer")
        .api_version(API_VERSION);
    let mut info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_extension_names(&extensions);
    if validation {
        info = info.enabled_layer_names(&layers);
    }
    // SAFETY: every pointer in `info` refers to locals (or static extension names) alive
    // for the call.
    unsafe { entry.create_instance(&info, None) }.map_err(vk_err("vkCreateInstance"))
}

/// `true` if the instance layer `name` is installed.
fn layer_installed(entry: &ash::Entry, name: &CStr) -> Result<bool, String> {
    // SAFETY: plain enumeration.
    let layers = unsafe { entry.enumerate_instance_layer_properties() }
        .map_err(vk_err("vkEnumerateInstanceLayerProperties"))?;
    Ok(layers
        .iter()
        .any(|l| l.layer_name_as_c_str().is_ok_and(|n| n == name)))
}

/// The window's surface.
fn create_surface(
    entry: &ash::Entry,
    instance: &ash::Instance,
    window: &Window,
) -> Result<vk::SurfaceKHR, String> {
    let display = window
        .display_handle()
        .map_err(|e| format!("the window's display: {e}"))?
        .as_raw();
    let handle = window
        .window_handle()
        .map_err(|e| format!("the window's handle: {e}"))?
        .as_raw();
    // SAFETY: the instance was created with the extensions this display needs
    // (`enumerate_required_extensions`); the window outlives the surface (the viewer
    // destroys the surface before dropping the window).
    unsafe { ash_window::create_surface(entry, instance, display, handle, None) }
        .map_err(vk_err("creating the window surface"))
}

/// The best device that has what caveclod needs, `VK_KHR_swapchain` and a graphics +
/// compute queue family that presents to `surface`: discrete, then integrated, virtual,
/// CPU. The error names each device and what it lacks.
fn pick_device(
    instance: &ash::Instance,
    surface_loader: &khr::surface::Instance,
    surface: vk::SurfaceKHR,
) -> Result<Candidate, String> {
    // SAFETY: plain enumeration.
    let devices = unsafe { instance.enumerate_physical_devices() }
        .map_err(vk_err("vkEnumeratePhysicalDevices"))?;
    let mut reasons = Vec::new();
    let mut best: Option<Candidate> = None;
    for pd in devices {
        match qualify(instance, surface_loader, surface, pd) {
            Ok(c) => {
                if best.as_ref().is_none_or(|b| rank(c.kind) < rank(b.kind)) {
                    best = Some(c);
                }
            }
            Err(why) => reasons.push(why),
        }
    }
    best.ok_or_else(|| {
        if reasons.is_empty() {
            "no Vulkan device (install Mesa's lavapipe: mesa-vulkan-drivers)".to_string()
        } else {
            format!("no usable Vulkan device: {}", reasons.join("; "))
        }
    })
}

fn rank(kind: vk::PhysicalDeviceType) -> u32 {
    match kind {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    }
}

/// `pd` as a candidate, or why it does not qualify.
fn qualify(
    instance: &ash::Instance,
    surface_loader: &khr::surface::Instance,
    surface: vk::SurfaceKHR,
    pd: vk::PhysicalDevice,
) -> Result<Candidate, String> {
    // SAFETY: `pd` was enumerated from `instance`.
    let props = unsafe { instance.get_physical_device_properties(pd) };
    let name = props
        .device_name_as_c_str()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|_| "unnamed device".into());
    if props.api_version < API_VERSION {
        return Err(format!("{name}: Vulkan 1.3 needed"));
    }
    // SAFETY: as above.
    let supported = unsafe { DeviceFeatures::supported(instance, pd) };
    let missing = supported.missing(DeviceFeatures::REQUIRED);
    if !missing.is_empty() {
        return Err(format!("{name}: lacks {}", missing.join(", ")));
    }
    // SAFETY: as above.
    let extensions = unsafe { instance.enumerate_device_extension_properties(pd) }
        .map_err(vk_err("vkEnumerateDeviceExtensionProperties"))?;
    if !extensions
        .iter()
        .any(|e| e.extension_name_as_c_str() == Ok(khr::swapchain::NAME))
    {
        return Err(format!("{name}: no VK_KHR_swapchain"));
    }
    // SAFETY: as above.
    let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    let want = vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE;
    let family = (0..families.len() as u32)
        .find(|&i| {
            let f = &families[i as usize];
            // SAFETY: `i` is a queue family of `pd`; the surface belongs to the instance.
            let presents =
                unsafe { surface_loader.get_physical_device_surface_support(pd, i, surface) }
                    .unwrap_or(false);
            f.queue_flags.contains(want) && f.queue_count > 0 && presents
        })
        .ok_or_else(|| format!("{name}: no graphics + compute queue that presents"))?;
    Ok(Candidate {
        physical_device: pd,
        family,
        kind: props.device_type,
        name,
        features: supported.and(DeviceFeatures::ALL),
    })
}

/// The logical device with one queue of the candidate's family, its features (caveclod's,
/// wireframe where supported) and `VK_KHR_swapchain`.
fn create_device(instance: &ash::Instance, c: &Candidate) -> Result<ash::Device, String> {
    let priorities = [1.0];
    let queues = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(c.family)
        .queue_priorities(&priorities)];
    let mut f10 = vk::PhysicalDeviceFeatures::default();
    let mut f12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
    c.features.enable(&mut f10, &mut f12, &mut f13);
    let extensions = [khr::swapchain::NAME.as_ptr()];
    let info = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queues)
        .enabled_extension_names(&extensions)
        .enabled_features(&f10)
        .push_next(&mut f12)
        .push_next(&mut f13);
    // SAFETY: the features are within what the device supports (`qualify`); every
    // pointer refers to locals alive for the call.
    unsafe { instance.create_device(c.physical_device, &info, None) }
        .map_err(vk_err("vkCreateDevice"))
}

fn create_allocator(
    instance: &ash::Instance,
    device: &ash::Device,
    physical_device: vk::PhysicalDevice,
) -> Result<SharedAllocator, String> {
    let allocator = Allocator::new(&AllocatorCreateDesc {
        instance: instance.clone(),
        device: device.clone(),
        physical_device,
        debug_settings: AllocatorDebugSettings::default(),
        buffer_device_address: false,
        allocation_sizes: AllocationSizes::default(),
    })
    .map_err(|e| format!("gpu-allocator: {e}"))?;
    Ok(Arc::new(Mutex::new(allocator)))
}
