//! A bake up to its arrays ([`Built`]), and the steps every bake takes to get there.

use std::path::{Path, PathBuf};
use std::time::Instant;

use caveclod_core::format::ExtraSection;

use super::error::BakeError;
use crate::baked::Baked;
use crate::base::progress::Stage;
use crate::clod_file::{BakeWriteError, Inspect};
use crate::hierarchy::Hierarchy;
use crate::mesh::{Mesh, Surface};
use crate::report::BakeInfo;
use crate::weld::{self, Welded};

/// A bake up to its arrays: the welded mesh, its collapse hierarchy and the surfaces, from
/// which the `.clod` arrays follow.
#[derive(Debug)]
pub struct Built {
    /// The welded mesh.
    pub welded: Welded,
    /// Its collapse hierarchy.
    pub collapses: Hierarchy,
    /// The input's surfaces with their materials.
    pub surfaces: Vec<Surface>,
    /// The directory the surfaces' texture paths are relative to.
    pub texture_dir: PathBuf,
    /// About the bake so far; `bake_seconds` is brought up to date by
    /// [`assemble`](Self::assemble) and [`write`](Self::write).
    pub info: BakeInfo,
    pub(super) start: Instant,
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
        inspect: Inspect<'_>,
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

/// The directory a source file's relative paths (its textures) start from.
pub(super) fn source_dir(path: &Path) -> PathBuf {
    path.parent().unwrap_or(Path::new("")).to_path_buf()
}

/// The welding step of a bake.
pub(super) fn weld_mesh(
    mesh: &Mesh,
    name: &str,
    progress: &mut dyn FnMut(Stage),
) -> Result<Welded, BakeError> {
    progress(Stage::Weld);
    weld::weld(mesh).map_err(|source| BakeError::Weld {
        path: name.to_string(),
        source,
    })
}

/// A bake up to its arrays from the welded mesh `w` and its hierarchy `h`.
pub(super) fn built(
    w: Welded,
    h: Hierarchy,
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
fn bake_info(w: &Welded, passes: u32, input_triangles: usize, start: Instant) -> BakeInfo {
    BakeInfo {
        input_triangles: input_triangles as u64,
        surface_groups: w.group_count as u64,
        repairs: w.repairs,
        bake_seconds: start.elapsed().as_secs_f64(),
        passes,
        notes: Vec::new(),
    }
}
