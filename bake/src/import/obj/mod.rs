//! Wavefront OBJ meshes, with their MTL materials.
//!
//! The geometry statements are parsed here, keeping the file's own position, texture-coordinate
//! and normal indices per corner, so a seam (one position, two UVs) stays a seam and corners
//! without a `vt` or `vn` get [`NO_ATTRIBUTE`]. MTL files are parsed with `tobj`. (tobj's OBJ
//! loader is not used: with `single_index: false` it re-indexes positions per group, invents a
//! texture coordinate or normal for corners that have none, forgets `usemtl` names that no MTL
//! defines, accepts index 0, and reports errors without a line number.)
//!
//! Supported statements: `v x y z [w]` and `v x y z r g b [a]` (vertex colours, taken as sRGB),
//! `vt u [v [w]]`, `vn`, `f` with `v`, `v/vt`, `v//vn`, `v/vt/vn` corners, negative
//! (relative) indices and forward references, any number of corners (triangulated as a fan),
//! `usemtl`, `mtllib` (one or more files, relative to the OBJ), line continuations (`\`) and
//! comments. `o`, `g`, `s` and other grouping or rendering statements are ignored; `p` and `l`
//! are skipped and counted; free-form geometry (`curv`, `surf`, ...) is ignored with a note.
//!
//! Surfaces: one per material name, in order of first use by a face; faces before any
//! `usemtl` use a surface named `default`. Colour is `Kd` with `d` (or `1 - Tr`) as alpha
//! (alpha mode blend when it is below 1), the texture `map_Kd` (options dropped, path made
//! relative to the OBJ). A missing MTL file
//! or an undefined material is not an error: the surface keeps its name, gets white, and a
//! note says so. A malformed MTL is an error naming its line.
//!
//! Errors name the line: malformed numbers, index 0 or out of range, NaN or infinite numbers,
//! `w = 0`, a control byte (binary data is not an OBJ file). A file that does not end with a
//! line break and whose last line does not parse, or is a face with fewer than three
//! corners, is reported as cut off there. Faces with fewer than three corners elsewhere are
//! skipped and counted (the bake reports them as `skipped_primitives`).

mod mtl;
#[cfg(test)]
mod tests;

use std::collections::HashMap;

use crate::base::colour::srgb_to_linear;
use crate::import::error::{ImportError, Source};
use crate::import::ids::next_index;
use crate::import::options::{ImportOptions, ImportReport, Loader};
use crate::mesh::{Mesh, Triangle, NO_ATTRIBUTE};
use mtl::{load_materials, push_surfaces, MaterialLibraries, NamedSurface};

pub(crate) fn import_obj(
    source: &Source,
    bytes: &[u8],
    load: &mut Loader<'_>,
    _options: &ImportOptions,
    report: &mut ImportReport,
) -> Result<Mesh, ImportError> {
    parse_obj(source, bytes, load, report)
}

/// "This corner has no such attribute" in a parsed corner.
const NONE: i64 = i64::MIN;

/// One face corner: 0-based indices as resolved at the face's line (forward references are
/// checked once the whole file is read).
#[derive(Clone, Copy)]
struct Corner {
    v: i64,
    vt: i64,
    vn: i64,
    /// The indices as written, for error messages.
    written: [i64; 3],
}

struct Face {
    line: usize,
    surface: u16,
    /// Range into the corner list.
    first: usize,
    count: usize,
}

/// The passes: every statement read, every index checked once the whole file is read, the
/// MTL libraries read, then the surfaces and the triangles appended, and notes on what was
/// skipped or ignored.
fn parse_obj(
    source: &Source,
    bytes: &[u8],
    load: &mut Loader<'_>,
    report: &mut ImportReport,
) -> Result<Mesh, ImportError> {
    check_text(source, bytes)?;
    let mut obj = Statements::new(source);
    let mut lines = logical_lines(bytes).peekable();
    let ends_mid_line = !bytes.is_empty() && !bytes.ends_with(b"\n");
    while let Some((line_no, line)) = lines.next() {
        if ends_mid_line && lines.peek().is_none() {
            read_last_line(&mut obj, line_no, &line, report)?;
        } else {
            obj.read(line_no, &line, report)?;
        }
    }
    let Statements {
        mut mesh,
        color_of,
        corners,
        faces,
        surfaces,
        libraries,
        ignored,
        ..
    } = obj;
    if faces.is_empty() && !ignored.is_empty() {
        return Err(no_faces(source, &ignored));
    }
    check_indices(source, &mesh, &faces, &corners)?;
    let materials = load_materials(source, &libraries, load, report)?;
    let defined = MaterialLibraries {
        materials: &materials,
        any: !libraries.is_empty(),
    };
    push_surfaces(source, &mut mesh, &surfaces, &defined, report)?;
    push_triangles(&mut mesh, &faces, &corners, &color_of);
    if report.skipped_primitives > 0 {
        report.notes.push(format!(
            "{}: {} point, line and degenerate face statements skipped",
            source.name, report.skipped_primitives
        ));
    }
    for (keyword, n) in ignored {
        report.notes.push(format!(
            "{}: {n} unsupported '{keyword}' statements ignored",
            source.name
        ));
    }
    Ok(mesh)
}

/// A file without faces whose statements include unknown ones: likely not an OBJ file.
fn no_faces(source: &Source, ignored: &[(String, usize)]) -> ImportError {
    let shown: Vec<String> = ignored
        .iter()
        .take(3)
        .map(|(k, n)| format!("{n} x '{k}'"))
        .collect();
    let more = if ignored.len() > 3 { ", ..." } else { "" };
    ImportError::Empty {
        file: source.name.clone(),
        detail: format!(
            ": no face, and unknown statements ({}{more}); expected 'v' and 'f' statements",
            shown.join(", ")
        ),
    }
}

/// The file is text: no control byte other than tab, line feed, vertical tab, form feed or
/// carriage return (binary data, or another format, under an `.obj` name).
fn check_text(source: &Source, bytes: &[u8]) -> Result<(), ImportError> {
    let text = |b: u8| b >= 0x20 || matches!(b, b'\t' | b'\n' | 0x0b | 0x0c | b'\r');
    match bytes.iter().position(|&b| !text(b)) {
        None => Ok(()),
        Some(offset) => {
            let line = 1 + bytes[..offset].iter().filter(|&&b| b == b'\n').count();
            Err(source.malformed(
                format!("line {line}"),
                format!(
                    "byte 0x{:02x} at offset {offset} is not text; expected a Wavefront OBJ \
                     text file",
                    bytes[offset]
                ),
            ))
        }
    }
}

/// The last line of a file that does not end with a line break: a statement that does not
/// parse, or a face left with fewer than three corners, is taken as the file cut off there.
fn read_last_line(
    obj: &mut Statements<'_>,
    line_no: usize,
    line: &str,
    report: &mut ImportReport,
) -> Result<(), ImportError> {
    let source = obj.source;
    let cut = |what: String| {
        source.truncated(format!(
            "line {line_no}: the file ends in the middle of it ({what}); expected a complete \
             last line"
        ))
    };
    let skipped = report.skipped_primitives;
    match obj.read(line_no, line, report) {
        Err(e) => {
            let message = e.to_string();
            let message = message
                .strip_prefix(&format!("{}: line {line_no}: ", source.name))
                .or_else(|| message.strip_prefix(&format!("{}: ", source.name)))
                .unwrap_or(&message)
                .to_owned();
            Err(cut(message))
        }
        Ok(()) if report.skipped_primitives > skipped && is_face(line) => {
            Err(cut("a face with fewer than 3 corners".to_owned()))
        }
        Ok(()) => Ok(()),
    }
}

/// Whether a line is an `f` (or `fo`) statement.
fn is_face(line: &str) -> bool {
    matches!(line.split_ascii_whitespace().next(), Some("f" | "fo"))
}

/// What the statements build: vertex data straight into the mesh, faces as corner ranges
/// with their surface, the material names in order of first use.
struct Statements<'a> {
    source: &'a Source,
    mesh: Mesh,
    /// Colour index of each position (`v` lines with colours), NO_ATTRIBUTE without.
    color_of: Vec<u32>,
    corners: Vec<Corner>,
    faces: Vec<Face>,
    surfaces: Vec<NamedSurface>,
    surface_ids: HashMap<String, u16>,
    current_material: Option<String>,
    current_surface: Option<u16>,
    libraries: Vec<String>,
    /// Unsupported statements and how often each appears, in order of first appearance.
    ignored: Vec<(String, usize)>,
}

impl<'a> Statements<'a> {
    fn new(source: &'a Source) -> Self {
        Statements {
            source,
            mesh: Mesh::default(),
            color_of: Vec::new(),
            corners: Vec::new(),
            faces: Vec::new(),
            surfaces: Vec::new(),
            surface_ids: HashMap::new(),
            current_material: None,
            current_surface: None,
            libraries: Vec::new(),
            ignored: Vec::new(),
        }
    }

    /// One logical line.
    fn read(
        &mut self,
        line_no: usize,
        line: &str,
        report: &mut ImportReport,
    ) -> Result<(), ImportError> {
        let source = self.source;
        let at = || format!("line {line_no}");
        let line = line.trim();
        let (keyword, rest) = match line.split_once(|c: char| c.is_ascii_whitespace()) {
            Some((k, r)) => (k, r.trim()),
            None => (line, ""),
        };
        // Numeric statements may carry a trailing comment.
        let numbers = rest.split('#').next().unwrap_or("");
        match keyword {
            "" => {}
            k if k.starts_with('#') => {}
            "v" => self.vertex(&at, numbers)?,
            "vt" => self.texcoord(&at, numbers)?,
            "vn" => self.normal(&at, numbers)?,
            "f" | "fo" => self.face(line_no, &at, numbers, report)?,
            "p" | "l" => report.skipped_primitives += 1,
            "usemtl" => {
                if rest.is_empty() {
                    return Err(source.malformed(at(), "usemtl without a material name"));
                }
                self.current_material = Some(rest.to_owned());
                self.current_surface = None;
            }
            "mtllib" => {
                if rest.is_empty() {
                    return Err(source.malformed(at(), "mtllib without a file name"));
                }
                self.libraries.push(rest.to_owned());
            }
            "o" | "g" | "s" | "mg" | "vp" | "lod" | "bevel" | "c_interp" | "d_interp"
            | "usemap" | "maplib" | "shadow_obj" | "trace_obj" => {}
            other => match self.ignored.iter_mut().find(|(k, _)| k == other) {
                Some((_, n)) => *n += 1,
                None => self.ignored.push((other.to_owned(), 1)),
            },
        }
        Ok(())
    }

    /// `v x y z [w]` or `v x y z r g b [a]`.
    fn vertex(&mut self, at: &dyn Fn() -> String, numbers: &str) -> Result<(), ImportError> {
        let source = self.source;
        let values = parse_floats(source, at, numbers.split_ascii_whitespace(), "v")?;
        let (p, color) = match values.as_slice() {
            [x, y, z] => ([*x, *y, *z], None),
            [x, y, z, w] => {
                if *w == 0.0 {
                    return Err(source.malformed(at(), "vertex weight w is 0"));
                }
                ([x / w, y / w, z / w], None)
            }
            [x, y, z, r, g, b] => ([*x, *y, *z], Some([*r, *g, *b, 1.0])),
            [x, y, z, r, g, b, a] => ([*x, *y, *z], Some([*r, *g, *b, *a])),
            other => {
                return Err(source.malformed(
                    at(),
                    format!("v needs 3, 4, 6 or 7 numbers, found {}", other.len()),
                ))
            }
        };
        source.check_finite(&p, &["coordinate x", "coordinate y", "coordinate z"], at)?;
        if let Some(c) = color {
            source.check_finite(&c, &["red", "green", "blue", "alpha"], at)?;
            self.color_of
                .push(next_index(source, self.mesh.colors.len(), "colours")?);
            self.mesh.colors.push([
                srgb_to_linear(c[0]),
                srgb_to_linear(c[1]),
                srgb_to_linear(c[2]),
                c[3],
            ]);
        } else {
            self.color_of.push(NO_ATTRIBUTE);
        }
        next_index(source, self.mesh.positions.len(), "positions")?;
        self.mesh.positions.push(p);
        Ok(())
    }

    /// `vt u [v [w]]`, `v` flipped.
    fn texcoord(&mut self, at: &dyn Fn() -> String, numbers: &str) -> Result<(), ImportError> {
        let source = self.source;
        let values = parse_floats(source, at, numbers.split_ascii_whitespace(), "vt")?;
        let uv = match values.as_slice() {
            [u] => [*u, 0.0],
            [u, v] | [u, v, _] => [*u, *v],
            other => {
                return Err(source.malformed(
                    at(),
                    format!("vt needs 1 to 3 numbers, found {}", other.len()),
                ))
            }
        };
        source.check_finite(&uv, &["texture coordinate u", "texture coordinate v"], at)?;
        next_index(source, self.mesh.uvs.len(), "texture coordinates")?;
        self.mesh.uvs.push([uv[0], 1.0 - uv[1]]);
        Ok(())
    }

    /// `vn x y z`.
    fn normal(&mut self, at: &dyn Fn() -> String, numbers: &str) -> Result<(), ImportError> {
        let source = self.source;
        let values = parse_floats(source, at, numbers.split_ascii_whitespace(), "vn")?;
        let &[x, y, z] = values.as_slice() else {
            return Err(
                source.malformed(at(), format!("vn needs 3 numbers, found {}", values.len()))
            );
        };
        source.check_finite(&[x, y, z], &["normal x", "normal y", "normal z"], at)?;
        next_index(source, self.mesh.normals.len(), "normals")?;
        self.mesh.normals.push([x, y, z]);
        Ok(())
    }

    /// `f` with its corners; faces under three corners skipped and counted.
    fn face(
        &mut self,
        line_no: usize,
        at: &dyn Fn() -> String,
        numbers: &str,
        report: &mut ImportReport,
    ) -> Result<(), ImportError> {
        let first = self.corners.len();
        let mesh = &self.mesh;
        let counts = [mesh.positions.len(), mesh.uvs.len(), mesh.normals.len()];
        for token in numbers.split_ascii_whitespace() {
            self.corners
                .push(parse_corner(self.source, at, token, counts)?);
        }
        let count = self.corners.len() - first;
        if count < 3 {
            self.corners.truncate(first);
            report.skipped_primitives += 1;
            return Ok(());
        }
        let surface = self.face_surface(at)?;
        self.faces.push(Face {
            line: line_no,
            surface,
            first,
            count,
        });
        Ok(())
    }

    /// The surface of the current material (`default` before any `usemtl`), numbered on its
    /// first face.
    fn face_surface(&mut self, at: &dyn Fn() -> String) -> Result<u16, ImportError> {
        if let Some(s) = self.current_surface {
            return Ok(s);
        }
        let name = self
            .current_material
            .clone()
            .unwrap_or_else(|| "default".to_owned());
        let id = match self.surface_ids.get(&name) {
            Some(&id) => id,
            None => {
                let id = u16::try_from(self.surfaces.len())
                    .map_err(|_| self.source.unsupported(at(), "more than 65,536 materials"))?;
                self.surfaces.push(NamedSurface { name: name.clone() });
                self.surface_ids.insert(name, id);
                id
            }
        };
        self.current_surface = Some(id);
        Ok(id)
    }
}

/// Every corner's indices in range, now that the whole file is read (forward references
/// allowed).
fn check_indices(
    source: &Source,
    mesh: &Mesh,
    faces: &[Face],
    corners: &[Corner],
) -> Result<(), ImportError> {
    let counts = [mesh.positions.len(), mesh.uvs.len(), mesh.normals.len()];
    const WHAT: [&str; 3] = ["vertex index", "texture coordinate index", "normal index"];
    const OF: [&str; 3] = ["positions", "texture coordinates", "normals"];
    for face in faces {
        for c in &corners[face.first..face.first + face.count] {
            for (k, index) in [c.v, c.vt, c.vn].into_iter().enumerate() {
                if index != NONE && !(0..counts[k] as i64).contains(&index) {
                    return Err(source.out_of_range(
                        format!("line {}", face.line),
                        WHAT[k],
                        c.written[k],
                        counts[k],
                        OF[k],
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Faces as fans, each corner keeping its own indices; vertex colours follow the position.
fn push_triangles(mesh: &mut Mesh, faces: &[Face], corners: &[Corner], color_of: &[u32]) {
    let index = |i: i64| if i == NONE { NO_ATTRIBUTE } else { i as u32 };
    let triangle_count: usize = faces.iter().map(|f| f.count - 2).sum();
    mesh.triangles.reserve(triangle_count);
    for face in faces {
        let cs = &corners[face.first..face.first + face.count];
        for k in 1..cs.len() - 1 {
            let tri = [cs[0], cs[k], cs[k + 1]];
            let position = tri.map(|c| c.v as u32);
            mesh.triangles.push(Triangle {
                position,
                normal: tri.map(|c| index(c.vn)),
                uv: tri.map(|c| index(c.vt)),
                color: position.map(|p| color_of[p as usize]),
                surface: face.surface,
            });
        }
    }
}

/// Lines joined across `\` continuations, with their 1-based number.
fn logical_lines(bytes: &[u8]) -> impl Iterator<Item = (usize, String)> + '_ {
    let mut physical = bytes.split(|&b| b == b'\n').enumerate().peekable();
    std::iter::from_fn(move || {
        let (i, first) = physical.next()?;
        let mut text = String::from_utf8_lossy(first).into_owned();
        loop {
            let trimmed = text.trim_end_matches('\r');
            if !trimmed.ends_with('\\') {
                text.truncate(trimmed.len());
                break;
            }
            text.truncate(trimmed.len() - 1);
            text.push(' ');
            match physical.next() {
                Some((_, next)) => text.push_str(&String::from_utf8_lossy(next)),
                None => break,
            }
        }
        Some((i + 1, text))
    })
}

fn parse_floats<'a>(
    source: &Source,
    at: &dyn Fn() -> String,
    tokens: impl Iterator<Item = &'a str>,
    keyword: &str,
) -> Result<Vec<f32>, ImportError> {
    tokens
        .map(|t| {
            t.parse::<f32>()
                .map_err(|_| source.malformed(at(), format!("{keyword}: '{t}' is not a number")))
        })
        .collect()
}

/// `v`, `v/vt`, `v//vn` or `v/vt/vn` to 0-based indices (relative ones resolved against
/// `counts` of positions, UVs, normals so far).
fn parse_corner(
    source: &Source,
    at: &dyn Fn() -> String,
    token: &str,
    counts: [usize; 3],
) -> Result<Corner, ImportError> {
    let mut parts = token.split('/');
    let mut resolved = [NONE; 3];
    let mut written = [0i64; 3];
    for k in 0..3 {
        let Some(part) = parts.next() else { break };
        if part.is_empty() {
            if k == 0 {
                return Err(source.malformed(at(), format!("face corner '{token}' has no vertex")));
            }
            continue;
        }
        let value: i64 = part.parse().map_err(|_| {
            source.malformed(
                at(),
                format!("face corner '{token}': '{part}' is not an index"),
            )
        })?;
        written[k] = value;
        resolved[k] = match value {
            0 => {
                return Err(source.malformed(
                    at(),
                    format!("face corner '{token}': index 0 (OBJ indices start at 1)"),
                ))
            }
            v if v > 0 => v - 1,
            // Relative: -1 is the latest element; below the first stays out of range.
            v => (counts[k] as i64).saturating_add(v).max(-1),
        };
    }
    if parts.next().is_some() {
        return Err(source.malformed(
            at(),
            format!("face corner '{token}' has more than three indices"),
        ));
    }
    Ok(Corner {
        v: resolved[0],
        vt: resolved[1],
        vn: resolved[2],
        written,
    })
}
