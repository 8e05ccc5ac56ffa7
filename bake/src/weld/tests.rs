use super::*;
use crate::mesh::{Mesh, Surface, Triangle, NO_ATTRIBUTE};
use caveclod_core::format::PositionClass;

/// A mesh of the given points and triangles, one surface, no attributes.
fn mesh(positions: &[[f32; 3]], triangles: &[[u32; 3]]) -> Mesh {
    Mesh {
        positions: positions.to_vec(),
        triangles: triangles
            .iter()
            .map(|&position| Triangle {
                position,
                normal: [NO_ATTRIBUTE; 3],
                uv: [NO_ATTRIBUTE; 3],
                color: [NO_ATTRIBUTE; 3],
                surface: 0,
            })
            .collect(),
        surfaces: vec![Surface::default()],
        ..Mesh::default()
    }
}

/// Every directed edge once, every edge at most twice, one fan around every position.
fn assert_manifold(w: &Welded) {
    let mut directed = std::collections::HashMap::new();
    for (f, t) in w.triangles.iter().enumerate() {
        for k in 0..3 {
            let e = (t.p[k], t.p[(k + 1) % 3]);
            assert!(directed.insert(e, f).is_none(), "edge {e:?} twice");
        }
    }
    for p in 0..w.positions.len() as u32 {
        let around: Vec<usize> = (0..w.triangles.len())
            .filter(|&f| w.triangles[f].p.contains(&p))
            .collect();
        let mut fan = vec![around[0]];
        let mut i = 0;
        while i < fan.len() {
            let t = w.triangles[fan[i]].p;
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if a == p || b == p {
                    if let Some(&o) = directed.get(&(b, a)) {
                        if !fan.contains(&o) {
                            fan.push(o);
                        }
                    }
                }
            }
            i += 1;
        }
        assert_eq!(fan.len(), around.len(), "position {p} has several fans");
    }
}

#[test]
fn welds_points_and_drops_degenerate_and_duplicate_triangles() {
    let points = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 0.0, 0.0], // the same point as 1
        [2.0, 0.0, 0.0], // on the line through 0 and 1
    ];
    let w = weld(&mesh(
        &points,
        &[
            [0, 1, 2],
            [0, 3, 2],
            [2, 1, 0],
            [0, 0, 2],
            [0, 1, 4],
            [1, 3, 2],
        ],
    ))
    .expect("weld");
    assert_eq!(w.positions.len(), 4);
    assert_eq!(w.triangles.len(), 1);
    assert_eq!(
        w.repairs,
        Repairs {
            welded_positions: 1,
            // [0, 0, 2], [0, 1, 4] (zero area) and [1, 3, 2] (1 and 3 are one point)
            degenerate_triangles: 3,
            // [0, 3, 2] is [0, 1, 2]; [2, 1, 0] is it turned over
            duplicate_triangles: 2,
            computed_normals: 3,
            ..Repairs::default()
        }
    );
    assert_eq!(w.triangles[0].p, [0, 1, 2]);
    // A lone triangle: every position on two border edges; the unused point is kept.
    use PositionClass::{Free, Sharp};
    assert_eq!(w.classes, vec![Sharp, Sharp, Sharp, Free]);
}

#[test]
fn a_duplicate_is_found_whichever_corner_it_starts_at() {
    let points = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.5],
        [0.5, -1.0, 0.25],
    ];
    let w = weld(&mesh(
        &points,
        &[
            [0, 1, 2],
            [0, 2, 3],
            [2, 1, 0], // [0, 1, 2] turned over
            [3, 0, 2], // [0, 2, 3] rotated
            [1, 4, 2],
            [2, 1, 4], // [1, 4, 2] rotated
            [4, 1, 2], // [1, 4, 2] turned over
        ],
    ))
    .expect("weld");
    let kept: Vec<[u32; 3]> = w.triangles.iter().map(|t| t.p).collect();
    assert_eq!(kept, vec![[0, 1, 2], [0, 2, 3], [1, 4, 2]]);
    assert_eq!(w.repairs.duplicate_triangles, 4);
}

#[test]
fn nothing_left_is_an_error() {
    let e = weld(&mesh(&[[0.0; 3], [1.0, 0.0, 0.0]], &[[0, 1, 1]])).expect_err("empty");
    assert_eq!(
        e,
        WeldError::Empty {
            degenerate: 1,
            duplicate: 0
        }
    );
}

#[test]
fn an_edge_of_three_triangles_is_cut() {
    // Three fins on the edge 0–1; the third runs the edge the same way as the first.
    let points = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.5, 1.0, 0.0],
        [0.5, -1.0, 0.0],
        [0.5, 0.0, 1.0],
    ];
    let w = weld(&mesh(&points, &[[0, 1, 2], [1, 0, 3], [0, 1, 4]])).expect("weld");
    assert_eq!(w.repairs.non_manifold_edges, 1);
    assert_eq!(w.positions.len(), 7, "the third fin gets its own 0 and 1");
    assert_eq!(w.triangles[2].p, [5, 6, 4]);
    assert_eq!(w.positions[5], points[0]);
    assert_eq!(w.positions[6], points[1]);
    assert_manifold(&w);
}

#[test]
fn a_bowtie_vertex_is_split() {
    let points = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 0.0, 0.0],
        [-1.0, -1.0, 0.0],
    ];
    let w = weld(&mesh(&points, &[[0, 1, 2], [0, 3, 4]])).expect("weld");
    assert_eq!(w.repairs.non_manifold_vertices, 1);
    assert_eq!(w.positions.len(), 6);
    assert_eq!(w.triangles[0].p, [0, 1, 2]);
    assert_eq!(w.triangles[1].p, [5, 3, 4]);
    assert_manifold(&w);
}

#[test]
fn a_uv_seam_makes_two_groups_and_classes_follow_boundaries() {
    // A quad of two triangles; the second has other UVs along the diagonal 0–2.
    let points = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    let mut m = mesh(&points, &[[0, 1, 2], [0, 2, 3]]);
    m.uvs = vec![[0.0, 0.0], [0.5, 0.5]];
    m.triangles[0].uv = [0, 0, 0];
    m.triangles[1].uv = [1, 1, 1];
    let w = weld(&m).expect("weld");
    assert_eq!(w.group_count, 2);
    assert_ne!(w.triangles[0].group, w.triangles[1].group);
    assert_eq!(w.group_id_count, 2, "the groups share positions");
    use PositionClass::{Rigid, Sharp};
    assert_eq!(w.classes, vec![Rigid, Sharp, Rigid, Sharp]);
    assert_eq!(w.vertices[0].len(), 2);
    assert_eq!(w.vertices[1].len(), 1);
    // Each corner's attributes are its position's vertex of its triangle's group.
    for (t, &uv) in w.triangles.iter().zip(&m.uvs) {
        let a = w.corner_attributes(t);
        assert!(a.iter().all(|&a| w.attributes[a as usize].uv == uv));
    }
    // The same UVs everywhere: one group, the diagonal no boundary.
    m.triangles[1].uv = [0, 0, 0];
    let w = weld(&m).expect("weld");
    assert_eq!(w.group_count, 1);
    assert_eq!(w.classes, vec![Sharp; 4]);
    assert_eq!(w.attributes.len(), 1);
}

#[test]
fn a_closed_mesh_is_free_and_groups_that_share_no_position_share_an_id() {
    // Two tetrahedra apart, of two surfaces.
    let mut points = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    points.extend(points.clone().iter().map(|p| [p[0] + 5.0, p[1], p[2]]));
    let tet = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]];
    let tris: Vec<[u32; 3]> = tet
        .iter()
        .chain(&tet.map(|t| t.map(|x| x + 4)))
        .copied()
        .collect();
    let mut m = mesh(&points, &tris);
    m.surfaces.push(Surface::default());
    for t in &mut m.triangles[4..] {
        t.surface = 1;
    }
    let w = weld(&m).expect("weld");
    assert_eq!(w.classes, vec![PositionClass::Free; 8]);
    assert_eq!(w.group_count, 2);
    assert_eq!(w.group_id_count, 1);
    assert_eq!(w.surface_count, 2);
    let surfaces: Vec<u16> = w.triangles.iter().map(|t| w.surface_of(t)).collect();
    assert_eq!(
        surfaces,
        [0, 0, 0, 0, 1, 1, 1, 1],
        "each triangle its group's surface"
    );
    assert_eq!(w.repairs.computed_normals, 24);
    assert_manifold(&w);
}

#[test]
fn normals_that_follow_from_the_geometry_are_marked() {
    // A pyramid's four sides: each apex corner's area-weighted normal is straight up.
    let points = [
        [0.0, 0.0, 0.0],
        [2.0, 0.0, 0.0],
        [2.0, 0.0, 2.0],
        [0.0, 0.0, 2.0],
        [1.0, 0.5, 1.0],
    ];
    let tris = [[0, 4, 1], [1, 4, 2], [2, 4, 3], [3, 4, 0]];
    let m = mesh(&points, &tris);
    let w = weld(&m).expect("weld");
    assert!(w.attributes.iter().all(|a| a.normal_from_geometry));

    // Given normals: up at the apex (its geometric normal) and 45° off at the base
    // corners (whose geometric normals lean outwards by less than that).
    let mut m = mesh(&points, &tris);
    let s = std::f32::consts::FRAC_1_SQRT_2;
    m.normals = vec![[0.0, 1.0, 0.0], [s, s, 0.0]];
    for t in &mut m.triangles {
        t.normal = t.position.map(|p| if p == 4 { 0 } else { 1 });
    }
    let w = weld(&m).expect("weld");
    let apex = w.vertices[4][0].1 as usize;
    assert!(w.attributes[apex].normal_from_geometry);
    let flagged = |p: usize| w.attributes[w.vertices[p][0].1 as usize].normal_from_geometry;
    assert!((0..4).all(|p| !flagged(p)));
    assert_eq!(w.repairs.computed_normals, 0);
}
