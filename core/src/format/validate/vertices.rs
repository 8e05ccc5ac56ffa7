//! Positions, the vertex table and the vertices.

use core::ops::Range;

use super::checks::{count, finite, in_pieces, invalid, keys, Pieces};
use crate::format::{tags, FormatError, HierarchyParts, PositionClass};
use crate::ids::PositionId;

/// Bounds of positions: the least and the greatest coordinates.
type Bounds = [[f32; 3]; 2];

/// Every position finite and of a known class; returns the bounds of the positions (zero
/// for none).
pub(super) fn positions(
    parts: &HierarchyParts<'_>,
    pieces: &impl Pieces,
) -> Result<Bounds, FormatError> {
    if parts.positions.is_empty() {
        return Ok([[0.0; 3]; 2]);
    }
    let join = |a: Result<Bounds, FormatError>, b: Result<Bounds, FormatError>| {
        let ([amin, amax], [bmin, bmax]) = (a?, b?);
        Ok([
            [0, 1, 2].map(|k| amin[k].min(bmin[k])),
            [0, 1, 2].map(|k| amax[k].max(bmax[k])),
        ])
    };
    pieces.fold(parts.positions.len(), &|r| positions_in(parts, r), &join)
}

/// [`positions`] of the positions in `range`: their bounds (infinite, inside out, for none).
fn positions_in(parts: &HierarchyParts<'_>, range: Range<usize>) -> Result<Bounds, FormatError> {
    let mut bounds_min = [f32::INFINITY; 3];
    let mut bounds_max = [f32::NEG_INFINITY; 3];
    let start = range.start;
    for (i, p) in parts.positions[range].iter().enumerate() {
        let i = start + i;
        if let Some(x) = p.xyz.iter().find(|x| !x.is_finite()) {
            return Err(invalid(
                tags::POSITIONS,
                i,
                "xyz",
                "not a finite number",
                x.to_bits().into(),
            ));
        }
        if PositionClass::from_u32(p.class).is_none() {
            return Err(invalid(
                tags::POSITIONS,
                i,
                "class",
                "not FREE (0), SHARP (1) or RIGID (2)",
                p.class.into(),
            ));
        }
        for k in 0..3 {
            bounds_min[k] = bounds_min[k].min(p.xyz[k]);
            bounds_max[k] = bounds_max[k].max(p.xyz[k]);
        }
    }
    Ok([bounds_min, bounds_max])
}

/// The vertex table: offsets, finite vertices, then each position's entries.
pub(super) fn vertex_table(
    parts: &HierarchyParts<'_>,
    pieces: &impl Pieces,
) -> Result<(), FormatError> {
    offsets(parts)?;
    in_pieces(pieces, parts.vertices.len(), &|r| vertices_in(parts, r))?;
    in_pieces(pieces, parts.positions.len(), &|r| entries_in(parts, r))
}

/// The entries of the positions in `range`.
fn entries_in(parts: &HierarchyParts<'_>, range: Range<usize>) -> Result<(), FormatError> {
    for pi in range {
        position_entries(parts, pi)?;
    }
    Ok(())
}

/// The vertices in `range` finite.
fn vertices_in(parts: &HierarchyParts<'_>, range: Range<usize>) -> Result<(), FormatError> {
    let start = range.start;
    for (i, v) in parts.vertices[range].iter().enumerate() {
        let i = start + i;
        if !finite(&v.position) || !finite(&v.normal) || !finite(&v.uv) {
            return Err(invalid(
                tags::VERTICES,
                i,
                "attributes",
                "not a finite number",
                0,
            ));
        }
    }
    Ok(())
}

/// One offset per position plus one, from 0, ascending, ending at the table's length.
fn offsets(parts: &HierarchyParts<'_>) -> Result<(), FormatError> {
    let ne = parts.positions.len();
    let offsets = parts.vertex_table_offsets;
    count(tags::VERTEX_TABLE_OFFSETS, ne + 1, offsets.len())?;
    if offsets[0] != 0 {
        return Err(invalid(
            tags::VERTEX_TABLE_OFFSETS,
            0,
            "offset",
            "the first offset is not 0",
            offsets[0].into(),
        ));
    }
    for i in 0..ne {
        if offsets[i + 1] < offsets[i] {
            return Err(invalid(
                tags::VERTEX_TABLE_OFFSETS,
                i + 1,
                "offset",
                "offsets decrease",
                offsets[i + 1].into(),
            ));
        }
    }
    if offsets[ne] as usize != parts.vertex_table.len() {
        return Err(invalid(
            tags::VERTEX_TABLE_OFFSETS,
            ne,
            "offset",
            "the last offset is not the table length",
            offsets[ne].into(),
        ));
    }
    Ok(())
}

/// Position `pi`'s entries: groups in range and strictly ascending, zero reserved words,
/// vertices in range that lie at the position; and a FREE position in one group only.
fn position_entries(parts: &HierarchyParts<'_>, pi: usize) -> Result<(), FormatError> {
    let ks = keys(parts, PositionId(pi as u32));
    let at = parts.vertex_table_offsets[pi] as usize;
    for (j, k) in ks.iter().enumerate() {
        if k.group.0 as u32 >= parts.surface_group_count {
            return Err(invalid(
                tags::VERTEX_TABLE,
                at + j,
                "group",
                "surface-group id out of range",
                k.group.0.into(),
            ));
        }
        if j > 0 && ks[j - 1].group >= k.group {
            return Err(invalid(
                tags::VERTEX_TABLE,
                at + j,
                "group",
                "groups of a position not strictly ascending",
                k.group.0.into(),
            ));
        }
        if k.reserved != 0 {
            return Err(invalid(
                tags::VERTEX_TABLE,
                at + j,
                "reserved",
                "not zero",
                k.reserved.into(),
            ));
        }
        let Some(v) = parts.vertices.get(k.vertex as usize) else {
            return Err(invalid(
                tags::VERTEX_TABLE,
                at + j,
                "vertex",
                "vertex index out of range",
                k.vertex.into(),
            ));
        };
        if v.position.map(f32::to_bits) != parts.positions[pi].xyz.map(f32::to_bits) {
            return Err(invalid(
                tags::VERTEX_TABLE,
                at + j,
                "vertex",
                "the vertex does not lie at the position it is keyed by",
                k.vertex.into(),
            ));
        }
    }
    if ks.len() >= 2 && parts.positions[pi].class == PositionClass::Free as u32 {
        return Err(invalid(
            tags::POSITIONS,
            pi,
            "class",
            "FREE but on a surface-group boundary (several groups)",
            ks.len() as u64,
        ));
    }
    Ok(())
}
