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
//! `usemtl` use a surface named `default`. Colour is `Kd` with `d` (or `1 - Tr`) as alpha,
//! the texture `map_Kd` (options dropped, path made relative to the OBJ). A missing MTL file
//! or an undefined material is not an error: the surface keeps its name, gets white, and a
//! note says so. A malformed MTL is an error naming its line.
//!
//! Errors name the line: malformed numbers, index 0 or out of range, NaN or infinite numbers,
//! `w = 0`.

use std::collections::HashMap;
use std::io::Cursor;
use std::path::Path;

use super::{next_index, push_surface, read_file, srgb_to_linear, ImportError};
use super::{ImportOptions, ImportReport, Source};
use crate::mesh::{Mesh, Surface, Triangle, NO_ATTRIBUTE};

pub(crate) fn import_obj(
    source: &Source,
    path: &Path,
    _options: &ImportOptions,
    report: &mut ImportReport,
) -> Result<Mesh, ImportError> {
    let bytes = read_file(source, path)?;
    let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let mut load = |name: &str| -> std::io::Result<Vec<u8>> { std::fs::read(dir.join(name)) };
    parse_obj(source, &bytes, &mut load, report)
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

/// A surface as the OBJ names it, before the MTL files are consulted.
struct NamedSurface {
    name: String,
}

/// Loads a file named by `mtllib`, relative to the OBJ.
type Loader<'a> = dyn FnMut(&str) -> std::io::Result<Vec<u8>> + 'a;

fn parse_obj(
    source: &Source,
    bytes: &[u8],
    load: &mut Loader<'_>,
    report: &mut ImportReport,
) -> Result<Mesh, ImportError> {
    let mut mesh = Mesh::default();
    // Colour index of each position (`v` lines with colours), NO_ATTRIBUTE without.
    let mut color_of: Vec<u32> = Vec::new();
    let mut corners: Vec<Corner> = Vec::new();
    let mut faces: Vec<Face> = Vec::new();
    let mut surfaces: Vec<NamedSurface> = Vec::new();
    let mut surface_ids: HashMap<String, u16> = HashMap::new();
    let mut current_material: Option<String> = None;
    let mut current_surface: Option<u16> = None;
    let mut libraries: Vec<String> = Vec::new();
    let mut ignored: Vec<(String, usize)> = Vec::new();

    for (line_no, line) in logical_lines(bytes) {
        let at = || format!("line {line_no}");
        let line = line.trim();
        let (keyword, rest) = match line.split_once(|c: char| c.is_ascii_whitespace()) {
            Some((k, r)) => (k, r.trim()),
            None => (line, ""),
        };
        // Numeric statements may carry a trailing comment.
        let numbers = || {
            rest.split('#')
                .next()
                .unwrap_or("")
                .split_ascii_whitespace()
        };
        match keyword {
            "" => {}
            k if k.starts_with('#') => {}
            "v" => {
                let values = parse_floats(source, &at, numbers(), "v")?;
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
                    color_of.push(next_index(source, mesh.colors.len(), "colours")?);
                    mesh.colors.push([
                        srgb_to_linear(c[0]),
                        srgb_to_linear(c[1]),
                        srgb_to_linear(c[2]),
                        c[3],
                    ]);
                } else {
                    color_of.push(NO_ATTRIBUTE);
                }
                next_index(source, mesh.positions.len(), "positions")?;
                mesh.positions.push(p);
            }
            "vt" => {
                let values = parse_floats(source, &at, numbers(), "vt")?;
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
                next_index(source, mesh.uvs.len(), "texture coordinates")?;
                mesh.uvs.push([uv[0], 1.0 - uv[1]]);
            }
            "vn" => {
                let values = parse_floats(source, &at, numbers(), "vn")?;
                let &[x, y, z] = values.as_slice() else {
                    return Err(source
                        .malformed(at(), format!("vn needs 3 numbers, found {}", values.len())));
                };
                source.check_finite(&[x, y, z], &["normal x", "normal y", "normal z"], at)?;
                next_index(source, mesh.normals.len(), "normals")?;
                mesh.normals.push([x, y, z]);
            }
            "f" | "fo" => {
                let first = corners.len();
                let counts = [mesh.positions.len(), mesh.uvs.len(), mesh.normals.len()];
                for token in numbers() {
                    corners.push(parse_corner(source, &at, token, counts)?);
                }
                let count = corners.len() - first;
                if count < 3 {
                    corners.truncate(first);
                    report.skipped_primitives += 1;
                    continue;
                }
                let surface = match current_surface {
                    Some(s) => s,
                    None => {
                        let name = current_material
                            .clone()
                            .unwrap_or_else(|| "default".to_owned());
                        let id = match surface_ids.get(&name) {
                            Some(&id) => id,
                            None => {
                                let id = u16::try_from(surfaces.len()).map_err(|_| {
                                    source.unsupported(at(), "more than 65,536 materials")
                                })?;
                                surfaces.push(NamedSurface { name: name.clone() });
                                surface_ids.insert(name, id);
                                id
                            }
                        };
                        current_surface = Some(id);
                        id
                    }
                };
                faces.push(Face {
                    line: line_no,
                    surface,
                    first,
                    count,
                });
            }
            "p" | "l" => report.skipped_primitives += 1,
            "usemtl" => {
                if rest.is_empty() {
                    return Err(source.malformed(at(), "usemtl without a material name"));
                }
                current_material = Some(rest.to_owned());
                current_surface = None;
            }
            "mtllib" => {
                if rest.is_empty() {
                    return Err(source.malformed(at(), "mtllib without a file name"));
                }
                libraries.push(rest.to_owned());
            }
            "o" | "g" | "s" | "mg" | "vp" | "lod" | "bevel" | "c_interp" | "d_interp"
            | "usemap" | "maplib" | "shadow_obj" | "trace_obj" => {}
            other => match ignored.iter_mut().find(|(k, _)| k == other) {
                Some((_, n)) => *n += 1,
                None => ignored.push((other.to_owned(), 1)),
            },
        }
    }

    // Every index now that the whole file is read.
    let counts = [mesh.positions.len(), mesh.uvs.len(), mesh.normals.len()];
    const WHAT: [&str; 3] = ["vertex index", "texture coordinate index", "normal index"];
    const OF: [&str; 3] = ["positions", "texture coordinates", "normals"];
    for face in &faces {
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

    let materials = load_materials(source, &libraries, load, report)?;
    for named in &surfaces {
        let surface = match materials.get(&named.name) {
            Some(s) => s.clone(),
            None => {
                if named.name != "default" || !libraries.is_empty() {
                    report.notes.push(format!(
                        "{}: material '{}' is not defined in any MTL file; it gets a white \
                         default surface",
                        source.name, named.name
                    ));
                }
                Surface {
                    name: named.name.clone(),
                    base_color: [1.0; 4],
                    texture: None,
                }
            }
        };
        push_surface(source, &mut mesh, surface)?;
    }

    let index = |i: i64| if i == NONE { NO_ATTRIBUTE } else { i as u32 };
    let triangle_count: usize = faces.iter().map(|f| f.count - 2).sum();
    mesh.triangles.reserve(triangle_count);
    for face in &faces {
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

/// Reads the MTL libraries into surfaces by material name (the first definition of a name
/// wins). Missing files are noted, malformed ones are errors.
fn load_materials(
    source: &Source,
    libraries: &[String],
    load: &mut Loader<'_>,
    report: &mut ImportReport,
) -> Result<HashMap<String, Surface>, ImportError> {
    let mut surfaces: HashMap<String, Surface> = HashMap::new();
    let mut seen: Vec<&str> = Vec::new();
    for line in libraries {
        // A file name may contain spaces; otherwise the line lists several files.
        let files: Vec<(&str, std::io::Result<Vec<u8>>)> = match load(line) {
            Ok(text) => vec![(line.as_str(), Ok(text))],
            Err(_) => line
                .split_ascii_whitespace()
                .map(|name| (name, load(name)))
                .collect(),
        };
        for (name, text) in files {
            if seen.contains(&name) {
                continue;
            }
            seen.push(name);
            let text = match text {
                Ok(text) => text,
                Err(e) => {
                    report.notes.push(format!(
                        "{}: material library '{name}' cannot be read ({e}); its materials get \
                         white default surfaces",
                        source.name
                    ));
                    continue;
                }
            };
            let materials = parse_mtl(source, name, &text)?;
            let dir = Path::new(name).parent().unwrap_or(Path::new(""));
            for m in materials {
                let alpha = m.dissolve.or_else(|| {
                    m.unknown_param
                        .get("Tr")
                        .and_then(|t| t.trim().parse::<f32>().ok())
                        .map(|tr| 1.0 - tr)
                });
                let [r, g, b] = m.diffuse.unwrap_or([1.0; 3]);
                let color = [r, g, b, alpha.unwrap_or(1.0)];
                source.check_finite(&color, &["Kd red", "Kd green", "Kd blue", "d"], || {
                    format!("{name}: material '{}'", m.name)
                })?;
                let texture = m
                    .diffuse_texture
                    .as_deref()
                    .and_then(texture_file)
                    .map(|t| dir.join(t).to_string_lossy().replace('\\', "/"));
                surfaces.entry(m.name.clone()).or_insert(Surface {
                    name: m.name,
                    base_color: color,
                    texture,
                });
            }
        }
    }
    Ok(surfaces)
}

/// The file of a `map_Kd` value, without options such as `-s 1 1 1`.
fn texture_file(value: &str) -> Option<String> {
    let value = value.trim();
    if value.starts_with('-') {
        value.split_ascii_whitespace().last().map(str::to_owned)
    } else if value.is_empty() {
        None
    } else {
        Some(value.to_owned())
    }
}

/// Parses an MTL file with tobj, after normalising the colour statements tobj would panic on
/// (`Kd 0.5` is valid MTL for a grey; tobj needs three numbers).
fn parse_mtl(
    source: &Source,
    name: &str,
    bytes: &[u8],
) -> Result<Vec<tobj::Material>, ImportError> {
    let mut text = String::with_capacity(bytes.len());
    for (i, raw) in String::from_utf8_lossy(bytes).lines().enumerate() {
        let line = raw.trim();
        let mut words = line.split_ascii_whitespace();
        match words.next() {
            Some(k @ ("Ka" | "Kd" | "Ks" | "Ke" | "Tf")) => {
                let values: Vec<&str> = words.collect();
                match values.as_slice() {
                    [v] => text.push_str(&format!("{k} {v} {v} {v}")),
                    [first, ..] if *first == "spectral" || *first == "xyz" => {}
                    [_, _, _, ..] => text.push_str(line),
                    _ => {
                        return Err(source.malformed(
                            format!("{name} line {}", i + 1),
                            format!("{k} needs 1 or 3 numbers"),
                        ))
                    }
                }
            }
            _ => text.push_str(line),
        }
        text.push('\n');
    }
    match tobj::load_mtl_buf(&mut Cursor::new(text.as_bytes())) {
        Ok((materials, _)) => Ok(materials),
        Err(e) => {
            // tobj names no line: find the first line it rejects on its own.
            let line = text
                .lines()
                .position(|l| tobj::load_mtl_buf(&mut Cursor::new(l.as_bytes())).is_err())
                .map(|i| format!("{name} line {}", i + 1))
                .unwrap_or_else(|| name.to_owned());
            Err(source.malformed(line, e.to_string()))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn src() -> Source {
        Source {
            name: "m.obj".to_owned(),
        }
    }

    fn parse_with(
        obj: &str,
        files: &[(&str, &str)],
        report: &mut ImportReport,
    ) -> Result<Mesh, ImportError> {
        let files: HashMap<String, Vec<u8>> = files
            .iter()
            .map(|(n, t)| (n.to_string(), t.as_bytes().to_vec()))
            .collect();
        let mut load = |name: &str| {
            files
                .get(name)
                .cloned()
                .ok_or_else(|| std::io::Error::new(std::io::ErrorKind::NotFound, "not found"))
        };
        parse_obj(&src(), obj.as_bytes(), &mut load, report)
    }

    fn parse(obj: &str) -> Result<Mesh, ImportError> {
        parse_with(obj, &[], &mut ImportReport::default())
    }

    #[test]
    fn corners_keep_their_own_indices() {
        let obj =
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\nvt 0.5 0.5\n\
                   vn 0 0 1\nf 1/1/1 2/2/1 3/3/1\nf 3/5/1 2/2 4/4/1\nf 1 2 4\n";
        let mesh = parse(obj).unwrap();
        mesh.validate().unwrap();
        assert_eq!(mesh.triangles.len(), 3);
        assert_eq!(mesh.triangles[1].position, [2, 1, 3]);
        assert_eq!(mesh.triangles[1].uv, [4, 1, 3]);
        assert_eq!(mesh.triangles[1].normal, [0, NO_ATTRIBUTE, 0]);
        assert_eq!(mesh.triangles[2].uv, [NO_ATTRIBUTE; 3]);
        assert_eq!(mesh.uvs[2], [0.0, 0.0], "v is flipped");
        assert_eq!(mesh.surfaces.len(), 1);
        assert_eq!(mesh.surfaces[0].name, "default");
    }

    #[test]
    fn polygons_relative_indices_and_continuations() {
        let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0 \\\n\nv 0 1 0\nv -1 0.5 0 2\nf -5 -4 -3 -2 \\\n -1\n";
        let mesh = parse(obj).unwrap();
        let tris: Vec<[u32; 3]> = mesh.triangles.iter().map(|t| t.position).collect();
        assert_eq!(tris, vec![[0, 1, 2], [0, 2, 3], [0, 3, 4]]);
        assert_eq!(mesh.positions[4], [-0.5, 0.25, 0.0], "w divides");
    }

    #[test]
    fn vertex_colours_are_per_position() {
        let obj = "v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0 0 0 1\nf 1 2 3\n";
        let mesh = parse(obj).unwrap();
        assert_eq!(mesh.colors.len(), 2);
        assert_eq!(mesh.triangles[0].color, [0, NO_ATTRIBUTE, 1]);
        assert_eq!(mesh.colors[1], [0.0, 0.0, 1.0, 1.0]);
    }

    #[test]
    fn errors_name_the_line() {
        let head = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\n";
        let err = |tail: &str| parse(&format!("{head}{tail}")).unwrap_err().to_string();
        assert_eq!(
            err("f 1 2 3\nf 1 2 4\n"),
            "m.obj: line 6: vertex index 4 out of range (3 positions)"
        );
        assert_eq!(
            err("f 1/1 2/2 3/1\n"),
            "m.obj: line 5: texture coordinate index 2 out of range (1 texture coordinates)"
        );
        assert_eq!(
            err("f 1//1 2//1 3//1\n"),
            "m.obj: line 5: normal index 1 out of range (0 normals)"
        );
        assert_eq!(
            err("f -4 1 2\n"),
            "m.obj: line 5: vertex index -4 out of range (3 positions)"
        );
        assert!(err("f 1/0 2/1 3/1\n").contains("line 5: face corner '1/0': index 0"));
        assert!(err("f 1 2 x\n").contains("line 5: face corner 'x'"));
        assert!(err("f 1/1/1/1 2 3\n").contains("more than three indices"));
        assert_eq!(err("v 1 nan 0\n"), "m.obj: line 5: coordinate y is NaN");
        assert_eq!(err("vn 1 0 inf\n"), "m.obj: line 5: normal z is inf");
        assert!(err("v 1 2\n").contains("line 5: v needs 3, 4, 6 or 7 numbers, found 2"));
        assert!(err("v 1 2 3 0\n").contains("line 5: vertex weight w is 0"));
        assert!(err("vt 1 abc\n").contains("line 5: vt: 'abc' is not a number"));
        // A forward reference resolves once the vertex exists.
        assert!(parse(&format!("{head}f 1 2 4\nv 1 1 0\n")).is_ok());
    }

    #[test]
    fn points_and_lines_are_skipped_and_counted() {
        let mut report = ImportReport::default();
        let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\np 1\nl 1 2\nf 1 2\nf 1 2 3\ncurv 0 1 1 2\n";
        let mesh = parse_with(obj, &[], &mut report).unwrap();
        assert_eq!(mesh.triangles.len(), 1);
        assert_eq!(report.skipped_primitives, 3);
        assert!(
            report.notes.iter().any(|n| n.contains("'curv'")),
            "{:?}",
            report.notes
        );
    }

    #[test]
    fn materials_become_surfaces_in_order_of_use() {
        let mtl = "newmtl red\nKd 1 0 0\nd 0.5\nmap_Kd -s 1 1 1 tex/red.png\n\
                   newmtl grey\nKd 0.5\nnewmtl unused\nKd 0 1 0\n";
        let obj = "mtllib lib/m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl grey\nf 1 2 3\n\
                   usemtl red\nf 1 3 2\nusemtl grey\nf 2 1 3\nusemtl ghost\nf 3 2 1\n";
        let mut report = ImportReport::default();
        let mesh = parse_with(obj, &[("lib/m.mtl", mtl)], &mut report).unwrap();
        let names: Vec<&str> = mesh.surfaces.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["grey", "red", "ghost"]);
        assert_eq!(mesh.surfaces[0].base_color, [0.5, 0.5, 0.5, 1.0]);
        assert_eq!(mesh.surfaces[1].base_color, [1.0, 0.0, 0.0, 0.5]);
        assert_eq!(mesh.surfaces[1].texture.as_deref(), Some("lib/tex/red.png"));
        assert_eq!(mesh.surfaces[2].base_color, [1.0; 4]);
        let ids: Vec<u16> = mesh.triangles.iter().map(|t| t.surface).collect();
        assert_eq!(ids, [0, 1, 0, 2]);
        assert!(
            report.notes.iter().any(|n| n.contains("'ghost'")),
            "{:?}",
            report.notes
        );
    }

    #[test]
    fn missing_mtl_keeps_material_names() {
        let obj =
            "mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\nusemtl b\nf 1 3 2\n";
        let mut report = ImportReport::default();
        let mesh = parse_with(obj, &[], &mut report).unwrap();
        let names: Vec<&str> = mesh.surfaces.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["a", "b"]);
        assert!(report
            .notes
            .iter()
            .any(|n| n.contains("'gone.mtl' cannot be read")));
    }

    #[test]
    fn malformed_mtl_names_its_line() {
        let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n";
        let mut report = ImportReport::default();
        let err = parse_with(obj, &[("m.mtl", "newmtl a\nKd 1 0\n")], &mut report)
            .unwrap_err()
            .to_string();
        assert_eq!(err, "m.obj: m.mtl line 2: Kd needs 1 or 3 numbers");
        let err = parse_with(obj, &[("m.mtl", "newmtl a\nNs 1\nillum x\n")], &mut report)
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("m.obj: m.mtl line 3: "), "{err}");
    }
}
