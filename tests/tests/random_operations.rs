//! proptest: random legal split / collapse / forced-split sequences and random camera paths on
//! three generated meshes. After every step the front passes every invariant of
//! `check_front` (active sets equal the sets derived from scratch, neighbour links symmetric,
//! corners above their leaves, emitted indices in the right surface group), a camera without
//! the index cache that takes the same steps emits the same indices, and a second camera over
//! the same hierarchy never changes. A second property runs a budgeted camera whose pair map
//! is hashed beside one with the same budget whose map is an array, through the same steps
//! (capacity refusals included): they must keep the same front and emit the same indices.
//! Steps include amortised refinement (a visit budget) and incremental compaction steps.

use std::sync::OnceLock;

use caveclod_core::glam::Vec3;
use caveclod_core::{CameraConfig, CameraState, LookAt, NodeId, RefineParams};
use caveclod_tests::check::check_front;
use caveclod_tests::{bake, meshes, BakedMesh};
use proptest::prelude::*;

/// A terrain large enough that a camera holding a seventh of its splits hashes its pair map.
fn larger_baked() -> &'static BakedMesh {
    static B: OnceLock<BakedMesh> = OnceLock::new();
    B.get_or_init(|| bake(&meshes::terrain(40, 40, 6)))
}

fn meshes_baked() -> &'static [BakedMesh; 3] {
    static B: OnceLock<[BakedMesh; 3]> = OnceLock::new();
    B.get_or_init(|| {
        [
            bake(&meshes::terrain(10, 8, 5)),
            bake(&meshes::sphere(2)),
            bake(&meshes::holed_terrain(12, 12, 9)),
        ]
    })
}

#[derive(Clone, Debug)]
enum Step {
    Split(u32),
    ForceSplit(u32),
    Collapse(u32),
    Compact,
    CompactBy(u32),
    Refine {
        eye: [f32; 3],
        target: [f32; 3],
        tolerance: f32,
        max_ops: u32,
        max_visits: u32,
    },
}

fn step() -> impl Strategy<Value = Step> {
    prop_oneof![
        3 => any::<u32>().prop_map(Step::Split),
        2 => any::<u32>().prop_map(Step::ForceSplit),
        3 => any::<u32>().prop_map(Step::Collapse),
        1 => Just(Step::Compact),
        2 => prop_oneof![1u32..20, 20u32..3000].prop_map(Step::CompactBy),
        1 => (prop::array::uniform3(-20.0f32..20.0), prop::array::uniform3(-5.0f32..15.0), 0.05f32..20.0, prop_oneof![Just(u32::MAX), 1u32..50], prop_oneof![Just(u32::MAX), 1u32..100])
            .prop_map(|(eye, target, tolerance, max_ops, max_visits)| Step::Refine { eye, target, tolerance, max_ops, max_visits }),
    ]
}

fn snapshot(
    h: &caveclod_core::Hierarchy<'_>,
    cam: &CameraState<'_>,
) -> (Vec<NodeId>, Vec<Option<[NodeId; 3]>>) {
    let nodes = cam.active_nodes().collect();
    let polys = (0..h.polygon_count() as u32)
        .map(|f| cam.polygon_corners(h, caveclod_core::PolyId(f)))
        .collect();
    (nodes, polys)
}

/// An active polygon with its corners and neighbours.
type PolyState = (u32, [NodeId; 3], [caveclod_core::PolyId; 3]);

/// The front as sets: active nodes, and every active polygon with its corners and
/// neighbours (independent of record and slot order).
fn snapshot_sorted(
    h: &caveclod_core::Hierarchy<'_>,
    cam: &CameraState<'_>,
) -> (Vec<NodeId>, Vec<PolyState>) {
    let mut nodes: Vec<NodeId> = cam.active_nodes().collect();
    nodes.sort_unstable();
    let mut polys: Vec<_> = cam
        .active_polygons(h)
        .map(|f| {
            (
                f.0,
                cam.polygon_corners(h, f).expect("active"),
                cam.polygon_neighbours(h, f).expect("active"),
            )
        })
        .collect();
    polys.sort_unstable();
    (nodes, polys)
}

/// Every surface's indices, packed, with the offsets.
fn emitted(h: &caveclod_core::Hierarchy<'_>, cam: &CameraState<'_>) -> (Vec<u32>, Vec<u32>) {
    let total = (0..h.surface_count()).map(|s| cam.index_count(s)).sum();
    let mut out = vec![0u32; total];
    let mut offsets = vec![0u32; h.surface_count() + 1];
    cam.emit_indices_packed(h, &mut out, &mut offsets)
        .expect("emit");
    (out, offsets)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn random_steps_keep_every_invariant(which in 0usize..3, steps in prop::collection::vec(step(), 1..120)) {
        let baked = &meshes_baked()[which];
        let h = baked.hierarchy();
        let mut mem = vec![0u32; CameraState::words_needed(&h)];
        let mut other_mem = vec![0u32; CameraState::words_needed(&h)];
        let mut cam = CameraState::new(&h, &mut mem).expect("sized");
        let mut other = CameraState::new(&h, &mut other_mem).expect("sized");
        // The same steps on a camera without the index cache: it must emit the same indices.
        let plain_config = CameraConfig { index_cache: false, ..CameraConfig::full(&h) };
        let mut plain_mem = vec![0u32; CameraState::words_needed_for(&h, &plain_config)];
        let mut plain = CameraState::with_config(&h, &mut plain_mem, &plain_config).expect("sized");
        let mut plain_stack = vec![NodeId::NONE; 1024];
        let far = LookAt { eye: Vec3::new(500.0, 300.0, 500.0), target: Vec3::ZERO, up: Vec3::Y, fov_y: 1.0, near: 0.1, far: 1e4 }.view(512, 512);
        other.refine(&h, &far, &RefineParams::default()).expect("refine");
        let other_before = snapshot(&h, &other);
        let mut stack = vec![NodeId::NONE; 1024];
        let ns = h.splits().len() as u32;
        for s in steps {
            match s {
                Step::Split(x) => {
                    let v = NodeId(x % ns);
                    let legal = cam.can_split(&h, v);
                    prop_assert_eq!(cam.split(&h, v).is_ok(), legal);
                    prop_assert_eq!(plain.split(&h, v).is_ok(), legal);
                }
                Step::ForceSplit(x) => {
                    // Any node, created or not: the forced split creates it first.
                    let v = NodeId(x % ns);
                    let applied = cam.force_split(&h, v, &mut stack).expect("force split");
                    prop_assert_eq!(plain.force_split(&h, v, &mut plain_stack), Ok(applied));
                    prop_assert!(cam.is_split(v));
                    prop_assert!(applied > 0 || !cam.is_node_active(&h, v));
                }
                Step::Collapse(x) => {
                    let v = NodeId(x % ns);
                    let legal = cam.can_collapse(&h, v);
                    prop_assert_eq!(cam.collapse(&h, v).is_ok(), legal);
                    prop_assert_eq!(plain.collapse(&h, v).is_ok(), legal);
                }
                Step::Compact => {
                    let before = snapshot_sorted(&h, &cam);
                    cam.compact(&h);
                    plain.compact(&h);
                    prop_assert_eq!(snapshot_sorted(&h, &cam), before);
                }
                Step::CompactBy(budget) => {
                    let before = snapshot_sorted(&h, &cam);
                    prop_assert_eq!(cam.compact_step(&h, budget), plain.compact_step(&h, budget));
                    prop_assert_eq!(snapshot_sorted(&h, &cam), before);
                }
                Step::Refine { eye, target, tolerance, max_ops, max_visits } => {
                    let view = LookAt { eye: Vec3::from(eye), target: Vec3::from(target), up: Vec3::Y, fov_y: 1.0, near: 0.05, far: 1e3 }.view(520, 400);
                    let params = RefineParams { tolerance_px: tolerance, max_ops, max_visits, ..RefineParams::default() };
                    let st = cam.refine(&h, &view, &params).expect("refine");
                    prop_assert!(st.operations() <= max_ops);
                    prop_assert!(st.nodes_visited <= max_visits.saturating_add(st.operations()));
                    prop_assert_eq!(plain.refine(&h, &view, &params), Ok(st));
                }
            }
            if let Err(e) = check_front(&h, &cam) {
                prop_assert!(false, "{}", e);
            }
            prop_assert_eq!(emitted(&h, &cam), emitted(&h, &plain));
        }
        prop_assert_eq!(snapshot(&h, &other), other_before);
    }

    /// A budgeted camera may keep its pair map hashed (`CameraConfig::hashed_pair_map`).
    /// One camera that does and one that keeps the array, with the same budget, take the same
    /// steps: their results (capacity refusals included), their fronts in record and slot
    /// order, and their emissions must be equal.
    #[test]
    fn hashed_and_array_pair_maps_agree(steps in prop::collection::vec(step(), 1..120)) {
        let baked = larger_baked();
        let h = baked.hierarchy();
        let ns = h.splits().len() as u32;
        let array = CameraConfig { max_pairs: ns / 7, ..CameraConfig::full(&h) };
        let hashed = CameraConfig { hashed_pair_map: true, ..array };
        let mut mem_a = vec![0u32; CameraState::words_needed_for(&h, &hashed)];
        let mut mem_b = vec![0u32; CameraState::words_needed_for(&h, &array)];
        // A seventh of the splits hash into less memory than the array (`pair_map`'s rule).
        prop_assert!(mem_a.len() < mem_b.len());
        let mut a = CameraState::with_config(&h, &mut mem_a, &hashed).expect("sized");
        let mut b = CameraState::with_config(&h, &mut mem_b, &array).expect("sized");
        let (mut stack_a, mut stack_b) = (vec![NodeId::NONE; 1024], vec![NodeId::NONE; 1024]);
        for s in steps {
            match s {
                Step::Split(x) => {
                    let v = NodeId(x % ns);
                    prop_assert_eq!(a.split(&h, v), b.split(&h, v));
                }
                Step::ForceSplit(x) => {
                    let v = NodeId(x % ns);
                    prop_assert_eq!(
                        a.force_split(&h, v, &mut stack_a),
                        b.force_split(&h, v, &mut stack_b)
                    );
                }
                Step::Collapse(x) => {
                    let v = NodeId(x % ns);
                    prop_assert_eq!(a.collapse(&h, v), b.collapse(&h, v));
                }
                Step::Compact => {
                    a.compact(&h);
                    b.compact(&h);
                }
                Step::CompactBy(budget) => {
                    prop_assert_eq!(a.compact_step(&h, budget), b.compact_step(&h, budget));
                }
                Step::Refine { eye, target, tolerance, max_ops, max_visits } => {
                    let view = LookAt { eye: Vec3::from(eye), target: Vec3::from(target), up: Vec3::Y, fov_y: 1.0, near: 0.05, far: 1e3 }.view(520, 400);
                    let params = RefineParams { tolerance_px: tolerance, max_ops, max_visits, ..RefineParams::default() };
                    prop_assert_eq!(a.refine(&h, &view, &params), b.refine(&h, &view, &params));
                }
            }
            if let Err(e) = check_front(&h, &a) {
                prop_assert!(false, "{}", e);
            }
            prop_assert_eq!(snapshot(&h, &a), snapshot(&h, &b));
            prop_assert_eq!(emitted(&h, &a), emitted(&h, &b));
        }
    }
}
