//! The welded mesh ([`Welded`]) and what a weld reports with it: its small fields
//! ([`WeldInfo`]), its repairs ([`Repairs`]) and why it failed ([`WeldError`]).

use caveclod_core::format::PositionClass;

use super::vertex_lists::VertexLists;

/// No triangle.
pub(super) const NONE: u32 = u32::MAX;

/// The most triangles a mesh may have: every corner (`3 f + k`) has a 32-bit id.
pub const MAX_TRIANGLES: usize = (NONE as usize - 1) / 3;

/// Counts of what welding repaired.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Repairs {
    /// Input positions merged into an identical one.
    pub welded_positions: u64,
    /// Triangles dropped for a repeated position or zero area.
    pub degenerate_triangles: u64,
    /// Triangles dropped as duplicates.
    pub duplicate_triangles: u64,
    /// Edges cut because more than two triangles (or two in one direction) shared them.
    pub non_manifold_edges: u64,
    /// Positions split because their triangles formed several fans.
    pub non_manifold_vertices: u64,
    /// Corners without a normal that got a computed one.
    pub computed_normals: u64,
    /// Primitives the importer skipped: points, lines, faces with fewer than three corners
    /// (counted by the import, not the weld).
    pub skipped_primitives: u64,
}

impl Repairs {
    /// `(name, count)` pairs, for reports.
    pub fn entries(&self) -> [(&'static str, u64); 7] {
        [
            ("welded_positions", self.welded_positions),
            ("degenerate_triangles", self.degenerate_triangles),
            ("duplicate_triangles", self.duplicate_triangles),
            ("non_manifold_edges", self.non_manifold_edges),
            ("non_manifold_vertices", self.non_manifold_vertices),
            ("computed_normals", self.computed_normals),
            ("skipped_primitives", self.skipped_primitives),
        ]
    }
}

/// Largest angle between a source's normal and the area-weighted normal at its position for
/// which the normal still counts as following from the geometry: wide enough for the normals
/// heightfield importers compute from the grid (central differences, which part from the
/// area-weighted normal only where the surface bends within a cell), narrow enough that an
/// authored normal set apart from the surface's keeps its weight.
pub const GEOMETRIC_NORMAL_DEGREES: f64 = 10.0;

/// The attributes of one vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Attributes {
    /// Unit normal.
    pub normal: [f32; 3],
    /// Texture coordinates.
    pub uv: [f32; 2],
    /// Linear RGBA.
    pub color: [f32; 4],
    /// Whether the normal follows from the geometry at every corner that has it: computed
    /// here (area-weighted at its position), or given by the source within
    /// [`GEOMETRIC_NORMAL_DEGREES`] of that (heightfield importers compute their normals
    /// from the grid, and a mesh cannot say which of its normals were authored). Such a
    /// normal says nothing the positions do not, so simplification gives it no weight. Not
    /// part of the attributes' identity.
    pub normal_from_geometry: bool,
}

impl Attributes {
    /// The attributes' identity: their bits, `-0.0` as `0.0`; the flag is not part of it.
    pub(super) fn key(&self) -> [u32; 9] {
        let n = self.normal.map(|x| (x + 0.0).to_bits());
        let u = self.uv.map(|x| (x + 0.0).to_bits());
        let c = self.color.map(|x| (x + 0.0).to_bits());
        [n[0], n[1], n[2], u[0], u[1], c[0], c[1], c[2], c[3]]
    }
}

/// One welded triangle: 16 bytes. Its corners' attributes and its surface are its
/// group's: a surface group lies on one surface and has one attribute set at each of its
/// positions, so a corner's attributes are its position's vertex of the group
/// ([`Welded::corner_attributes`]) and the surface the group's ([`Welded::surface_of`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WeldedTri {
    /// Position ids, counter-clockwise.
    pub p: [u32; 3],
    /// Surface group (before colouring).
    pub group: u32,
}

/// What a welded mesh says besides its arrays (the small fields of [`Welded`]): what a weld
/// that streams its arrays elsewhere ([`super::tiled`]) hands over at its end, and what the welded
/// store ([`crate::weld::store`]) keeps in memory.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct WeldInfo {
    /// Number of surface groups.
    pub group_count: u32,
    /// Surface-group id of each group (the colouring).
    pub group_ids: Vec<u16>,
    /// Number of surface-group ids.
    pub group_id_count: u32,
    /// Number of surfaces.
    pub surface_count: u32,
    /// Whether the mesh has vertex colours.
    pub has_colors: bool,
    /// What welding repaired.
    pub repairs: Repairs,
}

impl WeldInfo {
    /// The small fields of `w`.
    pub fn of(w: &Welded) -> Self {
        Self {
            group_count: w.group_count,
            group_ids: w.group_ids.clone(),
            group_id_count: w.group_id_count,
            surface_count: w.surface_count,
            has_colors: w.has_colors,
            repairs: w.repairs,
        }
    }
}

/// A manifold mesh with surface groups, classes and the vertex table's contents.
#[derive(Clone, Debug, Default)]
pub struct Welded {
    /// Node positions.
    pub positions: Vec<[f32; 3]>,
    /// Their classes.
    pub classes: Vec<PositionClass>,
    /// Distinct attribute sets.
    pub attributes: Vec<Attributes>,
    /// Triangles.
    pub triangles: Vec<WeldedTri>,
    /// Number of surface groups.
    pub group_count: u32,
    /// Surface-group id of each group (the colouring).
    pub group_ids: Vec<u16>,
    /// Surface of each group.
    pub group_surfaces: Vec<u16>,
    /// Number of surface-group ids.
    pub group_id_count: u32,
    /// Number of surfaces.
    pub surface_count: u32,
    /// Whether the mesh has colours: then every vertex keeps its own (white where a corner
    /// had none) and the `.clod` file gets a colour per vertex.
    pub has_colors: bool,
    /// Per position: `(group, attribute id)` of each group with a vertex there, by group.
    pub vertices: VertexLists,
    /// What was repaired.
    pub repairs: Repairs,
}

impl Welded {
    /// The attribute ids (into [`Welded::attributes`]) of `t`'s corners: at each, the
    /// vertex of `t`'s group at the corner's position.
    pub fn corner_attributes(&self, t: &WeldedTri) -> [u32; 3] {
        t.p.map(|x| self.vertices.attributes_of(x as usize, t.group))
    }

    /// The surface of `t` (its group's).
    #[inline]
    pub fn surface_of(&self, t: &WeldedTri) -> u16 {
        self.group_surfaces[t.group as usize]
    }
}

/// Why welding failed.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum WeldError {
    /// Nothing left after dropping degenerate and duplicate triangles.
    #[error("no triangle left after dropping {degenerate} degenerate and {duplicate} duplicate triangles")]
    Empty {
        /// Degenerate triangles dropped.
        degenerate: u64,
        /// Duplicates dropped.
        duplicate: u64,
    },
    /// More surface-group ids than the format's 16 bits.
    #[error("{0} surface-group ids needed, at most 65535 supported")]
    TooManyGroups(u32),
    /// More triangles or points than 32-bit ids number: the format's ids, and the weld's
    /// corner ids (three per triangle).
    #[error("{triangles} triangles and {points} points: at most {MAX_TRIANGLES} triangles and {} points supported", NONE - 1)]
    TooLarge {
        /// Triangles of the mesh.
        triangles: usize,
        /// Points of the mesh.
        points: usize,
    },
    /// More surfaces than the format's 16 bits.
    #[error("{0} surfaces, at most 65535 supported")]
    TooManySurfaces(usize),
    /// The mesh itself is not valid ([`crate::mesh::Mesh::validate`]): an index out of range,
    /// a value not finite or beyond what single-precision bounds hold.
    #[error("{0}")]
    Invalid(String),
}
