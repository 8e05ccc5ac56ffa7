//! The whole bake: import, weld, build the hierarchy ([`Built`]), then either assemble the
//! arrays ([`Built::assemble`], a [`Baked`]) or write the file from the collapses one array
//! at a time ([`Built::write`]).

use std::path::{Path, PathBuf};
use std::time::Instant;

use caveclod_core::format::ExtraSection;

use crate::baked::Baked;
pub use crate::base::progress::Stage;
use crate::clod_file::BakeWriteError;
use crate::hierarchy::{self, AttributeWeights};
use crate::import::{self, ImportError, ImportOptions};
use crate::mesh::{Mesh, Surface};
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

/// The directory a source file's relative paths (its textures) start from.
fn source_dir(path: &Path) -> std::path::PathBuf {
    path.parent().unwrap_or(Path::new("")).to_path_buf()
}

/// A bake up to its arrays: the welded mesh, its collapse hierarchy and the surfaces, from
/// which the `.clod` arrays follow.
#[derive(Debug)]
pub struct Built {
    /// The welded mesh.
    pub welded: weld::Welded,
    /// Its collapse hierarchy.
    pub collapses: hierarchy::Hierarchy,
    /// The input's surfaces with their materials.
    pub surfaces: Vec<Surface>,
    /// The directory the surfaces' texture paths are relative to.
    pub texture_dir: PathBuf,
    /// About the bake so far; `bake_seconds` is brought up to date by
    /// [`assemble`](Self::assemble) and [`write`](Self::write).
    pub info: BakeInfo,
    start: Instant,
}

impl Built {
    /// The arrays with the surfaces' materials, validated ([`Baked::new`]); the mesh and the
    /// collapses are dropped once the arrays are made.
    pub fn assemble(self, progress: &mut dyn FnMut(Stage)) -> Result<(Baked, BakeInfo), BakeError> {
        progress(Stage::Assemble);
        let baked = Baked::new(&self.welded, &self.collapses)
            .with_materials(&self.surfaces, &self.texture_dir);
        drop((self.welded, self.collapses));
        baked.hierarchy().map_err(BakeError::Invalid)?;
        let mut info = self.info;
        info.bake_seconds = self.start.elapsed().as_secs_f64();
        Ok((baked, info))
    }

    /// Writes the `.clod` file at `path` with `extra` sections from the welded mesh and the
    /// collapses one array at a time ([`crate::streamed`]): the arrays never all exist at
    /// once, the mesh and the collapses are dropped once written, and the written file is
    /// validated before it replaces `path`. Returns the file's length.
    pub fn write(self, path: &Path, extra: &[ExtraSection<'_>]) -> Result<u64, BakeWriteError> {
        self.write_inspected(path, extra, &mut |_| {})
    }

    /// [`write`](Self::write), handing the written file's validated hierarchy to `inspect`
    /// before the rename (for a report on the file without validating it again).
    pub fn write_inspected(
        self,
        path: &Path,
        extra: &[ExtraSection<'_>],
        inspect: crate::clod_file::Inspect<'_>,
    ) -> Result<u64, BakeWriteError> {
        crate::streamed::write(
            self.welded,
            self.collapses,
            &self.surfaces,
            &self.texture_dir,
            path,
            extra,
            inspect,
        )
    }

    /// Seconds since the bake started.
    pub fn seconds(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }
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

/// The step of a bake after welding: the hierarchy.
fn build_welded(
    w: weld::Welded,
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

/// A bake up to its arrays from the welded mesh `w` and its hierarchy `h`.
pub(crate) fn built(
    w: weld::Welded,
    h: hierarchy::Hierarchy,
    surfaces: Vec<Surface>,
    input_triangles: usize,
    start: Instant,
) -> Built {
    let info = bake_info(&w, h.passes, input_triangles, start);
    Built {
        welded: w,
        collapses: h,
        surfaces,
        texture_dir: PathBuf::new(),
        info,
        start,
    }
}

/// About a bake of the welded mesh `w` whose hierarchy took `passes` passes.
pub(crate) fn bake_info(
    w: &weld::Welded,
    passes: u32,
    input_triangles: usize,
    start: Instant,
) -> BakeInfo {
    BakeInfo {
        input_triangles: input_triangles as u64,
        surface_groups: w.group_count as u64,
        repairs: w.repairs,
        bake_seconds: start.elapsed().as_secs_f64(),
        passes,
        notes: Vec::new(),
    }
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

/// What [`build_out_of_core`] makes: [`OutOfCoreBake`] up to the arrays.
#[derive(Debug)]
pub struct OutOfCoreBuild {
    /// The clustered mesh's bake up to its arrays (`info.input_triangles` counts the file's
    /// triangles).
    pub built: Built,
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
    let o = build_out_of_core(path, options, ooc_progress, progress)?;
    let (baked, info) = o.built.assemble(progress)?;
    Ok(OutOfCoreBake {
        baked,
        info,
        stats: o.stats,
        octree: o.octree,
    })
}

/// [`bake_out_of_core`] up to the arrays.
pub fn build_out_of_core(
    path: &Path,
    options: &crate::ooc::OocOptions,
    ooc_progress: &mut dyn FnMut(crate::ooc::OocStage),
    progress: &mut dyn FnMut(Stage),
) -> Result<OutOfCoreBuild, BakeError> {
    let start = Instant::now();
    let s = crate::ooc::simplify(path, options, ooc_progress)?;
    let mut built = build_mesh(&s.mesh, &path.display().to_string(), progress)?;
    built.start = start;
    built.texture_dir = source_dir(path);
    drop(s.mesh);
    let mut octree = s.octree;
    if let Some(o) = &mut octree {
        o.surface_count = built.welded.surface_count;
    }
    let info = &mut built.info;
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
    Ok(OutOfCoreBuild {
        built,
        stats: s.stats,
        octree,
    })
}
