//! The window's swapchain (sRGB BGRA where offered; FIFO, or MAILBOX / IMMEDIATE without
//! vsync) with its image views, a depth image of the host's, and per image the semaphore
//! its rendering signals and its presentation waits for (presentation holds it until the
//! image comes back, which no frame slot can know). Recreated by the caller when the window
//! changes size or acquire or present says it is out of date.

use caveclod_vulkan::ash::{khr, vk};

use crate::error::{Error, Result, VkExt};
use crate::host::Host;
use crate::image::{range, Image, ImageDesc};
use crate::rendering::Attachments;
use crate::surface::Surface;

/// What a swapchain is made with; fixed for the window's life (pipelines are made for
/// these formats).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SwapchainDesc {
    /// The colour format and colour space.
    pub format: vk::SurfaceFormatKHR,
    /// The depth format (without stencil).
    pub depth: vk::Format,
    /// How images are presented.
    pub present_mode: vk::PresentModeKHR,
}

impl SwapchainDesc {
    /// sRGB BGRA8 if the surface offers it, else its first format; FIFO with `vsync`, else
    /// MAILBOX, IMMEDIATE or (always available) FIFO; a depth format without stencil
    /// (`D16_UNORM` always qualifies).
    pub fn choose(host: &Host, vsync: bool) -> Result<Self> {
        let s = surface(host)?;
        let pd = host.physical_device();
        // SAFETY: the surface and physical device belong to the host's instance.
        let formats = unsafe { s.loader.get_physical_device_surface_formats(pd, s.raw) }
            .vk("vkGetPhysicalDeviceSurfaceFormatsKHR")?;
        let format = formats
            .iter()
            .copied()
            .find(|f| {
                f.format == vk::Format::B8G8R8A8_SRGB
                    && f.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR
            })
            .or_else(|| formats.first().copied())
            .ok_or_else(|| Error::Window("the surface offers no format".into()))?;
        // SAFETY: as above.
        let modes = unsafe {
            s.loader
                .get_physical_device_surface_present_modes(pd, s.raw)
        }
        .vk("vkGetPhysicalDeviceSurfacePresentModesKHR")?;
        let present_mode = if vsync {
            vk::PresentModeKHR::FIFO
        } else {
            [vk::PresentModeKHR::MAILBOX, vk::PresentModeKHR::IMMEDIATE]
                .into_iter()
                .find(|m| modes.contains(m))
                .unwrap_or(vk::PresentModeKHR::FIFO)
        };
        Ok(Self {
            format,
            depth: host.depth_format(&[vk::Format::D32_SFLOAT, vk::Format::D16_UNORM])?,
            present_mode,
        })
    }

    /// `true` if the colour format stores sRGB-encoded values.
    pub fn srgb(&self) -> bool {
        matches!(
            self.format.format,
            vk::Format::B8G8R8A8_SRGB
                | vk::Format::R8G8B8A8_SRGB
                | vk::Format::A8B8G8R8_SRGB_PACK32
        )
    }
}

/// What acquiring an image gave.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Acquired {
    /// The image to render; `suboptimal`: present it, then recreate.
    Image {
        /// Its index.
        index: u32,
        /// The swapchain no longer matches the surface exactly.
        suboptimal: bool,
    },
    /// The swapchain no longer matches the surface: recreate, skip the frame.
    OutOfDate,
}

/// The swapchain and what goes with it (see the module docs).
pub struct Swapchain {
    loader: khr::swapchain::Device,
    raw: vk::SwapchainKHR,
    desc: SwapchainDesc,
    extent: vk::Extent2D,
    images: Vec<vk::Image>,
    views: Vec<vk::ImageView>,
    render_finished: Vec<vk::Semaphore>,
    depth: Image,
}

/// The windowed host's surface.
fn surface(host: &Host) -> Result<&Surface> {
    host.surface()
        .ok_or_else(|| Error::Window("a host without a window has no surface".into()))
}

impl Swapchain {
    /// A swapchain of `extent` (used where the surface leaves the size to the
    /// application), replacing `old` (destroyed by the caller after this returns). `None`
    /// when the surface's extent is zero (a minimised window). Its images can be copied
    /// from (screenshots).
    pub fn new(
        host: &Host,
        desc: SwapchainDesc,
        extent: vk::Extent2D,
        old: Option<&Swapchain>,
    ) -> Result<Option<Self>> {
        let s = surface(host)?;
        // SAFETY: the surface and physical device belong to the host's instance.
        let caps = unsafe {
            s.loader
                .get_physical_device_surface_capabilities(host.physical_device(), s.raw)
        }
        .vk("vkGetPhysicalDeviceSurfaceCapabilitiesKHR")?;
        let extent = surface_extent(&caps, extent);
        if extent.width == 0 || extent.height == 0 {
            return Ok(None);
        }
        let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC;
        if !caps.supported_usage_flags.contains(usage) {
            return Err(Error::Window(
                "the surface's images cannot be rendered into and copied from".into(),
            ));
        }
        let mut count = caps.min_image_count + 1;
        if caps.max_image_count > 0 {
            count = count.min(caps.max_image_count);
        }
        let alpha = [
            vk::CompositeAlphaFlagsKHR::OPAQUE,
            vk::CompositeAlphaFlagsKHR::INHERIT,
            vk::CompositeAlphaFlagsKHR::PRE_MULTIPLIED,
            vk::CompositeAlphaFlagsKHR::POST_MULTIPLIED,
        ]
        .into_iter()
        .find(|&a| caps.supported_composite_alpha.contains(a))
        .unwrap_or(vk::CompositeAlphaFlagsKHR::OPAQUE);
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(s.raw)
            .min_image_count(count)
            .image_format(desc.format.format)
            .image_color_space(desc.format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(usage)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(alpha)
            .present_mode(desc.present_mode)
            .clipped(true)
            .old_swapchain(old.map_or(vk::SwapchainKHR::null(), |o| o.raw));
        let loader = khr::swapchain::Device::new(host.instance(), host.device());
        // SAFETY: valid create info for this device's surface; `old` (if any) is a live
        // swapchain of the same surface.
        let raw = unsafe { loader.create_swapchain(&info, None) }.vk("vkCreateSwapchainKHR")?;
        let mut chain = Self {
            loader,
            raw,
            desc,
            extent,
            images: Vec::new(),
            views: Vec::new(),
            render_finished: Vec::new(),
            depth: Image::null(desc.depth),
        };
        match chain.make_per_image(host) {
            Ok(()) => Ok(Some(chain)),
            Err(e) => {
                chain.destroy(host);
                Err(e)
            }
        }
    }

    /// Image views, render-finished semaphores and the depth image.
    fn make_per_image(&mut self, host: &Host) -> Result<()> {
        let d = host.device();
        // SAFETY: `raw` is a live swapchain of this device.
        self.images =
            unsafe { self.loader.get_swapchain_images(self.raw) }.vk("vkGetSwapchainImagesKHR")?;
        for &image in &self.images {
            let info = vk::ImageViewCreateInfo::default()
                .image(image)
                .view_type(vk::ImageViewType::TYPE_2D)
                .format(self.desc.format.format)
                .subresource_range(range(vk::ImageAspectFlags::COLOR));
            // SAFETY: `image` is a swapchain image of this device.
            let view = unsafe { d.create_image_view(&info, None) }.vk("vkCreateImageView")?;
            self.views.push(view);
            // SAFETY: valid create info.
            let semaphore =
                unsafe { d.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }
                    .vk("vkCreateSemaphore")?;
            self.render_finished.push(semaphore);
        }
        let depth = ImageDesc {
            format: self.desc.depth,
            extent: self.extent,
            samples: vk::SampleCountFlags::TYPE_1,
            usage: vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
        };
        self.depth = Image::new(host, "swapchain depth", depth)?;
        Ok(())
    }

    /// What it was made with.
    pub fn desc(&self) -> &SwapchainDesc {
        &self.desc
    }

    /// The size of its images.
    pub fn extent(&self) -> vk::Extent2D {
        self.extent
    }

    /// The attachments of a frame rendering into image `index`: the image, and the one
    /// depth image every frame shares (each frame's rendering waits for the last one's
    /// depth tests).
    pub fn attachments(&self, index: u32) -> Result<Attachments> {
        let i = index as usize;
        let (image, view) = self
            .images
            .get(i)
            .zip(self.views.get(i))
            .ok_or_else(|| Error::InvalidArgument(format!("swapchain image {index}")))?;
        Ok(Attachments {
            colour: (*image, *view),
            resolve: None,
            depth: (self.depth.raw, self.depth.view, self.desc.depth),
            extent: self.extent,
        })
    }

    /// The semaphore the rendering of image `index` signals and its presentation waits
    /// for.
    pub fn render_finished(&self, index: u32) -> Result<vk::Semaphore> {
        self.render_finished
            .get(index as usize)
            .copied()
            .ok_or_else(|| Error::InvalidArgument(format!("swapchain image {index}")))
    }

    /// Acquires the next image, signalling `available` when it is ready to be rendered.
    pub fn acquire(&self, available: vk::Semaphore) -> Result<Acquired> {
        // SAFETY: `available` is unsignalled with no pending signal (its last wait was
        // submitted, or it was never used).
        let r = unsafe {
            self.loader
                .acquire_next_image(self.raw, u64::MAX, available, vk::Fence::null())
        };
        match r {
            Ok((index, suboptimal)) => Ok(Acquired::Image { index, suboptimal }),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(Acquired::OutOfDate),
            Err(result) => Err(Error::Vulkan {
                call: "vkAcquireNextImageKHR",
                result,
            }),
        }
    }

    /// Presents image `index` after its render-finished semaphore; `true` if the swapchain
    /// must be recreated (out of date or suboptimal).
    pub fn present(&self, host: &Host, index: u32) -> Result<bool> {
        let wait = [self.render_finished(index)?];
        let chains = [self.raw];
        let indices = [index];
        let info = vk::PresentInfoKHR::default()
            .wait_semaphores(&wait)
            .swapchains(&chains)
            .image_indices(&indices);
        // SAFETY: `index` was acquired and its rendering submitted to signal `wait`; the
        // host submits and presents from one thread.
        match unsafe { self.loader.queue_present(host.queue(), &info) } {
            Ok(suboptimal) => Ok(suboptimal),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(true),
            Err(result) => Err(Error::Vulkan {
                call: "vkQueuePresentKHR",
                result,
            }),
        }
    }

    /// Destroys the depth image, the semaphores, the views and the swapchain, in reverse
    /// order of creation. The GPU must be done with them (the caller waits for the device).
    pub fn destroy(self, host: &Host) {
        // A failed free only leaks memory the host's teardown reports.
        let _ = self.depth.destroy(host);
        let d = host.device();
        // SAFETY: the device is idle (the caller's contract); each handle is destroyed once.
        unsafe {
            for &s in &self.render_finished {
                d.destroy_semaphore(s, None);
            }
            for &v in &self.views {
                d.destroy_image_view(v, None);
            }
            self.loader.destroy_swapchain(self.raw, None);
        }
    }
}

/// The surface's extent, or `wanted` clamped to its limits where the surface lets the
/// application choose.
fn surface_extent(caps: &vk::SurfaceCapabilitiesKHR, wanted: vk::Extent2D) -> vk::Extent2D {
    if caps.current_extent.width != u32::MAX {
        return caps.current_extent;
    }
    vk::Extent2D {
        width: wanted
            .width
            .clamp(caps.min_image_extent.width, caps.max_image_extent.width),
        height: wanted
            .height
            .clamp(caps.min_image_extent.height, caps.max_image_extent.height),
    }
}
