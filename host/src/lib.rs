//! # caveclod-host
//!
//! What a host engine does around caveclod-vulkan, written once for caveclod's own tools,
//! tests, benches and viewer:
//!
//! - [`GpuMaterials`] ([`materials`]): a hierarchy's material textures decoded and uploaded
//!   once, and the material set a recorder draws with.
//! - [`palette()`]: colours for surfaces without materials.
//! - [`orbit`](orbit::orbit): cameras around a hierarchy, the views a one-shot render or a
//!   viewer starts from.
//! - [`write_png`] ([`png`]): a read-back image written as a PNG file.
#![deny(missing_docs)]

pub mod materials;
pub mod orbit;
pub mod palette;
pub mod png;

pub use materials::GpuMaterials;
pub use orbit::{orbit, orbit_box};
pub use palette::palette;
pub use png::{write_png, PngWriteError};
