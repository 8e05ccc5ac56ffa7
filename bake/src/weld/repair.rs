//! Steps 1–4: welding identical positions, dropping degenerate and duplicate triangles,
//! cutting non-manifold edges and splitting non-manifold vertices.

use super::vector::{cross, sub};
use super::welded::{Repairs, WeldError, NONE};
use crate::base::fxhash::{map_with_capacity, FxHashMap};
use crate::mesh::Mesh;
use rayon::prelude::*;

/// A kept triangle: its positions and the source triangle (for its attributes).
pub(super) type Kept = ([u32; 3], u32);

/// Step 1: welds positions with identical coordinates; returns the welded positions and the
/// welded position of every input position.
pub(super) fn weld_positions(mesh: &Mesh, repairs: &mut Repairs) -> (Vec<[f32; 3]>, Vec<u32>) {
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
    (positions, remap)
}

/// Step 2: drops degenerate triangles (a repeated or missing position, or zero area) and
/// duplicates (the same three positions, either orientation, as an earlier triangle); an
/// error when none is left.
pub(super) fn drop_degenerate_and_duplicates(
    mesh: &Mesh,
    remap: &[u32],
    positions: &[[f32; 3]],
    repairs: &mut Repairs,
) -> Result<Vec<Kept>, WeldError> {
    let mut kept: Vec<Kept> = Vec::with_capacity(mesh.triangles.len());
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
        kept.push((p, i as u32));
    }
    let duplicate = duplicates(&kept, positions.len());
    let mut flags = duplicate.iter();
    kept.retain(|_| flags.next() == Some(&false));
    repairs.duplicate_triangles += duplicate.iter().filter(|&&d| d).count() as u64;
    if kept.is_empty() {
        return Err(WeldError::Empty {
            degenerate: repairs.degenerate_triangles,
            duplicate: repairs.duplicate_triangles,
        });
    }
    Ok(kept)
}

/// Whether each of `tris` (of distinct corners below `positions`) has the same three
/// positions as an earlier one. Triangles with the same positions share their lowest one,
/// so each is compared with the earlier triangles listed at its lowest position (a handful),
/// in lists built by a counting sort: no table of every triangle's key.
fn duplicates(tris: &[Kept], positions: usize) -> Vec<bool> {
    let sorted = |p: [u32; 3]| {
        let mut key = p;
        key.sort_unstable();
        key
    };
    let mut start = vec![0u32; positions + 1];
    for &(p, _) in tris {
        start[sorted(p)[0] as usize + 1] += 1;
    }
    for i in 0..positions {
        start[i + 1] += start[i];
    }
    let mut at_lowest = vec![0u32; tris.len()];
    let mut fill = start;
    for (f, &(p, _)) in tris.iter().enumerate() {
        let i = &mut fill[sorted(p)[0] as usize];
        at_lowest[*i as usize] = f as u32;
        *i += 1;
    }
    // `fill[x]` is now where the list of position `x + 1` starts.
    let mut duplicate = vec![false; tris.len()];
    let mut lo = 0;
    for &hi in &fill {
        let list = &at_lowest[lo..hi as usize];
        for (j, &f) in list.iter().enumerate() {
            let key = sorted(tris[f as usize].0);
            duplicate[f as usize] = list[..j].iter().any(|&g| sorted(tris[g as usize].0) == key);
        }
        lo = hi as usize;
    }
    duplicate
}

/// Step 3: cuts the edges used by more than two triangles or twice in one direction: the later
/// triangle gets its own copies of the edge's two positions. Afterwards every directed edge
/// has one triangle and every edge at most two. (A triangle's edge is cut when the same
/// directed edge came before: a third triangle on an edge repeats one of the first two's
/// directions.) `faces_of` lists the triangles around each position before the cut.
/// Returns `(triangle, edges cut)` of each triangle given copies.
///
/// A triangle given copies has a copy at two corners at least, so each of its edges ends at
/// a copy, which no other triangle has: an edge conflicts exactly when an earlier triangle
/// that was not cut has it, which the lists around its first position tell.
pub(super) fn cut_non_manifold_edges(
    faces_of: &FacesOf,
    kept: &mut [Kept],
    positions: &mut Vec<[f32; 3]>,
    repairs: &mut Repairs,
) -> Vec<(u32, u8)> {
    let mut cut = Vec::new();
    let mut was_cut = vec![false; kept.len()];
    for f in 0..kept.len() {
        let p = kept[f].0;
        let mut conflict = [0usize; 3];
        let mut conflicts = 0;
        for k in 0..3 {
            if faces_of.earlier_with_edge(p[k], p[(k + 1) % 3], f as u32, &was_cut) {
                conflict[conflicts] = k;
                conflicts += 1;
            }
        }
        if conflicts == 0 {
            continue;
        }
        repairs.non_manifold_edges += conflicts as u64;
        cut.push((f as u32, conflicts as u8));
        was_cut[f] = true;
        // Each of the triangle's positions on a cut edge gets one copy.
        let mut q = p;
        let mut fresh = [u32::MAX; 3];
        for &k in &conflict[..conflicts] {
            for j in [k, (k + 1) % 3] {
                if fresh[j] == u32::MAX {
                    positions.push(positions[p[j] as usize]);
                    fresh[j] = positions.len() as u32 - 1;
                }
                q[j] = fresh[j];
            }
        }
        kept[f].0 = q;
    }
    cut
}

/// The triangle across each edge of every kept triangle, `NONE` on a border (on all cores).
pub(super) fn opposites(kept: &[Kept], faces_of: &FacesOf) -> Vec<[u32; 3]> {
    kept.par_iter()
        .map(|&(p, _)| [0, 1, 2].map(|k| faces_of.with_edge(p[(k + 1) % 3], p[k])))
        .collect()
}

/// Step 4: splits every position whose triangles form several fans: one copy per extra fan.
pub(super) fn split_non_manifold_vertices(
    faces_of: &FacesOf,
    opp: &[[u32; 3]],
    kept: &mut [Kept],
    positions: &mut Vec<[f32; 3]>,
    repairs: &mut Repairs,
) {
    let mut fans = Fans::default();
    for v in 0..faces_of.len() as u32 {
        if one_fan(v, faces_of.get(v), kept, opp) {
            continue;
        }
        fans.find(v, faces_of.get(v), kept, opp);
        for fan in 1..fans.count() {
            repairs.non_manifold_vertices += 1;
            let copy = positions.len() as u32;
            positions.push(positions[v as usize]);
            for &f in fans.fan(fan) {
                let p = &mut kept[f as usize].0;
                let k = p.iter().position(|&x| x == v).unwrap_or(0);
                p[k] = copy;
            }
        }
    }
}

/// Whether the triangles `faces` around `v` form one fan, as [`Fans::find`] would find, told
/// by walking around `v` across the edges through it: forward (across each triangle's edge
/// leaving `v`) until the walk ends or comes back, then backward from the start. Every
/// directed edge has one triangle and triangles are consistently oriented, so each triangle
/// has at most one triangle across each of its two edges through `v` and the walk never
/// turns back: it visits the fan of the first triangle once. `false` when in doubt.
fn one_fan(v: u32, faces: &[u32], kept: &[Kept], opp: &[[u32; 3]]) -> bool {
    let Some(&start) = faces.first() else {
        return true;
    };
    let corner = |f: u32| kept[f as usize].0.iter().position(|&x| x == v).unwrap_or(0);
    let mut visited = 1usize;
    for backward in [false, true] {
        let mut f = start;
        loop {
            let k = corner(f);
            let o = opp[f as usize][if backward { (k + 2) % 3 } else { k }];
            if o == NONE {
                break;
            }
            if o == start {
                return !backward && visited == faces.len();
            }
            visited += 1;
            if visited > faces.len() {
                return false;
            }
            f = o;
        }
    }
    visited == faces.len()
}

/// The triangles around every position, in triangle order, in one array.
pub(super) struct FacesOf {
    start: Vec<u32>,
    faces: Vec<u32>,
    /// For each entry of `faces`, the corner after the position in that triangle.
    next: Vec<u32>,
}

impl FacesOf {
    pub(super) fn new(
        positions: usize,
        tris: impl Iterator<Item = [u32; 3]> + Clone,
        n: usize,
    ) -> Self {
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

    /// Whether a triangle before `f` and not `cut` has the directed edge `a → b`.
    pub(super) fn earlier_with_edge(&self, a: u32, b: u32, f: u32, cut: &[bool]) -> bool {
        let range = self.start[a as usize] as usize..self.start[a as usize + 1] as usize;
        let (faces, next) = (&self.faces[range.clone()], &self.next[range]);
        // The list is in triangle order.
        faces
            .iter()
            .zip(next)
            .take_while(|&(&g, _)| g < f)
            .any(|(&g, &n)| n == b && !cut[g as usize])
    }

    /// The triangle with the directed edge `a → b`, or `NONE`.
    pub(super) fn with_edge(&self, a: u32, b: u32) -> u32 {
        let range = self.start[a as usize] as usize..self.start[a as usize + 1] as usize;
        self.next[range.clone()]
            .iter()
            .position(|&x| x == b)
            .map_or(NONE, |i| self.faces[range.start + i])
    }

    pub(super) fn len(&self) -> usize {
        self.start.len() - 1
    }

    pub(super) fn get(&self, v: u32) -> &[u32] {
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
    fn find(&mut self, v: u32, faces: &[u32], kept: &[Kept], opp: &[[u32; 3]]) {
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
