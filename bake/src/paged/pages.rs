//! One page's bytes: its records translated to page-major ids and laid out as
//! [`PageLayout`] says, with its page-table entry.

use bytemuck::Pod;
use caveclod_core::format::paged::{PageEntry, PageLayout, PAGE_HAS_COLOURS};
use caveclod_core::format::{checksum64, Creator, Node, Polygon, Split, VertexKey};
use caveclod_core::{Hierarchy, NodeId, PolyId, PositionId};

use super::error::PagedError;
use super::renumber::{Members, Renumbered};

const NONE: u32 = u32::MAX;

/// A page's bytes (64-byte words, so records cast in place) and its entry, but for its
/// offset and parents.
pub(crate) struct BuiltPage {
    pub words: Vec<u64>,
    pub entry: PageEntry,
}

impl BuiltPage {
    pub(crate) fn bytes(&self) -> &[u8] {
        &bytemuck::cast_slice(&self.words)[..self.entry.size as usize]
    }
}

/// The records of page `m` of `h`, renumbered by `r`.
pub(crate) fn build_page(
    h: &Hierarchy<'_>,
    r: &Renumbered,
    m: &Members,
) -> Result<BuiltPage, PagedError> {
    let colours = h.vertex_colours();
    let counts = [
        m.nodes.len(),
        m.splits as usize,
        m.polygons.len(),
        m.positions.len(),
        m.keys.len(),
        m.keys.len(),
    ]
    .map(|c| c as u32);
    let layout = PageLayout::new(counts, colours.is_some()).ok_or(PagedError::TooLarge)?;
    let mut words = vec![0u64; layout.len / 8];
    let bytes: &mut [u8] = bytemuck::cast_slice_mut(&mut words);
    let base = h.base_polygon_count() as u32;
    let node = |v: NodeId| NodeId(v.get().map_or(NONE, |v| r.node[v.index()]));
    let poly = |p: PolyId| PolyId(p.get().map_or(NONE, |p| r.polygon[p.index()]));
    fill(
        bytes,
        &layout.nodes,
        m.nodes.iter().map(|&v| {
            let n = h.nodes()[v as usize];
            Node {
                parent: node(n.parent),
                position: PositionId(r.position[n.position.index()]),
            }
        }),
    );
    let splits = &m.nodes[..m.splits as usize];
    fill(
        bytes,
        &layout.splits,
        splits.iter().map(|&v| {
            let s = h.splits()[v as usize];
            Split {
                stationary: node(s.stationary),
                floating: node(s.floating),
                f_l: poly(s.f_l),
                f_r: poly(s.f_r),
                neighbours: s.neighbours.map(|k| r.key(base, k)),
            }
        }),
    );
    fill(
        bytes,
        &layout.bounds,
        splits.iter().map(|&v| h.bounds()[v as usize]),
    );
    fill(
        bytes,
        &layout.polygons,
        m.polygons.iter().map(|&p| {
            let p = h.polygons()[p as usize];
            Polygon {
                nodes: p.nodes.map(node),
                creator: p.creator.node().map_or(Creator::BASE, |c| {
                    Creator::new(node(c), p.creator.is_right())
                }),
                ..p
            }
        }),
    );
    fill(
        bytes,
        &layout.positions,
        m.positions.iter().map(|&q| h.positions()[q as usize]),
    );
    let offsets = h.parts().vertex_table_offsets;
    let mut at = 0u32;
    let local = m.positions.iter().map(|&q| {
        let start = at;
        at += offsets[q as usize + 1] - offsets[q as usize];
        start
    });
    fill(
        bytes,
        &layout.vertex_table_offsets,
        local.chain([m.keys.len() as u32]),
    );
    let table = h.parts().vertex_table;
    fill(
        bytes,
        &layout.vertex_table,
        m.keys.iter().map(|&k| VertexKey {
            vertex: r.key_vertex[k as usize],
            ..table[k as usize]
        }),
    );
    fill(
        bytes,
        &layout.vertices,
        m.keys
            .iter()
            .map(|&k| h.vertices()[table[k as usize].vertex as usize]),
    );
    if let Some(c) = colours {
        fill(
            bytes,
            &layout.colours,
            m.keys.iter().map(|&k| c[table[k as usize].vertex as usize]),
        );
    }
    let entry = entry(h, m, counts, colours.is_some(), &bytes[..layout.len]);
    Ok(BuiltPage { words, entry })
}

/// Writes `records` over `range` of `bytes`.
fn fill<T: Pod>(
    bytes: &mut [u8],
    range: &core::ops::Range<usize>,
    records: impl Iterator<Item = T>,
) {
    let out: &mut [T] = bytemuck::cast_slice_mut(&mut bytes[range.clone()]);
    for (o, r) in out.iter_mut().zip(records) {
        *o = r;
    }
}

/// The page's entry: size, checksum, counts, and what loading it is worth.
fn entry(
    h: &Hierarchy<'_>,
    m: &Members,
    counts: [u32; 6],
    colours: bool,
    bytes: &[u8],
) -> PageEntry {
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    let mut max_error = 0.0f32;
    for &v in &m.nodes[..m.splits as usize] {
        let b = h.bounds()[v as usize];
        max_error = max_error.max(b.uni_error);
        grow(&mut lo, &mut hi, b.point.map(|x| x - b.radius));
        grow(&mut lo, &mut hi, b.point.map(|x| x + b.radius));
    }
    for &q in &m.positions {
        let p = h.positions()[q as usize].xyz;
        grow(&mut lo, &mut hi, p);
    }
    if lo[0] > hi[0] {
        (lo, hi) = ([0.0; 3], [0.0; 3]);
    }
    PageEntry {
        offset: 0,
        checksum: checksum64(bytes),
        size: bytes.len() as u32,
        parents_start: 0,
        parent_count: 0,
        max_error,
        bounds_min: lo,
        bounds_max: hi,
        counts,
        flags: if colours { PAGE_HAS_COLOURS } else { 0 },
        reserved: [0; 3],
    }
}

/// Grows the box `lo..hi` to hold `p`.
fn grow(lo: &mut [f32; 3], hi: &mut [f32; 3], p: [f32; 3]) {
    for k in 0..3 {
        lo[k] = lo[k].min(p[k]);
        hi[k] = hi[k].max(p[k]);
    }
}
