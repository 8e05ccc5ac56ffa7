//! What caveclod-vulkan needs of a device, in one place.
//!
//! | what | needed for |
//! |---|---|
//! | Vulkan 1.3 (instance and device) | synchronization2 barriers, dynamic rendering |
//! | `synchronization2` (1.3 feature) | every barrier this crate records (uploads, the headless renderer) |
//! | `dynamicRendering` (1.3 feature) | [`Rendering::Dynamic`](crate::Rendering) and the headless [`Renderer`](crate::Renderer); not used when the host records inside its own `VkRenderPass` |
//! | `vulkanMemoryModel` (1.2 feature) | the committed SPIR-V declares the `VulkanMemoryModel` capability |
//! | `fillModeNonSolid` (1.0 feature, optional) | wireframe pipelines ([`RecorderDesc::wireframe`](crate::RecorderDesc)) |
//! | a queue family with graphics (and compute, for the geomorph compute stage) | drawing, [`Geomorph`](crate::Geomorph) |
//! | no device extension | swapchains and surfaces are the host's |
//!
//! A host that creates its own device enables these with [`DeviceFeatures::chain`] (or
//! [`DeviceFeatures::enable`], into feature structures it already has) and says
//! what it enabled in [`HostDevice::enabled`](crate::HostDevice); [`Context::from_raw`]
//! checks that against [`DeviceFeatures::REQUIRED`] and against what the physical device
//! supports, and refuses with [`Error::Unsupported`](crate::Error::Unsupported) naming each
//! missing item.
//!
//! [`Context::from_raw`]: crate::Context::from_raw

use ash::vk;

/// The Vulkan version the device (and the host's instance) must support.
pub const API_VERSION: u32 = vk::API_VERSION_1_3;

/// The device features this crate uses, as booleans (supported, enabled or required).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DeviceFeatures {
    /// Vulkan 1.3 `synchronization2`.
    pub synchronization2: bool,
    /// Vulkan 1.3 `dynamicRendering`.
    pub dynamic_rendering: bool,
    /// Vulkan 1.2 `vulkanMemoryModel`.
    pub vulkan_memory_model: bool,
    /// Vulkan 1.0 `fillModeNonSolid` (wireframe only).
    pub fill_mode_non_solid: bool,
}

impl DeviceFeatures {
    /// What every use of this crate needs.
    pub const REQUIRED: Self = Self {
        synchronization2: true,
        dynamic_rendering: true,
        vulkan_memory_model: true,
        fill_mode_non_solid: false,
    };

    /// Everything this crate can use (the required features plus wireframe).
    pub const ALL: Self = Self {
        fill_mode_non_solid: true,
        ..Self::REQUIRED
    };

    /// What `physical_device` supports.
    ///
    /// # Safety
    /// `physical_device` must have been enumerated from `instance`, which must be alive.
    pub unsafe fn supported(instance: &ash::Instance, physical_device: vk::PhysicalDevice) -> Self {
        let mut f12 = vk::PhysicalDeviceVulkan12Features::default();
        let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
        let mut f2 = vk::PhysicalDeviceFeatures2::default()
            .push_next(&mut f12)
            .push_next(&mut f13);
        // SAFETY: the caller's contract; the chain holds structures alive for the call.
        unsafe { instance.get_physical_device_features2(physical_device, &mut f2) };
        let fill = f2.features.fill_mode_non_solid == vk::TRUE;
        Self {
            synchronization2: f13.synchronization2 == vk::TRUE,
            dynamic_rendering: f13.dynamic_rendering == vk::TRUE,
            vulkan_memory_model: f12.vulkan_memory_model == vk::TRUE,
            fill_mode_non_solid: fill,
        }
    }

    /// `self` without what `other` lacks (both together).
    pub fn and(self, other: Self) -> Self {
        Self {
            synchronization2: self.synchronization2 && other.synchronization2,
            dynamic_rendering: self.dynamic_rendering && other.dynamic_rendering,
            vulkan_memory_model: self.vulkan_memory_model && other.vulkan_memory_model,
            fill_mode_non_solid: self.fill_mode_non_solid && other.fill_mode_non_solid,
        }
    }

    /// The Vulkan names of the features `wanted` has and `self` lacks.
    pub fn missing(self, wanted: Self) -> Vec<&'static str> {
        let mut missing = Vec::new();
        let pairs = [
            (
                wanted.synchronization2,
                self.synchronization2,
                "synchronization2",
            ),
            (
                wanted.dynamic_rendering,
                self.dynamic_rendering,
                "dynamicRendering",
            ),
            (
                wanted.vulkan_memory_model,
                self.vulkan_memory_model,
                "vulkanMemoryModel",
            ),
            (
                wanted.fill_mode_non_solid,
                self.fill_mode_non_solid,
                "fillModeNonSolid",
            ),
        ];
        for (want, have, name) in pairs {
            if want && !have {
                missing.push(name);
            }
        }
        missing
    }

    /// Sets `self`'s features in a host's device-creation feature structures (features it
    /// does not name are left as they are).
    pub fn enable(
        self,
        f10: &mut vk::PhysicalDeviceFeatures,
        f12: &mut vk::PhysicalDeviceVulkan12Features<'_>,
        f13: &mut vk::PhysicalDeviceVulkan13Features<'_>,
    ) {
        if self.synchronization2 {
            f13.synchronization2 = vk::TRUE;
        }
        if self.dynamic_rendering {
            f13.dynamic_rendering = vk::TRUE;
        }
        if self.vulkan_memory_model {
            f12.vulkan_memory_model = vk::TRUE;
        }
        if self.fill_mode_non_solid {
            f10.fill_mode_non_solid = vk::TRUE;
        }
    }

    /// The feature structures of a device create info with `self`'s features set, for a
    /// host that creates its device for this crate:
    /// `DeviceFeatures::REQUIRED.chain().push(info)` ([`enable`](Self::enable) sets them in
    /// structures the host already has).
    pub fn chain(self) -> FeatureChain {
        let mut c = FeatureChain::default();
        self.enable(&mut c.vulkan10, &mut c.vulkan12, &mut c.vulkan13);
        c
    }
}

/// The feature structures of a host's `vk::DeviceCreateInfo`, made by
/// [`DeviceFeatures::chain`]. Their fields are public: a host sets its own features in them
/// too, then [`push`](Self::push)es them onto its create info.
#[derive(Clone, Copy, Debug, Default)]
pub struct FeatureChain {
    /// Vulkan 1.0 features (`pEnabledFeatures`).
    pub vulkan10: vk::PhysicalDeviceFeatures,
    /// Vulkan 1.2 features.
    pub vulkan12: vk::PhysicalDeviceVulkan12Features<'static>,
    /// Vulkan 1.3 features.
    pub vulkan13: vk::PhysicalDeviceVulkan13Features<'static>,
}

impl FeatureChain {
    /// `info` with `pEnabledFeatures` set to [`vulkan10`](Self::vulkan10) and the 1.2 and 1.3
    /// structures linked into its `pNext` chain ahead of what it already chains. `info` must
    /// not enable features otherwise (its own `pEnabledFeatures`, or a
    /// `PhysicalDeviceFeatures2`, `PhysicalDeviceVulkan12Features` or
    /// `PhysicalDeviceVulkan13Features` in its chain).
    pub fn push<'a>(&'a mut self, info: vk::DeviceCreateInfo<'a>) -> vk::DeviceCreateInfo<'a> {
        // Forget an earlier push's links, so the structures chain into `info` alone.
        self.vulkan12.p_next = std::ptr::null_mut();
        self.vulkan13.p_next = std::ptr::null_mut();
        info.enabled_features(&self.vulkan10)
            .push_next(&mut self.vulkan12)
            .push_next(&mut self.vulkan13)
    }
}

/// Why a device does not qualify: its name, its version if too old, and the missing
/// features; empty when it qualifies.
pub(crate) fn shortfall(
    api_version: u32,
    supported: DeviceFeatures,
    enabled: DeviceFeatures,
) -> Vec<String> {
    let mut missing = Vec::new();
    if api_version < API_VERSION {
        missing.push(format!(
            "Vulkan 1.3 (the device has {}.{})",
            vk::api_version_major(api_version),
            vk::api_version_minor(api_version)
        ));
    }
    for name in supported.missing(enabled.and(DeviceFeatures::ALL)) {
        missing.push(format!("{name} (not supported)"));
    }
    for name in enabled.missing(DeviceFeatures::REQUIRED) {
        if !missing.iter().any(|m| m.starts_with(name)) {
            missing.push(format!("{name} (not enabled)"));
        }
    }
    missing
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_names_each_lacking_feature() {
        let none = DeviceFeatures::default();
        assert_eq!(
            none.missing(DeviceFeatures::REQUIRED),
            vec!["synchronization2", "dynamicRendering", "vulkanMemoryModel"]
        );
        assert!(DeviceFeatures::ALL.missing(DeviceFeatures::ALL).is_empty());
        assert_eq!(
            DeviceFeatures::REQUIRED.missing(DeviceFeatures::ALL),
            vec!["fillModeNonSolid"]
        );
    }

    /// The structure types of `info`'s `pNext` chain, at most 8.
    fn chained(info: &vk::DeviceCreateInfo<'_>) -> Vec<vk::StructureType> {
        let mut types = Vec::new();
        let mut next = info.p_next.cast::<vk::BaseInStructure<'_>>();
        while !next.is_null() && types.len() < 8 {
            // SAFETY: every link of the chain is a live Vulkan structure, which starts with
            // the base structure's fields.
            let base = unsafe { &*next };
            types.push(base.s_type);
            next = base.p_next;
        }
        types
    }

    #[test]
    fn the_chain_enables_the_features_in_a_create_info() {
        let none = DeviceFeatures::default().chain();
        assert_eq!(none.vulkan13.synchronization2, vk::FALSE);
        assert_eq!(none.vulkan12.vulkan_memory_model, vk::FALSE);
        let mut chain = DeviceFeatures::ALL.chain();
        chain.vulkan12.descriptor_indexing = vk::TRUE;
        let mut host_own = vk::PhysicalDeviceMultiviewFeatures::default();
        // Pushing again relinks: still each structure once, no cycle.
        for _ in 0..2 {
            let base = vk::DeviceCreateInfo::default().push_next(&mut host_own);
            let info = chain.push(base);
            assert_eq!(
                chained(&info),
                vec![
                    vk::StructureType::PHYSICAL_DEVICE_VULKAN_1_3_FEATURES,
                    vk::StructureType::PHYSICAL_DEVICE_VULKAN_1_2_FEATURES,
                    vk::StructureType::PHYSICAL_DEVICE_MULTIVIEW_FEATURES,
                ]
            );
            // SAFETY: `push` pointed it at the chain's live 1.0 features.
            let f10 = unsafe { &*info.p_enabled_features };
            assert_eq!(f10.fill_mode_non_solid, vk::TRUE);
        }
        assert_eq!(chain.vulkan13.synchronization2, vk::TRUE);
        assert_eq!(chain.vulkan13.dynamic_rendering, vk::TRUE);
        assert_eq!(chain.vulkan12.vulkan_memory_model, vk::TRUE);
        assert_eq!(chain.vulkan12.descriptor_indexing, vk::TRUE);
    }

    #[test]
    fn shortfall_separates_unsupported_from_not_enabled() {
        let supported = DeviceFeatures {
            vulkan_memory_model: false,
            ..DeviceFeatures::ALL
        };
        let enabled = DeviceFeatures {
            dynamic_rendering: false,
            ..DeviceFeatures::REQUIRED
        };
        let s = shortfall(vk::API_VERSION_1_2, supported, enabled);
        assert_eq!(
            s,
            vec![
                "Vulkan 1.3 (the device has 1.2)".to_string(),
                "vulkanMemoryModel (not supported)".to_string(),
                "dynamicRendering (not enabled)".to_string(),
            ]
        );
        assert!(shortfall(API_VERSION, DeviceFeatures::ALL, DeviceFeatures::REQUIRED).is_empty());
    }
}
