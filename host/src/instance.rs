//! The host's instance, made the way an engine makes it: Vulkan 1.3, the window system's
//! surface extensions when windowed, and when asked the Khronos validation layer with a
//! debug messenger recording into a [`ValidationLog`].

use std::ffi::{c_char, CStr};
use std::sync::Arc;

use caveclod_vulkan::ash::{self, vk};
use caveclod_vulkan::{DebugMessenger, ValidationLog, API_VERSION, VALIDATION_LAYER};

use crate::error::{Error, Result, VkExt};

/// The loader, the instance and, with validation, the messenger and its log.
pub(crate) struct Instance {
    pub entry: ash::Entry,
    pub raw: ash::Instance,
    messenger: Option<DebugMessenger>,
    /// Where the validation layer's messages go (stays empty without validation).
    pub log: Arc<ValidationLog>,
    /// The layer is enabled and its messages recorded.
    pub validation: bool,
}

impl Instance {
    /// Loads the Vulkan loader and creates an instance with `extensions` (the surface's,
    /// when windowed); with `validation`, the Khronos layer (an error if it is not
    /// installed), `VK_EXT_debug_utils` and a messenger into a fresh log.
    pub fn new(validation: bool, extensions: &[*const c_char]) -> Result<Self> {
        // SAFETY: loads the system's Vulkan loader; nothing else runs its code yet.
        let entry = unsafe { ash::Entry::load() }.map_err(caveclod_vulkan::Error::from)?;
        if validation && !layer_installed(&entry, VALIDATION_LAYER)? {
            return Err(Error::NoValidationLayer(
                VALIDATION_LAYER.to_string_lossy().into_owned(),
            ));
        }
        let mut extensions = extensions.to_vec();
        if validation {
            extensions.push(ash::ext::debug_utils::NAME.as_ptr());
        }
        let layers = [VALIDATION_LAYER.as_ptr()];
        let app = vk::ApplicationInfo::default()
            .application_name(c"caveclod host")
            .engine_name(c"caveclod host")
            .api_version(API_VERSION);
        let mut info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_extension_names(&extensions);
        if validation {
            info = info.enabled_layer_names(&layers);
        }
        // SAFETY: every pointer in `info` refers to locals (or static names) alive for the
        // call.
        let raw = unsafe { entry.create_instance(&info, None) }.vk("vkCreateInstance")?;
        let log = ValidationLog::new();
        let messenger = if validation {
            match DebugMessenger::new(&entry, &raw, log.clone()) {
                Ok(m) => Some(m),
                Err(e) => {
                    // SAFETY: nothing was created from the instance.
                    unsafe { raw.destroy_instance(None) };
                    return Err(e.into());
                }
            }
        } else {
            None
        };
        Ok(Self {
            entry,
            raw,
            messenger,
            log,
            validation,
        })
    }

    /// Destroys the messenger, then the instance. Everything made from the instance (the
    /// device, a surface) must be destroyed first.
    pub fn destroy(self) {
        if let Some(m) = self.messenger {
            m.destroy();
        }
        // SAFETY: the caller destroyed everything made from the instance; the messenger
        // made from it is gone.
        unsafe { self.raw.destroy_instance(None) };
    }
}

/// `true` if the instance layer `name` is installed.
fn layer_installed(entry: &ash::Entry, name: &CStr) -> Result<bool> {
    // SAFETY: plain enumeration.
    let layers = unsafe { entry.enumerate_instance_layer_properties() }
        .vk("vkEnumerateInstanceLayerProperties")?;
    Ok(layers
        .iter()
        .any(|l| l.layer_name_as_c_str().is_ok_and(|n| n == name)))
}
