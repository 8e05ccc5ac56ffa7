//! # caveclod-vulkan
//!
//! Renders caveclod hierarchies with Vulkan (ash 0.38 + gpu-allocator 0.28, both
//! re-exported so users never mix versions) and the rust-gpu shaders committed as SPIR-V in
//! `vulkan/spirv/`.
//!
//! - [`Context`]: *embedded* in a host engine ([`Context::from_raw`]: the host's instance,
//!   device, queue, optionally allocator, and the features it enabled, checked against
//!   [`DeviceFeatures::REQUIRED`]; no instance is created) or *headless*
//!   ([`Context::headless`]: own instance and device, lavapipe preferred, validation layer
//!   enabled when installed and its messages recorded in a [`ValidationLog`]).
//! - Per baked mesh one device-local [`VertexBuffer`], uploaded once (submitted, or recorded
//!   into the host's command buffer with [`VertexBuffer::record_upload`]) and never
//!   rewritten ([`Context::vertex_uploads`] counts uploads).
//! - Per streamed hierarchy a [`VertexPool`]: the vertices of the resident pages in a
//!   device buffer of a fixed size, slot for slot beside the page pool, installs recorded
//!   into the host's command buffer.
//! - Per camera [`CameraIndices`]: per surface a host-visible index buffer in each slot of a
//!   ring over the host's frames in flight, grown by doubling, filled by caveclod-core's
//!   index emission.
//! - **The record path**, [`Recorder`]: pipelines for the host's [`TargetFormats`] and
//!   [`Rendering`] (dynamic rendering or its render pass and subpass); [`Recorder::record`]
//!   draws 1-4 cameras ([`RecordCamera`], split-screen [`Viewport`]s) into the host's command
//!   buffer inside its rendering: no submission, no wait, no queue lock.
//! - Materials: [`Texture`] (RGBA8, mip chain) and [`MaterialSet`] (per surface texture ×
//!   factor, alpha cutoff); without one, a palette colour per surface.
//! - [`ImageReadback`]: a host's colour image copied into host memory by commands recorded
//!   into the host's command buffer (screenshots, checks).
//! - [`Renderer`]: the headless convenience over the recorder (RGBA8 + D32 targets, command
//!   pool, fences, one submission per frame, [`RgbaImage`] read-back) for tests and tools;
//!   its cameras are the record path's [`RecordCamera`]s, their rings filled by the caller
//!   for the slot [`Renderer::begin_frame`] returns, as on the record path.
//! - Geomorphs: [`Geomorph`] runs the compute stage (read back for comparison with the
//!   CPU); a camera with a [`Morph`] draws through the geomorphing vertex stage.
//!
//! Everything is destroyed explicitly (`destroy(self, &Context)`); [`Context::destroy`]
//! reports resources still alive as [`Error::Leaked`].
//!
//! Faults are typed ([`Error::OutOfMemory`], [`Error::DeviceLost`]) and can be injected for
//! tests through [`Context::faults`]: [`Faults::exhaust_memory_after`] fails the n-th device
//! allocation this crate makes (and every later one until restored), and
//! [`Faults::lose_device_after`] loses the device at the n-th submission or wait. A lost
//! device's objects are still destroyed cleanly.
//!
//! ```no_run
//! # fn demo(bytes: &[u8]) -> caveclod_vulkan::Result<()> {
//! use caveclod_core::{CameraState, Hierarchy, RefineParams};
//! use caveclod_vulkan::*;
//! let h = Hierarchy::from_bytes(bytes)?;
//! let ctx = Context::headless(&HeadlessDesc::default())?;
//! let vertices = VertexBuffer::from_hierarchy(&ctx, "mesh", &h)?;
//! let mut renderer = Renderer::new(&ctx, RendererDesc::single(256, 256))?;
//! let mut indices = CameraIndices::new("camera 0", h.surface_count(), 2);
//! let mut memory = vec![0u32; CameraState::words_needed(&h)];
//! let mut cam = CameraState::new(&h, &mut memory)?;
//! let look = LookAt {
//!     eye: glam::Vec3::new(0.0, 5.0, 10.0),
//!     target: glam::Vec3::ZERO,
//!     up: glam::Vec3::Y,
//!     fov_y: 1.0,
//!     near: 0.1,
//!     far: 100.0,
//! };
//! let viewport = Viewport::full(256, 256);
//! cam.refine(&h, &look.view(viewport.width, viewport.height), &RefineParams::default())?;
//! let colours = vec![[0.8, 0.7, 0.6, 1.0]; h.surface_count()];
//! let slot = renderer.begin_frame(&ctx)?;
//! indices.fill(&ctx, slot, IndexSource::camera(&h, &cam))?;
//! let view_proj = look.view_projection(viewport.aspect());
//! let camera = RecordCamera::new(viewport, view_proj, &vertices, &indices).colours(&colours);
//! renderer.render(&ctx, &[(0, camera)])?;
//! let image = renderer.read_target(&ctx, 0)?;
//! assert_eq!(image.pixels.len(), 256 * 256 * 4);
//! renderer.destroy(&ctx)?;
//! indices.destroy(&ctx)?;
//! vertices.destroy(&ctx)?;
//! ctx.destroy()
//! # }
//! ```
#![deny(missing_docs)]
#![deny(clippy::unwrap_used, clippy::expect_used)]

pub use ash;
pub use gpu_allocator;

mod buffer;
mod camera_morphs;
mod device;
mod error;
mod fault;
mod frame;
mod geomorph;
mod image;
mod index_edits;
mod indices;
mod instance;
mod material;
mod mesh;
mod pipeline;
mod readback;
mod record;
mod requirements;
mod target;
mod texture;
mod validation;
mod vertex_pool;
mod viewport;

pub use buffer::{Buffer, BufferDesc};
pub use camera_morphs::{CameraMorphs, MorphStage};
pub use caveclod_core::LookAt;
pub use device::headless::HeadlessDesc;
pub use device::{Context, HostDevice, SharedAllocator};
pub use error::{Error, Result};
pub use fault::Faults;
pub use frame::{FrameStats, Renderer, RendererDesc};
pub use geomorph::Geomorph;
pub use indices::{CameraIndices, IndexSource};
pub use material::{MaterialSet, SurfaceMaterial};
pub use mesh::{MorphInstances, Staging, VertexBuffer, VERTEX_STRIDE};
pub use readback::{ImageDiff, ImageReadback, RgbaImage};
pub use record::{Morph, RecordCamera, Recorder};
pub use requirements::{DeviceFeatures, FeatureChain, API_VERSION};
pub use target::{RecorderDesc, Rendering, TargetFormats};
pub use texture::{Texture, TextureDesc};
pub use validation::{DebugMessenger, ValidationLog, VALIDATION_LAYER};
pub use vertex_pool::VertexPool;
pub use viewport::Viewport;
