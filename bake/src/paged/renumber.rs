//! Page-major ids: each page's records numbered in the order they lie in it, and the id
//! width that the largest page needs.

use caveclod_core::format::paged::SegmentedId;
use caveclod_core::{Hierarchy, PolyKey};

use super::error::PagedError;
use super::partition::Partition;

const NONE: u32 = u32::MAX;

/// The records of one page, by old id, in page order.
#[derive(Default)]
pub(crate) struct Members {
    /// Splittable nodes (depth-first), then leaves.
    pub nodes: Vec<u32>,
    /// How many of `nodes` can be split.
    pub splits: u32,
    /// Base polygons (root page), then each split's `f_l` and `f_r`.
    pub polygons: Vec<u32>,
    /// Positions the page's nodes bring.
    pub positions: Vec<u32>,
    /// Vertex-table entries of those positions, in order (one new vertex each).
    pub keys: Vec<u32>,
}

/// Old ids to new, and each page's members.
pub(crate) struct Renumbered {
    pub ids: SegmentedId,
    pub node: Vec<u32>,
    pub polygon: Vec<u32>,
    pub position: Vec<u32>,
    /// New vertex id per old vertex-table entry.
    pub key_vertex: Vec<u32>,
    pub pages: Vec<Members>,
}

impl Renumbered {
    /// The new key of an old polygon key.
    pub(crate) fn key(&self, base: u32, key: PolyKey) -> PolyKey {
        match key.creator(base) {
            None => key,
            Some((node, right)) => PolyKey(base + 2 * self.node[node.index()] + u32::from(right)),
        }
    }
}

/// Numbers every record of `h` page-major as `part` places them.
pub(crate) fn renumber(h: &Hierarchy<'_>, part: &Partition) -> Result<Renumbered, PagedError> {
    let pages = members(h, part);
    let largest = pages
        .iter()
        .flat_map(|m| {
            [
                m.nodes.len(),
                m.polygons.len(),
                m.positions.len(),
                m.keys.len(),
            ]
        })
        .max()
        .unwrap_or(1)
        .max(1);
    let bits = (usize::BITS - (largest - 1).leading_zeros()).max(1);
    let ids = SegmentedId::new(bits).ok_or(PagedError::TooLarge)?;
    // Polygon keys are `base + 2 · node + side`: every node id must keep them in 32 bits.
    let top = (u64::from(part.pages) << bits) - 1;
    if 2 * top + 1 + h.base_polygon_count() as u64 >= u64::from(u32::MAX) {
        return Err(PagedError::TooLarge);
    }
    let mut r = Renumbered {
        ids,
        node: vec![NONE; h.nodes().len()],
        polygon: vec![NONE; h.polygons().len()],
        position: vec![NONE; h.positions().len()],
        key_vertex: vec![NONE; h.parts().vertex_table.len()],
        pages: Vec::new(),
    };
    for (page, m) in (0u32..).zip(&pages) {
        let id = |i: usize| ids.id(page, i as u32).ok_or(PagedError::TooLarge);
        for (i, &v) in m.nodes.iter().enumerate() {
            r.node[v as usize] = id(i)?;
        }
        for (i, &p) in m.polygons.iter().enumerate() {
            r.polygon[p as usize] = id(i)?;
        }
        for (i, &q) in m.positions.iter().enumerate() {
            r.position[q as usize] = id(i)?;
        }
        for (i, &k) in m.keys.iter().enumerate() {
            r.key_vertex[k as usize] = id(i)?;
        }
    }
    r.pages = pages;
    Ok(r)
}

/// Each page's records in page order.
fn members(h: &Hierarchy<'_>, part: &Partition) -> Vec<Members> {
    let mut pages: Vec<Members> = (0..part.pages).map(|_| Members::default()).collect();
    let splits = h.splits();
    for v in 0..h.nodes().len() {
        let m = &mut pages[part.home[v] as usize];
        m.nodes.push(v as u32);
        if v < splits.len() {
            m.splits += 1;
        }
    }
    pages[0].polygons.extend(0..h.base_polygon_count() as u32);
    for (v, s) in splits.iter().enumerate() {
        let m = &mut pages[part.home[v] as usize];
        m.polygons.push(s.f_l.0);
        if let Some(r) = s.f_r.get() {
            m.polygons.push(r.0);
        }
    }
    let offsets = h.parts().vertex_table_offsets;
    for (q, &v) in part.introducer.iter().enumerate() {
        let m = &mut pages[part.home[v as usize] as usize];
        m.positions.push(q as u32);
        m.keys.extend(offsets[q]..offsets[q + 1]);
    }
    // Positions and their entries in node order within each page, as a pass reads them.
    for m in &mut pages {
        let mut by_node: Vec<(u32, u32)> = m
            .positions
            .iter()
            .map(|&q| (part.introducer[q as usize], q))
            .collect();
        by_node.sort_unstable();
        m.positions = by_node.into_iter().map(|(_, q)| q).collect();
        m.keys = m
            .positions
            .iter()
            .flat_map(|&q| offsets[q as usize]..offsets[q as usize + 1])
            .collect();
    }
    pages
}
