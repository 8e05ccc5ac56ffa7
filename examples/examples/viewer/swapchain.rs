//! The window's swapchain (sRGB BGRA where offered; FIFO, or MAILBOX / IMMEDIATE without
//! vsync), its depth image, and the per-frame synchronisation of two frames in flight.
//!
//! Per frame slot: a command pool and buffer, a fence (signalled when the slot's last
//! submission completed) and an image-available semaphore. Per swapchain image: a
//! render-finished semaphore, since presentation holds it until the image comes back, which
//! a frame slot cannot know.

use caveclod_vulkan::ash::{khr, vk};
use caveclod_vulkan::gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use caveclod_vulkan::gpu_allocator::MemoryLocation;

use crate::gpu::{vk_err, Gpu};

/// Frames the CPU records while the GPU still renders earlier ones.
pub const FRAMES_IN_FLIGHT: usize = 2;

/// What a swapchain is made with; fixed for the window's life (the recorder's and egui's
/// pipelines are made for these formats).
#[derive(Clone, Copy, Debug)]
pub struct SwapchainDesc {
    pub format: vk::SurfaceFormatKHR,
    pub depth: vk::Format,
    pub present_mode: vk::PresentModeKHR,
}

impl SwapchainDesc {
    /// sRGB BGRA8 if the surface offers it, else its first format; FIFO with `vsync`, else
    /// MAILBOX, IMMEDIATE or (always available) FIFO.
    pub fn choose(gpu: &Gpu, vsync: bool) -> Result<Self, String> {
        // SAFETY: the surface and physical device belong to the instance.
        let formats = unsafe {
            gpu.surface_loader
                .get_physical_device_surface_formats(gpu.physical_device, gpu.surface)
        }
        .map_err(vk_err("vkGetPhysicalDeviceSurfaceFormatsKHR"))?;
        let format = formats
            .iter()
            .copied()
            .find(|f| {
                f.format == vk::Format::B8G8R8A8_SRGB
                    && f.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR
            })
            .or_else(|| formats.first().copied())
            .ok_or("the surface offers no format")?;
        // SAFETY: as above.
        let modes = unsafe {
            gpu.surface_loader
                .get_physical_device_surface_present_modes(gpu.physical_device, gpu.surface)
        }
        .map_err(vk_err("vkGetPhysicalDeviceSurfacePresentModesKHR"))?;
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
            depth: gpu.depth_format()?,
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

/// An image of the host's with its memory and view.
pub struct DepthImage {
    pub image: vk::Image,
    pub view: vk::ImageView,
    allocation: Option<Allocation>,
}

/// The swapchain, its image views, its depth image and its render-finished semaphores.
pub struct Swapchain {
    loader: khr::swapchain::Device,
    raw: vk::SwapchainKHR,
    pub desc: SwapchainDesc,
    pub extent: vk::Extent2D,
    pub images: Vec<vk::Image>,
    pub views: Vec<vk::ImageView>,
    /// Per image: signalled by the frame that rendered it, waited for by its presentation.
    pub render_finished: Vec<vk::Semaphore>,
    pub depth: DepthImage,
}

/// What acquiring an image gave.
pub enum Acquired {
    /// The image to render; `suboptimal`: present it, then recreate.
    Image { index: u32, suboptimal: bool },
    /// The swapchain no longer matches the surface: recreate, skip the frame.
    OutOfDate,
}

impl Swapchain {
    /// A swapchain of `extent` (used where the surface leaves the size to the
    /// application), replacing `old` (retired by the caller after this returns). `None`
    /// when the surface's extent is zero (a minimised window).
    pub fn new(
        gpu: &Gpu,
        desc: SwapchainDesc,
        extent: vk::Extent2D,
        old: vk::SwapchainKHR,
    ) -> Result<Option<Self>, String> {
        // SAFETY: the surface and physical device belong to the instance.
        let caps = unsafe {
            gpu.surface_loader
                .get_physical_device_surface_capabilities(gpu.physical_device, gpu.surface)
        }
        .map_err(vk_err("vkGetPhysicalDeviceSurfaceCapabilitiesKHR"))?;
        let extent = surface_extent(&caps, extent);
        if extent.width == 0 || extent.height == 0 {
            return Ok(None);
        }
        if !caps
            .supported_usage_flags
            .contains(vk::ImageUsageFlags::TRANSFER_SRC)
        {
            return Err("the surface's images cannot be copied from (screenshots)".into());
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
            .surface(gpu.surface)
            .min_image_count(count)
            .image_format(desc.format.format)
            .image_color_space(desc.format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(alpha)
            .present_mode(desc.present_mode)
            .clipped(true)
            .old_swapchain(old);
        let loader = khr::swapchain::Device::new(&gpu.instance, &gpu.device);
        // SAFETY: valid create info for this device's surface; `old` (if any) is a swapchain
        // of the same surface, not yet destroyed.
        let raw = unsafe { loader.create_swapchain(&info, None) }
            .map_err(vk_err("vkCreateSwapchainKHR"))?;
        let mut chain = Self {
            loader,
            raw,
            desc,
            extent,
            images: Vec::new(),
            views: Vec::new(),
            render_finished: Vec::new(),
            depth: DepthImage {
                image: vk::Image::null(),
                view: vk::ImageView::null(),
                allocation: None,
            },
        };
        match chain.make_per_image(gpu) {
            Ok(()) => Ok(Some(chain)),
            Err(e) => {
                chain.destroy(gpu);
                Err(e)
            }
        }
    }

    /// Image views, render-finished semaphores and the depth image.
    fn make_per_image(&mut self, gpu: &Gpu) -> Result<(), String> {
        let d = &gpu.device;
        // SAFETY: `raw` is a live swapchain of this device.
        self.images = unsafe { self.loader.get_swapchain_images(self.raw) }
            .map_err(vk_err("vkGetSwapchainImagesKHR"))?;
        for &image in &self.images {
            let info = vk::ImageViewCreateInfo::default()
                .image(image)
                .view_type(vk::ImageViewType::TYPE_2D)
                .format(self.desc.format.format)
                .subresource_range(colour_range());
            // SAFETY: `image` is a swapchain image of this device.
            let view =
                unsafe { d.create_image_view(&info, None) }.map_err(vk_err("vkCreateImageView"))?;
            self.views.push(view);
            // SAFETY: valid create info.
            let semaphore =
                unsafe { d.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }
                    .map_err(vk_err("vkCreateSemaphore"))?;
            self.render_finished.push(semaphore);
        }
        self.depth = create_depth(gpu, self.desc.depth, self.extent)?;
        Ok(())
    }

    /// The swapchain handle (for [`Swapchain::new`]'s `old`).
    pub fn raw(&self) -> vk::SwapchainKHR {
        self.raw
    }

    /// Acquires the next image, signalling `available` when it is ready to be rendered.
    pub fn acquire(&self, available: vk::Semaphore) -> Result<Acquired, String> {
        // SAFETY: `available` is unsignalled with no pending signal (its last wait was
        // submitted, or it was never used).
        let r = unsafe {
            self.loader
                .acquire_next_image(self.raw, u64::MAX, available, vk::Fence::null())
        };
        match r {
            Ok((index, suboptimal)) => Ok(Acquired::Image { index, suboptimal }),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(Acquired::OutOfDate),
            Err(e) => Err(format!("vkAcquireNextImageKHR: {e}")),
        }
    }

    /// Presents `index` after its render-finished semaphore; `true` if the swapchain must
    /// be recreated (out of date or suboptimal).
    pub fn present(&self, queue: vk::Queue, index: u32) -> Result<bool, String> {
        let wait = [self.render_finished[index as usize]];
        let chains = [self.raw];
        let indices = [index];
        let info = vk::PresentInfoKHR::default()
            .wait_semaphores(&wait)
            .swapchains(&chains)
            .image_indices(&indices);
        // SAFETY: `index` was acquired and its rendering submitted to signal `wait`.
        match unsafe { self.loader.queue_present(queue, &info) } {
            Ok(suboptimal) => Ok(suboptimal),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(true),
            Err(e) => Err(format!("vkQueuePresentKHR: {e}")),
        }
    }

    /// Destroys views, semaphores, depth image and swapchain. The GPU must be done with
    /// them (the caller waits for the device).
    pub fn destroy(mut self, gpu: &Gpu) {
        let d = &gpu.device;
        // SAFETY: the device is idle (the caller's contract); each handle is destroyed once.
        unsafe {
            for &v in &self.views {
                d.destroy_image_view(v, None);
            }
            for &s in &self.render_finished {
                d.destroy_semaphore(s, None);
            }
        }
        destroy_depth(gpu, &mut self.depth);
        // SAFETY: as above; the swapchain's images are no longer used.
        unsafe { self.loader.destroy_swapchain(self.raw, None) };
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

pub fn colour_range() -> vk::ImageSubresourceRange {
    range(vk::ImageAspectFlags::COLOR)
}

pub fn range(aspect: vk::ImageAspectFlags) -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange {
        aspect_mask: aspect,
        base_mip_level: 0,
        level_count: 1,
        base_array_layer: 0,
        layer_count: 1,
    }
}

/// A device-local depth image of `extent`, from the host's allocator, and its view.
fn create_depth(gpu: &Gpu, format: vk::Format, extent: vk::Extent2D) -> Result<DepthImage, String> {
    let d = &gpu.device;
    let info = vk::ImageCreateInfo::default()
        .image_type(vk::ImageType::TYPE_2D)
        .format(format)
        .extent(extent.into())
        .mip_levels(1)
        .array_layers(1)
        .samples(vk::SampleCountFlags::TYPE_1)
        .tiling(vk::ImageTiling::OPTIMAL)
        .usage(vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT)
        .initial_layout(vk::ImageLayout::UNDEFINED);
    // SAFETY: valid create info; `format` is a depth attachment format of the device.
    let image = unsafe { d.create_image(&info, None) }.map_err(vk_err("vkCreateImage"))?;
    let mut depth = DepthImage {
        image,
        view: vk::ImageView::null(),
        allocation: None,
    };
    let made = (|| {
        // SAFETY: `image` is alive.
        let requirements = unsafe { d.get_image_memory_requirements(image) };
        let allocation = gpu
            .allocator
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .allocate(&AllocationCreateDesc {
                name: "viewer depth",
                requirements,
                location: MemoryLocation::GpuOnly,
                linear: false,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
            .map_err(|e| format!("depth image memory: {e}"))?;
        // SAFETY: the allocation satisfies the image's requirements and is bound once.
        let bound = unsafe { d.bind_image_memory(image, allocation.memory(), allocation.offset()) };
        depth.allocation = Some(allocation);
        bound.map_err(vk_err("vkBindImageMemory"))?;
        let view_info = vk::ImageViewCreateInfo::default()
            .image(image)
            .view_type(vk::ImageViewType::TYPE_2D)
            .format(format)
            .subresource_range(range(vk::ImageAspectFlags::DEPTH));
        // SAFETY: `image` is bound to memory.
        depth.view = unsafe { d.create_image_view(&view_info, None) }
            .map_err(vk_err("vkCreateImageView"))?;
        Ok(())
    })();
    match made {
        Ok(()) => Ok(depth),
        Err(e) => {
            destroy_depth(gpu, &mut depth);
            Err(e)
        }
    }
}

fn destroy_depth(gpu: &Gpu, depth: &mut DepthImage) {
    let d = &gpu.device;
    // SAFETY: the GPU is done with the image (the callers wait for the device); null
    // handles are ignored by Vulkan.
    unsafe {
        d.destroy_image_view(depth.view, None);
        d.destroy_image(depth.image, None);
    }
    if let Some(a) = depth.allocation.take() {
        // A failed free only leaks memory the allocator reports at teardown.
        let _ = gpu
            .allocator
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .free(a);
    }
}

/// One frame slot's command buffer and synchronisation.
pub struct FrameSlot {
    pool: vk::CommandPool,
    pub cmd: vk::CommandBuffer,
    /// Signalled when the slot's last submission completed (created signalled).
    pub fence: vk::Fence,
    /// Signalled by the acquire of the slot's image.
    pub image_available: vk::Semaphore,
}

impl FrameSlot {
    pub fn new(gpu: &Gpu) -> Result<Self, String> {
        let d = &gpu.device;
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(gpu.family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: valid create info.
        let pool = unsafe { d.create_command_pool(&pool_info, None) }
            .map_err(vk_err("vkCreateCommandPool"))?;
        let mut slot = Self {
            pool,
            cmd: vk::CommandBuffer::null(),
            fence: vk::Fence::null(),
            image_available: vk::Semaphore::null(),
        };
        let made = (|| {
            let alloc = vk::CommandBufferAllocateInfo::default()
                .command_pool(pool)
                .level(vk::CommandBufferLevel::PRIMARY)
                .command_buffer_count(1);
            // SAFETY: the pool is alive.
            slot.cmd = unsafe { d.allocate_command_buffers(&alloc) }
                .map_err(vk_err("vkAllocateCommandBuffers"))?
                .first()
                .copied()
                .ok_or("no command buffer allocated")?;
            let fence_info = vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED);
            // SAFETY: valid create info.
            slot.fence =
                unsafe { d.create_fence(&fence_info, None) }.map_err(vk_err("vkCreateFence"))?;
            // SAFETY: valid create info.
            slot.image_available =
                unsafe { d.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }
                    .map_err(vk_err("vkCreateSemaphore"))?;
            Ok::<(), String>(())
        })();
        match made {
            Ok(()) => Ok(slot),
            Err(e) => {
                slot.destroy(gpu);
                Err(e)
            }
        }
    }

    /// Waits until the slot's last submission completed.
    pub fn wait(&self, gpu: &Gpu) -> Result<(), String> {
        // SAFETY: the fence is alive; it is signalled or has a pending submission.
        unsafe { gpu.device.wait_for_fences(&[self.fence], true, u64::MAX) }
            .map_err(vk_err("vkWaitForFences"))
    }

    /// Destroys the pool (and its command buffer), fence and semaphore. The GPU must be
    /// done with them.
    pub fn destroy(self, gpu: &Gpu) {
        let d = &gpu.device;
        // SAFETY: the device is idle (the caller's contract); null handles are ignored.
        unsafe {
            d.destroy_semaphore(self.image_available, None);
            d.destroy_fence(self.fence, None);
            d.destroy_command_pool(self.pool, None);
        }
    }
}
