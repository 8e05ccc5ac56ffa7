//! The attributes of every corner, deduplicated (before the groups, which compare them).
//! A missing normal is the area-weighted normal at the position, which also tells which
//! given normals follow from the geometry.

use super::repair::Kept;
use super::{Attributes, Repairs, GEOMETRIC_NORMAL_DEGREES, NONE};
use crate::fxhash::{map_with_capacity, FxHashMap};
use crate::mesh::{Mesh, NO_ATTRIBUTE};

pub(super) fn sub(a: [f32; 3], b: [f32; 3]) -> [f64; 3] {
    [
        (a[0] - b[0]) as f64,
        (a[1] - b[1]) as f64,
        (a[2] - b[2]) as f64,
    ]
}

pub(super) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub(super) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub(super) fn normalize(v: [f64; 3]) -> [f32; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if l > 0.0 {
        [(v[0] / l) as f32, (v[1] / l) as f32, (v[2] / l) as f32]
    } else {
        [0.0, 0.0, 1.0]
    }
}

/// The distinct attribute sets and each kept triangle's per corner.
pub(super) fn corner_attributes(
    mesh: &Mesh,
    kept: &[Kept],
    positions: &[[f32; 3]],
    repairs: &mut Repairs,
) -> (Vec<Attributes>, Vec<[u32; 3]>) {
    let computed = area_normals(kept, positions);
    let min_cos = GEOMETRIC_NORMAL_DEGREES.to_radians().cos();
    let mut attr_ids: FxHashMap<[u32; 9], u32> = map_with_capacity(0);
    // Corners with the same sources (normal or, for a computed one, position; UV; colour)
    // have the same attributes: look those up once.
    let mut by_source: FxHashMap<[u64; 2], u32> = map_with_capacity(positions.len());
    let mut attributes: Vec<Attributes> = Vec::new();
    let mut tri_attrs: Vec<[u32; 3]> = Vec::with_capacity(kept.len());
    for &(p, i) in kept {
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
    (attributes, tri_attrs)
}

/// The area-weighted normal of every position (unnormalised).
fn area_normals(kept: &[Kept], positions: &[[f32; 3]]) -> Vec<[f64; 3]> {
    let mut computed = vec![[0f64; 3]; positions.len()];
    for &(p, _) in kept {
        let [a, b, c] = p.map(|x| positions[x as usize]);
        let n = cross(sub(b, a), sub(c, a));
        for &v in &p {
            for k in 0..3 {
                computed[v as usize][k] += n[k];
            }
        }
    }
    computed
}
