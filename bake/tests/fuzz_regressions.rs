//! Inputs the fuzz targets (`fuzz/`) found failing, each read again through `import_bytes`
//! as the target read it: a typed error or a mesh that validates, never a panic nor
//! `ImportError::Internal`. The files are the fuzzers' artifacts, kept in `tests/data/fuzz/`.

use caveclod_bake::import::{import_bytes, ImportError, ImportOptions};
use caveclod_bake::mesh::Mesh;

fn import_artifact(name: &str, options: &ImportOptions) -> Result<Mesh, ImportError> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/fuzz")
        .join(name);
    let bytes = std::fs::read(&path).expect("reading the artifact");
    let mut missing = |_: &str| Err(std::io::Error::from(std::io::ErrorKind::NotFound));
    let result = import_bytes(name, &bytes, &mut missing, options).map(|(mesh, _)| mesh);
    if let Err(ImportError::Internal { message, .. }) = &result {
        panic!("{name}: internal error: {message}");
    }
    result
}

/// `npy` target: 4 x 4 float32 grids (either byte order) with neighbouring heights near
/// `±f32::MAX`; their slope overflowed `f32` and the vertex normals came out NaN, so the
/// import failed its own mesh check. They import, every normal a unit vector.
#[test]
fn npy_heights_near_f32_max_give_finite_normals() {
    for name in ["npy_extreme_heights_le.npy", "npy_extreme_heights_be.npy"] {
        let options = ImportOptions { spacing: Some(1.0) };
        let mesh = import_artifact(name, &options).unwrap_or_else(|e| panic!("{name}: {e}"));
        mesh.validate().unwrap();
        assert!(!mesh.triangles.is_empty(), "{name}");
        for n in &mesh.normals {
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            assert!((len - 1.0).abs() < 1e-5, "{name}: normal {n:?}");
        }
    }
}

/// Found while reading the heightfield code after the `npy` finding (the `dem` target did not
/// reach them): a DEM whose header gives a resolution of 3e301 m (infinite as `f32`, so the
/// positions came out NaN) and one of 2e38 m over three profiles (an extent past `f32::MAX`,
/// so the last column's positions were infinite). Both are typed errors naming the grid.
#[test]
fn dem_spacing_outside_f32_is_a_typed_error() {
    for name in ["dem_resolution_past_f32.dem", "dem_extent_past_f32.dem"] {
        let err = import_artifact(name, &ImportOptions::default()).expect_err(name);
        assert!(
            matches!(err, ImportError::Unsupported { .. }),
            "{name}: {err}"
        );
        assert!(
            err.to_string().contains("32-bit coordinates"),
            "{name}: {err}"
        );
    }
}

/// The `bake_mesh` fuzzer's findings: coordinates near `f32::MAX` made the bake's own output
/// fail validation (an infinite bounding radius, non-finite attributes). Values beyond
/// `Mesh::MAX_MAGNITUDE` are refused up front, naming the element; large values within it
/// bake into a hierarchy that loads.
#[test]
fn coordinates_near_f32_max_are_refused_and_large_ones_bake() {
    use caveclod_bake::mesh::{Surface, Triangle, NO_ATTRIBUTE};
    use caveclod_bake::pipeline::{bake_mesh, BakeError};
    let mesh = |far: f32| Mesh {
        positions: vec![
            [0.0, 0.0, 0.0],
            [far, 0.0, 0.0],
            [0.0, far, 0.0],
            [far, far, 1.0],
        ],
        triangles: vec![
            Triangle {
                position: [0, 1, 2],
                normal: [NO_ATTRIBUTE; 3],
                uv: [NO_ATTRIBUTE; 3],
                color: [NO_ATTRIBUTE; 3],
                surface: 0,
            },
            Triangle {
                position: [1, 3, 2],
                normal: [NO_ATTRIBUTE; 3],
                uv: [NO_ATTRIBUTE; 3],
                color: [NO_ATTRIBUTE; 3],
                surface: 0,
            },
        ],
        surfaces: vec![Surface::plain("s".to_string())],
        ..Mesh::default()
    };
    match bake_mesh(&mesh(3.0e38), "huge", &mut |_| {}) {
        Err(BakeError::Weld { path, source }) => {
            let message = source.to_string();
            assert_eq!(path, "huge");
            assert!(message.contains("positions[1]"), "{message}");
        }
        other => panic!("{:?}", other.map(|_| ())),
    }
    let (baked, _) = bake_mesh(&mesh(1.0e17), "large", &mut |_| {}).expect("bakes");
    let bytes = baked.to_bytes(&[]).expect("writes");
    caveclod_core::Hierarchy::from_bytes(&bytes).expect("loads");
}
