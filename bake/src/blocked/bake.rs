//! A whole bake in blocks: import, weld, the blocked hierarchy, the `.clod` arrays and
//! their validation, as [`crate::pipeline::bake_file`] does in one build.

use std::path::Path;
use std::time::Instant;

use super::{build, BlockedError, BlockedOptions, LevelStats};
use crate::baked::Baked;
use crate::hierarchy::AttributeWeights;
use crate::import::{self, ImportOptions};
use crate::mesh::{Mesh, Surface};
use crate::pipeline::{built, weld_mesh, BakeError, Built, Stage};
use crate::report::BakeInfo;
use crate::weld;

/// Why a blocked bake failed.
#[derive(Debug, thiserror::Error)]
pub enum BlockedBakeError {
    /// Importing, welding or validating failed as in an in-core bake.
    #[error(transparent)]
    Bake(#[from] BakeError),
    /// The blocked build failed (a baker bug).
    #[error("{path}: {source}")]
    Blocked {
        /// The input.
        path: String,
        /// Why.
        source: BlockedError,
    },
}

/// Imports `path` and bakes it in blocks; `bake_seconds` includes the import.
pub fn bake_file_blocked(
    path: &Path,
    import_options: &ImportOptions,
    options: &BlockedOptions,
    progress: &mut dyn FnMut(Stage),
) -> Result<(Baked, BakeInfo, Vec<LevelStats>), BlockedBakeError> {
    let (built, levels) = build_file_blocked(path, import_options, options, progress)?;
    let (baked, info) = built.assemble(progress)?;
    Ok((baked, info, levels))
}

/// [`bake_file_blocked`] up to the arrays ([`Built`]). The imported mesh is dropped once
/// welded (only its surfaces are kept), so the two never take memory at once.
pub fn build_file_blocked(
    path: &Path,
    import_options: &ImportOptions,
    options: &BlockedOptions,
    progress: &mut dyn FnMut(Stage),
) -> Result<(Built, Vec<LevelStats>), BlockedBakeError> {
    let start = Instant::now();
    progress(Stage::Import);
    let (mut mesh, report) =
        import::import_with_report(path, import_options).map_err(BakeError::from)?;
    let name = path.display().to_string();
    let w = weld_mesh(&mesh, &name, progress)?;
    let (surfaces, triangles) = (std::mem::take(&mut mesh.surfaces), mesh.triangles.len());
    drop(mesh);
    let (mut built, levels) =
        build_welded(w, surfaces, triangles, &name, options, start, progress)?;
    built.texture_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    built.info.repairs.skipped_primitives = report.skipped_primitives as u64;
    built.info.notes = report.notes;
    Ok((built, levels))
}

/// Bakes a mesh in blocks: welds it, builds its hierarchy level by level
/// ([`super::build`]), assembles and validates the arrays.
pub fn bake_mesh_blocked(
    mesh: &Mesh,
    name: &str,
    options: &BlockedOptions,
    progress: &mut dyn FnMut(Stage),
) -> Result<(Baked, BakeInfo, Vec<LevelStats>), BlockedBakeError> {
    let start = Instant::now();
    let w = weld_mesh(mesh, name, progress)?;
    let (built, levels) = build_welded(
        w,
        mesh.surfaces.clone(),
        mesh.triangles.len(),
        name,
        options,
        start,
        progress,
    )?;
    let (baked, info) = built.assemble(progress)?;
    Ok((baked, info, levels))
}

/// The step after welding: the blocked hierarchy.
fn build_welded(
    w: weld::Welded,
    surfaces: Vec<Surface>,
    input_triangles: usize,
    name: &str,
    options: &BlockedOptions,
    start: Instant,
    progress: &mut dyn FnMut(Stage),
) -> Result<(Built, Vec<LevelStats>), BlockedBakeError> {
    let made = build(
        &w,
        &AttributeWeights::default(),
        options,
        &mut |done, most| progress(Stage::Collapse(done, most)),
    )
    .map_err(|source| BlockedBakeError::Blocked {
        path: name.to_string(),
        source,
    })?;
    let built = built(w, made.hierarchy, surfaces, input_triangles, start);
    Ok((built, made.levels))
}
