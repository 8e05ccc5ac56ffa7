//! Importers: files on disk, or bytes in memory, to a [`Mesh`].
//!
//! [`import`] picks the importer from the file's extension (case-insensitive);
//! [`import_bytes`] does the same for bytes held in memory under a file name, a [`Loader`] the
//! caller passes serving the files they refer to (MTL libraries, glTF buffers):
//!
//! | extension | format | source file |
//! |---|---|---|
//! | `.gltf`, `.glb` | glTF 2.0, JSON or binary | `import/gltf/` |
//! | `.obj` | Wavefront OBJ (+ MTL) | `import/obj/` |
//! | `.ply` | Stanford PLY, ascii and binary (either endianness) | `import/ply/` |
//! | `.dem` | USGS ASCII DEM | `import/dem.rs` |
//! | `.npy` | numpy array of heights (needs [`ImportOptions::spacing`]) | `import/npy.rs` |
//!
//! Each of those files documents what it supports and what it rejects. Each importer is a
//! cargo feature of the same name (`gltf`, `obj`, `ply`, `dem`, `npy`), all on by default; a
//! file whose importer is left out gives [`ImportError::FormatDisabled`].
//!
//! Every importer validates its input completely: a bad file gives an [`ImportError`] naming
//! the file and the element at fault, never a panic, and never a mesh with out-of-range
//! indices or non-finite numbers ([`Mesh::validate`] holds for every mesh returned).
//!
//! Conventions shared by all importers: positions in the file's units (heightfields: metres,
//! x east, y up, z south); UVs with `v = 0` at the top row of the image (glTF's convention; OBJ
//! and PLY `v` is flipped); colours linear RGBA (8- and 16-bit colours are taken as sRGB and
//! converted); triangles counter-clockwise seen from the front.

#[cfg(feature = "dem")]
mod dem;
mod error;
#[cfg(feature = "gltf")]
mod gltf;
#[cfg(any(feature = "dem", feature = "npy"))]
mod heightfield;
mod ids;
#[cfg(feature = "npy")]
mod npy;
#[cfg(feature = "obj")]
mod obj;
mod options;
#[cfg(feature = "ply")]
mod ply;

use std::panic::{self, AssertUnwindSafe};
use std::path::Path;

pub use error::ImportError;
pub use options::{HeightfieldInfo, ImportOptions, ImportReport, Loader};

use error::Source;

use crate::mesh::Mesh;

/// Reads the mesh in `path`, choosing the importer by extension.
///
/// See [`import_with_report`] for what was skipped along the way.
pub fn import(path: &Path, options: &ImportOptions) -> Result<Mesh, ImportError> {
    import_with_report(path, options).map(|(mesh, _)| mesh)
}

/// Like [`import`], and also returns what was skipped and any notes.
pub fn import_with_report(
    path: &Path,
    options: &ImportOptions,
) -> Result<(Mesh, ImportReport), ImportError> {
    let source = Source::new(path);
    let importer = importer_for(&source, path, options)?;
    let bytes = std::fs::read(path).map_err(|e| source.io("cannot read", e))?;
    let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let mut load = |name: &str| std::fs::read(dir.join(name));
    run_importer(source, importer, &bytes, &mut load, options)
}

/// Reads a mesh from `bytes` in memory: `name` stands for the file in errors and its
/// extension chooses the importer, as in [`import`]; `load` reads the files the input refers
/// to (MTL libraries, glTF buffers), by the name the input gives them. The same checks hold:
/// a typed error or a mesh for which [`Mesh::validate`] holds, never a panic.
pub fn import_bytes(
    name: &str,
    bytes: &[u8],
    load: &mut Loader<'_>,
    options: &ImportOptions,
) -> Result<(Mesh, ImportReport), ImportError> {
    let path = Path::new(name);
    let source = Source::new(path);
    let importer = importer_for(&source, path, options)?;
    run_importer(source, importer, bytes, load, options)
}

/// One importer: the input's bytes, a loader for the files it names, the options and the
/// report to add to.
type Importer = fn(
    &Source,
    &[u8],
    &mut Loader<'_>,
    &ImportOptions,
    &mut ImportReport,
) -> Result<Mesh, ImportError>;

/// The importer for `path`'s extension, after checking the options.
fn importer_for(
    source: &Source,
    path: &Path,
    options: &ImportOptions,
) -> Result<Importer, ImportError> {
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    let disabled = |feature: &'static str| ImportError::FormatDisabled {
        file: source.name.clone(),
        format: format!(".{}", extension.as_deref().unwrap_or_default()),
        feature,
    };
    // With every importer compiled in, the `disabled` arms below are never reached.
    #[allow(unreachable_patterns)]
    let importer: Importer = match extension.as_deref() {
        #[cfg(feature = "gltf")]
        Some("gltf") | Some("glb") => gltf::import_gltf,
        #[cfg(feature = "obj")]
        Some("obj") => obj::import_obj,
        #[cfg(feature = "ply")]
        Some("ply") => ply::import_ply,
        #[cfg(feature = "dem")]
        Some("dem") => dem::import_dem,
        #[cfg(feature = "npy")]
        Some("npy") => npy::import_npy,
        Some("gltf") | Some("glb") => return Err(disabled("gltf")),
        Some("obj") => return Err(disabled("obj")),
        Some("ply") => return Err(disabled("ply")),
        Some("dem") => return Err(disabled("dem")),
        Some("npy") => return Err(disabled("npy")),
        other => {
            return Err(ImportError::UnknownFormat {
                file: source.name.clone(),
                extension: match other {
                    Some(e) => format!(".{e}"),
                    None => "(no extension)".to_owned(),
                },
            })
        }
    };
    if let Some(spacing) = options.spacing {
        if !(spacing.is_finite() && spacing > 0.0) {
            return Err(ImportError::MissingOption {
                file: source.name.clone(),
                message: format!("spacing must be a positive number of metres, not {spacing}"),
            });
        }
    }
    Ok(importer)
}

/// Runs `importer`, turning a panic into [`ImportError::Internal`], and checks its mesh.
fn run_importer(
    source: Source,
    importer: Importer,
    bytes: &[u8],
    load: &mut Loader<'_>,
    options: &ImportOptions,
) -> Result<(Mesh, ImportReport), ImportError> {
    let mut report = ImportReport::default();
    // Every importer validates its input and returns errors; this only turns a bug (ours or a
    // dependency's) into an error instead of taking the caller down.
    let result = panic::catch_unwind(AssertUnwindSafe(|| {
        importer(&source, bytes, load, options, &mut report)
    }));
    let mesh = match result {
        Ok(result) => result?,
        Err(payload) => {
            let message = payload
                .downcast_ref::<&str>()
                .map(|s| (*s).to_owned())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "panic".to_owned());
            return Err(ImportError::Internal {
                file: source.name,
                message: format!("panicked: {message}"),
            });
        }
    };
    if let Err(message) = mesh.validate() {
        return Err(ImportError::Internal {
            file: source.name,
            message,
        });
    }
    if mesh.triangles.is_empty() {
        let detail = if report.skipped_primitives > 0 {
            format!(
                ": {} non-triangle primitives skipped",
                report.skipped_primitives
            )
        } else {
            String::new()
        };
        return Err(ImportError::Empty {
            file: source.name,
            detail,
        });
    }
    Ok((mesh, report))
}
