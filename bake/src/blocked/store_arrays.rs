//! The `.clod` arrays a blocked bake's writer makes from the welded store
//! ([`WeldedStore`]), a chunk at a time: the positions, the polygons of the triangles a
//! chunk of splits names, each split's position, and the vertex table, in store order.

use caveclod_core::format::{Position, Vertex, VertexKey};
use caveclod_core::SurfaceGroupId;

use crate::base::colour::encode_colour;
use crate::clod_file::{BakeWriteError, Sections, CHUNK_RECORDS as CHUNK};
use crate::weld::store::{StoredTri, WeldedStore};
use crate::weld::Attributes;

/// A failed read of a temporary file; [`crate::clod_file::write_sections`] names the
/// target with it.
pub(super) fn io(source: std::io::Error) -> BakeWriteError {
    BakeWriteError::Io {
        path: std::path::PathBuf::new(),
        source,
    }
}

/// Records of some ids read from the store, looked up by id.
pub(super) struct Gathered<T> {
    ids: Vec<u32>,
    values: Vec<T>,
}

impl<T: Copy> Gathered<T> {
    /// The records of `ids` (any order, repeats allowed, `NONE` skipped), read by `read`
    /// from their ascending distinct ids.
    fn new(
        ids: impl Iterator<Item = u32>,
        read: impl FnOnce(&[u32]) -> std::io::Result<Vec<T>>,
    ) -> Result<Self, BakeWriteError> {
        let mut ids: Vec<u32> = ids.filter(|&x| x != u32::MAX).collect();
        ids.sort_unstable();
        ids.dedup();
        let values = read(&ids).map_err(io)?;
        Ok(Self { ids, values })
    }

    /// The record of `id` (one of those read).
    pub(super) fn get(&self, id: u32) -> T {
        self.values[self.ids.binary_search(&id).unwrap_or(0)]
    }
}

/// The coordinates of positions `ids`.
pub(super) fn positions(
    store: &WeldedStore,
    ids: impl Iterator<Item = u32>,
) -> Result<Gathered<[f32; 3]>, BakeWriteError> {
    Gathered::new(ids, |ids| store.gather_positions(ids))
}

/// The triangles `ids`.
pub(super) fn triangles(
    store: &WeldedStore,
    ids: impl Iterator<Item = u32>,
) -> Result<Gathered<StoredTri>, BakeWriteError> {
    Gathered::new(ids, |ids| store.gather_triangles(ids))
}

/// The positions with their classes, in store order.
pub(super) fn put_positions(
    out: &mut Sections<'_>,
    store: &WeldedStore,
) -> Result<(), BakeWriteError> {
    let np = store.positions() as u32;
    for start in (0..np).step_by(CHUNK) {
        let range = start..np.min(start + CHUNK as u32);
        let xyz = store.read_positions(range.clone()).map_err(io)?;
        let classes = store.read_classes(range).map_err(io)?;
        let records: Vec<Position> = xyz
            .iter()
            .zip(&classes)
            .map(|(&xyz, &c)| Position {
                xyz,
                class: c as u32,
            })
            .collect();
        out.put(&records)?;
    }
    Ok(())
}

/// One vertex of the table: its position's coordinates, surface-group id and attributes.
struct TableVertex {
    xyz: [f32; 3],
    group: u16,
    attributes: Attributes,
}

/// Calls `f` with the vertex table's vertices in file order (per position, by surface-group
/// id), a chunk of positions at a time.
fn for_each_vertex(
    store: &WeldedStore,
    mut f: impl FnMut(&[TableVertex]) -> Result<(), BakeWriteError>,
) -> Result<(), BakeWriteError> {
    let np = store.positions() as u32;
    let group_ids = &store.info().group_ids;
    let mut made = Vec::new();
    for start in (0..np).step_by(CHUNK) {
        let range = start..np.min(start + CHUNK as u32);
        let xyz = store.read_positions(range.clone()).map_err(io)?;
        let lists = store.read_vertex_lists(range).map_err(io)?;
        let sets = Gathered::new(lists.entries.iter().map(|&[_, a]| a), |ids| {
            store.gather_attributes(ids)
        })?;
        made.clear();
        let mut keys = Vec::new();
        for (i, &xyz) in xyz.iter().enumerate() {
            keys.clear();
            keys.extend(lists.of(i).iter().map(|&[g, a]| (group_ids[g as usize], a)));
            keys.sort_unstable();
            made.extend(keys.iter().map(|&(group, a)| TableVertex {
                xyz,
                group,
                attributes: sets.get(a),
            }));
        }
        f(&made)?;
    }
    Ok(())
}

/// The vertices' colours in vertex-table order; empty when the mesh has none.
pub(super) fn colours(store: &WeldedStore) -> Result<Vec<[u8; 4]>, BakeWriteError> {
    let mut colours = Vec::new();
    if store.info().has_colors {
        colours.reserve(store.vertices());
        for_each_vertex(store, |vs| {
            colours.extend(vs.iter().map(|v| encode_colour(v.attributes.color)));
            Ok(())
        })?;
    }
    Ok(colours)
}

/// The vertex table's three arrays: where each position's entries start (the store's
/// list starts), the keys, the vertices.
pub(super) fn put_vertex_tables(
    out: &mut Sections<'_>,
    store: &WeldedStore,
) -> Result<(), BakeWriteError> {
    let starts = store.positions() as u32 + 1;
    for start in (0..starts).step_by(CHUNK) {
        let range = start..starts.min(start + CHUNK as u32);
        out.put(&store.read_vertex_starts(range).map_err(io)?)?;
    }
    let mut next = 0u32;
    for_each_vertex(store, |vs| {
        let keys: Vec<VertexKey> = vs
            .iter()
            .map(|v| {
                next += 1;
                VertexKey {
                    group: SurfaceGroupId(v.group),
                    reserved: 0,
                    vertex: next - 1,
                }
            })
            .collect();
        out.put(&keys)
    })?;
    for_each_vertex(store, |vs| {
        let vertices: Vec<Vertex> = vs
            .iter()
            .map(|v| Vertex {
                position: v.xyz,
                normal: v.attributes.normal,
                uv: v.attributes.uv,
            })
            .collect();
        out.put(&vertices)
    })
}
