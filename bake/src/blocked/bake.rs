//! A whole bake in blocks: import, weld, the blocked hierarchy, the `.clod` arrays and
//! their validation, as [`crate::pipeline::bake_file`] does in one build.

use std::path::Path;
use std::time::Instant;

use super::{build, BlockedError, BlockedOptions, LevelStats};
use crate::baked::Baked;
use crate::hierarchy::AttributeWeights;
use crate::import::{self, ImportOptions};
use crate::mesh::{Mesh, Surface};
use crate::pipeline::{assemble, weld_mesh, BakeError, Stage};
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

/// Imports `path` and bakes it in blocks; `bake_seconds` includes the import. The imported
/// mesh is dropped once welded (only its surfaces are kept), so the two never take memory at
/// once.
pub fn bake_file_blocked(
    path: &Path,
    import_options: &ImportOptions,
    options: &BlockedOptions,
    progress: &mut dyn FnMut(Stage),
) -> Result<(Baked, BakeInfo, Vec<LevelStats>), BlockedBakeError> {
    let start = Instant::now();
    progress(Stage::Import);
    let (mut mesh, report) =
        import::import_with_report(path, import_options).map_err(BakeError::from)?;
    let name = path.display().to_string();
    let w = weld_mesh(&mesh, &name, progress)?;
    let (surfaces, triangles) = (std::mem::take(&mut mesh.surfaces), mesh.triangles.len());
    drop(mesh);
    let (mut baked, mut info, levels) =
        bake_welded(&w, &surfaces, triangles, &name, options, progress)?;
    baked.texture_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    info.repairs.skipped_primitives = report.skipped_primitives as u64;
    info.notes = report.notes;
    info.bake_seconds = start.elapsed().as_secs_f64();
    Ok((baked, info, levels))
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
    let (baked, mut info, levels) = bake_welded(
        &w,
        &mesh.surfaces,
        mesh.triangles.len(),
        name,
        options,
        progress,
    )?;
    info.bake_seconds = start.elapsed().as_secs_f64();
    Ok((baked, info, levels))
}

/// The steps after welding: the blocked hierarchy, the arrays with the surfaces' materials,
/// and their validation.
fn bake_welded(
    w: &weld::Welded,
    surfaces: &[Surface],
    input_triangles: usize,
    name: &str,
    options: &BlockedOptions,
    progress: &mut dyn FnMut(Stage),
) -> Result<(Baked, BakeInfo, Vec<LevelStats>), BlockedBakeError> {
    let start = Instant::now();
    let built = build(
        w,
        &AttributeWeights::default(),
        options,
        &mut |done, most| progress(Stage::Collapse(done, most)),
    )
    .map_err(|source| BlockedBakeError::Blocked {
        path: name.to_string(),
        source,
    })?;
    let (baked, info) = assemble(
        w,
        built.hierarchy,
        surfaces,
        input_triangles,
        start,
        progress,
    )?;
    Ok((baked, info, built.levels))
}
