//! Materials and vertex colours through the bake and the OBJ export, on small files made in
//! a temporary directory: a glTF with a textured, masked, double-sided material, a blended
//! one with an embedded image and per-vertex colours; an OBJ with an MTL and vertex colours;
//! meshes without either get no sections.
//!
//! Each round trip goes source → `.clod` (written into another directory than the source) →
//! OBJ + MTL (into a third) → the OBJ importer, and checks that every material name and
//! texture survives and every texture path still names the source's image file.

use std::path::{Path, PathBuf};

use caveclod_bake::export::{obj_export, ExportError, Level};
use caveclod_bake::import::{import, ImportOptions};
use caveclod_bake::pipeline::bake_file;
use caveclod_core::format::materials::AlphaMode;
use caveclod_core::format::materials::{vertex_colour_linear, TextureRef};
use caveclod_core::Hierarchy;
use caveclod_tests::shared_data;
use caveclod_tests::AlignedBytes;
use serde_json::json;

/// A `n` x `n` grid of squares at `x0` as one primitive's data: positions, UVs, linear RGBA
/// colours varying over the grid, and `u32` triangle indices.
struct Grid {
    positions: Vec<[f32; 3]>,
    uvs: Vec<[f32; 2]>,
    colours: Vec<[f32; 4]>,
    indices: Vec<u32>,
}

fn grid(n: u32, x0: f32) -> Grid {
    let mut g = Grid {
        positions: Vec::new(),
        uvs: Vec::new(),
        colours: Vec::new(),
        indices: Vec::new(),
    };
    for j in 0..=n {
        for i in 0..=n {
            let (u, v) = (i as f32 / n as f32, j as f32 / n as f32);
            g.positions.push([x0 + u, v, 0.1 * (u * 6.0).sin() * v]);
            g.uvs.push([u, v]);
            g.colours.push([u, v, 1.0 - u, 0.5 + 0.5 * v]);
        }
    }
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            let (b, c, d) = (a + 1, a + n + 1, a + n + 2);
            g.indices.extend_from_slice(&[a, b, d, a, d, c]);
        }
    }
    g
}

/// The smallest PNG signature and header bytes: an "image" nobody decodes here.
const PNG: &[u8] = b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR";

fn base64(bytes: &[u8]) -> String {
    const ABC: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = u32::from(b[0]) << 16 | u32::from(b[1]) << 8 | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ABC[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// Writes `dir/src/model.gltf` + `model.bin` + `tex/wood grain.png`: two grids, "Wood"
/// (textured by file, MASK 0.3, double-sided) and "Glass" (an embedded PNG, BLEND, a base
/// colour), both with COLOR_0. Returns the glTF's path and the grids.
fn write_gltf(dir: &Path) -> (PathBuf, [Grid; 2]) {
    let src = dir.join("src");
    std::fs::create_dir_all(src.join("tex")).unwrap();
    std::fs::write(src.join("tex/wood grain.png"), PNG).unwrap();
    let grids = [grid(6, 0.0), grid(5, 3.0)];
    let mut bin: Vec<u8> = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    let mut primitives = Vec::new();
    for (m, g) in grids.iter().enumerate() {
        let mut view = |bin: &mut Vec<u8>, data: &[u8]| {
            views.push(json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": data.len()}));
            bin.extend_from_slice(data);
            views.len() - 1
        };
        let p = view(&mut bin, bytemuck::cast_slice(&g.positions));
        let t = view(&mut bin, bytemuck::cast_slice(&g.uvs));
        let c = view(&mut bin, bytemuck::cast_slice(&g.colours));
        let i = view(&mut bin, bytemuck::cast_slice(&g.indices));
        let count = g.positions.len();
        let first = accessors.len();
        accessors.extend([
            json!({"bufferView": p, "componentType": 5126, "count": count, "type": "VEC3",
                   "min": [-1e3, -1e3, -1e3], "max": [1e3, 1e3, 1e3]}),
            json!({"bufferView": t, "componentType": 5126, "count": count, "type": "VEC2"}),
            json!({"bufferView": c, "componentType": 5126, "count": count, "type": "VEC4"}),
            json!({"bufferView": i, "componentType": 5125, "count": g.indices.len(), "type": "SCALAR"}),
        ]);
        primitives.push(json!({
            "attributes": {"POSITION": first, "TEXCOORD_0": first + 1, "COLOR_0": first + 2},
            "indices": first + 3,
            "material": m,
        }));
    }
    let gltf = json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": primitives}],
        "materials": [
            {"name": "Wood", "alphaMode": "MASK", "alphaCutoff": 0.3, "doubleSided": true,
             "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}},
            {"name": "Glass", "alphaMode": "BLEND",
             "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.4, 0.6, 0.5],
                                      "baseColorTexture": {"index": 1}}},
        ],
        "textures": [{"source": 0}, {"source": 1}],
        "images": [
            {"uri": "tex/wood%20grain.png"},
            {"uri": format!("data:image/png;base64,{}", base64(PNG))},
        ],
        "buffers": [{"uri": "model.bin", "byteLength": bin.len()}],
        "bufferViews": views,
        "accessors": accessors,
    });
    std::fs::write(src.join("model.bin"), &bin).unwrap();
    let path = src.join("model.gltf");
    std::fs::write(&path, gltf.to_string()).unwrap();
    (path, grids)
}

/// Bakes `input` into `clod` (through `Baked::write`) and reads it back.
fn bake_to(input: &Path, clod: &Path) -> AlignedBytes {
    std::fs::create_dir_all(clod.parent().unwrap()).unwrap();
    let (baked, _) = bake_file(input, &ImportOptions::default(), &mut |_| {}).expect("bake");
    baked.write(clod, &[]).expect("write");
    AlignedBytes::from_slice(&std::fs::read(clod).unwrap())
}

fn canonical(p: &Path) -> PathBuf {
    std::fs::canonicalize(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

#[test]
fn gltf_materials_and_colours_survive_the_bake_and_the_export() {
    let dir = tempfile::tempdir().unwrap();
    let (gltf, grids) = write_gltf(dir.path());
    let clod = dir.path().join("out/model.clod");
    let file = bake_to(&gltf, &clod);
    let h = Hierarchy::from_bytes(&file).expect("loads");

    let m = h.materials().expect("materials");
    assert_eq!(m.len(), 2);
    let wood = m.get(0).unwrap();
    assert_eq!(wood.name, "Wood");
    // Relative to the .clod's directory, naming the source's file.
    assert_eq!(
        wood.texture,
        Some(TextureRef::Path("../src/tex/wood grain.png"))
    );
    assert_eq!(
        canonical(&clod.parent().unwrap().join("../src/tex/wood grain.png")),
        canonical(&dir.path().join("src/tex/wood grain.png"))
    );
    assert_eq!(wood.alpha, AlphaMode::Mask { cutoff: 0.3 });
    assert!(wood.double_sided);
    assert_eq!(wood.base_colour, [1.0; 4]);
    let glass = m.get(1).unwrap();
    assert_eq!(glass.name, "Glass");
    assert_eq!(
        glass.texture,
        Some(TextureRef::Embedded {
            mime: "image/png",
            bytes: PNG
        })
    );
    assert_eq!(glass.alpha, AlphaMode::Blend);
    assert!(!glass.double_sided);
    assert_eq!(glass.base_colour, [0.2, 0.4, 0.6, 0.5]);

    // Material i is surface i: each surface's polygons are its grid's.
    for (s, g) in grids.iter().enumerate() {
        let polygons = h
            .polygons()
            .iter()
            .filter(|p| p.surface.index() == s)
            .count();
        assert_eq!(polygons, g.indices.len() / 3, "surface {s}");
    }

    // One colour per vertex: the source colour of the vertex at that position.
    let colours = h.vertex_colours().expect("vertex colours");
    assert_eq!(colours.len(), h.vertices().len());
    for (v, c) in h.vertices().iter().zip(colours) {
        let source = grids
            .iter()
            .flat_map(|g| g.positions.iter().zip(&g.colours))
            .find(|(p, _)| **p == v.position)
            .map(|(_, c)| *c)
            .expect("a source vertex at every position");
        let got = vertex_colour_linear(*c);
        for k in 0..4 {
            // 8-bit sRGB steps are at most about 1.5% of full scale (near white).
            assert!((got[k] - source[k]).abs() < 0.02, "{got:?} vs {source:?}");
        }
    }

    // Export into a third directory: the MTL names the same texture file, the embedded
    // image is written beside it.
    let obj = dir.path().join("exported/model.obj");
    std::fs::create_dir_all(obj.parent().unwrap()).unwrap();
    let files = obj_export(&h, Level::Full, &clod, &obj).expect("export");
    files.write().expect("write the export");
    let mtl = std::fs::read_to_string(dir.path().join("exported/model.mtl")).unwrap();
    assert!(mtl.contains("map_Kd ../src/tex/wood grain.png"), "{mtl}");
    assert!(mtl.contains("map_Kd model_Glass.png"), "{mtl}");
    assert_eq!(
        std::fs::read(dir.path().join("exported/model_Glass.png")).unwrap(),
        PNG
    );
    let obj_text = std::fs::read_to_string(&obj).unwrap();
    assert!(obj_text.contains("mtllib model.mtl"));

    // Imported again: every name, every texture, and the colours.
    let again = import(&obj, &ImportOptions::default()).expect("the export imports");
    let names: Vec<&str> = again.surfaces.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["Wood", "Glass"]);
    let textures: Vec<PathBuf> = again
        .surfaces
        .iter()
        .map(|s| {
            canonical(
                &obj.parent()
                    .unwrap()
                    .join(s.texture_file().expect("a texture")),
            )
        })
        .collect();
    assert_eq!(
        textures,
        [
            canonical(&dir.path().join("src/tex/wood grain.png")),
            canonical(&dir.path().join("exported/model_Glass.png"))
        ]
    );
    assert_eq!(again.surfaces[1].base_color, [0.2, 0.4, 0.6, 0.5]);
    assert_eq!(again.colors.len(), h.vertices().len());
}

#[test]
fn obj_materials_and_colours_survive_the_bake() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("src");
    std::fs::create_dir_all(&src).unwrap();
    std::fs::write(
        src.join("m.mtl"),
        "newmtl red\nKd 1 0 0\nd 0.5\nmap_Kd red.png\nnewmtl blue\nKd 0 0 1\n",
    )
    .unwrap();
    let g = grid(4, 0.0);
    let mut obj = String::from("mtllib m.mtl\n");
    for (p, c) in g.positions.iter().zip(&g.colours) {
        obj += &format!("v {} {} {} {} {} {}\n", p[0], p[1], p[2], c[0], c[1], c[2]);
    }
    for (t, f) in g.indices.chunks(3).enumerate() {
        if t == 0 {
            obj += "usemtl red\n";
        }
        if t == g.indices.len() / 6 {
            obj += "usemtl blue\n";
        }
        obj += &format!("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1);
    }
    std::fs::write(src.join("m.obj"), obj).unwrap();
    let clod = dir.path().join("m.clod");
    let file = bake_to(&src.join("m.obj"), &clod);
    let h = Hierarchy::from_bytes(&file).unwrap();
    let m = h.materials().expect("materials");
    let red = m.get(0).unwrap();
    assert_eq!(
        (red.name, red.texture, red.alpha),
        (
            "red",
            Some(TextureRef::Path("src/red.png")),
            AlphaMode::Blend
        )
    );
    assert_eq!(red.base_colour, [1.0, 0.0, 0.0, 0.5]);
    let blue = m.get(1).unwrap();
    assert_eq!(
        (blue.name, blue.texture, blue.alpha),
        ("blue", None, AlphaMode::Opaque)
    );
    assert_eq!(h.vertex_colours().map(<[_]>::len), Some(h.vertices().len()));
}

#[test]
fn ply_colours_round_trip_exactly() {
    // 8-bit sRGB colours are stored as they are read: the same bytes come back.
    let dir = tempfile::tempdir().unwrap();
    let g = grid(5, 0.0);
    let byte = |i: usize, k: usize| ((i * 37 + k * 91) % 256) as u8;
    let mut ply = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\n\
         property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        g.positions.len(),
        g.indices.len() / 3
    );
    for (i, p) in g.positions.iter().enumerate() {
        let [r, gr, b] = [0, 1, 2].map(|k| byte(i, k));
        ply += &format!("{} {} {} {r} {gr} {b}\n", p[0], p[1], p[2]);
    }
    for f in g.indices.chunks(3) {
        ply += &format!("3 {} {} {}\n", f[0], f[1], f[2]);
    }
    let path = dir.path().join("coloured.ply");
    std::fs::write(&path, ply).unwrap();
    let file = bake_to(&path, &dir.path().join("coloured.clod"));
    let h = Hierarchy::from_bytes(&file).unwrap();
    assert!(h.materials().is_none(), "a PLY scan has no material");
    let colours = h.vertex_colours().expect("vertex colours");
    for (v, c) in h.vertices().iter().zip(colours) {
        let i = g.positions.iter().position(|p| *p == v.position).unwrap();
        assert_eq!(
            *c,
            [byte(i, 0), byte(i, 1), byte(i, 2), 255],
            "vertex at {i}"
        );
    }
}

#[test]
fn meshes_without_materials_or_colours_get_no_sections() {
    let dir = tempfile::tempdir().unwrap();
    let g = grid(3, 0.0);
    let mut obj = String::new();
    for p in &g.positions {
        obj += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    obj += "usemtl named_but_undefined\n";
    for f in g.indices.chunks(3) {
        obj += &format!("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1);
    }
    let path = dir.path().join("plain.obj");
    std::fs::write(&path, obj).unwrap();
    let file = bake_to(&path, &dir.path().join("plain.clod"));
    let h = Hierarchy::from_bytes(&file).unwrap();
    assert!(h.materials().is_none());
    assert!(h.vertex_colours().is_none());
    // Without materials, the export is the plain OBJ: no library.
    let files = obj_export(&h, Level::Base, &dir.path().join("plain.clod"), &path).unwrap();
    assert!(files.library.is_none());
}

#[test]
fn the_export_never_writes_over_its_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let (gltf, _) = write_gltf(dir.path());
    let clod = dir.path().join("out/model.clod");
    let file = bake_to(&gltf, &clod);
    let h = Hierarchy::from_bytes(&file).unwrap();
    let before = std::fs::read(&clod).unwrap();
    // The OBJ over the .clod file.
    let files = obj_export(&h, Level::Full, &clod, &clod).unwrap();
    assert!(matches!(files.write(), Err(ExportError::WouldOverwriteInput(p)) if p == clod));
    assert_eq!(std::fs::read(&clod).unwrap(), before);
    // The MTL over a texture the library names: a source whose texture is `wood grain.mtl`,
    // exported as `wood grain.obj` beside it.
    let old = dir.path().join("src/tex/wood grain.png");
    let texture = old.with_extension("mtl");
    std::fs::rename(&old, &texture).unwrap();
    let gltf_text = std::fs::read_to_string(&gltf)
        .unwrap()
        .replace("wood%20grain.png", "wood%20grain.mtl");
    std::fs::write(&gltf, gltf_text).unwrap();
    let obj = dir.path().join("src/tex/wood grain.obj");
    let file = bake_to(&gltf, &clod);
    let h = Hierarchy::from_bytes(&file).unwrap();
    let files = obj_export(&h, Level::Full, &clod, &obj).unwrap();
    assert!(
        matches!(files.write(), Err(ExportError::WouldOverwriteInput(p)) if p.ends_with("wood grain.mtl"))
    );
    assert_eq!(std::fs::read(&texture).unwrap(), PNG);
    assert!(
        !obj.exists(),
        "nothing is written when an output would replace an input"
    );
}

/// Bakes `input` into a temporary directory, exports the `.clod` into another and imports
/// the export: the `.clod`'s materials are the source's `(name, texture file)` pairs in
/// surface order, each texture path names the source's image from the `.clod`, and the OBJ
/// export keeps every name and texture.
fn round_trip_keeps(input: &Path, expected: &[(String, PathBuf)]) {
    let dir = tempfile::tempdir().unwrap();
    let clod = dir.path().join("baked/model.clod");
    let file = bake_to(input, &clod);
    let h = Hierarchy::from_bytes(&file).expect("loads");
    let m = h.materials().expect("materials");
    assert_eq!(m.len(), expected.len());
    for (s, (name, image)) in expected.iter().enumerate() {
        let got = m.get(s).unwrap();
        assert_eq!(got.name, name);
        let Some(TextureRef::Path(p)) = got.texture else {
            panic!("surface {s}: no texture path: {:?}", got.texture);
        };
        assert_eq!(canonical(&clod.parent().unwrap().join(p)), canonical(image));
    }
    let obj = dir.path().join("exported/model.obj");
    std::fs::create_dir_all(obj.parent().unwrap()).unwrap();
    obj_export(&h, Level::Full, &clod, &obj)
        .expect("export")
        .write()
        .expect("write the export");
    let again = import(&obj, &ImportOptions::default()).expect("the export imports");
    let got: Vec<(String, PathBuf)> = again
        .surfaces
        .iter()
        .map(|s| {
            let t = s.texture_file().expect("a texture");
            (s.name.clone(), canonical(&obj.parent().unwrap().join(t)))
        })
        .collect();
    let want: Vec<(String, PathBuf)> = expected
        .iter()
        .map(|(n, i)| (n.clone(), canonical(i)))
        .collect();
    assert_eq!(got, want);
}

#[test]
fn flight_helmet_keeps_its_six_textured_materials() {
    let Some(path) = shared_data::file("FlightHelmet/FlightHelmet.gltf") else {
        return;
    };
    // The materials in the order the meshes first use them (here: material order), each
    // with its base-colour image.
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let expected: Vec<(String, PathBuf)> = doc["materials"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| {
            let t = m["pbrMetallicRoughness"]["baseColorTexture"]["index"]
                .as_u64()
                .unwrap() as usize;
            let image = doc["textures"][t]["source"].as_u64().unwrap() as usize;
            let uri = doc["images"][image]["uri"].as_str().unwrap();
            (
                m["name"].as_str().unwrap().to_owned(),
                path.parent().unwrap().join(uri),
            )
        })
        .collect();
    assert_eq!(expected.len(), 6);
    round_trip_keeps(&path, &expected);
}

#[test]
fn spot_keeps_its_texture() {
    let (Some(obj), Some(png)) = (
        shared_data::file("spot/spot_triangulated.obj"),
        shared_data::file("spot/spot_texture.png"),
    ) else {
        return;
    };
    // Spot's OBJ names no material: give it one, in a directory of its own, whose MTL names
    // the texture where it lies.
    let dir = tempfile::tempdir().unwrap();
    let png = canonical(&png);
    std::fs::write(
        dir.path().join("spot.mtl"),
        format!("newmtl spot\nKd 1 1 1\nmap_Kd {}\n", png.display()),
    )
    .unwrap();
    let text = std::fs::read_to_string(obj).unwrap();
    let input = dir.path().join("spot.obj");
    std::fs::write(&input, format!("mtllib spot.mtl\nusemtl spot\n{text}")).unwrap();
    round_trip_keeps(&input, &[("spot".to_owned(), png)]);
}
