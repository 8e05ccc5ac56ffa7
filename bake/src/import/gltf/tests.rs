use super::buffers::decode_base64;
use super::*;
use crate::mesh::NO_ATTRIBUTE;

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
    assert_eq!(mesh.surfaces[0].texture_file(), Some("tex red.png"));
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

/// The sample with a second material on the strip, its texture's image as `image`, and the
/// first material masked and double-sided.
fn two_materials(image: &str) -> String {
    let json = SAMPLE_JSON
        .replace(
            r#"{"attributes": {"POSITION": 5}, "mode": 5}"#,
            r#"{"attributes": {"POSITION": 5}, "mode": 5, "material": 1}"#,
        )
        .replace(
            r#""materials": [{"name": "Red", "#,
            r#""materials": [{"name": "Glass", "alphaMode": "BLEND", "pbrMetallicRoughness": {"baseColorTexture": {"index": 1}}}, {"name": "Red", "alphaMode": "MASK", "alphaCutoff": 0.25, "doubleSided": true, "#,
        )
        .replace(r#""textures": [{"source": 0}]"#, r#""textures": [{"source": 0}, {"source": 1}]"#)
        .replace(
            r#""images": [{"uri": "tex%20red.png"}]"#,
            &format!(r#""images": [{{"uri": "tex%20red.png"}}, {image}]"#),
        )
        .replace(
            r#"{"buffer": 0, "byteOffset": 116, "byteLength": 48}"#,
            r#"{"buffer": 0, "byteOffset": 116, "byteLength": 48}, {"buffer": 0, "byteOffset": 8, "byteLength": 4}"#,
        );
    // Primitive 0 names material 0, now Glass; give it Red (1) and the strip Glass (0).
    json.replace(
        r#""indices": 4, "material": 0}"#,
        r#""indices": 4, "material": 1}"#,
    )
    .replace(
        r#""mode": 5, "material": 1}"#,
        r#""mode": 5, "material": 0}"#,
    )
}

#[test]
fn materials_keep_alpha_sides_and_embedded_images() {
    let bin = sample_bin();
    let (mesh, _) = run(
        &two_materials(r#"{"bufferView": 3, "mimeType": "image/jpeg"}"#),
        &bin,
    )
    .unwrap();
    let names: Vec<&str> = mesh.surfaces.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["Red", "Glass"]);
    let red = &mesh.surfaces[0];
    assert_eq!(red.texture_file(), Some("tex red.png"));
    assert_eq!(red.alpha, crate::mesh::AlphaMode::Mask { cutoff: 0.25 });
    assert!(red.double_sided);
    let glass = &mesh.surfaces[1];
    assert_eq!(glass.alpha, crate::mesh::AlphaMode::Blend);
    assert!(!glass.double_sided);
    assert_eq!(
        glass.texture,
        Some(crate::mesh::Texture::Embedded {
            mime: "image/jpeg".into(),
            bytes: bin[8..12].to_vec(),
        })
    );
    // A data URI: its own MIME type, its decoded bytes.
    let (mesh, _) = run(
        &two_materials(r#"{"uri": "data:image/png;base64,AAEC/w=="}"#),
        &bin,
    )
    .unwrap();
    assert_eq!(
        mesh.surfaces[1].texture,
        Some(crate::mesh::Texture::Embedded {
            mime: "image/png".into(),
            bytes: vec![0, 1, 2, 255],
        })
    );
    // A buffer-view image needs its MIME type.
    let e = err(&two_materials(r#"{"bufferView": 3}"#), &bin);
    assert!(e.contains("mimeType"), "{e}");
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
    assert!(
        err(&json, &bin).contains("accessor 3 (COLOR_0 of mesh 'Tri' primitive 0): out of bounds")
    );
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
    assert!(err(SAMPLE_JSON, &bin[..100]).contains("truncated: buffer 0 ('tri.bin') has 100 bytes"));
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

#[test]
fn files_are_sniffed_by_their_first_bytes() {
    let src = src();
    assert!(sniff(&src, b"glTF\x02\0\0\0", true).is_ok());
    assert!(sniff(&src, b"glTF\x02\0\0\0", false).is_ok());
    assert!(sniff(&src, b"\xef\xbb\xbf \n{\"asset\":{}}", false).is_ok());
    let err = sniff(&src, b"\x89PNG\r\n", true).unwrap_err().to_string();
    assert_eq!(
        err,
        "x.gltf: header: not a binary glTF file (it starts with bytes 89 50 4e 47); expected \
         the magic 'glTF'"
    );
    let err = sniff(&src, b"", false).unwrap_err().to_string();
    assert_eq!(
        err,
        "x.gltf: header: not a glTF JSON file (the file is empty); expected a JSON object '{' \
         or the magic 'glTF'"
    );
}

#[test]
fn json_cut_off_is_truncated() {
    let e = err("{\"asset\": {\"version\": \"2.0\"}, \"meshes\": [", &[]);
    assert_eq!(
        e,
        "x.gltf: truncated: JSON: the document ends at line 1 column 41; expected the rest of it"
    );
}
