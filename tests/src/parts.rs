//! Generated CAD-style part soups: many separate box parts that touch face to face without
//! sharing vertices (each face a grid of its own vertices with a flat normal, as CAD
//! exporters write them), many materials, and meshes instanced by several nodes with
//! transforms. Touching faces coincide partly or wholly, so welding merges some of their
//! positions, drops duplicate triangles and cuts non-manifold edges, and the surface groups
//! end at every face: what real assemblies bring to the baker.
//!
//! A soup is written as a glTF file ([`PartSoup::write_gltf`], the path users take) or made
//! directly into an imported mesh ([`PartSoup::to_mesh`], the same world positions).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use caveclod_bake::mesh::{Mesh, Surface, Triangle, NO_ATTRIBUTE};

use caveclod_bake::generate::SplitMix64;

/// One axis-aligned box part with its faces' grid resolution and its material.
#[derive(Clone, Debug, PartialEq)]
pub struct Part {
    /// Lowest corner.
    pub min: [f32; 3],
    /// Highest corner.
    pub max: [f32; 3],
    /// Grid cells along each axis (at least 1).
    pub cells: [u32; 3],
    /// Material index.
    pub material: u16,
    /// Shaded smooth, as CAD exports curved parts: every corner at a point gets the same
    /// normal (from the box's centre) and UV, so the part is one surface group; otherwise
    /// each face is flat, with a normal and UVs of its own.
    pub smooth: bool,
}

/// One instance of a mesh: a node with a transform.
#[derive(Clone, Debug, PartialEq)]
pub struct Instance {
    /// The mesh it draws.
    pub mesh: usize,
    /// Quarter turns about +Y (0..4), applied before the translation.
    pub quarter_turns: u8,
    /// Translation.
    pub translation: [f32; 3],
}

/// Meshes of touching parts, instanced by nodes.
#[derive(Clone, Debug, PartialEq)]
pub struct PartSoup {
    /// Each mesh's parts (one glTF primitive each).
    pub meshes: Vec<Vec<Part>>,
    /// The nodes drawing the meshes.
    pub instances: Vec<Instance>,
    /// Number of materials.
    pub materials: u16,
}

/// How big a [`PartSoup`] is made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SoupShape {
    /// Meshes.
    pub meshes: usize,
    /// Parts per mesh, at most (at least 1 each).
    pub parts: usize,
    /// Instances (every mesh is drawn at least once when there are enough).
    pub instances: usize,
    /// Materials.
    pub materials: u16,
    /// Grid cells per box edge, at most.
    pub cells: u32,
}

impl SoupShape {
    /// The traits of a CAD assembly that hung the baker: 29 meshes instanced by 82 nodes, 34
    /// materials, many small parts (about 80k triangles): thousands of edges are left that no
    /// collapse may take, as a real assembly leaves them.
    pub const CAD_ASSEMBLY: Self = Self {
        meshes: 29,
        parts: 40,
        instances: 82,
        materials: 34,
        cells: 3,
    };
}

/// A coordinate on the quarter-unit lattice, so that touching faces coincide exactly.
fn quarter(rng: &mut SplitMix64, lo: u32, hi: u32) -> f32 {
    (lo + rng.below((hi - lo + 1) as usize) as u32) as f32 * 0.25
}

impl PartSoup {
    /// A random soup of the given shape, reproducible from `seed`.
    pub fn generate(shape: &SoupShape, seed: u64) -> Self {
        let mut rng = SplitMix64::new(seed);
        let materials = shape.materials.max(1);
        let meshes: Vec<Vec<Part>> = (0..shape.meshes.max(1))
            .map(|_| assembly(&mut rng, shape, materials))
            .collect();
        let instances = place_instances(&mut rng, &meshes, shape.instances.max(1));
        Self {
            meshes,
            instances,
            materials,
        }
    }

    /// Triangles of one drawing of every instance.
    pub fn triangle_count(&self) -> usize {
        self.instances
            .iter()
            .map(|i| {
                self.meshes[i.mesh]
                    .iter()
                    .map(part_triangles)
                    .sum::<usize>()
            })
            .sum()
    }

    /// The soup as an imported mesh: every instance's parts in world space, per-corner flat
    /// normals, planar UVs, one surface per material.
    pub fn to_mesh(&self) -> Mesh {
        let mut m = Mesh {
            surfaces: (0..self.materials)
                .map(|i| Surface::plain(format!("material {i}")))
                .collect(),
            ..Mesh::default()
        };
        for inst in &self.instances {
            for part in &self.meshes[inst.mesh] {
                let g = part_geometry(part);
                let base = m.positions.len() as u32;
                m.positions
                    .extend(g.positions.iter().map(|&p| inst.apply(p)));
                m.normals.extend(g.normals.iter().map(|&n| inst.rotate(n)));
                m.uvs.extend_from_slice(&g.uvs);
                for t in g.indices.chunks(3) {
                    let i = [t[0], t[1], t[2]].map(|i| base + i);
                    m.triangles.push(Triangle {
                        position: i,
                        normal: i,
                        uv: i,
                        color: [NO_ATTRIBUTE; 3],
                        surface: part.material,
                    });
                }
            }
        }
        m
    }

    /// Writes the soup as `dir/<name>.gltf` with its buffer `dir/<name>.bin`: one glTF mesh
    /// per mesh (a primitive per part, with its material), one node per instance (a
    /// translation, or a matrix for a turned one) under a root node; returns the glTF's
    /// path.
    pub fn write_gltf(&self, dir: &Path, name: &str) -> std::io::Result<PathBuf> {
        let mut bin: Vec<u8> = Vec::new();
        let (mut views, mut accessors, mut meshes) = (String::new(), String::new(), String::new());
        let mut n_views = 0usize;
        let mut view = |bin: &mut Vec<u8>, data: &[u8], views: &mut String| {
            let sep = if n_views == 0 { "" } else { "," };
            let _ = write!(
                views,
                r#"{sep}{{"buffer":0,"byteOffset":{},"byteLength":{}}}"#,
                bin.len(),
                data.len()
            );
            bin.extend_from_slice(data);
            n_views += 1;
            n_views - 1
        };
        let mut n_accessors = 0usize;
        for (mi, parts) in self.meshes.iter().enumerate() {
            let mut primitives = String::new();
            for (pi, part) in parts.iter().enumerate() {
                let g = part_geometry(part);
                let bytes = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<_>>();
                let p = view(&mut bin, &bytes(g.positions.as_flattened()), &mut views);
                let n = view(&mut bin, &bytes(g.normals.as_flattened()), &mut views);
                let t = view(&mut bin, &bytes(g.uvs.as_flattened()), &mut views);
                let idx: Vec<u8> = g.indices.iter().flat_map(|i| i.to_le_bytes()).collect();
                let i = view(&mut bin, &idx, &mut views);
                let count = g.positions.len();
                let sep = if n_accessors == 0 { "" } else { "," };
                let first = n_accessors;
                let _ = write!(
                    accessors,
                    r#"{sep}{{"bufferView":{p},"componentType":5126,"count":{count},"type":"VEC3","min":{:?},"max":{:?}}},{{"bufferView":{n},"componentType":5126,"count":{count},"type":"VEC3"}},{{"bufferView":{t},"componentType":5126,"count":{count},"type":"VEC2"}},{{"bufferView":{i},"componentType":5125,"count":{},"type":"SCALAR"}}"#,
                    part.min,
                    part.max,
                    g.indices.len()
                );
                n_accessors += 4;
                let sep = if pi == 0 { "" } else { "," };
                let _ = write!(
                    primitives,
                    r#"{sep}{{"attributes":{{"POSITION":{first},"NORMAL":{},"TEXCOORD_0":{}}},"indices":{},"material":{}}}"#,
                    first + 1,
                    first + 2,
                    first + 3,
                    part.material
                );
            }
            let sep = if mi == 0 { "" } else { "," };
            let _ = write!(
                meshes,
                r#"{sep}{{"name":"mesh {mi}","primitives":[{primitives}]}}"#
            );
        }
        let mut nodes = String::new();
        let children: Vec<String> = (1..=self.instances.len()).map(|i| i.to_string()).collect();
        let _ = write!(
            nodes,
            r#"{{"name":"assembly","children":[{}]}}"#,
            children.join(",")
        );
        for inst in &self.instances {
            let [x, y, z] = inst.translation;
            if inst.quarter_turns % 4 == 0 {
                let _ = write!(
                    nodes,
                    r#",{{"mesh":{},"translation":[{x:?},{y:?},{z:?}]}}"#,
                    inst.mesh
                );
            } else {
                // Column-major; exact, where a quaternion's matrix would round.
                let [c0, _, c2] =
                    [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]].map(|e| inst.rotate(e));
                let _ = write!(
                    nodes,
                    r#",{{"mesh":{},"matrix":[{:?},{:?},{:?},0,0,1,0,0,{:?},{:?},{:?},0,{x:?},{y:?},{z:?},1]}}"#,
                    inst.mesh, c0[0], c0[1], c0[2], c2[0], c2[1], c2[2]
                );
            }
        }
        let materials: Vec<String> = (0..self.materials)
            .map(|i| {
                let c = [i % 3, (i / 3) % 3, (i / 9) % 3].map(|k| 0.2 + 0.3 * f32::from(k));
                format!(
                    r#"{{"name":"material {i}","pbrMetallicRoughness":{{"baseColorFactor":[{:?},{:?},{:?},1.0]}}}}"#,
                    c[0], c[1], c[2]
                )
            })
            .collect();
        let gltf = format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{nodes}],"meshes":[{meshes}],"materials":[{}],"buffers":[{{"uri":"{name}.bin","byteLength":{}}}],"bufferViews":[{views}],"accessors":[{accessors}]}}"#,
            materials.join(","),
            bin.len()
        );
        std::fs::write(dir.join(format!("{name}.bin")), &bin)?;
        let path = dir.join(format!("{name}.gltf"));
        std::fs::write(&path, gltf)?;
        Ok(path)
    }
}

impl Instance {
    /// A direction turned by the instance's quarter turns about +Y.
    fn rotate(&self, p: [f32; 3]) -> [f32; 3] {
        let mut p = p;
        for _ in 0..self.quarter_turns % 4 {
            // +90° about Y: x' = z, z' = -x.
            p = [p[2], p[1], -p[0]];
        }
        p
    }

    /// A point in the world.
    fn apply(&self, p: [f32; 3]) -> [f32; 3] {
        let r = self.rotate(p);
        [0, 1, 2].map(|k| r[k] + self.translation[k])
    }
}

/// A mesh of touching parts: the first a box at the origin, each next one against a face
/// of an earlier one, shifted along that face so the two faces overlap partly or wholly.
fn assembly(rng: &mut SplitMix64, shape: &SoupShape, materials: u16) -> Vec<Part> {
    let count = 1 + rng.below(shape.parts.max(1));
    let mut parts: Vec<Part> = Vec::with_capacity(count);
    let max_cells = shape.cells.max(1);
    for _ in 0..count {
        let size = [0; 3].map(|_| quarter(rng, 2, 12));
        let cells = [0; 3].map(|_| 1 + rng.below(max_cells as usize) as u32);
        let material = rng.below(usize::from(materials)) as u16;
        let smooth = rng.below(2) == 1;
        let min = match parts.len() {
            0 => [0.0; 3],
            n => {
                let other = &parts[rng.below(n)];
                let axis = rng.below(3);
                let high = rng.below(2) == 1;
                let mut min = [0.0; 3];
                for k in 0..3 {
                    min[k] = if k == axis {
                        if high {
                            other.max[k]
                        } else {
                            other.min[k] - size[k]
                        }
                    } else {
                        // Overlapping along the face: from flush with its low side to
                        // half past it.
                        other.min[k] + quarter(rng, 0, 4) - quarter(rng, 0, 2)
                    };
                }
                min
            }
        };
        let max = [0, 1, 2].map(|k| min[k] + size[k]);
        parts.push(Part {
            min,
            max,
            cells,
            material,
            smooth,
        });
    }
    parts
}

/// Every mesh once, then random ones, in rows of touching bounding boxes (some turned).
fn place_instances(rng: &mut SplitMix64, meshes: &[Vec<Part>], count: usize) -> Vec<Instance> {
    let per_row = (count as f64).sqrt().ceil() as usize;
    let (mut x, mut z, mut row_depth) = (0.0f32, 0.0f32, 0.0f32);
    let mut out = Vec::with_capacity(count);
    for i in 0..count {
        let mesh = if i < meshes.len() {
            i
        } else {
            rng.below(meshes.len())
        };
        let mut inst = Instance {
            mesh,
            quarter_turns: rng.below(4) as u8,
            translation: [0.0; 3],
        };
        let (lo, hi) = bounds(&meshes[mesh], &inst);
        if i > 0 && i % per_row == 0 {
            z += row_depth;
            x = 0.0;
            row_depth = 0.0;
        }
        // Its bounding box's low corner at the cursor: it touches the previous one.
        inst.translation = [x - lo[0], -lo[1], z - lo[2]];
        x += hi[0] - lo[0];
        row_depth = row_depth.max(hi[2] - lo[2]);
        out.push(inst);
    }
    out
}

/// The bounding box of a mesh's parts turned by an instance (before its translation).
fn bounds(parts: &[Part], inst: &Instance) -> ([f32; 3], [f32; 3]) {
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for p in parts {
        for corner in 0..8 {
            let c = [0, 1, 2].map(|k| {
                if corner >> k & 1 == 0 {
                    p.min[k]
                } else {
                    p.max[k]
                }
            });
            let r = inst.rotate(c);
            for k in 0..3 {
                lo[k] = lo[k].min(r[k]);
                hi[k] = hi[k].max(r[k]);
            }
        }
    }
    (lo, hi)
}

/// A part's triangles: two per grid cell on each of its six faces.
fn part_triangles(p: &Part) -> usize {
    let [a, b, c] = p.cells.map(|n| n as usize);
    4 * (a * b + b * c + c * a)
}

/// A part's vertices (its own on every face), normals, UVs and indices.
struct Geometry {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    uvs: Vec<[f32; 2]>,
    indices: Vec<u32>,
}

/// The six faces of a box, each a grid of its own vertices with the face's normal,
/// counter-clockwise seen from outside.
fn part_geometry(p: &Part) -> Geometry {
    let mut g = Geometry {
        positions: Vec::new(),
        normals: Vec::new(),
        uvs: Vec::new(),
        indices: Vec::new(),
    };
    let centre = [0, 1, 2].map(|k| (p.min[k] + p.max[k]) * 0.5);
    for axis in 0..3 {
        let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
        let (nb, nc) = (p.cells[b], p.cells[c]);
        for high in [false, true] {
            let base = g.positions.len() as u32;
            let mut normal = [0.0; 3];
            normal[axis] = if high { 1.0 } else { -1.0 };
            for j in 0..=nc {
                for i in 0..=nb {
                    let mut q = [0.0f32; 3];
                    q[axis] = if high { p.max[axis] } else { p.min[axis] };
                    q[b] = lerp(p.min[b], p.max[b], i, nb);
                    q[c] = lerp(p.min[c], p.max[c], j, nc);
                    g.positions.push(q);
                    if p.smooth {
                        g.normals.push(norm([0, 1, 2].map(|k| q[k] - centre[k])));
                        g.uvs.push([(q[0] + q[2]) * 0.1, q[1] * 0.1]);
                    } else {
                        g.normals.push(normal);
                        g.uvs.push([i as f32 / nb as f32, j as f32 / nc as f32]);
                    }
                }
            }
            let at = |i: u32, j: u32| base + j * (nb + 1) + i;
            for j in 0..nc {
                for i in 0..nb {
                    let (q00, q10, q11, q01) =
                        (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                    // (b, c, axis) is right-handed: b → c turns counter-clockwise about +axis.
                    let quads = if high {
                        [q00, q10, q11, q00, q11, q01]
                    } else {
                        [q00, q11, q10, q00, q01, q11]
                    };
                    g.indices.extend_from_slice(&quads);
                }
            }
        }
    }
    g
}

/// `v` scaled to unit length.
fn norm(v: [f32; 3]) -> [f32; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    v.map(|x| x / l)
}

/// `lo + (hi - lo) · i / n`, exact at both ends.
fn lerp(lo: f32, hi: f32, i: u32, n: u32) -> f32 {
    if i == n {
        return hi;
    }
    (f64::from(lo) + (f64::from(hi) - f64::from(lo)) * f64::from(i) / f64::from(n)) as f32
}
