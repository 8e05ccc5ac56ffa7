//! Polygons, roots, the base mesh and the depth of the hierarchy.

use core::ops::Range;

use super::checks::{count, in_pieces, invalid, keys, Pieces};
use crate::format::{tags, BaseFace, Creator, FormatError, HierarchyParts, Node, Polygon};
use crate::ids::{NodeId, PolyId};

/// Each polygon: its corners and surface, then its creator.
pub(super) fn polygons(
    parts: &HierarchyParts<'_>,
    pieces: &impl Pieces,
) -> Result<(), FormatError> {
    in_pieces(pieces, parts.polygons.len(), &|r| polygons_in(parts, r))
}

/// [`polygons`] of the records in `range`.
fn polygons_in(parts: &HierarchyParts<'_>, range: Range<usize>) -> Result<(), FormatError> {
    let start = range.start;
    for (i, poly) in parts.polygons[range].iter().enumerate() {
        let i = start + i;
        corners(parts, i, poly)?;
        creator(parts, i, poly)?;
    }
    Ok(())
}

/// Three distinct leaves, each with a vertex of the polygon's group at its position, and a
/// surface in range.
fn corners(parts: &HierarchyParts<'_>, i: usize, poly: &Polygon) -> Result<(), FormatError> {
    let t = tags::POLYGONS;
    let (n, ns) = (parts.nodes.len(), parts.splits.len());
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
    Ok(())
}

/// A base polygon has no creator; any other is named by its creator's split on its side,
/// and its corners descend from the split's children as the split's new edge requires.
fn creator(parts: &HierarchyParts<'_>, i: usize, poly: &Polygon) -> Result<(), FormatError> {
    let t = tags::POLYGONS;
    if i < parts.base.len() {
        if poly.creator != Creator::BASE {
            return Err(invalid(
                t,
                i,
                "creator",
                "a base polygon has no creator",
                poly.creator.0.into(),
            ));
        }
        return Ok(());
    }
    let ns = parts.splits.len();
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
    Ok(())
}

/// The roots list exactly the nodes without parent, ascending.
pub(super) fn roots(parts: &HierarchyParts<'_>) -> Result<(), FormatError> {
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
    count(tags::ROOTS, r, parts.roots.len())
}

/// Each base face: its corners the roots above its polygon's corners, no corner twice, and
/// its neighbours other base faces that share the edge and link back.
pub(super) fn base_mesh(
    parts: &HierarchyParts<'_>,
    pieces: &impl Pieces,
) -> Result<(), FormatError> {
    in_pieces(pieces, parts.base.len(), &|r| base_mesh_in(parts, r))
}

/// [`base_mesh`] of the records in `range`.
fn base_mesh_in(parts: &HierarchyParts<'_>, range: Range<usize>) -> Result<(), FormatError> {
    let start = range.start;
    for (i, b) in parts.base[range].iter().enumerate() {
        let i = start + i;
        for k in 0..3 {
            base_corner(parts, i, b, k)?;
        }
        if b.corners[0] == b.corners[1]
            || b.corners[1] == b.corners[2]
            || b.corners[0] == b.corners[2]
        {
            return Err(invalid(
                tags::BASE,
                i,
                "corners",
                "repeats a node",
                b.corners[0].0.into(),
            ));
        }
    }
    Ok(())
}

/// Corner `k` of base face `i` and its neighbour across the opposite edge.
fn base_corner(
    parts: &HierarchyParts<'_>,
    i: usize,
    b: &BaseFace,
    k: usize,
) -> Result<(), FormatError> {
    let t = tags::BASE;
    let c = b.corners[k];
    if c.index() >= parts.nodes.len() || parts.nodes[c.index()].parent.is_some() {
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
    let Some(g) = b.neighbours[k].get() else {
        return Ok(());
    };
    if g.index() >= parts.base.len() || g.index() == i {
        return Err(invalid(
            t,
            i,
            "neighbours",
            "not another base polygon",
            g.0.into(),
        ));
    }
    // Across the edge opposite corner k lie corners k+1 and k+2; the neighbour must hold
    // both and point back across that edge.
    let (a, bb) = (b.corners[(k + 1) % 3], b.corners[(k + 2) % 3]);
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
    Ok(())
}

/// The longest walk up from a leaf to its root.
pub(super) fn max_depth(parts: &HierarchyParts<'_>, pieces: &impl Pieces) -> u32 {
    let ns = parts.splits.len();
    let leaves = parts.nodes.len() - ns;
    pieces.fold(
        leaves,
        &|r| max_depth_in(parts, ns + r.start..ns + r.end),
        &|a, b| a.max(b),
    )
}

/// The longest walk up from the leaves `leaves`.
fn max_depth_in(parts: &HierarchyParts<'_>, leaves: Range<usize>) -> u32 {
    let mut max_depth = 0u32;
    for leaf in leaves {
        let mut d = 0;
        let mut v = NodeId(leaf as u32);
        while let Some(p) = parts.nodes[v.index()].parent.get() {
            d += 1;
            v = p;
        }
        max_depth = max_depth.max(d);
    }
    max_depth
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
