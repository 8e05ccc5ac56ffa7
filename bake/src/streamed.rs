//! Writing a `.clod` file straight from the welded mesh and its collapses, one array at a
//! time and each array in chunks: its records are made in file order (as
//! [`Baked::new`](crate::baked::Baked::new) collects them), each from its index on all
//! cores while the chunk before is written
//! ([`Sections::put_indexed`](crate::clod_file::Sections::put_indexed)), so the write step
//! holds the inputs, the numbering tables (`u32` per node, split and triangle, per polygon
//! while the polygons are written, and the vertex table's order, 12 bytes per vertex) and
//! two chunks, never an array whole (as a [`Baked`](crate::baked::Baked) does) nor the
//! file's bytes. Only the roots and the base mesh, both as small as the coarsest mesh, are
//! made whole.
//!
//! The arrays are never all in memory at once, so they cannot be validated before writing as
//! [`Baked::write`](crate::baked::Baked::write) validates its own; the written temporary file
//! is read back and validated instead
//! ([`Hierarchy::from_bytes`](caveclod_core::Hierarchy::from_bytes)) before the rename, so an
//! invalid file never replaces the target. The bytes are those `Baked::new(w, h)` followed by
//! `Baked::write` writes.

use std::path::Path;

use caveclod_core::format::ExtraSection;

use crate::arrays::{self, NodeIds, PolygonOrder, Polygons, VertexOrder};
use crate::baked::{appearance_then, material_sections, section_specs};
use crate::clod_file::{write_sections, BakeWriteError, Check, Inspect};
use crate::hierarchy::Hierarchy as Collapses;
use crate::materials::{has_materials, MaterialSections, TexturePaths};
use crate::mesh::Surface;
use crate::weld::Welded;

/// Writes the `.clod` file of the welded mesh `w` and its collapses `h`, with the surfaces'
/// materials (texture paths relative to `texture_dir`, stored relative to `path`'s
/// directory) and `extra` sections, at `path`, one array at a time. The mesh and the
/// collapses are dropped once the last array is written, before the written temporary file
/// is validated, its hierarchy handed to `inspect`, and renamed over `path`. Returns the
/// file's length.
pub fn write(
    w: Welded,
    h: Collapses,
    surfaces: &[Surface],
    texture_dir: &Path,
    path: &Path,
    extra: &[ExtraSection<'_>],
    inspect: Inspect<'_>,
) -> Result<u64, BakeWriteError> {
    let vertex_order = VertexOrder::new(&w);
    let colours = vertex_order.colours(&w);
    let appearance = Appearance::with_colours(colours, surfaces, texture_dir, path)?;
    let sections = appearance.then(extra);

    let ids = NodeIds::number(w.positions.len(), &h);
    let polys = PolygonOrder::number(w.triangles.len(), &h, &ids);
    let meta = arrays::meta(&w, &h, &ids, &polys);
    let specs = section_specs(&meta, &sections);
    write_sections(path, &specs, Check::ReadBack(inspect), move |out| {
        out.put(std::slice::from_ref(&meta))?;
        out.put_indexed(w.positions.len(), |p| arrays::position(&w, p))?;
        out.put_indexed(ids.total(), |id| ids.node(&h, id))?;
        let splits = h.collapses.len();
        out.put_indexed(splits, |s| arrays::split(&h, &ids, &polys, s))?;
        out.put_indexed(splits, |s| arrays::bound(&w, &h, &ids, s))?;
        let polygons = Polygons::new(&polys, &w, &h, &ids);
        out.put_indexed(polys.count, |id| polygons.polygon(id))?;
        drop(polygons);
        out.put(&ids.roots(&h))?;
        out.put(&polys.base_faces(&h, &ids))?;
        drop((h, ids, polys));
        out.put_iter(arrays::vertex_table_offset_records(&w))?;
        out.put_indexed(vertex_order.len(), |i| vertex_order.key(i))?;
        out.put_indexed(vertex_order.len(), |i| vertex_order.vertex(&w, i))?;
        drop((w, vertex_order));
        for e in &sections {
            out.put(e.bytes)?;
        }
        Ok(())
    })
}

/// The sections a file's appearance adds after the hierarchy's: the surfaces' materials
/// (texture paths relative to `texture_dir`, stored relative to the written file's
/// directory) and the vertex colours. The colours are the last array of the vertex table;
/// small beside the vertices, they are made with the other appearance sections, whose
/// lengths the plan needs before anything is written.
pub(crate) struct Appearance {
    materials: Option<MaterialSections>,
    colours: Vec<[u8; 4]>,
}

impl Appearance {
    /// The appearance of a mesh whose vertex colours in vertex-table order are `colours`
    /// (empty: none), with `surfaces`, for a file written at `path`.
    pub(crate) fn with_colours(
        colours: Vec<[u8; 4]>,
        surfaces: &[Surface],
        texture_dir: &Path,
        path: &Path,
    ) -> Result<Self, BakeWriteError> {
        let out_dir = path.parent().unwrap_or(Path::new(""));
        let paths = TexturePaths::new(texture_dir, out_dir);
        let materials = if has_materials(surfaces) {
            material_sections(surfaces, &|p| paths.rewrite(p), path)?
        } else {
            None
        };
        Ok(Self { materials, colours })
    }

    /// The appearance's sections, then `extra`.
    pub(crate) fn then<'a>(&'a self, extra: &[ExtraSection<'a>]) -> Vec<ExtraSection<'a>> {
        appearance_then(self.materials.as_ref(), &self.colours, extra)
    }
}
