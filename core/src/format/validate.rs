//! Reading the section table and validating every index, count and invariant, once.
//!
//! After [`validate`] succeeds, the runtime indexes the arrays with stored ids without
//! further checks: every id is in range, parents precede children (so every walk up the
//! hierarchy ends), each split's records agree with each other, and every vertex-table
//! look-up the runtime can make on a polygon exists. The cost is linear in the file size,
//! plus a walk up the hierarchy from each polygon corner (O(p · depth)).

use bytemuck::Pod;

use super::{
    tags, FileHeader, FormatError, HierarchyParts, SectionEntry, Tag, MAGIC, MAX_SECTIONS,
    SECTION_ALIGN, VERSION_MAJOR,
};
use crate::checksum::checksum64;
use crate::ids::{NodeId, PolyId, PositionId};
use crate::records::{BaseFace, Creator, Meta, Node, PositionClass, VertexKey};

fn invalid(
    tag: Tag,
    record: usize,
    field: &'static str,
    problem: &'static str,
    value: u64,
) -> FormatError {
    FormatError::Invalid {
        tag,
        record: record as u64,
        field,
        problem,
        value,
    }
}

/// The sections of a parsed file, before validation.
pub(crate) struct Parsed<'a> {
    pub parts: HierarchyParts<'a>,
    pub meta: Meta,
    pub checksum: u64,
}

/// The section table of `bytes` after its header checks and the checksum; entry `i` is valid
/// if the function returned `Ok`.
pub(crate) fn section_table(bytes: &[u8]) -> Result<(SectionTable<'_>, u64), FormatError> {
    section_table_checked(bytes, true)
}

/// [`section_table`], with the checksum of every byte after the header verified or not (a
/// file a [`Hierarchy`](crate::Hierarchy) was made from was verified once already: looking a
/// section up again must not read the whole file again).
pub(crate) fn section_table_checked(
    bytes: &[u8],
    verify_checksum: bool,
) -> Result<(SectionTable<'_>, u64), FormatError> {
    let header_len = core::mem::size_of::<FileHeader>();
    if bytes.len() < header_len {
        return Err(FormatError::Truncated {
            needed: header_len as u64,
            len: bytes.len() as u64,
        });
    }
    let header: FileHeader = bytemuck::pod_read_unaligned(&bytes[..header_len]);
    if header.magic != MAGIC {
        return Err(FormatError::BadMagic);
    }
    if header.version_major != VERSION_MAJOR {
        return Err(FormatError::UnsupportedVersion {
            major: header.version_major,
            minor: header.version_minor,
        });
    }
    if header.header_len as usize != header_len {
        return Err(FormatError::BadHeader {
            field: "header_len",
            value: header.header_len.into(),
        });
    }
    if header.file_len != bytes.len() as u64 {
        return Err(FormatError::LengthMismatch {
            header: header.file_len,
            actual: bytes.len() as u64,
        });
    }
    if header.flags != 0 {
        return Err(FormatError::BadHeader {
            field: "flags",
            value: header.flags.into(),
        });
    }
    if let Some(&r) = header.reserved.iter().find(|&&r| r != 0) {
        return Err(FormatError::BadHeader {
            field: "reserved",
            value: r.into(),
        });
    }
    if header.section_count > MAX_SECTIONS {
        return Err(FormatError::BadHeader {
            field: "section_count",
            value: header.section_count.into(),
        });
    }
    let table_len = header.section_count as usize * core::mem::size_of::<SectionEntry>();
    if bytes.len() < header_len + table_len {
        return Err(FormatError::Truncated {
            needed: (header_len + table_len) as u64,
            len: bytes.len() as u64,
        });
    }
    let computed = if verify_checksum {
        checksum64(&bytes[header_len..])
    } else {
        header.checksum
    };
    if computed != header.checksum {
        return Err(FormatError::ChecksumMismatch {
            stored: header.checksum,
            computed,
        });
    }
    let table = SectionTable {
        bytes: &bytes[header_len..header_len + table_len],
    };
    let mut end_of_previous = (header_len + table_len) as u64;
    for (i, e) in table.iter().enumerate() {
        let problem = |problem| FormatError::SectionTable {
            index: i as u32,
            tag: e.tag,
            problem,
        };
        if e.record_size == 0 {
            return Err(problem("record size is zero"));
        }
        if e.offset % SECTION_ALIGN as u64 != 0 {
            return Err(problem("offset is not a multiple of 64"));
        }
        if e.offset < end_of_previous {
            return Err(problem("overlaps the table or the previous section"));
        }
        let len = (e.record_size as u64)
            .checked_mul(e.record_count)
            .ok_or(problem("length overflows"))?;
        let end = e
            .offset
            .checked_add(len)
            .ok_or(problem("length overflows"))?;
        if end > bytes.len() as u64 {
            return Err(problem("extends past the end of the file"));
        }
        end_of_previous = end;
    }
    Ok((table, header.checksum))
}

/// The section table, read entry by entry (its `u64` fields need no alignment from the
/// caller's buffer: only the sections' own records, at most 4-byte aligned, are cast in
/// place).
#[derive(Clone, Copy)]
pub(crate) struct SectionTable<'a> {
    bytes: &'a [u8],
}

impl SectionTable<'_> {
    pub(crate) fn iter(&self) -> impl Iterator<Item = SectionEntry> + '_ {
        self.bytes
            .chunks_exact(core::mem::size_of::<SectionEntry>())
            .map(bytemuck::pod_read_unaligned)
    }
}

fn section<'a, T: Pod>(
    bytes: &'a [u8],
    table: SectionTable<'_>,
    tag: Tag,
) -> Result<&'a [T], FormatError> {
    let mut found: Option<SectionEntry> = None;
    for e in table.iter() {
        if e.tag == tag {
            if found.is_some() {
                return Err(FormatError::DuplicateSection { tag });
            }
            found = Some(e);
        }
    }
    let e = found.ok_or(FormatError::MissingSection { tag })?;
    let expected = core::mem::size_of::<T>() as u32;
    if e.record_size != expected {
        return Err(FormatError::RecordSize {
            tag,
            expected,
            found: e.record_size,
        });
    }
    // In range: checked by `section_table`.
    let start = e.offset as usize;
    let end = start + e.record_size as usize * e.record_count as usize;
    bytemuck::try_cast_slice(&bytes[start..end]).map_err(|_| FormatError::Misaligned { tag })
}

/// Finds the known sections of `bytes` (header, table and checksum checked), without
/// validating their contents.
pub(crate) fn parse(bytes: &[u8]) -> Result<Parsed<'_>, FormatError> {
    let (table, checksum) = section_table(bytes)?;
    let meta_records: &[Meta] = section(bytes, table, tags::META)?;
    let meta = match meta_records {
        [m] => *m,
        _ => {
            return Err(FormatError::Count {
                tag: tags::META,
                expected: 1,
                found: meta_records.len() as u64,
            })
        }
    };
    let parts = HierarchyParts {
        positions: section(bytes, table, tags::POSITIONS)?,
        nodes: section(bytes, table, tags::NODES)?,
        splits: section(bytes, table, tags::SPLITS)?,
        bounds: section(bytes, table, tags::BOUNDS)?,
        polygons: section(bytes, table, tags::POLYGONS)?,
        roots: section(bytes, table, tags::ROOTS)?,
        base: section(bytes, table, tags::BASE)?,
        vertex_table_offsets: section(bytes, table, tags::VERTEX_TABLE_OFFSETS)?,
        vertex_table: section(bytes, table, tags::VERTEX_TABLE)?,
        vertices: section(bytes, table, tags::VERTICES)?,
        surface_count: meta.surface_count,
        surface_group_count: meta.surface_group_count,
    };
    Ok(Parsed {
        parts,
        meta,
        checksum,
    })
}

fn finite(v: &[f32]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// `true` if `anc` is `leaf` or one of its ancestors. Parents precede children, so the walk
/// stops as soon as the id drops below `anc`.
fn descends(nodes: &[Node], leaf: NodeId, anc: NodeId) -> bool {
    let mut v = leaf;
    loop {
        if v == anc {
            return true;
        }
        if v.0 < anc.0 || nodes[v.index()].parent.is_none() {
            return false;
        }
        v = nodes[v.index()].parent;
    }
}

fn root_of(nodes: &[Node], leaf: NodeId) -> NodeId {
    let mut v = leaf;
    while nodes[v.index()].parent.is_some() {
        v = nodes[v.index()].parent;
    }
    v
}

/// The sorted vertex-table entries of a position (offsets already validated).
fn keys<'a>(parts: &HierarchyParts<'a>, p: PositionId) -> &'a [VertexKey] {
    let o = parts.vertex_table_offsets;
    &parts.vertex_table[o[p.index()] as usize..o[p.index() + 1] as usize]
}

fn count(tag: Tag, expected: usize, found: usize) -> Result<(), FormatError> {
    if expected != found {
        return Err(FormatError::Count {
            tag,
            expected: expected as u64,
            found: found as u64,
        });
    }
    Ok(())
}

/// Validates every invariant of `parts`; returns the counts and bounds. With `file_meta`,
/// the file's `META` must agree with them.
pub(crate) fn validate(
    parts: &HierarchyParts<'_>,
    file_meta: Option<&Meta>,
) -> Result<Meta, FormatError> {
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

    // Positions.
    let mut bounds_min = [f32::INFINITY; 3];
    let mut bounds_max = [f32::NEG_INFINITY; 3];
    for (i, p) in parts.positions.iter().enumerate() {
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

    // Vertex table and vertices.
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
    for (i, v) in parts.vertices.iter().enumerate() {
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
    for pi in 0..ne {
        let ks = keys(parts, PositionId(pi as u32));
        let at = offsets[pi] as usize;
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
    }

    // Nodes.
    for (i, node) in parts.nodes.iter().enumerate() {
        if node.position.index() >= ne {
            return Err(invalid(
                tags::NODES,
                i,
                "position",
                "position id out of range",
                node.position.0.into(),
            ));
        }
        if node.parent.is_some() && node.parent.0 as usize >= i.min(ns) {
            return Err(invalid(
                tags::NODES,
                i,
                "parent",
                "parent is not a splittable node before this one",
                node.parent.0.into(),
            ));
        }
        if let Some(p) = node.parent.get() {
            let s = &parts.splits[p.index()];
            if s.stationary.index() != i && s.floating.index() != i {
                return Err(invalid(
                    tags::NODES,
                    i,
                    "parent",
                    "the parent's split does not name this node as a child",
                    p.0.into(),
                ));
            }
        }
    }

    // Splits.
    let fields = ["fl_ccw", "fl_clw", "fr_clw", "fr_ccw"];
    for (i, s) in parts.splits.iter().enumerate() {
        let t = tags::SPLITS;
        for (field, c) in [("stationary", s.stationary), ("floating", s.floating)] {
            if c.index() >= n || c.index() <= i {
                return Err(invalid(
                    t,
                    i,
                    field,
                    "child id out of range or not after its parent",
                    c.0.into(),
                ));
            }
            if parts.nodes[c.index()].parent.index() != i {
                return Err(invalid(
                    t,
                    i,
                    field,
                    "the child's parent is not this node",
                    c.0.into(),
                ));
            }
        }
        if s.stationary == s.floating {
            return Err(invalid(
                t,
                i,
                "floating",
                "the same node as the stationary child",
                s.floating.0.into(),
            ));
        }
        let pos = parts.nodes[i].position;
        if parts.nodes[s.stationary.index()].position != pos {
            return Err(invalid(
                t,
                i,
                "stationary",
                "does not share the parent's position",
                s.stationary.0.into(),
            ));
        }
        let fpos = parts.nodes[s.floating.index()].position;
        if fpos == pos {
            return Err(invalid(
                t,
                i,
                "floating",
                "lies at the parent's position",
                s.floating.0.into(),
            ));
        }
        if parts.positions[fpos.index()].class == PositionClass::Rigid as u32 {
            return Err(invalid(
                t,
                i,
                "floating",
                "a RIGID position never floats",
                fpos.0.into(),
            ));
        }
        // A collapse moves the floating child's polygons onto the parent's position: every
        // surface group with a vertex at the floating position needs one there too.
        let (from, onto) = (keys(parts, fpos), keys(parts, pos));
        let mut j = 0;
        for k in from {
            while j < onto.len() && onto[j].group < k.group {
                j += 1;
            }
            if j == onto.len() || onto[j].group != k.group {
                return Err(invalid(
                    t,
                    i,
                    "floating",
                    "floats onto a position where one of its surface groups has no vertex",
                    k.group.0.into(),
                ));
            }
        }
        for (field, f) in [("f_l", s.f_l), ("f_r", s.f_r)] {
            if f.is_none() && field == "f_l" {
                return Err(invalid(t, i, field, "every split creates f_l", f.0.into()));
            }
            if let Some(f) = f.get() {
                if f.index() >= np || f.index() < nb {
                    return Err(invalid(
                        t,
                        i,
                        field,
                        "polygon id out of range or a base polygon",
                        f.0.into(),
                    ));
                }
                if parts.polygons[f.index()].creator.node() != Some(NodeId(i as u32)) {
                    return Err(invalid(
                        t,
                        i,
                        field,
                        "the polygon's creator is not this node",
                        f.0.into(),
                    ));
                }
            }
        }
        if s.f_l == s.f_r {
            return Err(invalid(
                t,
                i,
                "f_r",
                "the same polygon as f_l",
                s.f_r.0.into(),
            ));
        }
        for (k, &f) in s.neighbours.iter().enumerate() {
            let problem = match f.creator(nb as u32) {
                // A base polygon's key, or `NONE`.
                None => None,
                Some((node, _)) if node.index() >= ns => Some("polygon key out of range"),
                Some((node, _)) if node.index() == i => Some("one of the split's own polygons"),
                Some((node, true)) if parts.splits[node.index()].f_r.is_none() => {
                    Some("names the f_r of a split that has none")
                }
                Some(_) => None,
            };
            if let Some(problem) = problem {
                return Err(invalid(t, i, fields[k], problem, f.0.into()));
            }
        }
        if s.neighbours[1].is_none() {
            return Err(invalid(
                t,
                i,
                "fl_clw",
                "always present",
                PolyId::NONE.0.into(),
            ));
        }
        if s.f_r.is_some() != s.neighbours[3].is_some() {
            return Err(invalid(
                t,
                i,
                "fr_ccw",
                "present exactly when f_r is",
                s.neighbours[3].0.into(),
            ));
        }
        if s.f_r.is_none() && s.neighbours[2].is_some() {
            return Err(invalid(
                t,
                i,
                "fr_clw",
                "present without f_r",
                s.neighbours[2].0.into(),
            ));
        }
    }

    // Bounds.
    count(tags::BOUNDS, ns, parts.bounds.len())?;
    for (i, b) in parts.bounds.iter().enumerate() {
        let t = tags::BOUNDS;
        let pos = parts.nodes[i].position;
        if b.point.map(f32::to_bits) != parts.positions[pos.index()].xyz.map(f32::to_bits) {
            return Err(invalid(
                t,
                i,
                "point",
                "differs from the node's position",
                pos.0.into(),
            ));
        }
        for (field, x) in [
            ("radius", b.radius),
            ("cone_sin2", b.cone_sin2),
            ("uni_error", b.uni_error),
            ("dir_error", b.dir_error),
        ] {
            if !x.is_finite() || x < 0.0 {
                return Err(invalid(
                    t,
                    i,
                    field,
                    "not a finite, non-negative number",
                    x.to_bits().into(),
                ));
            }
        }
    }

    // Polygons.
    for (i, poly) in parts.polygons.iter().enumerate() {
        let t = tags::POLYGONS;
        for &v in &poly.nodes {
            if v.index() >= n || v.index() < ns {
                return Err(invalid(
                    t,
                    i,
                    "nodes",
                    "not a full-resolution (leaf) node",
                    v.0.into(),
                ));
            }
            let ks = keys(parts, parts.nodes[v.index()].position);
            if ks.binary_search_by_key(&poly.group, |k| k.group).is_err() {
                return Err(invalid(
                    t,
                    i,
                    "group",
                    "no vertex of this surface group at a corner's position",
                    poly.group.0.into(),
                ));
            }
        }
        if poly.nodes[0] == poly.nodes[1]
            || poly.nodes[1] == poly.nodes[2]
            || poly.nodes[0] == poly.nodes[2]
        {
            return Err(invalid(
                t,
                i,
                "nodes",
                "repeats a node (degenerate polygon)",
                poly.nodes[0].0.into(),
            ));
        }
        if poly.surface.0 as u32 >= parts.surface_count {
            return Err(invalid(
                t,
                i,
                "surface",
                "surface id out of range",
                poly.surface.0.into(),
            ));
        }
        if i < nb {
            if poly.creator != Creator::BASE {
                return Err(invalid(
                    t,
                    i,
                    "creator",
                    "a base polygon has no creator",
                    poly.creator.0.into(),
                ));
            }
            continue;
        }
        let Some(c) = poly.creator.node().filter(|c| c.index() < ns) else {
            return Err(invalid(
                t,
                i,
                "creator",
                "not a splittable node",
                poly.creator.0.into(),
            ));
        };
        let s = &parts.splits[c.index()];
        let id = PolyId(i as u32);
        let right = poly.creator.is_right();
        let float_corner = if right { 2 } else { 1 };
        if (if right { s.f_r } else { s.f_l }) != id {
            return Err(invalid(
                t,
                i,
                "creator",
                "the creator's split does not name this polygon on that side",
                poly.creator.0.into(),
            ));
        }
        if !descends(parts.nodes, poly.nodes[0], s.stationary) {
            return Err(invalid(
                t,
                i,
                "nodes",
                "corner 0 does not descend from the creator's stationary child",
                poly.nodes[0].0.into(),
            ));
        }
        if !descends(parts.nodes, poly.nodes[float_corner], s.floating) {
            return Err(invalid(
                t,
                i,
                "nodes",
                "the new edge's other corner does not descend from the floating child",
                poly.nodes[float_corner].0.into(),
            ));
        }
    }

    // Roots.
    let mut r = 0;
    for (i, node) in parts.nodes.iter().enumerate() {
        if node.parent.is_none() {
            if parts.roots.get(r).map(|x| x.index()) != Some(i) {
                return Err(invalid(
                    tags::ROOTS,
                    r,
                    "root",
                    "roots must list exactly the nodes without parent, ascending",
                    i as u64,
                ));
            }
            r += 1;
        }
    }
    count(tags::ROOTS, r, parts.roots.len())?;

    // Base mesh.
    for (i, b) in parts.base.iter().enumerate() {
        let t = tags::BASE;
        for k in 0..3 {
            let c = b.corners[k];
            if c.index() >= n || parts.nodes[c.index()].parent.is_some() {
                return Err(invalid(t, i, "corners", "not a root", c.0.into()));
            }
            if root_of(parts.nodes, parts.polygons[i].nodes[k]) != c {
                return Err(invalid(
                    t,
                    i,
                    "corners",
                    "not the root above the polygon's full-resolution node",
                    c.0.into(),
                ));
            }
            if let Some(g) = b.neighbours[k].get() {
                if g.index() >= nb || g.index() == i {
                    return Err(invalid(
                        t,
                        i,
                        "neighbours",
                        "not another base polygon",
                        g.0.into(),
                    ));
                }
                // Across the edge opposite corner k lie corners k+1 and k+2; the neighbour
                // must hold both and point back across that edge.
                let (a, bb) = (c_at(b, k + 1), c_at(b, k + 2));
                let other = &parts.base[g.index()];
                let back = (0..3).find(|&m| other.corners[m] != a && other.corners[m] != bb);
                let shares = other.corners.contains(&a) && other.corners.contains(&bb);
                if !shares || back.map(|m| other.neighbours[m]) != Some(PolyId(i as u32)) {
                    return Err(invalid(
                        t,
                        i,
                        "neighbours",
                        "the neighbour does not share the edge or does not link back",
                        g.0.into(),
                    ));
                }
            }
        }
        if b.corners[0] == b.corners[1]
            || b.corners[1] == b.corners[2]
            || b.corners[0] == b.corners[2]
        {
            return Err(invalid(
                t,
                i,
                "corners",
                "repeats a node",
                b.corners[0].0.into(),
            ));
        }
    }

    // Depth: walk up from each leaf.
    let mut max_depth = 0u32;
    for leaf in ns..n {
        let mut d = 0;
        let mut v = NodeId(leaf as u32);
        while let Some(p) = parts.nodes[v.index()].parent.get() {
            d += 1;
            v = p;
        }
        max_depth = max_depth.max(d);
    }

    if ne == 0 {
        bounds_min = [0.0; 3];
        bounds_max = [0.0; 3];
    }
    let meta = Meta {
        node_count: n as u32,
        split_count: ns as u32,
        root_count: parts.roots.len() as u32,
        polygon_count: np as u32,
        base_polygon_count: nb as u32,
        position_count: ne as u32,
        vertex_count: nd as u32,
        vertex_key_count: parts.vertex_table.len() as u32,
        surface_count: parts.surface_count,
        surface_group_count: parts.surface_group_count,
        max_depth,
        flags: 0,
        bounds_min,
        bounds_max,
        reserved: [0; 4],
    };
    if let Some(fm) = file_meta {
        if bytemuck::bytes_of(fm) != bytemuck::bytes_of(&meta) {
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
            return Err(invalid(
                tags::META,
                0,
                field,
                "disagrees with the sections",
                value,
            ));
        }
    }
    Ok(meta)
}

fn c_at(b: &BaseFace, k: usize) -> NodeId {
    b.corners[k % 3]
}
