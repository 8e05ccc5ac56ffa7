//! Stanford PLY meshes: the header and binary element data read with `ply-rs-bw`, ASCII
//! element data read line by line here (`ascii.rs`), so that an ASCII file's errors name the
//! element, its index, line and property, and `nan` is reported as in a binary file. Binary
//! data in the common layouts is read straight into the mesh instead (`binary.rs`), to the
//! same mesh and the same errors. Vertices become the mesh's positions and attributes on all
//! cores, a piece at a time (`vertices.rs`).
//!
//! Supported: `ascii`, `binary_little_endian` and `binary_big_endian`, any scalar types.
//! Element `vertex`: `x y z` (required), `nx ny nz`, colours `red green blue [alpha]` (or
//! `diffuse_red ...`), texture coordinates `u v`, `s t`, `texture_u texture_v` or
//! `texture_s texture_t`. Element `face`: a `vertex_indices` (or `vertex_index`) list of any
//! integer type and any length, triangulated as a fan; an optional per-corner `texcoord` float
//! list (`2n` values, as MeshLab writes it) takes precedence over vertex UVs. Element
//! `tristrips`: `vertex_indices` lists, `-1` restarting a strip, decoded with alternating
//! winding; the degenerate triangles strips use as joints are dropped (and counted in the
//! notes). A `comment TextureFile NAME` header line becomes the surface's texture. Other
//! elements and properties are read past and ignored.
//!
//! Colours: 8-bit (and other integer) colours are divided by 255, `ushort` by 65535, floats
//! taken as they are; all are taken as sRGB and converted to linear (alpha stays linear).
//! UV `v` is flipped (`1 - v`).
//!
//! Rejected with an error naming the element: a file without the `ply` magic line, a missing
//! `x`/`y`/`z`, a vertex index out of range (or negative), NaN or infinite numbers, a file
//! shorter than its header requires (binary files are checked against the header before
//! parsing; an ASCII file's message says in which element and after how many lines it ends),
//! an ASCII line with too few or too many values, elements with no properties.
//! Faces with fewer than three vertices are skipped and counted.

mod ascii;
mod binary;
mod properties;
#[cfg(test)]
mod tests;
mod vertices;

use std::io::{Cursor, ErrorKind};

use crate::base::ply::vertex_slot;
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{ElementDef, Encoding, Header, PropertyAccess, PropertyType, ScalarType};
use properties::{is_index_list, Face, Skip, Vertex};
use vertices::byte_colour;

use super::{next_index, push_surface, ImportError, Loader};
use super::{ImportOptions, ImportReport, Source};
use crate::base::colour::srgb_to_linear;
use crate::mesh::{Mesh, Surface, Texture, Triangle, NO_ATTRIBUTE};

/// The parser's reader over the file's bytes.
type ByteReader<'a> = Reader<Cursor<&'a [u8]>>;

pub(crate) fn import_ply(
    source: &Source,
    bytes: &[u8],
    _load: &mut Loader<'_>,
    _options: &ImportOptions,
    report: &mut ImportReport,
) -> Result<Mesh, ImportError> {
    parse_ply(source, bytes, report)
}

fn scalar_size(t: &ScalarType) -> usize {
    match t {
        ScalarType::Char | ScalarType::UChar => 1,
        ScalarType::Short | ScalarType::UShort => 2,
        ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
        ScalarType::Double => 8,
    }
}

/// The fewest bytes a binary payload can have (every list empty), or `None` on overflow.
fn min_binary_size(header: &Header) -> Option<u64> {
    let mut total: u64 = 0;
    for e in header.elements.values() {
        let per: u64 = e
            .properties
            .values()
            .map(|p| match &p.data_type {
                PropertyType::Scalar(t) => scalar_size(t) as u64,
                PropertyType::List(count, _) => scalar_size(count) as u64,
            })
            .sum();
        total = total.checked_add(per.checked_mul(e.count as u64)?)?;
    }
    Some(total)
}

/// The parser's message on one line.
fn one_line(e: impl std::fmt::Display) -> String {
    e.to_string()
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join("; ")
}

fn read_element<E: PropertyAccess>(
    source: &Source,
    reader: &mut ByteReader<'_>,
    def: &ElementDef,
    header: &Header,
) -> Result<Vec<E>, ImportError> {
    Parser::<E>::new()
        .read_payload_for_element(reader, def, header)
        .map_err(|e| {
            if e.kind() == ErrorKind::UnexpectedEof {
                source.truncated(format!("element '{}': {}", def.name, one_line(&e)))
            } else {
                source.malformed(format!("element '{}'", def.name), one_line(&e))
            }
        })
}

/// The passes: the header and what it promises checked, the elements read (straight into
/// the mesh where [`binary`] takes the layout, by the parser's reader otherwise), then the
/// surface, the vertices, the faces (fans) and the strips appended, and notes on what was
/// dropped.
fn parse_ply(
    source: &Source,
    bytes: &[u8],
    report: &mut ImportReport,
) -> Result<Mesh, ImportError> {
    let (mut reader, header) = read_header(source, bytes)?;
    check_binary_size(source, bytes, &reader, &header)?;
    let present = Present::check(source, &header)?;
    let start = reader.get_ref().position() as usize;
    match binary::Payload::find(&header, &bytes[start..]) {
        Some(payload) => read_direct(source, &payload, &header, present, report),
        None => read_parsed(source, bytes, &mut reader, &header, present, report),
    }
}

/// The mesh of a binary payload in a layout [`binary`] takes.
fn read_direct(
    source: &Source,
    payload: &binary::Payload<'_>,
    header: &Header,
    present: Present,
    report: &mut ImportReport,
) -> Result<Mesh, ImportError> {
    let mut mesh = Mesh::default();
    let vertex_count = header.elements.get("vertex").map_or(0, |v| v.count);
    let mut corners = Corners::new(source, vertex_count, present);
    corners.surface = push_texture_surface(source, &mut mesh, header)?;
    payload.read(&mut corners, &mut mesh, report)?;
    note_dropped(source, 0, report);
    Ok(mesh)
}

/// The mesh of any payload, its elements read by the parser (binary) or line by line
/// (ASCII) first.
fn read_parsed(
    source: &Source,
    bytes: &[u8],
    reader: &mut ByteReader<'_>,
    header: &Header,
    present: Present,
    report: &mut ImportReport,
) -> Result<Mesh, ImportError> {
    let start = reader.get_ref().position() as usize;
    let elements = if header.encoding == Encoding::Ascii {
        let first_line = 1 + bytes[..start].iter().filter(|&&b| b == b'\n').count();
        let text = std::str::from_utf8(&bytes[start..]).map_err(|e| {
            let line = first_line
                + bytes[start..start + e.valid_up_to()]
                    .iter()
                    .filter(|&&b| b == b'\n')
                    .count();
            source.malformed(
                format!("line {line}"),
                "not text (invalid UTF-8) in an ascii file; expected numbers",
            )
        })?;
        ascii::read_elements(source, &mut ascii::Lines::new(text, first_line), header)?
    } else {
        read_elements(source, reader, header)?
    };
    let mut mesh = Mesh::default();
    let mut corners = Corners::new(source, elements.vertices.len(), present);
    corners.surface = push_texture_surface(source, &mut mesh, header)?;
    let vertices = &elements.vertices;
    corners.push_vertices(&mut mesh, vertices.len(), |i| vertices[i])?;
    drop(elements.vertices);
    mesh.triangles.reserve(elements.faces.len());
    for (f, face) in elements.faces.iter().enumerate() {
        corners.push_face(&mut mesh, f, &face.indices, &face.texcoord, report)?;
    }
    let joints = corners.push_strips(&mut mesh, &elements.strips)?;
    note_dropped(source, joints, report);
    Ok(mesh)
}

/// Notes on the strips' joints and the faces dropped.
fn note_dropped(source: &Source, joints: usize, report: &mut ImportReport) {
    if joints > 0 {
        report.notes.push(format!(
            "{}: {joints} degenerate triangles joining triangle strips dropped",
            source.name
        ));
    }
    if report.skipped_primitives > 0 {
        report.notes.push(format!(
            "{}: {} faces with fewer than 3 vertices skipped",
            source.name, report.skipped_primitives
        ));
    }
}

/// The header parsed (the reader left at the element data); every element with instances
/// has properties.
fn read_header<'a>(
    source: &Source,
    bytes: &'a [u8],
) -> Result<(ByteReader<'a>, Header), ImportError> {
    if !bytes.starts_with(b"ply") && !b"ply".starts_with(bytes) {
        return Err(source.malformed(
            "header",
            "not a PLY file (no 'ply' magic line); expected the first line 'ply'",
        ));
    }
    if !bytes.windows(10).any(|w| w == b"end_header") {
        return Err(
            source.truncated("header: no end_header line; expected the header to end with one")
        );
    }
    let mut reader = Reader::new(Cursor::new(bytes));
    let header = Parser::<Skip>::new()
        .read_header(&mut reader)
        .map_err(|e| {
            if e.kind() == ErrorKind::UnexpectedEof {
                source.truncated(format!("header: {}", one_line(&e)))
            } else {
                source.malformed("header", one_line(&e))
            }
        })?;
    for def in header.elements.values() {
        if def.properties.is_empty() && def.count > 0 {
            return Err(source.malformed(format!("element '{}'", def.name), "has no properties"));
        }
    }
    Ok((reader, header))
}

/// A binary file holds at least the bytes its header declares, checked before the parser
/// allocates for the declared counts.
fn check_binary_size(
    source: &Source,
    bytes: &[u8],
    reader: &ByteReader<'_>,
    header: &Header,
) -> Result<(), ImportError> {
    if header.encoding == Encoding::Ascii {
        return Ok(());
    }
    let after_header = bytes.len() as u64 - reader.get_ref().position();
    match min_binary_size(header) {
        Some(need) if need <= after_header => Ok(()),
        need => Err(source.truncated(format!(
            "the header declares at least {} bytes of element data ({}), {after_header} follow it",
            need.map_or("more than 2^64".to_owned(), |n| n.to_string()),
            header
                .elements
                .values()
                .map(|e| format!("{} x '{}'", e.count, e.name))
                .collect::<Vec<_>>()
                .join(", ")
        ))),
    }
}

/// The optional vertex attributes the file has (all their components).
#[derive(Clone, Copy)]
struct Present {
    normals: bool,
    uvs: bool,
    colors: bool,
}

impl Present {
    /// Checks the elements the importer reads (a `vertex` element with scalar `x y z`; index
    /// lists on faces and strips) and finds the optional attributes.
    fn check(source: &Source, header: &Header) -> Result<Self, ImportError> {
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

/// The elements the importer uses.
struct Elements {
    vertices: Vec<Vertex>,
    faces: Vec<Face>,
    strips: Vec<Face>,
}

/// Every element in file order; the ones not used are read past.
fn read_elements(
    source: &Source,
    reader: &mut ByteReader<'_>,
    header: &Header,
) -> Result<Elements, ImportError> {
    let mut elements = Elements {
        vertices: Vec::new(),
        faces: Vec::new(),
        strips: Vec::new(),
    };
    for def in header.elements.values() {
        match def.name.as_str() {
            "vertex" => elements.vertices = read_element(source, reader, def, header)?,
            "face" => elements.faces = read_element(source, reader, def, header)?,
            "tristrips" => elements.strips = read_element(source, reader, def, header)?,
            _ => {
                read_element::<Skip>(source, reader, def, header)?;
            }
        }
    }
    Ok(elements)
}

/// The one surface, textured by a `comment TextureFile NAME` header line.
fn push_texture_surface(
    source: &Source,
    mesh: &mut Mesh,
    header: &Header,
) -> Result<u16, ImportError> {
    let texture = header.comments.iter().find_map(|c| {
        let c = c.trim();
        c.strip_prefix("TextureFile")
            .map(|t| t.trim().to_owned())
            .filter(|t| !t.is_empty())
    });
    push_surface(
        source,
        mesh,
        Surface {
            texture: texture.map(Texture::File),
            ..Surface::plain("default")
        },
    )
}

/// Turns vertices into positions and attributes, faces and strips into triangles: vertex
/// indices checked, per-vertex attributes sharing the position's index.
struct Corners<'a> {
    source: &'a Source,
    vertex_count: usize,
    present: Present,
    surface: u16,
    /// A face's corners, reused from face to face.
    face: Vec<u32>,
    /// The linear value of each 8-bit colour channel ([`Self::linear`]).
    byte_linear: [f32; 256],
}

impl<'a> Corners<'a> {
    fn new(source: &'a Source, vertex_count: usize, present: Present) -> Self {
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
    fn in_range(&self, index: i64) -> bool {
        (0..self.vertex_count as i64).contains(&index)
    }

    fn vertex(&self, at: &dyn Fn() -> String, index: i64) -> Result<u32, ImportError> {
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

    fn vertices(&self, at: &dyn Fn() -> String, indices: &[i64]) -> Result<Vec<u32>, ImportError> {
        indices.iter().map(|&i| self.vertex(at, i)).collect()
    }

    /// A triangle whose attributes share the position's indices (where present); `uv`
    /// overrides the UVs.
    fn triangle(&self, position: [u32; 3], uv: Option<[u32; 3]>) -> Triangle {
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
    fn push_face(
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
    fn push_corner_uvs(
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
    fn push_strips(&mut self, mesh: &mut Mesh, strips: &[Face]) -> Result<usize, ImportError> {
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
