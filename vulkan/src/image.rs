//! 2D images with one view: the headless renderer's colour and depth targets.

use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

use crate::device::Context;
use crate::error::{Error, Result, VkResultExt};
use crate::target::TargetFormats;

/// What an image is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct ImageDesc {
    /// Width and height in pixels.
    pub(crate) extent: vk::Extent2D,
    /// Pixel format.
    pub(crate) format: vk::Format,
    /// Usage flags.
    pub(crate) usage: vk::ImageUsageFlags,
    /// Aspect of its view.
    pub(crate) aspect: vk::ImageAspectFlags,
    /// Mip levels (1 for targets).
    pub(crate) mip_levels: u32,
}

impl ImageDesc {
    /// An RGBA8 colour target that can be copied out.
    pub(crate) fn colour_target(width: u32, height: u32) -> Self {
        Self {
            extent: vk::Extent2D { width, height },
            format: TargetFormats::HEADLESS.colour,
            usage: vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC,
            aspect: vk::ImageAspectFlags::COLOR,
            mip_levels: 1,
        }
    }

    /// A 32-bit float depth target.
    pub(crate) fn depth_target(width: u32, height: u32) -> Self {
        Self {
            extent: vk::Extent2D { width, height },
            format: TargetFormats::HEADLESS.depth,
            usage: vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
            aspect: vk::ImageAspectFlags::DEPTH,
            mip_levels: 1,
        }
    }
}

/// An image, its memory and its view.
#[derive(Debug)]
pub(crate) struct Image {
    /// The Vulkan handle.
    pub(crate) raw: vk::Image,
    /// Its one view (whole image).
    pub(crate) view: vk::ImageView,
    /// Its description.
    pub(crate) desc: ImageDesc,
    allocation: Allocation,
    id: u64,
}

impl Image {
    /// Creates a device-local image with a view.
    pub(crate) fn new(ctx: &Context, name: &str, desc: ImageDesc) -> Result<Self> {
        if desc.extent.width == 0 || desc.extent.height == 0 {
            return Err(Error::InvalidArgument(format!(
                "image {name}: empty extent {}x{}",
                desc.extent.width, desc.extent.height
            )));
        }
        let d = &ctx.device;
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(desc.format)
            .extent(desc.extent.into())
            .mip_levels(desc.mip_levels.max(1))
            .array_layers(1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(desc.usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: valid create info.
        let raw = unsafe { d.create_image(&info, None) }.vk("vkCreateImage")?;
        // SAFETY: `raw` is alive.
        let requirements = unsafe { d.get_image_memory_requirements(raw) };
        let allocated = ctx.allocate(&AllocationCreateDesc {
            name,
            requirements,
            location: MemoryLocation::GpuOnly,
            linear: false,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let allocation = match allocated {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: `raw` is unused.
                unsafe { d.destroy_image(raw, None) };
                return Err(e);
            }
        };
        let free = |allocation: Allocation| {
            // SAFETY: `raw` is unused.
            unsafe { d.destroy_image(raw, None) };
            let _ = ctx.free(name, allocation);
        };
        // SAFETY: the allocation satisfies `requirements`.
        let bound = unsafe { d.bind_image_memory(raw, allocation.memory(), allocation.offset()) };
        if let Err(e) = bound.vk("vkBindImageMemory") {
            free(allocation);
            return Err(e);
        }
        let view_info = vk::ImageViewCreateInfo::default()
            .image(raw)
            .view_type(vk::ImageViewType::TYPE_2D)
            .format(desc.format)
            .subresource_range(vk::ImageSubresourceRange {
                level_count: desc.mip_levels.max(1),
                ..Self::range(desc.aspect)
            });
        // SAFETY: `raw` is bound to memory.
        let view = match unsafe { d.create_image_view(&view_info, None) }.vk("vkCreateImageView") {
            Ok(v) => v,
            Err(e) => {
                free(allocation);
                return Err(e);
            }
        };
        let id = ctx.track(name);
        Ok(Self {
            raw,
            view,
            desc,
            allocation,
            id,
        })
    }

    /// The whole image's subresource range for `aspect`.
    pub(crate) fn range(aspect: vk::ImageAspectFlags) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange {
            aspect_mask: aspect,
            base_mip_level: 0,
            level_count: 1,
            base_array_layer: 0,
            layer_count: 1,
        }
    }

    /// Destroys view, image and memory. The GPU must be done with them.
    pub(crate) fn destroy(self, ctx: &Context) -> Result<()> {
        // SAFETY: the caller guarantees no pending GPU work uses the image.
        unsafe {
            ctx.device.destroy_image_view(self.view, None);
            ctx.device.destroy_image(self.raw, None);
        }
        ctx.untrack(self.id);
        ctx.free("image free", self.allocation)
    }
}
