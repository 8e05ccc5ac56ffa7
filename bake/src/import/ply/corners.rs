//! The vertices' attributes a PLY header declares ([`Present`]), and the corners of the
//! triangles read from its faces and strips ([`Corners`]).

use ply_rs_bw::ply::{Header, PropertyType};

use super::properties::{byte_colour, is_index_list, Face};
use crate::base::colour::srgb_to_linear;
use crate::base::ply::vertex_slot;
use crate::import::error::{ImportError, Source};
use crate::import::ids::next_index;
use crate::import::options::ImportReport;
use crate::mesh::{Mesh, Triangle, NO_ATTRIBUTE};

#[derive(Clone, Copy)]
/// The optional vertex attributes the file has (all their components).
pub(super) struct Present {
    pub(super) normals: bool,
    pub(super) uvs: bool,
    pub(super) colors: bool,
}

impl Present {
    /// Checks the elements the importer reads (a `vertex` element with scalar `x y z`; index
    /// lists on faces and strips) and finds the optional attributes.
    /// The attributes of the header's vertices, after checking the header has what a mesh
    /// needs.
    pub(super) fn check(source: &Source, header: &Header) -> Result<Self, ImportError> {
        let vertex_def = header
            .elements
            .get("vertex")
            .ok_or_else(|| source.malformed("header", "no 'vertex' element"))?;
        let has = |name: &str| {
            vertex_def
                .properties
                .keys()
                .any(|k| vertex_slot(k) == vertex_slot(name))
        };
        for axis in ["x", "y", "z"] {
            if !has(axis) {
                return Err(source.malformed("element 'vertex'", format!("no '{axis}' property")));
            }
        }
        for (name, property) in &vertex_def.properties {
            if vertex_slot(name).is_some() && !matches!(property.data_type, PropertyType::Scalar(_))
            {
                return Err(source.malformed(
                    "element 'vertex'",
                    format!("property '{name}' is a list, not a number"),
                ));
            }
        }
        let present = Present {
            normals: has("nx") && has("ny") && has("nz"),
            uvs: has("u") && has("v"),
            colors: has("red") && has("green") && has("blue"),
        };
        for def in header.elements.values() {
            if (def.name == "face" || def.name == "tristrips")
                && !def.properties.keys().any(|k| is_index_list(k))
            {
                return Err(source.malformed(
                    format!("element '{}'", def.name),
                    "no 'vertex_indices' list",
                ));
            }
        }
        Ok(present)
    }
}

/// Turns vertices into positions and attributes, faces and strips into triangles: vertex
/// indices checked, per-vertex attributes sharing the position's index.
pub(super) struct Corners<'a> {
    pub(super) source: &'a Source,
    pub(super) vertex_count: usize,
    pub(super) present: Present,
    pub(super) surface: u16,
    /// A face's corners, reused from face to face.
    pub(super) face: Vec<u32>,
    /// The linear value of each 8-bit colour channel ([`Self::linear`]).
    pub(super) byte_linear: [f32; 256],
}

impl<'a> Corners<'a> {
    pub(super) fn new(source: &'a Source, vertex_count: usize, present: Present) -> Self {
        Corners {
            source,
            vertex_count,
            present,
            surface: 0,
            face: Vec::new(),
            byte_linear: std::array::from_fn(|k| srgb_to_linear(byte_colour(k))),
        }
    }

    /// Whether `index` names a vertex.
    pub(super) fn in_range(&self, index: i64) -> bool {
        (0..self.vertex_count as i64).contains(&index)
    }

    pub(super) fn vertex(&self, at: &dyn Fn() -> String, index: i64) -> Result<u32, ImportError> {
        if self.in_range(index) {
            Ok(index as u32)
        } else {
            Err(self.source.out_of_range(
                at(),
                "vertex index",
                index,
                self.vertex_count,
                "vertices",
            ))
        }
    }

    pub(super) fn vertices(
        &self,
        at: &dyn Fn() -> String,
        indices: &[i64],
    ) -> Result<Vec<u32>, ImportError> {
        indices.iter().map(|&i| self.vertex(at, i)).collect()
    }

    /// A triangle whose attributes share the position's indices (where present); `uv`
    /// overrides the UVs.
    pub(super) fn triangle(&self, position: [u32; 3], uv: Option<[u32; 3]>) -> Triangle {
        let same = |present: bool| position.map(|i| if present { i } else { NO_ATTRIBUTE });
        Triangle {
            position,
            normal: same(self.present.normals),
            uv: uv.unwrap_or_else(|| same(self.present.uvs)),
            color: same(self.present.colors),
            surface: self.surface,
        }
    }

    /// Face `f` (its vertex `indices`, and per-corner UVs `texcoord` or none) as a fan; a
    /// face under three vertices skipped and counted.
    pub(super) fn push_face(
        &mut self,
        mesh: &mut Mesh,
        f: usize,
        indices: &[i64],
        texcoord: &[f32],
        report: &mut ImportReport,
    ) -> Result<(), ImportError> {
        let at = || format!("face {f}");
        let n = indices.len();
        if n < 3 {
            report.skipped_primitives += 1;
            return Ok(());
        }
        let mut corners = std::mem::take(&mut self.face);
        corners.clear();
        for &i in indices {
            corners.push(self.vertex(&at, i)?);
        }
        let corner_uvs = self.push_corner_uvs(mesh, f, n, texcoord)?;
        for k in 1..n - 1 {
            let pick = [0, k, k + 1];
            let uv = corner_uvs.as_ref().map(|ids| pick.map(|c| ids[c]));
            mesh.triangles
                .push(self.triangle(pick.map(|c| corners[c]), uv));
        }
        self.face = corners;
        Ok(())
    }

    /// The per-corner UVs (`texcoord`, two for each of the face's `n` corners) of face `f`
    /// appended; their indices.
    pub(super) fn push_corner_uvs(
        &self,
        mesh: &mut Mesh,
        f: usize,
        n: usize,
        texcoord: &[f32],
    ) -> Result<Option<Vec<u32>>, ImportError> {
        let source = self.source;
        if texcoord.is_empty() {
            return Ok(None);
        }
        if texcoord.len() != 2 * n {
            return Err(source.malformed(
                format!("face {f}"),
                format!("{} texcoord values for {n} vertices", texcoord.len()),
            ));
        }
        let mut ids = Vec::with_capacity(n);
        for (k, uv) in texcoord.chunks_exact(2).enumerate() {
            source.check_finite(&[uv[0], uv[1]], &["texcoord u", "texcoord v"], || {
                format!("face {f} corner {k}")
            })?;
            ids.push(next_index(source, mesh.uvs.len(), "texture coordinates")?);
            mesh.uvs.push([uv[0], 1.0 - uv[1]]);
        }
        Ok(Some(ids))
    }

    /// Strips (`-1` restarts) with alternating winding; the degenerate joint triangles
    /// dropped and counted.
    pub(super) fn push_strips(
        &mut self,
        mesh: &mut Mesh,
        strips: &[Face],
    ) -> Result<usize, ImportError> {
        let mut joints = 0usize;
        for (s, strip) in strips.iter().enumerate() {
            let at = || format!("tristrips {s}");
            for run in strip.indices.split(|&i| i == -1) {
                let run = self.vertices(&at, run)?;
                for k in 0..run.len().saturating_sub(2) {
                    let (a, b, c) = (run[k], run[k + 1], run[k + 2]);
                    if a == b || b == c || a == c {
                        joints += 1;
                        continue;
                    }
                    let position = if k % 2 == 0 { [a, b, c] } else { [b, a, c] };
                    mesh.triangles.push(self.triangle(position, None));
                }
            }
        }
        Ok(joints)
    }
}
