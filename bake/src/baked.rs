//! Turning a welded mesh and its collapse hierarchy into the `.clod` arrays, and writing them
//! to disk safely.
//!
//! Node ids: splittable nodes first, in depth-first preorder (stationary child first, roots
//! in position order), so a subtree is one id range and a stationary child sits next to its
//! parent — the records a refinement pass reads together lie together. Leaves follow in
//! position order. Polygons: the base mesh first, then each split's `f_l` and `f_r` in split
//! order.
//!
//! Materials and vertex colours, when the mesh has them, are written beside the hierarchy
//! ([`crate::materials`]).

use std::io::Write;
use std::path::{Path, PathBuf};

use caveclod_core::format::materials::vertex_colour_section;
use caveclod_core::format::{
    serialized_len, write_into, BaseFace, Creator, ExtraSection, HierarchyParts, Node, Polygon,
    Position, Split, SplitBounds, Vertex, VertexKey, WriteError,
};
use caveclod_core::{Hierarchy, NodeId, PolyId, PolyKey, PositionId, SurfaceGroupId, SurfaceId};

use crate::hierarchy::Hierarchy as Collapses;
use crate::materials::{
    encode_colour, has_materials, MaterialSections, TextureError, TexturePaths,
};
use crate::mesh::Surface;
use crate::weld::Welded;

const NONE: u32 = u32::MAX;

/// The arrays of a baked hierarchy.
#[derive(Clone, Debug, Default)]
pub struct Baked {
    /// Node positions.
    pub positions: Vec<Position>,
    /// Nodes.
    pub nodes: Vec<Node>,
    /// Split records.
    pub splits: Vec<Split>,
    /// Refinement bounds.
    pub bounds: Vec<SplitBounds>,
    /// Polygons, base first.
    pub polygons: Vec<Polygon>,
    /// Roots, ascending.
    pub roots: Vec<NodeId>,
    /// Base mesh.
    pub base: Vec<BaseFace>,
    /// Vertex-table offsets.
    pub vertex_table_offsets: Vec<u32>,
    /// Vertex-table entries.
    pub vertex_table: Vec<VertexKey>,
    /// Vertex buffer.
    pub vertices: Vec<Vertex>,
    /// Surfaces.
    pub surface_count: u32,
    /// Surface-group ids.
    pub surface_group_count: u32,
    /// One colour per vertex (RGBA8, sRGB colour, linear alpha); empty when the mesh had
    /// none, and then the file has no colour section.
    pub vertex_colours: Vec<[u8; 4]>,
    /// One material per surface; empty when no surface carries one
    /// ([`crate::materials::has_materials`]), and then the file has no material sections.
    pub materials: Vec<Surface>,
    /// The directory the texture files of [`materials`](Self::materials) are relative to:
    /// the source file's (empty: the current directory).
    pub texture_dir: PathBuf,
}

/// Why writing failed.
#[derive(Debug, thiserror::Error)]
pub enum BakeWriteError {
    /// The arrays do not form a valid hierarchy (a baker bug; nothing was written).
    #[error("internal error, nothing written: {0}")]
    Invalid(#[from] WriteError),
    /// A texture cannot be referred to from the output file (no relative path to it, or
    /// one the format refuses).
    #[error("{path}: {source}")]
    Texture {
        /// The file being written.
        path: PathBuf,
        /// Why.
        source: TextureError,
    },
    /// The file system refused.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}

impl Baked {
    /// Assembles the arrays: nodes and polygons renumbered into their file order, then each
    /// array built from the collapses in that order.
    pub fn new(w: &Welded, h: &Collapses) -> Self {
        let ids = NodeIds::number(w.positions.len(), h);
        let polys = PolygonOrder::number(w.triangles.len(), h, &ids);
        let (splits, bounds) = split_records(w, h, &ids, &polys);
        let (vertex_table_offsets, vertex_table, vertices, vertex_colours) = vertex_table(w);
        Self {
            positions: positions(w),
            nodes: ids.nodes(h),
            splits,
            bounds,
            polygons: polys.polygons(w, &ids),
            roots: ids.roots(h),
            base: polys.base_faces(h, &ids),
            vertex_table_offsets,
            vertex_table,
            vertices,
            surface_count: w.surface_count,
            surface_group_count: w.group_id_count,
            vertex_colours,
            materials: Vec::new(),
            texture_dir: PathBuf::new(),
        }
    }

    /// Gives the surfaces their materials, when any carries one
    /// ([`crate::materials::has_materials`]); texture files relative to `texture_dir`.
    pub fn with_materials(mut self, surfaces: &[Surface], texture_dir: &Path) -> Self {
        self.materials = if has_materials(surfaces) {
            surfaces.to_vec()
        } else {
            Vec::new()
        };
        self.texture_dir = texture_dir.to_path_buf();
        self
    }

    /// Borrowed arrays.
    pub fn parts(&self) -> HierarchyParts<'_> {
        HierarchyParts {
            positions: &self.positions,
            nodes: &self.nodes,
            splits: &self.splits,
            bounds: &self.bounds,
            polygons: &self.polygons,
            roots: &self.roots,
            base: &self.base,
            vertex_table_offsets: &self.vertex_table_offsets,
            vertex_table: &self.vertex_table,
            vertices: &self.vertices,
            surface_count: self.surface_count,
            surface_group_count: self.surface_group_count,
        }
    }

    /// The validated hierarchy over these arrays.
    pub fn hierarchy(&self) -> Result<Hierarchy<'_>, caveclod_core::FormatError> {
        Hierarchy::from_parts(self.parts())
    }

    /// The `.clod` bytes with the materials and vertex colours, when there are any, and
    /// `extra` sections (all validated before writing). Texture paths are kept as the
    /// source gives them, relative to [`texture_dir`](Self::texture_dir): right for a file
    /// written into that directory ([`to_bytes_for`](Self::to_bytes_for) for any other).
    pub fn to_bytes(&self, extra: &[ExtraSection<'_>]) -> Result<Vec<u8>, BakeWriteError> {
        self.bytes_with(&|p| Ok(p.to_owned()), Path::new(""), extra)
    }

    /// [`to_bytes`](Self::to_bytes) for a file to be written at `path`: texture paths are
    /// rewritten relative to its directory ([`TexturePaths`]).
    pub fn to_bytes_for(
        &self,
        path: &Path,
        extra: &[ExtraSection<'_>],
    ) -> Result<Vec<u8>, BakeWriteError> {
        let out_dir = path.parent().unwrap_or(Path::new(""));
        let paths = TexturePaths::new(&self.texture_dir, out_dir);
        self.bytes_with(&|p| paths.rewrite(p), path, extra)
    }

    fn bytes_with(
        &self,
        texture_path: &dyn Fn(&str) -> Result<String, String>,
        path: &Path,
        extra: &[ExtraSection<'_>],
    ) -> Result<Vec<u8>, BakeWriteError> {
        let materials = if self.materials.is_empty() {
            None
        } else {
            let m = MaterialSections::new(&self.materials, texture_path).map_err(|source| {
                BakeWriteError::Texture {
                    path: path.to_path_buf(),
                    source,
                }
            })?;
            Some(m)
        };
        let mut sections: Vec<ExtraSection<'_>> = Vec::with_capacity(extra.len() + 3);
        if let Some(m) = &materials {
            sections.extend(m.parts().sections());
        }
        if !self.vertex_colours.is_empty() {
            sections.push(vertex_colour_section(&self.vertex_colours));
        }
        sections.extend_from_slice(extra);
        let parts = self.parts();
        let mut out = vec![0u8; serialized_len(&parts, &sections)];
        write_into(&parts, &sections, &mut out)?;
        Ok(out)
    }

    /// Writes the file through a temporary file in the same directory and a rename, so a
    /// reader never sees a partial file and an existing file is replaced only by a complete
    /// one. Texture paths are stored relative to `path`'s directory.
    pub fn write(&self, path: &Path, extra: &[ExtraSection<'_>]) -> Result<u64, BakeWriteError> {
        let bytes = self.to_bytes_for(path, extra)?;
        write_atomically(path, &bytes)?;
        Ok(bytes.len() as u64)
    }
}

/// Node ids in file order: the collapses' nodes (splittable) in depth-first preorder from
/// the roots in position order, stationary child first; then the leaves (the welded
/// positions) in position order.
struct NodeIds {
    /// Welded positions, the leaves.
    np: usize,
    /// The new id of each collapse's node.
    split_new: Vec<u32>,
    /// Collapses in new-id (split) order.
    by_new: Vec<usize>,
}

impl NodeIds {
    fn number(np: usize, h: &Collapses) -> Self {
        let created = h.collapses.len();
        let mut split_new = vec![NONE; created];
        let mut by_new = Vec::with_capacity(created);
        let mut stack: Vec<u32> = (np as u32..(np + created) as u32)
            .filter(|&o| h.parent[o as usize] == NONE)
            .collect();
        stack.sort_unstable_by_key(|&o| std::cmp::Reverse(h.node_position[o as usize]));
        while let Some(o) = stack.pop() {
            let c = o as usize - np;
            split_new[c] = by_new.len() as u32;
            by_new.push(c);
            for child in [h.collapses[c].u, h.collapses[c].t] {
                if child as usize >= np {
                    stack.push(child);
                }
            }
        }
        NodeIds {
            np,
            split_new,
            by_new,
        }
    }

    /// The new id of old node `old` (positions first, then collapses).
    fn of(&self, old: u32) -> u32 {
        if (old as usize) < self.np {
            (self.split_new.len() + old as usize) as u32
        } else {
            self.split_new[old as usize - self.np]
        }
    }

    fn total(&self) -> usize {
        self.np + self.split_new.len()
    }

    /// Every node with its parent and position, at its new id.
    fn nodes(&self, h: &Collapses) -> Vec<Node> {
        let mut nodes = vec![
            Node {
                parent: NodeId::NONE,
                position: PositionId(0)
            };
            self.total()
        ];
        for old in 0..self.total() as u32 {
            let p = h.parent[old as usize];
            nodes[self.of(old) as usize] = Node {
                parent: if p == NONE {
                    NodeId::NONE
                } else {
                    NodeId(self.of(p))
                },
                position: PositionId(h.node_position[old as usize]),
            };
        }
        nodes
    }

    /// The parentless nodes, ascending.
    fn roots(&self, h: &Collapses) -> Vec<NodeId> {
        let mut roots: Vec<NodeId> = (0..self.total() as u32)
            .filter(|&o| h.parent[o as usize] == NONE)
            .map(|o| NodeId(self.of(o)))
            .collect();
        roots.sort_unstable();
        roots
    }
}

/// Polygon ids in file order: the base (surviving) triangles in triangle order, then each
/// split's `f_l` and `f_r` in split order, each with the corner rotation it is stored with.
struct PolygonOrder {
    /// The new id of each welded triangle.
    poly_new: Vec<u32>,
    /// Triangle and rotation of each new id.
    order: Vec<(u32, u8)>,
    base_count: usize,
    /// The split that creates each triangle (`BASE` for base triangles).
    creator: Vec<Creator>,
}

impl PolygonOrder {
    fn number(nt: usize, h: &Collapses, ids: &NodeIds) -> Self {
        let mut poly_new = vec![NONE; nt];
        let mut order: Vec<(u32, u8)> = Vec::with_capacity(nt);
        for f in 0..nt {
            if h.alive[f] {
                poly_new[f] = order.len() as u32;
                order.push((f as u32, 0));
            }
        }
        let base_count = order.len();
        let mut creator = vec![Creator::BASE; nt];
        for &c in &ids.by_new {
            let col = h.collapses[c];
            let s = NodeId(ids.split_new[c]);
            poly_new[col.fl as usize] = order.len() as u32;
            order.push((col.fl, col.rot_l));
            creator[col.fl as usize] = Creator::new(s, false);
            if col.fr != NONE {
                poly_new[col.fr as usize] = order.len() as u32;
                order.push((col.fr, col.rot_r));
                creator[col.fr as usize] = Creator::new(s, true);
            }
        }
        PolygonOrder {
            poly_new,
            order,
            base_count,
            creator,
        }
    }

    /// The new id of welded triangle `f` (`NONE`: none).
    fn pid(&self, f: u32) -> PolyId {
        if f == NONE {
            PolyId::NONE
        } else {
            PolyId(self.poly_new[f as usize])
        }
    }

    /// The polygons in file order, corners rotated as stored.
    fn polygons(&self, w: &Welded, ids: &NodeIds) -> Vec<Polygon> {
        self.order
            .iter()
            .map(|&(f, rot)| {
                let t = &w.triangles[f as usize];
                let k = rot as usize;
                Polygon {
                    nodes: [t.p[k], t.p[(k + 1) % 3], t.p[(k + 2) % 3]].map(|p| NodeId(ids.of(p))),
                    creator: self.creator[f as usize],
                    surface: SurfaceId(t.surface),
                    group: SurfaceGroupId(w.group_ids[t.group as usize]),
                }
            })
            .collect()
    }

    /// The base mesh with its adjacency, from the final corners.
    fn base_faces(&self, h: &Collapses, ids: &NodeIds) -> Vec<BaseFace> {
        let base = &self.order[..self.base_count];
        let mut directed = std::collections::HashMap::with_capacity(3 * self.base_count);
        for &(f, _) in base {
            let c = h.corners[f as usize];
            for k in 0..3 {
                directed.insert((c[k], c[(k + 1) % 3]), f);
            }
        }
        base.iter()
            .map(|&(f, _)| {
                let c = h.corners[f as usize];
                BaseFace {
                    corners: c.map(|x| NodeId(ids.of(x))),
                    neighbours: [0, 1, 2].map(|k| {
                        let (a, b) = (c[(k + 1) % 3], c[(k + 2) % 3]);
                        directed.get(&(b, a)).map_or(PolyId::NONE, |&g| self.pid(g))
                    }),
                }
            })
            .collect()
    }
}

/// The split record and refinement bounds of every collapse, at its split id. Splits name
/// their neighbours by key (`PolyKey`): base polygons by id, the others by creator and side.
fn split_records(
    w: &Welded,
    h: &Collapses,
    ids: &NodeIds,
    polys: &PolygonOrder,
) -> (Vec<Split>, Vec<SplitBounds>) {
    let created = h.collapses.len();
    let np = ids.np;
    let polygons_creator: Vec<Creator> = polys
        .order
        .iter()
        .map(|&(f, _)| polys.creator[f as usize])
        .collect();
    let base_keys = polys.base_count as u32;
    let key = |p: PolyId| match p.get() {
        None => PolyKey::NONE,
        Some(p) => polygons_creator[p.index()].key(base_keys, p),
    };
    let mut splits = vec![bytemuck::Zeroable::zeroed(); created];
    let mut bounds = vec![bytemuck::Zeroable::zeroed(); created];
    for (c, col) in h.collapses.iter().enumerate() {
        let old = np + c;
        let (axis, angle) = h.cone[old];
        let sin2 = if angle >= std::f32::consts::FRAC_PI_2 {
            1.0
        } else {
            angle.sin() * angle.sin()
        };
        let at = ids.split_new[c] as usize;
        splits[at] = Split {
            stationary: NodeId(ids.of(col.t)),
            floating: NodeId(ids.of(col.u)),
            f_l: polys.pid(col.fl),
            f_r: polys.pid(col.fr),
            neighbours: col.neighbours.map(|f| key(polys.pid(f))),
        };
        bounds[at] = SplitBounds::new(
            w.positions[h.node_position[old] as usize],
            h.radius[old],
            if sin2 >= 1.0 { [0.0; 3] } else { axis },
            sin2,
            h.error[old],
            0.0,
        );
    }
    (splits, bounds)
}

/// The vertex table: per position, its vertices sorted by surface-group id, each a key into
/// the vertex buffer; and the vertices' colours when the mesh has colours.
fn vertex_table(w: &Welded) -> (Vec<u32>, Vec<VertexKey>, Vec<Vertex>, Vec<[u8; 4]>) {
    let mut vertex_table_offsets = vec![0u32];
    let mut vertex_table = Vec::new();
    let mut vertices = Vec::new();
    let mut colours = Vec::new();
    for (p, vs) in w.vertices.iter().enumerate() {
        let mut keys: Vec<(u16, u32)> = vs
            .iter()
            .map(|&(g, a)| (w.group_ids[g as usize], a))
            .collect();
        keys.sort_unstable();
        for (group, a) in keys {
            let attrs = &w.attributes[a as usize];
            vertex_table.push(VertexKey {
                group: SurfaceGroupId(group),
                reserved: 0,
                vertex: vertices.len() as u32,
            });
            vertices.push(Vertex {
                position: w.positions[p],
                normal: attrs.normal,
                uv: attrs.uv,
            });
            if w.has_colors {
                colours.push(encode_colour(attrs.color));
            }
        }
        vertex_table_offsets.push(vertex_table.len() as u32);
    }
    (vertex_table_offsets, vertex_table, vertices, colours)
}

/// Welded positions with their classes.
fn positions(w: &Welded) -> Vec<Position> {
    w.positions
        .iter()
        .zip(&w.classes)
        .map(|(&xyz, &c)| Position {
            xyz,
            class: c as u32,
        })
        .collect()
}

/// Writes `bytes` to `path` via a temporary sibling and a rename; the temporary file is
/// removed on failure.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), BakeWriteError> {
    write_atomically_with(path, |f| f.write_all(bytes)).map_err(|source| BakeWriteError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Creates a temporary sibling of `path`, lets `fill` write it, syncs it and renames it over
/// `path`: a reader never sees a partial file, and the temporary file is removed on failure.
/// For output streamed as it is made (`write_atomically` for bytes already in memory).
pub fn write_atomically_with(
    path: &Path,
    fill: impl FnOnce(&mut std::fs::File) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        fill(&mut f)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}
