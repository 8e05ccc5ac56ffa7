//! Out-of-core simplification: the quadric optimum on a hand-computable case, materials and
//! UV seams on FlightHelmet, streaming readers against the in-core importers, the hand-off to
//! the hierarchy, and bad input (truncated files, a budget too small, a full temporary disk)
//! with the temporary files gone afterwards. The 20-million-triangle bake is `#[ignore]`d
//! (run it in release: `cargo test --release -p caveclod-bake --test ooc -- --ignored`).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use caveclod_bake::import;
use caveclod_bake::mesh::{Mesh, Surface, Triangle, NO_ATTRIBUTE};
use caveclod_bake::ooc::{
    self, cluster_mesh, cluster_mesh_in, ClusterOptions, Cube, OocError, OocOptions,
};
use caveclod_bake::pipeline;
use caveclod_tests::generate;
use caveclod_tests::shared_data;

fn no_progress(_: ooc::OocStage) {}

/// A square pyramid (apex (0, 0, 1), base corners (±1, ±1, 0)) whose sides are cut at a
/// tenth of the way down: flat-shaded faces, UV = (x + 2z, y), one surface.
fn pyramid() -> Mesh {
    let apex = [0.0f32, 0.0, 1.0];
    let base = [
        [1.0f32, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
        [-1.0, -1.0, 0.0],
        [1.0, -1.0, 0.0],
    ];
    let mut m = Mesh {
        surfaces: vec![Surface::plain("stone")],
        ..Default::default()
    };
    let corner = |m: &mut Mesh, p: [f32; 3]| {
        m.positions.push(p);
        m.uvs.push([p[0] + 2.0 * p[2], p[1]]);
        (m.positions.len() - 1) as u32
    };
    for i in 0..4 {
        let (b0, b1) = (base[i], base[(i + 1) % 4]);
        let mid = |b: [f32; 3]| [0, 1, 2].map(|k| apex[k] + 0.1 * (b[k] - apex[k]));
        let (m0, m1) = (mid(b0), mid(b1));
        // Face normal: outward, (e1 × e2) of (apex, b0, b1).
        let e1 = [0, 1, 2].map(|k| b0[k] - apex[k]);
        let e2 = [0, 1, 2].map(|k| b1[k] - apex[k]);
        let n = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ];
        let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        m.normals.push(n.map(|c| c / l));
        let ni = (m.normals.len() - 1) as u32;
        for tri in [[apex, m0, m1], [m0, b0, b1], [m0, b1, m1]] {
            let idx = tri.map(|p| corner(&mut m, p));
            m.triangles.push(Triangle {
                position: idx,
                normal: [ni; 3],
                uv: idx,
                color: [NO_ATTRIBUTE; 3],
                surface: 0,
            });
        }
    }
    m
}

#[test]
fn a_cluster_is_at_the_quadric_optimum_not_the_mean() {
    let mesh = pyramid();
    // Cells of 1/4: the apex and the cut points (±0.1, ±0.1, 0.9) share the cell
    // x, y in [-0.125, 0.125), z in [0.875, 1.125); the base corners are elsewhere.
    let cube = Cube {
        origin: [-1.125, -1.125, -0.125],
        size: 2.0,
    };
    let options = ClusterOptions {
        record_corners: true,
        ..ClusterOptions::at_level(3)
    };
    let (out, c) = cluster_mesh_in(&mesh, cube, options);
    // The apex's cluster: the cluster of corner 0 (the apex of the first triangle).
    let k = c.corner_clusters()[0] as usize;
    // Every apex and cut-point corner is in it (one surface, no UV seam).
    let apex_cell: Vec<usize> = (0..mesh.triangles.len() * 3)
        .filter(|&i| {
            let p = mesh.positions[mesh.triangles[i / 3].position[i % 3] as usize];
            p[2] > 0.8
        })
        .collect();
    assert!(apex_cell
        .iter()
        .all(|&i| c.corner_clusters()[i] as usize == k));
    // Its position index is its cell's; find the output triangle corner that uses it.
    let t = out
        .triangles
        .iter()
        .find_map(|t| {
            (0..3)
                .find(|&j| t.normal[j] as usize == k)
                .map(|j| t.position[j])
        })
        .expect("the apex cluster is in an output triangle");
    let p = out.positions[t as usize];
    // The four face planes meet at the apex: the optimum is (0, 0, 1) exactly, where the
    // mean of the cluster's corners is lower (z = 0.9 for the cut points).
    for (a, e) in p.iter().zip([0.0, 0.0, 1.0]) {
        assert!((a - e).abs() < 1e-3, "position {p:?}");
    }
    // The normal: the area-weighted mean of the four equal faces' normals, normalised: +z.
    let n = out.normals[k];
    for (a, e) in n.iter().zip([0.0, 0.0, 1.0]) {
        assert!((a - e).abs() < 1e-3, "normal {n:?}");
    }
    // UV is linear in position on every face, so the optimum is its value at the apex,
    // (0 + 2 * 1, 0) = (2, 0); the mean of the corners' UVs would be (1.86, 0).
    let uv = out.uvs[k];
    assert!(
        (uv[0] - 2.0).abs() < 1e-3 && uv[1].abs() < 1e-3,
        "uv {uv:?}"
    );
    let mean_u: f32 = apex_cell
        .iter()
        .map(|&i| mesh.uvs[mesh.triangles[i / 3].uv[i % 3] as usize][0])
        .sum::<f32>()
        / apex_cell.len() as f32;
    assert!(
        (mean_u - 2.0).abs() > 0.1,
        "the test tells the optimum from the mean"
    );
}

#[test]
fn flight_helmet_clusters_keep_materials_apart_and_uv_seams_open() {
    let Some(path) = shared_data::file("FlightHelmet/FlightHelmet.gltf") else {
        return;
    };
    let mesh = import::import(&path, &Default::default()).unwrap();
    assert!(mesh.surfaces.len() > 1);
    for level in [5, 6, 7, 8, 10] {
        let options = ClusterOptions {
            record_corners: true,
            ..ClusterOptions::at_level(level)
        };
        let (out, c) = cluster_mesh(&mesh, options);
        out.validate().unwrap();
        let cc = c.corner_clusters();
        // No cluster takes corners of two materials.
        let mut surface_of: HashMap<u32, u16> = HashMap::new();
        for (i, &k) in cc.iter().enumerate() {
            let s = mesh.triangles[i / 3].surface;
            assert_eq!(
                *surface_of.entry(k).or_insert(s),
                s,
                "level {level}: cluster {k}"
            );
        }
        for t in &out.triangles {
            for k in t.uv {
                if k != NO_ATTRIBUTE {
                    assert_eq!(surface_of[&k], t.surface);
                }
            }
        }
        // UV seams stay seams: corners at one point of one material whose UVs differ by more
        // than 0.1 land in different clusters, with different UVs.
        let mut at_point: HashMap<([u32; 3], u16), Vec<usize>> = HashMap::new();
        for i in 0..cc.len() {
            let t = &mesh.triangles[i / 3];
            if t.uv[0] == NO_ATTRIBUTE {
                continue;
            }
            let p = mesh.positions[t.position[i % 3] as usize].map(f32::to_bits);
            at_point.entry((p, t.surface)).or_default().push(i);
        }
        let uv = |i: usize| mesh.uvs[mesh.triangles[i / 3].uv[i % 3] as usize];
        let (mut seams, mut merged, mut closed) = (0, 0, 0);
        for corners in at_point.values() {
            for (a, &i) in corners.iter().enumerate() {
                for &j in &corners[a + 1..] {
                    let (u, v) = (uv(i), uv(j));
                    if (u[0] - v[0]).abs().max((u[1] - v[1]).abs()) > 0.1 {
                        seams += 1;
                        let (ki, kj) = (cc[i] as usize, cc[j] as usize);
                        if ki == kj {
                            merged += 1;
                            continue;
                        }
                        let (ou, ov) = (out.uvs[ki], out.uvs[kj]);
                        if (ou[0] - ov[0]).abs().max((ou[1] - ov[1]).abs()) <= 0.02 {
                            closed += 1;
                        }
                    }
                }
            }
        }
        assert!(
            seams > 100,
            "FlightHelmet has UV seams ({seams} pairs found)"
        );
        // Sides of a seam keep their own UVs wherever they are apart.
        assert_eq!(closed, 0, "level {level}");
        // From 128 cells across on, no seam corners share a cluster; coarser, where a cell
        // spans a good part of a chart and the UV map is far from affine across it, fewer
        // than one in a thousand.
        if level >= 7 {
            assert_eq!(merged, 0, "level {level}");
        } else {
            assert!(
                merged * 1000 < seams,
                "level {level}: {merged} of {seams} merged"
            );
        }
        eprintln!(
            "level {level}: {} -> {} triangles, {} clusters, {seams} seam pairs, {merged} merged, {closed} closed",
            mesh.triangles.len(),
            out.triangles.len(),
            c.cluster_count()
        );
    }
}

/// A small generated terrain in `dir`.
fn terrain(dir: &Path, triangles: u64) -> PathBuf {
    let path = dir.join("terrain.ply");
    generate::terrain(&path, triangles, &mut |_, _| {}).unwrap();
    path
}

/// Empty directory check: nothing left in the temporary parent.
fn assert_empty(dir: &Path) {
    let left: Vec<_> = std::fs::read_dir(dir).unwrap().collect();
    assert!(left.is_empty(), "temporary files left: {left:?}");
}

fn options(temp: &Path, budget: u64) -> OocOptions {
    OocOptions {
        temp_dir: Some(temp.to_path_buf()),
        leaf_triangles: 1 << 10,
        ..OocOptions::with_budget(budget)
    }
}

#[test]
fn a_small_terrain_bakes_out_of_core_within_its_target_and_leaves_no_files() {
    let dir = tempfile::tempdir().unwrap();
    let temp = tempfile::tempdir().unwrap();
    let input = terrain(dir.path(), 60_000);
    // A budget whose sort chunk holds about a quarter of the input's keys: several runs to
    // merge.
    let o = OocOptions {
        target_triangles: Some(4000),
        ..options(temp.path(), 1 << 20)
    };
    let pipeline::OutOfCoreBake {
        baked, info, stats, ..
    } = pipeline::bake_out_of_core(&input, &o, &mut no_progress, &mut |_| {}).unwrap();
    assert_empty(temp.path());
    assert!(stats.runs > 1, "{stats:?}");
    assert!(stats.octree_leaves > 10, "{stats:?}");
    let grid = generate::TerrainGrid::for_triangles(60_000).unwrap();
    assert_eq!(info.input_triangles, grid.triangles());
    assert!(
        stats.output_triangles <= 2 * 4000 && stats.output_triangles > 4000 / 4,
        "{stats:?}"
    );
    let h = baked.hierarchy().unwrap();
    assert!(h.meta().polygon_count as u64 >= stats.output_triangles / 2);
    // The clustered terrain keeps its extent and its attributes.
    let (mesh, _) = ooc::simplify_file(&input, &o, &mut no_progress).unwrap();
    mesh.validate().unwrap();
    assert_eq!(mesh.normals.len(), mesh.uvs.len());
    assert!(!mesh.colors.is_empty());
    let xs = mesh.positions.iter().map(|p| p[0]);
    let (lo, hi) = xs.fold((f32::MAX, f32::MIN), |(a, b), x| (a.min(x), b.max(x)));
    assert!(lo < 0.05 * generate::TERRAIN_SIZE && hi > 0.95 * generate::TERRAIN_SIZE);
    for n in &mesh.normals {
        assert!(n[1] > 0.3, "terrain normals point up: {n:?}");
    }
    assert_empty(temp.path());
}

/// The same small mesh as binary PLY, ascii PLY and OBJ.
fn write_formats(dir: &Path) -> (Mesh, [PathBuf; 3]) {
    let bin = terrain(dir, 2000);
    let mesh = import::import(&bin, &Default::default()).unwrap();
    let mut ascii = String::from("ply\nformat ascii 1.0\nelement vertex ");
    ascii += &format!(
        "{}\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\n\
         property float ny\nproperty float nz\nproperty float u\nproperty float v\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        mesh.positions.len(),
        mesh.triangles.len()
    );
    let mut obj = String::new();
    for i in 0..mesh.positions.len() {
        let (p, n, uv) = (mesh.positions[i], mesh.normals[i], mesh.uvs[i]);
        ascii += &format!(
            "{} {} {} {} {} {} {} {}\n",
            p[0],
            p[1],
            p[2],
            n[0],
            n[1],
            n[2],
            uv[0],
            1.0 - uv[1]
        );
        obj += &format!(
            "v {} {} {}\nvt {} {}\nvn {} {} {}\n",
            p[0],
            p[1],
            p[2],
            uv[0],
            1.0 - uv[1],
            n[0],
            n[1],
            n[2]
        );
    }
    obj += "usemtl ground\n";
    for t in &mesh.triangles {
        let i = t.position.map(|i| i + 1);
        ascii += &format!("3 {} {} {}\n", i[0] - 1, i[1] - 1, i[2] - 1);
        obj += &format!("f {0}/{0}/{0} {1}/{1}/{1} {2}/{2}/{2}\n", i[0], i[1], i[2]);
    }
    let (a, o) = (dir.join("a.ply"), dir.join("m.obj"));
    std::fs::write(&a, ascii).unwrap();
    std::fs::write(&o, obj).unwrap();
    (mesh, [bin, a, o])
}

#[test]
fn streaming_readers_agree_with_the_in_core_importers() {
    let dir = tempfile::tempdir().unwrap();
    let temp = tempfile::tempdir().unwrap();
    let (mesh, files) = write_formats(dir.path());
    // At the finest resolution nothing merges: every format gives the input's triangles.
    let o = OocOptions {
        target_triangles: Some(1 << 20),
        ..options(temp.path(), 4 << 20)
    };
    let mut results = Vec::new();
    for f in &files {
        let (m, stats) = ooc::simplify_file(f, &o, &mut no_progress).unwrap();
        assert_eq!(stats.input_triangles, mesh.triangles.len() as u64, "{f:?}");
        assert_eq!(m.triangles.len(), mesh.triangles.len(), "{f:?}");
        // Every output position is an input position (a cluster of one vertex sits at its
        // vertex), up to the solve's rounding.
        assert_eq!(m.positions.len(), mesh.positions.len(), "{f:?}");
        for p in &m.positions {
            let d = mesh
                .positions
                .iter()
                .map(|q| (0..3).map(|k| (p[k] - q[k]).abs()).fold(0.0, f32::max))
                .fold(f32::MAX, f32::min);
            assert!(
                d < 1e-3,
                "{f:?}: {p:?} is {d} from the nearest input position"
            );
        }
        results.push((m.triangles.len(), m.uvs.len(), m.normals.len()));
        assert_empty(temp.path());
    }
    assert_eq!(results[0], results[1], "binary and ascii PLY");
    assert_eq!(results[0], results[2], "PLY and OBJ");
}

fn expect_error(input: &Path, o: &OocOptions, what: &str) -> OocError {
    let e = ooc::simplify_file(input, o, &mut no_progress).unwrap_err();
    let msg = e.to_string();
    assert!(msg.contains(what), "expected '{what}' in: {msg}");
    e
}

#[test]
fn bad_input_gives_clear_errors_and_leaves_no_temporary_files() {
    let dir = tempfile::tempdir().unwrap();
    let temp = tempfile::tempdir().unwrap();
    let input = terrain(dir.path(), 20_000);
    let bytes = std::fs::read(&input).unwrap();
    let o = options(temp.path(), 4 << 20);

    // Truncated in the faces, and in the vertices.
    for (cut, element) in [(bytes.len() - 100, "face "), (2000, "vertex ")] {
        let short = dir.path().join("short.ply");
        std::fs::write(&short, &bytes[..cut]).unwrap();
        let e = expect_error(&short, &o, element);
        assert!(e.to_string().contains("truncated"), "{e}");
        assert!(
            e.to_string().starts_with(&short.display().to_string()),
            "{e}"
        );
        assert_empty(temp.path());
    }

    // A face naming a vertex that does not exist.
    let mut bad = bytes.clone();
    let n = bad.len();
    bad[n - 4..].copy_from_slice(&u32::MAX.to_le_bytes());
    let badp = dir.path().join("bad.ply");
    std::fs::write(&badp, &bad).unwrap();
    expect_error(&badp, &o, "out of range");
    assert_empty(temp.path());

    // A budget too small for one leaf.
    let tiny = OocOptions {
        leaf_triangles: 1 << 16,
        ..options(temp.path(), 1 << 20)
    };
    let e = expect_error(&input, &tiny, "too small");
    assert!(matches!(e, OocError::Budget { .. }), "{e}");
    assert_empty(temp.path());

    // A full disk: a temporary-space quota below what the sort writes.
    let full = OocOptions {
        temp_quota: Some(200_000),
        ..options(temp.path(), 4 << 20)
    };
    let e = expect_error(&input, &full, "temporary space full");
    assert!(matches!(e, OocError::Temp { .. }), "{e}");
    assert_empty(temp.path());

    // Not a streamable format, and an OBJ face out of range.
    let gl = dir.path().join("x.gltf");
    std::fs::write(&gl, "{}").unwrap();
    expect_error(&gl, &o, "bake it in core");
    let obj = dir.path().join("x.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n").unwrap();
    expect_error(&obj, &o, "line 4: vertex index 4 out of range");
    assert_empty(temp.path());

    // And success leaves nothing either.
    ooc::simplify_file(&input, &o, &mut no_progress).unwrap();
    assert_empty(temp.path());
}

/// The acceptance run: 20 million generated triangles with a 256 MiB budget. Slow (a 610 MB
/// file and about 320 MB of temporary files); run in release with `--ignored`.
#[test]
#[ignore]
fn twenty_million_triangles_bake_within_the_memory_budget() {
    let dir = tempfile::tempdir().unwrap();
    let input = terrain(dir.path(), 20_000_000);
    let budget = 256 << 20;
    let o = OocOptions {
        temp_dir: Some(dir.path().to_path_buf()),
        ..OocOptions::with_budget(budget)
    };
    let start = std::time::Instant::now();
    let pipeline::OutOfCoreBake {
        baked, info, stats, ..
    } = pipeline::bake_out_of_core(&input, &o, &mut no_progress, &mut |_| {}).unwrap();
    let seconds = start.elapsed().as_secs_f64();
    baked.hierarchy().unwrap();
    let rss = ooc::peak_rss_bytes().unwrap();
    eprintln!(
        "{} triangles in {seconds:.1} s ({:.2} M/s), peak RSS {} MiB, {stats:?}",
        info.input_triangles,
        info.input_triangles as f64 / seconds / 1e6,
        rss >> 20
    );
    assert!(rss <= 320 << 20, "peak RSS {rss}");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[test]
fn threads_cluster_exactly_like_one_thread() {
    let dir = tempfile::tempdir().unwrap();
    let temp = tempfile::tempdir().unwrap();
    let input = terrain(dir.path(), 30_000);
    let run = |threads| {
        let o = OocOptions {
            threads,
            target_triangles: Some(3000),
            ..options(temp.path(), 4 << 20)
        };
        ooc::simplify(&input, &o, &mut no_progress).unwrap()
    };
    let one = run(1);
    assert!(one.stats.octree_leaves > 8, "{:?}", one.stats);
    for threads in [2, 3] {
        let other = run(threads);
        assert_eq!(one.stats.resolution, other.stats.resolution);
        assert_eq!(one.stats.clusters, other.stats.clusters);
        // The same mesh and octree, to the bit: the threads share out fixed parts.
        assert_eq!(one.mesh, other.mesh, "{threads} threads");
        assert_eq!(one.octree, other.octree, "{threads} threads");
    }
    assert_empty(temp.path());
}
