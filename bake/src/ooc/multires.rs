//! The multiresolution octree: every coarser level of the clustering, derived from the finest
//! one, cut into octree nodes a renderer chooses per camera.
//!
//! # Levels
//! Level 0 is the finest clustering (the [`Clusterer`] that made the hand-off mesh), or,
//! when that grid is far finer than the mesh (an input below the target is clustered at
//! 2^21 cells and keeps every triangle), the coarsest grid that still keeps 95% of its
//! triangles: otherwise a small mesh would get a dozen levels that merge nothing and a node
//! per triangle. Level
//! `l + 1` clusters on cells twice as large: each level-`l` cluster joins the level-`l + 1`
//! cluster of its parent cell (coordinates halved) with the same surface and a matching UV
//! prediction at the parent cell's centre. Its quadric, corner sum, corner count and corner box
//! are summed into the parent's. Because every triangle's generalized quadric was added once
//! per corner to the cluster of that corner, the summed quadric of a level-`l + 1` cluster is
//! exactly the quadric a direct clustering of the input on the coarser grid would have
//! accumulated: internal levels are simplified recursively from their children with no loss
//! and without reading the input again. (The quadrics keep the finest level's units, so the
//! attribute weights weigh relatively less at coarse levels, as in Garland & Heckbert's
//! absolute-space quadrics.) The UV prediction of a child cluster at the parent centre is the
//! minimiser of its own quadric's UV with the position held there: for one triangle exactly
//! its affine UV map, so the two sides of a seam stay apart at every level. A level-`l`
//! triangle survives at `l + 1` when its three clusters' parents lie in three different cells
//! (once per set of three cells), as in the finest clustering.
//!
//! # Nodes
//! A node is a block of `2^block_levels` cells per axis of one level; the node of block `b` at
//! level `l + 1` is the parent of the level-`l` blocks `b'` with `b' >> 1 == b`, so the nodes
//! form an octree over space (each level's cells nest in the next's). Levels are added until
//! one block holds the whole level and it has at most `coarsest_triangles` triangles (or one
//! cell): that block is the root. A triangle belongs to every block one of its corners' cells
//! lies in, so neighbouring nodes overlap by the triangles crossing their border: where both
//! are drawn at the same level the shared triangles are drawn twice in the same place (same
//! vertices, same depth), and where they are drawn at different levels each side reaches
//! past the border and covers the gap the other leaves, so the surface stays closed where
//! levels change. The overlap draws the border triangles twice, a smaller share of a node's
//! triangles the more cells a block has. The vertices are
//! the level's cluster representatives, shared by every node of the level that uses them, in
//! one vertex buffer for all levels.
//!
//! # Error bounds
//! Each cluster keeps the box of the input corners it stands for. Inside the surface, moving
//! a corner along the surface does not move the surface, so a cluster's error is the box's
//! extent along its vertex normal measured from the representative (how far its input corners
//! can lie from the plane through the representative). On a border of the level (a cell edge
//! one triangle uses) moving along the surface moves the border: there the error is the
//! distance from the representative to the box's farthest corner plus half the cell's
//! diagonal (the triangles that collapse there are no longer drawn). A node's error is the
//! largest error of the clusters its cells and its triangles use, raised to its children's so
//! that it never grows down the tree. The tests check it against the distances of the input's
//! vertices to each level's triangles. Nodes inside the surface get much smaller errors than
//! nodes on its border, which carry the half cell diagonal, so the run-time selection refines
//! the interior no further than its shape needs. Neighbouring nodes drawn at different levels
//! do not share vertices: what the overlap leaves of a gap between them is bounded by
//! the coarser node's error, which the run-time selection keeps under its pixel tolerance.
//!
//! Memory: one level's clusters at a time (the finest is the largest) and the outputs (a
//! vertex per used cluster and three indices per triangle, about a third more than the finest
//! level over all levels).

use super::cluster::{cell_position, cluster_attributes, Cluster, Clusterer};
use super::soup::{HAS_NORMAL, HAS_UV};
use crate::base::fxhash::{FxHashMap, FxHashSet};
use caveclod_core::format::Vertex;
use caveclod_core::octree::{OctreeMeta, OctreeNode, OctreeParts, OctreeRange};

/// How to cut the levels into nodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MultiresOptions {
    /// A node is `2^block_levels` cells per axis of its level.
    pub block_levels: u32,
    /// Levels are added until the root holds at most this many triangles.
    pub coarsest_triangles: usize,
}

impl Default for MultiresOptions {
    fn default() -> Self {
        Self {
            block_levels: 5,
            coarsest_triangles: 1024,
        }
    }
}

/// A multiresolution octree: nodes in breadth-first order (node 0 is the root), their
/// per-surface ranges of `indices`, and one vertex buffer for every level.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MultiresOctree {
    /// Nodes, breadth first.
    pub nodes: Vec<OctreeNode>,
    /// Ranges of `indices` per node and surface with triangles.
    pub ranges: Vec<OctreeRange>,
    /// Vertices of every level.
    pub vertices: Vec<Vertex>,
    /// Triangle lists, three indices into `vertices` per triangle.
    pub indices: Vec<u32>,
    /// Number of surfaces.
    pub surface_count: u32,
    /// Number of levels.
    pub level_count: u32,
    /// Triangles per level, finest first (each once, though the nodes on both sides of a
    /// block border hold the triangles crossing it).
    pub level_triangles: Vec<u64>,
}

impl MultiresOctree {
    /// The arrays as the core reads them ([`OctreeParts::sections`] gives the `.clod`
    /// sections).
    pub fn parts(&self) -> OctreeParts<'_> {
        OctreeParts {
            meta: OctreeMeta {
                node_count: self.nodes.len() as u32,
                level_count: self.level_count,
                vertex_count: self.vertices.len() as u32,
                index_count: self.indices.len() as u32,
                range_count: self.ranges.len() as u32,
                surface_count: self.surface_count,
                reserved: [0; 2],
            },
            nodes: &self.nodes,
            ranges: &self.ranges,
            vertices: &self.vertices,
            indices: &self.indices,
        }
    }
}

/// One level's clusters (quadrics in the finest level's cell units).
struct Level {
    /// Cell coordinates at this level.
    cell_coords: Vec<[u32; 3]>,
    /// Each cell's first cluster.
    cell_first: Vec<u32>,
    clusters: Vec<Cluster>,
    /// Surviving triangles: clusters and surface.
    triangles: Vec<([u32; 3], u16)>,
}

/// What a level leaves for the assembly.
struct LevelOut {
    /// One vertex per cluster.
    vertices: Vec<Vertex>,
    /// The blocks of the level.
    blocks: FxHashMap<[u32; 3], Block>,
    /// Triangles of the level (each once; blocks share the ones on their borders).
    triangles: u64,
}

/// One block of one level.
#[derive(Clone, Debug)]
struct Block {
    /// Triangles (clusters of the level, surface), in the level's order.
    triangles: Vec<([u32; 3], u16)>,
    error: f32,
    min: [f32; 3],
    max: [f32; 3],
}

impl Block {
    fn new() -> Self {
        Self {
            triangles: Vec::new(),
            error: 0.0,
            min: [f32::MAX; 3],
            max: [f32::MIN; 3],
        }
    }

    fn include(&mut self, lo: [f32; 3], hi: [f32; 3]) {
        for a in 0..3 {
            self.min[a] = self.min[a].min(lo[a]);
            self.max[a] = self.max[a].max(hi[a]);
        }
    }
}

/// Builds the multiresolution octree from the finest clustering, consuming it.
pub fn build(c: Clusterer, surface_count: u32, options: &MultiresOptions) -> MultiresOctree {
    let weights = c.options.weights;
    let tolerance = c.options.seam_tolerance;
    let origin = c.cube.origin;
    let unit = 1.0 / c.scale;
    let k = options.block_levels.min(21);
    let mut level = Level {
        cell_coords: c.cell_coords,
        cell_first: c.cell_first,
        clusters: c.clusters,
        triangles: c
            .triangles
            .into_iter()
            .map(|(_, ids, s)| (ids, s))
            .collect(),
    };
    let mut outs: Vec<LevelOut> = Vec::new();
    let mut shift = 0u32;
    // A grid far finer than the mesh's edges (an input smaller than the target keeps every
    // triangle at 2^21 cells) coarsens without merging anything for many levels: start at the
    // coarsest grid that still keeps nearly all of the finest clustering's triangles.
    let finest_triangles = level.triangles.len();
    while shift < 31 && !level.cell_coords.iter().all(|c| *c == [0; 3]) {
        let next = coarsen(&level, shift, tolerance, &weights);
        if (next.triangles.len() as f64) < 0.95 * finest_triangles as f64 {
            break;
        }
        level = next;
        shift += 1;
    }
    loop {
        let out = level_out(&level, shift, k, origin, unit, &weights, outs.last());
        let single_block = out.blocks.len() == 1;
        let finest_cell = level.cell_coords.iter().all(|c| *c == [0; 3]);
        let done = (single_block && level.triangles.len() <= options.coarsest_triangles)
            || finest_cell
            || shift >= 31;
        outs.push(out);
        if done {
            break;
        }
        level = coarsen(&level, shift, tolerance, &weights);
        shift += 1;
    }
    assemble(outs, surface_count)
}

/// The level's vertices and blocks (errors raised to the finer level's blocks).
fn level_out(
    level: &Level,
    shift: u32,
    k: u32,
    origin: [f64; 3],
    unit: f64,
    weights: &super::Weights,
    finer: Option<&LevelOut>,
) -> LevelOut {
    let size = f64::from(1u32 << shift.min(31));
    let world = |x: [f64; 3]| [0, 1, 2].map(|a| (origin[a] + x[a] * unit) as f32);
    let cell_pos = cell_positions(level, size);
    let (mut vertices, boxes) = cluster_vertices(level, &cell_pos, weights, &world);
    fill_missing_normals(level, &mut vertices);
    let border_cell = border_cells(level);
    let errors = cluster_errors(level, &cell_pos, &vertices, &border_cell, size, unit);
    let mut blocks = level_blocks(level, k, &vertices, &errors, &boxes);
    if let Some(finer) = finer {
        for (fb, child) in &finer.blocks {
            if let Some(b) = blocks.get_mut(&fb.map(|v| v >> 1)) {
                b.error = b.error.max(child.error);
                b.include(child.min, child.max);
            }
        }
    }
    LevelOut {
        vertices,
        blocks,
        triangles: level.triangles.len() as u64,
    }
}

/// Each cell's representative position, in grid units.
fn cell_positions(level: &Level, size: f64) -> Vec<[f64; 3]> {
    let mut cell_pos = Vec::with_capacity(level.cell_first.len());
    for (ci, &first) in level.cell_first.iter().enumerate() {
        let lo = level.cell_coords[ci].map(|v| f64::from(v) * size);
        cell_pos.push(cell_position(
            super::cluster::cluster_list(&level.clusters, first),
            lo,
            size,
        ));
    }
    cell_pos
}

/// The lowest and highest corner of a box, in world units.
type WorldBox = ([f32; 3], [f32; 3]);

/// One vertex per cluster (attributes the input lacks are zero) and the world box of the
/// input corners it stands for.
fn cluster_vertices(
    level: &Level,
    cell_pos: &[[f64; 3]],
    weights: &super::Weights,
    world: &dyn Fn([f64; 3]) -> [f32; 3],
) -> (Vec<Vertex>, Vec<WorldBox>) {
    let mut vertices = Vec::with_capacity(level.clusters.len());
    let mut boxes = Vec::with_capacity(level.clusters.len());
    for c in &level.clusters {
        let p = cell_pos[c.cell as usize];
        let (normal, uv, _) = cluster_attributes(c, p, weights);
        boxes.push((world(c.lo), world(c.hi)));
        vertices.push(Vertex {
            position: world(p),
            normal: if c.flags & HAS_NORMAL != 0 {
                normal
            } else {
                [0.0; 3]
            },
            uv: if c.flags & HAS_UV != 0 { uv } else { [0.0; 2] },
        });
    }
    (vertices, boxes)
}

/// Normals from the level's geometry (area-weighted face normals) where the input had none.
fn fill_missing_normals(level: &Level, vertices: &mut [Vertex]) {
    let mut face_sums = vec![[0.0f64; 3]; level.clusters.len()];
    for (ids, _) in &level.triangles {
        let p = ids.map(|i| vertices[i as usize].position.map(f64::from));
        let (u, v) = (sub(p[1], p[0]), sub(p[2], p[0]));
        let n = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        for &i in ids {
            for a in 0..3 {
                face_sums[i as usize][a] += n[a];
            }
        }
    }
    for (i, c) in level.clusters.iter().enumerate() {
        if c.flags & HAS_NORMAL == 0 {
            let n = face_sums[i];
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            vertices[i].normal = if len > 0.0 {
                n.map(|v| (v / len) as f32)
            } else {
                [0.0, 0.0, 1.0]
            };
        }
    }
}

/// Border cells: on an edge (between cells) that one triangle of the level uses.
fn border_cells(level: &Level) -> Vec<bool> {
    let mut edges: FxHashMap<(u32, u32), u32> = FxHashMap::default();
    for (ids, _) in &level.triangles {
        let cells = ids.map(|i| level.clusters[i as usize].cell);
        for e in 0..3 {
            let (a, b) = (cells[e], cells[(e + 1) % 3]);
            *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    let mut border_cell = vec![false; level.cell_first.len()];
    for (&(a, b), &n) in &edges {
        if n == 1 {
            border_cell[a as usize] = true;
            border_cell[b as usize] = true;
        }
    }
    border_cell
}

/// Each cluster's error, in world units. Inside the surface, moving a corner along the
/// surface does not move the surface: the error is how far the cluster's input corners can
/// lie from the plane through the representative with the vertex normal (the corner box's
/// extent along the normal). On a border it does: the farthest corner of the box, plus half
/// the cell's diagonal for the triangles that collapse there and are no longer drawn.
fn cluster_errors(
    level: &Level,
    cell_pos: &[[f64; 3]],
    vertices: &[Vertex],
    border_cell: &[bool],
    size: f64,
    unit: f64,
) -> Vec<f32> {
    let mut errors = Vec::with_capacity(level.clusters.len());
    for (i, c) in level.clusters.iter().enumerate() {
        let p = cell_pos[c.cell as usize];
        let far = |a: usize| (c.lo[a] - p[a]).abs().max((c.hi[a] - p[a]).abs());
        let e = if border_cell[c.cell as usize] {
            (0..3).map(|a| far(a).powi(2)).sum::<f64>().sqrt() + 0.5 * 3f64.sqrt() * size
        } else {
            let n = vertices[i].normal.map(f64::from);
            (0..3).map(|a| n[a].abs() * far(a)).sum()
        };
        errors.push((e * unit) as f32);
    }
    errors
}

/// The level cut into blocks of `2^k` cells a side: each with its clusters' boxes and errors
/// and the triangles with a corner in it.
fn level_blocks(
    level: &Level,
    k: u32,
    vertices: &[Vertex],
    errors: &[f32],
    boxes: &[WorldBox],
) -> FxHashMap<[u32; 3], Block> {
    let block_of = |cell: [u32; 3]| cell.map(|v| v >> k);
    let mut blocks: FxHashMap<[u32; 3], Block> = FxHashMap::default();
    for (i, c) in level.clusters.iter().enumerate() {
        let b = blocks
            .entry(block_of(level.cell_coords[c.cell as usize]))
            .or_insert_with(Block::new);
        b.error = b.error.max(errors[i]);
        b.include(boxes[i].0, boxes[i].1);
    }
    for &(ids, surface) in &level.triangles {
        // Every block a corner lies in holds the triangle: blocks overlap by the triangles
        // that cross their borders, which closes the gaps between neighbours drawn at
        // different levels.
        let mut owners =
            ids.map(|i| block_of(level.cell_coords[level.clusters[i as usize].cell as usize]));
        owners.sort_unstable();
        for (k, owner) in owners.iter().enumerate() {
            if k > 0 && owners[k - 1] == *owner {
                continue;
            }
            let b = blocks.entry(*owner).or_insert_with(Block::new);
            b.triangles.push((ids, surface));
            for i in ids {
                let p = vertices[i as usize].position;
                b.include(p, p);
                b.error = b.error.max(errors[i as usize]);
            }
        }
    }
    blocks
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// The next coarser level: clusters merged into their parent cells' clusters.
fn coarsen(level: &Level, shift: u32, tolerance: f32, weights: &super::Weights) -> Level {
    let parent_size = f64::from(1u32 << (shift + 1).min(31));
    let mut cells: FxHashMap<[u32; 3], u32> = FxHashMap::default();
    let mut next = Level {
        cell_coords: Vec::new(),
        cell_first: Vec::new(),
        clusters: Vec::new(),
        triangles: Vec::new(),
    };
    let mut map = vec![u32::MAX; level.clusters.len()];
    for (ci, &first) in level.cell_first.iter().enumerate() {
        let pc = level.cell_coords[ci].map(|v| v >> 1);
        let pci = *cells.entry(pc).or_insert_with(|| {
            next.cell_coords.push(pc);
            next.cell_first.push(u32::MAX);
            (next.cell_coords.len() - 1) as u32
        });
        let centre = pc.map(|v| (f64::from(v) + 0.5) * parent_size);
        let mut k = first;
        while let Some(c) = level.clusters.get(k as usize) {
            let has_uv = c.flags & HAS_UV != 0;
            let uv = if has_uv {
                let x = c.quadric.minimize_given(centre, &c.mean());
                [(x[6] / weights.uv) as f32, (x[7] / weights.uv) as f32]
            } else {
                [0.0; 2]
            };
            let mut p = next.cell_first[pci as usize];
            let found = loop {
                let Some(d) = next.clusters.get(p as usize) else {
                    break None;
                };
                let uv_ok = !has_uv
                    || d.flags & HAS_UV == 0
                    || ((d.uv_ref[0] - uv[0]).abs() <= tolerance
                        && (d.uv_ref[1] - uv[1]).abs() <= tolerance);
                if d.surface == c.surface && uv_ok {
                    break Some(p);
                }
                p = d.next;
            };
            let p = match found {
                Some(p) => p,
                None => {
                    let p = next.clusters.len() as u32;
                    next.clusters.push(Cluster {
                        cell: pci,
                        surface: c.surface,
                        flags: 0,
                        next: next.cell_first[pci as usize],
                        uv_ref: uv,
                        quadric: Default::default(),
                        sum: [0.0; super::quadric::DIM],
                        corners: 0.0,
                        lo: [f64::MAX; 3],
                        hi: [f64::MIN; 3],
                    });
                    next.cell_first[pci as usize] = p;
                    p
                }
            };
            let d = &mut next.clusters[p as usize];
            if has_uv && d.flags & HAS_UV == 0 {
                d.uv_ref = uv;
            }
            d.flags |= c.flags;
            d.quadric.add_scaled(&c.quadric, 1.0);
            for a in 0..super::quadric::DIM {
                d.sum[a] += c.sum[a];
            }
            d.corners += c.corners;
            for a in 0..3 {
                d.lo[a] = d.lo[a].min(c.lo[a]);
                d.hi[a] = d.hi[a].max(c.hi[a]);
            }
            map[k as usize] = p;
            k = c.next;
        }
    }
    let mut seen: FxHashSet<[u32; 3]> = FxHashSet::default();
    for &(ids, surface) in &level.triangles {
        let ids = ids.map(|i| map[i as usize]);
        let cs = ids.map(|i| next.clusters[i as usize].cell);
        if cs[0] != cs[1] && cs[1] != cs[2] && cs[0] != cs[2] {
            let mut key = cs;
            key.sort_unstable();
            if seen.insert(key) {
                next.triangles.push((ids, surface));
            }
        }
    }
    next
}

/// Nodes breadth first from the root, ranges, and the used vertices in first-use order.
fn assemble(outs: Vec<LevelOut>, surface_count: u32) -> MultiresOctree {
    let top = outs.len() - 1;
    let mut tree = MultiresOctree {
        surface_count,
        level_count: outs.len() as u32,
        level_triangles: outs.iter().map(|o| o.triangles).collect(),
        ..Default::default()
    };
    // Children of every block, sorted, per level.
    let mut children: Vec<FxHashMap<[u32; 3], Vec<[u32; 3]>>> = Vec::with_capacity(outs.len());
    for l in 0..outs.len() {
        let mut m: FxHashMap<[u32; 3], Vec<[u32; 3]>> = FxHashMap::default();
        if l > 0 {
            for fb in outs[l - 1].blocks.keys() {
                m.entry(fb.map(|v| v >> 1)).or_default().push(*fb);
            }
            for v in m.values_mut() {
                v.sort_unstable();
            }
        }
        children.push(m);
    }
    let mut remap: Vec<Vec<u32>> = outs
        .iter()
        .map(|o| vec![u32::MAX; o.vertices.len()])
        .collect();
    // Breadth first: (level, block) per node.
    let mut queue: Vec<(usize, [u32; 3])> = outs[top].blocks.keys().map(|b| (top, *b)).collect();
    queue.sort_unstable();
    let mut head = 0;
    while head < queue.len() {
        let (l, b) = queue[head];
        head += 1;
        let block = &outs[l].blocks[&b];
        let kids = if l > 0 {
            children[l].get(&b).cloned().unwrap_or_default()
        } else {
            Vec::new()
        };
        let first_child = queue.len() as u32;
        for kb in &kids {
            queue.push((l - 1, *kb));
        }
        let mut tris = block.triangles.clone();
        tris.sort_by_key(|t| t.1);
        let first_range = tree.ranges.len() as u32;
        let mut i = 0;
        while i < tris.len() {
            let surface = tris[i].1;
            let first_index = tree.indices.len() as u32;
            while i < tris.len() && tris[i].1 == surface {
                for id in tris[i].0 {
                    let r = &mut remap[l][id as usize];
                    if *r == u32::MAX {
                        *r = tree.vertices.len() as u32;
                        tree.vertices.push(outs[l].vertices[id as usize]);
                    }
                    tree.indices.push(*r);
                }
                i += 1;
            }
            tree.ranges.push(OctreeRange {
                surface: u32::from(surface),
                first_index,
                index_count: tree.indices.len() as u32 - first_index,
            });
        }
        tree.nodes.push(OctreeNode {
            min: block.min,
            max: block.max,
            error: block.error,
            level: l as u32,
            first_child: if kids.is_empty() { 0 } else { first_child },
            child_count: kids.len() as u32,
            first_range,
            range_count: tree.ranges.len() as u32 - first_range,
        });
    }
    tree
}
