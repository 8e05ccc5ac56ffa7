//! From an imported [`Mesh`] to a clean, manifold, welded mesh with surface groups.
//!
//! Steps, each counted in [`Repairs`]:
//! 1. positions with identical coordinates are welded into one node position;
//! 2. degenerate triangles (a repeated position or zero area) and duplicate triangles (the
//!    same three positions, either orientation) are dropped;
//! 3. an edge used by more than two triangles, or twice in one direction, is cut: the later
//!    triangle gets its own copies of the edge's two positions;
//! 4. a position whose triangles form several fans (a non-manifold vertex) is split, one
//!    copy per extra fan;
//! 5. surface groups grow over edges where the surface and the attributes at both ends match,
//!    never taking a triangle that would give the group a second attribute set at one
//!    position (a UV seam that closes on itself, as on a cylinder, is cut open instead);
//! 6. positions are classified FREE / SHARP / RIGID by the boundary edges through them (mesh
//!    borders and surface-group changes), and groups that share no position share an id
//!    (greedy colouring, largest groups first).
//!
//! Missing normals are computed (area-weighted, per position), missing UVs are zero and
//! missing colours white. Each attribute set records whether its normal follows from the
//! geometry (computed here, or within [`GEOMETRIC_NORMAL_DEGREES`] of the computed one),
//! which simplification then ignores.
//!
//! [`weld`] runs these steps in order, one module each: `repair` (1–4), `groups` (5–6),
//! and between them `attributes` (the corners' attributes, deduplicated).

pub use vertex_lists::{Lists, VertexLists};

mod attributes;
mod groups;
mod repair;
pub mod store;
#[cfg(test)]
mod tests;
pub mod tiled;
mod vertex_lists;

use caveclod_core::format::PositionClass;

use crate::mesh::Mesh;
use groups::Groups;
use repair::FacesOf;

/// No triangle.
const NONE: u32 = u32::MAX;

/// The most triangles a mesh may have: every corner (`3 f + k`) has a 32-bit id.
pub const MAX_TRIANGLES: usize = (NONE as usize - 1) / 3;

/// Directed edge `a → b` as a map key.
#[inline]
fn ek(a: u32, b: u32) -> u64 {
    (a as u64) << 32 | b as u64
}

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
/// which the normal still counts as following from the geometry. Heightfield normals (central
/// differences) are within 10° of it at 99.98% of St. Helens' corners, within 2° at 88%.
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
    fn key(&self) -> [u32; 9] {
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
/// that streams its arrays elsewhere ([`tiled`]) hands over at its end, and what the welded
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
    /// The mesh itself is not valid ([`Mesh::validate`]): an index out of range, a value not
    /// finite or beyond what single-precision bounds hold.
    #[error("{0}")]
    Invalid(String),
}

/// Welds, repairs and groups `mesh`.
pub fn weld(mesh: &Mesh) -> Result<Welded, WeldError> {
    weld_traced(mesh).map(|(w, _)| w)
}

/// Where the weld's triangles and positions came from, for a caller that joins welds of
/// parts of a mesh ([`tiled`]).
#[derive(Clone, Debug, Default)]
pub(crate) struct Trace {
    /// The mesh triangle of every welded triangle.
    pub(crate) source: Vec<u32>,
    /// `(welded triangle, edges cut)` of every triangle step 3 gave copies.
    pub(crate) cut: Vec<(u32, u8)>,
    /// Positions after step 1 (the first of step 3's copies).
    pub(crate) welded_positions: u32,
    /// Positions after step 3 (the first of step 4's copies).
    pub(crate) cut_positions: u32,
}

/// Whether `mesh` is one the weld takes: valid ([`Mesh::validate`]), every value within
/// [`Mesh::MAX_MAGNITUDE`], its surfaces and sizes within the welded mesh's id ranges.
pub(crate) fn check_weldable(mesh: &Mesh) -> Result<(), WeldError> {
    mesh.validate()
        .and_then(|()| mesh.check_magnitudes())
        .map_err(WeldError::Invalid)?;
    if mesh.surfaces.len() > u16::MAX as usize {
        return Err(WeldError::TooManySurfaces(mesh.surfaces.len()));
    }
    let (triangles, points) = (mesh.triangles.len(), mesh.positions.len());
    if triangles > MAX_TRIANGLES || points >= NONE as usize {
        return Err(WeldError::TooLarge { triangles, points });
    }
    Ok(())
}

/// [`weld`], and where its triangles and positions came from.
pub(crate) fn weld_traced(mesh: &Mesh) -> Result<(Welded, Trace), WeldError> {
    check_weldable(mesh)?;
    let mut repairs = Repairs::default();
    let (mut positions, remap) = repair::weld_positions(mesh, &mut repairs);
    let mut kept = repair::drop_degenerate_and_duplicates(mesh, &remap, &positions, &mut repairs)?;
    let welded_positions = positions.len() as u32;
    let faces_of = FacesOf::new(positions.len(), kept.iter().map(|k| k.0), kept.len());
    let cut = repair::cut_non_manifold_edges(&faces_of, &mut kept, &mut positions, &mut repairs);
    let cut_positions = positions.len() as u32;
    // The lists change only where a triangle was cut.
    let faces_of = if cut.is_empty() {
        faces_of
    } else {
        drop(faces_of);
        FacesOf::new(positions.len(), kept.iter().map(|k| k.0), kept.len())
    };
    // Now every directed edge has one triangle and every edge at most two: the triangle
    // across each edge, `NONE` on a border. Splitting vertices keeps these pairs (the two
    // triangles on an edge through a vertex are always in the same fan).
    let opp = repair::opposites(&kept, &faces_of);
    repair::split_non_manifold_vertices(&faces_of, &opp, &mut kept, &mut positions, &mut repairs);
    drop(faces_of);
    let (attributes, tri_attrs) =
        attributes::corner_attributes(mesh, &kept, &positions, &mut repairs);
    let groups = groups::grow_groups(mesh, &kept, &tri_attrs, &opp, positions.len());
    // A corner's attributes are its position's vertex of its triangle's group from here on.
    drop(tri_attrs);
    let classes = groups::classify(&kept, &opp, &groups.group, positions.len());
    // The steps below build the result: the repair tables go first, so they and the result
    // never take memory at once.
    drop(opp);
    let vertices = groups::vertices_per_position(&groups.vertex_of, positions.len());
    let (colour, colour_count) = groups::colour_groups(&vertices, &groups);
    if colour_count > u16::MAX as u32 {
        return Err(WeldError::TooManyGroups(colour_count));
    }
    let Groups { group, count, .. } = groups;
    let trace = Trace {
        source: kept.iter().map(|k| k.1).collect(),
        cut,
        welded_positions,
        cut_positions,
    };
    let triangles = kept
        .iter()
        .enumerate()
        .map(|(f, &(p, _))| WeldedTri { p, group: group[f] })
        .collect();
    let mut group_surfaces = vec![0u16; count as usize];
    for (&g, &(_, i)) in group.iter().zip(&kept) {
        group_surfaces[g as usize] = mesh.triangles[i as usize].surface;
    }
    let welded = Welded {
        positions,
        classes,
        attributes,
        triangles,
        group_count: count,
        group_ids: colour.iter().map(|&c| c as u16).collect(),
        group_surfaces,
        group_id_count: colour_count,
        surface_count: mesh.surfaces.len().max(1) as u32,
        has_colors: mesh.triangles.iter().any(|t| {
            t.color
                .iter()
                .any(|&c| c != crate::mesh::NO_ATTRIBUTE && (c as usize) < mesh.colors.len())
        }),
        vertices,
        repairs,
    };
    Ok((welded, trace))
}
