//! Steps 5–6: surface groups grown over matching edges, position classes from the
//! boundary edges, each position's vertices, and the colouring of groups into ids.

use caveclod_core::format::PositionClass;

use super::repair::Kept;
use super::vertex_lists::VertexLists;
use super::welded::NONE;
use crate::base::fxhash::{map_with_capacity, FxHashMap};
use crate::mesh::Mesh;
use rayon::prelude::*;

/// Directed edge `a → b` as a map key.
#[inline]
fn ek(a: u32, b: u32) -> u64 {
    (a as u64) << 32 | b as u64
}

/// The surface groups of the kept triangles.
pub(super) struct Groups {
    /// The group of every kept triangle.
    pub(super) group: Vec<u32>,
    /// Number of groups.
    pub(super) count: u32,
    /// Triangles in every group.
    pub(super) size: Vec<u32>,
    /// Every group's vertex (attribute id) at each of its positions.
    pub(super) vertex_of: VertexOf,
}

/// Step 5: grows surface groups from each triangle not yet in one, over edges where the surface
/// and the attributes at both ends match, never taking a triangle that would give the
/// group a second attribute set at one position.
pub(super) fn grow_groups(
    mesh: &Mesh,
    kept: &[Kept],
    tri_attrs: &[[u32; 3]],
    opp: &[[u32; 3]],
    positions: usize,
) -> Groups {
    let nt = kept.len();
    // Each triangle's surface, read at random as the groups grow.
    let surfaces: Vec<u16> = kept
        .par_iter()
        .map(|&(_, i)| mesh.triangles[i as usize].surface)
        .collect();
    let surface = |f: usize| surfaces[f];
    let corner_attr = |f: usize, v: u32| {
        let k = kept[f].0.iter().position(|&x| x == v).unwrap_or(0);
        tri_attrs[f][k]
    };
    let mut group = vec![u32::MAX; nt];
    let mut vertex_of = VertexOf::new(positions);
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
    Groups {
        group,
        count: group_count,
        size: group_size,
        vertex_of,
    }
}

/// Step 6: the class of every position by the boundary edges through it (mesh borders and
/// surface-group changes): none FREE, two SHARP, others RIGID.
pub(super) fn classify(
    kept: &[Kept],
    opp: &[[u32; 3]],
    group: &[u32],
    positions: usize,
) -> Vec<PositionClass> {
    let mut boundary = vec![0u32; positions];
    for (f, (&(p, _), o)) in kept.iter().zip(opp).enumerate() {
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
    boundary
        .iter()
        .map(|&n| match n {
            0 => PositionClass::Free,
            2 => PositionClass::Sharp,
            _ => PositionClass::Rigid,
        })
        .collect()
}

/// Step 6: the `(group, attribute id)` of each group with a vertex at every position, by group.
pub(super) fn vertices_per_position(vertex_of: &VertexOf, positions: usize) -> VertexLists {
    VertexLists::from_entries(positions, vertex_of.entries())
}

/// The colouring of groups: groups that share no position may share an id (greedy, the
/// largest groups first). Returns every group's id and the number of ids.
pub(super) fn colour_groups(vertices: &VertexLists, groups: &Groups) -> (Vec<u32>, u32) {
    let (group_count, group_size) = (groups.count, &groups.size);
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
    (colour, colour_count)
}

/// The attribute id of each surface group's vertex at each position: the first group at a
/// position in an array, others in a map.
pub(super) struct VertexOf {
    first: Vec<(u32, u32)>,
    more: FxHashMap<u64, u32>,
}

impl VertexOf {
    pub(super) fn new(positions: usize) -> Self {
        Self {
            first: vec![(NONE, NONE); positions],
            more: map_with_capacity(0),
        }
    }

    pub(super) fn get(&self, group: u32, p: u32) -> Option<u32> {
        match self.first[p as usize] {
            (g, a) if g == group => Some(a),
            (NONE, _) => None,
            _ => self.more.get(&ek(group, p)).copied(),
        }
    }

    pub(super) fn insert(&mut self, group: u32, p: u32, attr: u32) {
        let first = &mut self.first[p as usize];
        if first.0 == NONE || first.0 == group {
            *first = (group, attr);
        } else {
            self.more.insert(ek(group, p), attr);
        }
    }

    /// `(group, position, attribute id)` of every vertex.
    pub(super) fn entries(&self) -> impl Iterator<Item = (u32, u32, u32)> + Clone + '_ {
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
