//! The vertex table, the vertex buffer and the vertices' colours: per position, its vertices
//! sorted by surface-group id, in the order [`VertexOrder`] gives once for all three.

use caveclod_core::format::{Vertex, VertexKey};
use caveclod_core::SurfaceGroupId;
use rayon::prelude::*;

use super::indexed::collect_indexed;
use crate::base::colour::encode_colour;
use crate::weld::Welded;

/// The vertex table in file order: per position, its vertices sorted by surface-group id,
/// each as (position, group id, attribute index); made on all cores, so that the vertex
/// table, the vertices and their colours are made by index like the other arrays.
pub(crate) struct VertexOrder(Vec<(u32, u16, u32)>);

impl VertexOrder {
    pub(crate) fn new(w: &Welded) -> Self {
        let ids = &w.group_ids;
        let mut order: Vec<(u32, u16, u32)> = (0..w.vertices.len())
            .into_par_iter()
            .flat_map_iter(|p| {
                let vs = &w.vertices[p];
                vs.iter().map(move |&(g, a)| (p as u32, ids[g as usize], a))
            })
            .collect();
        order
            .par_chunk_by_mut(|x, y| x.0 == y.0)
            .for_each(|position| position.sort_unstable());
        Self(order)
    }

    /// Vertices (and vertex-table entries).
    pub(crate) fn len(&self) -> usize {
        self.0.len()
    }

    /// Vertex-table entry `i`: its group and the vertex it keys, which the vertex buffer
    /// holds at the same place.
    pub(crate) fn key(&self, i: usize) -> VertexKey {
        VertexKey {
            group: SurfaceGroupId(self.0[i].1),
            reserved: 0,
            vertex: i as u32,
        }
    }

    /// Vertex `i` of the vertex buffer.
    pub(crate) fn vertex(&self, w: &Welded, i: usize) -> Vertex {
        let (p, _, a) = self.0[i];
        let attrs = &w.attributes[a as usize];
        Vertex {
            position: w.positions[p as usize],
            normal: attrs.normal,
            uv: attrs.uv,
        }
    }

    /// Vertex `i`'s colour.
    fn colour(&self, w: &Welded, i: usize) -> [u8; 4] {
        encode_colour(w.attributes[self.0[i].2 as usize].color)
    }

    /// The vertices' colours in vertex-table order, made on all cores; empty when the mesh
    /// has none.
    pub(crate) fn colours(&self, w: &Welded) -> Vec<[u8; 4]> {
        if !w.has_colors {
            return Vec::new();
        }
        collect_indexed(self.len(), |i| self.colour(w, i))
    }
}

/// Vertices (and vertex-table entries) of the welded mesh.
pub(crate) fn vertex_count(w: &Welded) -> usize {
    w.vertices.iter().map(<[_]>::len).sum()
}

/// Where each position's vertex-table entries start, and the end.
pub(crate) fn vertex_table_offset_records(w: &Welded) -> impl Iterator<Item = u32> + '_ {
    let ends = w.vertices.iter().scan(0u32, |at, vs| {
        *at += vs.len() as u32;
        Some(*at)
    });
    std::iter::once(0).chain(ends)
}

/// [`vertex_table_offset_records`] collected.
pub(crate) fn vertex_table_offsets(w: &Welded) -> Vec<u32> {
    vertex_table_offset_records(w).collect()
}

/// The vertex table: per position, its vertices sorted by surface-group id, each a key into
/// the vertex buffer, which holds them in the same order.
pub(crate) fn vertex_table(w: &Welded) -> Vec<VertexKey> {
    let order = VertexOrder::new(w);
    collect_indexed(order.len(), |i| order.key(i))
}

/// The vertex buffer, in vertex-table order.
pub(crate) fn vertices(w: &Welded) -> Vec<Vertex> {
    let order = VertexOrder::new(w);
    collect_indexed(order.len(), |i| order.vertex(w, i))
}

/// The vertices' colours in vertex-table order; empty when the mesh has none.
pub(crate) fn vertex_colours(w: &Welded) -> Vec<[u8; 4]> {
    if !w.has_colors {
        return Vec::new();
    }
    VertexOrder::new(w).colours(w)
}
