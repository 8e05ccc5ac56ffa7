//! The [`Context`]: instance, device, queue and allocator, headless or embedded (the
//! design decisions are on the type).

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, Allocator, AllocatorCreateDesc};
use gpu_allocator::{AllocationSizes, AllocatorDebugSettings};

use crate::error::{from_allocation, Error, Result, VkResultExt};
use crate::fault::Faults;
use crate::instance::OwnedInstance;
use crate::requirements::{self, DeviceFeatures};
use crate::validation::ValidationLog;

pub(crate) mod headless;

/// A host engine's device, handed to [`Context::from_raw`].
pub struct HostDevice {
    /// The host's instance.
    pub instance: ash::Instance,
    /// The host's logical device.
    pub device: ash::Device,
    /// Its physical device.
    pub physical_device: vk::PhysicalDevice,
    /// The family of `queue`.
    pub queue_family: u32,
    /// A queue this crate may submit to (uploads, headless frames, compute read-backs); the
    /// record path never submits.
    pub queue: vk::Queue,
    /// The host's allocator, or `None` to let the context make its own.
    pub allocator: Option<SharedAllocator>,
    /// The features the host enabled on `device` (at least [`DeviceFeatures::REQUIRED`];
    /// [`DeviceFeatures::chain`] or [`DeviceFeatures::enable`] sets them in its create info).
    pub enabled: DeviceFeatures,
}

impl HostDevice {
    /// The host's handles, claiming [`DeviceFeatures::REQUIRED`] (what
    /// `DeviceFeatures::REQUIRED.chain()` enables), without an allocator (the context makes
    /// its own unless [`allocator`](Self::allocator) gives the host's).
    pub fn new(
        instance: &ash::Instance,
        device: &ash::Device,
        physical_device: vk::PhysicalDevice,
        queue_family: u32,
        queue: vk::Queue,
    ) -> Self {
        Self {
            instance: instance.clone(),
            device: device.clone(),
            physical_device,
            queue_family,
            queue,
            allocator: None,
            enabled: DeviceFeatures::REQUIRED,
        }
    }

    /// Shares the host's `allocator` with the context.
    pub fn allocator(self, allocator: SharedAllocator) -> Self {
        Self {
            allocator: Some(allocator),
            ..self
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
///   and must have enabled [`DeviceFeatures::REQUIRED`], which `from_raw` checks.
/// - **Headless** ([`Context::headless`]) creates all of it, prefers lavapipe when asked (the
///   tests, the CLI) and enables `VK_LAYER_KHRONOS_validation` when installed.
/// - **Resources are tracked.** Every buffer and image made through a context is registered
///   by name until destroyed; [`Context::destroy`] reports what is still alive as
///   [`Error::Leaked`] (gpu-allocator would only log it), then frees the allocator before
///   the device, as gpu-allocator requires.
/// - **Faults can be injected** ([`Context::faults`]): every device allocation and every
///   call that can report a lost device passes one seam, so tests run out of memory or lose
///   the device at any of them (the decisions are on [`Faults`]).
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
    features: DeviceFeatures,
    live: Mutex<BTreeMap<u64, String>>,
    next_id: AtomicU64,
    vertex_uploads: AtomicU64,
    faults: Faults,
    destroyed: bool,
}

fn device_name(props: &vk::PhysicalDeviceProperties) -> String {
    props
        .device_name_as_c_str()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|_| "unnamed device".into())
}

impl Context {
    /// Wraps a host engine's instance, device and queue (and optionally its allocator). The
    /// host keeps ownership of all of them: [`destroy`](Self::destroy) only releases what
    /// this crate made. Without an allocator, one is created (and freed on destroy).
    ///
    /// Refuses with [`Error::Unsupported`] a device older than
    /// [`API_VERSION`](crate::API_VERSION), or whose `host.enabled` lacks one of
    /// [`DeviceFeatures::REQUIRED`] or claims a feature the physical device does not
    /// support; each missing item is named.
    ///
    /// # Safety
    /// - `host.device` was created from `host.physical_device`, which was enumerated from
    ///   `host.instance`; all three outlive the context.
    /// - `host.enabled` is no more than what the device was created with.
    /// - `host.queue` is queue of family `host.queue_family` of that device, supporting
    ///   graphics (and compute, for [`Geomorph`](crate::Geomorph)); the host does not submit
    ///   to it while a call of this crate that submits ([`Context::submit_and_wait`],
    ///   [`Renderer::render`](crate::Renderer::render), uploads) runs on another thread.
    /// - `host.allocator`, if given, was made for that instance and device.
    pub unsafe fn from_raw(host: HostDevice) -> Result<Self> {
        // SAFETY: `physical_device` belongs to `instance` (the caller's contract).
        let props = unsafe {
            host.instance
                .get_physical_device_properties(host.physical_device)
        };
        let name = device_name(&props);
        // SAFETY: as above.
        let supported = unsafe { DeviceFeatures::supported(&host.instance, host.physical_device) };
        let missing = requirements::shortfall(props.api_version, supported, host.enabled);
        if !missing.is_empty() {
            return Err(Error::Unsupported {
                device: name,
                missing,
            });
        }
        Self::assemble(host, ValidationLog::new(), name)
    }

    /// The device features this context may use (enabled on its device).
    pub fn features(&self) -> DeviceFeatures {
        self.features
    }

    /// Records validation messages into the host's `log` (the one its debug messenger
    /// fills, e.g. a [`DebugMessenger`](crate::DebugMessenger)), so
    /// [`take_validation_messages`](Self::take_validation_messages) sees them.
    pub fn with_validation_log(mut self, log: Arc<ValidationLog>) -> Self {
        self.log = log;
        self.validation = true;
        self
    }

    fn assemble(host: HostDevice, log: Arc<ValidationLog>, device_name: String) -> Result<Self> {
        let HostDevice {
            instance,
            device,
            physical_device,
            queue_family,
            queue,
            allocator,
            enabled,
        } = host;
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
            features: enabled,
            live: Mutex::new(BTreeMap::new()),
            next_id: AtomicU64::new(0),
            vertex_uploads: AtomicU64::new(0),
            faults: Faults::default(),
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

    /// The allocator's report: its live allocations and memory blocks (a host's too, when
    /// the allocator is shared). After every resource is destroyed, a context's own
    /// allocator reports no allocation.
    pub fn allocator_report(&self) -> Result<gpu_allocator::AllocatorReport> {
        Ok(self.allocator()?.generate_report())
    }

    /// The fault plan: out-of-memory and device-loss injection for tests, and the counts
    /// of allocations and device checkpoints.
    pub fn faults(&self) -> &Faults {
        &self.faults
    }

    /// Allocates device memory for `desc` through the fault seam and the allocator.
    pub(crate) fn allocate(&self, desc: &AllocationCreateDesc<'_>) -> Result<Allocation> {
        self.faults.allocation(desc.name)?;
        self.allocator()?
            .allocate(desc)
            .map_err(|e| from_allocation(desc.name, e))
    }

    /// Frees an allocation made by [`allocate`](Self::allocate).
    pub(crate) fn free(&self, what: &str, allocation: Allocation) -> Result<()> {
        self.allocator()?
            .free(allocation)
            .map_err(|e| from_allocation(what, e))
    }

    /// The device checkpoint before `call` (one that can report a lost device): an
    /// injected loss is reported here.
    pub(crate) fn checkpoint(&self, call: &'static str) -> Result<()> {
        self.faults.checkpoint(call)
    }

    /// Waits for `fences` before destroying what their work uses: no checkpoint, and a
    /// lost device counts as done (its objects may be destroyed).
    pub(crate) fn wait_for_teardown(&self, fences: &[vk::Fence]) -> Result<()> {
        if fences.is_empty() {
            return Ok(());
        }
        // SAFETY: the caller passes live fences of this device.
        match unsafe { self.device.wait_for_fences(fences, true, u64::MAX) } {
            Ok(()) | Err(vk::Result::ERROR_DEVICE_LOST) => Ok(()),
            Err(e) => Err(crate::error::from_vk("vkWaitForFences", e)),
        }
    }

    /// Waits for the device before tearing down: no checkpoint, and a lost device counts
    /// as idle.
    pub(crate) fn idle_for_teardown(&self) -> Result<()> {
        let _q = self.queue();
        // SAFETY: the queue lock is held, so no submission races the wait.
        match unsafe { self.device.device_wait_idle() } {
            Ok(()) | Err(vk::Result::ERROR_DEVICE_LOST) => Ok(()),
            Err(e) => Err(crate::error::from_vk("vkDeviceWaitIdle", e)),
        }
    }

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

    /// The queue, locked for submission.
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

    /// Buffers and images made through this context so far (destroyed ones included): a
    /// frame loop that allocates nothing leaves it unchanged.
    pub fn resources_created(&self) -> u64 {
        self.next_id.load(Ordering::Relaxed)
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

    /// Runs `f` with the context's queue, locked against this crate's own submissions for
    /// the duration (for a tool on a headless context that submits frames it recorded
    /// itself; an embedding host already has its queue).
    pub fn with_queue<R>(&self, f: impl FnOnce(vk::Queue) -> R) -> R {
        let q = self.queue();
        f(*q)
    }

    /// Waits until the device is idle.
    pub fn wait_idle(&self) -> Result<()> {
        self.checkpoint("vkDeviceWaitIdle")?;
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
            let waited = self
                .checkpoint("vkQueueSubmit2")
                .and_then(|()| {
                    let q = self.queue();
                    // SAFETY: `cmd` is executable; the queue lock serialises submissions.
                    unsafe { d.queue_submit2(*q, &submit, fence) }.vk("vkQueueSubmit2")
                })
                .and_then(|()| self.checkpoint("vkWaitForFences"))
                .and_then(|()| {
                    // SAFETY: `fence` was just submitted.
                    unsafe { d.wait_for_fences(&[fence], true, u64::MAX) }.vk("vkWaitForFences")
                });
            if waited.is_err() {
                // Neither the fence nor the pool may be destroyed while its commands run.
                let _ = self.idle_for_teardown();
            }
            // SAFETY: the fence is signalled, was never submitted, or the device is idle.
            unsafe { d.destroy_fence(fence, None) };
            waited
        })();
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
        let idle = self.idle_for_teardown();
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
