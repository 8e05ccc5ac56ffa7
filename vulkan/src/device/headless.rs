//! The headless path: an instance of this crate's own, the physical devices ranked
//! (lavapipe first when asked) and the first that qualifies made a logical device.

use ash::vk;

use super::{device_name, Context, HostDevice};
use crate::error::{Error, Result, VkResultExt};
use crate::instance::{self, OwnedInstance};
use crate::requirements::{self, DeviceFeatures};
use crate::validation::ValidationLog;

/// How to create a headless context.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HeadlessDesc {
    /// Enable `VK_LAYER_KHRONOS_validation` (when installed) and record its messages.
    pub validation: bool,
    /// Prefer a CPU device (lavapipe) over GPUs: deterministic images for tests.
    pub prefer_lavapipe: bool,
    /// With `validation`, also enable the layer's synchronization validation (hazards
    /// between commands, and between submissions on the queue, reported as messages).
    pub synchronization_validation: bool,
}

impl Default for HeadlessDesc {
    fn default() -> Self {
        Self {
            validation: true,
            prefer_lavapipe: true,
            synchronization_validation: false,
        }
    }
}

/// A device picked and created by the headless path.
struct PickedDevice {
    physical_device: vk::PhysicalDevice,
    family: u32,
    device: ash::Device,
    name: String,
    enabled: DeviceFeatures,
}

/// The queue family and device kind of a physical device that has what this crate needs
/// (the `requirements` module's table), or why it does not qualify.
fn qualify(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
) -> std::result::Result<(u32, vk::PhysicalDeviceType, String, DeviceFeatures), String> {
    // SAFETY: `pd` was enumerated from `instance`.
    let props = unsafe { instance.get_physical_device_properties(pd) };
    let name = device_name(&props);
    // SAFETY: as above.
    let supported = unsafe { DeviceFeatures::supported(instance, pd) };
    let missing = requirements::shortfall(props.api_version, supported, DeviceFeatures::REQUIRED);
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
    Ok((
        family as u32,
        props.device_type,
        name,
        supported.and(DeviceFeatures::ALL),
    ))
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
    /// device with [`DeviceFeatures::REQUIRED`] (plus `fillModeNonSolid` where supported)
    /// and an allocator.
    pub fn headless(desc: &HeadlessDesc) -> Result<Self> {
        let log = ValidationLog::new();
        let owned = instance::create(desc.validation, desc.synchronization_validation, &log)?;
        match Self::headless_device(&owned, desc.prefer_lavapipe) {
            Ok(picked) => {
                let device = picked.device.clone();
                // SAFETY: queue 0 of `family` was requested at device creation.
                let queue = unsafe { device.get_device_queue(picked.family, 0) };
                let host = HostDevice {
                    instance: owned.instance.clone(),
                    device: picked.device,
                    physical_device: picked.physical_device,
                    queue_family: picked.family,
                    queue,
                    allocator: None,
                    enabled: picked.enabled,
                };
                let validation = owned.validation;
                match Self::assemble(host, log, picked.name) {
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

    fn headless_device(owned: &OwnedInstance, prefer_lavapipe: bool) -> Result<PickedDevice> {
        let instance = &owned.instance;
        // SAFETY: plain enumeration.
        let devices =
            unsafe { instance.enumerate_physical_devices() }.vk("vkEnumeratePhysicalDevices")?;
        let mut rejected = Vec::new();
        let mut best: Option<(u32, vk::PhysicalDevice, u32, String, DeviceFeatures)> = None;
        for pd in devices {
            match qualify(instance, pd) {
                Ok((family, kind, name, features)) => {
                    let r = rank(kind, prefer_lavapipe);
                    if best.as_ref().is_none_or(|b| r < b.0) {
                        best = Some((r, pd, family, name, features));
                    }
                }
                Err(why) => rejected.push(why),
            }
        }
        let Some((_, pd, family, name, enabled)) = best else {
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
        let mut f10 = vk::PhysicalDeviceFeatures::default();
        let mut f12 = vk::PhysicalDeviceVulkan12Features::default();
        let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
        enabled.enable(&mut f10, &mut f12, &mut f13);
        let info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queues)
            .enabled_features(&f10)
            .push_next(&mut f12)
            .push_next(&mut f13);
        // SAFETY: `pd` qualified and `enabled` is within what it supports; pointers are to
        // locals.
        let device = unsafe { instance.create_device(pd, &info, None) }.vk("vkCreateDevice")?;
        Ok(PickedDevice {
            physical_device: pd,
            family,
            device,
            name,
            enabled,
        })
    }
}
