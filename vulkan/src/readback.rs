//! Read-back pixels: an RGBA8 image, crops and comparisons (encoding it is the
//! application's business), and [`ImageReadback`], which copies a host's colour image into
//! host memory by commands recorded into the host's command buffer.

use ash::vk;

use crate::buffer::{Buffer, BufferDesc};
use crate::device::Context;
use crate::error::{Error, Result};
use crate::viewport::Viewport;

/// Pixels of a colour target, RGBA8, rows top to bottom.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RgbaImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height * 4` bytes.
    pub pixels: Vec<u8>,
}

/// How two images differ.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImageDiff {
    /// Pixels compared.
    pub pixels: u64,
    /// Pixels equal in every channel.
    pub equal: u64,
    /// Pixels whose channels all differ by at most 1 (of 255).
    pub within_one: u64,
    /// Largest channel difference.
    pub max_channel_difference: u8,
    /// Mean absolute channel difference.
    pub mean_channel_difference: f64,
}

impl ImageDiff {
    /// Fraction of pixels within 1/255 in every channel.
    pub fn within_one_fraction(&self) -> f64 {
        self.within_one as f64 / self.pixels.max(1) as f64
    }

    /// Fraction of identical pixels.
    pub fn equal_fraction(&self) -> f64 {
        self.equal as f64 / self.pixels.max(1) as f64
    }
}

impl RgbaImage {
    /// The RGBA of pixel (x, y), if inside.
    pub fn pixel(&self, x: u32, y: u32) -> Option<[u8; 4]> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let i = 4 * (y as usize * self.width as usize + x as usize);
        let p = self.pixels.get(i..i + 4)?;
        Some([p[0], p[1], p[2], p[3]])
    }

    /// The part of the image under `v`.
    pub fn crop(&self, v: Viewport) -> Result<Self> {
        if v.x + v.width > self.width || v.y + v.height > self.height {
            return Err(Error::InvalidArgument(format!(
                "crop {v:?} outside a {}x{} image",
                self.width, self.height
            )));
        }
        let mut pixels = Vec::with_capacity(v.width as usize * v.height as usize * 4);
        for y in v.y..v.y + v.height {
            let start = 4 * (y as usize * self.width as usize + v.x as usize);
            pixels.extend_from_slice(&self.pixels[start..start + 4 * v.width as usize]);
        }
        Ok(Self {
            width: v.width,
            height: v.height,
            pixels,
        })
    }

    /// Per-pixel comparison with an image of the same size.
    pub fn diff(&self, other: &Self) -> Result<ImageDiff> {
        if (self.width, self.height) != (other.width, other.height) {
            return Err(Error::InvalidArgument(format!(
                "comparing a {}x{} image with a {}x{} one",
                self.width, self.height, other.width, other.height
            )));
        }
        let mut d = ImageDiff::default();
        let mut sum = 0u64;
        for (a, b) in self
            .pixels
            .chunks_exact(4)
            .zip(other.pixels.chunks_exact(4))
        {
            let m = a
                .iter()
                .zip(b)
                .map(|(x, y)| x.abs_diff(*y))
                .max()
                .unwrap_or(0);
            sum += a
                .iter()
                .zip(b)
                .map(|(x, y)| u64::from(x.abs_diff(*y)))
                .sum::<u64>();
            d.pixels += 1;
            d.equal += u64::from(m == 0);
            d.within_one += u64::from(m <= 1);
            d.max_channel_difference = d.max_channel_difference.max(m);
        }
        d.mean_channel_difference = sum as f64 / (4 * d.pixels.max(1)) as f64;
        Ok(d)
    }

    /// Pixels that differ from `background` in some channel.
    pub fn covered(&self, background: [u8; 4]) -> u64 {
        self.pixels
            .chunks_exact(4)
            .filter(|p| *p != background.as_slice())
            .count() as u64
    }
}

/// A colour target's pixels on their way to the host, recorded into the caller's command
/// buffer after its rendering (a screenshot of a host's frame, a test's check): a barrier
/// from the colour attachment writes to a copy into a host-visible buffer, the copy, and a
/// barrier to host reads. The caller submits and waits.
#[derive(Debug)]
pub struct ImageReadback {
    buffer: Buffer,
    extent: vk::Extent2D,
    bgra: bool,
}

impl ImageReadback {
    /// Records into `cmd` (recording, outside rendering) the read-back of `image`'s first
    /// mip level and layer: `extent` texels of `format` (RGBA8 or BGRA8, UNORM or sRGB; one
    /// sample), last written as a colour attachment and now in `layout`
    /// (`COLOR_ATTACHMENT_OPTIMAL`, `TRANSFER_SRC_OPTIMAL` or `GENERAL`). The image is left in
    /// `TRANSFER_SRC_OPTIMAL` (`GENERAL` stays `GENERAL`); keep it alive until `cmd` has
    /// executed.
    pub fn record(
        ctx: &Context,
        cmd: vk::CommandBuffer,
        image: vk::Image,
        layout: vk::ImageLayout,
        format: vk::Format,
        extent: vk::Extent2D,
    ) -> Result<Self> {
        let bgra = match format {
            vk::Format::R8G8B8A8_UNORM | vk::Format::R8G8B8A8_SRGB => false,
            vk::Format::B8G8R8A8_UNORM | vk::Format::B8G8R8A8_SRGB => true,
            _ => {
                return Err(Error::InvalidArgument(format!(
                    "read-back of {format:?}: RGBA8 or BGRA8 expected"
                )))
            }
        };
        let size = u64::from(extent.width) * u64::from(extent.height) * 4;
        if size == 0 {
            return Err(Error::InvalidArgument(format!(
                "read-back of an empty {}x{} image",
                extent.width, extent.height
            )));
        }
        let buffer = Buffer::new(
            ctx,
            "image read-back",
            BufferDesc::gpu_to_cpu(size, vk::BufferUsageFlags::TRANSFER_DST),
        )?;
        record_copy_out(&ctx.device, cmd, image, layout, extent, buffer.raw);
        Ok(Self {
            buffer,
            extent,
            bgra,
        })
    }

    /// The pixels as RGBA8 (BGRA swizzled), rows top to bottom; valid once the command
    /// buffer [`record`](Self::record) recorded into has executed and been waited for.
    pub fn image(&self) -> Result<RgbaImage> {
        let n = self.buffer.desc.size as usize;
        let mut pixels = match self.buffer.mapped() {
            Some(bytes) if bytes.len() >= n => bytes[..n].to_vec(),
            _ => {
                return Err(Error::InvalidArgument(
                    "read-back memory is not host-visible".into(),
                ))
            }
        };
        if self.bgra {
            for p in pixels.chunks_exact_mut(4) {
                p.swap(0, 2);
            }
        }
        Ok(RgbaImage {
            width: self.extent.width,
            height: self.extent.height,
            pixels,
        })
    }

    /// Destroys the buffer. The GPU must be done with the command buffer that copied into
    /// it.
    pub fn destroy(self, ctx: &Context) -> Result<()> {
        self.buffer.destroy(ctx)
    }
}

/// Records the copy of colour `image` (single-sample, in `layout` after colour-attachment
/// writes) into `buffer` (tightly packed 4-byte texels of `extent`): a barrier from the
/// attachment writes into a copy source layout, the copy, and a barrier making it visible
/// to host reads once the submission completed. `cmd` must be recording outside rendering.
pub(crate) fn record_copy_out(
    d: &ash::Device,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    layout: vk::ImageLayout,
    extent: vk::Extent2D,
    buffer: vk::Buffer,
) {
    let copy_layout = match layout {
        vk::ImageLayout::GENERAL => vk::ImageLayout::GENERAL,
        _ => vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
    };
    let to_copy = [vk::ImageMemoryBarrier2::default()
        .src_stage_mask(vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT)
        .src_access_mask(vk::AccessFlags2::COLOR_ATTACHMENT_WRITE)
        .dst_stage_mask(vk::PipelineStageFlags2::COPY)
        .dst_access_mask(vk::AccessFlags2::TRANSFER_READ)
        .old_layout(layout)
        .new_layout(copy_layout)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(
            vk::ImageSubresourceRange::default()
                .aspect_mask(vk::ImageAspectFlags::COLOR)
                .level_count(1)
                .layer_count(1),
        )];
    let region = [vk::BufferImageCopy::default()
        .image_subresource(
            vk::ImageSubresourceLayers::default()
                .aspect_mask(vk::ImageAspectFlags::COLOR)
                .layer_count(1),
        )
        .image_extent(extent.into())];
    let to_host = [vk::BufferMemoryBarrier2::default()
        .src_stage_mask(vk::PipelineStageFlags2::COPY)
        .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
        .dst_stage_mask(vk::PipelineStageFlags2::HOST)
        .dst_access_mask(vk::AccessFlags2::HOST_READ)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .buffer(buffer)
        .size(vk::WHOLE_SIZE)];
    let before = vk::DependencyInfo::default().image_memory_barriers(&to_copy);
    let after = vk::DependencyInfo::default().buffer_memory_barriers(&to_host);
    // SAFETY: `cmd` is recording outside rendering and `image` is a live single-sample
    // colour image in `layout` (the callers' contract); the buffer holds `extent` texels
    // of 4 bytes.
    unsafe {
        d.cmd_pipeline_barrier2(cmd, &before);
        d.cmd_copy_image_to_buffer(cmd, image, copy_layout, buffer, &region);
        d.cmd_pipeline_barrier2(cmd, &after);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 4]) -> RgbaImage {
        let mut pixels = Vec::new();
        for y in 0..h {
            for x in 0..w {
                pixels.extend_from_slice(&f(x, y));
            }
        }
        RgbaImage {
            width: w,
            height: h,
            pixels,
        }
    }

    #[test]
    fn crop_and_diff() {
        let a = image(4, 4, |x, y| [x as u8, y as u8, 0, 255]);
        let c = a
            .crop(Viewport {
                x: 2,
                y: 1,
                width: 2,
                height: 3,
            })
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(c.pixel(0, 0), Some([2, 1, 0, 255]));
        assert_eq!(c.pixel(1, 2), Some([3, 3, 0, 255]));
        let b = image(4, 4, |x, y| [x as u8 + u8::from(x == 3), y as u8, 0, 255]);
        let d = a.diff(&b).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!((d.pixels, d.equal, d.within_one), (16, 12, 16));
        assert_eq!(d.max_channel_difference, 1);
        assert_eq!(a.covered([0, 0, 0, 255]), 15);
    }
}
