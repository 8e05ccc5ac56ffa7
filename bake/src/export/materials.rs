//! The MTL file of an OBJ export: one `newmtl` per surface with `Kd` and `d` (the base
//! colour factor), `map_Kd` (the texture, by a path from the OBJ's directory), and what MTL
//! cannot say (alpha mode, double-sidedness) as a comment. Embedded textures become image
//! files beside the MTL, named after the OBJ and the material.

use std::collections::HashSet;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use caveclod_core::format::materials::{AlphaMode, TextureRef};
use caveclod_core::Hierarchy;

use super::error::ExportError;
use crate::materials::TexturePaths;

/// An MTL file and the images it names.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialLibrary {
    /// Its file name, beside the OBJ (the OBJ's with `.mtl`).
    pub file_name: String,
    /// Its text.
    pub text: String,
    /// Each surface's material name in the library: unique, non-empty, one line.
    pub names: Vec<String>,
    /// The embedded textures: file name (beside the MTL) and bytes.
    pub images: Vec<(String, Vec<u8>)>,
    /// The texture files the library names by path, as paths to open.
    pub texture_files: Vec<PathBuf>,
}

/// The MTL library of an OBJ at `obj_path` exported from the `.clod` file at `clod_path`, or
/// `None` when the hierarchy has no materials.
pub fn material_library(
    h: &Hierarchy<'_>,
    clod_path: &Path,
    obj_path: &Path,
) -> Result<Option<MaterialLibrary>, ExportError> {
    let Some(materials) = h.materials() else {
        return Ok(None);
    };
    let dir_of = |p: &Path| p.parent().unwrap_or(Path::new("")).to_path_buf();
    let (clod_dir, obj_dir) = (dir_of(clod_path), dir_of(obj_path));
    let paths = TexturePaths::new(&clod_dir, &obj_dir);
    let stem = obj_path
        .file_stem()
        .map_or("export".into(), |s| s.to_string_lossy().into_owned());
    let mut library = MaterialLibrary {
        file_name: format!("{stem}.mtl"),
        text: String::from("# caveclod export: materials\n"),
        names: unique_names(materials.iter().map(|m| m.name)),
        images: Vec::new(),
        texture_files: Vec::new(),
    };
    let mut image_names = HashSet::new();
    for (s, m) in materials.iter().enumerate() {
        let name = library.names[s].clone();
        let map = match m.texture {
            None => None,
            Some(TextureRef::Path(p)) => {
                let from_obj = paths.rewrite(p).map_err(|problem| ExportError::Texture {
                    surface: s,
                    name: m.name.to_owned(),
                    texture: p.to_owned(),
                    problem,
                })?;
                library.texture_files.push(clod_dir.join(p));
                Some(from_obj)
            }
            Some(TextureRef::Embedded { mime, bytes }) => {
                let file = image_file_name(&stem, &name, mime, &mut image_names);
                library.images.push((file.clone(), bytes.to_vec()));
                Some(file)
            }
        };
        let t = &mut library.text;
        let [r, g, b, a] = m.base_colour;
        let _ = writeln!(t, "\nnewmtl {name}");
        let _ = writeln!(t, "Kd {r} {g} {b}");
        let _ = writeln!(t, "d {a}");
        if let Some(map) = map {
            let _ = writeln!(t, "map_Kd {map}");
        }
        let alpha = match m.alpha {
            AlphaMode::Mask { cutoff } => format!("MASK {cutoff}"),
            other => other.name().to_owned(),
        };
        let sides = if m.double_sided { ", double-sided" } else { "" };
        let _ = writeln!(t, "# alpha {alpha}{sides}");
    }
    Ok(Some(library))
}

/// The materials' names as MTL names: on one line, non-empty (`surface<N>` for an empty
/// one), and unique (a repeated name gets `_<N>`, `N` its surface).
fn unique_names<'a>(names: impl Iterator<Item = &'a str>) -> Vec<String> {
    let mut seen = HashSet::new();
    names
        .enumerate()
        .map(|(s, n)| {
            let one_line: String = n
                .trim()
                .chars()
                .map(|c| if c.is_control() { '_' } else { c })
                .collect();
            let mut name = if one_line.is_empty() {
                format!("surface{s}")
            } else {
                one_line
            };
            if !seen.insert(name.clone()) {
                name = format!("{name}_{s}");
                seen.insert(name.clone());
            }
            name
        })
        .collect()
}

/// `<stem>_<material>.<ext>`, with only letters, digits, `-`, `_` and `.` (others become
/// `_`), unique among `taken`.
fn image_file_name(stem: &str, material: &str, mime: &str, taken: &mut HashSet<String>) -> String {
    let safe = |s: &str| -> String {
        s.chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || "-_.".contains(c) {
                    c
                } else {
                    '_'
                }
            })
            .collect()
    };
    let ext = match mime {
        "image/png" => "png",
        "image/jpeg" => "jpg",
        "image/webp" => "webp",
        "image/ktx2" => "ktx2",
        "image/avif" => "avif",
        _ => "bin",
    };
    let base = format!("{}_{}", safe(stem), safe(material));
    let mut name = format!("{base}.{ext}");
    let mut n = 1;
    while !taken.insert(name.clone()) {
        name = format!("{base}_{n}.{ext}");
        n += 1;
    }
    name
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_on_one_line() {
        let names = unique_names(["Wood", "", "Wood", "two\nlines"].into_iter());
        assert_eq!(names, ["Wood", "surface1", "Wood_2", "two_lines"]);
    }

    #[test]
    fn image_names_are_safe_and_unique() {
        let mut taken = HashSet::new();
        assert_eq!(
            image_file_name("helmet", "Glass/Lens", "image/png", &mut taken),
            "helmet_Glass_Lens.png"
        );
        assert_eq!(
            image_file_name("helmet", "Glass Lens", "image/png", &mut taken),
            "helmet_Glass_Lens_1.png"
        );
        assert_eq!(
            image_file_name("helmet", "x", "image/jpeg", &mut taken),
            "helmet_x.jpg"
        );
    }
}
