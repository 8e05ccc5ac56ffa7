//! glTF 2.0 meshes (`.gltf` with external or data-URI buffers, and `.glb`).
//!
//! The `gltf` crate parses and validates the JSON (every index reference checked). Everything
//! that touches bytes is done here, with explicit checks, because the crate's own readers
//! assume a valid file (its GLB header parsing underflows on a short length, its buffer loader
//! unwraps the percent-decoding of URIs, its accessor readers slice without bounds checks):
//! the GLB container, buffer loading (relative files, `data:` base64 URIs, the GLB `BIN`
//! chunk), and every accessor read, which is checked against its buffer view (offset, stride,
//! count) and the view against its buffer before a byte is read. No image is decoded.
//!
//! Imported: the default scene (or the first; or, without scenes, every root node), each
//! node's mesh with the node's world transform applied (normals by the inverse transpose,
//! winding flipped when the determinant is negative); primitives in `TRIANGLES`,
//! `TRIANGLE_STRIP` and `TRIANGLE_FAN` modes (strips and fans converted, their degenerate
//! joint triangles dropped), indexed or not; attributes `POSITION`, `NORMAL`, `TEXCOORD_0`,
//! `COLOR_0` (`VEC3` or `VEC4`), in any component type the specification allows (normalized
//! integers converted), sparse accessors included. Each material becomes one surface (name,
//! `baseColorFactor`, the base-colour texture's image, `alphaMode` with `alphaCutoff`,
//! `doubleSided`): an image with a URI is a file relative to the glTF file, one in a buffer
//! view (GLB) or a `data:` URI is kept as its bytes with its MIME type (neither is decoded);
//! primitives without a material share a surface named `default`. `POINTS` and `LINE*` primitives are
//! skipped and counted; morph targets and skins are ignored (the base shape in its bind pose).
//!
//! Rejected with an error naming the element: accessors or buffer views out of bounds, index
//! values out of range, attributes of different lengths, NaN or infinite values, a
//! non-finite node transform, cycles in the node hierarchy, missing or short buffers, and
//! required extensions other than `KHR_mesh_quantization`, `KHR_texture_transform` and the
//! `KHR_materials_*` family (Draco and meshopt compression are not decoded).

mod accessors;
mod buffers;
mod importer;
mod materials;
mod primitives;
mod scene;
#[cfg(test)]
pub(crate) mod tests;

use std::collections::HashMap;

use ::gltf::json;
use ::gltf::Semantic;

use crate::import::error::{ImportError, Source};
use crate::import::options::{ImportOptions, ImportReport, Loader};
use crate::mesh::Mesh;
use buffers::{load_buffers, split_glb};
use importer::Importer;

pub(crate) fn import_gltf(
    source: &Source,
    bytes: &[u8],
    load: &mut Loader<'_>,
    _options: &ImportOptions,
    report: &mut ImportReport,
) -> Result<Mesh, ImportError> {
    let glb = std::path::Path::new(&source.name)
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    sniff(source, bytes, glb)?;
    import_bytes(source, bytes, load, report)
}

/// The file's first bytes checked against its extension: a `.glb` starts with the magic
/// `glTF`; a `.gltf` with a JSON object (or, binary under the other name, the magic).
fn sniff(source: &Source, bytes: &[u8], glb: bool) -> Result<(), ImportError> {
    if bytes.starts_with(b"glTF") {
        return Ok(());
    }
    let start: Vec<String> = bytes.iter().take(4).map(|b| format!("{b:02x}")).collect();
    let start = if start.is_empty() {
        "the file is empty".to_owned()
    } else {
        format!("it starts with bytes {}", start.join(" "))
    };
    if glb {
        return Err(source.malformed(
            "header",
            format!("not a binary glTF file ({start}); expected the magic 'glTF'"),
        ));
    }
    let text = bytes.strip_prefix(b"\xef\xbb\xbf").unwrap_or(bytes);
    match text.iter().find(|b| !b.is_ascii_whitespace()) {
        Some(b'{') => Ok(()),
        _ => Err(source.malformed(
            "header",
            format!(
                "not a glTF JSON file ({start}); expected a JSON object '{{' or the magic 'glTF'"
            ),
        )),
    }
}

/// The passes: the container, the validated document, the buffers, then every mesh of the
/// scene's nodes, and the notes about what was dropped or ignored on the way.
fn import_bytes(
    source: &Source,
    bytes: &[u8],
    load: &mut Loader<'_>,
    report: &mut ImportReport,
) -> Result<Mesh, ImportError> {
    let (json_bytes, blob) = if bytes.starts_with(b"glTF") {
        split_glb(source, bytes)?
    } else {
        (bytes, None)
    };
    let document = parse_document(source, json_bytes, report)?;
    let root = document.as_json();
    let buffers = load_buffers(source, root, blob, load)?;
    let mut reader = Importer {
        source,
        root,
        buffers: &buffers,
        mesh: Mesh::default(),
        surfaces: HashMap::new(),
        report,
        strip_joints: 0,
        ignored_targets: 0,
        ignored_skins: 0,
    };
    reader.add_scene(&document)?;
    Ok(reader.finish())
}

/// The JSON parsed, checked by [`prepare_root`], then validated by the crate.
fn parse_document(
    source: &Source,
    json_bytes: &[u8],
    report: &mut ImportReport,
) -> Result<::gltf::Document, ImportError> {
    let mut root = json::Root::from_slice(json_bytes).map_err(|e| {
        if e.is_eof() {
            source.truncated(format!(
                "JSON: the document ends at line {} column {}; expected the rest of it",
                e.line(),
                e.column()
            ))
        } else {
            source.malformed("JSON", e.to_string())
        }
    })?;
    prepare_root(source, &mut root, report)?;
    ::gltf::Document::from_json(root).map_err(|e| match e {
        ::gltf::Error::Validation(errors) => validation_error(source, &errors),
        other => source.malformed("document", other.to_string()),
    })
}

/// The crate's validation errors, the first five of them named.
fn validation_error(
    source: &Source,
    errors: &[(json::Path, json::validation::Error)],
) -> ImportError {
    let shown: Vec<String> = errors
        .iter()
        .take(5)
        .map(|(path, error)| format!("{path}: {error}"))
        .collect();
    let more = errors.len().saturating_sub(shown.len());
    source.malformed(
        "document",
        format!(
            "invalid glTF: {}{}",
            shown.join("; "),
            if more > 0 {
                format!(" (and {more} more)")
            } else {
                String::new()
            }
        ),
    )
}

/// Required extensions this importer handles (the others change geometry or its storage:
/// Draco and meshopt compression, GPU instancing, ...).
const HANDLED_EXTENSIONS: &[&str] = &[
    "KHR_mesh_quantization",
    "KHR_texture_transform",
    "KHR_lights_punctual",
    "KHR_texture_basisu",
    "EXT_texture_webp",
    "EXT_texture_avif",
    "MSFT_texture_dds",
];

/// Checks what the crate's validation would get wrong before it runs: required extensions
/// (the crate knows only the ones compiled into it, and not `KHR_mesh_quantization`, which
/// the accessor reader handles), POSITION accessors that do not exist (its validation indexes
/// them without a check), and POSITION accessors without `min`/`max` (required by the
/// specification, often missing, never needed here: filled in with a note).
fn prepare_root(
    source: &Source,
    root: &mut json::Root,
    report: &mut ImportReport,
) -> Result<(), ImportError> {
    check_extensions(source, root, report)?;
    root.extensions_required.clear();
    fill_position_bounds(source, root, report)
}

/// Rejects required extensions that change geometry or its storage; notes the ones whose
/// effect is dropped.
fn check_extensions(
    source: &Source,
    root: &json::Root,
    report: &mut ImportReport,
) -> Result<(), ImportError> {
    for ext in &root.extensions_required {
        if !(HANDLED_EXTENSIONS.contains(&ext.as_str()) || ext.starts_with("KHR_materials_")) {
            return Err(source.unsupported(
                "extensionsRequired",
                format!("extension {ext} (compressed or extended geometry is not decoded)"),
            ));
        }
    }
    if root
        .extensions_required
        .iter()
        .any(|e| e == "KHR_texture_transform")
    {
        report.notes.push(format!(
            "{}: KHR_texture_transform is ignored: UVs are imported untransformed",
            source.name
        ));
    }
    Ok(())
}

/// Every POSITION accessor exists and has a three-number `min` and `max` (zeros where
/// missing, with a note).
fn fill_position_bounds(
    source: &Source,
    root: &mut json::Root,
    report: &mut ImportReport,
) -> Result<(), ImportError> {
    let accessors = root.accessors.len();
    let mut filled = 0;
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let Some(index) = primitive
                .attributes
                .get(&json::validation::Checked::Valid(Semantic::Positions))
            else {
                continue;
            };
            let Some(accessor) = root.accessors.get_mut(index.value()) else {
                return Err(source.out_of_range(
                    format!("mesh {m} primitive {p} POSITION"),
                    "accessor",
                    index.value() as i64,
                    accessors,
                    "accessors",
                ));
            };
            for bound in [&mut accessor.min, &mut accessor.max] {
                let valid = bound
                    .as_ref()
                    .and_then(|v| v.as_array())
                    .is_some_and(|a| a.len() == 3 && a.iter().all(|x| x.is_number()));
                if !valid {
                    *bound = Some(json::Value::from(vec![0.0; 3]));
                    filled += 1;
                }
            }
        }
    }
    if filled > 0 {
        report.notes.push(format!(
            "{}: {filled} POSITION min/max bounds missing or invalid (required by glTF, not \
             needed here)",
            source.name
        ));
    }
    Ok(())
}
