//! The bake in core: import, weld, build the hierarchy ([`Built`]), then either assemble the
//! arrays ([`Built::assemble`], a [`Baked`]) or write the file from the collapses one array
//! at a time ([`Built::write`]).

use std::path::Path;
use std::time::Instant;

use super::built::{built, source_dir, weld_mesh, Built};
use super::error::BakeError;
use crate::baked::Baked;
use crate::base::progress::Stage;
use crate::hierarchy::{self, AttributeWeights};
use crate::import::{self, ImportOptions};
use crate::mesh::{Mesh, Surface};
use crate::report::BakeInfo;
use crate::weld::Welded;

/// Bakes an imported mesh, with its surfaces' materials and its vertex colours when it has
/// them; texture files are taken as relative to the current directory (set
/// [`Baked::texture_dir`] where they are relative to another; [`bake_file`] sets the
/// source's).
pub fn bake_mesh(
    mesh: &Mesh,
    name: &str,
    progress: &mut dyn FnMut(Stage),
) -> Result<(Baked, BakeInfo), BakeError> {
    build_mesh(mesh, name, progress)?.assemble(progress)
}

/// [`bake_mesh`] up to the arrays.
pub fn build_mesh(
    mesh: &Mesh,
    name: &str,
    progress: &mut dyn FnMut(Stage),
) -> Result<Built, BakeError> {
    let start = Instant::now();
    let w = weld_mesh(mesh, name, progress)?;
    build_welded(
        w,
        mesh.surfaces.clone(),
        mesh.triangles.len(),
        name,
        start,
        progress,
    )
}

/// Imports and bakes a file; `bake_seconds` includes the import. Texture files are relative
/// to the file's directory. The primitives the import skipped are counted in the repairs
/// (`skipped_primitives`), its notes kept in [`BakeInfo::notes`].
pub fn bake_file(
    path: &Path,
    options: &ImportOptions,
    progress: &mut dyn FnMut(Stage),
) -> Result<(Baked, BakeInfo), BakeError> {
    build_file(path, options, progress)?.assemble(progress)
}

/// [`bake_file`] up to the arrays. The imported mesh is dropped once welded, before the
/// hierarchy is built (of it only the surfaces are kept), so that the two never take memory
/// at once.
pub fn build_file(
    path: &Path,
    options: &ImportOptions,
    progress: &mut dyn FnMut(Stage),
) -> Result<Built, BakeError> {
    let start = Instant::now();
    progress(Stage::Import);
    let (mut mesh, report) = import::import_with_report(path, options)?;
    let name = path.display().to_string();
    let w = weld_mesh(&mesh, &name, progress)?;
    let (surfaces, triangles) = (std::mem::take(&mut mesh.surfaces), mesh.triangles.len());
    drop(mesh);
    let mut built = build_welded(w, surfaces, triangles, &name, start, progress)?;
    built.texture_dir = source_dir(path);
    built.info.repairs.skipped_primitives = report.skipped_primitives as u64;
    built.info.notes = report.notes;
    Ok(built)
}

/// Imports a mesh from bytes in memory ([`import::import_bytes`]: `name`'s extension picks
/// the importer, `load` reads the files the input names) and bakes it; `bake_seconds`
/// includes the import. Texture paths stay as the input gives them.
pub fn bake_bytes(
    name: &str,
    bytes: &[u8],
    load: &mut import::Loader<'_>,
    options: &ImportOptions,
    progress: &mut dyn FnMut(Stage),
) -> Result<(Baked, BakeInfo), BakeError> {
    let start = Instant::now();
    progress(Stage::Import);
    let (mesh, _) = import::import_bytes(name, bytes, load, options)?;
    let (baked, mut info) = bake_mesh(&mesh, name, progress)?;
    info.bake_seconds = start.elapsed().as_secs_f64();
    Ok((baked, info))
}

/// The step of a bake after welding: the hierarchy.
fn build_welded(
    w: Welded,
    surfaces: Vec<Surface>,
    input_triangles: usize,
    name: &str,
    start: Instant,
    progress: &mut dyn FnMut(Stage),
) -> Result<Built, BakeError> {
    let h = hierarchy::build(&w, &AttributeWeights::default(), &mut |done, most| {
        progress(Stage::Collapse(done, most))
    })
    .map_err(|source| BakeError::Hierarchy {
        path: name.to_string(),
        source,
    })?;
    Ok(built(w, h, surfaces, input_triangles, start))
}
