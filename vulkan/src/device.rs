//! The [`Context`]: instance, device, queue and allocator, headless or embedded (the
//! design decisions are on the type).

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use gpu_allocator::{AllocationSizes, AllocatorDebugSettings};

use crate::error::{Error, Result, VkResultExt};
use crate::instance::{self, OwnedInstance};
use crate::validation::ValidationLog;

/// How to create a headless context.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HeadlessDesc {
    /// Enable `VK_LAYER_KHRONOS_validation` (when installed) and record its messages.
    pub validation: bool,
    /// Prefer a CPU device (lavapipe) over GPUs: deterministic images for tests.
    pub prefer_lavapipe: bool,
}

impl Default for HeadlessDesc {
    fn default() -> Self {
        Self {
            validation: true,
            prefer_lavapipe: true,
        }
    }
}

/// A shared gpu-allocator, as a host engine would hold it.
pub type SharedAllocator = Arc<Mutex<Allocator>>;

/// Instance, device, queue and allocator, either created here (headless) or borrowed from
/// a host engine (embedded).
///
/// Design decisions:
/// - **Embedding never creates an instance.** [`Context::from_raw`] takes the host's handles
///   (and optionally its gpu-allocator) and destroys none of them; the host keeps ownership
///   and must have enabled what the shaders need: Vulkan 1.3 `dynamicRendering` and
///   `synchronization2`, Vulkan 1.2 `vulkanMemoryModel`.
/// - **Headless** ([`Context::headless`]) creates all of it, prefers lavapipe when asked (the
///   tests, the CLI) and enables `VK_LAYER_KHRONOS_validation` when installed.
/// - **Resources are tracked.** Every buffer and image made through a context is registered
///   by name until destroyed; [`Context::destroy`] reports what is still alive as
///   [`Error::Leaked`] (gpu-allocator would only log it), then frees the allocator before
///   the device, as gpu-allocator requires.
/// - One queue, used under a mutex, for graphics, compute and transfer.
pub struct Context {
    /// The instance.
    pub instance: ash::Instance,
    /// The logical device.
    pub device: ash::Device,
    /// Its physical device.
    pub physical_device: vk::PhysicalDevice,
    /// The queue family of the context's queue (graphics + compute).
    pub queue_family: u32,
    queue: Mutex<vk::Queue>,
    allocator: Option<SharedAllocator>,
    owned: Option<OwnedInstance>,
    log: Arc<ValidationLog>,
    validation: bool,
    device_name: String,
    live: Mutex<BTreeMap<u64, String>>,
    next_id: AtomicU64,
    vertex_uploads: AtomicU64,
    destroyed: bool,
}

/// What the renderer needs of a physical device, or why it does not qualify.
fn qualify(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
) -> std::result::Result<(u32, vk::PhysicalDeviceType, String), String> {
    // SAFETY: `pd` was enumerated from `instance`.
    let props = unsafe { instance.get_physical_device_properties(pd) };
    let name = props
        .device_name_as_c_str()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|_| "unnamed device".into());
    if props.api_version < vk::API_VERSION_1_3 {
        return Err(format!("{name}: Vulkan 1.3 needed"));
    }
    let mut f12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
    let mut f2 = vk::PhysicalDeviceFeatures2::default()
        .push_next(&mut f12)
        .push_next(&mut f13);
    // SAFETY: the chain holds structures alive for the call.
    unsafe { instance.get_physical_device_features2(pd, &mut f2) };
    let mut missing = Vec::new();
    if f13.dynamic_rendering == vk::FALSE {
        missing.push("dynamicRendering");
    }
    if f13.synchronization2 == vk::FALSE {
        missing.push("synchronization2");
    }
    if f12.vulkan_memory_model == vk::FALSE {
        missing.push("vulkanMemoryModel");
    }
    if !missing.is_empty() {
        return Err(format!("{name}: lacks {}", missing.join(", ")));
    }
    // SAFETY: as above.
    let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    let want = vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE;
    let family = families
        .iter()
        .position(|f| f.queue_flags.contains(want) && f.queue_count > 0)
        .ok_or_else(|| format!("{name}: no graphics + compute queue"))?;
    Ok((family as u32, props.device_type, name))
}

fn rank(kind: vk::PhysicalDeviceType, prefer_lavapipe: bool) -> u32 {
    match kind {
        vk::PhysicalDeviceType::CPU if prefer_lavapipe => 0,
        vk::PhysicalDeviceType::DISCRETE_GPU => 1,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 2,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 3,
        _ => 4,
    }
}

impl Context {
    /// Creates an instance, picks a device (see [`HeadlessDesc`]) and creates a logical
    /// device with Vulkan 1.3 `dynamicRendering` + `synchronization2` and Vulkan 1.2
    /// `vulkanMemoryModel`, and an allocator.
    pub fn headless(desc: &HeadlessDesc) -> Result<Self> {
        let log = ValidationLog::new();
        let owned = instance::create(desc.validation, &log)?;
        match Self::headless_device(&owned, desc.prefer_lavapipe) {
            Ok((pd, family, device, name)) => {
                // SAFETY: queue 0 of `family` was requested at device creation.
                let queue = unsafe { device.get_device_queue(family, 0) };
                let validation = owned.validation;
                match Self::assemble(
                    owned.instance.clone(),
                    device.clone(),
                    pd,
                    family,
                    queue,
                    None,
                    log,
                    name,
                ) {
                    Ok(mut ctx) => {
                        ctx.validation = validation;
                        ctx.owned = Some(owned);
                        Ok(ctx)
                    }
                    Err(e) => {
                        // SAFETY: nothing was created from the device.
                        unsafe { device.destroy_device(None) };
                        if let Some(m) = owned.messenger {
                            m.destroy();
                        }
                        // SAFETY: device and messenger are gone.
                        unsafe { owned.instance.destroy_instance(None) };
                        Err(e)
                    }
                }
            }
            Err(e) => {
                if let Some(m) = owned.messenger {
                    m.destroy();
                }
                // SAFETY: no object created from the instance is alive.
                unsafe { owned.instance.destroy_instance(None) };
                Err(e)
            }
        }
    }

    fn headless_device(
        owned: &OwnedInstance,
        prefer_lavapipe: bool,
    ) -> Result<(vk::PhysicalDevice, u32, ash::Device, String)> {
        let instance = &owned.instance;
        // SAFETY: plain enumeration.
        let devices =
            unsafe { instance.enumerate_physical_devices() }.vk("vkEnumeratePhysicalDevices")?;
        let mut rejected = Vec::new();
        let mut best: Option<(u32, vk::PhysicalDevice, u32, String)> = None;
        for pd in devices {
            match qualify(instance, pd) {
                Ok((family, kind, name)) => {
                    let r = rank(kind, prefer_lavapipe);
                    if best.as_ref().is_none_or(|b| r < b.0) {
                        best = Some((r, pd, family, name));
                    }
                }
                Err(why) => rejected.push(why),
            }
        }
        let Some((_, pd, family, name)) = best else {
            return Err(Error::NoDevice(if rejected.is_empty() {
                "no Vulkan physical device found (install Mesa's lavapipe: mesa-vulkan-drivers)"
                    .into()
            } else {
                rejected.join("; ")
            }));
        };
        let priorities = [1.0f32];
        let queues = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(family)
            .queue_priorities(&priorities)];
        let mut f12 = vk::PhysicalDeviceVulkan12Features::default().vulkan_memory_model(true);
        let mut f13 = vk::PhysicalDeviceVulkan13Features::default()
            .dynamic_rendering(true)
            .synchronization2(true);
        let info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queues)
            .push_next(&mut f12)
            .push_next(&mut f13);
        // SAFETY: `pd` qualified (the features are supported); pointers are to locals.
        let device = unsafe { instance.create_device(pd, &info, None) }.vk("vkCreateDevice")?;
        Ok((pd, family, device, name))
    }

    /// Wraps a host engine's instance, device and queue (and optionally its allocator). The
    /// host keeps ownership of all of them: [`destroy`](Self::destroy) only releases what
    /// this crate made. The device must have Vulkan 1.3 `dynamicRendering` and
    /// `synchronization2` and Vulkan 1.2 `vulkanMemoryModel` enabled; `queue` must support
    /// graphics and compute. Without an allocator, one is created (and freed on destroy).
    pub fn from_raw(
        instance: ash::Instance,
        device: ash::Device,
        physical_device: vk::PhysicalDevice,
        queue_family: u32,
        queue: vk::Queue,
        allocator: Option<SharedAllocator>,
    ) -> Result<Self> {
        // SAFETY: `physical_device` belongs to `instance` (the caller's contract).
        let props = unsafe { instance.get_physical_device_properties(physical_device) };
        let name = props
            .device_name_as_c_str()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        Self::assemble(
            instance,
            device,
            physical_device,
            queue_family,
            queue,
            allocator,
            ValidationLog::new(),
            name,
        )
    }

    /// Records validation messages into the host's `log` (the one its debug messenger
    /// fills, e.g. a [`DebugMessenger`](crate::DebugMessenger)), so
    /// [`take_validation_messages`](Self::take_validation_messages) sees them.
    pub fn with_validation_log(mut self, log: Arc<ValidationLog>) -> Self {
        self.log = log;
        self.validation = true;
        self
    }

    #[allow(clippy::too_many_arguments)]
    fn assemble(
        instance: ash::Instance,
        device: ash::Device,
        physical_device: vk::PhysicalDevice,
        queue_family: u32,
        queue: vk::Queue,
        allocator: Option<SharedAllocator>,
        log: Arc<ValidationLog>,
        device_name: String,
    ) -> Result<Self> {
        let allocator = match allocator {
            Some(a) => a,
            None => {
                let a = Allocator::new(&AllocatorCreateDesc {
                    instance: instance.clone(),
                    device: device.clone(),
                    physical_device,
                    debug_settings: AllocatorDebugSettings::default(),
                    buffer_device_address: false,
                    allocation_sizes: AllocationSizes::default(),
                })
                .map_err(|e| crate::error::from_allocation("the allocator", e))?;
                Arc::new(Mutex::new(a))
            }
        };
        Ok(Self {
            instance,
            device,
            physical_device,
            queue_family,
            queue: Mutex::new(queue),
            allocator: Some(allocator),
            owned: None,
            log,
            validation: false,
            device_name,
            live: Mutex::new(BTreeMap::new()),
            next_id: AtomicU64::new(0),
            vertex_uploads: AtomicU64::new(0),
            destroyed: false,
        })
    }

    /// The physical device's name (e.g. "llvmpipe (LLVM 19.1.7, 256 bits)").
    pub fn device_name(&self) -> &str {
        &self.device_name
    }

    /// `true` if validation messages are being recorded (the layer is enabled, or the host
    /// handed over its log).
    pub fn validation_enabled(&self) -> bool {
        self.validation
    }

    /// The validation log (messages of the layer at ERROR and WARNING severity).
    pub fn validation_log(&self) -> Arc<ValidationLog> {
        self.log.clone()
    }

    /// Removes and returns the validation messages recorded so far.
    pub fn take_validation_messages(&self) -> Vec<String> {
        self.log.take()
    }

    /// The allocator (shared with the host in embed mode).
    pub(crate) fn allocator(&self) -> Result<MutexGuard<'_, Allocator>> {
        let a = self
            .allocator
            .as_ref()
            .ok_or_else(|| Error::InvalidArgument("context already destroyed".into()))?;
        Ok(match a.lock() {
            Ok(g) => g,
            Err(p) => p.into_inner(),
        })
    }

    /// The queue, locked for submission.
    /// One primary command buffer from `pool`, which must be a live pool of this device.
    pub(crate) fn allocate_command_buffer(
        &self,
        pool: vk::CommandPool,
    ) -> Result<vk::CommandBuffer> {
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: the caller passes a live pool of this device.
        unsafe { self.device.allocate_command_buffers(&alloc) }
            .vk("vkAllocateCommandBuffers")?
            .first()
            .copied()
            .ok_or_else(|| Error::InvalidArgument("no command buffer allocated".into()))
    }

    pub(crate) fn queue(&self) -> MutexGuard<'_, vk::Queue> {
        match self.queue.lock() {
            Ok(g) => g,
            Err(p) => p.into_inner(),
        }
    }

    /// Registers a live resource; returns its tracking id.
    pub(crate) fn track(&self, name: &str) -> u64 {
        let id = self.next_id.fetch_add(1, Ordering::Relaxed);
        match self.live.lock() {
            Ok(mut l) => l.insert(id, name.to_string()),
            Err(p) => p.into_inner().insert(id, name.to_string()),
        };
        id
    }

    /// Unregisters a destroyed resource.
    pub(crate) fn untrack(&self, id: u64) {
        match self.live.lock() {
            Ok(mut l) => l.remove(&id),
            Err(p) => p.into_inner().remove(&id),
        };
    }

    /// Names of the resources made through this context and not destroyed yet.
    pub fn live_resources(&self) -> Vec<String> {
        match self.live.lock() {
            Ok(l) => l.values().cloned().collect(),
            Err(p) => p.into_inner().values().cloned().collect(),
        }
    }

    /// Counts one upload into a device-local vertex buffer.
    pub(crate) fn count_vertex_upload(&self) {
        self.vertex_uploads.fetch_add(1, Ordering::Relaxed);
    }

    /// Uploads into device-local vertex buffers since the context was made (each mesh's
    /// buffer is written exactly once, at creation).
    pub fn vertex_uploads(&self) -> u64 {
        self.vertex_uploads.load(Ordering::Relaxed)
    }

    /// Waits until the device is idle.
    pub fn wait_idle(&self) -> Result<()> {
        let _q = self.queue();
        // SAFETY: the queue lock is held, so no submission races the wait.
        unsafe { self.device.device_wait_idle() }.vk("vkDeviceWaitIdle")
    }

    /// Records commands with `record` into a one-time command buffer, submits it and waits
    /// for it (uploads, compute dispatches, readbacks outside frames).
    pub fn submit_and_wait(&self, record: impl FnOnce(vk::CommandBuffer)) -> Result<()> {
        let d = &self.device;
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(self.queue_family)
            .flags(vk::CommandPoolCreateFlags::TRANSIENT);
        // SAFETY: valid create info.
        let pool = unsafe { d.create_command_pool(&pool_info, None) }.vk("vkCreateCommandPool")?;
        let result = (|| {
            let cmd = self.allocate_command_buffer(pool)?;
            let begin = vk::CommandBufferBeginInfo::default()
                .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
            // SAFETY: `cmd` is fresh.
            unsafe { d.begin_command_buffer(cmd, &begin) }.vk("vkBeginCommandBuffer")?;
            record(cmd);
            // SAFETY: `cmd` is recording.
            unsafe { d.end_command_buffer(cmd) }.vk("vkEndCommandBuffer")?;
            // SAFETY: valid create info.
            let fence = unsafe { d.create_fence(&vk::FenceCreateInfo::default(), None) }
                .vk("vkCreateFence")?;
            let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
            let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cmds)];
            let waited = {
                let q = self.queue();
                // SAFETY: `cmd` is executable; the queue lock serialises submissions.
                unsafe { d.queue_submit2(*q, &submit, fence) }.vk("vkQueueSubmit2")
            }
            .and_then(|()| {
                // SAFETY: `fence` was just submitted.
                unsafe { d.wait_for_fences(&[fence], true, u64::MAX) }.vk("vkWaitForFences")
            });
            // SAFETY: the fence is signalled or was never submitted.
            unsafe { d.destroy_fence(fence, None) };
            waited
        })();
        if result.is_err() {
            // Do not free a pool whose commands may still run.
            let _ = self.wait_idle();
        }
        // SAFETY: its command buffer has completed (or the device is idle).
        unsafe { d.destroy_command_pool(pool, None) };
        result
    }

    /// Destroys what this context made, in order: waits for the device, checks for live
    /// resources, frees the allocator (before the device), then — headless only — the
    /// device, the messenger and the instance. Live resources are reported as
    /// [`Error::Leaked`] after the teardown.
    pub fn destroy(mut self) -> Result<()> {
        self.teardown()
    }

    fn teardown(&mut self) -> Result<()> {
        if self.destroyed {
            return Ok(());
        }
        self.destroyed = true;
        let idle = self.wait_idle();
        let leaked = self.live_resources();
        if let Some(a) = self.allocator.take() {
            // Our own allocator: drop it now, before the device. A host's: just our clone.
            drop(a);
        }
        if let Some(owned) = self.owned.take() {
            // SAFETY: the device is idle and every object this crate made from it is gone
            // (or reported as leaked); the allocator has been dropped.
            unsafe { self.device.destroy_device(None) };
            if let Some(m) = owned.messenger {
                m.destroy();
            }
            // SAFETY: the device and messenger created from the instance are destroyed.
            unsafe { owned.instance.destroy_instance(None) };
            drop(owned.entry);
        }
        idle?;
        if leaked.is_empty() {
            Ok(())
        } else {
            Err(Error::Leaked(leaked))
        }
    }
}

impl Drop for Context {
    fn drop(&mut self) {
        // Explicit `destroy` is the API; this only keeps a forgotten context from leaking
        // its device and instance.
        let _ = self.teardown();
    }
}
