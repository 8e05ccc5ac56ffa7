//! Stanford PLY meshes, read with `ply-rs-bw`.
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
//! Rejected with an error naming the element: a missing `x`/`y`/`z`, a vertex index out of
//! range (or negative), NaN or infinite numbers, a file shorter than its header requires
//! (binary files are checked against the header before parsing), elements with no properties.
//! Faces with fewer than three vertices are skipped and counted.

use std::io::{Cursor, ErrorKind};
use std::path::Path;

use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{
    ElementDef, Encoding, Header, PropertyAccess, PropertyAccessResult, PropertyType, ScalarType,
};

use super::{next_index, push_surface, read_file, srgb_to_linear, ImportError};
use super::{ImportOptions, ImportReport, Source};
use crate::mesh::{Mesh, Surface, Triangle, NO_ATTRIBUTE};

pub(crate) fn import_ply(
    source: &Source,
    path: &Path,
    _options: &ImportOptions,
    report: &mut ImportReport,
) -> Result<Mesh, ImportError> {
    let bytes = read_file(source, path)?;
    parse_ply(source, &bytes, report)
}

/// Slots of a vertex, in the order of [`VERTEX_NAMES`].
const X: usize = 0;
const NX: usize = 3;
const U: usize = 6;
const R: usize = 8;
const A: usize = 11;
const SLOTS: usize = 12;

/// One vertex as the parser fills it.
struct Vertex {
    values: [f32; SLOTS],
}

fn vertex_slot(name: &str) -> Option<usize> {
    Some(match name {
        "x" => X,
        "y" => X + 1,
        "z" => X + 2,
        "nx" => NX,
        "ny" => NX + 1,
        "nz" => NX + 2,
        "u" | "s" | "texture_u" | "texture_s" => U,
        "v" | "t" | "texture_v" | "texture_t" => U + 1,
        "red" | "diffuse_red" => R,
        "green" | "diffuse_green" => R + 1,
        "blue" | "diffuse_blue" => R + 2,
        "alpha" | "diffuse_alpha" => A,
        _ => return None,
    })
}

impl Vertex {
    /// Stores `value`; colours are normalised by `color_scale` (1/255 for bytes, ...).
    fn set(&mut self, name: &str, value: f64, color_scale: f64) -> PropertyAccessResult {
        match vertex_slot(name) {
            Some(slot) if slot >= R => {
                self.values[slot] = (value * color_scale) as f32;
                PropertyAccessResult::Set
            }
            Some(slot) => {
                self.values[slot] = value as f32;
                PropertyAccessResult::Set
            }
            None => PropertyAccessResult::Ignored,
        }
    }
}

const BYTE_COLOR: f64 = 1.0 / 255.0;

impl PropertyAccess for Vertex {
    fn new() -> Self {
        let mut values = [0.0; SLOTS];
        values[A] = 1.0;
        Vertex { values }
    }
    fn set_char(&mut self, name: &str, value: i8) -> PropertyAccessResult {
        self.set(name, f64::from(value), BYTE_COLOR)
    }
    fn set_uchar(&mut self, name: &str, value: u8) -> PropertyAccessResult {
        self.set(name, f64::from(value), BYTE_COLOR)
    }
    fn set_short(&mut self, name: &str, value: i16) -> PropertyAccessResult {
        self.set(name, f64::from(value), BYTE_COLOR)
    }
    fn set_ushort(&mut self, name: &str, value: u16) -> PropertyAccessResult {
        self.set(name, f64::from(value), 1.0 / 65535.0)
    }
    fn set_int(&mut self, name: &str, value: i32) -> PropertyAccessResult {
        self.set(name, f64::from(value), BYTE_COLOR)
    }
    fn set_uint(&mut self, name: &str, value: u32) -> PropertyAccessResult {
        self.set(name, f64::from(value), BYTE_COLOR)
    }
    fn set_float(&mut self, name: &str, value: f32) -> PropertyAccessResult {
        self.set(name, f64::from(value), 1.0)
    }
    fn set_double(&mut self, name: &str, value: f64) -> PropertyAccessResult {
        self.set(name, value, 1.0)
    }
}

/// One `face` or `tristrips` element: its index list and optional per-corner UVs.
#[derive(Default)]
struct Face {
    indices: Vec<i64>,
    texcoord: Vec<f32>,
}

fn is_index_list(name: &str) -> bool {
    name == "vertex_indices" || name == "vertex_index"
}

impl Face {
    fn set_indices<T: Into<i64>>(&mut self, name: &str, values: Vec<T>) -> PropertyAccessResult {
        if is_index_list(name) {
            self.indices = values.into_iter().map(Into::into).collect();
            PropertyAccessResult::Set
        } else {
            PropertyAccessResult::Ignored
        }
    }
}

impl PropertyAccess for Face {
    fn new() -> Self {
        Face::default()
    }
    fn set_list_char(&mut self, name: &str, value: Vec<i8>) -> PropertyAccessResult {
        self.set_indices(name, value)
    }
    fn set_list_uchar(&mut self, name: &str, value: Vec<u8>) -> PropertyAccessResult {
        self.set_indices(name, value)
    }
    fn set_list_short(&mut self, name: &str, value: Vec<i16>) -> PropertyAccessResult {
        self.set_indices(name, value)
    }
    fn set_list_ushort(&mut self, name: &str, value: Vec<u16>) -> PropertyAccessResult {
        self.set_indices(name, value)
    }
    fn set_list_int(&mut self, name: &str, value: Vec<i32>) -> PropertyAccessResult {
        self.set_indices(name, value)
    }
    fn set_list_uint(&mut self, name: &str, value: Vec<u32>) -> PropertyAccessResult {
        self.set_indices(name, value)
    }
    fn set_list_float(&mut self, name: &str, value: Vec<f32>) -> PropertyAccessResult {
        if name == "texcoord" {
            self.texcoord = value;
            PropertyAccessResult::Set
        } else if is_index_list(name) {
            PropertyAccessResult::UnsupportedType
        } else {
            PropertyAccessResult::Ignored
        }
    }
    fn set_list_double(&mut self, name: &str, value: Vec<f64>) -> PropertyAccessResult {
        if name == "texcoord" {
            self.texcoord = value.into_iter().map(|v| v as f32).collect();
            PropertyAccessResult::Set
        } else if is_index_list(name) {
            PropertyAccessResult::UnsupportedType
        } else {
            PropertyAccessResult::Ignored
        }
    }
}

/// An element the importer does not use: read past.
struct Skip;

impl PropertyAccess for Skip {
    fn new() -> Self {
        Skip
    }
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
    reader: &mut Reader<Cursor<&[u8]>>,
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

fn parse_ply(
    source: &Source,
    bytes: &[u8],
    report: &mut ImportReport,
) -> Result<Mesh, ImportError> {
    if !bytes.starts_with(b"ply") && !b"ply".starts_with(bytes) {
        return Err(source.malformed("header", "not a PLY file (no 'ply' magic line)"));
    }
    if !bytes.windows(10).any(|w| w == b"end_header") {
        return Err(source.truncated("the header has no end_header line"));
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
    if header.encoding != Encoding::Ascii {
        let after_header = bytes.len() as u64 - reader.get_ref().position();
        match min_binary_size(&header) {
            Some(need) if need <= after_header => {}
            need => {
                return Err(source.truncated(format!(
                    "the header declares at least {} bytes of element data ({}), {after_header} follow it",
                    need.map_or("more than 2^64".to_owned(), |n| n.to_string()),
                    header
                        .elements
                        .values()
                        .map(|e| format!("{} x '{}'", e.count, e.name))
                        .collect::<Vec<_>>()
                        .join(", ")
                )))
            }
        }
    }

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
        if vertex_slot(name).is_some() && !matches!(property.data_type, PropertyType::Scalar(_)) {
            return Err(source.malformed(
                "element 'vertex'",
                format!("property '{name}' is a list, not a number"),
            ));
        }
    }
    let has_normals = has("nx") && has("ny") && has("nz");
    let has_uvs = has("u") && has("v");
    let has_colors = has("red") && has("green") && has("blue");
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

    let mut vertices: Vec<Vertex> = Vec::new();
    let mut faces: Vec<Face> = Vec::new();
    let mut strips: Vec<Face> = Vec::new();
    for def in header.elements.values() {
        match def.name.as_str() {
            "vertex" => vertices = read_element(source, &mut reader, def, &header)?,
            "face" => faces = read_element(source, &mut reader, def, &header)?,
            "tristrips" => strips = read_element(source, &mut reader, def, &header)?,
            _ => {
                read_element::<Skip>(source, &mut reader, def, &header)?;
            }
        }
    }

    let mut mesh = Mesh::default();
    let texture = header.comments.iter().find_map(|c| {
        let c = c.trim();
        c.strip_prefix("TextureFile")
            .map(|t| t.trim().to_owned())
            .filter(|t| !t.is_empty())
    });
    let surface = push_surface(
        source,
        &mut mesh,
        Surface {
            name: "default".to_owned(),
            base_color: [1.0; 4],
            texture,
        },
    )?;

    const NAMES: [&str; SLOTS] = [
        "coordinate x",
        "coordinate y",
        "coordinate z",
        "normal x",
        "normal y",
        "normal z",
        "texture coordinate u",
        "texture coordinate v",
        "red",
        "green",
        "blue",
        "alpha",
    ];
    mesh.positions.reserve(vertices.len());
    for (i, v) in vertices.iter().enumerate() {
        source.check_finite(&v.values, &NAMES, || format!("vertex {i}"))?;
        let x = &v.values;
        mesh.positions.push([x[X], x[X + 1], x[X + 2]]);
        if has_normals {
            mesh.normals.push([x[NX], x[NX + 1], x[NX + 2]]);
        }
        if has_uvs {
            mesh.uvs.push([x[U], 1.0 - x[U + 1]]);
        }
        if has_colors {
            mesh.colors.push([
                srgb_to_linear(x[R]),
                srgb_to_linear(x[R + 1]),
                srgb_to_linear(x[R + 2]),
                x[A],
            ]);
        }
    }
    let vertex_count = vertices.len();
    drop(vertices);
    let same = |i: u32, present: bool| if present { i } else { NO_ATTRIBUTE };
    let check = |at: &dyn Fn() -> String, index: i64| -> Result<u32, ImportError> {
        if (0..vertex_count as i64).contains(&index) {
            Ok(index as u32)
        } else {
            Err(source.out_of_range(at(), "vertex index", index, vertex_count, "vertices"))
        }
    };

    mesh.triangles.reserve(faces.len());
    for (f, face) in faces.iter().enumerate() {
        let at = || format!("face {f}");
        let n = face.indices.len();
        if n < 3 {
            report.skipped_primitives += 1;
            continue;
        }
        let corners: Vec<u32> = face
            .indices
            .iter()
            .map(|&i| check(&at, i))
            .collect::<Result<_, _>>()?;
        let corner_uvs: Option<Vec<u32>> = if face.texcoord.is_empty() {
            None
        } else if face.texcoord.len() != 2 * n {
            return Err(source.malformed(
                at(),
                format!("{} texcoord values for {n} vertices", face.texcoord.len()),
            ));
        } else {
            let mut ids = Vec::with_capacity(n);
            for (k, uv) in face.texcoord.chunks_exact(2).enumerate() {
                source.check_finite(&[uv[0], uv[1]], &["texcoord u", "texcoord v"], || {
                    format!("face {f} corner {k}")
                })?;
                ids.push(next_index(source, mesh.uvs.len(), "texture coordinates")?);
                mesh.uvs.push([uv[0], 1.0 - uv[1]]);
            }
            Some(ids)
        };
        for k in 1..n - 1 {
            let pick = [0, k, k + 1];
            let position = pick.map(|c| corners[c]);
            mesh.triangles.push(Triangle {
                position,
                normal: position.map(|i| same(i, has_normals)),
                uv: match &corner_uvs {
                    Some(ids) => pick.map(|c| ids[c]),
                    None => position.map(|i| same(i, has_uvs)),
                },
                color: position.map(|i| same(i, has_colors)),
                surface,
            });
        }
    }

    let mut joints = 0usize;
    for (s, strip) in strips.iter().enumerate() {
        let at = || format!("tristrips {s}");
        for run in strip.indices.split(|&i| i == -1) {
            let run: Vec<u32> = run
                .iter()
                .map(|&i| check(&at, i))
                .collect::<Result<_, _>>()?;
            for k in 0..run.len().saturating_sub(2) {
                let (a, b, c) = (run[k], run[k + 1], run[k + 2]);
                if a == b || b == c || a == c {
                    joints += 1;
                    continue;
                }
                let position = if k % 2 == 0 { [a, b, c] } else { [b, a, c] };
                mesh.triangles.push(Triangle {
                    position,
                    normal: position.map(|i| same(i, has_normals)),
                    uv: position.map(|i| same(i, has_uvs)),
                    color: position.map(|i| same(i, has_colors)),
                    surface,
                });
            }
        }
    }
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
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn src() -> Source {
        Source {
            name: "t.ply".to_owned(),
        }
    }

    #[derive(Clone, Copy)]
    enum Format {
        Ascii,
        Le,
        Be,
    }

    /// Position, normal, RGBA bytes, UV.
    type SampleVertex = ([f32; 3], [f32; 3], [u8; 4], [f32; 2]);

    /// A quad and a triangle over five vertices with normals, byte colours and UVs.
    fn sample(format: Format) -> Vec<u8> {
        let verts: [SampleVertex; 5] = [
            (
                [0.0, 0.0, 0.0],
                [0.0, 0.0, 1.0],
                [255, 0, 0, 255],
                [0.0, 0.0],
            ),
            (
                [1.0, 0.0, 0.0],
                [0.0, 0.0, 1.0],
                [0, 255, 0, 128],
                [1.0, 0.0],
            ),
            (
                [1.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
                [0, 0, 255, 255],
                [1.0, 1.0],
            ),
            (
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
                [10, 20, 30, 255],
                [0.0, 1.0],
            ),
            (
                [0.5, 2.0, 0.25],
                [0.0, 0.6, 0.8],
                [200, 100, 50, 0],
                [0.5, 1.5],
            ),
        ];
        let faces: [&[i32]; 2] = [&[0, 1, 2, 3], &[3, 2, 4]];
        let name = match format {
            Format::Ascii => "ascii",
            Format::Le => "binary_little_endian",
            Format::Be => "binary_big_endian",
        };
        let mut out = format!(
            "ply\nformat {name} 1.0\ncomment TextureFile skin.png\nelement vertex 5\n\
             property float x\nproperty float y\nproperty float z\nproperty float nx\n\
             property float ny\nproperty float nz\nproperty uchar red\nproperty uchar green\n\
             property uchar blue\nproperty uchar alpha\nproperty float u\nproperty float v\n\
             element face 2\nproperty list uchar int vertex_indices\nproperty uchar flags\n\
             end_header\n"
        )
        .into_bytes();
        let f = |out: &mut Vec<u8>, v: f32| match format {
            Format::Le => out.extend_from_slice(&v.to_le_bytes()),
            Format::Be => out.extend_from_slice(&v.to_be_bytes()),
            Format::Ascii => out.extend_from_slice(format!("{v} ").as_bytes()),
        };
        for (p, n, c, uv) in verts {
            for v in p.into_iter().chain(n) {
                f(&mut out, v);
            }
            for b in c {
                match format {
                    Format::Ascii => out.extend_from_slice(format!("{b} ").as_bytes()),
                    _ => out.push(b),
                }
            }
            for v in uv {
                f(&mut out, v);
            }
            if let Format::Ascii = format {
                out.push(b'\n');
            }
        }
        for face in faces {
            match format {
                Format::Ascii => {
                    let list: Vec<String> = face.iter().map(|i| i.to_string()).collect();
                    out.extend_from_slice(
                        format!("{} {} 7\n", face.len(), list.join(" ")).as_bytes(),
                    );
                }
                Format::Le | Format::Be => {
                    out.push(face.len() as u8);
                    for &i in face {
                        match format {
                            Format::Le => out.extend_from_slice(&i.to_le_bytes()),
                            _ => out.extend_from_slice(&i.to_be_bytes()),
                        }
                    }
                    out.push(7);
                }
            }
        }
        out
    }

    fn parse(bytes: &[u8]) -> Result<Mesh, ImportError> {
        parse_ply(&src(), bytes, &mut ImportReport::default())
    }

    #[test]
    fn ascii_and_both_binaries_give_the_same_mesh() {
        let ascii = parse(&sample(Format::Ascii)).unwrap();
        let le = parse(&sample(Format::Le)).unwrap();
        let be = parse(&sample(Format::Be)).unwrap();
        assert_eq!(ascii, le);
        assert_eq!(ascii, be);
        ascii.validate().unwrap();
        assert_eq!(ascii.positions.len(), 5);
        assert_eq!(ascii.normals.len(), 5);
        assert_eq!(ascii.uvs.len(), 5);
        assert_eq!(ascii.colors.len(), 5);
        // The quad becomes a fan of two triangles, then the triangle.
        let tris: Vec<[u32; 3]> = ascii.triangles.iter().map(|t| t.position).collect();
        assert_eq!(tris, vec![[0, 1, 2], [0, 2, 3], [3, 2, 4]]);
        assert!(ascii
            .triangles
            .iter()
            .all(|t| t.uv == t.position && t.normal == t.position));
        assert_eq!(ascii.uvs[4], [0.5, -0.5]);
        assert_eq!(ascii.colors[0], [1.0, 0.0, 0.0, 1.0]);
        assert!((ascii.colors[1][3] - 128.0 / 255.0).abs() < 1e-6);
        assert!((ascii.colors[3][0] - srgb_to_linear(10.0 / 255.0)).abs() < 1e-7);
        assert_eq!(ascii.surfaces[0].texture.as_deref(), Some("skin.png"));
    }

    #[test]
    fn truncated_binary_files_are_errors_at_every_cut() {
        for format in [Format::Le, Format::Be] {
            let full = sample(format);
            assert!(parse(&full).is_ok());
            let header_end = full.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
            let cuts = [
                0,
                3,
                header_end - 5,
                header_end,
                header_end + 1,
                header_end + 44,
                header_end + 150,
                full.len() - 13,
                full.len() - 1,
            ];
            for cut in cuts {
                let err = parse(&full[..cut]).expect_err("a cut file must not import");
                assert!(
                    matches!(err, ImportError::Truncated { .. }),
                    "cut at {cut}: {err}"
                );
            }
        }
    }

    #[test]
    fn truncated_ascii_is_an_error() {
        let full = sample(Format::Ascii);
        for cut in [full.len() - 4, full.len() - 30, full.len() / 2] {
            let err = parse(&full[..cut]).expect_err("a cut file must not import");
            assert!(
                matches!(
                    err,
                    ImportError::Truncated { .. } | ImportError::Malformed { .. }
                ),
                "{err}"
            );
        }
    }

    /// A binary little-endian triangle whose vertex 1 has coordinate y = `y`.
    fn triangle_with_y(y: f32) -> Vec<u8> {
        let mut out = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\n\
                        property float x\nproperty float y\nproperty float z\nelement face 1\n\
                        property list uchar uint vertex_indices\nend_header\n"
            .to_vec();
        for v in [0.0, 0.0, 0.0, 1.0, y, 0.0, 0.0, 1.0, 0.0f32] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out.push(3);
        for i in 0..3u32 {
            out.extend_from_slice(&i.to_le_bytes());
        }
        out
    }

    #[test]
    fn non_finite_coordinates_are_named() {
        assert!(parse(&triangle_with_y(0.0)).is_ok());
        let err = parse(&triangle_with_y(f32::NAN)).unwrap_err().to_string();
        assert_eq!(err, "t.ply: vertex 1: coordinate y is NaN");
        let err = parse(&triangle_with_y(f32::NEG_INFINITY))
            .unwrap_err()
            .to_string();
        assert_eq!(err, "t.ply: vertex 1: coordinate y is -inf");
        // ply-rs-bw's ascii grammar has no NaN: the line is rejected as malformed.
        let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                    property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
                    end_header\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n";
        let err = parse(text.as_bytes()).unwrap_err().to_string();
        assert!(err.starts_with("t.ply: element 'vertex': Line 11"), "{err}");
    }

    #[test]
    fn index_out_of_range_is_named() {
        let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                    property float z\nelement face 2\nproperty list uchar int vertex_indices\n\
                    end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 7\n";
        let err = parse(text.as_bytes()).unwrap_err().to_string();
        assert_eq!(
            err,
            "t.ply: face 1: vertex index 7 out of range (3 vertices)"
        );
        let neg = text.replace("3 0 1 7", "3 0 -1 2");
        let err = parse(neg.as_bytes()).unwrap_err().to_string();
        assert_eq!(
            err,
            "t.ply: face 1: vertex index -1 out of range (3 vertices)"
        );
    }

    #[test]
    fn tristrips_are_decoded_with_restarts() {
        let text = "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\n\
                    property float z\nelement tristrips 1\nproperty list int int vertex_indices\n\
                    end_header\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n2 0 0\n2 1 0\n\
                    9 0 1 2 3 -1 1 4 3 5\n";
        let mut report = ImportReport::default();
        let mesh = parse_ply(&src(), text.as_bytes(), &mut report).unwrap();
        let tris: Vec<[u32; 3]> = mesh.triangles.iter().map(|t| t.position).collect();
        assert_eq!(tris, vec![[0, 1, 2], [2, 1, 3], [1, 4, 3], [3, 4, 5]]);
        // Every triangle faces +z (counter-clockwise seen from above).
        for [a, b, c] in tris {
            let (a, b, c) = (
                mesh.positions[a as usize],
                mesh.positions[b as usize],
                mesh.positions[c as usize],
            );
            let z = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            assert!(z > 0.0);
        }
        // A joint (repeated index) is dropped and noted.
        let joint = text.replace("9 0 1 2 3 -1 1 4 3 5", "6 0 1 2 2 3 4");
        let mesh = parse_ply(&src(), joint.as_bytes(), &mut report).unwrap();
        assert_eq!(mesh.triangles.len(), 2);
        assert!(
            report.notes.iter().any(|n| n.contains("2 degenerate")),
            "{:?}",
            report.notes
        );
    }

    #[test]
    fn per_corner_texcoords_make_seams() {
        let text = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
                    property float z\nelement face 2\nproperty list uchar int vertex_indices\n\
                    property list uchar float texcoord\nend_header\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n\
                    3 0 1 2 6 0 0 1 0 0 1\n3 2 1 3 6 0.5 0.5 0.25 0.25 1 1\n";
        let mesh = parse(text.as_bytes()).unwrap();
        assert_eq!(mesh.uvs.len(), 6);
        assert_eq!(mesh.triangles[1].uv, [3, 4, 5]);
        assert_eq!(mesh.uvs[3], [0.5, 0.5]);
        let bad = text.replace("6 0.5 0.5 0.25 0.25 1 1", "4 0.5 0.5 0.25 0.25");
        let err = parse(bad.as_bytes()).unwrap_err().to_string();
        assert!(
            err.contains("face 1: 4 texcoord values for 3 vertices"),
            "{err}"
        );
    }

    #[test]
    fn malformed_headers_are_errors() {
        let err = |t: &str| parse(t.as_bytes()).unwrap_err().to_string();
        assert!(err("ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n")
            .contains("no 'vertex' element"));
        assert!(err("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n")
            .contains("no 'z' property"));
        assert!(err("ply\nformat binary_little_endian 1.0\nelement vertex 1\nelement junk 4000000000000\nend_header\n")
            .contains("no properties"));
        assert!(
            err("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n")
                .contains("truncated")
        );
        assert!(err("not a ply").contains("header"));
        assert!(err("ply\nformat ascii 1.0\nelement vertex 1\nproperty list uchar float x\nproperty float y\nproperty float z\nend_header\n1 0 0 0\n")
            .contains("property 'x' is a list"));
        assert!(err("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar float vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
            .contains("element 'face'"));
        // A huge count in a small binary file is caught before parsing.
        let huge = "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000000\n\
                    property float x\nproperty float y\nproperty float z\nend_header\n";
        let e = err(huge);
        assert!(
            e.contains("truncated") && e.contains("4000000000000 x 'vertex'"),
            "{e}"
        );
    }
}
