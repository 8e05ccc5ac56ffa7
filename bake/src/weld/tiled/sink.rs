//! Where a tiled weld's result goes: a [`WeldSink`] takes it piece by piece (the welded store
//! does, `store_sink`), or a [`WeldedBuilder`] makes a [`Welded`] of it in memory.

use std::io;

use caveclod_core::format::PositionClass;

use crate::weld::store::StoredTri;
use crate::weld::vertex_lists::VertexLists;
use crate::weld::welded::{Attributes, WeldInfo, Welded, WeldedTri};

/// Receives a welded mesh piece by piece, as the welded store takes it.
pub trait WeldSink {
    /// The next position (ids in push order), its class, and its vertices: `[surface group,
    /// attribute set]` of each group with a vertex there, by group, each group once.
    fn push_position(
        &mut self,
        xyz: [f32; 3],
        class: PositionClass,
        vertices: &[[u32; 2]],
    ) -> io::Result<()>;
    /// The next attribute sets (ids in push order).
    fn push_attributes(&mut self, attributes: &[Attributes]) -> io::Result<()>;
    /// Triangles, in any order, each with its group and surface.
    fn push_triangles(&mut self, triangles: &[StoredTri]) -> io::Result<()>;
}

/// A [`WeldSink`] into a [`Welded`] in memory.
#[derive(Default)]
pub struct WeldedBuilder {
    w: Welded,
    lists: Vec<Vec<(u32, u32)>>,
}

impl WeldSink for WeldedBuilder {
    fn push_position(
        &mut self,
        xyz: [f32; 3],
        class: PositionClass,
        vertices: &[[u32; 2]],
    ) -> io::Result<()> {
        self.w.positions.push(xyz);
        self.w.classes.push(class);
        self.lists
            .push(vertices.iter().map(|&[g, a]| (g, a)).collect());
        Ok(())
    }

    fn push_attributes(&mut self, attributes: &[Attributes]) -> io::Result<()> {
        self.w.attributes.extend_from_slice(attributes);
        Ok(())
    }

    fn push_triangles(&mut self, triangles: &[StoredTri]) -> io::Result<()> {
        let w = &mut self.w;
        for t in triangles {
            let g = t.group as usize;
            if g >= w.group_surfaces.len() {
                w.group_surfaces.resize(g + 1, 0);
            }
            w.group_surfaces[g] = t.surface;
            w.triangles.push(WeldedTri {
                p: t.p,
                group: t.group,
            });
        }
        Ok(())
    }
}

impl WeldedBuilder {
    /// The welded mesh, with `summary`.
    pub fn finish(self, summary: WeldInfo) -> Welded {
        let mut w = self.w;
        w.vertices = self
            .lists
            .iter()
            .map(|l| l.iter().copied())
            .collect::<VertexLists>();
        w.group_count = summary.group_count;
        w.group_ids = summary.group_ids;
        w.group_surfaces.resize(summary.group_count as usize, 0);
        w.group_id_count = summary.group_id_count;
        w.surface_count = summary.surface_count;
        w.has_colors = summary.has_colors;
        w.repairs = summary.repairs;
        w
    }
}
