//! Writing the `.clod` file of a blocked build from its spilled collapses
//! ([`super::Spilled`]) and its welded store ([`WeldedStore`]), both read back from disk a
//! chunk at a time, so that neither the hierarchy, nor the welded mesh, nor any array is
//! ever whole in memory.
//!
//! Splits are numbered in reverse creation order: split `s` undoes the collapse created
//! `s`-th from the last, so a node's parent, created after it, comes before it, which is all
//! the format asks of the order (parents precede children, splittable nodes first; leaves
//! follow in position order). It needs no numbering table, and each array is one pass over
//! the records, last first. Depth-first order ([`crate::arrays`]) serves a refinement pass's
//! locality only; within a blocked build's levels the reverse order keeps each block's
//! collapses together.

use std::path::Path;

use caveclod_core::format::{ExtraSection, Node, Polygon, Split, SplitBounds};
use caveclod_core::{NodeId, PositionId, SurfaceGroupId, SurfaceId};

use super::spill::{Record, Spilled};
use super::store_arrays::{self, Gathered};
use crate::arrays::{self, Counts, MeshCounts, PolygonOrder};
use crate::baked::section_specs;
use crate::base::memory::release_freed;
use crate::clod_file::{
    write_sections, BakeWriteError, Check, Inspect, Sections, CHUNK_RECORDS as CHUNK,
};
use crate::mesh::Surface;
use crate::streamed::Appearance;
use crate::weld::store::{StoredTri, WeldedStore};

const NONE: u32 = u32::MAX;

/// New node ids in reverse creation order: the splits' nodes last-created first, then the
/// leaves.
#[derive(Clone, Copy)]
pub(crate) struct ReverseIds {
    positions: u32,
    splits: u32,
}

impl ReverseIds {
    /// The new id of node `old` (leaves `0..positions`, then collapse `c`'s node).
    pub(crate) fn of(self, old: u32) -> u32 {
        if old < self.positions {
            self.splits + old
        } else {
            self.splits - 1 - (old - self.positions)
        }
    }

    /// The split id of collapse `c`.
    fn split(self, c: usize) -> NodeId {
        NodeId(self.splits - 1 - c as u32)
    }
}

/// Writes the `.clod` file of the welded store `store` and the spilled hierarchy `h` at
/// `path`, as [`crate::streamed::write`] writes an in-memory one, with splits in reverse
/// creation order; the welded data is read from the store a chunk at a time. The written
/// file's validated hierarchy is handed to `inspect` before the rename. Returns the file's
/// length.
pub fn write(
    store: WeldedStore,
    h: Spilled,
    surfaces: &[Surface],
    texture_dir: &Path,
    path: &Path,
    extra: &[ExtraSection<'_>],
    inspect: Inspect<'_>,
) -> Result<u64, BakeWriteError> {
    let colours = store_arrays::colours(&store)?;
    let appearance = Appearance::with_colours(colours, surfaces, texture_dir, path)?;
    let sections = appearance.then(extra);

    let ids = ReverseIds {
        positions: h.positions as u32,
        splits: h.len() as u32,
    };
    let polys = number_polygons(&h, ids)?;
    let mut roots: Vec<NodeId> = (0..h.parent.len() as u32)
        .filter(|&o| h.parent[o as usize] == NONE)
        .map(|o| NodeId(ids.of(o)))
        .collect();
    roots.sort_unstable();
    let counts = Counts {
        nodes: h.positions + h.len(),
        splits: h.len(),
        roots: roots.len(),
        max_depth: max_depth(&h, ids),
    };
    let info = store.info();
    let group_ids = info.group_ids.clone();
    let mesh = MeshCounts {
        bounds: store.bounds(),
        positions: store.positions(),
        vertices: store.vertices(),
        surfaces: info.surface_count,
        group_ids: info.group_id_count,
    };
    let meta = arrays::meta_from(&mesh, &counts, &polys);
    let specs = section_specs(&meta, &sections);
    write_sections(path, &specs, Check::ReadBack(inspect), move |out| {
        out.put(std::slice::from_ref(&meta))?;
        store_arrays::put_positions(out, &store)?;
        put_records(out, &h, |r| node(ids, r.record.position, r.parent))?;
        out.put_iter((0..ids.positions).map(|x| node(ids, x, h.parent[x as usize])))?;
        put_records(out, &h, |r| -> Split {
            polys.split(&r.record.collapse(), |x| ids.of(x))
        })?;
        h.for_each_chunk(true, spill_io, |_, chunk| {
            let at = store_arrays::positions(&store, chunk.iter().map(|r| r.position))?;
            let made: Vec<SplitBounds> = chunk
                .iter()
                .map(|r| {
                    let (position, cone) = (at.get(r.position), (r.axis, r.angle));
                    arrays::split_bounds(position, r.radius, cone, r.error)
                })
                .collect();
            out.put(&made)
        })?;
        let polygon = |tris: &Gathered<StoredTri>, f: u32, rot: u8| {
            let t = tris.get(f);
            let group = SurfaceGroupId(group_ids[t.group as usize]);
            polys.polygon_of(f, t.p, SurfaceId(t.surface), group, rot, |x| ids.of(x))
        };
        for base in polys.base_triangles().chunks(CHUNK) {
            let tris = store_arrays::triangles(&store, base.iter().copied())?;
            let made: Vec<Polygon> = base.iter().map(|&f| polygon(&tris, f, 0)).collect();
            out.put(&made)?;
        }
        h.for_each_chunk(true, spill_io, |_, chunk| {
            let named = chunk.iter().flat_map(|r| [r.fl, r.fr]);
            let tris = store_arrays::triangles(&store, named)?;
            let mut made = Vec::with_capacity(2 * chunk.len());
            for r in chunk {
                made.push(polygon(&tris, r.fl, r.rot[0]));
                if r.fr != NONE {
                    made.push(polygon(&tris, r.fr, r.rot[1]));
                }
            }
            out.put(&made)
        })?;
        out.put(&roots)?;
        let base_corners = |f: u32| h.corners[f as usize].map(|x| h.current[x as usize]);
        out.put(&polys.base_faces_by(base_corners, |x| ids.of(x)))?;
        drop((h, polys));
        store_arrays::put_vertex_tables(out, &store)?;
        drop(store);
        release_freed();
        for e in &sections {
            out.put(e.bytes)?;
        }
        Ok(())
    })
}

/// A record as a split's arrays read it: with the parent of the node it creates.
struct WithParent<'r> {
    record: &'r Record,
    parent: u32,
}

/// Writes one record per split, `make` from each record (last-created first).
fn put_records<T: bytemuck::Pod>(
    out: &mut Sections<'_>,
    h: &Spilled,
    mut make: impl FnMut(WithParent<'_>) -> T,
) -> Result<(), BakeWriteError> {
    h.for_each_chunk(true, spill_io, |last, chunk| {
        let made: Vec<T> = chunk
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let c = last - i;
                make(WithParent {
                    record: r,
                    parent: h.parent[h.positions + c],
                })
            })
            .collect();
        out.put(&made)
    })
}

/// A failed read of the spill file; [`write_sections`] names the target with it.
fn spill_io(source: std::io::Error) -> BakeWriteError {
    store_arrays::io(source)
}

/// The node record of a node at `position` under `parent` (old ids).
fn node(ids: ReverseIds, position: u32, parent: u32) -> Node {
    Node {
        parent: if parent == NONE {
            NodeId::NONE
        } else {
            NodeId(ids.of(parent))
        },
        position: PositionId(position),
    }
}

/// The polygons' numbering: the base triangles, then each split's, last-created first.
fn number_polygons(h: &Spilled, ids: ReverseIds) -> Result<PolygonOrder, BakeWriteError> {
    let mut polys = PolygonOrder::base(&h.alive);
    h.for_each_chunk(true, spill_io, |last, chunk| {
        for (i, r) in chunk.iter().enumerate() {
            polys.add_split(ids.split(last - i), &r.collapse());
        }
        Ok(())
    })?;
    Ok(polys)
}

/// The longest root-to-leaf path in edges. A parent is created after its children, so its
/// depth is known when the collapses are visited last first.
fn max_depth(h: &Spilled, ids: ReverseIds) -> u32 {
    let np = h.positions;
    let mut depth = vec![0u32; h.len()];
    let below = |depth: &[u32], p: u32| {
        if p == NONE {
            0
        } else {
            depth[ids.of(p) as usize] + 1
        }
    };
    for c in (0..h.len()).rev() {
        let s = ids.split(c).index();
        depth[s] = below(&depth, h.parent[np + c]);
    }
    (0..np)
        .map(|leaf| below(&depth, h.parent[leaf]))
        .max()
        .unwrap_or(0)
}
