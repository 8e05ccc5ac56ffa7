//! # caveclod-host
//!
//! What a host engine does around caveclod-vulkan, written once for caveclod's own tools,
//! tests, benchmarks and viewer, in the spirit of ash-examples' `ExampleBase`:
//!
//! - [`Host`] ([`host`]): the loader, an instance (with the Khronos validation layer and a
//!   debug messenger recording into a `ValidationLog` when asked), a physical device chosen
//!   by [`HostDesc`] (lavapipe first when asked), a device with caveclod's features, one
//!   queue and a gpu-allocator shared with caveclod; [`Host::context`] hands them to
//!   `Context::from_raw`. With the `window` feature, `Host::windowed` also makes a winit
//!   window's surface and a device that presents to it.
//! - [`Frames`] ([`frames`]): frames in flight, each slot a command buffer, a fence and, for
//!   a swapchain, an acquire semaphore.
//! - [`Target`] ([`target`]): a windowless target (colour of any format and sample count,
//!   resolve, depth-stencil; the host's own render pass or dynamic rendering; read-back).
//! - `Swapchain` (`swapchain`, the `window` feature): the window's swapchain with its depth
//!   image, recreated when the window changes.
//! - [`rendering`]: the barriers and the rendering a host records around caveclod's draws,
//!   shared by the targets and the swapchain; [`image`]: the host's images and read-back
//!   buffers.
//! - [`GpuMaterials`] ([`materials`]): a hierarchy's material textures decoded and uploaded
//!   once, and the material set a recorder draws with; [`palette()`]: colours for surfaces
//!   without materials; [`terrain_colours`]: a terrain tinted by height and slope;
//!   [`orbit`](orbit::orbit): cameras around a hierarchy; [`write_png`]
//!   ([`png`]): a read-back image written as a PNG file.
//!
//! Every object is destroyed explicitly (`destroy(self, &Host)`), in reverse order of
//! creation; [`Host::destroy`] reports allocations left behind.
//!
//! ```no_run
//! # fn demo() -> caveclod_host::Result<()> {
//! use caveclod_host::{Frames, Host, HostDesc, Target, TargetDesc};
//! use caveclod_vulkan::{Recorder, RecorderDesc, TargetFormats};
//! let host = Host::headless(&HostDesc::default())?;
//! let ctx = host.context()?;
//! let target = Target::new(&host, TargetDesc::new(TargetFormats::HEADLESS, 256, 256))?;
//! let recorder = Recorder::new(&ctx, RecorderDesc::dynamic(target.formats()))?;
//! let mut frames = Frames::new(&host, 1, false)?;
//! frames.submit_and_wait(&host, 0, |cmd| {
//!     target.begin(&host, cmd);
//!     // caveclod records its cameras here: recorder.record(&ctx, cmd, 0, &cameras)
//!     target.end(&host, cmd);
//! })?;
//! let image = target.pixels()?;
//! assert_eq!(image.pixels.len(), 256 * 256 * 4);
//! frames.destroy(&host)?;
//! recorder.destroy(&ctx)?;
//! target.destroy(&host)?;
//! ctx.destroy()?;
//! host.destroy()
//! # }
//! ```
#![deny(missing_docs)]
#![deny(clippy::unwrap_used, clippy::expect_used)]

pub mod error;
pub mod frames;
pub mod host;
pub mod image;
mod instance;
pub mod materials;
pub mod orbit;
pub mod palette;
pub mod png;
pub mod rendering;
mod select;
#[cfg(feature = "window")]
mod surface;
#[cfg(feature = "window")]
pub mod swapchain;
pub mod target;
pub mod terrain;

pub use error::{Error, Result};
pub use frames::Frames;
pub use host::{Host, HostDesc};
pub use image::{Image, ImageDesc, ReadbackBuffer};
pub use materials::GpuMaterials;
pub use orbit::{orbit, orbit_box};
pub use palette::{hue, palette};
pub use png::{write_png, PngWriteError};
pub use rendering::Attachments;
#[cfg(feature = "window")]
pub use swapchain::{Acquired, Swapchain, SwapchainDesc};
pub use target::{Target, TargetDesc, TargetRendering};
pub use terrain::terrain_colours;
