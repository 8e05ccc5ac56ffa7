//! Writing `.clod` files section by section: `Baked::write` (validated arrays, streamed
//! through a buffer) and `Built::write` (one array at a time from the collapses, the written
//! file validated before the rename) write exactly the bytes of `Baked::to_bytes_for`, with
//! materials, vertex colours, g-mesh levels, octree sections and a blocked build; a failed or invalid write
//! leaves an existing target as it was and no temporary file behind.

use std::path::Path;

use caveclod_bake::baked::{BakeWriteError, Baked};
use caveclod_bake::blocked::BlockedOptions;
use caveclod_bake::gmesh::{build as gmesh_levels, GMeshOptions};
use caveclod_bake::import::ImportOptions;
use caveclod_bake::mesh::{Mesh, Surface, Texture};
use caveclod_bake::ooc::{MultiresOptions, OocOptions};
use caveclod_bake::pipeline::{build_file_blocked, build_mesh, build_out_of_core, Built};
use caveclod_bake::report::BakeInfo;
use caveclod_core::format::{tags, ExtraSection, WriteError};
use caveclod_core::{FormatError, Hierarchy};
use caveclod_tests::{generate, meshes, to_mesh, AlignedBytes};

/// The arrays of `built`, with its materials.
fn arrays(built: &Built) -> Baked {
    Baked::new(&built.welded, &built.collapses).with_materials(&built.surfaces, &built.texture_dir)
}

/// Both streaming writers give `to_bytes_for`'s bytes at `dir`, and the file reads back.
fn assert_streams_identical(built: Built, dir: &Path, extra: &[ExtraSection<'_>]) {
    let baked = arrays(&built);
    let by_arrays = dir.join("arrays.clod");
    let by_collapses = dir.join("collapses.clod");
    let want = baked.to_bytes_for(&by_arrays, extra).expect("to_bytes_for");
    let n = baked.write(&by_arrays, extra).expect("Baked::write");
    assert_eq!(n, want.len() as u64);
    assert!(
        std::fs::read(&by_arrays).unwrap() == want,
        "Baked::write differs"
    );
    let n = built.write(&by_collapses, extra).expect("Built::write");
    assert_eq!(n, want.len() as u64);
    let got = std::fs::read(&by_collapses).unwrap();
    assert_eq!(got.len(), want.len());
    if let Some(at) = got.iter().zip(&want).position(|(a, b)| a != b) {
        panic!("Built::write differs first at byte {at}");
    }
    Hierarchy::from_bytes(AlignedBytes::from_slice(&got).bytes()).expect("valid");
    assert_no_temporary_files(dir);
}

fn assert_no_temporary_files(dir: &Path) {
    let left: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tmp"))
        .collect();
    assert!(left.is_empty(), "temporary files left: {left:?}");
}

fn built_of(mesh: &Mesh) -> Built {
    build_mesh(mesh, "test", &mut |_| {}).expect("bake")
}

/// A terrain with two textured surfaces (one texture path with a space, relative to a
/// source directory elsewhere) and a colour per position.
fn coloured_textured_terrain() -> Mesh {
    let mut mesh = to_mesh(&meshes::terrain(12, 10, 3));
    mesh.colors = (0..mesh.positions.len())
        .map(|i| [(i % 7) as f32 / 7.0, (i % 5) as f32 / 5.0, 0.5, 1.0])
        .collect();
    for (i, t) in mesh.triangles.iter_mut().enumerate() {
        t.color = t.position;
        t.surface = (i % 2) as u16;
    }
    mesh.surfaces = vec![
        Surface {
            texture: Some(Texture::File("tex/wood grain.png".into())),
            ..Surface::plain("wood")
        },
        Surface {
            base_color: [0.2, 0.4, 0.6, 1.0],
            double_sided: true,
            ..Surface::plain("paint")
        },
    ];
    mesh
}

#[test]
fn plain_meshes_stream_to_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    for t in [
        meshes::terrain(6, 6, 1),
        meshes::holed_terrain(9, 7, 2),
        meshes::sphere(2),
    ] {
        assert_streams_identical(built_of(&to_mesh(&t)), dir.path(), &[]);
        let built = built_of(&to_mesh(&t));
        let json = built.info.to_json();
        assert_streams_identical(built, dir.path(), &[BakeInfo::section(&json)]);
    }
}

#[test]
fn materials_and_vertex_colours_stream_to_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let mut built = built_of(&coloured_textured_terrain());
    built.texture_dir = dir.path().join("source");
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    assert_streams_identical(built, &out, &[]);
    let file = std::fs::read(out.join("collapses.clod")).unwrap();
    let file = AlignedBytes::from_slice(&file);
    let h = Hierarchy::from_bytes(file.bytes()).unwrap();
    assert!(h.vertex_colours().is_some(), "no colour section");
    let materials = h.materials().expect("material sections");
    assert_eq!(materials.len(), 2);
}

#[test]
fn g_mesh_levels_stream_to_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let built = built_of(&to_mesh(&meshes::terrain(16, 16, 5)));
    let baked = arrays(&built);
    let h = baked.hierarchy().unwrap();
    let g = gmesh_levels(&h, &GMeshOptions::default()).expect("g-mesh levels");
    assert_streams_identical(built, dir.path(), &g.sections());
}

#[test]
fn an_out_of_core_bake_with_its_octree_streams_to_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("terrain.ply");
    generate::terrain(&input, 12_000, &mut |_, _| {}).unwrap();
    let options = OocOptions {
        temp_dir: Some(dir.path().to_path_buf()),
        leaf_triangles: 1 << 9,
        target_triangles: Some(3000),
        octree: Some(MultiresOptions {
            block_levels: 2,
            coarsest_triangles: 128,
        }),
        ..OocOptions::with_budget(8 << 20)
    };
    let o = build_out_of_core(&input, &options, &mut |_| {}, &mut |_| {}).unwrap();
    let octree = o.octree.as_ref().expect("the octree was asked for");
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let json = o.built.info.to_json();
    let parts = octree.parts();
    let mut extra = vec![BakeInfo::section(&json)];
    extra.extend(parts.sections());
    assert_streams_identical(o.built, &out, &extra);
}

#[test]
fn a_blocked_bake_streams_to_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("terrain.ply");
    generate::terrain(&input, 20_000, &mut |_, _| {}).unwrap();
    let options = BlockedOptions {
        block_triangles: 2048,
    };
    let (built, levels) =
        build_file_blocked(&input, &ImportOptions::default(), &options, &mut |_| {}).unwrap();
    assert!(levels[0].blocks > 1, "one block: {levels:?}");
    let json = built.info.to_json();
    assert_streams_identical(built, dir.path(), &[BakeInfo::section(&json)]);
}

/// Writes `old` at `target`, lets `write` fail on it, and checks that the target still holds
/// `old` and no temporary file is left.
fn assert_untouched_after(
    dir: &Path,
    write: impl FnOnce(&Path) -> Result<u64, BakeWriteError>,
) -> BakeWriteError {
    let target = dir.join("target.clod");
    let old = b"the previous file".to_vec();
    std::fs::write(&target, &old).unwrap();
    let e = write(&target).expect_err("the write must fail");
    assert_eq!(std::fs::read(&target).unwrap(), old, "the target changed");
    assert_no_temporary_files(dir);
    e
}

#[test]
fn refused_arrays_leave_the_target_untouched() {
    let dir = tempfile::tempdir().unwrap();
    let built = built_of(&to_mesh(&meshes::terrain(6, 6, 1)));
    let bad = ExtraSection {
        tag: tags::NODES,
        record_size: 8,
        bytes: &[0; 16],
    };
    let e = assert_untouched_after(dir.path(), |p| arrays(&built).write(p, &[bad]));
    assert!(
        matches!(e, BakeWriteError::Invalid(WriteError::BadExtraSection { tag }) if tag == tags::NODES),
        "{e}"
    );
}

#[test]
fn an_invalid_file_written_from_the_collapses_never_replaces_the_target() {
    let dir = tempfile::tempdir().unwrap();
    let built = built_of(&to_mesh(&meshes::terrain(6, 6, 1)));
    // A section the hierarchy already has: the file is written, then refused on reading back.
    let duplicate = ExtraSection {
        tag: tags::ROOTS,
        record_size: 4,
        bytes: &[0; 4],
    };
    let e = assert_untouched_after(dir.path(), |p| built.write(p, &[duplicate]));
    assert!(
        matches!(
            e,
            BakeWriteError::Invalid(WriteError::Invalid(FormatError::DuplicateSection { tag }))
                if tag == tags::ROOTS
        ),
        "{e}"
    );
    // Broken collapses: a refinement radius that is not a number.
    let mut built = built_of(&to_mesh(&meshes::terrain(6, 6, 1)));
    let c = built.welded.positions.len();
    built.collapses.radius[c] = f32::NAN;
    let e = assert_untouched_after(dir.path(), |p| built.write(p, &[]));
    assert!(
        matches!(e, BakeWriteError::Invalid(WriteError::Invalid(_))),
        "{e}"
    );
}

#[test]
fn a_write_into_a_missing_directory_fails_with_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let built = built_of(&to_mesh(&meshes::terrain(6, 6, 1)));
    let target = dir.path().join("missing/out.clod");
    let from_arrays = arrays(&built).write(&target, &[]);
    for e in [
        from_arrays.expect_err("no directory"),
        built.write(&target, &[]).expect_err("no directory"),
    ] {
        assert!(
            matches!(&e, BakeWriteError::Io { path, .. } if path == &target),
            "{e}"
        );
    }
}
