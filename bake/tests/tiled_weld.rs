//! The tiled weld against the in-core one: the same welded mesh up to numbering, from a mesh
//! in memory cut into tiles ([`MeshTiles`]) and from a PLY file streamed into tiles on disk
//! ([`StreamTiles`]), on generated terrains, a PLY with quads and seams, and the shared real
//! data (each test skips with a note when its file is absent).

use std::collections::HashMap;
use std::io::Write;
use std::path::Path;

use caveclod_bake::import::{self, ImportOptions};
use caveclod_bake::ooc::temp::TempSpace;
use caveclod_bake::weld::tiled::{weld_tiled, MeshTiles, StreamTiles};
use caveclod_bake::weld::{weld, Welded};
use caveclod_core::format::PositionClass;
use caveclod_tests::generate::{write_terrain, TerrainGrid};
use caveclod_tests::shared_data;

mod tiled_support;
use tiled_support::{assert_same, matched_triangles};

/// Checks `w` keeps the weld's invariants: every directed edge once, one fan around every
/// position, each corner's attribute set its group's one vertex at its position, the
/// classes counted from the mesh borders and group changes, groups meeting at a position
/// with different ids.
fn assert_invariants(w: &Welded) {
    let mut by_edge = HashMap::new();
    for (f, t) in w.triangles.iter().enumerate() {
        for k in 0..3 {
            let e = (t.p[k], t.p[(k + 1) % 3]);
            assert!(by_edge.insert(e, f).is_none(), "edge {e:?} twice");
        }
    }
    // Fans: corners joined across the edges through their position.
    let mut parent: Vec<usize> = (0..3 * w.triangles.len()).collect();
    fn find(parent: &mut [usize], mut x: usize) -> usize {
        while parent[x] != x {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        x
    }
    let mut boundary = vec![0u32; w.positions.len()];
    for (f, t) in w.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t.p[k], t.p[(k + 1) % 3]);
            match by_edge.get(&(b, a)) {
                Some(&o) => {
                    let u = w.triangles[o].p;
                    let at = |x: u32| 3 * o + u.iter().position(|&y| y == x).unwrap();
                    for (c, x) in [(3 * f + k, a), (3 * f + (k + 1) % 3, b)] {
                        let (r, s) = (find(&mut parent, c), find(&mut parent, at(x)));
                        parent[r] = s;
                    }
                    if f < o && w.triangles[o].group != t.group {
                        boundary[a as usize] += 1;
                        boundary[b as usize] += 1;
                    }
                }
                None => {
                    boundary[a as usize] += 1;
                    boundary[b as usize] += 1;
                }
            }
        }
    }
    let mut fan_of = vec![usize::MAX; w.positions.len()];
    let mut entries: Vec<Vec<(u32, u32)>> = vec![Vec::new(); w.positions.len()];
    for (f, t) in w.triangles.iter().enumerate() {
        for k in 0..3 {
            let x = t.p[k] as usize;
            let r = find(&mut parent, 3 * f + k);
            assert!(
                fan_of[x] == usize::MAX || fan_of[x] == r,
                "position {x} has two fans"
            );
            fan_of[x] = r;
            entries[x].push((t.group, w.corner_attributes(t)[k]));
        }
    }
    for (x, mut e) in entries.into_iter().enumerate() {
        e.sort_unstable();
        e.dedup();
        assert_eq!(e, w.vertices[x].to_vec(), "vertices at position {x}");
        let mut ids: Vec<u16> = e.iter().map(|&(g, _)| w.group_ids[g as usize]).collect();
        ids.dedup();
        assert_eq!(
            ids.len(),
            e.len(),
            "a group with two attribute sets, or two groups sharing an id, at {x}"
        );
        let class = match boundary[x] {
            0 => PositionClass::Free,
            2 => PositionClass::Sharp,
            _ => PositionClass::Rigid,
        };
        assert_eq!(w.classes[x], class, "class of position {x}");
    }
}

/// Checks that `b` has `a`'s triangles (by corner coordinates), each corner with the same
/// attribute set, and the same repairs: all but the groups, which a weld growing them in
/// another order may cut differently where a seam closes on itself.
fn assert_same_triangles(a: &Welded, b: &Welded) {
    assert_eq!(a.triangles.len(), b.triangles.len(), "triangles");
    assert_eq!(a.positions.len(), b.positions.len(), "positions");
    assert_eq!(a.repairs, b.repairs, "repairs");
    for (ta, tb) in matched_triangles(a, b) {
        assert_eq!(a.surface_of(ta), b.surface_of(tb));
        let (aa, ab) = (a.corner_attributes(ta), b.corner_attributes(tb));
        for k in 0..3 {
            let (x, y) = (&a.attributes[aa[k] as usize], &b.attributes[ab[k] as usize]);
            assert_eq!((x.normal, x.uv, x.color), (y.normal, y.uv, y.color));
        }
    }
}

/// The in-core import and weld of `path` against the streamed tiles' weld.
fn check_streamed(path: &Path, tile_triangles: usize, exact: bool) {
    let mesh = import::import(path, &ImportOptions::default()).expect("import");
    let reference = weld(&mesh).expect("weld");
    let temp = TempSpace::new(None, None).expect("temp");
    let name = path.display().to_string();
    let mut tiles = StreamTiles::open(path, &name, &temp, tile_triangles).expect("stream");
    let tiled = weld_tiled(&mut tiles).expect("tiled weld");
    compare(&reference, &tiled, exact);
}

/// `tiled` against the in-core weld `reference`: the same up to numbering when `exact` (the
/// in-core growth took no order-dependent choice: checked), else the same triangles and the
/// invariants.
fn compare(reference: &Welded, tiled: &Welded, exact: bool) {
    assert_invariants(tiled);
    assert_same_triangles(reference, tiled);
    if exact {
        assert_eq!(
            refused_edges(reference),
            0,
            "the in-core weld took order-dependent choices"
        );
        assert_same(reference, tiled);
    }
}

/// The in-core import and weld of `path` against its tiles' weld at each side of `sides`.
fn check_in_memory(path: &Path, sides: &[u32], exact: bool) {
    let mesh = import::import(path, &ImportOptions::default()).expect("import");
    let reference = weld(&mesh).expect("weld");
    for &side in sides {
        let mut tiles = MeshTiles::new(&mesh, side).expect("tiles");
        let tiled = weld_tiled(&mut tiles).expect("tiled weld");
        compare(&reference, &tiled, exact);
    }
}

#[test]
fn a_generated_terrain_streamed_in_tiles_welds_as_in_core() {
    let dir = tempfile::tempdir().expect("dir");
    let path = dir.path().join("terrain.ply");
    let mut f = std::io::BufWriter::new(std::fs::File::create(&path).expect("create"));
    let grid = TerrainGrid::for_triangles(20_000).expect("grid");
    write_terrain(&mut f, grid, &mut |_, _| {}).expect("write");
    f.flush().expect("flush");
    drop(f);
    for tile_triangles in [1_000_000, 5_000, 700] {
        check_streamed(&path, tile_triangles, true);
    }
}

#[test]
fn an_ascii_ply_with_quads_seams_and_repeated_vertices_welds_as_in_core() {
    // A 4 × 3 grid of quads whose column x = 2 is written twice, with two UVs: a seam; a
    // lone pentagon; a repeated quad; a face of two corners (skipped).
    let mut vertices = Vec::new();
    let mut faces = Vec::new();
    let mut id = HashMap::new();
    for y in 0..=3 {
        for x in 0..=4 {
            for side in 0..2 {
                if side == 1 && x != 2 {
                    continue;
                }
                id.insert((x, y, side), vertices.len());
                let h = ((x * 3 + y) % 4) as f32 * 0.5;
                let u = x as f32 * 0.25 + side as f32;
                vertices.push(format!("{x} {y} {h} {u} {}", y as f32 * 0.3));
            }
        }
    }
    for y in 0..3 {
        for x in 0..4 {
            let s = |xx: i32| usize::from(x >= 2 && xx == 2);
            let v = |xx: i32, yy: i32| id[&(xx, yy, s(xx))];
            faces.push(format!(
                "4 {} {} {} {}",
                v(x, y),
                v(x + 1, y),
                v(x + 1, y + 1),
                v(x, y + 1)
            ));
        }
    }
    faces.push(faces[5].clone());
    faces.push(format!("2 {} {}", id[&(0, 0, 0)], id[&(1, 0, 0)]));
    let n = vertices.len();
    for (k, (x, y)) in [(6.0, 0.0), (7.0, 0.5), (6.8, 1.5), (5.8, 1.7), (5.5, 0.8)]
        .iter()
        .enumerate()
    {
        vertices.push(format!("{x} {y} {} 0 0", k as f32 * 0.1));
    }
    faces.push(format!("5 {} {} {} {} {}", n, n + 1, n + 2, n + 3, n + 4));
    let text = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\n\
         property float z\nproperty float u\nproperty float v\nelement face {}\n\
         property list uchar int vertex_indices\nend_header\n{}\n{}\n",
        vertices.len(),
        faces.len(),
        vertices.join("\n"),
        faces.join("\n")
    );
    let dir = tempfile::tempdir().expect("dir");
    let path = dir.path().join("quads.ply");
    std::fs::write(&path, text).expect("write");
    for tile_triangles in [1000, 8, 3] {
        check_streamed(&path, tile_triangles, true);
    }
}

#[test]
fn lucy_streamed_in_tiles_welds_as_in_core() {
    let Some(path) = shared_data::file("scans/lucy.ply") else {
        return;
    };
    check_streamed(&path, 10_000, true);
}

#[test]
fn spot_in_tiles_welds_as_in_core() {
    let Some(path) = shared_data::file("spot/spot_triangulated.obj") else {
        return;
    };
    check_in_memory(&path, &[2, 4, 8], true);
}

#[test]
fn flight_helmet_in_tiles_keeps_the_welds_invariants() {
    // Its UV seams close on themselves: where the in-core growth refuses a matching
    // triangle, the groups depend on the order they grow in.
    let Some(path) = shared_data::file("FlightHelmet/FlightHelmet.gltf") else {
        return;
    };
    check_in_memory(&path, &[2, 8], false);
}

#[test]
#[cfg_attr(debug_assertions, ignore = "slow in a debug build")]
fn st_helens_in_tiles_welds_as_in_core() {
    let Some(path) = shared_data::file("terrain/SainteHelens.dem") else {
        return;
    };
    check_in_memory(&path, &[4, 16], true);
}

/// Edges across which the in-core growth refused a matching triangle (a seam closing on
/// itself): there the groups depend on the order the weld grows them in.
fn refused_edges(w: &Welded) -> usize {
    let mut by_edge = HashMap::new();
    for (f, t) in w.triangles.iter().enumerate() {
        for k in 0..3 {
            by_edge.insert((t.p[k], t.p[(k + 1) % 3]), (f, k));
        }
    }
    let mut n = 0;
    for (f, t) in w.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t.p[k], t.p[(k + 1) % 3]);
            if let Some(&(o, j)) = by_edge.get(&(b, a)) {
                let u = &w.triangles[o];
                let (ua, ta) = (w.corner_attributes(u), w.corner_attributes(t));
                let matching = w.surface_of(u) == w.surface_of(t)
                    && ua[(j + 1) % 3] == ta[k]
                    && ua[j] == ta[(k + 1) % 3];
                if f < o && matching && u.group != t.group {
                    n += 1;
                }
            }
        }
    }
    n
}

/// A PLY with what only the in-core importer reads is imported in core; a bad index is an
/// error naming the file and the face.
#[test]
fn ply_files_the_stream_does_not_read_are_welded_in_core_and_bad_ones_named() {
    use caveclod_bake::pipeline::{import_and_weld, WeldedMesh, TILE_TRIANGLES};
    use caveclod_bake::weld::tiled::WeldedBuilder;
    let dir = tempfile::tempdir().expect("dir");
    let header = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
                  property float z\n";
    let vertices = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n";
    let strips = dir.path().join("strips.ply");
    std::fs::write(
        &strips,
        format!(
            "{header}element face 1\nproperty list uchar int vertex_indices\n\
             element tristrips 1\nproperty list int int vertex_indices\nend_header\n\
             {vertices}3 0 1 2\n4 0 1 3 2\n"
        ),
    )
    .expect("write");
    let mut sink = WeldedBuilder::default();
    let file = import_and_weld(
        &strips,
        &ImportOptions::default(),
        TILE_TRIANGLES,
        &mut sink,
        &mut |_| {},
    )
    .expect("in core");
    match file.welded {
        // The face and the strip's two triangles.
        WeldedMesh::InCore(w) => assert_eq!(w.triangles.len(), 3),
        WeldedMesh::Streamed(_) => panic!("a PLY with strips was streamed"),
    }
    let quads = dir.path().join("quads.ply");
    std::fs::write(
        &quads,
        format!(
            "{header}element face 1\nproperty list uchar int vertex_indices\nend_header\n\
             {vertices}4 0 1 2 3\n"
        ),
    )
    .expect("write");
    let mut sink = WeldedBuilder::default();
    let file = import_and_weld(
        &quads,
        &ImportOptions::default(),
        TILE_TRIANGLES,
        &mut sink,
        &mut |_| {},
    )
    .expect("streamed");
    match file.welded {
        WeldedMesh::Streamed(s) => assert_eq!(sink.finish(s).triangles.len(), 2),
        WeldedMesh::InCore(_) => panic!("a plain PLY was imported in core"),
    }
    let bad = dir.path().join("bad.ply");
    std::fs::write(
        &bad,
        format!(
            "{header}element face 2\nproperty list uchar int vertex_indices\nend_header\n\
             {vertices}3 0 1 2\n3 0 2 7\n"
        ),
    )
    .expect("write");
    let mut sink = WeldedBuilder::default();
    let e = import_and_weld(
        &bad,
        &ImportOptions::default(),
        TILE_TRIANGLES,
        &mut sink,
        &mut |_| {},
    )
    .expect_err("bad index")
    .to_string();
    assert!(
        e.contains("bad.ply") && e.contains("face 1") && e.contains('7'),
        "{e}"
    );
}
