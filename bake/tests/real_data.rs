//! Baking the real data in `../shared/data` (relative to the repository root): FlightHelmet
//! (glTF, 6 materials), spot (OBJ), lucy (PLY) and St. Helens (USGS DEM). Each test skips with
//! a note when its file is absent.
//!
//! For each file: `pipeline::bake_file` succeeds; the hierarchy validates in memory and again
//! after a round trip through the `.clod` bytes (read in aligned memory); on the hierarchy read
//! back, the base front, a few random intermediate fronts and the full front pass
//! `check_front` (every polygon's three vertex-table look-ups exist); at every one of those
//! fronts each emitted vertex carries the attributes the welded input has at that position in
//! the polygon's surface group; full refinement gives back exactly the welded input triangles
//! per surface (as position triples), each corner with its welded normal and UV; and the base
//! mesh of a closed mesh has at most 1% of the input triangles, or the topological minimum.
//!
//! St. Helens takes about 40 s in a debug build, so it is ignored there (it runs in
//! `cargo test --release -p caveclod-bake --test real_data`, or with `--include-ignored`).

use std::collections::HashMap;
use std::time::Instant;

use caveclod_bake::import::{self, ImportOptions};
use caveclod_bake::pipeline::bake_file;
use caveclod_bake::report::BakeInfo;
use caveclod_bake::weld::{self, Welded};
use caveclod_core::format::PositionClass;
use caveclod_core::{CameraState, Hierarchy, NodeId};
use caveclod_tests::check::{check_front, split_all};
// The tests' generator, so failures reproduce from the seed.
use caveclod_tests::rng::SplitMix64 as Rng;
use caveclod_tests::shared_data;
use caveclod_tests::AlignedBytes;

type Key = [[u32; 3]; 3];

/// A triangle as its corner coordinates' bits, rotated so the smallest corner comes first
/// (orientation kept), and the rotation applied: `key[i] = corners[(i + rot) % 3]`.
fn key(pts: [[f32; 3]; 3]) -> (Key, usize) {
    let b = pts.map(|p| p.map(|x| (x + 0.0).to_bits()));
    (0..3)
        .map(|r| ([b[r], b[(r + 1) % 3], b[(r + 2) % 3]], r))
        .min()
        .expect("three rotations")
}

/// Topology of the welded mesh: border edges and, per connected component, its Euler
/// characteristic and RIGID positions.
struct Topology {
    border_edges: usize,
    /// `(euler characteristic, rigid positions)` per component.
    components: Vec<(i64, i64)>,
}

fn topology(w: &Welded) -> Topology {
    let np = w.positions.len();
    let mut parent: Vec<u32> = (0..np as u32).collect();
    fn find(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            parent[x as usize] = parent[parent[x as usize] as usize];
            x = parent[x as usize];
        }
        x
    }
    let mut directed = std::collections::HashSet::with_capacity(3 * w.triangles.len());
    for t in &w.triangles {
        for k in 0..3 {
            directed.insert((t.p[k], t.p[(k + 1) % 3]));
            let (a, b) = (
                find(&mut parent, t.p[k]),
                find(&mut parent, t.p[(k + 1) % 3]),
            );
            parent[a as usize] = b;
        }
    }
    let border_edges = directed
        .iter()
        .filter(|&&(a, b)| !directed.contains(&(b, a)))
        .count();
    // V - E + F per component, each undirected edge counted once.
    let mut per: HashMap<u32, (i64, i64)> = HashMap::new();
    let mut used = vec![false; np];
    for t in &w.triangles {
        let c = find(&mut parent, t.p[0]);
        per.entry(c).or_default().0 += 1;
        for &p in &t.p {
            if !std::mem::replace(&mut used[p as usize], true) {
                let e = per.entry(c).or_default();
                e.0 += 1;
                e.1 += i64::from(w.classes[p as usize] == PositionClass::Rigid);
            }
        }
    }
    for &(a, b) in &directed {
        if a < b || !directed.contains(&(b, a)) {
            per.entry(find(&mut parent, a)).or_default().0 -= 1;
        }
    }
    let mut components: Vec<(i64, i64)> = per.into_values().collect();
    components.sort_unstable();
    Topology {
        border_edges,
        components,
    }
}

/// Fewest triangles of a closed triangulated surface with Euler characteristic `chi` (as a
/// simplicial complex: Heawood's bound on the vertices, `F = 2 (V - chi)`), and at least
/// `vertices` vertices.
fn min_closed_triangles(chi: i64, vertices: i64) -> i64 {
    let v = ((7.0 + ((49 - 24 * chi) as f64).sqrt()) / 2.0).ceil() as i64;
    2 * (v.max(vertices) - chi)
}

struct Expect {
    file: &'static str,
    input_triangles: usize,
    surfaces: usize,
}

struct Checker<'w> {
    w: &'w Welded,
    /// Per polygon of the hierarchy: its welded triangle and the rotation from the welded
    /// triangle's corners to the polygon's.
    welded_of: Vec<(u32, u8)>,
}

impl<'w> Checker<'w> {
    fn new(w: &'w Welded, h: &Hierarchy<'_>) -> Self {
        // The baked positions are the welded positions, in order, so position ids agree.
        assert_eq!(h.positions().len(), w.positions.len());
        for (i, p) in h.positions().iter().enumerate() {
            assert_eq!(p.xyz, w.positions[i], "position {i}");
        }
        let mut by_key: HashMap<(u16, Key), (u32, usize)> =
            HashMap::with_capacity(w.triangles.len());
        for (i, t) in w.triangles.iter().enumerate() {
            let (k, r) = key(t.p.map(|p| w.positions[p as usize]));
            let old = by_key.insert((w.surface_of(t), k), (i as u32, r));
            assert!(old.is_none(), "two welded triangles with the same corners");
        }
        let welded_of = h
            .polygons()
            .iter()
            .enumerate()
            .map(|(f, poly)| {
                let pts = poly.nodes.map(|n| h.node_point(n).expect("validated node"));
                let (k, r) = key(pts);
                let (t, rt) = *by_key
                    .get(&(poly.surface.0, k))
                    .unwrap_or_else(|| panic!("polygon {f} is no welded triangle"));
                // polygon corner j = key[(j - r)] = welded corner (j - r + rt).
                (t, ((rt + 3 - r) % 3) as u8)
            })
            .collect();
        Self { w, welded_of }
    }

    /// `check_front`, then: every emitted vertex has the welded attributes of the polygon's
    /// surface group at the corner's position.
    fn front(&self, h: &Hierarchy<'_>, cam: &CameraState<'_>, what: &str) {
        if let Err(e) = check_front(h, cam) {
            panic!("{what}: {e}");
        }
        let ns = h.surface_count();
        let mut out = vec![0u32; (0..ns).map(|s| cam.index_count(s)).sum()];
        let mut offsets = vec![0u32; ns + 1];
        cam.emit_indices_packed(h, &mut out, &mut offsets)
            .expect("emit");
        let mut cursor = offsets.clone();
        for f in cam.active_polygons(h) {
            let poly = h.polygons()[f.index()];
            let s = poly.surface.index();
            let (t, _) = self.welded_of[f.index()];
            let group = self.w.triangles[t as usize].group;
            let corners = cam.polygon_corners(h, f).expect("active");
            for k in 0..3 {
                let v = h.vertices()[out[cursor[s] as usize + k] as usize];
                let pos = h.node(corners[k]).expect("node").position.index();
                let a = self.w.vertices[pos]
                    .iter()
                    .find(|&&(g, _)| g == group)
                    .map(|&(_, a)| self.w.attributes[a as usize])
                    .unwrap_or_else(|| {
                        panic!("{what}: {f} corner {k}: group {group} has no vertex at {pos}")
                    });
                assert!(
                    v.normal == a.normal && v.uv == a.uv,
                    "{what}: {f} corner {k}: attributes {:?} {:?}, welded {:?} {:?}",
                    v.normal,
                    v.uv,
                    a.normal,
                    a.uv
                );
            }
            cursor[s] += 3;
        }
    }

    /// The full front is exactly the welded triangles, per surface, each corner with its
    /// welded attributes.
    fn full(&self, h: &Hierarchy<'_>, cam: &CameraState<'_>) {
        let w = self.w;
        let mut want: Vec<(u16, Key)> = w
            .triangles
            .iter()
            .map(|t| (w.surface_of(t), key(t.p.map(|p| w.positions[p as usize])).0))
            .collect();
        let mut got: Vec<(u16, Key)> = cam
            .active_polygons(h)
            .map(|f| {
                let c = cam.polygon_corners(h, f).expect("active");
                (
                    h.polygons()[f.index()].surface.0,
                    key(c.map(|v| h.node_point(v).expect("node"))).0,
                )
            })
            .collect();
        want.sort_unstable();
        got.sort_unstable();
        assert_eq!(got.len(), want.len(), "full front size");
        assert!(got == want, "the full front is not the welded mesh");
        let ns = h.surface_count();
        let mut out = vec![0u32; (0..ns).map(|s| cam.index_count(s)).sum()];
        let mut offsets = vec![0u32; ns + 1];
        cam.emit_indices_packed(h, &mut out, &mut offsets)
            .expect("emit");
        let mut cursor = offsets.clone();
        for f in cam.active_polygons(h) {
            let s = h.polygons()[f.index()].surface.index();
            let (t, rot) = self.welded_of[f.index()];
            let tri = &w.triangles[t as usize];
            for k in 0..3 {
                let v = h.vertices()[out[cursor[s] as usize + k] as usize];
                let a = &w.attributes[w.corner_attributes(tri)[(k + rot as usize) % 3] as usize];
                assert_eq!(
                    v.position,
                    w.positions[tri.p[(k + rot as usize) % 3] as usize]
                );
                assert!(
                    v.normal == a.normal && v.uv == a.uv,
                    "{f} corner {k}: emitted {:?} {:?}, welded corner {:?} {:?}",
                    v.normal,
                    v.uv,
                    a.normal,
                    a.uv
                );
            }
            cursor[s] += 3;
        }
    }
}

/// Force-splits random active nodes until at least `target` polygons are active.
fn random_splits(h: &Hierarchy<'_>, cam: &mut CameraState<'_>, rng: &mut Rng, target: u32) {
    let mut stack = vec![NodeId::NONE; 4096];
    while cam.active_polygon_count() < target {
        let todo: Vec<NodeId> = cam
            .active_nodes()
            .filter(|&v| h.split(v).is_some())
            .collect();
        assert!(!todo.is_empty(), "nothing left to split below {target}");
        for _ in 0..(todo.len() / 8).max(1) {
            let v = todo[rng.below(todo.len())];
            if !cam.is_split(v) {
                cam.force_split(h, v, &mut stack).expect("force_split");
            }
            if cam.active_polygon_count() >= target {
                break;
            }
        }
    }
}

/// Collapses about `fraction` of the legal collapses, chosen at random.
fn random_collapses(h: &Hierarchy<'_>, cam: &mut CameraState<'_>, rng: &mut Rng, fraction: f64) {
    let legal: Vec<NodeId> = (0..h.splits().len() as u32)
        .map(NodeId)
        .filter(|&v| cam.can_collapse(h, v))
        .collect();
    for v in legal {
        if ((rng.next_u64() % 1000) as f64) < 1000.0 * fraction && cam.can_collapse(h, v) {
            cam.collapse(h, v).expect("collapse");
        }
    }
}

fn bake_and_check(e: &Expect) {
    let Some(path) = shared_data::file(e.file) else {
        return;
    };
    let build = if cfg!(debug_assertions) {
        "debug"
    } else {
        "release"
    };
    let start = Instant::now();
    let (baked, info) = bake_file(&path, &ImportOptions::default(), &mut |_| {}).expect("bake");
    let bake_s = start.elapsed().as_secs_f64();

    // The reference: the imported mesh, welded as the bake welds it.
    let mesh = import::import(&path, &ImportOptions::default()).expect("import");
    let w = weld::weld(&mesh).expect("weld");
    assert_eq!(mesh.triangles.len(), e.input_triangles);
    assert_eq!(mesh.surfaces.len(), e.surfaces);
    assert_eq!(info.input_triangles, e.input_triangles as u64);
    assert_eq!(info.repairs, w.repairs, "reported repairs");
    assert_eq!(info.surface_groups, w.group_count as u64);
    let r = &info.repairs;
    assert_eq!(
        w.triangles.len() as u64,
        e.input_triangles as u64 - r.degenerate_triangles - r.duplicate_triangles,
        "triangles left after the reported repairs"
    );

    // Validation in memory and after a round trip through the file's bytes.
    let in_memory = baked.hierarchy().expect("the baked arrays validate");
    let json = info.to_json();
    let bytes = baked
        .to_bytes(&[BakeInfo::section(&json)])
        .expect("to_bytes");
    let aligned = AlignedBytes::from_slice(&bytes);
    let h = Hierarchy::from_bytes(&aligned).expect("the file validates");
    assert_eq!(h.meta(), in_memory.meta());
    let (a, b) = (h.parts(), in_memory.parts());
    assert!(
        bytemuck::cast_slice::<_, u8>(a.positions) == bytemuck::cast_slice::<_, u8>(b.positions)
            && a.nodes == b.nodes
            && a.splits == b.splits
            && bytemuck::cast_slice::<_, u8>(a.bounds) == bytemuck::cast_slice::<_, u8>(b.bounds)
            && a.polygons == b.polygons
            && a.roots == b.roots
            && a.base == b.base
            && a.vertex_table_offsets == b.vertex_table_offsets
            && a.vertex_table == b.vertex_table
            && bytemuck::cast_slice::<_, u8>(a.vertices)
                == bytemuck::cast_slice::<_, u8>(b.vertices),
        "the arrays read back differ from the arrays written"
    );
    assert_eq!(BakeInfo::read(&h).as_ref(), Some(&info));
    assert_eq!(h.polygon_count(), w.triangles.len());

    let checker = Checker::new(&w, &h);
    let mut memory = vec![0u32; CameraState::words_needed(&h)];
    let mut cam = CameraState::new(&h, &mut memory).expect("camera");
    checker.front(&h, &cam, "base");

    // Random intermediate fronts, growing, with some collapses in between.
    let total = h.polygon_count() as u32;
    let mut rng = Rng(0x5EED ^ e.input_triangles as u64);
    for (i, share) in [0.02, 0.15, 0.5].into_iter().enumerate() {
        let target = ((share * total as f64) as u32).max(h.base_polygon_count() as u32 + 1);
        random_splits(&h, &mut cam, &mut rng, target);
        checker.front(&h, &cam, &format!("random front {i} (split)"));
        random_collapses(&h, &mut cam, &mut rng, 0.3);
        checker.front(&h, &cam, &format!("random front {i} (collapsed)"));
    }

    split_all(&h, &mut cam);
    assert_eq!(cam.split_count() as usize, h.splits().len());
    checker.front(&h, &cam, "full");
    checker.full(&h, &cam);

    // The base mesh of a closed mesh: at most 1% of the input, or the topological minimum
    // (every RIGID position stays in the base mesh, and each component needs a triangulation
    // of its own).
    let topo = topology(&w);
    let rigid: i64 = topo.components.iter().map(|c| c.1).sum();
    let base = h.base_polygon_count();
    let one_percent = e.input_triangles.div_ceil(100);
    let minimum: i64 = topo
        .components
        .iter()
        .map(|&(chi, rigid)| min_closed_triangles(chi, rigid))
        .sum();
    eprintln!(
        "{}: {} input triangles, {} welded, repairs {:?}; baked in {bake_s:.1} s ({build}); \
         {} positions, {} nodes, {} splits, depth {}, base {} polygons ({:.2}% of the input), \
         {} roots; surfaces {}, surface groups {} before colouring, {} ids after; \
         {} border edges, {} components (Euler characteristics {:?}), {} RIGID positions; \
         checked in {:.1} s",
        e.file,
        e.input_triangles,
        w.triangles.len(),
        info.repairs,
        h.positions().len(),
        h.node_count(),
        h.splits().len(),
        h.meta().max_depth,
        base,
        100.0 * base as f64 / e.input_triangles as f64,
        h.roots().len(),
        h.surface_count(),
        info.surface_groups,
        h.meta().surface_group_count,
        topo.border_edges,
        topo.components.len(),
        topo.components
            .iter()
            .map(|c| c.0)
            .take(8)
            .collect::<Vec<_>>(),
        rigid,
        start.elapsed().as_secs_f64() - bake_s,
    );
    if topo.border_edges == 0 {
        assert!(
            base <= one_percent || base as i64 <= minimum,
            "closed mesh: base {base} > 1% ({one_percent}) and > the topological minimum \
             {minimum}"
        );
    }
}

#[test]
fn spot() {
    bake_and_check(&Expect {
        file: "spot/spot_triangulated.obj",
        input_triangles: 5_856,
        surfaces: 1,
    });
}

#[test]
fn flight_helmet() {
    bake_and_check(&Expect {
        file: "FlightHelmet/FlightHelmet.gltf",
        input_triangles: 94_722,
        surfaces: 6,
    });
}

#[test]
fn lucy() {
    bake_and_check(&Expect {
        file: "scans/lucy.ply",
        input_triangles: 99_970,
        surfaces: 1,
    });
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "40 s in a debug build, which would take the file past 60 s; runs in --release"
)]
fn st_helens() {
    bake_and_check(&Expect {
        file: "terrain/SainteHelens.dem",
        input_triangles: 296_186,
        surfaces: 1,
    });
}
