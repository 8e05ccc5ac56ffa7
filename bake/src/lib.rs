//! # caveclod-bake
//!
//! From real meshes to baked caveclod hierarchies, as a library for asset pipelines and build
//! scripts: importers ([`import`], each format a cargo feature), welding, repairs and surface
//! groups ([`weld`]), attribute-aware quadric simplification into a balanced hierarchy of
//! half-edge collapses ([`hierarchy`], [`quadric`]), the same hierarchy built in blocks for meshes
//! too large for one build ([`blocked`]), g-mesh levels ([`gmesh`]), out-of-core
//! simplification with a multiresolution octree ([`ooc`]), materials and vertex colours
//! ([`materials`]), the `.clod` writer ([`baked`]; section by section, [`clod_file`]; one array at a time from
//! the collapses, [`streamed`]),
//! and OBJ export ([`export`]). [`pipeline`] runs the whole bake; progress reaches the caller
//! through the callbacks it passes. The `caveclod` command-line tool is `caveclod-cli`.

mod arrays;
pub mod baked;
pub mod blocked;
pub mod clod_file;
pub mod export;
mod fxhash;
pub mod generate;
pub mod gmesh;
pub mod hierarchy;
pub mod import;
pub mod materials;
pub mod mesh;
pub mod ooc;
pub mod pipeline;
pub mod quadric;
pub mod report;
pub mod streamed;
pub mod weld;
pub mod weld_store;
