//! The importers through the public API, on files the tests write, and on the real data in
//! `../shared/data` when it is there (each such test prints a note and passes when the file is
//! absent).

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::time::Instant;

use caveclod_bake::import::{import, import_bytes, import_with_report, ImportError, ImportOptions};
use caveclod_bake::mesh::{Mesh, NO_ATTRIBUTE};
use caveclod_tests::shared_data;

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).expect("write test file");
    path
}

fn no_options() -> ImportOptions {
    ImportOptions::default()
}

fn spacing(m: f32) -> ImportOptions {
    ImportOptions { spacing: Some(m) }
}

/// The error for `path`, which must be a real error about the file (not an importer bug).
fn error(path: &Path, options: &ImportOptions) -> ImportError {
    let err = import(path, options).expect_err("import must fail");
    assert!(
        !matches!(err, ImportError::Internal { .. }),
        "importer bug on {}: {err}",
        path.display()
    );
    assert_eq!(err.file(), path.display().to_string());
    err
}

#[test]
fn unknown_extension_and_missing_file() {
    let dir = tempfile::tempdir().unwrap();
    let stl = write(dir.path(), "part.STL", b"solid x\nendsolid x\n");
    let err = error(&stl, &no_options());
    assert!(matches!(err, ImportError::UnknownFormat { .. }));
    assert!(err.to_string().ends_with(
        "part.STL: unknown format .stl (expected .gltf, .glb, .obj, .ply, .dem or .npy)"
    ));
    let bare = write(dir.path(), "mesh", b"");
    assert!(error(&bare, &no_options())
        .to_string()
        .contains("unknown format (no extension)"));

    for name in [
        "gone.obj",
        "gone.ply",
        "gone.gltf",
        "gone.glb",
        "gone.dem",
        "gone.npy",
    ] {
        let path = dir.path().join(name);
        let err = error(&path, &spacing(1.0));
        assert!(matches!(err, ImportError::Io { .. }), "{err}");
        assert!(
            err.to_string().contains(&format!("{name}: cannot read: ")),
            "{err}"
        );
    }
}

#[test]
fn obj_with_seam_and_two_materials() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "box.mtl",
        b"newmtl wood\nKd 0.6 0.4 0.2\nmap_Kd wood.png\n\nnewmtl steel\nKd 0.5 0.5 0.5\nd 0.25\n",
    );
    // Two quads sharing the edge 2-3; the UVs are cut along it (a seam): the second quad uses
    // texture coordinates 5 and 6 at positions 2 and 3, where the first uses 3 and 4.
    let obj = write(
        dir.path(),
        "box.obj",
        b"mtllib box.mtl\n\
          v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 1 2 0\nv 0 2 0\n\
          vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0\nvt 0 0.5\nvt 1 1\nvt 0 1\n\
          vn 0 0 1\n\
          usemtl wood\nf 1/1/1 2/2/1 3/3/1 4/4/1\n\
          usemtl steel\nf 4/6/1 3/5/1 5/7/1 6/8/1\n",
    );
    let (mesh, report) = import_with_report(&obj, &no_options()).unwrap();
    assert!(report.notes.is_empty(), "{:?}", report.notes);
    assert_eq!(mesh.triangles.len(), 4);
    assert_eq!(mesh.positions.len(), 6);
    assert_eq!(mesh.uvs.len(), 8);
    let names: Vec<&str> = mesh.surfaces.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["wood", "steel"]);
    assert_eq!(mesh.surfaces[0].base_color, [0.6, 0.4, 0.2, 1.0]);
    assert_eq!(mesh.surfaces[0].texture_file(), Some("wood.png"));
    assert_eq!(mesh.surfaces[1].base_color, [0.5, 0.5, 0.5, 0.25]);
    assert_eq!(mesh.triangles_per_surface(), [2, 2]);
    // The seam: position 2 (0-based) has UV 2 in the first quad and UV 4 in the second.
    let uvs_at = |p: u32| -> HashSet<u32> {
        mesh.triangles
            .iter()
            .flat_map(|t| {
                (0..3)
                    .filter(move |&k| t.position[k] == p)
                    .map(move |k| t.uv[k])
            })
            .collect()
    };
    assert_eq!(uvs_at(2), HashSet::from([2, 4]));
    assert_eq!(uvs_at(3), HashSet::from([3, 5]));
    assert!(mesh.triangles.iter().all(|t| t.normal == [0, 0, 0]));
}

/// `import_bytes` reads what `import` reads, asking its loader for the files the input names
/// (here an MTL library and a glTF buffer), and picks the importer by the name's extension.
#[test]
fn import_bytes_reads_as_import_does() {
    let dir = tempfile::tempdir().unwrap();
    let mtl = b"newmtl red\nKd 1 0 0\nd 0.5\n";
    write(dir.path(), "m.mtl", mtl);
    let obj = b"mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n";
    let path = write(dir.path(), "m.obj", obj);
    let mut asked = Vec::new();
    let mut load = |name: &str| {
        asked.push(name.to_owned());
        std::fs::read(dir.path().join(name))
    };
    let (from_bytes, _) = import_bytes("m.obj", obj, &mut load, &no_options()).unwrap();
    assert_eq!(asked, ["m.mtl"]);
    assert_eq!(from_bytes, import(&path, &no_options()).unwrap());
    assert_eq!(from_bytes.surfaces[0].base_color, [1.0, 0.0, 0.0, 0.5]);

    let gltf = gltf_files(dir.path(), 3);
    let json = std::fs::read(&gltf).unwrap();
    let mut load = |name: &str| std::fs::read(dir.path().join(name));
    let (from_bytes, _) = import_bytes("scene.gltf", &json, &mut load, &no_options()).unwrap();
    assert_eq!(from_bytes, import(&gltf, &no_options()).unwrap());

    // Without the files it names, the import says which one it could not read.
    let mut missing = |_: &str| Err(std::io::Error::from(std::io::ErrorKind::NotFound));
    let err = import_bytes("scene.gltf", &json, &mut missing, &no_options()).unwrap_err();
    assert!(matches!(err, ImportError::Io { .. }), "{err}");
    assert_eq!(err.file(), "scene.gltf");
    let err = import_bytes("x.stl", obj, &mut missing, &no_options()).unwrap_err();
    assert!(matches!(err, ImportError::UnknownFormat { .. }), "{err}");
}

#[test]
fn obj_index_out_of_range_names_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let obj = write(
        dir.path(),
        "model.obj",
        b"# header\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n\nf 1 2 9\n",
    );
    let err = error(&obj, &no_options());
    assert!(matches!(err, ImportError::IndexOutOfRange { .. }));
    assert!(
        err.to_string()
            .ends_with("model.obj: line 7: vertex index 9 out of range (3 positions)"),
        "{err}"
    );
}

/// A .gltf with a node transform (translation 5 along y, child scaled by 2) over a 44-byte
/// .bin: three positions and three u16 indices (+ padding); the POSITION accessor claims
/// `position_count` elements.
fn gltf_files(dir: &Path, position_count: usize) -> PathBuf {
    let mut bin = Vec::new();
    for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    for i in [0u16, 1, 2, 0] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    write(dir, "tri.bin", &bin);
    let json = format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "scenes": [{{"nodes": [0]}}],
  "nodes": [{{"translation": [0, 5, 0], "children": [1]}}, {{"scale": [2, 2, 2], "mesh": 0}}],
  "meshes": [{{"name": "Helmet", "primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1, "material": 0}}]}}],
  "materials": [{{"name": "Visor", "pbrMetallicRoughness": {{"baseColorFactor": [0.1, 0.2, 0.3, 1]}}}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": {position_count}, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}}
  ],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": 36}},
    {{"buffer": 0, "byteOffset": 36, "byteLength": 6}}
  ],
  "buffers": [{{"uri": "tri.bin", "byteLength": 44}}]
}}"#
    );
    write(dir, "x.gltf", json.as_bytes())
}

#[test]
fn gltf_node_transform_and_accessor_out_of_bounds() {
    let dir = tempfile::tempdir().unwrap();
    let path = gltf_files(dir.path(), 3);
    let mesh = import(&path, &no_options()).unwrap();
    assert_eq!(
        mesh.positions,
        [[0.0, 5.0, 0.0], [2.0, 5.0, 0.0], [0.0, 7.0, 0.0]]
    );
    assert_eq!(mesh.triangles.len(), 1);
    assert_eq!(mesh.surfaces.len(), 1);
    assert_eq!(mesh.surfaces[0].name, "Visor");
    assert_eq!(mesh.surfaces[0].base_color, [0.1, 0.2, 0.3, 1.0]);
    assert_eq!(mesh.triangles[0].uv, [NO_ATTRIBUTE; 3]);

    let path = gltf_files(dir.path(), 4);
    let err = error(&path, &no_options());
    assert!(
        err.to_string().contains(
            "x.gltf: accessor 0 (POSITION of mesh 'Helmet' primitive 0): out of bounds of buffer view 0"
        ),
        "{err}"
    );
}

/// A binary little-endian PLY: a quad (fan-triangulated) over four vertices.
fn ply_quad(y1: f32) -> Vec<u8> {
    let mut out = b"ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\n\
                    property float y\nproperty float z\nelement face 1\n\
                    property list uchar int vertex_indices\nend_header\n"
        .to_vec();
    for v in [0.0, 0.0, 0.0, 1.0, y1, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0f32] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.push(4);
    for i in [0i32, 1, 2, 3] {
        out.extend_from_slice(&i.to_le_bytes());
    }
    out
}

#[test]
fn ply_quad_truncation_and_nan() {
    let dir = tempfile::tempdir().unwrap();
    let good = ply_quad(0.0);
    let path = write(dir.path(), "quad.ply", &good);
    let mesh = import(&path, &no_options()).unwrap();
    let tris: Vec<[u32; 3]> = mesh.triangles.iter().map(|t| t.position).collect();
    assert_eq!(tris, [[0, 1, 2], [0, 2, 3]]);

    for cut in [good.len() - 1, good.len() - 17, good.len() - 40, 150, 20] {
        let path = write(dir.path(), "cut.ply", &good[..cut]);
        let err = error(&path, &no_options());
        assert!(
            matches!(err, ImportError::Truncated { .. }),
            "cut {cut}: {err}"
        );
        assert!(err.to_string().contains("cut.ply: truncated: "));
    }

    let path = write(dir.path(), "nan.ply", &ply_quad(f32::NAN));
    assert!(error(&path, &no_options())
        .to_string()
        .ends_with("nan.ply: vertex 1: coordinate y is NaN"));
}

fn npy(descr: &str, fortran: bool, shape: &str, data: &[u8]) -> Vec<u8> {
    let mut dict = format!(
        "{{'descr': '{descr}', 'fortran_order': {}, 'shape': {shape}, }}",
        if fortran { "True" } else { "False" }
    );
    while (10 + dict.len() + 1) % 64 != 0 {
        dict.push(' ');
    }
    dict.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(dict.len() as u16).to_le_bytes());
    out.extend_from_slice(dict.as_bytes());
    out.extend_from_slice(data);
    out
}

fn heights_of(mesh: &Mesh) -> Vec<f32> {
    mesh.positions.iter().map(|p| p[1]).collect()
}

#[test]
fn npy_int16_and_float32() {
    let dir = tempfile::tempdir().unwrap();
    let values: [i16; 6] = [100, 101, 102, 110, 111, 112];
    let data: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    let path = write(dir.path(), "h16.npy", &npy("<i2", false, "(2, 3)", &data));
    let (mesh, report) = import_with_report(&path, &spacing(10.0)).unwrap();
    assert_eq!(mesh.triangles.len(), 4);
    assert_eq!(
        heights_of(&mesh),
        [100.0, 101.0, 102.0, 110.0, 111.0, 112.0]
    );
    // Row 0 is the northern edge (z = 0); x east in steps of the spacing.
    assert_eq!(mesh.positions[5], [20.0, 112.0, 10.0]);
    let info = report.heightfield.unwrap();
    assert_eq!((info.columns, info.rows, info.posts), (3, 2, 6));

    let values: [f32; 6] = [1.5, f32::NAN, 2.5, 3.5, 4.5, 5.5];
    let data: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    let path = write(dir.path(), "h32.npy", &npy("<f4", false, "(2, 3)", &data));
    // The NaN post removes both cells that touch it: nothing is left.
    assert!(matches!(
        error(&path, &spacing(1.0)),
        ImportError::Empty { .. }
    ));

    let values: [f32; 9] = [1.5, 2.0, 2.5, 3.5, 4.5, 5.5, 6.0, 6.5, f32::NAN];
    let data: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    let path = write(dir.path(), "h33.npy", &npy("<f4", false, "(3, 3)", &data));
    let (mesh, report) = import_with_report(&path, &spacing(1.0)).unwrap();
    assert_eq!(mesh.triangles.len(), 6, "the south-east cell is a hole");
    assert_eq!(report.heightfield.unwrap().posts, 8);
    assert!(report
        .notes
        .iter()
        .any(|n| n.contains("1 of 9 grid posts are missing")));

    let err = error(&path, &no_options());
    assert!(matches!(err, ImportError::MissingOption { .. }));
    assert!(err.to_string().contains("--spacing"), "{err}");
    assert!(error(&path, &spacing(-1.0))
        .to_string()
        .contains("positive"));
}

#[test]
fn npy_fortran_order_is_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "f.npy", &npy("<f4", true, "(2, 2)", &[0; 16]));
    let err = error(&path, &spacing(1.0));
    assert!(matches!(err, ImportError::Unsupported { .. }));
    assert!(err.to_string().contains("fortran_order: True"), "{err}");
}

#[test]
fn lines_only_obj_is_an_empty_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "lines.obj", b"v 0 0 0\nv 1 0 0\nl 1 2\n");
    let err = error(&path, &no_options());
    assert!(matches!(err, ImportError::Empty { .. }));
    assert!(err
        .to_string()
        .ends_with("lines.obj: no triangles: 1 non-triangle primitives skipped"));
}

/// Deterministic byte mutations of small valid files of every format: each result is a mesh
/// that validates or an error about the file, never a panic or an importer bug.
#[test]
fn mutated_files_never_panic() {
    let dir = tempfile::tempdir().unwrap();
    let gltf_dir = dir.path().join("g");
    std::fs::create_dir(&gltf_dir).unwrap();
    let gltf = std::fs::read(gltf_files(&gltf_dir, 3)).unwrap();
    let obj = b"mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0 1 0 0\nvt 0 0\nvn 0 0 1\n\
                usemtl a\nf 1/1/1 2/1/1 3//1\nf -1 -2 -3\n"
        .to_vec();
    let ascii_ply =
        b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                      property float z\nproperty uchar red\nelement face 1\n\
                      property list uchar int vertex_indices\nend_header\n0 0 0 9\n1 0 0 8\n\
                      0 1 0 7\n3 0 1 2\n"
            .to_vec();
    let data: Vec<u8> = [1.0f32, 2.0, 3.0, 4.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let cases: Vec<(&str, Vec<u8>)> = vec![
        ("m.gltf", gltf),
        ("m.obj", obj),
        ("m.ply", ascii_ply),
        ("b.ply", ply_quad(0.0)),
        ("m.npy", npy("<f4", false, "(2, 2)", &data)),
    ];
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let mut outcomes = [0usize; 2];
    for (name, original) in &cases {
        for _ in 0..300 {
            let mut bytes = original.clone();
            for _ in 0..1 + next() % 4 {
                let at = (next() % bytes.len() as u64) as usize;
                match next() % 4 {
                    0 => bytes[at] = next() as u8,
                    1 => bytes[at] = b"0123456789-.eE /\n"[(next() % 17) as usize],
                    2 => bytes.truncate(at),
                    _ => bytes.insert(at, next() as u8),
                }
                if bytes.is_empty() {
                    break;
                }
            }
            let path = if *name == "m.gltf" {
                write(&gltf_dir, "x.gltf", &bytes)
            } else {
                write(dir.path(), name, &bytes)
            };
            match import(&path, &spacing(1.0)) {
                Ok(mesh) => {
                    mesh.validate().unwrap();
                    outcomes[0] += 1;
                }
                Err(ImportError::Internal { message, .. }) => {
                    panic!("importer bug on mutated {name}: {message}\n{bytes:?}")
                }
                Err(_) => outcomes[1] += 1,
            }
        }
    }
    // Both outcomes must occur, or the mutations test nothing.
    assert!(outcomes[0] > 0 && outcomes[1] > 0, "{outcomes:?}");
}

fn timed(path: &Path, options: &ImportOptions) -> (Mesh, caveclod_bake::import::ImportReport) {
    let start = Instant::now();
    let result = import_with_report(path, options).unwrap();
    eprintln!(
        "imported {} in {:.1} ms ({} build)",
        path.file_name().unwrap().to_string_lossy(),
        start.elapsed().as_secs_f64() * 1e3,
        if cfg!(debug_assertions) {
            "debug"
        } else {
            "release"
        }
    );
    result
}

#[test]
fn flight_helmet() {
    let Some(path) = shared_data::file("FlightHelmet/FlightHelmet.gltf") else {
        return;
    };
    let (mesh, report) = timed(&path, &no_options());
    assert_eq!(mesh.triangles.len(), 94_722);
    assert_eq!(mesh.surfaces.len(), 6, "{:?}", mesh.surfaces);
    assert_eq!(report.skipped_primitives, 0);
    assert!(mesh.surfaces.iter().all(|s| s
        .texture_file()
        .is_some_and(|t| t.ends_with("_BaseColor.png"))));
    for s in &mesh.surfaces {
        let texture = path.parent().unwrap().join(s.texture_file().unwrap());
        assert!(texture.exists(), "{}", texture.display());
    }
    assert!(mesh
        .triangles
        .iter()
        .all(|t| t.normal[0] != NO_ATTRIBUTE && t.uv[0] != NO_ATTRIBUTE));
    assert!(mesh.triangles_per_surface().iter().all(|&n| n > 0));
}

#[test]
fn spot_obj() {
    let Some(path) = shared_data::file("spot/spot_triangulated.obj") else {
        return;
    };
    let (mesh, _) = timed(&path, &no_options());
    assert_eq!(mesh.triangles.len(), 5_856);
    assert_eq!(mesh.positions.len(), 2_930);
    assert!(
        mesh.uvs.len() > mesh.positions.len(),
        "{} UVs",
        mesh.uvs.len()
    );
    // Seams preserved: some positions carry two or more UVs.
    let mut uvs_of = vec![HashSet::new(); mesh.positions.len()];
    for t in &mesh.triangles {
        for k in 0..3 {
            uvs_of[t.position[k] as usize].insert(t.uv[k]);
        }
    }
    let seam_positions = uvs_of.iter().filter(|s| s.len() > 1).count();
    assert!(seam_positions > 0);
    eprintln!("spot: {seam_positions} positions on UV seams");
}

#[test]
fn lucy_ply() {
    let Some(path) = shared_data::file("scans/lucy.ply") else {
        return;
    };
    let (mesh, _) = timed(&path, &no_options());
    assert_eq!(mesh.triangles.len(), 99_970);
    assert_eq!(mesh.positions.len(), 49_987);
    assert!(mesh.normals.is_empty() && mesh.uvs.is_empty() && mesh.colors.is_empty());
}

#[test]
fn sainte_helens_dem() {
    let Some(path) = shared_data::file("terrain/SainteHelens.dem") else {
        return;
    };
    let (mesh, report) = timed(&path, &no_options());
    let info = report.heightfield.expect("heightfield info");
    assert_eq!(info.posts, 148_885);
    assert_eq!(info.spacing, [30.0, 30.0]);
    assert!(
        (info.height_range[0] - 682.0).abs() <= 1.0,
        "{:?}",
        info.height_range
    );
    assert!(
        (info.height_range[1] - 2_543.0).abs() <= 1.0,
        "{:?}",
        info.height_range
    );
    let (low, high) = mesh
        .positions
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), p| {
            (l.min(p[1]), h.max(p[1]))
        });
    assert!(low >= 681.0 && high <= 2_544.0, "{low}..{high}");
    assert!(high >= 2_542.0, "the summit is in the mesh");
    // Irregular corners are holes and borders: every position is a real post, and every
    // triangle spans at most one grid cell.
    assert!(mesh.positions.len() <= info.posts);
    for t in &mesh.triangles {
        let p = t.position.map(|i| mesh.positions[i as usize]);
        for (a, b) in [(0, 1), (1, 2), (2, 0)] {
            assert!((p[a][0] - p[b][0]).abs() <= 30.0 && (p[a][2] - p[b][2]).abs() <= 30.0);
        }
    }
    assert!(mesh.triangles.len() > 2 * (info.posts - 2 * (info.columns + info.rows)) * 9 / 10);
    eprintln!(
        "St. Helens: {} x {} grid, {} posts, {} positions, {} triangles",
        info.columns,
        info.rows,
        info.posts,
        mesh.positions.len(),
        mesh.triangles.len()
    );
}
