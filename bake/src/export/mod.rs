//! Exporting one level of a hierarchy as Wavefront OBJ, to inspect it in any viewer: with
//! its materials as an MTL file beside it, and the embedded textures as image files beside
//! that ([`material_library`]).

mod error;
mod materials;

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use caveclod_core::{Hierarchy, NodeId};

use crate::base::atomic::write_atomically_with;

pub use error::ExportError;
pub use materials::{material_library, MaterialLibrary};

/// Which level to export.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Level {
    /// Every full-resolution polygon.
    Full,
    /// The base mesh.
    Base,
}

/// The OBJ text of `level`: positions (with their colours, when the hierarchy has vertex
/// colours), normals and UVs of the vertices used, one `usemtl` group per surface named
/// `surface<N>`, and no material library.
pub fn obj(h: &Hierarchy<'_>, level: Level) -> String {
    let names: Vec<String> = (0..h.surface_count())
        .map(|s| format!("surface{s}"))
        .collect();
    obj_text(h, level, None, &names)
}

/// An OBJ export and what goes beside it.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjExport {
    /// The OBJ file's path.
    pub obj_path: PathBuf,
    /// Its text.
    pub obj: String,
    /// The material library, when the hierarchy has materials.
    pub library: Option<MaterialLibrary>,
    /// The files the export reads (the `.clod` file, the textures it names by path): no
    /// output may replace one.
    pub inputs: Vec<PathBuf>,
}

/// The OBJ export of `level` of the hierarchy read from `clod_path`, to be written at
/// `obj_path`: with the hierarchy's materials, an MTL file of the OBJ's name beside it
/// (`mtllib`, one `usemtl` per surface named after its material) whose texture paths name
/// the `.clod` file's textures from the OBJ's directory, and the embedded textures as files
/// beside it.
pub fn obj_export(
    h: &Hierarchy<'_>,
    level: Level,
    clod_path: &Path,
    obj_path: &Path,
) -> Result<ObjExport, ExportError> {
    let mut inputs = vec![clod_path.to_path_buf()];
    let (obj, library) = match material_library(h, clod_path, obj_path)? {
        None => (obj(h, level), None),
        Some(library) => {
            inputs.extend(library.texture_files.iter().cloned());
            let text = obj_text(h, level, Some(&library.file_name), &library.names);
            (text, Some(library))
        }
    };
    Ok(ObjExport {
        obj_path: obj_path.to_path_buf(),
        obj,
        library,
        inputs,
    })
}

impl ObjExport {
    /// Writes the images, then the MTL file, then the OBJ file, each through a temporary file
    /// and a rename (so the OBJ appears only once what it names is there); refuses, before
    /// writing anything, an output that would replace one of [`inputs`](Self::inputs).
    pub fn write(&self) -> Result<(), ExportError> {
        let dir = self
            .obj_path
            .parent()
            .filter(|d| !d.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        let mut outputs: Vec<(PathBuf, &[u8])> = Vec::new();
        if let Some(l) = &self.library {
            for (name, bytes) in &l.images {
                outputs.push((dir.join(name), bytes));
            }
            outputs.push((dir.join(&l.file_name), l.text.as_bytes()));
        }
        outputs.push((self.obj_path.clone(), self.obj.as_bytes()));
        for (path, _) in &outputs {
            if self.inputs.iter().any(|i| same_file(i, path)) {
                return Err(ExportError::WouldOverwriteInput(path.clone()));
            }
        }
        for (path, bytes) in outputs {
            write_atomically_with(&path, |f| f.write_all(bytes))
                .map_err(|source| ExportError::Io { path, source })?;
        }
        Ok(())
    }
}

/// Whether `a` and `b` name the same existing file: the same device and inode where the
/// system says (a hard link or a symbolic link to it counts), else the same canonical path.
fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (std::fs::metadata(a), std::fs::metadata(b)) {
            (Ok(ma), Ok(mb)) => ma.dev() == mb.dev() && ma.ino() == mb.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
}

/// The OBJ text of `level` with `mtllib` (when given) and the surfaces' `usemtl` names.
fn obj_text(h: &Hierarchy<'_>, level: Level, mtllib: Option<&str>, names: &[String]) -> String {
    let tris: Vec<(usize, [NodeId; 3])> = match level {
        Level::Full => h
            .polygons()
            .iter()
            .enumerate()
            .map(|(i, p)| (i, p.nodes))
            .collect(),
        Level::Base => h
            .base()
            .iter()
            .enumerate()
            .map(|(i, b)| (i, b.corners))
            .collect(),
    };
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# caveclod export: {} level, {} triangles",
        if level == Level::Full { "full" } else { "base" },
        tris.len()
    );
    if let Some(lib) = mtllib {
        let _ = writeln!(out, "mtllib {lib}");
    }
    let colours = h.vertex_colours();
    let mut index = vec![0u32; h.vertices().len()];
    let mut next = 1u32;
    let mut faces: Vec<Vec<[u32; 3]>> = vec![Vec::new(); h.surface_count()];
    for &(poly, corners) in &tris {
        let p = &h.polygons()[poly];
        let mut f = [0u32; 3];
        for k in 0..3 {
            let pos = h.nodes()[corners[k].index()].position;
            // Validated at load: the group has a vertex at every corner of every level.
            let v = h.vertex_index(p.group, pos).unwrap_or(0) as usize;
            if index[v] == 0 {
                let x = h.vertices()[v];
                let _ = write!(
                    out,
                    "v {} {} {}",
                    x.position[0], x.position[1], x.position[2]
                );
                if let Some(c) = colours.and_then(|c| c.get(v)) {
                    write_colour(&mut out, *c);
                }
                out.push('\n');
                let _ = writeln!(out, "vn {} {} {}", x.normal[0], x.normal[1], x.normal[2]);
                // OBJ's v points up; the format's (glTF's) points down.
                let _ = writeln!(out, "vt {} {}", x.uv[0], 1.0 - x.uv[1]);
                index[v] = next;
                next += 1;
            }
            f[k] = index[v];
        }
        faces[p.surface.index()].push(f);
    }
    for (s, fs) in faces.iter().enumerate() {
        if fs.is_empty() {
            continue;
        }
        let _ = writeln!(out, "usemtl {}", names[s]);
        for f in fs {
            let _ = writeln!(
                out,
                "f {0}/{0}/{0} {1}/{1}/{1} {2}/{2}/{2}",
                f[0], f[1], f[2]
            );
        }
    }
    out
}

/// ` r g b` of an OBJ vertex colour (the stored sRGB values in 0..=1, as OBJ tools read
/// them), and ` a` when not opaque.
fn write_colour(out: &mut String, c: [u8; 4]) {
    let f = |v: u8| f32::from(v) / 255.0;
    let _ = write!(out, " {} {} {}", f(c[0]), f(c[1]), f(c[2]));
    if c[3] != 255 {
        let _ = write!(out, " {}", f(c[3]));
    }
}
