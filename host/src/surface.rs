//! A window's surface (ash-window over winit's raw handles) and the instance extensions it
//! needs.

use std::ffi::c_char;

use caveclod_vulkan::ash::{self, khr, vk};
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use winit::window::Window;

use crate::error::{Error, Result, VkExt};

/// The window's surface and the loader of its functions.
pub(crate) struct Surface {
    pub loader: khr::surface::Instance,
    pub raw: vk::SurfaceKHR,
}

/// The instance extensions a surface of `window`'s display needs.
pub(crate) fn required_extensions(window: &Window) -> Result<&'static [*const c_char]> {
    let display = window
        .display_handle()
        .map_err(|e| Error::Window(format!("its display: {e}")))?
        .as_raw();
    ash_window::enumerate_required_extensions(display).vk("surface extensions")
}

impl Surface {
    /// The surface of `window`, on an instance made with [`required_extensions`]. The
    /// window must outlive the surface.
    pub fn new(entry: &ash::Entry, instance: &ash::Instance, window: &Window) -> Result<Self> {
        let display = window
            .display_handle()
            .map_err(|e| Error::Window(format!("its display: {e}")))?
            .as_raw();
        let handle = window
            .window_handle()
            .map_err(|e| Error::Window(format!("its handle: {e}")))?
            .as_raw();
        // SAFETY: the instance was made with the extensions this display needs
        // (`required_extensions`); the window outlives the surface (the caller's contract,
        // kept by `Host`'s documentation).
        let raw = unsafe { ash_window::create_surface(entry, instance, display, handle, None) }
            .vk("vkCreate*SurfaceKHR")?;
        Ok(Self {
            loader: khr::surface::Instance::new(entry, instance),
            raw,
        })
    }

    /// Whether queue family `family` of `pd` presents to the surface (a failing query
    /// counts as no).
    pub fn presents(&self, pd: vk::PhysicalDevice, family: u32) -> bool {
        // SAFETY: `pd` belongs to the instance the surface was made on; `family` is one of
        // its queue families (the caller enumerates them).
        unsafe {
            self.loader
                .get_physical_device_surface_support(pd, family, self.raw)
        }
        .unwrap_or(false)
    }

    /// Destroys the surface. Its swapchains must be destroyed first.
    pub fn destroy(self) {
        // SAFETY: the caller destroyed every swapchain of the surface.
        unsafe { self.loader.destroy_surface(self.raw, None) };
    }
}
