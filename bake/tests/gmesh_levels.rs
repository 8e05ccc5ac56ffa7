//! g-mesh levels built from baked hierarchies: levels shrink, each level morphed to its end
//! (`a'_i`) draws exactly the next level's triangles (C0 continuity of the geomorph), the
//! sections round-trip through a `.clod` file, and corrupt sections are refused.

use caveclod_bake::gmesh::{build, GMeshData, GMeshOptions};
use caveclod_core::gmesh::{gmesh_tags, GMesh, GMeshFormatError};
use caveclod_core::Hierarchy;
use caveclod_tests::{bake, meshes, AlignedBytes, TestMesh};

fn levels_of(t: &TestMesh) -> (AlignedBytes, GMeshData) {
    let baked = bake(t);
    let h = baked.hierarchy();
    let g = build(&h, &GMeshOptions::default()).expect("g-mesh levels");
    let bytes = AlignedBytes::from_slice(&baked.0.to_bytes(&g.sections()).expect("bytes"));
    (bytes, g)
}

/// The non-degenerate triangles of `level` with `side` (0: from, 1: to) attributes, as sorted
/// (surface, rotated position triple) keys.
fn triangles(
    h: &Hierarchy<'_>,
    g: &GMesh<'_>,
    level: usize,
    side: usize,
) -> Vec<(usize, [[u32; 3]; 3])> {
    let l = g.level(level).expect("level");
    let mut out = Vec::new();
    for s in 0..g.surfaces() {
        for tri in l.surface_indices(s).chunks_exact(3) {
            let p = [0, 1, 2].map(|k| {
                let v = l.vertices[tri[k] as usize][side];
                h.vertices()[v as usize].position.map(f32::to_bits)
            });
            if p[0] == p[1] || p[1] == p[2] || p[0] == p[2] {
                continue;
            }
            let rots = [[p[0], p[1], p[2]], [p[1], p[2], p[0]], [p[2], p[0], p[1]]];
            out.push((s, rots.into_iter().min().expect("three")));
        }
    }
    out.sort_unstable();
    out
}

fn check(t: &TestMesh) {
    let (bytes, data) = levels_of(t);
    let h = Hierarchy::from_bytes(&bytes).expect("valid file");
    let g = GMesh::from_hierarchy(&h)
        .expect("valid g-mesh")
        .expect("g-mesh sections present");
    assert_eq!(g.parts().level_polygons, &data.level_polygons[..]);
    let n = g.levels();
    eprintln!(
        "levels {:?}, volumes {:?}, boundaries {:?}",
        g.level_polygons(),
        g.volumes(),
        g.partitions().boundaries()
    );
    assert!(n >= 3, "only {n} levels");
    assert_eq!(g.level_polygons()[0] as usize, t.triangles.len());
    assert!(
        g.level_polygons().windows(2).all(|w| w[1] < w[0]),
        "{:?}",
        g.level_polygons()
    );
    // Batches remove a large share each time (the paper's roughly halving).
    let first = f64::from(g.level_polygons()[1]) / f64::from(g.level_polygons()[0]);
    assert!(first < 0.8, "first batch kept {first:.2} of the polygons");
    assert_eq!(g.volumes()[0], 1.0);
    for i in 0..n - 1 {
        assert_eq!(
            triangles(&h, &g, i, 1),
            triangles(&h, &g, i + 1, 0),
            "level {i} morphed to its end differs from level {}",
            i + 1
        );
    }
}

#[test]
fn terrain_levels_morph_continuously() {
    check(&meshes::terrain(40, 30, 3));
}

#[test]
fn closed_sphere_levels_morph_continuously() {
    check(&meshes::sphere(4));
}

#[test]
fn terrain_with_hole_levels_morph_continuously() {
    check(&meshes::holed_terrain(30, 30, 5));
}

#[test]
fn corrupt_sections_are_refused() {
    let (_, data) = levels_of(&meshes::terrain(12, 12, 1));
    let baked = bake(&meshes::terrain(12, 12, 1));
    let h = baked.hierarchy();
    let nv = h.vertices().len();
    let surfaces = h.surface_count();
    GMesh::new(data.parts(), nv, surfaces).expect("valid as built");

    let mut bad = data.clone();
    bad.indices[5] = 1_000_000;
    assert!(matches!(
        GMesh::new(bad.parts(), nv, surfaces),
        Err(GMeshFormatError::IndexOutOfRange { index: 5, .. })
    ));
    let mut bad = data.clone();
    bad.vertices[3][1] = nv as u32;
    assert!(matches!(
        GMesh::new(bad.parts(), nv, surfaces),
        Err(GMeshFormatError::VertexOutOfRange { index: 3, .. })
    ));
    let mut bad = data.clone();
    bad.level_polygons[1] += 1;
    assert!(matches!(
        GMesh::new(bad.parts(), nv, surfaces),
        Err(GMeshFormatError::PolygonCount { level: 1 })
    ));
    let mut bad = data.clone();
    bad.boundaries[1] = f32::NAN;
    assert!(matches!(
        GMesh::new(bad.parts(), nv, surfaces),
        Err(GMeshFormatError::Levels(_))
    ));
    let mut bad = data.clone();
    let last = bad.vertex_offsets.len() - 1;
    bad.vertex_offsets[last] -= 1;
    assert!(matches!(
        GMesh::new(bad.parts(), nv, surfaces),
        Err(GMeshFormatError::BadOffsets { .. })
    ));
    // A file with only some of the sections.
    let sections = data.sections();
    let partial: Vec<_> = sections
        .iter()
        .copied()
        .filter(|s| s.tag != gmesh_tags::INDICES)
        .collect();
    let bytes = AlignedBytes::from_slice(&baked.0.to_bytes(&partial).expect("bytes"));
    let h2 = Hierarchy::from_bytes(&bytes).expect("the hierarchy itself is fine");
    assert!(matches!(
        GMesh::from_hierarchy(&h2),
        Err(GMeshFormatError::MissingSection(t)) if t == gmesh_tags::INDICES
    ));
    // And none: no g-mesh.
    let bytes = AlignedBytes::from_slice(&baked.0.to_bytes(&[]).expect("bytes"));
    let h3 = Hierarchy::from_bytes(&bytes).expect("valid");
    assert!(GMesh::from_hierarchy(&h3).expect("no error").is_none());
}
