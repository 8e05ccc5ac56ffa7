//! A page's checks when it is installed: every reference within the page in full, every
//! reference into another page by that page's counts, and each node against its parent's
//! split record (the parent's page is resident: it is this page or one of its parents).

use super::layout::{RecordKind, SegmentedId};
use super::table::PageTable;
use super::view::PageView;
use crate::format::records::{Creator, PositionClass};
use crate::format::validate::invalid;
use crate::format::{tags, FormatError};
use crate::ids::NodeId;

/// What a page's references are checked against: its file's page table and counts.
#[derive(Clone, Copy, Debug)]
pub struct PageContext<'t> {
    /// The file's page table.
    pub table: PageTable<'t>,
    /// How the file's ids split.
    pub ids: SegmentedId,
    /// Pages `0..root_pages` are the root's.
    pub root_pages: u32,
    /// Polygons of the base mesh: polygon keys below it name them.
    pub base_polygons: u32,
    /// Surfaces: every polygon's surface is below it.
    pub surfaces: u32,
    /// Surface groups: every group id is below it.
    pub groups: u32,
}

impl PageContext<'_> {
    /// `true` if `id` names a record of `kind` in some page.
    pub(crate) fn exists(&self, id: u32, kind: RecordKind) -> bool {
        let page = self.ids.page(id);
        self.table
            .entry(page)
            .is_some_and(|e| self.ids.index(id) < e.counts[kind as usize])
    }
}

/// Checks page `page`'s records. `resident` gives the views of resident pages (its parents
/// and the root's pages at least).
pub fn check_page<'p>(
    cx: &PageContext<'_>,
    page: u32,
    view: &PageView<'_>,
    resident: impl Fn(u32) -> Option<PageView<'p>>,
) -> Result<(), FormatError> {
    check_nodes(cx, page, view, &resident)?;
    check_splits(cx, page, view)?;
    check_bounds(view)?;
    check_polygons(cx, page, view)?;
    check_positions(view)?;
    check_vertex_table(cx, page, view)
}

fn check_nodes<'p>(
    cx: &PageContext<'_>,
    page: u32,
    view: &PageView<'_>,
    resident: &impl Fn(u32) -> Option<PageView<'p>>,
) -> Result<(), FormatError> {
    let parents = cx.table.parents(page);
    for (i, n) in view.nodes.iter().enumerate() {
        let id = cx.ids.id(page, i as u32).unwrap_or(u32::MAX);
        let bad =
            |field, problem, value: u32| invalid(tags::NODES, i, field, problem, value.into());
        let p = n.position.0;
        if !cx.exists(p, RecordKind::Positions) || cx.ids.page(p) > page {
            return Err(bad(
                "position",
                "names no position of this page or an earlier one",
                p,
            ));
        }
        let Some(parent) = n.parent.get() else {
            if page < cx.root_pages {
                continue;
            }
            return Err(bad(
                "parent",
                "a node outside the root's pages has no parent",
                u32::MAX,
            ));
        };
        let pp = cx.ids.page(parent.0);
        if pp != page && parents.binary_search(&pp).is_err() {
            return Err(bad(
                "parent",
                "lies neither in this page nor in one of its parents",
                parent.0,
            ));
        }
        let split = if pp == page {
            view.splits.get(cx.ids.index(parent.0) as usize).copied()
        } else {
            resident(pp).and_then(|v| v.splits.get(cx.ids.index(parent.0) as usize).copied())
        };
        let Some(split) = split else {
            return Err(bad(
                "parent",
                "names a node that cannot be split (or its page is absent)",
                parent.0,
            ));
        };
        if split.stationary.0 != id && split.floating.0 != id {
            return Err(bad(
                "parent",
                "its split record does not name this node as a child",
                parent.0,
            ));
        }
    }
    Ok(())
}

fn check_splits(cx: &PageContext<'_>, page: u32, view: &PageView<'_>) -> Result<(), FormatError> {
    for (i, s) in view.splits.iter().enumerate() {
        let bad =
            |field, problem, value: u32| invalid(tags::SPLITS, i, field, problem, value.into());
        let id = cx.ids.id(page, i as u32).unwrap_or(u32::MAX);
        for (field, child) in [("stationary", s.stationary.0), ("floating", s.floating.0)] {
            if !cx.exists(child, RecordKind::Nodes) || cx.ids.page(child) < page {
                return Err(bad(
                    field,
                    "names no node of this page or a later one",
                    child,
                ));
            }
        }
        if s.stationary == s.floating {
            return Err(bad("floating", "equals the stationary child", s.floating.0));
        }
        for (field, poly, right) in [("f_l", s.f_l.0, false), ("f_r", s.f_r.0, true)] {
            if right && poly == u32::MAX {
                continue;
            }
            let polygon = (cx.ids.page(poly) == page)
                .then(|| view.polygons.get(cx.ids.index(poly) as usize))
                .flatten();
            if polygon.map(|p| p.creator) != Some(Creator::new(NodeId(id), right)) {
                return Err(bad(
                    field,
                    "names no polygon of this page created by this split",
                    poly,
                ));
            }
        }
        for (k, key) in s.neighbours.iter().enumerate() {
            let required = k == 1 || (k == 3 && s.f_r.is_some());
            let allowed = k != 3 || s.f_r.is_some();
            let Some(key) = key.get() else {
                if required {
                    return Err(bad(
                        "neighbours",
                        "a neighbour the split needs is missing",
                        u32::MAX,
                    ));
                }
                continue;
            };
            let ok = allowed
                && (key.0 < cx.base_polygons
                    || cx.exists((key.0 - cx.base_polygons) >> 1, RecordKind::Splits));
            if !ok {
                return Err(bad("neighbours", "names no polygon", key.0));
            }
        }
    }
    Ok(())
}

fn check_bounds(view: &PageView<'_>) -> Result<(), FormatError> {
    for (i, b) in view.bounds.iter().enumerate() {
        let figures = [b.radius, b.uni_error, b.dir_error];
        let finite = b.point.iter().all(|v| v.is_finite()) && b.cone_sin2.is_finite();
        if !finite || figures.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
            return Err(invalid(
                tags::BOUNDS,
                i,
                "bounds",
                "not finite, or a negative radius or error",
                0,
            ));
        }
    }
    Ok(())
}

fn check_polygons(cx: &PageContext<'_>, page: u32, view: &PageView<'_>) -> Result<(), FormatError> {
    for (i, p) in view.polygons.iter().enumerate() {
        let bad =
            |field, problem, value: u32| invalid(tags::POLYGONS, i, field, problem, value.into());
        if let Some(&n) = p.nodes.iter().find(|n| !cx.exists(n.0, RecordKind::Nodes)) {
            return Err(bad("nodes", "names no node", n.0));
        }
        if u32::from(p.surface.0) >= cx.surfaces || u32::from(p.group.0) >= cx.groups {
            return Err(bad(
                "surface",
                "surface or group out of range",
                p.surface.0.into(),
            ));
        }
        match p.creator.node() {
            None if page < cx.root_pages => {}
            None => {
                return Err(bad(
                    "creator",
                    "a base polygon outside the root's pages",
                    u32::MAX,
                ))
            }
            Some(node) => {
                let here = cx.ids.page(node.0) == page
                    && (cx.ids.index(node.0) as usize) < view.splits.len();
                if !here {
                    return Err(bad("creator", "names no split of this page", node.0));
                }
            }
        }
    }
    Ok(())
}

fn check_positions(view: &PageView<'_>) -> Result<(), FormatError> {
    for (i, p) in view.positions.iter().enumerate() {
        if !p.xyz.iter().all(|v| v.is_finite()) || PositionClass::from_u32(p.class).is_none() {
            return Err(invalid(
                tags::POSITIONS,
                i,
                "xyz",
                "not finite, or an unknown class",
                p.class.into(),
            ));
        }
    }
    for (i, v) in view.vertices.iter().enumerate() {
        let all = v.position.iter().chain(&v.normal).chain(&v.uv);
        if !all.into_iter().all(|x| x.is_finite()) {
            return Err(invalid(tags::VERTICES, i, "position", "not finite", 0));
        }
    }
    Ok(())
}

fn check_vertex_table(
    cx: &PageContext<'_>,
    page: u32,
    view: &PageView<'_>,
) -> Result<(), FormatError> {
    let offsets = view.vertex_table_offsets;
    let ascending = offsets.windows(2).all(|w| w[0] <= w[1]);
    let ends = offsets.first() == Some(&0)
        && offsets.last().map(|&l| l as usize) == Some(view.vertex_table.len());
    if !(ascending && ends) {
        return Err(invalid(
            tags::VERTEX_TABLE_OFFSETS,
            0,
            "offsets",
            "not ascending from 0 to the table's length",
            0,
        ));
    }
    for q in 0..view.positions.len() {
        let keys = view.vertex_keys(q);
        if keys.windows(2).any(|w| w[0].group.0 >= w[1].group.0) {
            return Err(invalid(
                tags::VERTEX_TABLE,
                offsets[q] as usize,
                "group",
                "groups not strictly ascending",
                0,
            ));
        }
    }
    for (i, k) in view.vertex_table.iter().enumerate() {
        let here = cx.ids.page(k.vertex) == page
            && (cx.ids.index(k.vertex) as usize) < view.vertices.len();
        if u32::from(k.group.0) >= cx.groups || k.reserved != 0 || !here {
            return Err(invalid(
                tags::VERTEX_TABLE,
                i,
                "vertex",
                "names no vertex of this page, or a bad group",
                k.vertex.into(),
            ));
        }
    }
    Ok(())
}
