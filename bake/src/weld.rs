//! From an imported [`Mesh`] to a clean, manifold, welded mesh with surface groups.
//!
//! Steps, each counted in [`Repairs`]:
//! 1. positions with identical coordinates are welded into one node position;
//! 2. degenerate triangles (a repeated position or zero area) and duplicate triangles (the
//!    same three positions, either orientation) are dropped;
//! 3. an edge used by more than two triangles, or twice in one direction, is cut: the later
//!    triangle gets its own copies of the edge's two positions;
//! 4. a position whose triangles form several fans (a non-manifold vertex) is split, one
//!    copy per extra fan;
//! 5. surface groups grow over edges where the surface and the attributes at both ends match,
//!    never taking a triangle that would give the group a second attribute set at one
//!    position (a UV seam that closes on itself, as on a cylinder, is cut open instead);
//! 6. positions are classified FREE / SHARP / RIGID by the boundary edges through them (mesh
//!    borders and surface-group changes), and groups that share no position share an id
//!    (greedy colouring, largest groups first).
//!
//! Missing normals are computed (area-weighted, per position), missing UVs are zero and
//! missing colours white. Each attribute set records whether its normal follows from the
//! geometry (computed here, or within [`GEOMETRIC_NORMAL_DEGREES`] of the computed one),
//! which simplification then ignores.

use caveclod_core::format::PositionClass;

use crate::fxhash::{map_with_capacity, set_with_capacity, FxHashMap};
use crate::mesh::{Mesh, NO_ATTRIBUTE};

/// No triangle.
const NONE: u32 = u32::MAX;

/// Directed edge `a → b` as a map key.
#[inline]
fn ek(a: u32, b: u32) -> u64 {
    (a as u64) << 32 | b as u64
}

/// Counts of what welding repaired.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Repairs {
    /// Input positions merged into an identical one.
    pub welded_positions: u64,
    /// Triangles dropped for a repeated position or zero area.
    pub degenerate_triangles: u64,
    /// Triangles dropped as duplicates.
    pub duplicate_triangles: u64,
    /// Edges cut because more than two triangles (or two in one direction) shared them.
    pub non_manifold_edges: u64,
    /// Positions split because their triangles formed several fans.
    pub non_manifold_vertices: u64,
    /// Corners without a normal that got a computed one.
    pub computed_normals: u64,
}

impl Repairs {
    /// `(name, count)` pairs, for reports.
    pub fn entries(&self) -> [(&'static str, u64); 6] {
        [
            ("welded_positions", self.welded_positions),
            ("degenerate_triangles", self.degenerate_triangles),
            ("duplicate_triangles", self.duplicate_triangles),
            ("non_manifold_edges", self.non_manifold_edges),
            ("non_manifold_vertices", self.non_manifold_vertices),
            ("computed_normals", self.computed_normals),
        ]
    }
}

/// Largest angle between a source's normal and the area-weighted normal at its position for
/// which the normal still counts as following from the geometry. Heightfield normals (central
/// differences) are within 10° of it at 99.98% of St. Helens' corners, within 2° at 88%.
pub const GEOMETRIC_NORMAL_DEGREES: f64 = 10.0;

/// The attributes of one vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Attributes {
    /// Unit normal.
    pub normal: [f32; 3],
    /// Texture coordinates.
    pub uv: [f32; 2],
    /// Linear RGBA.
    pub color: [f32; 4],
    /// Whether the normal follows from the geometry at every corner that has it: computed
    /// here (area-weighted at its position), or given by the source within
    /// [`GEOMETRIC_NORMAL_DEGREES`] of that (heightfield importers compute their normals
    /// from the grid, and a mesh cannot say which of its normals were authored). Such a
    /// normal says nothing the positions do not, so simplification gives it no weight. Not
    /// part of the attributes' identity.
    pub normal_from_geometry: bool,
}

impl Attributes {
    fn key(&self) -> [u32; 9] {
        let n = self.normal.map(|x| (x + 0.0).to_bits());
        let u = self.uv.map(|x| (x + 0.0).to_bits());
        let c = self.color.map(|x| (x + 0.0).to_bits());
        [n[0], n[1], n[2], u[0], u[1], c[0], c[1], c[2], c[3]]
    }
}

/// One welded triangle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WeldedTri {
    /// Position ids, counter-clockwise.
    pub p: [u32; 3],
    /// Per-corner attribute ids into [`Welded::attributes`].
    pub a: [u32; 3],
    /// Surface.
    pub surface: u16,
    /// Surface group (before colouring).
    pub group: u32,
}

/// A manifold mesh with surface groups, classes and the vertex table's contents.
#[derive(Clone, Debug, Default)]
pub struct Welded {
    /// Node positions.
    pub positions: Vec<[f32; 3]>,
    /// Their classes.
    pub classes: Vec<PositionClass>,
    /// Distinct attribute sets.
    pub attributes: Vec<Attributes>,
    /// Triangles.
    pub triangles: Vec<WeldedTri>,
    /// Number of surface groups.
    pub group_count: u32,
    /// Surface-group id of each group (the colouring).
    pub group_ids: Vec<u16>,
    /// Number of surface-group ids.
    pub group_id_count: u32,
    /// Number of surfaces.
    pub surface_count: u32,
    /// Per position: `(group, attribute id)` of each group with a vertex there, by group.
    pub vertices: Vec<Vec<(u32, u32)>>,
    /// What was repaired.
    pub repairs: Repairs,
}

/// Why welding failed.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum WeldError {
    /// Nothing left after dropping degenerate and duplicate triangles.
    #[error("no triangle left after dropping {degenerate} degenerate and {duplicate} duplicate triangles")]
    Empty {
        /// Degenerate triangles dropped.
        degenerate: u64,
        /// Duplicates dropped.
        duplicate: u64,
    },
    /// More surface-group ids than the format's 16 bits.
    #[error("{0} surface-group ids needed, at most 65535 supported")]
    TooManyGroups(u32),
    /// More surfaces than the format's 16 bits.
    #[error("{0} surfaces, at most 65535 supported")]
    TooManySurfaces(usize),
}

fn sub(a: [f32; 3], b: [f32; 3]) -> [f64; 3] {
    [
        (a[0] - b[0]) as f64,
        (a[1] - b[1]) as f64,
        (a[2] - b[2]) as f64,
    ]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn normalize(v: [f64; 3]) -> [f32; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if l > 0.0 {
        [(v[0] / l) as f32, (v[1] / l) as f32, (v[2] / l) as f32]
    } else {
        [0.0, 0.0, 1.0]
    }
}

/// Welds, repairs and groups `mesh`.
pub fn weld(mesh: &Mesh) -> Result<Welded, WeldError> {
    if mesh.surfaces.len() > u16::MAX as usize {
        return Err(WeldError::TooManySurfaces(mesh.surfaces.len()));
    }
    let mut repairs = Repairs::default();
    // 1. Weld identical positions.
    let mut by_bits: FxHashMap<[u32; 3], u32> = map_with_capacity(mesh.positions.len());
    let mut positions: Vec<[f32; 3]> = Vec::with_capacity(mesh.positions.len());
    let remap: Vec<u32> = mesh
        .positions
        .iter()
        .map(|p| {
            let key = p.map(|x| (x + 0.0).to_bits());
            *by_bits.entry(key).or_insert_with(|| {
                positions.push(*p);
                positions.len() as u32 - 1
            })
        })
        .collect();
    repairs.welded_positions = (mesh.positions.len() - positions.len()) as u64;

    // 2. Drop degenerate and duplicate triangles; keep the source triangle for attributes.
    let mut kept: Vec<([u32; 3], usize)> = Vec::with_capacity(mesh.triangles.len());
    let mut seen = set_with_capacity::<[u32; 3]>(mesh.triangles.len());
    for (i, t) in mesh.triangles.iter().enumerate() {
        let p = t
            .position
            .map(|x| remap.get(x as usize).copied().unwrap_or(u32::MAX));
        if p.contains(&u32::MAX) || p[0] == p[1] || p[1] == p[2] || p[0] == p[2] {
            repairs.degenerate_triangles += 1;
            continue;
        }
        let [a, b, c] = p.map(|x| positions[x as usize]);
        let n = cross(sub(b, a), sub(c, a));
        if n == [0.0; 3] {
            repairs.degenerate_triangles += 1;
            continue;
        }
        let mut key = p;
        key.sort_unstable();
        if !seen.insert(key) {
            repairs.duplicate_triangles += 1;
            continue;
        }
        kept.push((p, i));
    }
    if kept.is_empty() {
        return Err(WeldError::Empty {
            degenerate: repairs.degenerate_triangles,
            duplicate: repairs.duplicate_triangles,
        });
    }

    // 3. Cut non-manifold edges.
    let mut directed: FxHashMap<u64, u32> = map_with_capacity(3 * kept.len());
    let mut copies: Vec<u32> = (0..positions.len() as u32).collect(); // copy -> original
    for f in 0..kept.len() {
        let p = kept[f].0;
        let conflict: Vec<usize> = (0..3)
            .filter(|&k| {
                let (a, b) = (p[k], p[(k + 1) % 3]);
                directed.contains_key(&ek(a, b))
                    || (directed.contains_key(&ek(b, a)) && edge_faces(&directed, a, b) >= 2)
            })
            .collect();
        let mut q = p;
        if !conflict.is_empty() {
            repairs.non_manifold_edges += conflict.len() as u64;
            // Each of the triangle's positions on a cut edge gets one copy.
            let mut fresh = [u32::MAX; 3];
            for &k in &conflict {
                for j in [k, (k + 1) % 3] {
                    if fresh[j] == u32::MAX {
                        let orig = p[j];
                        positions.push(positions[orig as usize]);
                        copies.push(copies[orig as usize]);
                        fresh[j] = positions.len() as u32 - 1;
                    }
                    q[j] = fresh[j];
                }
            }
            kept[f].0 = q;
        }
        for k in 0..3 {
            directed.insert(ek(q[k], q[(k + 1) % 3]), f as u32);
        }
    }

    // Now every directed edge has one triangle and every edge at most two: the triangle
    // across each edge, `NONE` on a border. Splitting vertices below keeps these pairs (the
    // two triangles on an edge through a vertex are always in the same fan).
    drop(directed);
    let faces_of = FacesOf::new(positions.len(), kept.iter().map(|k| k.0), kept.len());
    let opp: Vec<[u32; 3]> = kept
        .iter()
        .map(|&(p, _)| [0, 1, 2].map(|k| faces_of.with_edge(p[(k + 1) % 3], p[k])))
        .collect();

    // 4. Split non-manifold vertices: one position per fan.
    let mut fans = Fans::default();
    for v in 0..faces_of.len() as u32 {
        fans.find(v, faces_of.get(v), &kept, &opp);
        for fan in 1..fans.count() {
            repairs.non_manifold_vertices += 1;
            let copy = positions.len() as u32;
            positions.push(positions[v as usize]);
            copies.push(copies[v as usize]);
            for &f in fans.fan(fan) {
                let p = &mut kept[f as usize].0;
                let k = p.iter().position(|&x| x == v).unwrap_or(0);
                p[k] = copy;
            }
        }
    }

    // 5. Attributes per corner. The area-weighted normal of every position: for corners
    // without a normal, and to tell which given ones follow from the geometry.
    let mut computed = vec![[0f64; 3]; positions.len()];
    for &(p, _) in &kept {
        let [a, b, c] = p.map(|x| positions[x as usize]);
        let n = cross(sub(b, a), sub(c, a));
        for &v in &p {
            for k in 0..3 {
                computed[v as usize][k] += n[k];
            }
        }
    }
    let min_cos = GEOMETRIC_NORMAL_DEGREES.to_radians().cos();
    let mut attr_ids: FxHashMap<[u32; 9], u32> = map_with_capacity(0);
    // Corners with the same sources (normal or, for a computed one, position; UV; colour)
    // have the same attributes: look those up once.
    let mut by_source: FxHashMap<[u64; 2], u32> = map_with_capacity(positions.len());
    let mut attributes: Vec<Attributes> = Vec::new();
    let mut tri_attrs: Vec<[u32; 3]> = Vec::with_capacity(kept.len());
    for &(p, i) in &kept {
        let t = &mesh.triangles[i];
        let mut a = [0u32; 3];
        for k in 0..3 {
            let normal = mesh
                .normals
                .get(t.normal[k] as usize)
                .filter(|_| t.normal[k] != NO_ATTRIBUTE);
            let uv = mesh.uvs.get(t.uv[k] as usize);
            let color = mesh.colors.get(t.color[k] as usize);
            if normal.is_none() {
                repairs.computed_normals += 1;
            }
            let source = [
                normal.map_or(1 << 32 | p[k] as u64, |_| t.normal[k] as u64),
                (uv.map_or(NONE, |_| t.uv[k]) as u64) << 32
                    | color.map_or(NONE, |_| t.color[k]) as u64,
            ];
            a[k] = *by_source.entry(source).or_insert_with(|| {
                let attrs = Attributes {
                    normal: normal
                        .copied()
                        .unwrap_or_else(|| normalize(computed[p[k] as usize])),
                    uv: uv.copied().unwrap_or([0.0; 2]),
                    color: color.copied().unwrap_or([1.0; 4]),
                    normal_from_geometry: true,
                };
                *attr_ids.entry(attrs.key()).or_insert_with(|| {
                    attributes.push(attrs);
                    attributes.len() as u32 - 1
                })
            });
            let from_geometry = normal.is_none_or(|&n| {
                let g = computed[p[k] as usize];
                let n = n.map(f64::from);
                dot(n, g) >= min_cos * (dot(n, n) * dot(g, g)).sqrt()
            });
            attributes[a[k] as usize].normal_from_geometry &= from_geometry;
        }
        tri_attrs.push(a);
    }

    // 6. Surface groups by region growing.
    let nt = kept.len();
    let surface = |f: usize| mesh.triangles[kept[f].1].surface;
    let corner_attr = |f: usize, v: u32| {
        let k = kept[f].0.iter().position(|&x| x == v).unwrap_or(0);
        tri_attrs[f][k]
    };
    let mut group = vec![u32::MAX; nt];
    let mut vertex_of = VertexOf::new(positions.len());
    let mut group_count = 0u32;
    let mut group_size: Vec<u32> = Vec::new();
    let mut queue = Vec::new();
    for seed in 0..nt {
        if group[seed] != u32::MAX {
            continue;
        }
        let g = group_count;
        group_count += 1;
        group_size.push(0);
        queue.clear();
        queue.push(seed as u32);
        while let Some(f) = queue.pop() {
            let f = f as usize;
            if group[f] != u32::MAX {
                continue;
            }
            let p = kept[f].0;
            let fits = (0..3).all(|k| vertex_of.get(g, p[k]).is_none_or(|a| a == tri_attrs[f][k]));
            if !fits {
                continue;
            }
            group[f] = g;
            group_size[g as usize] += 1;
            for k in 0..3 {
                vertex_of.insert(g, p[k], tri_attrs[f][k]);
            }
            for k in 0..3 {
                let (a, b) = (p[k], p[(k + 1) % 3]);
                let o = opp[f][k];
                if o != NONE {
                    let o = o as usize;
                    if group[o] == u32::MAX
                        && surface(o) == surface(f)
                        && corner_attr(o, a) == corner_attr(f, a)
                        && corner_attr(o, b) == corner_attr(f, b)
                    {
                        queue.push(o as u32);
                    }
                }
            }
        }
    }

    // 7. Classes from boundary edges.
    let mut boundary = vec![0u32; positions.len()];
    for (f, (&(p, _), o)) in kept.iter().zip(&opp).enumerate() {
        for k in 0..3 {
            let counts = match o[k] {
                NONE => true,
                o => (f as u32) < o && group[f] != group[o as usize],
            };
            if counts {
                boundary[p[k] as usize] += 1;
                boundary[p[(k + 1) % 3] as usize] += 1;
            }
        }
    }
    let classes = boundary
        .iter()
        .map(|&n| match n {
            0 => PositionClass::Free,
            2 => PositionClass::Sharp,
            _ => PositionClass::Rigid,
        })
        .collect();

    // 8. Vertices per position and the colouring of groups.
    let mut vertices: Vec<Vec<(u32, u32)>> = vec![Vec::new(); positions.len()];
    for (g, p, a) in vertex_of.entries() {
        vertices[p as usize].push((g, a));
    }
    for v in &mut vertices {
        v.sort_unstable();
    }
    let mut order: Vec<u32> = (0..group_count).collect();
    order.sort_unstable_by_key(|&g| std::cmp::Reverse(group_size[g as usize]));
    let mut positions_of: Vec<Vec<u32>> = vec![Vec::new(); group_count as usize];
    for (p, vs) in vertices.iter().enumerate() {
        for &(g, _) in vs {
            positions_of[g as usize].push(p as u32);
        }
    }
    let mut colour = vec![u32::MAX; group_count as usize];
    let mut colour_count = 0u32;
    let mut used: Vec<u32> = Vec::new();
    for &g in &order {
        used.clear();
        for &p in &positions_of[g as usize] {
            for &(o, _) in &vertices[p as usize] {
                let c = colour[o as usize];
                if c != u32::MAX && !used.contains(&c) {
                    used.push(c);
                }
            }
        }
        let c = (0..).find(|c| !used.contains(c)).unwrap_or(0);
        colour[g as usize] = c;
        colour_count = colour_count.max(c + 1);
    }
    if colour_count > u16::MAX as u32 {
        return Err(WeldError::TooManyGroups(colour_count));
    }
    let triangles = kept
        .iter()
        .zip(&tri_attrs)
        .enumerate()
        .map(|(f, (&(p, i), &a))| WeldedTri {
            p,
            a,
            surface: mesh.triangles[i].surface,
            group: group[f],
        })
        .collect();
    Ok(Welded {
        positions,
        classes,
        attributes,
        triangles,
        group_count,
        group_ids: colour.iter().map(|&c| c as u16).collect(),
        group_id_count: colour_count,
        surface_count: mesh.surfaces.len().max(1) as u32,
        vertices,
        repairs,
    })
}

/// Triangles on the undirected edge `a`–`b` so far.
fn edge_faces(directed: &FxHashMap<u64, u32>, a: u32, b: u32) -> usize {
    usize::from(directed.contains_key(&ek(a, b))) + usize::from(directed.contains_key(&ek(b, a)))
}

/// The attribute id of each surface group's vertex at each position: the first group at a
/// position in an array, others in a map.
struct VertexOf {
    first: Vec<(u32, u32)>,
    more: FxHashMap<u64, u32>,
}

impl VertexOf {
    fn new(positions: usize) -> Self {
        Self {
            first: vec![(NONE, NONE); positions],
            more: map_with_capacity(0),
        }
    }

    fn get(&self, group: u32, p: u32) -> Option<u32> {
        match self.first[p as usize] {
            (g, a) if g == group => Some(a),
            (NONE, _) => None,
            _ => self.more.get(&ek(group, p)).copied(),
        }
    }

    fn insert(&mut self, group: u32, p: u32, attr: u32) {
        let first = &mut self.first[p as usize];
        if first.0 == NONE || first.0 == group {
            *first = (group, attr);
        } else {
            self.more.insert(ek(group, p), attr);
        }
    }

    /// `(group, position, attribute id)` of every vertex.
    fn entries(&self) -> impl Iterator<Item = (u32, u32, u32)> + '_ {
        let first = self
            .first
            .iter()
            .enumerate()
            .filter(|(_, &(g, _))| g != NONE)
            .map(|(p, &(g, a))| (g, p as u32, a));
        let more = self
            .more
            .iter()
            .map(|(&e, &a)| ((e >> 32) as u32, e as u32, a));
        first.chain(more)
    }
}

/// The triangles around every position, in triangle order, in one array.
struct FacesOf {
    start: Vec<u32>,
    faces: Vec<u32>,
    /// For each entry of `faces`, the corner after the position in that triangle.
    next: Vec<u32>,
}

impl FacesOf {
    fn new(positions: usize, tris: impl Iterator<Item = [u32; 3]> + Clone, n: usize) -> Self {
        let mut start = vec![0u32; positions + 1];
        for p in tris.clone() {
            for v in p {
                start[v as usize + 1] += 1;
            }
        }
        for i in 0..positions {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut faces = vec![0u32; 3 * n];
        let mut next = vec![0u32; 3 * n];
        for (f, p) in tris.enumerate() {
            for k in 0..3 {
                let i = &mut fill[p[k] as usize];
                faces[*i as usize] = f as u32;
                next[*i as usize] = p[(k + 1) % 3];
                *i += 1;
            }
        }
        Self { start, faces, next }
    }

    /// The triangle with the directed edge `a → b`, or `NONE`.
    fn with_edge(&self, a: u32, b: u32) -> u32 {
        let range = self.start[a as usize] as usize..self.start[a as usize + 1] as usize;
        self.next[range.clone()]
            .iter()
            .position(|&x| x == b)
            .map_or(NONE, |i| self.faces[range.start + i])
    }

    fn len(&self) -> usize {
        self.start.len() - 1
    }

    fn get(&self, v: u32) -> &[u32] {
        &self.faces[self.start[v as usize] as usize..self.start[v as usize + 1] as usize]
    }
}

/// The fans of triangles around a position: triangles joined across edges through it.
#[derive(Default)]
struct Fans {
    /// Triangles, fan after fan.
    order: Vec<u32>,
    /// Where each fan starts in `order`, and its end.
    bounds: Vec<usize>,
    /// Per triangle of the position (by index in its list): taken by a fan.
    done: Vec<bool>,
}

impl Fans {
    /// Finds the fans around `v`, each grown breadth-first from the first triangle (in
    /// `faces` order) that no earlier fan took.
    fn find(&mut self, v: u32, faces: &[u32], kept: &[([u32; 3], usize)], opp: &[[u32; 3]]) {
        self.order.clear();
        self.bounds.clear();
        self.done.clear();
        self.done.resize(faces.len(), false);
        for start in 0..faces.len() {
            if self.done[start] {
                continue;
            }
            self.done[start] = true;
            self.bounds.push(self.order.len());
            self.order.push(faces[start]);
            let mut i = *self.bounds.last().unwrap_or(&0);
            while i < self.order.len() {
                let p = kept[self.order[i] as usize].0;
                let k = p.iter().position(|&x| x == v).unwrap_or(0);
                let f = self.order[i] as usize;
                for o in [opp[f][k], opp[f][(k + 2) % 3]] {
                    if o != NONE {
                        if let Some(j) = faces.iter().position(|&g| g == o) {
                            if !self.done[j] {
                                self.done[j] = true;
                                self.order.push(o);
                            }
                        }
                    }
                }
                i += 1;
            }
        }
        self.bounds.push(self.order.len());
    }

    /// Number of fans found.
    fn count(&self) -> usize {
        self.bounds.len() - 1
    }

    /// The triangles of fan `i`.
    fn fan(&self, i: usize) -> &[u32] {
        &self.order[self.bounds[i]..self.bounds[i + 1]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{Surface, Triangle};

    /// A mesh of the given points and triangles, one surface, no attributes.
    fn mesh(positions: &[[f32; 3]], triangles: &[[u32; 3]]) -> Mesh {
        Mesh {
            positions: positions.to_vec(),
            triangles: triangles
                .iter()
                .map(|&position| Triangle {
                    position,
                    normal: [NO_ATTRIBUTE; 3],
                    uv: [NO_ATTRIBUTE; 3],
                    color: [NO_ATTRIBUTE; 3],
                    surface: 0,
                })
                .collect(),
            surfaces: vec![Surface::default()],
            ..Mesh::default()
        }
    }

    /// Every directed edge once, every edge at most twice, one fan around every position.
    fn assert_manifold(w: &Welded) {
        let mut directed = std::collections::HashMap::new();
        for (f, t) in w.triangles.iter().enumerate() {
            for k in 0..3 {
                let e = (t.p[k], t.p[(k + 1) % 3]);
                assert!(directed.insert(e, f).is_none(), "edge {e:?} twice");
            }
        }
        for p in 0..w.positions.len() as u32 {
            let around: Vec<usize> = (0..w.triangles.len())
                .filter(|&f| w.triangles[f].p.contains(&p))
                .collect();
            let mut fan = vec![around[0]];
            let mut i = 0;
            while i < fan.len() {
                let t = w.triangles[fan[i]].p;
                for k in 0..3 {
                    let (a, b) = (t[k], t[(k + 1) % 3]);
                    if a == p || b == p {
                        if let Some(&o) = directed.get(&(b, a)) {
                            if !fan.contains(&o) {
                                fan.push(o);
                            }
                        }
                    }
                }
                i += 1;
            }
            assert_eq!(fan.len(), around.len(), "position {p} has several fans");
        }
    }

    #[test]
    fn welds_points_and_drops_degenerate_and_duplicate_triangles() {
        let points = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 0.0, 0.0], // the same point as 1
            [2.0, 0.0, 0.0], // on the line through 0 and 1
        ];
        let w = weld(&mesh(
            &points,
            &[
                [0, 1, 2],
                [0, 3, 2],
                [2, 1, 0],
                [0, 0, 2],
                [0, 1, 4],
                [1, 3, 2],
            ],
        ))
        .expect("weld");
        assert_eq!(w.positions.len(), 4);
        assert_eq!(w.triangles.len(), 1);
        assert_eq!(
            w.repairs,
            Repairs {
                welded_positions: 1,
                // [0, 0, 2], [0, 1, 4] (zero area) and [1, 3, 2] (1 and 3 are one point)
                degenerate_triangles: 3,
                // [0, 3, 2] is [0, 1, 2]; [2, 1, 0] is it turned over
                duplicate_triangles: 2,
                computed_normals: 3,
                ..Repairs::default()
            }
        );
        assert_eq!(w.triangles[0].p, [0, 1, 2]);
        // A lone triangle: every position on two border edges; the unused point is kept.
        use PositionClass::{Free, Sharp};
        assert_eq!(w.classes, vec![Sharp, Sharp, Sharp, Free]);
    }

    #[test]
    fn nothing_left_is_an_error() {
        let e = weld(&mesh(&[[0.0; 3], [1.0, 0.0, 0.0]], &[[0, 1, 1]])).expect_err("empty");
        assert_eq!(
            e,
            WeldError::Empty {
                degenerate: 1,
                duplicate: 0
            }
        );
    }

    #[test]
    fn an_edge_of_three_triangles_is_cut() {
        // Three fins on the edge 0–1; the third runs the edge the same way as the first.
        let points = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.5, 1.0, 0.0],
            [0.5, -1.0, 0.0],
            [0.5, 0.0, 1.0],
        ];
        let w = weld(&mesh(&points, &[[0, 1, 2], [1, 0, 3], [0, 1, 4]])).expect("weld");
        assert_eq!(w.repairs.non_manifold_edges, 1);
        assert_eq!(w.positions.len(), 7, "the third fin gets its own 0 and 1");
        assert_eq!(w.triangles[2].p, [5, 6, 4]);
        assert_eq!(w.positions[5], points[0]);
        assert_eq!(w.positions[6], points[1]);
        assert_manifold(&w);
    }

    #[test]
    fn a_bowtie_vertex_is_split() {
        let points = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [-1.0, 0.0, 0.0],
            [-1.0, -1.0, 0.0],
        ];
        let w = weld(&mesh(&points, &[[0, 1, 2], [0, 3, 4]])).expect("weld");
        assert_eq!(w.repairs.non_manifold_vertices, 1);
        assert_eq!(w.positions.len(), 6);
        assert_eq!(w.triangles[0].p, [0, 1, 2]);
        assert_eq!(w.triangles[1].p, [5, 3, 4]);
        assert_manifold(&w);
    }

    #[test]
    fn a_uv_seam_makes_two_groups_and_classes_follow_boundaries() {
        // A quad of two triangles; the second has other UVs along the diagonal 0–2.
        let points = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        let mut m = mesh(&points, &[[0, 1, 2], [0, 2, 3]]);
        m.uvs = vec![[0.0, 0.0], [0.5, 0.5]];
        m.triangles[0].uv = [0, 0, 0];
        m.triangles[1].uv = [1, 1, 1];
        let w = weld(&m).expect("weld");
        assert_eq!(w.group_count, 2);
        assert_ne!(w.triangles[0].group, w.triangles[1].group);
        assert_eq!(w.group_id_count, 2, "the groups share positions");
        use PositionClass::{Rigid, Sharp};
        assert_eq!(w.classes, vec![Rigid, Sharp, Rigid, Sharp]);
        assert_eq!(w.vertices[0].len(), 2);
        assert_eq!(w.vertices[1].len(), 1);
        // The same UVs everywhere: one group, the diagonal no boundary.
        m.triangles[1].uv = [0, 0, 0];
        let w = weld(&m).expect("weld");
        assert_eq!(w.group_count, 1);
        assert_eq!(w.classes, vec![Sharp; 4]);
        assert_eq!(w.attributes.len(), 1);
    }

    #[test]
    fn a_closed_mesh_is_free_and_groups_that_share_no_position_share_an_id() {
        // Two tetrahedra apart, of two surfaces.
        let mut points = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        points.extend(points.clone().iter().map(|p| [p[0] + 5.0, p[1], p[2]]));
        let tet = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]];
        let tris: Vec<[u32; 3]> = tet
            .iter()
            .chain(&tet.map(|t| t.map(|x| x + 4)))
            .copied()
            .collect();
        let mut m = mesh(&points, &tris);
        m.surfaces.push(Surface::default());
        for t in &mut m.triangles[4..] {
            t.surface = 1;
        }
        let w = weld(&m).expect("weld");
        assert_eq!(w.classes, vec![PositionClass::Free; 8]);
        assert_eq!(w.group_count, 2);
        assert_eq!(w.group_id_count, 1);
        assert_eq!(w.surface_count, 2);
        assert_eq!(w.repairs.computed_normals, 24);
        assert_manifold(&w);
    }

    #[test]
    fn normals_that_follow_from_the_geometry_are_marked() {
        // A pyramid's four sides: each apex corner's area-weighted normal is straight up.
        let points = [
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [2.0, 0.0, 2.0],
            [0.0, 0.0, 2.0],
            [1.0, 0.5, 1.0],
        ];
        let tris = [[0, 4, 1], [1, 4, 2], [2, 4, 3], [3, 4, 0]];
        let m = mesh(&points, &tris);
        let w = weld(&m).expect("weld");
        assert!(w.attributes.iter().all(|a| a.normal_from_geometry));

        // Given normals: up at the apex (its geometric normal) and 45° off at the base
        // corners (whose geometric normals lean outwards by less than that).
        let mut m = mesh(&points, &tris);
        let s = std::f32::consts::FRAC_1_SQRT_2;
        m.normals = vec![[0.0, 1.0, 0.0], [s, s, 0.0]];
        for t in &mut m.triangles {
            t.normal = t.position.map(|p| if p == 4 { 0 } else { 1 });
        }
        let w = weld(&m).expect("weld");
        let apex = w.vertices[4][0].1 as usize;
        assert!(w.attributes[apex].normal_from_geometry);
        let flagged = |p: usize| w.attributes[w.vertices[p][0].1 as usize].normal_from_geometry;
        assert!((0..4).all(|p| !flagged(p)));
        assert_eq!(w.repairs.computed_normals, 0);
    }
}
