//! # caveclod-bake
//!
//! From real meshes to baked caveclod hierarchies: importers ([`import`]), welding, repairs
//! and surface groups ([`weld`]), attribute-aware quadric simplification into a balanced
//! hierarchy of half-edge collapses ([`hierarchy`], [`quadric`]), the `.clod` writer
//! ([`baked`]), and the reports and exports of the `caveclod` command-line tool.

pub mod aligned;
pub mod baked;
pub mod demo;
pub mod export;
pub mod flyover;
mod fxhash;
pub mod generate;
pub mod gmesh;
pub mod hierarchy;
pub mod import;
pub mod mesh;
pub mod ooc;
pub mod pipeline;
pub mod quadric;
pub mod report;
pub mod weld;
