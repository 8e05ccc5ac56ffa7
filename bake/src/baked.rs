//! The `.clod` arrays of a welded mesh and its collapse hierarchy (the `arrays` module numbers
//! and builds them), and writing them to disk safely: validated, then section by section
//! into a temporary file that a rename puts in place ([`crate::clod_file`]).
//!
//! Materials and vertex colours, when the mesh has them, are written beside the hierarchy
//! ([`crate::materials`]).

use std::io::Write;
use std::path::{Path, PathBuf};

use caveclod_core::format::materials::vertex_colour_section;
use caveclod_core::format::{
    serialized_len, validate_parts, write_into, BaseFace, ExtraSection, HierarchyParts, Meta, Node,
    Polygon, Position, SectionSpec, Split, SplitBounds, Tag, Vertex, VertexKey, KNOWN_SECTIONS,
};
use caveclod_core::{Hierarchy, NodeId};

pub use crate::base::atomic::write_atomically_with;
pub use crate::clod_file::BakeWriteError;

use crate::arrays::{self, NodeIds, PolygonOrder};
use crate::clod_file::{write_sections, Check};
use crate::hierarchy::Hierarchy as Collapses;
use crate::materials::{has_materials, MaterialSections, TexturePaths};
use crate::mesh::Surface;
use crate::weld::Welded;

/// The arrays of a baked hierarchy.
#[derive(Clone, Debug, Default)]
pub struct Baked {
    /// Node positions.
    pub positions: Vec<Position>,
    /// Nodes.
    pub nodes: Vec<Node>,
    /// Split records.
    pub splits: Vec<Split>,
    /// Refinement bounds.
    pub bounds: Vec<SplitBounds>,
    /// Polygons, base first.
    pub polygons: Vec<Polygon>,
    /// Roots, ascending.
    pub roots: Vec<NodeId>,
    /// Base mesh.
    pub base: Vec<BaseFace>,
    /// Vertex-table offsets.
    pub vertex_table_offsets: Vec<u32>,
    /// Vertex-table entries.
    pub vertex_table: Vec<VertexKey>,
    /// Vertex buffer.
    pub vertices: Vec<Vertex>,
    /// Surfaces.
    pub surface_count: u32,
    /// Surface-group ids.
    pub surface_group_count: u32,
    /// One colour per vertex (RGBA8, sRGB colour, linear alpha); empty when the mesh had
    /// none, and then the file has no colour section.
    pub vertex_colours: Vec<[u8; 4]>,
    /// One material per surface; empty when no surface carries one
    /// ([`crate::materials::has_materials`]), and then the file has no material sections.
    pub materials: Vec<Surface>,
    /// The directory the texture files of [`materials`](Self::materials) are relative to:
    /// the source file's (empty: the current directory).
    pub texture_dir: PathBuf,
}

impl Baked {
    /// Assembles the arrays: nodes and polygons renumbered into their file order, then each
    /// array built from the collapses in that order, the arrays on all cores (each is made
    /// alone from the numbering, so the result does not depend on the threads).
    pub fn new(w: &Welded, h: &Collapses) -> Self {
        let ids = NodeIds::number(w.positions.len(), h);
        let polys = PolygonOrder::number(w.triangles.len(), h, &ids);
        let (ids, polys) = (&ids, &polys);
        let ((positions, nodes), (splits, bounds)) = rayon::join(
            || rayon::join(|| arrays::positions(w), || ids.nodes(h)),
            || {
                rayon::join(
                    || arrays::splits(h, ids, polys),
                    || arrays::bounds(w, h, ids),
                )
            },
        );
        let ((polygons, (roots, base)), ((vertex_table_offsets, vertex_table), both)) = rayon::join(
            || {
                rayon::join(
                    || polys.polygons(w, h, ids),
                    || (ids.roots(h), polys.base_faces(h, ids)),
                )
            },
            || {
                rayon::join(
                    || (arrays::vertex_table_offsets(w), arrays::vertex_table(w)),
                    || rayon::join(|| arrays::vertices(w), || arrays::vertex_colours(w)),
                )
            },
        );
        let (vertices, vertex_colours) = both;
        Self {
            positions,
            nodes,
            splits,
            bounds,
            polygons,
            roots,
            base,
            vertex_table_offsets,
            vertex_table,
            vertices,
            surface_count: w.surface_count,
            surface_group_count: w.group_id_count,
            vertex_colours,
            materials: Vec::new(),
            texture_dir: PathBuf::new(),
        }
    }

    /// Gives the surfaces their materials, when any carries one
    /// ([`crate::materials::has_materials`]); texture files relative to `texture_dir`.
    pub fn with_materials(mut self, surfaces: &[Surface], texture_dir: &Path) -> Self {
        self.materials = if has_materials(surfaces) {
            surfaces.to_vec()
        } else {
            Vec::new()
        };
        self.texture_dir = texture_dir.to_path_buf();
        self
    }

    /// Borrowed arrays.
    pub fn parts(&self) -> HierarchyParts<'_> {
        HierarchyParts {
            positions: &self.positions,
            nodes: &self.nodes,
            splits: &self.splits,
            bounds: &self.bounds,
            polygons: &self.polygons,
            roots: &self.roots,
            base: &self.base,
            vertex_table_offsets: &self.vertex_table_offsets,
            vertex_table: &self.vertex_table,
            vertices: &self.vertices,
            surface_count: self.surface_count,
            surface_group_count: self.surface_group_count,
        }
    }

    /// The validated hierarchy over these arrays (each pass on all cores).
    pub fn hierarchy(&self) -> Result<Hierarchy<'_>, caveclod_core::FormatError> {
        Hierarchy::from_parts_in(self.parts(), &crate::clod_file::OnRayon)
    }

    /// The `.clod` bytes with the materials and vertex colours, when there are any, and
    /// `extra` sections (all validated before writing). Texture paths are kept as the
    /// source gives them, relative to [`texture_dir`](Self::texture_dir): right for a file
    /// written into that directory ([`to_bytes_for`](Self::to_bytes_for) for any other).
    pub fn to_bytes(&self, extra: &[ExtraSection<'_>]) -> Result<Vec<u8>, BakeWriteError> {
        self.bytes_with(&|p| Ok(p.to_owned()), Path::new(""), extra)
    }

    /// [`to_bytes`](Self::to_bytes) for a file to be written at `path`: texture paths are
    /// rewritten relative to its directory ([`TexturePaths`]).
    pub fn to_bytes_for(
        &self,
        path: &Path,
        extra: &[ExtraSection<'_>],
    ) -> Result<Vec<u8>, BakeWriteError> {
        let out_dir = path.parent().unwrap_or(Path::new(""));
        let paths = TexturePaths::new(&self.texture_dir, out_dir);
        self.bytes_with(&|p| paths.rewrite(p), path, extra)
    }

    fn bytes_with(
        &self,
        texture_path: &dyn Fn(&str) -> Result<String, String>,
        path: &Path,
        extra: &[ExtraSection<'_>],
    ) -> Result<Vec<u8>, BakeWriteError> {
        let materials = material_sections(&self.materials, texture_path, path)?;
        let sections = self.extra_sections(materials.as_ref(), extra);
        let parts = self.parts();
        let mut out = vec![0u8; serialized_len(&parts, &sections)];
        write_into(&parts, &sections, &mut out)?;
        Ok(out)
    }

    /// The sections after the hierarchy's: materials, vertex colours, then `extra`.
    fn extra_sections<'a>(
        &'a self,
        materials: Option<&'a MaterialSections>,
        extra: &[ExtraSection<'a>],
    ) -> Vec<ExtraSection<'a>> {
        appearance_then(materials, &self.vertex_colours, extra)
    }

    /// Writes the file (the bytes [`to_bytes_for`](Self::to_bytes_for) gives) through a
    /// temporary file in the same directory and a rename, so a reader never sees a partial
    /// file and an existing file is replaced only by a complete one. The arrays are validated
    /// first, then written section by section through a buffer ([`crate::clod_file`]): no
    /// copy of the whole file is made. Texture paths are stored relative to `path`'s
    /// directory.
    pub fn write(&self, path: &Path, extra: &[ExtraSection<'_>]) -> Result<u64, BakeWriteError> {
        let out_dir = path.parent().unwrap_or(Path::new(""));
        let paths = TexturePaths::new(&self.texture_dir, out_dir);
        let materials = material_sections(&self.materials, &|p| paths.rewrite(p), path)?;
        let sections = self.extra_sections(materials.as_ref(), extra);
        let parts = self.parts();
        let meta = validate_parts(&parts, &sections)?;
        let specs = section_specs(&meta, &sections);
        write_sections(path, &specs, Check::Validated, |out| {
            out.put(core::slice::from_ref(&meta))?;
            out.put(parts.positions)?;
            out.put(parts.nodes)?;
            out.put(parts.splits)?;
            out.put(parts.bounds)?;
            out.put(parts.polygons)?;
            out.put(parts.roots)?;
            out.put(parts.base)?;
            out.put(parts.vertex_table_offsets)?;
            out.put(parts.vertex_table)?;
            out.put(parts.vertices)?;
            for e in &sections {
                out.put(e.bytes)?;
            }
            Ok(())
        })
    }
}

/// The material sections of `materials` (none when empty), texture paths rewritten by
/// `texture_path`, for the file at `path`.
pub(crate) fn material_sections(
    materials: &[Surface],
    texture_path: &dyn Fn(&str) -> Result<String, String>,
    path: &Path,
) -> Result<Option<MaterialSections>, BakeWriteError> {
    if materials.is_empty() {
        return Ok(None);
    }
    MaterialSections::new(materials, texture_path)
        .map(Some)
        .map_err(|source| BakeWriteError::Texture {
            path: path.to_path_buf(),
            source,
        })
}

/// The sections after a hierarchy's, in file order: materials, vertex colours (when there
/// are any), then `extra`.
pub(crate) fn appearance_then<'a>(
    materials: Option<&'a MaterialSections>,
    colours: &'a [[u8; 4]],
    extra: &[ExtraSection<'a>],
) -> Vec<ExtraSection<'a>> {
    let mut sections: Vec<ExtraSection<'a>> = Vec::with_capacity(extra.len() + 3);
    if let Some(m) = materials {
        sections.extend(m.parts().sections());
    }
    if !colours.is_empty() {
        sections.push(vertex_colour_section(colours));
    }
    sections.extend_from_slice(extra);
    sections
}

/// The record size and byte length of `count` records of `T`.
fn spec_of_len<T>(count: usize) -> (u32, u64) {
    let size = std::mem::size_of::<T>();
    (size as u32, (count * size) as u64)
}

/// The hierarchy's sections, in [`KNOWN_SECTIONS`] order, sized from the counts of `meta`
/// (the one list both writers plan from, whether the arrays exist yet or not).
fn known_specs(meta: &Meta) -> [(u32, u64); 11] {
    let n = |c: u32| c as usize;
    [
        spec_of_len::<Meta>(1),
        spec_of_len::<Position>(n(meta.position_count)),
        spec_of_len::<Node>(n(meta.node_count)),
        spec_of_len::<Split>(n(meta.split_count)),
        spec_of_len::<SplitBounds>(n(meta.split_count)),
        spec_of_len::<Polygon>(n(meta.polygon_count)),
        spec_of_len::<NodeId>(n(meta.root_count)),
        spec_of_len::<BaseFace>(n(meta.base_polygon_count)),
        spec_of_len::<u32>(n(meta.position_count) + 1),
        spec_of_len::<VertexKey>(n(meta.vertex_key_count)),
        spec_of_len::<Vertex>(n(meta.vertex_count)),
    ]
}

/// Every section of a file: the hierarchy's ([`known_specs`]), then `extra`.
pub(crate) fn section_specs(meta: &Meta, extra: &[ExtraSection<'_>]) -> Vec<SectionSpec> {
    let known = known_specs(meta);
    let spec = |tag: Tag, (record_size, byte_len): (u32, u64)| SectionSpec {
        tag,
        record_size,
        byte_len,
    };
    KNOWN_SECTIONS
        .iter()
        .zip(known)
        .map(|(&tag, k)| spec(tag, k))
        .chain(
            extra
                .iter()
                .map(|e| spec(e.tag, (e.record_size, e.bytes.len() as u64))),
        )
        .collect()
}

/// Writes `bytes` to `path` via a temporary sibling and a rename; the temporary file is
/// removed on failure.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), BakeWriteError> {
    write_atomically_with(path, |f| f.write_all(bytes)).map_err(|source| BakeWriteError::Io {
        path: path.to_path_buf(),
        source,
    })
}
