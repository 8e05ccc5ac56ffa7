//! [`Host`]: what an engine makes before caveclod can draw (instance, device, queue,
//! allocator), windowless or for a window.

use std::sync::{Arc, Mutex};

use caveclod_vulkan::ash::{self, vk};
use caveclod_vulkan::gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use caveclod_vulkan::gpu_allocator::{AllocationSizes, AllocatorDebugSettings};
use caveclod_vulkan::{Context, DeviceFeatures, HostDevice, SharedAllocator, ValidationLog};

use crate::error::{Error, Result, VkExt};
use crate::instance::Instance;
use crate::select::{self, Candidate, Wanted};
#[cfg(feature = "window")]
use crate::surface::{self, Surface};

/// How to make a [`Host`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HostDesc {
    /// Enable the Khronos validation layer (an error if it is not installed) and record
    /// its messages in the host's [`ValidationLog`].
    pub validation: bool,
    /// Prefer a CPU device (lavapipe: the tests' reference images are its) over GPUs.
    pub prefer_cpu: bool,
    /// Features the device must support; all are enabled.
    pub required: DeviceFeatures,
    /// Features enabled where the device supports them.
    pub optional: DeviceFeatures,
}

impl Default for HostDesc {
    /// Validation on, lavapipe first, exactly [`DeviceFeatures::REQUIRED`]: the tests' host.
    fn default() -> Self {
        Self {
            validation: true,
            prefer_cpu: true,
            required: DeviceFeatures::REQUIRED,
            optional: DeviceFeatures::default(),
        }
    }
}

/// A host engine's Vulkan, in the spirit of ash-examples' `ExampleBase`: the loader, an
/// instance (with validation and a debug messenger recording into a [`ValidationLog`] when
/// asked), a physical device chosen by [`HostDesc`], a device with caveclod's features, one
/// graphics + compute queue and a gpu-allocator shared with caveclod. Windowed
/// (`Host::windowed`, the `window` feature) it also holds the window's surface, and its
/// device has `VK_KHR_swapchain` and a queue that presents.
///
/// caveclod only borrows it: [`Host::context`] wraps it with `Context::from_raw`. The host
/// submits from one thread, the one that uses the context. [`Host::destroy`] tears it down
/// in reverse order of creation.
pub struct Host {
    instance: Instance,
    #[cfg(feature = "window")]
    surface: Option<Surface>,
    physical_device: vk::PhysicalDevice,
    device: ash::Device,
    family: u32,
    queue: vk::Queue,
    allocator: SharedAllocator,
    enabled: DeviceFeatures,
    device_name: String,
}

impl Host {
    /// A host without a window: its images are read back, not presented.
    pub fn headless(desc: &HostDesc) -> Result<Self> {
        let instance = Instance::new(desc.validation, &[])?;
        let wanted = Wanted {
            required: desc.required,
            optional: desc.optional,
            prefer_cpu: desc.prefer_cpu,
            presents: None,
        };
        match select::pick(&instance.raw, &wanted).and_then(|c| open(&instance.raw, c, false)) {
            Ok(opened) => Ok(Self::assemble(instance, opened)),
            Err(e) => {
                instance.destroy();
                Err(e)
            }
        }
    }

    /// A host for `window`: its surface, and a device that presents to it. The window must
    /// outlive the host (destroy the host before dropping the window).
    #[cfg(feature = "window")]
    pub fn windowed(window: &winit::window::Window, desc: &HostDesc) -> Result<Self> {
        let extensions = surface::required_extensions(window)?;
        let instance = Instance::new(desc.validation, extensions)?;
        let surface = match Surface::new(&instance.entry, &instance.raw, window) {
            Ok(s) => s,
            Err(e) => {
                instance.destroy();
                return Err(e);
            }
        };
        let presents = |pd, family| surface.presents(pd, family);
        let wanted = Wanted {
            required: desc.required,
            optional: desc.optional,
            prefer_cpu: desc.prefer_cpu,
            presents: Some(&presents),
        };
        match select::pick(&instance.raw, &wanted).and_then(|c| open(&instance.raw, c, true)) {
            Ok(opened) => {
                let mut host = Self::assemble(instance, opened);
                host.surface = Some(surface);
                Ok(host)
            }
            Err(e) => {
                surface.destroy();
                instance.destroy();
                Err(e)
            }
        }
    }

    fn assemble(instance: Instance, o: Opened) -> Self {
        Self {
            instance,
            #[cfg(feature = "window")]
            surface: None,
            physical_device: o.candidate.physical_device,
            device: o.device,
            family: o.candidate.family,
            queue: o.queue,
            allocator: o.allocator,
            enabled: o.candidate.enabled,
            device_name: o.candidate.name,
        }
    }

    /// The Vulkan loader's entry points.
    pub fn entry(&self) -> &ash::Entry {
        &self.instance.entry
    }

    /// The instance.
    pub fn instance(&self) -> &ash::Instance {
        &self.instance.raw
    }

    /// The physical device chosen.
    pub fn physical_device(&self) -> vk::PhysicalDevice {
        self.physical_device
    }

    /// The logical device.
    pub fn device(&self) -> &ash::Device {
        &self.device
    }

    /// The family of [`queue`](Self::queue): graphics and compute (and presentation,
    /// windowed).
    pub fn queue_family(&self) -> u32 {
        self.family
    }

    /// The queue the host submits to, and caveclod too.
    pub fn queue(&self) -> vk::Queue {
        self.queue
    }

    /// The gpu-allocator the host's images and caveclod's buffers come from.
    pub fn allocator(&self) -> &SharedAllocator {
        &self.allocator
    }

    /// Where the validation layer's messages go (stays empty without validation).
    pub fn log(&self) -> &Arc<ValidationLog> {
        &self.instance.log
    }

    /// Whether the validation layer is enabled.
    pub fn validation(&self) -> bool {
        self.instance.validation
    }

    /// The features enabled on the device.
    pub fn enabled(&self) -> DeviceFeatures {
        self.enabled
    }

    /// The physical device's name.
    pub fn device_name(&self) -> &str {
        &self.device_name
    }

    /// The window's surface and its loader (windowed hosts only).
    #[cfg(feature = "window")]
    pub(crate) fn surface(&self) -> Option<&Surface> {
        self.surface.as_ref()
    }

    /// The handles for `Context::from_raw`, with the host's allocator, claiming `claimed`
    /// (a host says what it enabled; claiming more is refused by the context).
    pub fn handles(&self, claimed: DeviceFeatures) -> HostDevice {
        HostDevice {
            instance: self.instance.raw.clone(),
            device: self.device.clone(),
            physical_device: self.physical_device,
            queue_family: self.family,
            queue: self.queue,
            allocator: Some(self.allocator.clone()),
            enabled: claimed,
        }
    }

    /// caveclod's context over this host's device, recording into the host's validation
    /// log. Destroy it before the host: [`Host::destroy`] refuses to destroy the device while
    /// a context holds the allocator.
    pub fn context(&self) -> Result<Context> {
        // SAFETY: the handles are this host's live instance, device (created from
        // `physical_device` with `enabled`), graphics + compute queue of `family` and the
        // allocator made for that device; `destroy` keeps them alive while a context holds
        // the allocator, and the host submits from the thread that uses the context.
        let ctx = unsafe { Context::from_raw(self.handles(self.enabled)) }?;
        Ok(if self.instance.validation {
            ctx.with_validation_log(self.instance.log.clone())
        } else {
            ctx
        })
    }

    /// The first of `candidates` the device can use as a depth(-stencil) attachment.
    pub fn depth_format(&self, candidates: &[vk::Format]) -> Result<vk::Format> {
        candidates
            .iter()
            .copied()
            .find(|&f| {
                // SAFETY: the physical device belongs to the instance.
                let p = unsafe {
                    self.instance
                        .raw
                        .get_physical_device_format_properties(self.physical_device, f)
                };
                p.optimal_tiling_features
                    .contains(vk::FormatFeatureFlags::DEPTH_STENCIL_ATTACHMENT)
            })
            .ok_or_else(|| {
                Error::InvalidArgument(format!(
                    "{}: none of {candidates:?} is a depth attachment format",
                    self.device_name
                ))
            })
    }

    /// Waits until the device is idle.
    pub fn wait_idle(&self) -> Result<()> {
        // SAFETY: the host submits from one thread, this one, so no submission races it.
        unsafe { self.device.device_wait_idle() }.vk("vkDeviceWaitIdle")
    }

    /// Tears down in reverse order of creation: the allocator (an error if it still has
    /// allocations), the device, the surface, the messenger and the instance. Everything
    /// made from the device must be destroyed first; while a context still holds the
    /// allocator nothing is destroyed (the device would go from under it) and the error
    /// says so. The validation log stays readable through a clone of [`log`](Self::log).
    pub fn destroy(self) -> Result<()> {
        let allocator = match Arc::try_unwrap(self.allocator) {
            Ok(a) => a.into_inner().unwrap_or_else(|p| p.into_inner()),
            Err(_) => {
                // The device, and the instance under it, stay alive for the context.
                return Err(Error::Teardown(
                    "a context (or another owner) still holds the host's allocator; \
                     destroy it first"
                        .into(),
                ));
            }
        };
        let report = allocator.generate_report();
        drop(allocator);
        // SAFETY: everything made from the device is destroyed (the caller's contract) and
        // the allocator has freed its memory.
        unsafe { self.device.destroy_device(None) };
        #[cfg(feature = "window")]
        if let Some(s) = self.surface {
            s.destroy();
        }
        self.instance.destroy();
        if report.allocations.is_empty() {
            Ok(())
        } else {
            let names: Vec<&str> = report.allocations.iter().map(|r| r.name.as_str()).collect();
            Err(Error::Teardown(format!(
                "{} allocation(s) left: {}",
                names.len(),
                names.join(", ")
            )))
        }
    }
}

/// A device made on a candidate.
struct Opened {
    candidate: Candidate,
    device: ash::Device,
    queue: vk::Queue,
    allocator: SharedAllocator,
}

/// The logical device with one queue of the candidate's family, its features and, when
/// `swapchain`, `VK_KHR_swapchain`; its queue and a gpu-allocator for it.
fn open(instance: &ash::Instance, c: Candidate, swapchain: bool) -> Result<Opened> {
    let priorities = [1.0];
    let queues = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(c.family)
        .queue_priorities(&priorities)];
    let extensions = [ash::khr::swapchain::NAME.as_ptr()];
    let mut info = vk::DeviceCreateInfo::default().queue_create_infos(&queues);
    if swapchain {
        info = info.enabled_extension_names(&extensions);
    }
    let mut chain = c.enabled.chain();
    let info = chain.push(info);
    // SAFETY: the features are within what the device supports (`select::pick`); every
    // pointer refers to locals alive for the call.
    let device =
        unsafe { instance.create_device(c.physical_device, &info, None) }.vk("vkCreateDevice")?;
    // SAFETY: queue 0 of `c.family` was requested at device creation.
    let queue = unsafe { device.get_device_queue(c.family, 0) };
    let allocator = Allocator::new(&AllocatorCreateDesc {
        instance: instance.clone(),
        device: device.clone(),
        physical_device: c.physical_device,
        debug_settings: AllocatorDebugSettings::default(),
        buffer_device_address: false,
        allocation_sizes: AllocationSizes::default(),
    });
    match allocator {
        Ok(a) => Ok(Opened {
            candidate: c,
            device,
            queue,
            allocator: Arc::new(Mutex::new(a)),
        }),
        Err(e) => {
            // SAFETY: nothing was created from the device.
            unsafe { device.destroy_device(None) };
            Err(crate::error::allocation("the host's allocator")(e))
        }
    }
}
