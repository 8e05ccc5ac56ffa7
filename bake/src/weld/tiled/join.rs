//! The tiles' welds joined into one: positions and copies numbered over the whole mesh,
//! attribute sets made distinct, the groups joined across borders (union-find), the classes
//! of the watched positions counted from the joined groups, and the colouring; the result
//! handed to a [`WeldSink`] piece by piece. Triangles and vertices wait in spools on disk
//! until their groups are known; in memory stay a byte per position (its class), the
//! distinct attribute sets, and what the borders need.

use std::io;

use bytemuck::{Pod, Zeroable};
use caveclod_core::format::PositionClass;
use hashbrown::hash_table::{Entry, HashTable};

use super::error::TiledWeldError;
use super::sink::WeldSink;
use super::spool::Spool;
use super::tile::{Across, TileWeld, COPY};
use super::tiles::TiledMesh;
use crate::base::fxhash::{hash_of, map_with_capacity, FxHashMap};
use crate::weld::groups::{colour_groups, Groups, VertexOf};
use crate::weld::store::StoredTri;
use crate::weld::vertex_lists::VertexLists;
use crate::weld::welded::{Attributes, Repairs, WeldError, WeldInfo};

/// A triangle waiting for its group.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct SpooledTri {
    p: [u32; 3],
    node: u32,
    surface: u32,
}

/// Triangles handed to the sink at a time.
const PUSH: usize = 1 << 14;

/// What lies across a watched edge, over the whole mesh.
#[derive(Clone, Copy, Debug)]
enum Other {
    Nothing,
    Node(u32),
    Triangle(u32),
}

/// The tiles' welds so far. A *node* is a tile's local group (`(tile, group)`, numbered in
/// the order the tiles come); the joined groups are sets of nodes.
pub(super) struct Joiner {
    /// Welded positions (copies follow).
    welded: u32,
    /// Coordinates of the copies.
    copy_positions: Vec<[f32; 3]>,
    classes: Vec<PositionClass>,
    /// The id of every copy by its key.
    copies: FxHashMap<u64, u32>,
    attributes: Vec<Attributes>,
    by_value: HashTable<u32>,
    triangles: Spool<SpooledTri>,
    /// Per node, the first of its triangles in input order.
    first: Vec<u32>,
    nodes: u32,
    /// `[node, position, attribute id]` of every vertex (repeats where tiles meet).
    vertices: Spool<[u32; 3]>,
    /// Boundary edges at each watched position.
    watched: FxHashMap<u32, u32>,
    /// Per node, `(position, attribute id)` of its vertices at watched positions.
    watched_vertices: FxHashMap<u32, Vec<(u32, u32)>>,
    class_edges: Vec<([u32; 2], u32, Other)>,
    /// `(node, input number of the triangle across a matching edge)`.
    joins: Vec<(u32, u32)>,
    /// The node of every own triangle in the band, by input number.
    band_nodes: FxHashMap<u32, u32>,
    repairs: Repairs,
}

impl Joiner {
    pub(super) fn new(mesh: &TiledMesh) -> io::Result<Self> {
        Ok(Self {
            welded: mesh.positions.len() as u32,
            copy_positions: Vec::new(),
            classes: vec![PositionClass::Free; mesh.positions.len()],
            copies: map_with_capacity(0),
            // A mesh has about an attribute set per position: room for that up front, so the
            // table never holds its old and new buckets at once while it grows.
            attributes: Vec::with_capacity(mesh.positions.len()),
            by_value: HashTable::with_capacity(mesh.positions.len()),
            triangles: Spool::new()?,
            first: Vec::new(),
            nodes: 0,
            vertices: Spool::new()?,
            watched: map_with_capacity(0),
            watched_vertices: map_with_capacity(0),
            class_edges: Vec::new(),
            joins: Vec::new(),
            band_nodes: map_with_capacity(0),
            repairs: Repairs::default(),
        })
    }

    /// Adds one tile's weld.
    pub(super) fn add(&mut self, t: TileWeld) -> io::Result<()> {
        let node0 = self.nodes;
        self.nodes += t.group_count;
        self.first.resize(self.nodes as usize, u32::MAX);
        let position: Vec<u32> = t
            .positions
            .iter()
            .map(|lp| {
                lp.map_or(u32::MAX, |lp| {
                    self.position_id(lp.key, lp.position, lp.split)
                })
            })
            .collect();
        let mut attribute = vec![u32::MAX; t.attributes.len()];
        let watched = |x: u32| t.positions[x as usize].is_some_and(|p| p.watched);
        let mut watched_here: Vec<(u32, u32, u32)> = Vec::new();
        for tri in &t.triangles {
            let a = tri
                .a
                .map(|a| self.attribute_id(&t.attributes, &mut attribute, a));
            let p = tri.p.map(|x| position[x as usize]);
            let node = node0 + tri.group;
            for k in 0..3 {
                if watched(tri.p[k]) {
                    watched_here.push((node, p[k], a[k]));
                }
            }
            let first = &mut self.first[node as usize];
            *first = (*first).min(tri.index);
            self.triangles.push(SpooledTri {
                p,
                node,
                surface: u32::from(tri.surface),
            })?;
        }
        watched_here.sort_unstable();
        watched_here.dedup();
        for &(node, p, a) in &watched_here {
            self.watched.entry(p).or_insert(0);
            self.watched_vertices.entry(node).or_default().push((p, a));
            self.vertices.push([node, p, a])?;
        }
        for (x, lp) in t.positions.iter().enumerate() {
            match lp {
                Some(lp) if !lp.watched => {
                    let p = position[x];
                    self.classes[p as usize] = t.classes[x];
                    for &(g, a) in &t.vertices[x] {
                        let a = self.attribute_id(&t.attributes, &mut attribute, a);
                        self.vertices.push([node0 + g, p, a])?;
                    }
                }
                _ => {}
            }
        }
        for e in &t.class_edges {
            let other = match e.across {
                Across::Nothing => Other::Nothing,
                Across::Group(g) => Other::Node(node0 + g),
                Across::Triangle(i) => Other::Triangle(i),
            };
            let ends = e.ends.map(|x| position[x as usize]);
            self.class_edges.push((ends, node0 + e.group, other));
        }
        self.joins
            .extend(t.joins.iter().map(|&(g, i)| (node0 + g, i)));
        self.band_nodes
            .extend(t.band_groups.iter().map(|&(i, g)| (i, node0 + g)));
        add_repairs(&mut self.repairs, &t.repairs);
        Ok(())
    }

    /// The id of the position with key `key`: a welded id, or a copy numbered when first met.
    fn position_id(&mut self, key: u64, position: [f32; 3], split: bool) -> u32 {
        if key & COPY == 0 {
            return key as u32;
        }
        if let Some(&id) = self.copies.get(&key) {
            return id;
        }
        let id = self.welded + self.copy_positions.len() as u32;
        self.copy_positions.push(position);
        self.classes.push(PositionClass::Free);
        self.copies.insert(key, id);
        if split {
            self.repairs.non_manifold_vertices += 1;
        }
        id
    }

    /// The id over the whole mesh of a tile's attribute set `a` (`ids` its tile's ids so far),
    /// its `normal_from_geometry` joined with the tile's.
    fn attribute_id(&mut self, local: &[Attributes], ids: &mut [u32], a: u32) -> u32 {
        if ids[a as usize] != u32::MAX {
            return ids[a as usize];
        }
        let attrs = local[a as usize];
        let key = attrs.key();
        let attributes = &mut self.attributes;
        let entry = self.by_value.entry(
            hash_of(&key),
            |&id| attributes[id as usize].key() == key,
            |&id| hash_of(&attributes[id as usize].key()),
        );
        let id = match entry {
            Entry::Occupied(e) => {
                let id = *e.get();
                attributes[id as usize].normal_from_geometry &= attrs.normal_from_geometry;
                id
            }
            Entry::Vacant(v) => {
                attributes.push(attrs);
                let id = attributes.len() as u32 - 1;
                v.insert(id);
                id
            }
        };
        ids[a as usize] = id;
        id
    }

    /// Joins the groups, counts the watched classes, colours the groups and hands the
    /// mesh to `sink`.
    pub(super) fn finish(
        mut self,
        mesh: &TiledMesh,
        sink: &mut dyn WeldSink,
    ) -> Result<WeldInfo, TiledWeldError> {
        if self.triangles.len() == 0 {
            return Err(WeldError::Empty {
                degenerate: self.repairs.degenerate_triangles,
                duplicate: self.repairs.duplicate_triangles,
            }
            .into());
        }
        let mut sets = Sets::new(self.nodes, std::mem::take(&mut self.watched_vertices));
        for &(node, i) in &self.joins {
            if let Some(&other) = self.band_nodes.get(&i) {
                sets.join(node, other);
            }
        }
        // Groups numbered by their first triangle in input order, as the in-core growth
        // numbers them (each group grows from the first triangle no group has yet), so the
        // colouring sees them in the same order.
        let mut first = vec![u32::MAX; self.nodes as usize];
        for n in 0..self.nodes {
            let root = sets.find(n) as usize;
            first[root] = first[root].min(self.first[n as usize]);
        }
        let mut roots: Vec<u32> = (0..self.nodes)
            .filter(|&n| first[n as usize] != u32::MAX)
            .collect();
        roots.sort_unstable_by_key(|&n| first[n as usize]);
        let mut group_of_root = vec![u32::MAX; self.nodes as usize];
        for (g, &n) in roots.iter().enumerate() {
            group_of_root[n as usize] = g as u32;
        }
        let group_of: Vec<u32> = (0..self.nodes)
            .map(|n| group_of_root[sets.find(n) as usize])
            .collect();
        self.count_classes(&mut sets);
        let positions = self.welded as usize + self.copy_positions.len();
        let vertices = vertex_lists(&mut self.vertices, &group_of, positions)?;
        let mut size = vec![0u32; roots.len()];
        self.triangles.for_each_chunk(|chunk| {
            for t in chunk {
                size[group_of[t.node as usize] as usize] += 1;
            }
            Ok(())
        })?;
        let groups = Groups {
            group: Vec::new(),
            count: size.len() as u32,
            size,
            vertex_of: VertexOf::new(0),
        };
        let (colour, colour_count) = colour_groups(&vertices, &groups);
        if colour_count > u32::from(u16::MAX) {
            return Err(WeldError::TooManyGroups(colour_count).into());
        }
        // In batches: a sink may copy what it is handed.
        for batch in self.attributes.chunks(PUSH) {
            sink.push_attributes(batch)?;
        }
        let mut list: Vec<[u32; 2]> = Vec::new();
        for (x, vs) in vertices.iter().enumerate() {
            let xyz = match x.checked_sub(self.welded as usize) {
                None => mesh.positions[x],
                Some(c) => self.copy_positions[c],
            };
            list.clear();
            list.extend(vs.iter().map(|&(g, a)| [g, a]));
            sink.push_position(xyz, self.classes[x], &list)?;
        }
        drop(vertices);
        let mut batch: Vec<StoredTri> = Vec::with_capacity(PUSH);
        self.triangles.for_each_chunk(|chunk| {
            batch.clear();
            batch.extend(chunk.iter().map(|t| StoredTri {
                p: t.p,
                group: group_of[t.node as usize],
                surface: t.surface as u16,
                reserved: 0,
            }));
            sink.push_triangles(&batch)
        })?;
        self.repairs.welded_positions = mesh.welded_positions;
        Ok(WeldInfo {
            group_count: groups.count,
            group_ids: colour.iter().map(|&c| c as u16).collect(),
            group_id_count: colour_count,
            surface_count: mesh.surface_count.max(1),
            has_colors: mesh.has_colors,
            repairs: self.repairs,
        })
    }

    /// The classes of the watched positions, from the boundary edges through them: mesh
    /// borders and edges between two joined groups.
    fn count_classes(&mut self, sets: &mut Sets) {
        for &(ends, node, other) in &self.class_edges {
            let boundary = match other {
                Other::Nothing => true,
                Other::Node(o) => sets.find(o) != sets.find(node),
                Other::Triangle(i) => self
                    .band_nodes
                    .get(&i)
                    .is_none_or(|&o| sets.find(o) != sets.find(node)),
            };
            if boundary {
                for p in ends {
                    if let Some(n) = self.watched.get_mut(&p) {
                        *n += 1;
                    }
                }
            }
        }
        for (&p, &n) in &self.watched {
            self.classes[p as usize] = match n {
                0 => PositionClass::Free,
                2 => PositionClass::Sharp,
                _ => PositionClass::Rigid,
            };
        }
    }
}

/// Every position's vertices `(group, attribute id)` by group, each once, from the spooled
/// `[node, position, attribute id]` entries: counted per position, then placed.
fn vertex_lists(
    spool: &mut Spool<[u32; 3]>,
    group_of: &[u32],
    positions: usize,
) -> io::Result<VertexLists> {
    // One array serves as the fill pointers and then the starts: position `p`'s count goes
    // to `start[p + 2]`, so that summed, `start[p + 1]` is where its list starts; placing an
    // entry moves that on, to where the list ends, which is where the next one starts.
    let mut start = vec![0u32; positions + 1];
    let total = spool.len();
    spool.for_each_chunk(|chunk| {
        for e in chunk {
            if let Some(c) = start.get_mut(e[1] as usize + 2) {
                *c += 1;
            }
        }
        Ok(())
    })?;
    for p in 2..=positions {
        start[p] += start[p - 1];
    }
    let mut entries = vec![(0u32, 0u32); total];
    spool.for_each_chunk(|chunk| {
        for &[node, p, a] in chunk {
            let at = &mut start[p as usize + 1];
            entries[*at as usize] = (group_of[node as usize], a);
            *at += 1;
        }
        Ok(())
    })?;
    // Each list sorted and its repeats dropped, moved down in place.
    let mut end = 0usize;
    for p in 0..positions {
        let (from, to) = (start[p] as usize, start[p + 1] as usize);
        entries[from..to].sort_unstable();
        start[p] = end as u32;
        for i in from..to {
            if i == from || entries[i] != entries[i - 1] {
                entries[end] = entries[i];
                end += 1;
            }
        }
    }
    start[positions] = end as u32;
    entries.truncate(end);
    entries.shrink_to_fit();
    Ok(VertexLists::from_parts(start, entries))
}

/// Union-find over the nodes; each set keeps its vertices at watched positions, sorted, so a
/// join that would give a group two attribute sets at one position is refused.
struct Sets {
    parent: Vec<u32>,
    vertices: FxHashMap<u32, Vec<(u32, u32)>>,
}

impl Sets {
    fn new(nodes: u32, mut vertices: FxHashMap<u32, Vec<(u32, u32)>>) -> Self {
        for list in vertices.values_mut() {
            list.sort_unstable();
            list.dedup();
        }
        Self {
            parent: (0..nodes).collect(),
            vertices,
        }
    }

    fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let up = self.parent[self.parent[x as usize] as usize];
            self.parent[x as usize] = up;
            x = up;
        }
        x
    }

    /// Joins the sets of `a` and `b` unless they have different attribute sets at one
    /// position.
    fn join(&mut self, a: u32, b: u32) {
        let (a, b) = (self.find(a), self.find(b));
        if a == b {
            return;
        }
        let la = self.vertices.remove(&a).unwrap_or_default();
        let lb = self.vertices.remove(&b).unwrap_or_default();
        match merge_consistent(&la, &lb) {
            Some(merged) => {
                // The larger set's root stays the root.
                let (root, child) = if la.len() >= lb.len() { (a, b) } else { (b, a) };
                self.parent[child as usize] = root;
                self.vertices.insert(root, merged);
            }
            None => {
                self.vertices.insert(a, la);
                self.vertices.insert(b, lb);
            }
        }
    }
}

/// Two sorted `(position, attribute id)` lists merged, or `None` when they have different
/// attribute ids at one position.
fn merge_consistent(a: &[(u32, u32)], b: &[(u32, u32)]) -> Option<Vec<(u32, u32)>> {
    let mut out = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        match a[i].0.cmp(&b[j].0) {
            std::cmp::Ordering::Less => {
                out.push(a[i]);
                i += 1;
            }
            std::cmp::Ordering::Greater => {
                out.push(b[j]);
                j += 1;
            }
            std::cmp::Ordering::Equal => {
                if a[i].1 != b[j].1 {
                    return None;
                }
                out.push(a[i]);
                i += 1;
                j += 1;
            }
        }
    }
    out.extend_from_slice(&a[i..]);
    out.extend_from_slice(&b[j..]);
    Some(out)
}

/// The repairs of the tiles' own triangles, summed.
fn add_repairs(total: &mut Repairs, r: &Repairs) {
    total.degenerate_triangles += r.degenerate_triangles;
    total.duplicate_triangles += r.duplicate_triangles;
    total.non_manifold_edges += r.non_manifold_edges;
    total.non_manifold_vertices += r.non_manifold_vertices;
    total.computed_normals += r.computed_normals;
}
