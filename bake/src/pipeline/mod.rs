//! Every bake's entry points, from a file or a mesh to the `.clod` arrays or file: in core
//! ([`bake_file`], [`bake_mesh`], [`bake_bytes`]), out of core for files of any size
//! ([`bake_out_of_core`]), and in blocks ([`build_file_spilled`], [`bake_file_blocked`]), with
//! the step they share before the hierarchy: a file imported and welded with the least
//! memory its format allows ([`import_and_weld`]). A bake up to its arrays is a [`Built`] (in
//! blocks, a [`SpilledBuild`]); progress reaches the caller as [`Stage`]s.

mod built;
mod error;
mod import_weld;
mod in_blocks;
mod in_core;
mod out_of_core;

pub use crate::base::progress::Stage;
pub use built::Built;
pub use error::BakeError;
pub use import_weld::{import_and_weld, WeldedFile, WeldedMesh, TILE_TRIANGLES};
pub use in_blocks::{
    bake_file_blocked, bake_mesh_blocked, build_file_blocked, build_file_spilled, BlockedBakeError,
    SpilledBuild,
};
pub use in_core::{bake_bytes, bake_file, bake_mesh, build_file, build_mesh};
pub use out_of_core::{bake_out_of_core, build_out_of_core, OutOfCoreBake, OutOfCoreBuild};
