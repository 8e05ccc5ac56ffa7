//! Reading the section table and validating every index, count and invariant, once.
//!
//! After [`validate`] succeeds, the runtime indexes the arrays with stored ids without
//! further checks: every id is in range, parents precede children (so every walk up the
//! hierarchy ends), each split's records agree with each other, and every vertex-table
//! look-up the runtime can make on a polygon exists. The cost is linear in the file size,
//! plus a walk up the hierarchy from each polygon corner (O(p · depth)).
//!
//! The passes run in a fixed order, each over its records in id order, and a pass may rely
//! on what the earlier ones checked (the splits' pass indexes nodes by the children it has
//! just checked, the polygons' pass reads vertex-table rows the offsets' pass bounded), so
//! the first error found is always the same one:
//! 1. counts: every array within what 32-bit ids (and 16-bit surface ids) can name;
//! 2. positions, then the vertex table and vertices ([`vertices`]);
//! 3. nodes, splits and their bounds ([`nodes`]);
//! 4. polygons, roots and the base mesh ([`polygons`]);
//! 5. the meta record the sections imply, against the file's `META`.
//!
//! The optional appearance sections (materials and vertex colours, [`materials`]) are
//! checked after these, against the surface and vertex counts: [`appearance`].
//!
//! Within a pass each record is checked on its own, reading only what earlier passes (and
//! its own earlier checks) bounded, so a pass may run over pieces of its records at once:
//! [`Pieces`] says how, and the first error in record order is the one reported whatever the
//! pieces, so the answer is the one a single piece gives.

mod checks;
mod materials;
mod nodes;
mod polygons;
mod table;
mod vertices;

pub use checks::{OnePiece, Pieces};
pub(crate) use materials::{appearance, Appearance};
#[cfg(feature = "alloc")]
pub(crate) use table::parse_checked;
pub(crate) use table::{
    appearance_extras, find, optional_section, parse, section, section_table_checked,
    section_table_flagged,
};

use crate::format::{tags, FormatError, HierarchyParts, Meta};
pub(crate) use checks::invalid;

/// Validates every invariant of `parts`; returns the counts and bounds. With `file_meta`,
/// the file's `META` must agree with them.
pub(crate) fn validate(
    parts: &HierarchyParts<'_>,
    file_meta: Option<&Meta>,
    pieces: &impl Pieces,
) -> Result<Meta, FormatError> {
    counts(parts)?;
    let [bounds_min, bounds_max] = vertices::positions(parts, pieces)?;
    vertices::vertex_table(parts, pieces)?;
    nodes::nodes(parts, pieces)?;
    nodes::splits(parts, pieces)?;
    nodes::bounds(parts, pieces)?;
    polygons::polygons(parts, pieces)?;
    polygons::roots(parts)?;
    polygons::base_mesh(parts, pieces)?;
    let meta = Meta {
        node_count: parts.nodes.len() as u32,
        split_count: parts.splits.len() as u32,
        root_count: parts.roots.len() as u32,
        polygon_count: parts.polygons.len() as u32,
        base_polygon_count: parts.base.len() as u32,
        position_count: parts.positions.len() as u32,
        vertex_count: parts.vertices.len() as u32,
        vertex_key_count: parts.vertex_table.len() as u32,
        surface_count: parts.surface_count,
        surface_group_count: parts.surface_group_count,
        max_depth: polygons::max_depth(parts, pieces),
        flags: 0,
        bounds_min,
        bounds_max,
        reserved: [0; 4],
    };
    if let Some(fm) = file_meta {
        agrees(fm, &meta)?;
    }
    Ok(meta)
}

/// Counts within what the ids can name, splits and base polygons within nodes and polygons,
/// and a base mesh.
fn counts(parts: &HierarchyParts<'_>) -> Result<(), FormatError> {
    let n = parts.nodes.len();
    let ns = parts.splits.len();
    let np = parts.polygons.len();
    let nb = parts.base.len();
    let ne = parts.positions.len();
    let nd = parts.vertices.len();
    let limit = u32::MAX as usize - 1;
    // Cameras tag free active-vertex records with the top bit, so node ids stay below 2^31.
    if n >= 1 << 31 || np > limit || ne > limit || nd > limit || parts.vertex_table.len() > limit {
        return Err(invalid(
            tags::META,
            0,
            "counts",
            "more records than 32-bit ids can name",
            n.max(np) as u64,
        ));
    }
    if ns > n {
        return Err(FormatError::Count {
            tag: tags::SPLITS,
            expected: n as u64,
            found: ns as u64,
        });
    }
    if nb > np {
        return Err(FormatError::Count {
            tag: tags::BASE,
            expected: np as u64,
            found: nb as u64,
        });
    }
    // Splits name their neighbours by `PolyKey`: base polygons, then two keys per split.
    if nb as u64 + 2 * ns as u64 >= u32::MAX as u64 {
        return Err(invalid(
            tags::META,
            0,
            "counts",
            "more polygon keys (base polygons + 2 per split) than 32 bits can name",
            nb as u64 + 2 * ns as u64,
        ));
    }
    if parts.surface_count > u16::MAX as u32 || parts.surface_group_count > u16::MAX as u32 {
        return Err(invalid(
            tags::META,
            0,
            "surface_count",
            "more than 65535 surfaces or groups",
            parts.surface_count.max(parts.surface_group_count).into(),
        ));
    }
    if nb == 0 {
        return Err(invalid(
            tags::BASE,
            0,
            "base",
            "the base mesh has no polygon",
            0,
        ));
    }
    Ok(())
}

/// The file's `META` (`fm`) is the record the sections imply; else the first field that
/// differs is named.
fn agrees(fm: &Meta, meta: &Meta) -> Result<(), FormatError> {
    if bytemuck::bytes_of(fm) == bytemuck::bytes_of(meta) {
        return Ok(());
    }
    let fields: [(&'static str, u32, u32); 12] = [
        ("node_count", fm.node_count, meta.node_count),
        ("split_count", fm.split_count, meta.split_count),
        ("root_count", fm.root_count, meta.root_count),
        ("polygon_count", fm.polygon_count, meta.polygon_count),
        (
            "base_polygon_count",
            fm.base_polygon_count,
            meta.base_polygon_count,
        ),
        ("position_count", fm.position_count, meta.position_count),
        ("vertex_count", fm.vertex_count, meta.vertex_count),
        (
            "vertex_key_count",
            fm.vertex_key_count,
            meta.vertex_key_count,
        ),
        ("surface_count", fm.surface_count, meta.surface_count),
        (
            "surface_group_count",
            fm.surface_group_count,
            meta.surface_group_count,
        ),
        ("max_depth", fm.max_depth, meta.max_depth),
        ("flags", fm.flags, meta.flags),
    ];
    let (field, value) = fields
        .iter()
        .find(|(_, a, b)| a != b)
        .map(|&(f, a, _)| (f, a as u64))
        .unwrap_or(("bounds", 0));
    Err(invalid(
        tags::META,
        0,
        field,
        "disagrees with the sections",
        value,
    ))
}
