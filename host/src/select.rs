//! Which physical device the host takes: the best ranked of those that have what caveclod
//! needs (and, windowed, `VK_KHR_swapchain` and a queue family that presents), with the
//! features the host will enable on it.

use caveclod_vulkan::ash::{self, khr, vk};
use caveclod_vulkan::{DeviceFeatures, API_VERSION};

use crate::error::{Error, Result, VkExt};

/// What the host asks of a device.
pub(crate) struct Wanted<'a> {
    /// Features it must support; all are enabled.
    pub required: DeviceFeatures,
    /// Features enabled where supported.
    pub optional: DeviceFeatures,
    /// Rank CPU devices (lavapipe) first, else GPUs first.
    pub prefer_cpu: bool,
    /// Whether queue family `f` of a device presents to the window's surface (windowed);
    /// a device also needs `VK_KHR_swapchain` then.
    pub presents: Option<&'a dyn Fn(vk::PhysicalDevice, u32) -> bool>,
}

/// A physical device that qualifies, with what the host will enable on it.
pub(crate) struct Candidate {
    pub physical_device: vk::PhysicalDevice,
    /// A graphics + compute queue family (presenting, when windowed).
    pub family: u32,
    pub kind: vk::PhysicalDeviceType,
    pub name: String,
    /// The required features and the supported optional ones.
    pub enabled: DeviceFeatures,
}

/// The best ranked device that qualifies; the error names each device and what it lacks.
pub(crate) fn pick(instance: &ash::Instance, wanted: &Wanted<'_>) -> Result<Candidate> {
    // SAFETY: plain enumeration.
    let devices =
        unsafe { instance.enumerate_physical_devices() }.vk("vkEnumeratePhysicalDevices")?;
    let mut reasons = Vec::new();
    let mut best: Option<Candidate> = None;
    for pd in devices {
        match qualify(instance, wanted, pd) {
            Ok(c) => {
                let rank = |c: &Candidate| rank(c.kind, wanted.prefer_cpu);
                if best.as_ref().is_none_or(|b| rank(&c) < rank(b)) {
                    best = Some(c);
                }
            }
            Err(why) => reasons.push(why),
        }
    }
    best.ok_or_else(|| {
        Error::NoDevice(if reasons.is_empty() {
            "none found (install Mesa's lavapipe: mesa-vulkan-drivers)".to_string()
        } else {
            reasons.join("; ")
        })
    })
}

/// Lower ranks first: CPU devices first when preferred, then discrete, integrated and
/// virtual GPUs.
fn rank(kind: vk::PhysicalDeviceType, prefer_cpu: bool) -> u32 {
    match kind {
        vk::PhysicalDeviceType::CPU if prefer_cpu => 0,
        vk::PhysicalDeviceType::DISCRETE_GPU => 1,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 2,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 3,
        vk::PhysicalDeviceType::CPU => 4,
        _ => 5,
    }
}

/// `pd` as a candidate, or why it does not qualify.
fn qualify(
    instance: &ash::Instance,
    wanted: &Wanted<'_>,
    pd: vk::PhysicalDevice,
) -> std::result::Result<Candidate, String> {
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
    let missing = supported.missing(wanted.required);
    if !missing.is_empty() {
        return Err(format!("{name}: lacks {}", missing.join(", ")));
    }
    if wanted.presents.is_some() && !has_swapchain(instance, pd)? {
        return Err(format!("{name}: no VK_KHR_swapchain"));
    }
    // SAFETY: as above.
    let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    let want = vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE;
    let family = (0..families.len() as u32)
        .find(|&i| {
            let f = &families[i as usize];
            f.queue_flags.contains(want)
                && f.queue_count > 0
                && wanted.presents.is_none_or(|presents| presents(pd, i))
        })
        .ok_or_else(|| match wanted.presents {
            Some(_) => format!("{name}: no graphics + compute queue that presents"),
            None => format!("{name}: no graphics + compute queue"),
        })?;
    Ok(Candidate {
        physical_device: pd,
        family,
        kind: props.device_type,
        name,
        enabled: either(wanted.required, supported.and(wanted.optional)),
    })
}

/// Whether `pd` offers `VK_KHR_swapchain`.
fn has_swapchain(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
) -> std::result::Result<bool, String> {
    // SAFETY: `pd` was enumerated from `instance`.
    let extensions = unsafe { instance.enumerate_device_extension_properties(pd) }
        .map_err(|e| format!("vkEnumerateDeviceExtensionProperties: {e}"))?;
    Ok(extensions
        .iter()
        .any(|e| e.extension_name_as_c_str() == Ok(khr::swapchain::NAME)))
}

/// The features either of `a` and `b` has.
fn either(a: DeviceFeatures, b: DeviceFeatures) -> DeviceFeatures {
    DeviceFeatures {
        synchronization2: a.synchronization2 || b.synchronization2,
        dynamic_rendering: a.dynamic_rendering || b.dynamic_rendering,
        vulkan_memory_model: a.vulkan_memory_model || b.vulkan_memory_model,
        fill_mode_non_solid: a.fill_mode_non_solid || b.fill_mode_non_solid,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpu_devices_rank_first_only_when_preferred() {
        let cpu = vk::PhysicalDeviceType::CPU;
        let gpu = vk::PhysicalDeviceType::DISCRETE_GPU;
        assert!(rank(cpu, true) < rank(gpu, true));
        assert!(rank(gpu, false) < rank(cpu, false));
        assert!(rank(vk::PhysicalDeviceType::INTEGRATED_GPU, false) < rank(cpu, false));
    }

    #[test]
    fn optional_features_add_to_the_required_ones() {
        let wire = DeviceFeatures {
            fill_mode_non_solid: true,
            ..DeviceFeatures::default()
        };
        assert_eq!(either(DeviceFeatures::REQUIRED, wire), DeviceFeatures::ALL);
        assert_eq!(
            either(DeviceFeatures::REQUIRED, DeviceFeatures::default()),
            DeviceFeatures::REQUIRED
        );
    }
}
