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
