//! The attributes of every corner, deduplicated (before the groups, which compare them).
//! A missing normal is the area-weighted normal at the position, which also tells which
//! given normals follow from the geometry.

use super::repair::Kept;
use super::vector::{cross, dot, sub};
use super::welded::{Attributes, Repairs, GEOMETRIC_NORMAL_DEGREES, NONE};
use crate::base::fxhash::hash_of;
use crate::mesh::{Mesh, NO_ATTRIBUTE};
use hashbrown::hash_table::{Entry, HashTable};
use rayon::prelude::*;

fn normalize(v: [f64; 3]) -> [f32; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if l > 0.0 {
        [(v[0] / l) as f32, (v[1] / l) as f32, (v[2] / l) as f32]
    } else {
        [0.0, 0.0, 1.0]
    }
}

/// Where a corner's attributes come from: its normal's index (or, for a normal computed
/// here, its position's, flagged), and its UV's and colour's indices, `NONE` where absent.
/// Corners from the same sources have the same attributes.
fn source(mesh: &Mesh, kept: &[Kept], corner: u32) -> [u64; 2] {
    let (p, i) = kept[corner as usize / 3];
    let (t, k) = (&mesh.triangles[i as usize], corner as usize % 3);
    let normal = mesh.normals.get(t.normal[k] as usize).is_some() && t.normal[k] != NO_ATTRIBUTE;
    let uv = mesh.uvs.get(t.uv[k] as usize).map_or(NONE, |_| t.uv[k]);
    let color = mesh
        .colors
        .get(t.color[k] as usize)
        .map_or(NONE, |_| t.color[k]);
    [
        if normal {
            t.normal[k] as u64
        } else {
            1 << 32 | p[k] as u64
        },
        (uv as u64) << 32 | color as u64,
    ]
}

/// The distinct attribute sets and each kept triangle's per corner.
///
/// The corners are looked up by their sources ([`SourceIds`]: 12 bytes a normal or
/// position, where a map from the sources would take 24), the distinct sets in a table of
/// ids that hashes what they point at (4 bytes an entry, where a map from their 36-byte keys
/// would take 40). On a mesh with a set per position these are the weld's
/// largest temporaries.
pub(super) fn corner_attributes(
    mesh: &Mesh,
    kept: &[Kept],
    positions: &[[f32; 3]],
    repairs: &mut Repairs,
) -> (Vec<Attributes>, Vec<[u32; 3]>) {
    let computed = area_normals(kept, positions);
    let min_cos = GEOMETRIC_NORMAL_DEGREES.to_radians().cos();
    let mut by_value: HashTable<u32> = HashTable::new();
    let mut first = SourceIds::new();
    let mut attributes: Vec<Attributes> = Vec::new();
    let mut tri_attrs: Vec<[u32; 3]> = Vec::with_capacity(kept.len());
    for (f, &(p, i)) in kept.iter().enumerate() {
        let t = &mesh.triangles[i as usize];
        let mut a = [0u32; 3];
        for k in 0..3 {
            let corner = (3 * f + k) as u32;
            let normal = mesh
                .normals
                .get(t.normal[k] as usize)
                .filter(|_| t.normal[k] != NO_ATTRIBUTE);
            if normal.is_none() {
                repairs.computed_normals += 1;
            }
            let src = (corner, source(mesh, kept, corner));
            a[k] = first.id(mesh, kept, positions.len(), src, || {
                let attrs = Attributes {
                    normal: normal
                        .copied()
                        .unwrap_or_else(|| normalize(computed[p[k] as usize])),
                    uv: mesh.uvs.get(t.uv[k] as usize).copied().unwrap_or([0.0; 2]),
                    color: mesh
                        .colors
                        .get(t.color[k] as usize)
                        .copied()
                        .unwrap_or([1.0; 4]),
                    normal_from_geometry: true,
                };
                distinct_id(&mut by_value, &mut attributes, attrs)
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
    (attributes, tri_attrs)
}

/// The attribute id of each source: a source is found by its normal's index, or, for a
/// normal computed here, by its position, in an array whose entry holds the id and the rest
/// of the first source found there (its UV's and colour's indices); the sources that share
/// that index with an earlier one (another UV or colour) are in a table that holds their
/// first corner and hashes what its source is rather than storing it.
struct SourceIds {
    by_normal: Vec<Slot>,
    by_position: Vec<Slot>,
    more: HashTable<(u32, u32)>,
}

/// An array entry of [`SourceIds`]: the id, and the UV's and colour's indices of the
/// source (`[NONE; 3]`: empty).
type Slot = [u32; 3];

impl SourceIds {
    fn new() -> Self {
        Self {
            by_normal: Vec::new(),
            by_position: Vec::new(),
            more: HashTable::new(),
        }
    }

    /// The array entry of source `src`, the array made on first use.
    fn slot(&mut self, mesh: &Mesh, positions: usize, src: [u64; 2]) -> &mut Slot {
        let (array, len) = if src[0] >> 32 == 0 {
            (&mut self.by_normal, mesh.normals.len())
        } else {
            (&mut self.by_position, positions)
        };
        if array.is_empty() {
            array.resize(len, [NONE; 3]);
        }
        &mut array[src[0] as u32 as usize]
    }

    /// The attribute id of source `src` (of `corner`), or the one `new` gives it when it is
    /// the first corner read from it.
    fn id(
        &mut self,
        mesh: &Mesh,
        kept: &[Kept],
        positions: usize,
        (corner, src): (u32, [u64; 2]),
        new: impl FnOnce() -> u32,
    ) -> u32 {
        let rest = [(src[1] >> 32) as u32, src[1] as u32];
        let slot = self.slot(mesh, positions, src);
        if slot[0] == NONE {
            let id = new();
            *slot = [id, rest[0], rest[1]];
            return id;
        }
        if slot[1..] == rest {
            return slot[0];
        }
        let entry = self.more.entry(
            hash_of(&src),
            |&(c, _)| source(mesh, kept, c) == src,
            |&(c, _)| hash_of(&source(mesh, kept, c)),
        );
        match entry {
            Entry::Occupied(e) => e.get().1,
            Entry::Vacant(v) => {
                let id = new();
                v.insert((corner, id));
                id
            }
        }
    }
}

/// The id of the set equal to `attrs` (by [`Attributes::key`]) in `attributes`, appended
/// when new; `table` holds every id of `attributes`.
fn distinct_id(
    table: &mut HashTable<u32>,
    attributes: &mut Vec<Attributes>,
    attrs: Attributes,
) -> u32 {
    let key = attrs.key();
    let entry = table.entry(
        hash_of(&key),
        |&id| attributes[id as usize].key() == key,
        |&id| hash_of(&attributes[id as usize].key()),
    );
    match entry {
        Entry::Occupied(e) => *e.get(),
        Entry::Vacant(v) => {
            attributes.push(attrs);
            let id = attributes.len() as u32 - 1;
            v.insert(id);
            id
        }
    }
}

/// The area-weighted normal of every position (unnormalised). The positions are split
/// into a range per thread, each going through all the triangles and summing those at its
/// positions in triangle order, so the sums do not depend on the threads.
fn area_normals(kept: &[Kept], positions: &[[f32; 3]]) -> Vec<[f64; 3]> {
    let mut computed = vec![[0f64; 3]; positions.len()];
    let per = positions
        .len()
        .div_ceil(rayon::current_num_threads())
        .max(1 << 16);
    computed
        .par_chunks_mut(per)
        .enumerate()
        .for_each(|(i, sums)| {
            let range = (i * per) as u32..(i * per + sums.len()) as u32;
            for &(p, _) in kept {
                if !p.iter().any(|v| range.contains(v)) {
                    continue;
                }
                let [a, b, c] = p.map(|x| positions[x as usize]);
                let n = cross(sub(b, a), sub(c, a));
                for v in p.iter().filter(|v| range.contains(v)) {
                    let sum = &mut sums[(v - range.start) as usize];
                    for k in 0..3 {
                        sum[k] += n[k];
                    }
                }
            }
        });
    computed
}
