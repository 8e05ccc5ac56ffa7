//! MTL libraries to surfaces: `Kd` with `d` (or `1 - Tr`) as alpha (blended when below 1),
//! `map_Kd` relative to the OBJ; MTL files parsed with `tobj`. MTL has no double-sided
//! materials.

use std::collections::HashMap;
use std::io::Cursor;
use std::path::Path;

use crate::import::error::{ImportError, Source};
use crate::import::ids::push_surface;
use crate::import::options::{ImportReport, Loader};
use crate::mesh::{AlphaMode, Mesh, Surface, Texture};

/// A surface as the OBJ names it, before the MTL files are consulted.
pub(super) struct NamedSurface {
    pub(super) name: String,
}

/// The materials the MTL libraries define, and whether the OBJ named any library.
pub(super) struct MaterialLibraries<'a> {
    pub(super) materials: &'a HashMap<String, Surface>,
    pub(super) any: bool,
}

/// One surface per material name in order of first use; names no MTL defines get white
/// (noted, unless it is the `default` of a file without libraries).
pub(super) fn push_surfaces(
    source: &Source,
    mesh: &mut Mesh,
    surfaces: &[NamedSurface],
    defined: &MaterialLibraries<'_>,
    report: &mut ImportReport,
) -> Result<(), ImportError> {
    for named in surfaces {
        let surface = match defined.materials.get(&named.name) {
            Some(s) => s.clone(),
            None => {
                if named.name != "default" || defined.any {
                    report.notes.push(format!(
                        "{}: material '{}' is not defined in any MTL file; it gets a white \
                         default surface",
                        source.name, named.name
                    ));
                }
                Surface::plain(named.name.as_str())
            }
        };
        push_surface(source, mesh, surface)?;
    }
    Ok(())
}

/// Reads the MTL libraries into surfaces by material name (the first definition of a name
/// wins). Missing files are noted, malformed ones are errors.
pub(super) fn load_materials(
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
                    .map(|t| Texture::File(dir.join(t).to_string_lossy().replace('\\', "/")));
                let alpha = if color[3] < 1.0 {
                    AlphaMode::Blend
                } else {
                    AlphaMode::Opaque
                };
                surfaces.entry(m.name.clone()).or_insert(Surface {
                    name: m.name,
                    base_color: color,
                    texture,
                    alpha,
                    double_sided: false,
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
