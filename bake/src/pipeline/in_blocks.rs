//! A whole bake in blocks: import, weld, the blocked hierarchy, the `.clod` arrays and
//! their validation, as [`super::bake_file`] does in one build. The hierarchy's
//! collapses are on disk ([`SpilledBuild`]) until written ([`SpilledBuild::write`]) or read
//! back into memory ([`SpilledBuild::into_built`]).

use std::path::{Path, PathBuf};
use std::time::Instant;

use caveclod_core::format::ExtraSection;

use super::built::{built, source_dir, weld_mesh, Built};
use super::error::BakeError;
use super::import_weld::{import_and_weld, WeldedMesh};
use crate::baked::Baked;
use crate::base::progress::Stage;
use crate::blocked::{build, build_spilled, BlockedError, BlockedOptions, LevelStats, Spilled};
use crate::clod_file::{BakeWriteError, Inspect};
use crate::hierarchy::AttributeWeights;
use crate::import::ImportOptions;
use crate::mesh::{Mesh, Surface};
use crate::report::BakeInfo;
use crate::weld::store::{StoreWriter, WeldedStore};
use crate::weld::{Repairs, Welded};

/// A blocked bake up to its arrays: the welded mesh and its hierarchy, both on disk.
#[derive(Debug)]
pub struct SpilledBuild {
    /// The welded mesh, in block order (the hierarchy's ids are the store's).
    pub store: WeldedStore,
    /// Its hierarchy.
    pub spilled: Spilled,
    /// The input's surfaces with their materials.
    pub surfaces: Vec<Surface>,
    /// The directory the surfaces' texture paths are relative to.
    pub texture_dir: PathBuf,
    /// About the bake so far.
    pub info: BakeInfo,
    start: Instant,
}

impl SpilledBuild {
    /// Writes the `.clod` file at `path` with `extra` sections from the welded mesh and the
    /// spilled collapses, splits in reverse creation order (`blocked::write`); the written
    /// file is validated before it replaces `path`. Returns the file's length.
    pub fn write(self, path: &Path, extra: &[ExtraSection<'_>]) -> Result<u64, BakeWriteError> {
        self.write_inspected(path, extra, &mut |_| {})
    }

    /// [`write`](Self::write), handing the written file's validated hierarchy to `inspect`
    /// before the rename (for a report on the file without validating it again).
    pub fn write_inspected(
        self,
        path: &Path,
        extra: &[ExtraSection<'_>],
        inspect: Inspect<'_>,
    ) -> Result<u64, BakeWriteError> {
        crate::blocked::write::write(
            self.store,
            self.spilled,
            &self.surfaces,
            &self.texture_dir,
            path,
            extra,
            inspect,
        )
    }

    /// The hierarchy and the welded mesh read back into memory
    /// ([`Spilled::into_hierarchy`], [`WeldedStore::into_welded`]: the store's order), as an
    /// in-core bake's [`Built`] (whose arrays number the splits depth-first).
    pub fn into_built(self, name: &str) -> Result<Built, BlockedBakeError> {
        let failed = |source| BlockedBakeError::Blocked {
            path: name.to_string(),
            source,
        };
        let h = self
            .spilled
            .into_hierarchy()
            .map_err(|e| failed(BlockedError::Spill(e.to_string())))?;
        let welded = self
            .store
            .into_welded()
            .map_err(|e| failed(BlockedError::Store(e.to_string())))?;
        let mut b = built(
            welded,
            h,
            self.surfaces,
            self.info.input_triangles as usize,
            self.start,
        );
        b.texture_dir = self.texture_dir;
        b.info = self.info;
        Ok(b)
    }

    /// Seconds since the bake started.
    pub fn seconds(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }
}

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

/// [`bake_file_blocked`] up to the arrays ([`Built`]): [`build_file_spilled`], the
/// hierarchy read back into memory.
pub fn build_file_blocked(
    path: &Path,
    import_options: &ImportOptions,
    options: &BlockedOptions,
    progress: &mut dyn FnMut(Stage),
) -> Result<(Built, Vec<LevelStats>), BlockedBakeError> {
    let (spilled, levels) = build_file_spilled(path, import_options, options, progress)?;
    Ok((spilled.into_built(&path.display().to_string())?, levels))
}

/// Imports `path` and builds its hierarchy in blocks, the welded mesh and the collapses on
/// disk. A PLY file is streamed and welded tile by tile straight into the store
/// ([`import_and_weld`]), never held whole; other files are imported and welded
/// in core, the imported mesh dropped once welded (only its surfaces are kept) and the
/// welded mesh once stored in block order ([`WeldedStore::from_welded`]), so no two of them
/// take memory at once and the build holds only the blocks in flight and what stitching
/// needs.
pub fn build_file_spilled(
    path: &Path,
    import_options: &ImportOptions,
    options: &BlockedOptions,
    progress: &mut dyn FnMut(Stage),
) -> Result<(SpilledBuild, Vec<LevelStats>), BlockedBakeError> {
    let start = Instant::now();
    let name = path.display().to_string();
    let failed = |source| BlockedBakeError::Blocked {
        path: name.clone(),
        source,
    };
    let store_failed = |e: std::io::Error| failed(BlockedError::Store(e.to_string()));
    let mut writer = StoreWriter::new().map_err(store_failed)?;
    // A tile's weld takes no more than a block's build, and as many of each run at once.
    let file = import_and_weld(
        path,
        import_options,
        options.block_triangles,
        &mut writer,
        progress,
    )?;
    let (store, surface_groups, repairs) = match file.welded {
        WeldedMesh::Streamed(s) => {
            let (groups, repairs) = (s.group_count, s.repairs);
            let store = writer
                .finish(s, options.block_triangles, false)
                .map_err(store_failed)?;
            (store, groups, repairs)
        }
        WeldedMesh::InCore(w) => {
            drop(writer);
            let (groups, repairs) = (w.group_count, w.repairs);
            let store = WeldedStore::from_welded(w, options.block_triangles, false)
                .map_err(store_failed)?;
            (store, groups, repairs)
        }
    };
    let (spilled, levels) =
        build_spilled(&store, &AttributeWeights::default(), &mut |done, most| {
            progress(Stage::Collapse(done, most))
        })
        .map_err(failed)?;
    let info = BakeInfo {
        input_triangles: file.input_triangles as u64,
        surface_groups: u64::from(surface_groups),
        repairs: Repairs {
            skipped_primitives: file.skipped_primitives,
            ..repairs
        },
        bake_seconds: start.elapsed().as_secs_f64(),
        passes: spilled.passes,
        notes: file.notes,
    };
    let built = SpilledBuild {
        info,
        store,
        spilled,
        surfaces: file.surfaces,
        texture_dir: source_dir(path),
        start,
    };
    Ok((built, levels))
}

/// Bakes a mesh in blocks: welds it, builds its hierarchy level by level
/// ([`crate::blocked::build`]), assembles and validates the arrays.
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
    w: Welded,
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
