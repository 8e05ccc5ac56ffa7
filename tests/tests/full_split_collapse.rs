//! Full split reproduces the full-resolution mesh exactly; full collapse gives back exactly
//! the base mesh; on the three generated meshes.

use caveclod_core::{CameraState, NodeId, PolyId};
use caveclod_tests::check::{check_front, collapse_all, split_all};
use caveclod_tests::{bake, meshes, TestMesh};

fn round_trip(mesh: &TestMesh) {
    let baked = bake(mesh);
    let h = baked.hierarchy();
    let mut mem = vec![0u32; CameraState::words_needed(&h)];
    let mut cam = CameraState::new(&h, &mut mem).expect("memory sized by words_needed");
    check_front(&h, &cam).expect("base front");
    split_all(&h, &mut cam);
    check_front(&h, &cam).expect("full front");
    assert_eq!(cam.active_polygon_count() as usize, mesh.triangles.len());
    for (i, p) in h.polygons().iter().enumerate() {
        assert_eq!(
            cam.polygon_corners(&h, PolyId(i as u32)),
            Some(p.nodes),
            "polygon {i}"
        );
    }
    // Per surface, as position triples: the emitted mesh is the input mesh.
    let mut want: Vec<(u16, [[u32; 3]; 3])> = mesh
        .triangles
        .iter()
        .map(|t| {
            (
                t.surface,
                rotate_min(t.p.map(|p| mesh.positions[p as usize].map(f32::to_bits))),
            )
        })
        .collect();
    let mut got: Vec<(u16, [[u32; 3]; 3])> = cam
        .active_polygons(&h)
        .map(|f| {
            let c = cam.polygon_corners(&h, f).expect("active");
            (
                h.polygons()[f.index()].surface.0,
                rotate_min(c.map(|v| h.node_point(v).expect("node").map(f32::to_bits))),
            )
        })
        .collect();
    want.sort_unstable();
    got.sort_unstable();
    assert_eq!(got, want);
    let collapses = collapse_all(&h, &mut cam);
    assert_eq!(collapses, h.splits().len());
    check_front(&h, &cam).expect("collapsed front");
    assert_eq!(cam.split_count(), 0);
    for (i, b) in h.base().iter().enumerate() {
        assert_eq!(cam.polygon_corners(&h, PolyId(i as u32)), Some(b.corners));
    }
    let roots: Vec<NodeId> = cam
        .active_nodes()
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .collect();
    assert_eq!(roots, h.roots());
}

fn rotate_min(t: [[u32; 3]; 3]) -> [[u32; 3]; 3] {
    let r = [t, [t[1], t[2], t[0]], [t[2], t[0], t[1]]];
    r.into_iter().min().expect("three rotations")
}

#[test]
fn terrain_with_seam() {
    round_trip(&meshes::terrain(16, 12, 7));
}

#[test]
fn closed_sphere() {
    round_trip(&meshes::sphere(2));
}

#[test]
fn terrain_with_hole_and_borders() {
    round_trip(&meshes::holed_terrain(18, 18, 3));
}
