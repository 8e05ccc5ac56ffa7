//! # caveclod-core
//!
//! The allocation-free runtime of caveclod: view-dependent continuous level of detail over a
//! hierarchy of vertex splits (Hoppe's view-dependent progressive meshes, organised as in
//! Kram & Shaw's CAVECLOD), with one static [`Hierarchy`] shared by any number of cameras,
//! each keeping its own [`CameraState`] for temporal coherence.
//!
//! - `#![no_std]`, no `alloc` by default: every array is borrowed — the hierarchy from the
//!   baked file's bytes, each camera from a `&mut [u32]` the caller sizes with
//!   [`CameraState::words_needed`].
//! - Never panics on data: [`Hierarchy::from_bytes`] validates every index and invariant once;
//!   operations that meet contradictions return errors.
//! - Inputs are checked in one place each: [`RefineParams::validate`] ([`ParamsError`], which
//!   refinement, [`CameraState::lag`] and [`OctreeCut::select`] return for values out of
//!   range) and [`LookAt::validate`] ([`ViewError`]).
//! - The `.clod` format ([`format`]) is defined here, reader and writer.
//! - The multiresolution octree of out-of-core bakes ([`octree`]) is selected per camera and
//!   emitted the same way, as a cut of its nodes in caller memory.
//! - The shaders' math ([`gpu`]: geomorphing and shading) is defined here too, so the rust-gpu
//!   shaders and the CPU run the same functions.
//! - Geomorphs of refinement (a split's new vertex gliding out of its parent, and back before
//!   a collapse) are per-camera data too: a camera with morph memory
//!   ([`CameraConfig::with_morphs`]) lists its morphing vertices
//!   ([`CameraState::morph_vertices`]) for the GPU to blend, and its morphed emission points
//!   at them.
//! - A [`Regulator`] adapts a camera's pixel tolerance each frame to hold a number of active
//!   polygons (Hoppe's regulation, predicting the count from the front's estimated response
//!   and the view's drift, damped).
//!
//! ```no_run
//! # fn demo(bytes: &[u8]) -> Result<(), Box<dyn core::error::Error>> {
//! use caveclod_core::glam::Vec3;
//! use caveclod_core::{CameraState, Hierarchy, LookAt, RefineParams};
//! let h = Hierarchy::from_bytes(bytes)?;
//! let mut memory = vec![0u32; CameraState::words_needed(&h)];
//! let mut cam = CameraState::new(&h, &mut memory)?;
//! let look = LookAt {
//!     eye: Vec3::new(0.0, 50.0, 200.0),
//!     target: Vec3::ZERO,
//!     up: Vec3::Y,
//!     fov_y: 1.0,
//!     near: 0.1,
//!     far: 1e4,
//! };
//! let view = look.view(1920, 1080);
//! let stats = cam.refine(&h, &view, &RefineParams::default())?;
//! let mut indices = vec![0u32; cam.total_index_count()];
//! let mut offsets = vec![0u32; h.surface_count() + 1];
//! cam.emit_indices_packed(&h, &mut indices, &mut offsets)?;
//! // Draw `indices` with `look.view_projection(1920.0 / 1080.0)`.
//! # let _ = stats; Ok(()) }
//! ```
//!
//! With the `alloc` feature (off by default), `HierarchyBuf` and `OwnedCamera` own their
//! memory, so an asset can keep its hierarchy and cameras without borrowing them.
#![no_std]
#![deny(missing_docs)]
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
// One `unsafe` block with the `prefetch` feature: the cache hint in `prefetch.rs`.
#![cfg_attr(feature = "prefetch", deny(unsafe_code))]
#![cfg_attr(not(feature = "prefetch"), forbid(unsafe_code))]

#[cfg(feature = "alloc")]
extern crate alloc;

mod camera;
mod checksum;
pub mod format;
pub mod gmesh;
pub mod gpu;
mod hierarchy;
mod ids;
mod memory;
pub mod octree;
mod outputs;
#[cfg(feature = "alloc")]
mod owned;
mod params;
mod prefetch;
mod regulator;
mod screen;
pub mod stream;
mod view;

/// The records are `bytemuck::Pod`: `bytemuck::cast_slice(h.vertices())` gives the vertex
/// buffer's bytes to upload, with the crate's own version.
pub use bytemuck;
pub use camera::{
    CameraConfig, CameraError, CameraState, CompactProgress, EmitError, FrontLag, IndexEdit,
    IndexEdits, OpError, RefineStats, SurfaceDraw, COMPACT_STEP,
};
pub use format::error::FormatError;
pub use glam;
pub use gpu::MorphVertex;
pub use hierarchy::{Absent, Hierarchy, HierarchyRecords};
pub use ids::{NodeId, PolyId, PolyKey, PositionId, SurfaceGroupId, SurfaceId};
pub use memory::MemoryReport;
pub use octree::error::OctreeFormatError;
pub use octree::model::Octree;
pub use octree::select::{CutError, OctreeCut, SelectStats};
#[cfg(feature = "alloc")]
pub use owned::{CameraGuard, HierarchyBuf, OwnedCamera};
pub use params::{ParamField, ParamsError, RefineParams};
pub use regulator::Regulator;
pub use view::{LookAt, View, ViewError};
