//! Generated test meshes in memory: a heightfield terrain with two surfaces and a texture
//! seam, the same with a hole, and a closed bumpy sphere with two surfaces; [`to_mesh`] makes
//! one an imported [`Mesh`], the input the bake takes.

use crate::mesh::{Mesh, Surface, Triangle, NO_ATTRIBUTE};

/// One triangle: three positions (counter-clockwise seen from outside), a surface and the
/// attributes of its corners.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tri {
    /// Position indices.
    pub p: [u32; 3],
    /// Surface (material).
    pub surface: u16,
    /// Per-corner normals.
    pub normal: [[f32; 3]; 3],
    /// Per-corner texture coordinates.
    pub uv: [[f32; 2]; 3],
}

/// A triangle mesh with per-corner attributes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TestMesh {
    /// Unique points.
    pub positions: Vec<[f32; 3]>,
    /// Triangles.
    pub triangles: Vec<Tri>,
}

impl TestMesh {
    /// Number of distinct surfaces.
    pub fn surface_count(&self) -> u16 {
        self.triangles
            .iter()
            .map(|t| t.surface + 1)
            .max()
            .unwrap_or(0)
    }
}

/// The generators' random numbers ([`SplitMix64`](super::rng::SplitMix64)) under the name
/// the mesh users know.
pub use super::rng::SplitMix64 as Rng;

/// A test mesh as an imported mesh: per-corner normal and UV streams (so seams stay seams),
/// no colours, one surface per distinct surface id.
pub fn to_mesh(t: &TestMesh) -> Mesh {
    let mut m = Mesh {
        positions: t.positions.clone(),
        ..Mesh::default()
    };
    for tri in &t.triangles {
        let mut out = Triangle {
            position: tri.p,
            normal: [0; 3],
            uv: [0; 3],
            color: [NO_ATTRIBUTE; 3],
            surface: tri.surface,
        };
        for k in 0..3 {
            out.normal[k] = m.normals.len() as u32;
            m.normals.push(tri.normal[k]);
            out.uv[k] = m.uvs.len() as u32;
            m.uvs.push(tri.uv[k]);
        }
        m.triangles.push(out);
    }
    m.surfaces = (0..t.surface_count())
        .map(|s| Surface::plain(format!("s{s}")))
        .collect();
    m
}

/// Fractal sum of sines: multi-scale relief, so refinement has work at every scale.
fn height(x: f32, z: f32, size: f32, waves: &[(f32, f32, f32, f32, f32)]) -> f32 {
    let mut h = 0.0;
    for &(amp, fx, fz, px, pz) in waves {
        h += amp * (fx * x / size + px).sin() * (fz * z / size + pz).sin();
    }
    h
}

fn waves(size: f32, seed: u64) -> Vec<(f32, f32, f32, f32, f32)> {
    let mut rng = Rng(seed);
    let mut out = Vec::new();
    let mut amp = 0.08 * size;
    let mut freq = 3.0;
    for _ in 0..9 {
        out.push((
            amp,
            freq * (0.7 + 0.6 * rng.unit()),
            freq * (0.7 + 0.6 * rng.unit()),
            std::f32::consts::TAU * rng.unit(),
            std::f32::consts::TAU * rng.unit(),
        ));
        amp *= 0.5;
        freq *= 2.0;
    }
    out
}

fn normalize(v: [f32; 3]) -> [f32; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if l > 0.0 {
        [v[0] / l, v[1] / l, v[2] / l]
    } else {
        [0.0, 1.0, 0.0]
    }
}

/// A heightfield of `nx × ny` cells (`2·nx·ny` triangles) over `[0, nx] × [0, ny]` in x and z,
/// y up. Columns left of `nx / 2` are surface 0, the rest surface 1; each surface maps its own
/// texture, so the seam column has two UVs per position (a real texture seam). The outer
/// rim is a mesh border.
pub fn terrain(nx: u32, ny: u32, seed: u64) -> TestMesh {
    terrain_with(nx, ny, seed, |_, _| true)
}

/// [`terrain`] without the cells inside a circle around the centre and without one corner
/// cell: borders inside the mesh and irregular outer borders.
pub fn holed_terrain(nx: u32, ny: u32, seed: u64) -> TestMesh {
    let (cx, cy, r) = (nx as f32 * 0.5, ny as f32 * 0.5, nx.min(ny) as f32 * 0.2);
    terrain_with(nx, ny, seed, move |i, j| {
        let (dx, dy) = (i as f32 + 0.5 - cx, j as f32 + 0.5 - cy);
        dx * dx + dy * dy > r * r && !(i == 0 && j == 0)
    })
}

fn terrain_with(nx: u32, ny: u32, seed: u64, keep: impl Fn(u32, u32) -> bool) -> TestMesh {
    let size = nx.max(ny) as f32;
    let w = waves(size, seed);
    let idx = |i: u32, j: u32| j * (nx + 1) + i;
    let mut used = vec![false; ((nx + 1) * (ny + 1)) as usize];
    for j in 0..ny {
        for i in 0..nx {
            if keep(i, j) {
                for (a, b) in [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)] {
                    used[idx(a, b) as usize] = true;
                }
            }
        }
    }
    // Compact the positions actually used.
    let mut remap = vec![u32::MAX; used.len()];
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            if !used[idx(i, j) as usize] {
                continue;
            }
            let (x, z) = (i as f32, j as f32);
            let y = height(x, z, size, &w);
            let e = 0.5;
            let dx = height(x + e, z, size, &w) - height(x - e, z, size, &w);
            let dz = height(x, z + e, size, &w) - height(x, z - e, size, &w);
            remap[idx(i, j) as usize] = positions.len() as u32;
            positions.push([x, y, z]);
            normals.push(normalize([-dx, 2.0 * e, -dz]));
        }
    }
    let half = nx / 2;
    let mut triangles = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            if !keep(i, j) {
                continue;
            }
            let surface = u16::from(i >= half);
            let u0 = if surface == 0 { 0.0 } else { half as f32 };
            let span = if surface == 0 {
                half.max(1)
            } else {
                (nx - half).max(1)
            } as f32;
            let corner = |a: u32, b: u32| {
                let p = remap[idx(a, b) as usize];
                (
                    p,
                    normals[p as usize],
                    [(a as f32 - u0) / span, b as f32 / ny as f32],
                )
            };
            let (a, b, c, d) = (
                corner(i, j),
                corner(i + 1, j),
                corner(i + 1, j + 1),
                corner(i, j + 1),
            );
            for [x, y, z] in [[a, d, b], [b, d, c]] {
                triangles.push(Tri {
                    p: [x.0, y.0, z.0],
                    surface,
                    normal: [x.1, y.1, z.1],
                    uv: [x.2, y.2, z.2],
                });
            }
        }
    }
    TestMesh {
        positions,
        triangles,
    }
}

/// A closed, bumpy icosphere (`20 · 4^subdivisions` triangles) of radius about 1: the upper
/// half is surface 0, the lower half surface 1 (a material boundary around the equator).
pub fn sphere(subdivisions: u32) -> TestMesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut pts: Vec<[f32; 3]> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|&p| normalize(p))
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut mid = std::collections::HashMap::new();
        let mut next = Vec::with_capacity(faces.len() * 4);
        let mut midpoint = |a: u32, b: u32, pts: &mut Vec<[f32; 3]>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let (p, q) = (pts[a as usize], pts[b as usize]);
                pts.push(normalize([p[0] + q[0], p[1] + q[1], p[2] + q[2]]));
                pts.len() as u32 - 1
            })
        };
        for f in &faces {
            let ab = midpoint(f[0], f[1], &mut pts);
            let bc = midpoint(f[1], f[2], &mut pts);
            let ca = midpoint(f[2], f[0], &mut pts);
            next.extend([[f[0], ab, ca], [f[1], bc, ab], [f[2], ca, bc], [ab, bc, ca]]);
        }
        faces = next;
    }
    let bump =
        |p: [f32; 3]| 1.0 + 0.08 * (5.0 * p[0]).sin() * (4.0 * p[1]).sin() * (6.0 * p[2]).cos();
    let normals: Vec<[f32; 3]> = pts.clone();
    let positions: Vec<[f32; 3]> = pts
        .iter()
        .map(|&p| {
            let r = bump(p);
            [p[0] * r, p[1] * r, p[2] * r]
        })
        .collect();
    let triangles = faces
        .iter()
        .map(|f| {
            let cy: f32 = f.iter().map(|&i| positions[i as usize][1]).sum();
            let surface = u16::from(cy < 0.0);
            let uv = f.map(|i| {
                let p = positions[i as usize];
                [p[0] * 0.5 + 0.5, p[2] * 0.5 + 0.5]
            });
            Tri {
                p: *f,
                surface,
                normal: f.map(|i| normals[i as usize]),
                uv,
            }
        })
        .collect();
    TestMesh {
        positions,
        triangles,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn terrain_counts_and_winding() {
        let m = terrain(8, 6, 3);
        assert_eq!(m.triangles.len(), 96);
        assert_eq!(m.positions.len(), 63);
        assert_eq!(m.surface_count(), 2);
        for t in &m.triangles {
            let [a, b, c] = t.p.map(|i| m.positions[i as usize]);
            let (u, v) = (
                [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
                [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
            );
            let ny = u[2] * v[0] - u[0] * v[2];
            assert!(ny > 0.0, "faces point up");
        }
    }

    #[test]
    fn sphere_is_closed() {
        let m = sphere(2);
        assert_eq!(m.triangles.len(), 320);
        let mut edges = std::collections::HashMap::new();
        for t in &m.triangles {
            for k in 0..3 {
                *edges.entry((t.p[k], t.p[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        for (&(a, b), &n) in &edges {
            assert_eq!(n, 1);
            assert_eq!(edges.get(&(b, a)), Some(&1), "every edge has its twin");
        }
    }

    #[test]
    fn an_imported_mesh_keeps_corners_and_surfaces() {
        let t = terrain(4, 3, 2);
        let m = to_mesh(&t);
        assert_eq!(m.positions, t.positions);
        assert_eq!(m.triangles.len(), t.triangles.len());
        assert_eq!(m.surfaces.len(), 2);
        for (a, b) in m.triangles.iter().zip(&t.triangles) {
            assert_eq!(a.position, b.p);
            assert_eq!(a.surface, b.surface);
            for k in 0..3 {
                assert_eq!(m.normals[a.normal[k] as usize], b.normal[k]);
                assert_eq!(m.uvs[a.uv[k] as usize], b.uv[k]);
            }
        }
    }

    #[test]
    fn holed_terrain_drops_cells() {
        let full = terrain(20, 20, 1);
        let holed = holed_terrain(20, 20, 1);
        assert!(holed.triangles.len() < full.triangles.len() - 40);
    }
}
