//! Validation-layer messages, collected instead of printed.
//!
//! The debug messenger's callback runs inside the driver's call stack (across FFI), so it
//! must never unwind: it catches panics, tolerates a poisoned mutex, and only appends the
//! message text to a [`ValidationLog`]. Tests take the log after each step and assert it is
//! empty, which is what makes "zero validation errors" a checked property (as wgpu's test
//! harness does). Only ERROR and WARNING severities are kept.

use std::ffi::{c_void, CStr};
use std::sync::{Arc, Mutex};

use ash::vk;

use crate::error::{Result, VkResultExt};

/// Name of the Khronos validation layer.
pub const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// ERROR and WARNING messages of the validation layer (and loader), in arrival order.
///
/// The messenger's callback appends to the log and never prints; tests take the log after
/// each step and assert it is empty, which makes "zero validation errors" a checked
/// property.
#[derive(Debug, Default)]
pub struct ValidationLog {
    messages: Mutex<Vec<String>>,
}

impl ValidationLog {
    /// An empty log.
    pub fn new() -> Arc<Self> {
        Arc::new(Self::default())
    }

    /// Appends a message (never panics).
    pub fn push(&self, message: String) {
        match self.messages.lock() {
            Ok(mut m) => m.push(message),
            Err(poisoned) => poisoned.into_inner().push(message),
        }
    }

    /// Removes and returns every message recorded so far.
    pub fn take(&self) -> Vec<String> {
        match self.messages.lock() {
            Ok(mut m) => std::mem::take(&mut *m),
            Err(poisoned) => std::mem::take(&mut *poisoned.into_inner()),
        }
    }

    /// Number of messages recorded and not yet taken.
    pub fn len(&self) -> usize {
        match self.messages.lock() {
            Ok(m) => m.len(),
            Err(poisoned) => poisoned.into_inner().len(),
        }
    }

    /// `true` if no message is waiting.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The messenger's callback; `user_data` is an `Arc<ValidationLog>` raw pointer kept alive
/// by the [`DebugMessenger`] that registered it.
unsafe extern "system" fn callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user_data: *mut c_void,
) -> vk::Bool32 {
    let _ = std::panic::catch_unwind(|| {
        if user_data.is_null() || data.is_null() {
            return;
        }
        // SAFETY: `user_data` is the pointer of an `Arc<ValidationLog>` that the messenger
        // owns for as long as the callback is registered; `data` is valid for this call.
        let (log, data) = unsafe { (&*(user_data as *const ValidationLog), &*data) };
        let text = if data.p_message.is_null() {
            String::from("(no message)")
        } else {
            // SAFETY: the layer passes a NUL-terminated string valid for this call.
            unsafe { CStr::from_ptr(data.p_message) }
                .to_string_lossy()
                .into_owned()
        };
        let level = if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
            "ERROR"
        } else {
            "WARNING"
        };
        log.push(format!("[{level} {kind:?}] {text}"));
    });
    vk::FALSE
}

/// The create info of a messenger that records into `log` (also usable in the `pNext`
/// chain of `VkInstanceCreateInfo`, to catch instance creation and destruction).
pub(crate) fn messenger_info(
    log: &Arc<ValidationLog>,
) -> vk::DebugUtilsMessengerCreateInfoEXT<'static> {
    vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(
            vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
                | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING,
        )
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(callback))
        .user_data(Arc::as_ptr(log) as *mut c_void)
}

/// A registered debug messenger and the log it fills: the entry point for a host that
/// creates its own instance (with `VK_EXT_debug_utils`) and wants the layer's messages in a
/// [`ValidationLog`], as a headless [`Context`](crate::Context) records them.
pub struct DebugMessenger {
    loader: ash::ext::debug_utils::Instance,
    /// The Vulkan handle.
    pub raw: vk::DebugUtilsMessengerEXT,
    /// Where messages go.
    pub log: Arc<ValidationLog>,
}

impl DebugMessenger {
    /// Registers a messenger on `instance` (which must have `VK_EXT_debug_utils` enabled).
    /// Hosts that create their own instance can use this too.
    pub fn new(
        entry: &ash::Entry,
        instance: &ash::Instance,
        log: Arc<ValidationLog>,
    ) -> Result<Self> {
        let loader = ash::ext::debug_utils::Instance::new(entry, instance);
        let info = messenger_info(&log);
        // SAFETY: `info` is valid; `log` outlives the messenger because `Self` owns it and
        // destroys the messenger before dropping it.
        let raw = unsafe { loader.create_debug_utils_messenger(&info, None) }
            .vk("vkCreateDebugUtilsMessengerEXT")?;
        Ok(Self { loader, raw, log })
    }

    /// Unregisters the messenger (as dropping it does); call before destroying the
    /// instance.
    pub fn destroy(self) {
        drop(self);
    }
}

/// A messenger unregisters itself when dropped, so it must be dropped (or destroyed) before
/// its instance is destroyed, as Vulkan requires of every child of an instance.
impl Drop for DebugMessenger {
    fn drop(&mut self) {
        // SAFETY: `raw` was created from this loader's instance; destroying that instance
        // while a messenger is alive violates `vkDestroyInstance`'s contract, which the
        // (unsafe) call that destroys the instance must uphold, so the instance is alive.
        unsafe { self.loader.destroy_debug_utils_messenger(self.raw, None) };
    }
}

/// `true` if the Khronos validation layer is installed.
pub(crate) fn validation_layer_present(entry: &ash::Entry) -> bool {
    // SAFETY: plain enumeration call.
    match unsafe { entry.enumerate_instance_layer_properties() } {
        Ok(layers) => layers
            .iter()
            .any(|l| l.layer_name_as_c_str().is_ok_and(|n| n == VALIDATION_LAYER)),
        Err(_) => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_take_empties_it() {
        let log = ValidationLog::new();
        assert!(log.is_empty());
        log.push("a".into());
        log.push("b".into());
        assert_eq!(log.len(), 2);
        assert_eq!(log.take(), vec!["a".to_string(), "b".to_string()]);
        assert!(log.is_empty());
    }
}
