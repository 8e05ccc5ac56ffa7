//! A file imported and welded with the least memory the format allows: a PLY file streamed
//! into tiles and welded tile by tile into a [`WeldSink`], never held whole; other formats
//! (and PLY files with what only the in-core importer reads) imported and welded in core.

use std::path::Path;

use super::built::weld_mesh;
use super::error::BakeError;
use crate::base::progress::Stage;
use crate::base::temp::TempSpace;
use crate::import::{self, ImportOptions};
use crate::mesh::Surface;
use crate::ooc::OocError;
use crate::weld::tiled::{weld_tiled_into, StreamTiles, TiledWeldError, WeldSink};
use crate::weld::{WeldInfo, Welded};

/// Triangles a tile holds at most: its weld (with the mesh it is built from) takes some
/// hundreds of bytes a triangle, and as many tiles as threads are welded at once, so callers
/// with a memory budget ask for smaller tiles ([`import_and_weld`]'s `tile_triangles`).
pub const TILE_TRIANGLES: usize = 1 << 17;

/// Where the welded mesh went.
#[derive(Debug)]
pub enum WeldedMesh {
    /// Into the sink, piece by piece.
    Streamed(WeldInfo),
    /// Into memory (the file was imported in core); the sink got nothing.
    InCore(Welded),
}

/// A file imported and welded.
#[derive(Debug)]
pub struct WeldedFile {
    /// The welded mesh, or what the sink was not told.
    pub welded: WeldedMesh,
    /// The input's surfaces.
    pub surfaces: Vec<Surface>,
    /// Triangles of the input.
    pub input_triangles: usize,
    /// Primitives the import skipped.
    pub skipped_primitives: u64,
    /// The import's notes.
    pub notes: Vec<String>,
}

/// Imports and welds `path`: a PLY file streamed into `sink` (see the module's doc) in tiles
/// of about `tile_triangles` triangles (at most [`TILE_TRIANGLES`]), as many welded at once as
/// there are threads; any other file into memory.
pub fn import_and_weld(
    path: &Path,
    options: &ImportOptions,
    tile_triangles: usize,
    sink: &mut dyn WeldSink,
    progress: &mut dyn FnMut(Stage),
) -> Result<WeldedFile, BakeError> {
    let name = path.display().to_string();
    progress(Stage::Import);
    let is_ply = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ply"));
    if is_ply {
        let temp = TempSpace::new(None, None)
            .map_err(|e| OocError::temp("making the temporary directory", e))?;
        match StreamTiles::open(path, &name, &temp, tile_triangles.clamp(1, TILE_TRIANGLES)) {
            Ok(mut tiles) => {
                progress(Stage::Weld);
                let summary = weld_tiled_into(&mut tiles, sink).map_err(|e| match e {
                    TiledWeldError::Weld(source) => BakeError::Weld {
                        path: name.clone(),
                        source,
                    },
                    TiledWeldError::Io(e) => OocError::temp("the tiled weld's files", e).into(),
                })?;
                return Ok(WeldedFile {
                    welded: WeldedMesh::Streamed(summary),
                    surfaces: tiles.report.surfaces.clone(),
                    input_triangles: tiles.report.triangles as usize,
                    skipped_primitives: tiles.report.skipped_faces,
                    notes: Vec::new(),
                });
            }
            // What the streaming reader does not read, the in-core importer does.
            Err(OocError::Unsupported { .. }) => {}
            Err(e) => return Err(e.into()),
        }
    }
    let (mut mesh, report) = import::import_with_report(path, options)?;
    let w = weld_mesh(&mesh, &name, progress)?;
    Ok(WeldedFile {
        welded: WeldedMesh::InCore(w),
        surfaces: std::mem::take(&mut mesh.surfaces),
        input_triangles: mesh.triangles.len(),
        skipped_primitives: report.skipped_primitives as u64,
        notes: report.notes,
    })
}
