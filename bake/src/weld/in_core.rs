//! The weld of a mesh in memory: the steps of the module's doc in order ([`weld`]), and where
//! their triangles and positions came from ([`Trace`], for the tiled weld).

use super::attributes::corner_attributes;
use super::groups::{self, Groups};
use super::repair::{self, FacesOf};
use super::welded::{Repairs, WeldError, Welded, WeldedTri, MAX_TRIANGLES, NONE};
use crate::mesh::Mesh;

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
    let (attributes, tri_attrs) = corner_attributes(mesh, &kept, &positions, &mut repairs);
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
