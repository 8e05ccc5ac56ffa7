//! Mesh primitives: attributes and indices read, triangles assembled for the primitive's mode,
//! then everything appended to the mesh in the node's world frame.

use ::gltf::mesh::Mode;
use ::gltf::Semantic;

use super::importer::{Expect, Importer};
use super::scene::{Mat4, Placement};
use crate::import::error::ImportError;
use crate::import::ids::next_index;
use crate::mesh::{Triangle, NO_ATTRIBUTE};

/// Names a primitive's parts in errors and notes: "POSITION of mesh 'Tri' primitive 0".
struct Label<'a> {
    mesh: &'a str,
    primitive: usize,
}

impl Label<'_> {
    fn of(&self, semantic: &str) -> String {
        format!("{semantic} of {} primitive {}", self.mesh, self.primitive)
    }
}

/// One primitive's attribute values (`count` vertices each; colours with their 3 or 4
/// components) and its triangles as vertex indices.
struct Primitive {
    positions: Vec<f64>,
    normals: Option<Vec<f64>>,
    uvs: Option<Vec<f64>>,
    colors: Option<(Vec<f64>, usize)>,
    triangles: Vec<[u32; 3]>,
}

/// Where a primitive's first position, normal, UV and colour land in the mesh.
struct Bases {
    position: u32,
    normal: Option<u32>,
    uv: Option<u32>,
    color: Option<u32>,
}

impl Importer<'_> {
    pub(super) fn add_mesh(
        &mut self,
        mesh: &::gltf::Mesh<'_>,
        world: &Mat4,
    ) -> Result<(), ImportError> {
        let mesh_name = match mesh.name() {
            Some(n) => format!("mesh '{n}'"),
            None => format!("mesh {}", mesh.index()),
        };
        let placement = Placement::new(world);
        for primitive in mesh.primitives() {
            let label = Label {
                mesh: &mesh_name,
                primitive: primitive.index(),
            };
            if let Some(read) = self.read_primitive(&primitive, &label)? {
                let surface = self.surface(primitive.material().index())?;
                self.push_primitive(read, &placement, &label, surface)?;
            }
        }
        Ok(())
    }

    /// A triangle primitive's data; `None` for points, lines and primitives without
    /// POSITION (counted or noted).
    fn read_primitive(
        &mut self,
        primitive: &::gltf::Primitive<'_>,
        label: &Label<'_>,
    ) -> Result<Option<Primitive>, ImportError> {
        match primitive.mode() {
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan => {}
            Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip => {
                self.report.skipped_primitives += 1;
                return Ok(None);
            }
        }
        if primitive.morph_targets().next().is_some() {
            self.ignored_targets += 1;
        }
        let Some(positions) = primitive.get(&Semantic::Positions) else {
            self.report.notes.push(format!(
                "{}: {} has no POSITION and is skipped",
                self.source.name,
                label.of("primitive")
            ));
            return Ok(None);
        };
        let positions = self
            .read_attribute(
                positions.index(),
                &label.of("POSITION"),
                &Expect {
                    semantic: "POSITION",
                    dims: &[3],
                },
            )?
            .values;
        let count = positions.len() / 3;
        let optional = |semantic: Semantic, name: &'static str, dims: &'static [usize]| {
            let expect = Expect {
                semantic: name,
                dims,
            };
            self.read_optional(primitive, semantic, &expect, count, label)
        };
        let normals = optional(Semantic::Normals, "NORMAL", &[3])?.map(|(v, _)| v);
        let uvs = optional(Semantic::TexCoords(0), "TEXCOORD_0", &[2])?.map(|(v, _)| v);
        let colors = optional(Semantic::Colors(0), "COLOR_0", &[3, 4])?;
        let indices = self.read_index_list(primitive, count, label)?;
        let triangles = self.assemble(primitive.mode(), &indices, &label.of("indices"));
        Ok(Some(Primitive {
            positions,
            normals,
            uvs,
            colors,
            triangles,
        }))
    }

    /// An optional attribute's values and components per element, as many elements as
    /// POSITION has.
    fn read_optional(
        &self,
        primitive: &::gltf::Primitive<'_>,
        semantic: Semantic,
        expect: &Expect,
        count: usize,
        label: &Label<'_>,
    ) -> Result<Option<(Vec<f64>, usize)>, ImportError> {
        let Some(acc) = primitive.get(&semantic) else {
            return Ok(None);
        };
        let name = label.of(expect.semantic);
        let raw = self.read_attribute(acc.index(), &name, expect)?;
        let n = raw.values.len() / raw.dims;
        if n != count {
            return Err(self.source.malformed(
                self.accessor_label(acc.index(), &name),
                format!("{n} elements, POSITION has {count}"),
            ));
        }
        Ok(Some((raw.values, raw.dims)))
    }

    /// The index accessor's values, each checked against `count`; without one, every vertex
    /// in order.
    fn read_index_list(
        &self,
        primitive: &::gltf::Primitive<'_>,
        count: usize,
        label: &Label<'_>,
    ) -> Result<Vec<u32>, ImportError> {
        let Some(acc) = primitive.indices() else {
            let n = u32::try_from(count).map_err(|_| {
                self.source
                    .unsupported(label.of("POSITION"), "more than 2^32 vertices")
            })?;
            return Ok((0..n).collect());
        };
        let at = self.accessor_label(acc.index(), &label.of("indices"));
        let values = self.read_indices(acc.index(), &at)?;
        if let Some(&bad) = values.iter().find(|&&v| v as usize >= count) {
            return Err(self
                .source
                .out_of_range(at, "index", i64::from(bad), count, "vertices"));
        }
        Ok(values)
    }

    /// Appends the primitive's vertices and triangles to the mesh.
    fn push_primitive(
        &mut self,
        read: Primitive,
        placement: &Placement<'_>,
        label: &Label<'_>,
        surface: u16,
    ) -> Result<(), ImportError> {
        let bases = Bases {
            position: self.push_positions(&read.positions, placement, label)?,
            normal: read
                .normals
                .map(|n| self.push_normals(&n, placement))
                .transpose()?,
            uv: read.uvs.map(|uv| self.push_uvs(&uv)).transpose()?,
            color: read
                .colors
                .map(|(c, dims)| self.push_colors(&c, dims))
                .transpose()?,
        };
        self.push_triangles(read.triangles, placement.flip, &bases, surface);
        Ok(())
    }

    /// Positions in the world frame, which must stay finite; the index of the first.
    fn push_positions(
        &mut self,
        positions: &[f64],
        placement: &Placement<'_>,
        label: &Label<'_>,
    ) -> Result<u32, ImportError> {
        let count = positions.len() / 3;
        let base =
            next_index(self.source, self.mesh.positions.len() + count, "positions")? - count as u32;
        for p in positions.chunks_exact(3) {
            self.mesh
                .positions
                .push(placement.position([p[0], p[1], p[2]]));
        }
        if let Some((i, v)) = self.mesh.positions[base as usize..]
            .iter()
            .enumerate()
            .find_map(|(i, p)| p.iter().find(|v| !v.is_finite()).map(|v| (i, *v)))
        {
            return Err(self.source.non_finite(
                format!("{} vertex {i}", label.of("POSITION")),
                "position after the node transform",
                f64::from(v),
            ));
        }
        Ok(base)
    }

    fn push_normals(
        &mut self,
        normals: &[f64],
        placement: &Placement<'_>,
    ) -> Result<u32, ImportError> {
        let count = normals.len() / 3;
        let base =
            next_index(self.source, self.mesh.normals.len() + count, "normals")? - count as u32;
        for n in normals.chunks_exact(3) {
            self.mesh.normals.push(placement.normal(n));
        }
        Ok(base)
    }

    fn push_uvs(&mut self, uvs: &[f64]) -> Result<u32, ImportError> {
        let count = uvs.len() / 2;
        let base = next_index(self.source, self.mesh.uvs.len() + count, "UVs")? - count as u32;
        for uv in uvs.chunks_exact(2) {
            self.mesh.uvs.push([uv[0] as f32, uv[1] as f32]);
        }
        Ok(base)
    }

    /// RGB or RGBA colours (`dims` components), alpha 1 where absent.
    fn push_colors(&mut self, colors: &[f64], dims: usize) -> Result<u32, ImportError> {
        let count = colors.len() / dims;
        let base =
            next_index(self.source, self.mesh.colors.len() + count, "colours")? - count as u32;
        for c in colors.chunks_exact(dims) {
            let alpha = if dims == 4 { c[3] } else { 1.0 };
            self.mesh
                .colors
                .push([c[0] as f32, c[1] as f32, c[2] as f32, alpha as f32]);
        }
        Ok(base)
    }

    /// Triangles with every corner offset by its attribute's base, wound the other way when
    /// the node mirrors.
    fn push_triangles(
        &mut self,
        triangles: Vec<[u32; 3]>,
        flip: bool,
        bases: &Bases,
        surface: u16,
    ) {
        let at = |base: Option<u32>, corners: [u32; 3]| match base {
            Some(b) => corners.map(|i| b + i),
            None => [NO_ATTRIBUTE; 3],
        };
        for mut t in triangles {
            if flip {
                t.swap(1, 2);
            }
            self.mesh.triangles.push(Triangle {
                position: t.map(|i| bases.position + i),
                normal: at(bases.normal, t),
                uv: at(bases.uv, t),
                color: at(bases.color, t),
                surface,
            });
        }
    }

    /// Index list to triangles for the primitive's mode.
    fn assemble(&mut self, mode: Mode, indices: &[u32], label: &str) -> Vec<[u32; 3]> {
        let mut out = Vec::new();
        match mode {
            Mode::Triangles => {
                let whole = indices.chunks_exact(3);
                if !whole.remainder().is_empty() {
                    self.report.notes.push(format!(
                        "{}: {label}: {} indices is not a multiple of 3; the last {} ignored",
                        self.source.name,
                        indices.len(),
                        whole.remainder().len()
                    ));
                }
                out.extend(whole.map(|t| [t[0], t[1], t[2]]));
            }
            Mode::TriangleStrip => {
                for i in 0..indices.len().saturating_sub(2) {
                    let t = if i % 2 == 0 {
                        [indices[i], indices[i + 1], indices[i + 2]]
                    } else {
                        [indices[i], indices[i + 2], indices[i + 1]]
                    };
                    self.push_nondegenerate(&mut out, t);
                }
            }
            Mode::TriangleFan => {
                for i in 1..indices.len().saturating_sub(1) {
                    self.push_nondegenerate(&mut out, [indices[0], indices[i], indices[i + 1]]);
                }
            }
            _ => {}
        }
        out
    }

    fn push_nondegenerate(&mut self, out: &mut Vec<[u32; 3]>, t: [u32; 3]) {
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            self.strip_joints += 1;
        } else {
            out.push(t);
        }
    }
}
