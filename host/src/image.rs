//! The host's images and read-back buffers, from its own allocator.

use caveclod_vulkan::ash::vk;
use caveclod_vulkan::gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use caveclod_vulkan::gpu_allocator::MemoryLocation;
use caveclod_vulkan::RgbaImage;

use crate::error::{allocation, Error, Result, VkExt};
use crate::host::Host;

/// What an [`Image`] is made with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImageDesc {
    /// Its format.
    pub format: vk::Format,
    /// Its size.
    pub extent: vk::Extent2D,
    /// Samples per texel.
    pub samples: vk::SampleCountFlags,
    /// What it is used for.
    pub usage: vk::ImageUsageFlags,
}

/// A device-local 2D image of the host's, one mip level and layer, with its view.
pub struct Image {
    /// The image.
    pub raw: vk::Image,
    /// A view of all of it (every aspect of its format).
    pub view: vk::ImageView,
    /// What it was made with.
    pub desc: ImageDesc,
    allocation: Option<Allocation>,
}

impl Image {
    /// An image of `desc` with memory from the host's allocator; `name` names the
    /// allocation.
    pub fn new(host: &Host, name: &str, desc: ImageDesc) -> Result<Self> {
        let d = host.device();
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(desc.format)
            .extent(desc.extent.into())
            .mip_levels(1)
            .array_layers(1)
            .samples(desc.samples)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(desc.usage)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: valid create info.
        let raw = unsafe { d.create_image(&info, None) }.vk("vkCreateImage")?;
        let mut image = Self {
            raw,
            view: vk::ImageView::null(),
            desc,
            allocation: None,
        };
        match image.bind_and_view(host, name) {
            Ok(()) => Ok(image),
            Err(e) => {
                let _ = image.destroy(host);
                Err(e)
            }
        }
    }

    /// No image: null handles, which [`destroy`](Self::destroy) ignores (a placeholder
    /// until the real one is made).
    pub(crate) fn null(format: vk::Format) -> Self {
        Self {
            raw: vk::Image::null(),
            view: vk::ImageView::null(),
            desc: ImageDesc {
                format,
                extent: vk::Extent2D::default(),
                samples: vk::SampleCountFlags::TYPE_1,
                usage: vk::ImageUsageFlags::empty(),
            },
            allocation: None,
        }
    }

    fn bind_and_view(&mut self, host: &Host, name: &str) -> Result<()> {
        let d = host.device();
        // SAFETY: the image is alive.
        let requirements = unsafe { d.get_image_memory_requirements(self.raw) };
        let memory = lock(host)
            .allocate(&AllocationCreateDesc {
                name,
                requirements,
                location: MemoryLocation::GpuOnly,
                linear: false,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
            .map_err(allocation(name))?;
        // SAFETY: the allocation meets the image's requirements; the image is bound once.
        let bound = unsafe { d.bind_image_memory(self.raw, memory.memory(), memory.offset()) };
        self.allocation = Some(memory);
        bound.vk("vkBindImageMemory")?;
        let view = vk::ImageViewCreateInfo::default()
            .image(self.raw)
            .view_type(vk::ImageViewType::TYPE_2D)
            .format(self.desc.format)
            .subresource_range(range(aspect(self.desc.format)));
        // SAFETY: the image is bound to memory.
        self.view = unsafe { d.create_image_view(&view, None) }.vk("vkCreateImageView")?;
        Ok(())
    }

    /// Destroys the view and the image and frees the memory. The GPU must be done with
    /// them.
    pub fn destroy(mut self, host: &Host) -> Result<()> {
        let d = host.device();
        // SAFETY: the GPU is done with the image (the caller's contract); null handles are
        // ignored.
        unsafe {
            d.destroy_image_view(self.view, None);
            d.destroy_image(self.raw, None);
        }
        match self.allocation.take() {
            Some(a) => lock(host).free(a).map_err(allocation("an image")),
            None => Ok(()),
        }
    }
}

/// A host-visible buffer the GPU copies an image into, from the host's allocator.
pub struct ReadbackBuffer {
    /// The buffer.
    pub raw: vk::Buffer,
    size: u64,
    allocation: Option<Allocation>,
}

impl ReadbackBuffer {
    /// A buffer of `size` bytes, transfer destination, mapped for host reads.
    pub fn new(host: &Host, name: &str, size: u64) -> Result<Self> {
        let d = host.device();
        let info = vk::BufferCreateInfo::default()
            .size(size)
            .usage(vk::BufferUsageFlags::TRANSFER_DST)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: valid create info.
        let raw = unsafe { d.create_buffer(&info, None) }.vk("vkCreateBuffer")?;
        let mut buffer = Self {
            raw,
            size,
            allocation: None,
        };
        // SAFETY: the buffer is alive.
        let requirements = unsafe { d.get_buffer_memory_requirements(raw) };
        let memory = lock(host).allocate(&AllocationCreateDesc {
            name,
            requirements,
            location: MemoryLocation::GpuToCpu,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let bound = memory.map_err(allocation(name)).and_then(|m| {
            // SAFETY: the allocation meets the buffer's requirements; bound once.
            let r = unsafe { d.bind_buffer_memory(raw, m.memory(), m.offset()) };
            buffer.allocation = Some(m);
            r.vk("vkBindBufferMemory")
        });
        match bound {
            Ok(()) => Ok(buffer),
            Err(e) => {
                let _ = buffer.destroy(host);
                Err(e)
            }
        }
    }

    /// The bytes the GPU copied (valid once the copy's submission completed).
    pub fn bytes(&self) -> Result<&[u8]> {
        self.allocation
            .as_ref()
            .and_then(|a| a.mapped_slice())
            .and_then(|b| b.get(..self.size as usize))
            .ok_or_else(|| Error::InvalidArgument("read-back memory is not mapped".into()))
    }

    /// The copied image of `extent` in `format` as RGBA8 (BGRA formats swizzled; sRGB
    /// values as stored).
    pub fn image(&self, extent: vk::Extent2D, format: vk::Format) -> Result<RgbaImage> {
        let n = 4 * extent.width as usize * extent.height as usize;
        let mut pixels = self
            .bytes()?
            .get(..n)
            .ok_or_else(|| Error::InvalidArgument(format!("{n} bytes of {}", self.size)))?
            .to_vec();
        if matches!(
            format,
            vk::Format::B8G8R8A8_UNORM | vk::Format::B8G8R8A8_SRGB
        ) {
            for p in pixels.chunks_exact_mut(4) {
                p.swap(0, 2);
            }
        }
        Ok(RgbaImage {
            width: extent.width,
            height: extent.height,
            pixels,
        })
    }

    /// Destroys the buffer and frees its memory. The GPU must be done with it.
    pub fn destroy(mut self, host: &Host) -> Result<()> {
        // SAFETY: the GPU is done with the buffer (the caller's contract).
        unsafe { host.device().destroy_buffer(self.raw, None) };
        match self.allocation.take() {
            Some(a) => lock(host).free(a).map_err(allocation("a read-back buffer")),
            None => Ok(()),
        }
    }
}

/// The host's allocator, locked (a poisoned lock still guards a consistent allocator: its
/// calls do not panic midway).
fn lock(
    host: &Host,
) -> std::sync::MutexGuard<'_, caveclod_vulkan::gpu_allocator::vulkan::Allocator> {
    host.allocator().lock().unwrap_or_else(|p| p.into_inner())
}

/// The aspects of `format`: depth and stencil for a depth format, else colour.
pub fn aspect(format: vk::Format) -> vk::ImageAspectFlags {
    match format {
        vk::Format::D16_UNORM | vk::Format::D32_SFLOAT | vk::Format::X8_D24_UNORM_PACK32 => {
            vk::ImageAspectFlags::DEPTH
        }
        vk::Format::D16_UNORM_S8_UINT
        | vk::Format::D24_UNORM_S8_UINT
        | vk::Format::D32_SFLOAT_S8_UINT => {
            vk::ImageAspectFlags::DEPTH | vk::ImageAspectFlags::STENCIL
        }
        vk::Format::S8_UINT => vk::ImageAspectFlags::STENCIL,
        _ => vk::ImageAspectFlags::COLOR,
    }
}

/// The first mip level and layer of `aspect`.
pub fn range(aspect: vk::ImageAspectFlags) -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange {
        aspect_mask: aspect,
        base_mip_level: 0,
        level_count: 1,
        base_array_layer: 0,
        layer_count: 1,
    }
}
