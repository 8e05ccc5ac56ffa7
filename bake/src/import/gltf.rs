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
//! `baseColorFactor`, the base-colour texture's URI, relative to the glTF file); primitives
//! without a material share a surface named `default`. `POINTS` and `LINE*` primitives are
//! skipped and counted; morph targets and skins are ignored (the base shape in its bind pose).
//!
//! Rejected with an error naming the element: accessors or buffer views out of bounds, index
//! values out of range, attributes of different lengths, NaN or infinite values, a
//! non-finite node transform, cycles in the node hierarchy, missing or short buffers, and
//! required extensions other than `KHR_mesh_quantization`, `KHR_texture_transform` and the
//! `KHR_materials_*` family (Draco and meshopt compression are not decoded).

use std::collections::HashMap;
use std::path::Path;

use ::gltf::json;
use ::gltf::mesh::Mode;
use ::gltf::Semantic;
use json::accessor::{ComponentType, Type};

use super::{next_index, push_surface, read_file, ImportError};
use super::{ImportOptions, ImportReport, Source};
use crate::mesh::{Mesh, Surface, Triangle, NO_ATTRIBUTE};

pub(crate) fn import_gltf(
    source: &Source,
    path: &Path,
    _options: &ImportOptions,
    report: &mut ImportReport,
) -> Result<Mesh, ImportError> {
    let bytes = read_file(source, path)?;
    let base = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let mut load = |uri: &str| std::fs::read(base.join(uri));
    import_bytes(source, &bytes, &mut load, report)
}

/// Loads a file a URI names, relative to the glTF file.
type Loader<'a> = dyn FnMut(&str) -> std::io::Result<Vec<u8>> + 'a;

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
    let mut root =
        json::Root::from_slice(json_bytes).map_err(|e| source.malformed("JSON", e.to_string()))?;
    prepare_root(source, &mut root, report)?;
    let document = ::gltf::Document::from_json(root).map_err(|e| match e {
        ::gltf::Error::Validation(errors) => {
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
        other => source.malformed("document", other.to_string()),
    })?;
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
    let nodes: Vec<::gltf::Node<'_>> = document.nodes().collect();
    for (node, world) in scene_nodes(source, &document, &nodes)? {
        let n = &nodes[node];
        if n.skin().is_some() {
            reader.ignored_skins += 1;
        }
        if let Some(mesh) = n.mesh() {
            reader.add_mesh(&mesh, &world)?;
        }
    }
    let Importer {
        mesh,
        report,
        strip_joints,
        ignored_targets,
        ignored_skins,
        ..
    } = reader;
    if strip_joints > 0 {
        report.notes.push(format!(
            "{}: {strip_joints} degenerate triangles joining strips or fans dropped",
            source.name
        ));
    }
    if report.skipped_primitives > 0 {
        report.notes.push(format!(
            "{}: {} POINTS or LINES primitives skipped",
            source.name, report.skipped_primitives
        ));
    }
    if ignored_targets > 0 {
        report.notes.push(format!(
            "{}: morph targets of {ignored_targets} primitives ignored (base shape imported)",
            source.name
        ));
    }
    if ignored_skins > 0 {
        report.notes.push(format!(
            "{}: skins of {ignored_skins} nodes ignored (bind pose imported)",
            source.name
        ));
    }
    Ok(mesh)
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
    root.extensions_required.clear();
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

/// The JSON and BIN chunks of a GLB file.
fn split_glb<'a>(
    source: &Source,
    bytes: &'a [u8],
) -> Result<(&'a [u8], Option<&'a [u8]>), ImportError> {
    let u32_at = |at: usize| {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
    };
    let (Some(version), Some(length)) = (u32_at(4), u32_at(8)) else {
        return Err(source.truncated("the 12-byte GLB header is cut off"));
    };
    if version != 2 {
        return Err(source.unsupported("GLB header", format!("glTF version {version}")));
    }
    if length > bytes.len() {
        return Err(source.truncated(format!(
            "the GLB header says {length} bytes, the file has {}",
            bytes.len()
        )));
    }
    let bytes = &bytes[..length];
    let mut at = 12;
    let mut json = None;
    let mut bin = None;
    let mut index = 0;
    while at < bytes.len() {
        let (Some(len), Some(kind)) = (u32_at(at), u32_at(at + 4)) else {
            return Err(source.truncated(format!("GLB chunk {index} header is cut off")));
        };
        let start = at + 8;
        let end = start
            .checked_add(len)
            .filter(|&e| e <= bytes.len())
            .ok_or_else(|| {
                source.truncated(format!(
                    "GLB chunk {index} claims {len} bytes, {} remain",
                    bytes.len() - start.min(bytes.len())
                ))
            })?;
        match (kind, index) {
            (0x4E4F_534A, 0) => json = Some(&bytes[start..end]),
            (0x004E_4942, 1) => bin = Some(&bytes[start..end]),
            (_, 0) => {
                return Err(source.malformed("GLB chunk 0", "the first chunk is not JSON"));
            }
            _ => {}
        }
        at = end;
        index += 1;
    }
    let json = json.ok_or_else(|| source.malformed("GLB", "no JSON chunk"))?;
    Ok((json, bin))
}

fn load_buffers(
    source: &Source,
    root: &json::Root,
    blob: Option<&[u8]>,
    load: &mut Loader<'_>,
) -> Result<Vec<Vec<u8>>, ImportError> {
    let mut buffers = Vec::with_capacity(root.buffers.len());
    for (i, buffer) in root.buffers.iter().enumerate() {
        let declared = buffer.byte_length.0;
        let (data, what) = match buffer.uri.as_deref() {
            None => match blob {
                Some(blob) if i == 0 => (blob.to_vec(), format!("buffer {i} (GLB BIN chunk)")),
                _ => {
                    return Err(source
                        .malformed(format!("buffer {i}"), "no uri and no GLB BIN chunk to read"))
                }
            },
            Some(uri) => {
                let what = format!("buffer {i}");
                if let Some(rest) = uri.strip_prefix("data:") {
                    let payload = rest.split_once(";base64,").map(|(_, p)| p).ok_or_else(|| {
                        source.unsupported(&what, "data URI without base64 encoding")
                    })?;
                    let data = decode_base64(payload)
                        .ok_or_else(|| source.malformed(&what, "data URI is not valid base64"))?;
                    (data, what)
                } else {
                    let file = decode_uri(source, &what, uri)?;
                    let what = format!("{what} ('{file}')");
                    let data = load(&file).map_err(|e| source.io(&what, e))?;
                    (data, what)
                }
            }
        };
        if (data.len() as u64) < declared {
            return Err(source.truncated(format!(
                "{what} has {} bytes, its byteLength is {declared}",
                data.len()
            )));
        }
        buffers.push(data);
    }
    Ok(buffers)
}

/// A relative URI to a file name: percent-decoded, UTF-8, no scheme.
fn decode_uri(source: &Source, what: &str, uri: &str) -> Result<String, ImportError> {
    if let Some((scheme, _)) = uri.split_once(':') {
        if !scheme.is_empty()
            && scheme
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
            && scheme.len() > 1
        {
            return Err(source.unsupported(
                what,
                format!("URI scheme '{scheme}:' (only relative paths and data URIs are read)"),
            ));
        }
    }
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = bytes
                .get(i + 1..i + 3)
                .and_then(|h| std::str::from_utf8(h).ok())
                .and_then(|h| u8::from_str_radix(h, 16).ok())
                .ok_or_else(|| {
                    source.malformed(what, format!("bad percent-encoding in '{uri}'"))
                })?;
            out.push(hex);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out)
        .map_err(|_| source.malformed(what, format!("'{uri}' does not decode to UTF-8")))
}

/// Standard base64 (padding optional); `None` if any other character appears.
fn decode_base64(text: &str) -> Option<Vec<u8>> {
    let mut out = Vec::with_capacity(text.len() / 4 * 3);
    let mut acc = 0u32;
    let mut bits = 0;
    for c in text.trim_end_matches('=').bytes() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        };
        acc = (acc << 6) | u32::from(v);
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    Some(out)
}

/// Column-major 4 x 4 matrix, as glTF stores it.
type Mat4 = [[f64; 4]; 4];

fn mul(a: &Mat4, b: &Mat4) -> Mat4 {
    let mut m = [[0.0; 4]; 4];
    for (c, col) in m.iter_mut().enumerate() {
        for (r, v) in col.iter_mut().enumerate() {
            *v = (0..4).map(|k| a[k][r] * b[c][k]).sum();
        }
    }
    m
}

const IDENTITY: Mat4 = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
    [0.0, 0.0, 0.0, 1.0],
];

/// The nodes to draw with their world matrices, depth first.
fn scene_nodes(
    source: &Source,
    document: &::gltf::Document,
    nodes: &[::gltf::Node<'_>],
) -> Result<Vec<(usize, Mat4)>, ImportError> {
    let roots: Vec<usize> = match document
        .default_scene()
        .or_else(|| document.scenes().next())
    {
        Some(scene) => scene.nodes().map(|n| n.index()).collect(),
        None => {
            let mut is_child = vec![false; nodes.len()];
            for n in nodes {
                for c in n.children() {
                    is_child[c.index()] = true;
                }
            }
            (0..nodes.len()).filter(|&i| !is_child[i]).collect()
        }
    };
    let mut visited = vec![false; nodes.len()];
    let mut out = Vec::new();
    let mut stack: Vec<(usize, Mat4)> = roots.into_iter().rev().map(|r| (r, IDENTITY)).collect();
    while let Some((i, parent)) = stack.pop() {
        let node = &nodes[i];
        let name = || match node.name() {
            Some(n) => format!("node {i} ('{n}')"),
            None => format!("node {i}"),
        };
        if std::mem::replace(&mut visited[i], true) {
            return Err(source.malformed(
                name(),
                "appears twice in the scene's node hierarchy (a cycle or a shared child)",
            ));
        }
        let local = node.transform().matrix().map(|c| c.map(f64::from));
        let world = mul(&parent, &local);
        if world.iter().flatten().any(|v| !v.is_finite()) {
            return Err(source.non_finite(name(), "world transform", f64::NAN));
        }
        out.push((i, world));
        let children: Vec<usize> = node.children().map(|c| c.index()).collect();
        for c in children.into_iter().rev() {
            stack.push((c, world));
        }
    }
    Ok(out)
}

/// What an attribute accessor must look like.
struct Expect {
    semantic: &'static str,
    dims: &'static [usize],
}

struct Importer<'a> {
    source: &'a Source,
    root: &'a json::Root,
    buffers: &'a [Vec<u8>],
    mesh: Mesh,
    /// Material index (`None`: no material) to surface id.
    surfaces: HashMap<Option<usize>, u16>,
    report: &'a mut ImportReport,
    strip_joints: usize,
    ignored_targets: usize,
    ignored_skins: usize,
}

impl Importer<'_> {
    fn add_mesh(&mut self, mesh: &::gltf::Mesh<'_>, world: &Mat4) -> Result<(), ImportError> {
        let mesh_name = match mesh.name() {
            Some(n) => format!("mesh '{n}'"),
            None => format!("mesh {}", mesh.index()),
        };
        // Upper 3 x 3 of the world matrix, its cofactor matrix (det * inverse transpose) for
        // normals, and its determinant for winding.
        let a = |r: usize, c: usize| world[c][r];
        let cof = [
            [
                a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1),
                a(1, 2) * a(2, 0) - a(1, 0) * a(2, 2),
                a(1, 0) * a(2, 1) - a(1, 1) * a(2, 0),
            ],
            [
                a(0, 2) * a(2, 1) - a(0, 1) * a(2, 2),
                a(0, 0) * a(2, 2) - a(0, 2) * a(2, 0),
                a(0, 1) * a(2, 0) - a(0, 0) * a(2, 1),
            ],
            [
                a(0, 1) * a(1, 2) - a(0, 2) * a(1, 1),
                a(0, 2) * a(1, 0) - a(0, 0) * a(1, 2),
                a(0, 0) * a(1, 1) - a(0, 1) * a(1, 0),
            ],
        ];
        let det = a(0, 0) * cof[0][0] + a(0, 1) * cof[0][1] + a(0, 2) * cof[0][2];
        let flip = det < 0.0;
        let normal_sign = if flip { -1.0 } else { 1.0 };

        for primitive in mesh.primitives() {
            let label = |semantic: &str| {
                format!("{semantic} of {mesh_name} primitive {}", primitive.index())
            };
            match primitive.mode() {
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan => {}
                Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip => {
                    self.report.skipped_primitives += 1;
                    continue;
                }
            }
            if primitive.morph_targets().next().is_some() {
                self.ignored_targets += 1;
            }
            let Some(positions) = primitive.get(&Semantic::Positions) else {
                self.report.notes.push(format!(
                    "{}: {} has no POSITION and is skipped",
                    self.source.name,
                    label("primitive")
                ));
                continue;
            };
            let positions = self
                .read_attribute(
                    positions.index(),
                    &label("POSITION"),
                    &Expect {
                        semantic: "POSITION",
                        dims: &[3],
                    },
                )?
                .values;
            let count = positions.len() / 3;
            let optional = |semantic: Semantic, name: &'static str, dims: &'static [usize]| {
                primitive
                    .get(&semantic)
                    .map(|acc| {
                        let raw = self.read_attribute(
                            acc.index(),
                            &label(name),
                            &Expect {
                                semantic: name,
                                dims,
                            },
                        )?;
                        let n = raw.values.len() / raw.dims;
                        if n != count {
                            return Err(self.source.malformed(
                                self.accessor_label(acc.index(), &label(name)),
                                format!("{n} elements, POSITION has {count}"),
                            ));
                        }
                        Ok((raw.values, raw.dims))
                    })
                    .transpose()
            };
            let normals = optional(Semantic::Normals, "NORMAL", &[3])?;
            let uvs = optional(Semantic::TexCoords(0), "TEXCOORD_0", &[2])?;
            let colors = optional(Semantic::Colors(0), "COLOR_0", &[3, 4])?;

            let indices: Vec<u32> = match primitive.indices() {
                Some(acc) => {
                    let at = self.accessor_label(acc.index(), &label("indices"));
                    let values = self.read_indices(acc.index(), &at)?;
                    if let Some(&bad) = values.iter().find(|&&v| v as usize >= count) {
                        return Err(self.source.out_of_range(
                            at,
                            "index",
                            i64::from(bad),
                            count,
                            "vertices",
                        ));
                    }
                    values
                }
                None => {
                    let n = u32::try_from(count).map_err(|_| {
                        self.source
                            .unsupported(label("POSITION"), "more than 2^32 vertices")
                    })?;
                    (0..n).collect()
                }
            };
            let triangles = self.assemble(primitive.mode(), &indices, &label("indices"));

            let surface = self.surface(primitive.material().index())?;
            let base_p = next_index(self.source, self.mesh.positions.len() + count, "positions")?
                - count as u32;
            for p in positions.chunks_exact(3) {
                let p = [p[0], p[1], p[2]];
                let out: [f64; 3] =
                    std::array::from_fn(|r| (0..3).map(|c| a(r, c) * p[c]).sum::<f64>() + a(r, 3));
                self.mesh.positions.push(out.map(|v| v as f32));
            }
            if let Some((i, v)) = self.mesh.positions[base_p as usize..]
                .iter()
                .enumerate()
                .find_map(|(i, p)| p.iter().find(|v| !v.is_finite()).map(|v| (i, *v)))
            {
                return Err(self.source.non_finite(
                    format!("{} vertex {i}", label("POSITION")),
                    "position after the node transform",
                    f64::from(v),
                ));
            }
            let base_n = match &normals {
                Some((values, _)) => {
                    let base = next_index(self.source, self.mesh.normals.len() + count, "normals")?
                        - count as u32;
                    for n in values.chunks_exact(3) {
                        let t: [f64; 3] = std::array::from_fn(|r| {
                            normal_sign * (0..3).map(|c| cof[r][c] * n[c]).sum::<f64>()
                        });
                        let len = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
                        let unit = if len > 0.0 && len.is_finite() {
                            t.map(|v| (v / len) as f32)
                        } else {
                            [0.0; 3]
                        };
                        self.mesh.normals.push(unit);
                    }
                    Some(base)
                }
                None => None,
            };
            let base_uv = match &uvs {
                Some((values, _)) => {
                    let base =
                        next_index(self.source, self.mesh.uvs.len() + count, "UVs")? - count as u32;
                    for uv in values.chunks_exact(2) {
                        self.mesh.uvs.push([uv[0] as f32, uv[1] as f32]);
                    }
                    Some(base)
                }
                None => None,
            };
            let base_c = match &colors {
                Some((values, d)) => {
                    let base = next_index(self.source, self.mesh.colors.len() + count, "colours")?
                        - count as u32;
                    for c in values.chunks_exact(*d) {
                        let alpha = if *d == 4 { c[3] } else { 1.0 };
                        self.mesh.colors.push([
                            c[0] as f32,
                            c[1] as f32,
                            c[2] as f32,
                            alpha as f32,
                        ]);
                    }
                    Some(base)
                }
                None => None,
            };
            let at = |base: Option<u32>, corners: [u32; 3]| match base {
                Some(b) => corners.map(|i| b + i),
                None => [NO_ATTRIBUTE; 3],
            };
            for mut t in triangles {
                if flip {
                    t.swap(1, 2);
                }
                self.mesh.triangles.push(Triangle {
                    position: t.map(|i| base_p + i),
                    normal: at(base_n, t),
                    uv: at(base_uv, t),
                    color: at(base_c, t),
                    surface,
                });
            }
        }
        Ok(())
    }

    /// Index list to triangles for the primitive's mode.
    fn assemble(&mut self, mode: Mode, indices: &[u32], label: &str) -> Vec<[u32; 3]> {
        let mut out = Vec::new();
        match mode {
            Mode::Triangles => {
                let whole = indices.chunks_exact(3);
                if !whole.remainder().is_empty() {
                    self.report.notes.push(format!(
                        "{}: {label}: {} indices is not a multiple of 3; the last {} ignored",
                        self.source.name,
                        indices.len(),
                        whole.remainder().len()
                    ));
                }
                out.extend(whole.map(|t| [t[0], t[1], t[2]]));
            }
            Mode::TriangleStrip => {
                for i in 0..indices.len().saturating_sub(2) {
                    let t = if i % 2 == 0 {
                        [indices[i], indices[i + 1], indices[i + 2]]
                    } else {
                        [indices[i], indices[i + 2], indices[i + 1]]
                    };
                    self.push_nondegenerate(&mut out, t);
                }
            }
            Mode::TriangleFan => {
                for i in 1..indices.len().saturating_sub(1) {
                    self.push_nondegenerate(&mut out, [indices[0], indices[i], indices[i + 1]]);
                }
            }
            _ => {}
        }
        out
    }

    fn push_nondegenerate(&mut self, out: &mut Vec<[u32; 3]>, t: [u32; 3]) {
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            self.strip_joints += 1;
        } else {
            out.push(t);
        }
    }

    fn surface(&mut self, material: Option<usize>) -> Result<u16, ImportError> {
        if let Some(&id) = self.surfaces.get(&material) {
            return Ok(id);
        }
        let surface = match material.and_then(|m| self.root.materials.get(m).map(|j| (m, j))) {
            None => Surface {
                name: "default".to_owned(),
                base_color: [1.0; 4],
                texture: None,
            },
            Some((m, json)) => {
                let pbr = &json.pbr_metallic_roughness;
                let texture = match &pbr.base_color_texture {
                    None => None,
                    Some(info) => self.texture_uri(info.index.value(), m)?,
                };
                let base_color = pbr.base_color_factor.0;
                self.source.check_finite(
                    &base_color,
                    &["red", "green", "blue", "alpha"],
                    || format!("material {m} baseColorFactor"),
                )?;
                Surface {
                    name: json.name.clone().unwrap_or_else(|| format!("material {m}")),
                    base_color,
                    texture,
                }
            }
        };
        let id = push_surface(self.source, &mut self.mesh, surface)?;
        self.surfaces.insert(material, id);
        Ok(id)
    }

    /// The file name of a texture's image, if it is an external file.
    fn texture_uri(
        &mut self,
        texture: usize,
        material: usize,
    ) -> Result<Option<String>, ImportError> {
        let image = self
            .root
            .textures
            .get(texture)
            .and_then(|t| self.root.images.get(t.source.value()));
        let what = format!("material {material} base colour texture");
        match image.and_then(|i| i.uri.as_deref()) {
            Some(uri) if !uri.starts_with("data:") => {
                Ok(Some(decode_uri(self.source, &what, uri)?))
            }
            _ => {
                self.report.notes.push(format!(
                    "{}: {what} is embedded (buffer view or data URI) and not referenced by \
                     the surface",
                    self.source.name
                ));
                Ok(None)
            }
        }
    }

    fn accessor_label(&self, index: usize, what: &str) -> String {
        format!("accessor {index} ({what})")
    }

    /// An attribute accessor's values as `f64`, `count * dims` of them, checked for bounds and
    /// finiteness.
    fn read_attribute(
        &self,
        index: usize,
        what: &str,
        expect: &Expect,
    ) -> Result<Raw, ImportError> {
        let at = self.accessor_label(index, what);
        let raw = self.read(index, &at)?;
        if !expect.dims.contains(&raw.dims) {
            return Err(self.source.malformed(
                &at,
                format!(
                    "type has {} components; {} needs {}",
                    raw.dims,
                    expect.semantic,
                    expect
                        .dims
                        .iter()
                        .map(|d| d.to_string())
                        .collect::<Vec<_>>()
                        .join(" or ")
                ),
            ));
        }
        if let Some(i) = raw.values.iter().position(|v| !v.is_finite()) {
            return Err(self.source.non_finite(
                at,
                format!("element {} component {}", i / raw.dims, i % raw.dims),
                raw.values[i],
            ));
        }
        Ok(raw)
    }

    fn read_indices(&self, index: usize, at: &str) -> Result<Vec<u32>, ImportError> {
        let accessor = &self.root.accessors[index];
        match accessor.component_type {
            json::validation::Checked::Valid(json::accessor::GenericComponentType(
                ComponentType::U8 | ComponentType::U16 | ComponentType::U32,
            )) => {}
            _ => {
                return Err(self
                    .source
                    .malformed(at, "indices must be unsigned bytes, shorts or ints"))
            }
        }
        let raw = self.read(index, at)?;
        if raw.dims != 1 || accessor.normalized {
            return Err(self
                .source
                .malformed(at, "indices must be SCALAR and not normalized"));
        }
        Ok(raw.values.into_iter().map(|v| v as u32).collect())
    }

    /// Reads any accessor: every byte range checked before reading.
    fn read(&self, index: usize, at: &str) -> Result<Raw, ImportError> {
        let source = self.source;
        let accessor = self
            .root
            .accessors
            .get(index)
            .ok_or_else(|| source.malformed(at, "no such accessor"))?;
        let component = match accessor.component_type {
            json::validation::Checked::Valid(json::accessor::GenericComponentType(c)) => c,
            json::validation::Checked::Invalid => {
                return Err(source.malformed(at, "invalid componentType"))
            }
        };
        let dims = match accessor.type_ {
            json::validation::Checked::Valid(t) => type_dims(t).ok_or_else(|| {
                source.unsupported(at, "matrix accessors are not vertex attributes")
            })?,
            json::validation::Checked::Invalid => return Err(source.malformed(at, "invalid type")),
        };
        let count = usize::try_from(accessor.count.0)
            .map_err(|_| source.malformed(at, "count too large"))?;
        let total = count
            .checked_mul(dims)
            .ok_or_else(|| source.malformed(at, "count too large"))?;
        let size = component_size(component);
        let element = size * dims;
        let mut values = match accessor.buffer_view {
            None => {
                // All zeros (then sparse substitution), as the specification says. A huge count
                // without any data behind it is not a reason to allocate gigabytes.
                if accessor.sparse.is_none() {
                    return Err(source.malformed(at, "no bufferView and no sparse data"));
                }
                if total > (1 << 24) {
                    return Err(source.malformed(at, format!("count {count} without a bufferView")));
                }
                vec![0.0; total]
            }
            Some(view) => {
                let offset = accessor.byte_offset.map_or(0, |o| o.0);
                let (bytes, stride) = self.view_bytes(view.value(), at)?;
                let stride = stride.unwrap_or(element);
                if stride < element {
                    return Err(source.malformed(
                        at,
                        format!("byteStride {stride} of buffer view {} is less than the element size {element}", view.value()),
                    ));
                }
                let need = if count == 0 {
                    Some(0)
                } else {
                    (count as u64 - 1)
                        .checked_mul(stride as u64)
                        .and_then(|v| v.checked_add(element as u64))
                        .and_then(|v| v.checked_add(offset))
                };
                match need {
                    Some(n) if n <= bytes.len() as u64 => {}
                    _ => {
                        return Err(source.malformed(
                            at,
                            format!(
                                "out of bounds of buffer view {}: {count} elements of {element} bytes with stride {stride} from byte {offset} need {} bytes, the view has {}",
                                view.value(),
                                need.map_or("more than 2^64".to_owned(), |n| n.to_string()),
                                bytes.len()
                            ),
                        ))
                    }
                }
                let offset = offset as usize;
                let mut values = Vec::with_capacity(total);
                for e in 0..count {
                    let start = offset + e * stride;
                    for c in 0..dims {
                        let at = start + c * size;
                        values.push(decode(
                            component,
                            accessor.normalized,
                            &bytes[at..at + size],
                        ));
                    }
                }
                values
            }
        };
        if let Some(sparse) = &accessor.sparse {
            let n = usize::try_from(sparse.count.0)
                .map_err(|_| source.malformed(at, "sparse count too large"))?;
            let index_type = match sparse.indices.component_type {
                json::validation::Checked::Valid(json::accessor::IndexComponentType(c)) => c,
                json::validation::Checked::Invalid => {
                    return Err(source.malformed(at, "invalid sparse index componentType"))
                }
            };
            let isize_ = component_size(index_type);
            let (ibytes, _) = self.view_bytes(sparse.indices.buffer_view.value(), at)?;
            let (vbytes, _) = self.view_bytes(sparse.values.buffer_view.value(), at)?;
            let ioff = sparse.indices.byte_offset.0;
            let voff = sparse.values.byte_offset.0;
            let fits = |off: u64, per: usize, len: usize| {
                (n as u64)
                    .checked_mul(per as u64)
                    .and_then(|v| v.checked_add(off))
                    .is_some_and(|end| end <= len as u64)
            };
            if !fits(ioff, isize_, ibytes.len()) || !fits(voff, element, vbytes.len()) {
                return Err(source.malformed(
                    at,
                    format!("sparse indices or values ({n} of them) out of bounds of their buffer views"),
                ));
            }
            let (ioff, voff) = (ioff as usize, voff as usize);
            for k in 0..n {
                let i0 = ioff + k * isize_;
                let target = decode(index_type, false, &ibytes[i0..i0 + isize_]) as usize;
                if target >= count {
                    return Err(source.out_of_range(
                        at,
                        "sparse index",
                        target as i64,
                        count,
                        "elements",
                    ));
                }
                for c in 0..dims {
                    let v0 = voff + k * element + c * size;
                    values[target * dims + c] =
                        decode(component, accessor.normalized, &vbytes[v0..v0 + size]);
                }
            }
        }
        Ok(Raw { values, dims })
    }

    /// A buffer view's bytes (checked against its buffer) and its stride.
    fn view_bytes(&self, view: usize, at: &str) -> Result<(&[u8], Option<usize>), ImportError> {
        let source = self.source;
        let json = self
            .root
            .buffer_views
            .get(view)
            .ok_or_else(|| source.malformed(at, format!("no buffer view {view}")))?;
        let buffer = json.buffer.value();
        let data = self.buffers.get(buffer).ok_or_else(|| {
            source.malformed(format!("buffer view {view}"), format!("no buffer {buffer}"))
        })?;
        let declared = self.root.buffers.get(buffer).map_or(0, |b| b.byte_length.0);
        let start = json.byte_offset.map_or(0, |o| o.0);
        let end = start.checked_add(json.byte_length.0);
        match end {
            Some(end) if end <= declared && end <= data.len() as u64 => {}
            _ => {
                return Err(source.malformed(
                    format!("buffer view {view}"),
                    format!(
                        "bytes {start}..{} out of bounds of buffer {buffer} ({declared} bytes)",
                        end.map_or("overflow".to_owned(), |e| e.to_string())
                    ),
                ))
            }
        }
        let stride = json.byte_stride.map(|s| s.0).filter(|&s| s != 0);
        Ok((
            &data[start as usize..(start + json.byte_length.0) as usize],
            stride,
        ))
    }
}

/// An accessor's values and components per element.
struct Raw {
    values: Vec<f64>,
    dims: usize,
}

fn type_dims(t: Type) -> Option<usize> {
    match t {
        Type::Scalar => Some(1),
        Type::Vec2 => Some(2),
        Type::Vec3 => Some(3),
        Type::Vec4 => Some(4),
        Type::Mat2 | Type::Mat3 | Type::Mat4 => None,
    }
}

fn component_size(c: ComponentType) -> usize {
    match c {
        ComponentType::I8 | ComponentType::U8 => 1,
        ComponentType::I16 | ComponentType::U16 => 2,
        ComponentType::U32 | ComponentType::F32 => 4,
    }
}

/// One little-endian component, normalized integers mapped as the specification says.
fn decode(c: ComponentType, normalized: bool, b: &[u8]) -> f64 {
    match c {
        ComponentType::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        ComponentType::U8 => {
            let v = f64::from(b[0]);
            if normalized {
                v / 255.0
            } else {
                v
            }
        }
        ComponentType::I8 => {
            let v = f64::from(b[0] as i8);
            if normalized {
                (v / 127.0).max(-1.0)
            } else {
                v
            }
        }
        ComponentType::U16 => {
            let v = f64::from(u16::from_le_bytes([b[0], b[1]]));
            if normalized {
                v / 65535.0
            } else {
                v
            }
        }
        ComponentType::I16 => {
            let v = f64::from(i16::from_le_bytes([b[0], b[1]]));
            if normalized {
                (v / 32767.0).max(-1.0)
            } else {
                v
            }
        }
        ComponentType::U32 => {
            let v = f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
            if normalized {
                v / f64::from(u32::MAX)
            } else {
                v
            }
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A triangle (positions, normals, UVs, byte colours, u16 indices) and a 4-vertex strip
    /// in one 164-byte buffer.
    pub(crate) fn sample_bin() -> Vec<u8> {
        let mut bin = Vec::new();
        let floats = |bin: &mut Vec<u8>, values: &[f32]| {
            for v in values {
                bin.extend_from_slice(&v.to_le_bytes());
            }
        };
        floats(&mut bin, &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
        floats(&mut bin, &[0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0]);
        floats(&mut bin, &[0.0, 0.0, 1.0, 0.0, 0.0, 1.0]);
        bin.extend_from_slice(&[255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 51]);
        for i in [0u16, 1, 2, 0] {
            bin.extend_from_slice(&i.to_le_bytes());
        }
        assert_eq!(bin.len(), 116);
        floats(
            &mut bin,
            &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0],
        );
        bin
    }

    /// Root node translated by 10 along x with two children instancing mesh 'Tri': one plain,
    /// one mirrored (scale -1 in x). Primitives: indexed triangle with material 'Red', strip
    /// without material, points.
    pub(crate) const SAMPLE_JSON: &str = r#"{
 "asset": {"version": "2.0"},
 "scene": 0,
 "scenes": [{"nodes": [0]}],
 "nodes": [
   {"name": "root", "translation": [10, 0, 0], "children": [1, 2]},
   {"name": "plain", "mesh": 0},
   {"name": "mirrored", "scale": [-1, 1, 1], "mesh": 0}
 ],
 "meshes": [{"name": "Tri", "primitives": [
   {"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2, "COLOR_0": 3}, "indices": 4, "material": 0},
   {"attributes": {"POSITION": 5}, "mode": 5},
   {"attributes": {"POSITION": 5}, "mode": 0}
 ]}],
 "materials": [{"name": "Red", "pbrMetallicRoughness": {"baseColorFactor": [1, 0, 0, 0.5], "baseColorTexture": {"index": 0}}}],
 "textures": [{"source": 0}],
 "images": [{"uri": "tex%20red.png"}],
 "accessors": [
   {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
   {"bufferView": 0, "byteOffset": 36, "componentType": 5126, "count": 3, "type": "VEC3"},
   {"bufferView": 0, "byteOffset": 72, "componentType": 5126, "count": 3, "type": "VEC2"},
   {"bufferView": 0, "byteOffset": 96, "componentType": 5121, "normalized": true, "count": 3, "type": "VEC4"},
   {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"},
   {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}
 ],
 "bufferViews": [
   {"buffer": 0, "byteOffset": 0, "byteLength": 108},
   {"buffer": 0, "byteOffset": 108, "byteLength": 6},
   {"buffer": 0, "byteOffset": 116, "byteLength": 48}
 ],
 "buffers": [{"uri": "tri.bin", "byteLength": 164}]
}"#;

    /// `json` and `bin` packed as a GLB file (the buffer's uri removed).
    pub(crate) fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
        let mut json = json
            .replace(
                r#"{"uri": "tri.bin", "byteLength": 164}"#,
                r#"{"byteLength": 164}"#,
            )
            .into_bytes();
        while json.len() % 4 != 0 {
            json.push(b' ');
        }
        let mut bin = bin.to_vec();
        while bin.len() % 4 != 0 {
            bin.push(0);
        }
        let total = 12 + 8 + json.len() + 8 + bin.len();
        let mut out = b"glTF".to_vec();
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&(total as u32).to_le_bytes());
        out.extend_from_slice(&(json.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&json);
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
        out
    }

    fn src() -> Source {
        Source {
            name: "x.gltf".to_owned(),
        }
    }

    fn run(json: &str, bin: &[u8]) -> Result<(Mesh, ImportReport), ImportError> {
        let mut report = ImportReport::default();
        let bin = bin.to_vec();
        let mut load = |uri: &str| {
            if uri == "tri.bin" {
                Ok(bin.clone())
            } else {
                Err(std::io::Error::new(
                    std::io::ErrorKind::NotFound,
                    "no such file",
                ))
            }
        };
        import_bytes(&src(), json.as_bytes(), &mut load, &mut report).map(|m| (m, report))
    }

    fn err(json: &str, bin: &[u8]) -> String {
        run(json, bin).expect_err("must fail").to_string()
    }

    #[test]
    fn transforms_materials_and_modes() {
        let (mesh, report) = run(SAMPLE_JSON, &sample_bin()).unwrap();
        mesh.validate().unwrap();
        // Per instance: one indexed triangle and a two-triangle strip; the points are skipped.
        assert_eq!(mesh.triangles.len(), 6);
        assert_eq!(report.skipped_primitives, 2);
        let names: Vec<&str> = mesh.surfaces.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["Red", "default"]);
        assert_eq!(mesh.surfaces[0].base_color, [1.0, 0.0, 0.0, 0.5]);
        assert_eq!(mesh.surfaces[0].texture.as_deref(), Some("tex red.png"));
        assert_eq!(mesh.triangles_per_surface(), [2, 4]);

        let corner = |t: usize| {
            mesh.triangles[t]
                .position
                .map(|i| mesh.positions[i as usize])
        };
        // The plain instance is translated.
        assert_eq!(
            corner(0),
            [[10.0, 0.0, 0.0], [11.0, 0.0, 0.0], [10.0, 1.0, 0.0]]
        );
        // The strip: (0 1 2), then (1 3 2).
        assert_eq!(corner(2)[1], [11.0, 1.0, 0.0]);
        // The mirrored instance: x reflected, winding flipped so it still faces +z.
        assert_eq!(
            corner(3),
            [[10.0, 0.0, 0.0], [10.0, 1.0, 0.0], [9.0, 0.0, 0.0]]
        );
        for t in 0..mesh.triangles.len() {
            let [a, b, c] = corner(t);
            let z = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            assert!(z > 0.0, "triangle {t} faces -z");
        }
        // Normals by the inverse transpose: still +z on both instances.
        let n = mesh.triangles[3].normal[0];
        assert_eq!(mesh.normals[n as usize], [0.0, 0.0, 1.0]);
        assert_eq!(mesh.normals.len(), 6);
        assert_eq!(mesh.uvs[1], [1.0, 0.0]);
        assert!(
            (mesh.colors[2][3] - 0.2).abs() < 1e-6,
            "{:?}",
            mesh.colors[2]
        );
        // The strip has no normals.
        assert_eq!(mesh.triangles[1].normal, [NO_ATTRIBUTE; 3]);
    }

    #[test]
    fn glb_and_data_uri_read_the_same() {
        let bin = sample_bin();
        let (expected, _) = run(SAMPLE_JSON, &bin).unwrap();
        let mut report = ImportReport::default();
        let mut no_files = |_: &str| {
            Err(std::io::Error::new(
                std::io::ErrorKind::NotFound,
                "no files",
            ))
        };
        let packed = glb(SAMPLE_JSON, &bin);
        let mesh = import_bytes(&src(), &packed, &mut no_files, &mut report).unwrap();
        assert_eq!(mesh, expected);

        let encoded = encode_base64(&bin);
        let json = SAMPLE_JSON.replace(
            "\"uri\": \"tri.bin\"",
            &format!("\"uri\": \"data:application/octet-stream;base64,{encoded}\""),
        );
        let mesh = import_bytes(&src(), json.as_bytes(), &mut no_files, &mut report).unwrap();
        assert_eq!(mesh, expected);

        // Every cut of the GLB is an error, never a panic.
        for cut in [
            0,
            4,
            11,
            12,
            19,
            20,
            100,
            packed.len() - 100,
            packed.len() - 1,
        ] {
            assert!(import_bytes(&src(), &packed[..cut], &mut no_files, &mut report).is_err());
        }
    }

    fn encode_base64(bytes: &[u8]) -> String {
        const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let mut out = String::new();
        for chunk in bytes.chunks(3) {
            let b = [
                chunk[0],
                *chunk.get(1).unwrap_or(&0),
                *chunk.get(2).unwrap_or(&0),
            ];
            let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
            for k in 0..=chunk.len() {
                out.push(char::from(A[((n >> (18 - 6 * k)) & 63) as usize]));
            }
        }
        while out.len() % 4 != 0 {
            out.push('=');
        }
        out
    }

    #[test]
    fn base64_round_trips() {
        for len in 0..10 {
            let bytes: Vec<u8> = (0..len).map(|i| (i * 37 + 5) as u8).collect();
            assert_eq!(decode_base64(&encode_base64(&bytes)), Some(bytes));
        }
        assert_eq!(decode_base64("QUJD"), Some(b"ABC".to_vec()));
        assert_eq!(decode_base64("QU*D"), None);
    }

    #[test]
    fn accessor_out_of_bounds_is_named() {
        let bin = sample_bin();
        let json = SAMPLE_JSON.replace(
            r#"{"bufferView": 2, "componentType": 5126, "count": 4,"#,
            r#"{"bufferView": 2, "componentType": 5126, "count": 5,"#,
        );
        let e = err(&json, &bin);
        assert!(
            e.starts_with(
                "x.gltf: accessor 5 (POSITION of mesh 'Tri' primitive 1): out of bounds of buffer view 2"
            ),
            "{e}"
        );
        let json = SAMPLE_JSON.replace(
            r#""byteOffset": 116, "byteLength": 48"#,
            r#""byteOffset": 116, "byteLength": 60"#,
        );
        let e = err(&json, &bin);
        assert_eq!(
            e,
            "x.gltf: buffer view 2: bytes 116..176 out of bounds of buffer 0 (164 bytes)"
        );
        let json = SAMPLE_JSON.replace(r#""byteOffset": 96,"#, r#""byteOffset": 100,"#);
        assert!(err(&json, &bin)
            .contains("accessor 3 (COLOR_0 of mesh 'Tri' primitive 0): out of bounds"));
        let json = SAMPLE_JSON.replace(
            r#""byteLength": 108}"#,
            r#""byteLength": 108, "byteStride": 8}"#,
        );
        assert!(
            err(&json, &bin).contains("byteStride 8"),
            "{}",
            err(&json, &bin)
        );
        // A buffer shorter than its byteLength.
        assert!(
            err(SAMPLE_JSON, &bin[..100]).contains("truncated: buffer 0 ('tri.bin') has 100 bytes")
        );
    }

    #[test]
    fn bad_values_are_named() {
        let mut bin = sample_bin();
        bin[108..110].copy_from_slice(&7u16.to_le_bytes());
        assert_eq!(
            err(SAMPLE_JSON, &bin),
            "x.gltf: accessor 4 (indices of mesh 'Tri' primitive 0): index 7 out of range (3 vertices)"
        );
        let mut bin = sample_bin();
        bin[12..16].copy_from_slice(&f32::NAN.to_le_bytes());
        assert_eq!(
            err(SAMPLE_JSON, &bin),
            "x.gltf: accessor 0 (POSITION of mesh 'Tri' primitive 0): element 1 component 0 is NaN"
        );
        let json = SAMPLE_JSON.replace(
            r#""byteOffset": 72, "componentType": 5126, "count": 3"#,
            r#""byteOffset": 72, "componentType": 5126, "count": 2"#,
        );
        assert!(err(&json, &sample_bin())
            .contains("TEXCOORD_0 of mesh 'Tri' primitive 0): 2 elements, POSITION has 3"));
        let json = SAMPLE_JSON.replace(
            r#""translation": [10, 0, 0]"#,
            r#""matrix": [3e38, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 3e38, 0, 0, 1]"#,
        );
        let e = err(&json, &sample_bin());
        assert!(
            e.contains("position after the node transform is inf"),
            "{e}"
        );
    }

    #[test]
    fn quantized_and_sparse_positions() {
        let mut bin = Vec::new();
        for p in [[0u16, 0, 0, 0], [2, 0, 0, 0], [0, 2, 0, 0]] {
            for v in p {
                bin.extend_from_slice(&v.to_le_bytes());
            }
        }
        bin.extend_from_slice(&[2, 0, 0, 0]);
        for v in [0u16, 3, 0, 0] {
            bin.extend_from_slice(&v.to_le_bytes());
        }
        let json = r#"{
 "asset": {"version": "2.0"},
 "extensionsUsed": ["KHR_mesh_quantization"],
 "extensionsRequired": ["KHR_mesh_quantization"],
 "nodes": [{"mesh": 0}],
 "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
 "accessors": [{"bufferView": 0, "componentType": 5123, "count": 3, "type": "VEC3",
   "sparse": {"count": 1, "indices": {"bufferView": 1, "componentType": 5121},
              "values": {"bufferView": 2}}}],
 "bufferViews": [
   {"buffer": 0, "byteOffset": 0, "byteLength": 24, "byteStride": 8},
   {"buffer": 0, "byteOffset": 24, "byteLength": 1},
   {"buffer": 0, "byteOffset": 28, "byteLength": 6}
 ],
 "buffers": [{"uri": "tri.bin", "byteLength": 36}]
}"#;
        let (mesh, report) = run(json, &bin).unwrap();
        assert_eq!(
            mesh.positions,
            [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 3.0, 0.0]]
        );
        assert_eq!(mesh.triangles.len(), 1);
        assert_eq!(mesh.surfaces[0].name, "default");
        assert!(
            report.notes.iter().any(|n| n.contains("min/max")),
            "{:?}",
            report.notes
        );
        // A sparse index past the accessor's count.
        let mut bad = bin.clone();
        bad[24] = 3;
        assert_eq!(
            err(json, &bad),
            "x.gltf: accessor 0 (POSITION of mesh 0 primitive 0): sparse index 3 out of range (3 elements)"
        );
    }

    #[test]
    fn structural_errors() {
        let bin = sample_bin();
        let json = SAMPLE_JSON.replace(
            r#""mesh": 0}
 ],"#,
            r#""mesh": 0, "children": [0]}
 ],"#,
        );
        assert!(
            err(&json, &bin).contains("appears twice"),
            "{}",
            err(&json, &bin)
        );
        let json = SAMPLE_JSON.replace("tri.bin", "gone.bin");
        let e = err(&json, &bin);
        assert!(e.starts_with("x.gltf: buffer 0 ('gone.bin'): "), "{e}");
        let json = SAMPLE_JSON.replace(
            r#""asset": {"version": "2.0"},"#,
            r#""asset": {"version": "2.0"}, "extensionsRequired": ["KHR_draco_mesh_compression"], "extensionsUsed": ["KHR_draco_mesh_compression"],"#,
        );
        let e = err(&json, &bin);
        assert!(
            e.contains("unsupported: extension KHR_draco_mesh_compression"),
            "{e}"
        );
        // POSITION naming a missing accessor (the crate's validation would index it blindly).
        let json = SAMPLE_JSON.replace(
            r#""POSITION": 5}, "mode": 0"#,
            r#""POSITION": 99}, "mode": 0"#,
        );
        assert_eq!(
            err(&json, &bin),
            "x.gltf: mesh 0 primitive 2 POSITION: accessor 99 out of range (6 accessors)"
        );
        let json = SAMPLE_JSON.replace(r#""material": 0}"#, r#""material": 4}"#);
        let e = err(&json, &bin);
        assert!(
            e.starts_with("x.gltf: document: invalid glTF: meshes[0].primitives[0].material"),
            "{e}"
        );
        assert!(err("{ not json", &bin).starts_with("x.gltf: JSON: "));
        let json = SAMPLE_JSON.replace("tex%20red.png", "tex%ZZ.png");
        assert!(err(&json, &bin).contains("bad percent-encoding"));
        let json = SAMPLE_JSON.replace("tri.bin", "https://example.invalid/tri.bin");
        assert!(err(&json, &bin).contains("URI scheme 'https:'"));
    }
}
