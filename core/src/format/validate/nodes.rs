//! Nodes, splits and the splits' refinement bounds.

use core::ops::Range;

use super::checks::{count, in_pieces, invalid, keys, Pieces};
use crate::format::{tags, FormatError, HierarchyParts, PositionClass, Split};
use crate::ids::{NodeId, PolyId};

/// Each node: its position in range, its parent a splittable node before it whose split
/// names it as a child.
pub(super) fn nodes(parts: &HierarchyParts<'_>, pieces: &impl Pieces) -> Result<(), FormatError> {
    in_pieces(pieces, parts.nodes.len(), &|r| nodes_in(parts, r))
}

/// [`nodes`] of the records in `range`.
fn nodes_in(parts: &HierarchyParts<'_>, range: Range<usize>) -> Result<(), FormatError> {
    let (ne, ns) = (parts.positions.len(), parts.splits.len());
    let start = range.start;
    for (i, node) in parts.nodes[range].iter().enumerate() {
        let i = start + i;
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
    Ok(())
}

/// Each split, one record after the other: children, where the floating child may go, the
/// polygons it creates and the neighbours it names.
pub(super) fn splits(parts: &HierarchyParts<'_>, pieces: &impl Pieces) -> Result<(), FormatError> {
    in_pieces(pieces, parts.splits.len(), &|r| splits_in(parts, r))
}

/// [`splits`] of the records in `range`.
fn splits_in(parts: &HierarchyParts<'_>, range: Range<usize>) -> Result<(), FormatError> {
    let start = range.start;
    for (i, s) in parts.splits[range].iter().enumerate() {
        let i = start + i;
        children(parts, i, s)?;
        floats_onto_its_groups(parts, i, s)?;
        created_polygons(parts, i, s)?;
        neighbours(parts, i, s)?;
    }
    Ok(())
}

/// Two distinct children after the node, whose parent it is; the stationary child at the
/// node's position, the floating one elsewhere and not RIGID.
fn children(parts: &HierarchyParts<'_>, i: usize, s: &Split) -> Result<(), FormatError> {
    let t = tags::SPLITS;
    for (field, c) in [("stationary", s.stationary), ("floating", s.floating)] {
        if c.index() >= parts.nodes.len() || c.index() <= i {
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
    Ok(())
}

/// A collapse moves the floating child's polygons onto the parent's position: every surface
/// group with a vertex at the floating position needs one there too.
fn floats_onto_its_groups(
    parts: &HierarchyParts<'_>,
    i: usize,
    s: &Split,
) -> Result<(), FormatError> {
    let pos = parts.nodes[i].position;
    let fpos = parts.nodes[s.floating.index()].position;
    let (from, onto) = (keys(parts, fpos), keys(parts, pos));
    let mut j = 0;
    for k in from {
        while j < onto.len() && onto[j].group < k.group {
            j += 1;
        }
        if j == onto.len() || onto[j].group != k.group {
            return Err(invalid(
                tags::SPLITS,
                i,
                "floating",
                "floats onto a position where one of its surface groups has no vertex",
                k.group.0.into(),
            ));
        }
    }
    Ok(())
}

/// `f_l` always, `f_r` optional: non-base polygons created by this node, not the same one.
fn created_polygons(parts: &HierarchyParts<'_>, i: usize, s: &Split) -> Result<(), FormatError> {
    let t = tags::SPLITS;
    let (np, nb) = (parts.polygons.len(), parts.base.len());
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
    Ok(())
}

/// The four neighbour keys: each a base polygon, `NONE` or a polygon another split creates;
/// `fl_clw` always present, `fr_ccw` exactly with `f_r`, `fr_clw` only with it.
fn neighbours(parts: &HierarchyParts<'_>, i: usize, s: &Split) -> Result<(), FormatError> {
    let t = tags::SPLITS;
    let (ns, nb) = (parts.splits.len(), parts.base.len());
    let fields = ["fl_ccw", "fl_clw", "fr_clw", "fr_ccw"];
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
    Ok(())
}

/// One bounds record per split, at its node's position, with finite non-negative figures.
pub(super) fn bounds(parts: &HierarchyParts<'_>, pieces: &impl Pieces) -> Result<(), FormatError> {
    count(tags::BOUNDS, parts.splits.len(), parts.bounds.len())?;
    in_pieces(pieces, parts.bounds.len(), &|r| bounds_in(parts, r))
}

/// [`bounds`] of the records in `range`.
fn bounds_in(parts: &HierarchyParts<'_>, range: Range<usize>) -> Result<(), FormatError> {
    let start = range.start;
    for (i, b) in parts.bounds[range].iter().enumerate() {
        let i = start + i;
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
    Ok(())
}
