//! # caveclod-bake
//!
//! From real meshes to baked caveclod hierarchies, as a library for asset pipelines and build
//! scripts: importers ([`import`], each format a cargo feature), welding, repairs and surface
//! groups ([`weld`]), attribute-aware quadric simplification into a balanced hierarchy of
//! half-edge collapses ([`hierarchy`], [`quadric`]), the same hierarchy built in blocks for
//! meshes too large for one build ([`blocked`]), g-mesh levels ([`gmesh`]), out-of-core
//! simplification with a multiresolution octree ([`ooc`]), materials and vertex colours
//! ([`materials`]), the `.clod` writer ([`baked`]; section by section, [`clod_file`]; one array
//! at a time from the collapses, [`streamed`]), and OBJ export ([`export`]). [`pipeline`] runs
//! the whole bake; progress reaches the caller through the callbacks it passes. The `caveclod`
//! command-line tool is `caveclod-cli`.
//!
//! ## Layers
//!
//! The modules are layers, bottom to top; a module imports only from the layers below it
//! (and, inside a layer, from modules listed before it), and the files of a module import
//! only files below them, so there is no import circle:
//!
//! 1. base (`base`): temporary space and the files spilled into it, files written whole or
//!    not at all, the progress stages, the PLY scalar types and vertex slots, colour
//!    encodings, the process's memory, the hasher;
//! 2. model ([`mesh`], [`materials`], [`quadric`]): the imported mesh, its surfaces'
//!    materials, the attribute-aware quadrics;
//! 3. readers ([`import`], [`ooc`]): files to a [`mesh::Mesh`], whole files in core, files of
//!    any size streamed and simplified out of core (whose stream readers also feed the tiled
//!    weld);
//! 4. weld ([`weld`], with [`weld::store`] and [`weld::tiled`]): the welded mesh in memory, on
//!    disk in block order, and welded tile by tile;
//! 5. build ([`hierarchy`], [`gmesh`]): the collapse hierarchy of a welded mesh, g-mesh levels
//!    of a baked one;
//! 6. writer (`arrays`, [`clod_file`], [`baked`], [`streamed`], [`export`], [`report`]): the
//!    `.clod` arrays and file, the OBJ export, the bake's report;
//! 7. blocked ([`blocked`]): the hierarchy built in blocks, its collapses on disk, and their
//!    file;
//! 8. pipeline ([`pipeline`]): every bake's entry points, in core, out of core and in blocks.
//!
//! Beside them, [`generate`] makes procedural meshes (terrains, spheres) and terrain files to
//! try and test bakes on, from the model and base layers only.

mod arrays;
pub mod baked;
mod base;
pub mod blocked;
pub mod clod_file;
pub mod export;
pub mod generate;
pub mod gmesh;
pub mod hierarchy;
pub mod import;
pub mod materials;
pub mod mesh;
pub mod ooc;
pub mod paged;
pub mod pipeline;
pub mod quadric;
pub mod report;
pub mod streamed;
pub mod weld;

/// The welded store ([`weld::store`]) under its own name.
pub use weld::store as weld_store;
