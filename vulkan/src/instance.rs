//! Headless instance creation: Vulkan 1.3, the Khronos validation layer and
//! `VK_EXT_debug_utils` when requested and installed, no surface extensions (nothing is
//! presented; targets are read back).

use std::sync::Arc;

use ash::vk;

use crate::error::{Error, Result, VkResultExt};
use crate::validation::{self, DebugMessenger, ValidationLog};

/// An instance this crate created, with its messenger.
pub(crate) struct OwnedInstance {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    pub messenger: Option<DebugMessenger>,
    /// `true` if the validation layer is enabled.
    pub validation: bool,
}

/// Loads the Vulkan loader and creates a Vulkan 1.3 instance. With `validation`, the
/// Khronos layer is enabled if installed and its messages go to `log`; with `synchronization`
/// too, so is its synchronization validation (through `VK_EXT_validation_features`, which the
/// layer provides).
pub(crate) fn create(
    validation: bool,
    synchronization: bool,
    log: &Arc<ValidationLog>,
) -> Result<OwnedInstance> {
    // SAFETY: loading the system's Vulkan loader library; nothing else runs its code yet.
    let entry = unsafe { ash::Entry::load() }?;
    // SAFETY: plain query.
    let version = unsafe { entry.try_enumerate_instance_version() }
        .vk("vkEnumerateInstanceVersion")?
        .unwrap_or(vk::API_VERSION_1_0);
    if version < vk::API_VERSION_1_3 {
        return Err(Error::NoDevice(format!(
            "the Vulkan loader supports {}.{}, 1.3 is needed",
            vk::api_version_major(version),
            vk::api_version_minor(version)
        )));
    }
    let validation = validation && validation::validation_layer_present(&entry);
    // SAFETY: plain query.
    let has_debug_utils = unsafe { entry.enumerate_instance_extension_properties(None) }
        .vk("vkEnumerateInstanceExtensionProperties")?
        .iter()
        .any(|e| e.extension_name_as_c_str() == Ok(ash::ext::debug_utils::NAME));
    let debug = validation && has_debug_utils;

    let app = vk::ApplicationInfo::default()
        .application_name(c"caveclod")
        .engine_name(c"caveclod-vulkan")
        .api_version(vk::API_VERSION_1_3);
    let layers = [validation::VALIDATION_LAYER.as_ptr()];
    let mut extensions = Vec::new();
    if debug {
        extensions.push(ash::ext::debug_utils::NAME.as_ptr());
    }
    let sync = validation && synchronization;
    if sync {
        extensions.push(ash::ext::validation_features::NAME.as_ptr());
    }
    let enables = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
    let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enables);
    let mut messenger_info = validation::messenger_info(log);
    let mut info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_extension_names(&extensions);
    if validation {
        info = info.enabled_layer_names(&layers);
    }
    if debug {
        info = info.push_next(&mut messenger_info);
    }
    if sync {
        info = info.push_next(&mut features);
    }
    // SAFETY: every pointer in `info` refers to locals alive for the call.
    let instance =
        match unsafe { entry.create_instance(&info, None) } {
            Ok(i) => i,
            Err(vk::Result::ERROR_INCOMPATIBLE_DRIVER) => return Err(Error::NoDevice(
                "the Vulkan loader found no driver (install Mesa's lavapipe: mesa-vulkan-drivers)"
                    .into(),
            )),
            Err(e) => return Err(crate::error::from_vk("vkCreateInstance", e)),
        };
    let messenger = if debug {
        match DebugMessenger::new(&entry, &instance, log.clone()) {
            Ok(m) => Some(m),
            Err(e) => {
                // SAFETY: nothing was created from the instance.
                unsafe { instance.destroy_instance(None) };
                return Err(e);
            }
        }
    } else {
        None
    };
    Ok(OwnedInstance {
        entry,
        instance,
        messenger,
        validation,
    })
}
