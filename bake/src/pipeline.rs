//! The whole bake: import, weld, build the hierarchy, assemble the arrays.

use std::path::Path;
use std::time::Instant;

use crate::baked::Baked;
use crate::hierarchy::{self, AttributeWeights};
use crate::import::{self, ImportError, ImportOptions};
use crate::mesh::Mesh;
use crate::report::BakeInfo;
use crate::weld::{self, WeldError};

/// Why a bake failed.
#[derive(Debug, thiserror::Error)]
pub enum BakeError {
    /// Reading the input failed.
    #[error(transparent)]
    Import(#[from] ImportError),
    /// The input has nothing usable.
    #[error("{path}: {source}")]
    Weld {
        /// The input.
        path: String,
        /// Why.
        source: WeldError,
    },
    /// The out-of-core simplification failed.
    #[error(transparent)]
    OutOfCore(#[from] crate::ooc::OocError),
    /// The hierarchy build broke an invariant its termination rests on (a baker bug).
    #[error("{path}: {source}")]
    Hierarchy {
        /// The input.
        path: String,
        /// The stage and the invariant.
        source: hierarchy::BuildError,
    },
    /// The baked arrays did not validate (a baker bug).
    #[error("internal error: the baked hierarchy does not validate: {0}")]
    Invalid(caveclod_core::FormatError),
}

/// Stages of a bake, for progress reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// Reading the input.
    Import,
    /// Welding and grouping.
    Weld,
    /// Collapsing: `(done, at most)`.
    Collapse(u64, u64),
    /// Assembling the arrays.
    Assemble,
}

/// The directory a source file's relative paths (its textures) start from.
fn source_dir(path: &Path) -> std::path::PathBuf {
    path.parent().unwrap_or(Path::new("")).to_path_buf()
}

/// Bakes an imported mesh, with its surfaces' materials and its vertex colours when it has
/// them; texture files are taken as relative to the current directory (set
/// [`Baked::texture_dir`] where they are relative to another; [`bake_file`] sets the
/// source's).
pub fn bake_mesh(
    mesh: &Mesh,
    name: &str,
    progress: &mut dyn FnMut(Stage),
) -> Result<(Baked, BakeInfo), BakeError> {
    let start = Instant::now();
    let w = weld_mesh(mesh, name, progress)?;
    build_welded(
        &w,
        &mesh.surfaces,
        mesh.triangles.len(),
        name,
        start,
        progress,
    )
}

/// Imports and bakes a file; `bake_seconds` includes the import. Texture files are relative
/// to the file's directory. The primitives the import skipped are counted in the repairs
/// (`skipped_primitives`), its notes kept in [`BakeInfo::notes`]. The imported mesh is
/// dropped once welded, before the hierarchy is built (of it only the surfaces are kept),
/// so that the two never take memory at once.
pub fn bake_file(
    path: &Path,
    options: &ImportOptions,
    progress: &mut dyn FnMut(Stage),
) -> Result<(Baked, BakeInfo), BakeError> {
    let start = Instant::now();
    progress(Stage::Import);
    let (mut mesh, report) = import::import_with_report(path, options)?;
    let name = path.display().to_string();
    let w = weld_mesh(&mesh, &name, progress)?;
    let (surfaces, triangles) = (std::mem::take(&mut mesh.surfaces), mesh.triangles.len());
    drop(mesh);
    let (mut baked, mut info) = build_welded(&w, &surfaces, triangles, &name, start, progress)?;
    baked.texture_dir = source_dir(path);
    info.repairs.skipped_primitives = report.skipped_primitives as u64;
    info.notes = report.notes;
    info.bake_seconds = start.elapsed().as_secs_f64();
    Ok((baked, info))
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

/// The welding step of a bake.
pub(crate) fn weld_mesh(
    mesh: &Mesh,
    name: &str,
    progress: &mut dyn FnMut(Stage),
) -> Result<weld::Welded, BakeError> {
    progress(Stage::Weld);
    weld::weld(mesh).map_err(|source| BakeError::Weld {
        path: name.to_string(),
        source,
    })
}

/// The steps of a bake after welding: the hierarchy, the arrays with the surfaces'
/// materials, and their validation.
fn build_welded(
    w: &weld::Welded,
    surfaces: &[crate::mesh::Surface],
    input_triangles: usize,
    name: &str,
    start: Instant,
    progress: &mut dyn FnMut(Stage),
) -> Result<(Baked, BakeInfo), BakeError> {
    let h = hierarchy::build(w, &AttributeWeights::default(), &mut |done, most| {
        progress(Stage::Collapse(done, most))
    })
    .map_err(|source| BakeError::Hierarchy {
        path: name.to_string(),
        source,
    })?;
    assemble(w, h, surfaces, input_triangles, start, progress)
}

/// The last steps of a bake: the arrays of `w` and its hierarchy `h` with the surfaces'
/// materials, their validation, and the report.
pub(crate) fn assemble(
    w: &weld::Welded,
    h: hierarchy::Hierarchy,
    surfaces: &[crate::mesh::Surface],
    input_triangles: usize,
    start: Instant,
    progress: &mut dyn FnMut(Stage),
) -> Result<(Baked, BakeInfo), BakeError> {
    progress(Stage::Assemble);
    let baked = Baked::new(w, &h).with_materials(surfaces, Path::new(""));
    // The hierarchy is in the arrays now; validating them does not need it.
    let passes = h.passes;
    drop(h);
    baked.hierarchy().map_err(BakeError::Invalid)?;
    let info = BakeInfo {
        input_triangles: input_triangles as u64,
        surface_groups: w.group_count as u64,
        repairs: w.repairs,
        bake_seconds: start.elapsed().as_secs_f64(),
        passes,
        notes: Vec::new(),
    };
    Ok((baked, info))
}

/// What [`bake_out_of_core`] makes.
#[derive(Debug)]
pub struct OutOfCoreBake {
    /// The view-dependent hierarchy over the clustered mesh.
    pub baked: Baked,
    /// About the bake (`input_triangles` counts the file's triangles).
    pub info: BakeInfo,
    /// About the out-of-core simplification.
    pub stats: crate::ooc::OocStats,
    /// The multiresolution octree over every clustering level, when the options ask for it.
    pub octree: Option<crate::ooc::MultiresOctree>,
}

/// Simplifies a file of any size out of core ([`crate::ooc::simplify`]) to a mesh that fits
/// the memory budget, then bakes that mesh in core; `bake_seconds` covers both. The
/// multiresolution octree (if [`crate::ooc::OocOptions::octree`]) describes the same surfaces
/// as the hierarchy.
pub fn bake_out_of_core(
    path: &Path,
    options: &crate::ooc::OocOptions,
    ooc_progress: &mut dyn FnMut(crate::ooc::OocStage),
    progress: &mut dyn FnMut(Stage),
) -> Result<OutOfCoreBake, BakeError> {
    let start = Instant::now();
    let s = crate::ooc::simplify(path, options, ooc_progress)?;
    let (mut baked, mut info) = bake_mesh(&s.mesh, &path.display().to_string(), progress)?;
    baked.texture_dir = source_dir(path);
    drop(s.mesh);
    let mut octree = s.octree;
    if let Some(o) = &mut octree {
        o.surface_count = baked.surface_count;
    }
    info.input_triangles = s.stats.input_triangles;
    info.repairs.skipped_primitives = s.stats.skipped_primitives;
    if s.stats.skipped_primitives > 0 {
        info.notes.push(format!(
            "{}: {} faces with fewer than 3 corners skipped",
            path.display(),
            s.stats.skipped_primitives
        ));
    }
    info.bake_seconds = start.elapsed().as_secs_f64();
    Ok(OutOfCoreBake {
        baked,
        info,
        stats: s.stats,
        octree,
    })
}
