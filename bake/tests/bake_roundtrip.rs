//! Baking generated meshes: the hierarchy validates, full refinement gives back exactly the
//! input triangles (per surface, as position triples) with their attributes, and full
//! collapse gives back the base mesh.

use caveclod_bake::hierarchy::{build, AttributeWeights};
use caveclod_bake::{baked::Baked, weld::weld};
use caveclod_core::{CameraState, PolyId};
use caveclod_tests::check::{check_front, collapse_all, split_all};
use caveclod_tests::{meshes, to_mesh, TestMesh};

fn bake(t: &TestMesh) -> Baked {
    let w = weld(&to_mesh(t)).expect("weld");
    let h = build(&w, &AttributeWeights::default(), &mut |_, _| {}).expect("build");
    Baked::new(&w, &h)
}

fn round_trip(t: &TestMesh, max_base_fraction: f64) {
    let baked = bake(t);
    let h = baked.hierarchy().expect("valid hierarchy");
    assert!(
        (h.base_polygon_count() as f64) <= max_base_fraction * t.triangles.len() as f64,
        "base {} of {}",
        h.base_polygon_count(),
        t.triangles.len()
    );
    let mut mem = vec![0u32; CameraState::words_needed(&h)];
    let mut cam = CameraState::new(&h, &mut mem).expect("sized");
    split_all(&h, &mut cam);
    check_front(&h, &cam).expect("full front");
    let key = |pts: [[f32; 3]; 3]| {
        let b = pts.map(|p| p.map(f32::to_bits));
        [b, [b[1], b[2], b[0]], [b[2], b[0], b[1]]]
            .into_iter()
            .min()
            .expect("rotations")
    };
    let mut want: Vec<_> = t
        .triangles
        .iter()
        .map(|x| (x.surface, key(x.p.map(|i| t.positions[i as usize]))))
        .collect();
    let mut got: Vec<_> = cam
        .active_polygons(&h)
        .map(|f| {
            let c = cam.polygon_corners(&h, f).expect("active");
            (
                h.polygons()[f.index()].surface.0,
                key(c.map(|v| h.node_point(v).expect("node"))),
            )
        })
        .collect();
    want.sort_unstable();
    got.sort_unstable();
    assert_eq!(got, want);
    // Attributes survive: every corner's vertex carries the input corner's normal and UV.
    let mut by_pos = std::collections::HashMap::new();
    for tri in &t.triangles {
        for k in 0..3 {
            by_pos
                .entry((
                    tri.surface,
                    t.positions[tri.p[k] as usize].map(f32::to_bits),
                ))
                .or_insert_with(Vec::new)
                .push((tri.normal[k], tri.uv[k]));
        }
    }
    let ns = h.surface_count();
    let mut out = vec![0u32; (0..ns).map(|s| cam.index_count(s)).sum()];
    let mut offsets = vec![0u32; ns + 1];
    cam.emit_indices_packed(&h, &mut out, &mut offsets)
        .expect("emit");
    for s in 0..ns {
        for &i in &out[offsets[s] as usize..offsets[s + 1] as usize] {
            let v = h.vertices()[i as usize];
            let seen = &by_pos[&(s as u16, v.position.map(f32::to_bits))];
            assert!(
                seen.contains(&(v.normal, v.uv)),
                "vertex {i} of surface {s} has attributes no input corner had"
            );
        }
    }
    assert_eq!(collapse_all(&h, &mut cam), h.splits().len());
    for (i, b) in h.base().iter().enumerate() {
        assert_eq!(cam.polygon_corners(&h, PolyId(i as u32)), Some(b.corners));
    }
}

#[test]
fn terrain_with_seam_round_trips() {
    round_trip(&meshes::terrain(24, 20, 3), 0.05);
}

#[test]
fn closed_sphere_round_trips_to_a_tiny_base() {
    round_trip(&meshes::sphere(3), 0.05);
}

#[test]
fn holed_terrain_round_trips() {
    round_trip(&meshes::holed_terrain(24, 24, 5), 0.2);
}

#[test]
fn the_file_is_written_atomically_and_reads_back() {
    let baked = bake(&meshes::terrain(8, 8, 1));
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("t.clod");
    std::fs::write(&path, b"old contents").expect("write");
    let n = baked.write(&path, &[]).expect("write");
    let bytes = std::fs::read(&path).expect("read");
    assert_eq!(bytes.len() as u64, n);
    let aligned = caveclod_tests::AlignedBytes::from_slice(&bytes);
    let h = caveclod_core::Hierarchy::from_bytes(&aligned).expect("valid");
    assert_eq!(h.polygon_count(), 128);
    assert_eq!(
        std::fs::read_dir(dir.path()).expect("dir").count(),
        1,
        "no temporary file left behind"
    );
    // A directory that does not exist: an error naming the path, nothing created.
    let bad = dir.path().join("missing").join("t.clod");
    let e = baked.write(&bad, &[]).expect_err("no such directory");
    assert!(e.to_string().contains("t.clod"), "{e}");
}
