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
mod corners;
mod properties;
#[cfg(test)]
mod tests;
mod vertices;

use std::io::{Cursor, ErrorKind};

use corners::{Corners, Present};
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{ElementDef, Encoding, Header, PropertyAccess, PropertyType};
use properties::{scalar_size, Elements, Skip};

use crate::import::error::{ImportError, Source};
use crate::import::ids::push_surface;
use crate::import::options::{ImportOptions, ImportReport, Loader};
use crate::mesh::{Mesh, Surface, Texture};

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
