//! The bottom layer: what the importers, the out-of-core simplification, the weld (in core
//! and tiled), the blocked build and the writers all stand on, importing nothing of the
//! crate above it.
//!
//! - [`temp`]: the private temporary directory with its byte quota, and the files spilled
//!   into it;
//! - [`atomic`]: files that appear whole or not at all (a temporary sibling, then a rename);
//! - [`progress`]: the stages a bake reports;
//! - [`ply`]: the PLY scalar types and vertex slots both PLY readers decode with;
//! - [`colour`]: sRGB and linear colour conversions;
//! - [`fxhash`]: the fast hasher of the baker's hash maps;
//! - [`memory`]: the process's peak memory, and freed memory handed back to the system.

pub mod atomic;
pub mod colour;
pub mod fxhash;
pub mod memory;
pub mod ply;
pub mod progress;
pub mod temp;
