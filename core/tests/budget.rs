//! Bounded work per frame on the golden hierarchy: amortised refinement (a share of the
//! active list per call, resuming where the last call stopped) converges, while the view
//! holds still, to the front full passes settle at, with and without geomorphs; incremental
//! compaction leaves the front, its emission and its morphs as they were after every step,
//! whatever refinement does between steps, and a cycle over a still front ends in the order
//! of the full compaction.

mod common;

use caveclod_core::{CameraState, Hierarchy, NodeId, RefineParams, View};
use common::morphs::*;
use common::{emit_checked, golden_hierarchy, views};
use proptest::prelude::*;

/// Frames of a random flight, at most `most` (fewer under miri).
fn flight_len(most: usize) -> std::ops::Range<usize> {
    1..if cfg!(miri) { 4 } else { most }
}

/// The views a flight picks from: around the terrain, and along an approach to it.
fn all_views(h: &Hierarchy<'_>) -> Vec<View> {
    let mut all = views(h, 6);
    all.extend((0..6).map(|k| approach(h, k as f32 / 5.0)));
    all
}

/// Amortised calls at `view` until one lap of the active list changes nothing and nothing
/// morphs; returns the calls made.
fn settle_amortised(
    h: &Hierarchy<'_>,
    cam: &mut CameraState<'_>,
    view: &View,
    p: &RefineParams,
) -> u32 {
    let mut quiet_visits = 0u64;
    for calls in 1..200_000 {
        let st = cam.refine(h, view, p).expect("refine");
        if st.operations() == 0 && st.morphing == 0 {
            quiet_visits += u64::from(st.nodes_visited);
            if quiet_visits >= u64::from(cam.active_node_count()) {
                return calls;
            }
        } else {
            quiet_visits = 0;
        }
    }
    panic!("amortised refinement did not settle");
}

/// The active list's order and the emission order of polygons.
fn order(h: &Hierarchy<'_>, cam: &CameraState<'_>) -> (Vec<NodeId>, Vec<u32>) {
    (
        cam.active_nodes().collect(),
        cam.active_polygons(h).map(|p| p.0).collect(),
    )
}

/// The morphed emission's triangles, sorted: what the GPU draws, whatever the slot order.
fn morphed_triangles(h: &Hierarchy<'_>, cam: &CameraState<'_>) -> (Vec<[u32; 3]>, Vec<u32>) {
    let (out, offsets) = packed(h, cam, true);
    let mut t: Vec<[u32; 3]> = out.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
    t.sort_unstable();
    (t, offsets)
}

/// Steps of `budget` until the cycle under way (or a new one) ends; the steps taken.
fn finish_cycle(h: &Hierarchy<'_>, cam: &mut CameraState<'_>, budget: u32) -> u32 {
    for steps in 1..10_000_000 {
        if cam.compact_step(h, budget).finished {
            return steps;
        }
    }
    panic!("compaction did not finish");
}

#[test]
fn a_visit_budget_bounds_each_call_and_the_calls_cover_the_list() {
    let h = golden_hierarchy();
    let view = approach(&h, 0.0);
    let mut memory = vec![0u32; CameraState::words_needed(&h)];
    let mut cam = CameraState::new(&h, &mut memory).expect("memory");
    settle(&h, &mut cam, &view, &fine().without_morphs());
    cam.compact(&h); // no free records in the list: every record looked at is a visit
    let n = cam.active_node_count();
    assert!(n > 40, "the view refines: {n} active nodes");
    // A settled front: every call looks at exactly its budget, and the calls go round.
    let p = RefineParams {
        max_visits: 7,
        ..fine().without_morphs()
    };
    let mut seen = 0u64;
    for _ in 0..n.div_ceil(7) {
        let st = cam.refine(&h, &view, &p).expect("refine");
        assert_eq!(st.operations(), 0);
        assert_eq!(st.nodes_visited, 7);
        seen += u64::from(st.nodes_visited);
    }
    assert!(seen >= u64::from(n));
    // A share: a third of the list per call.
    let st = cam
        .refine(&h, &view, &fine().without_morphs().amortised(1.0 / 3.0))
        .expect("refine");
    assert_eq!(st.nodes_visited, n.div_ceil(3));
    // Far away the front coarsens a share at a time, and converges.
    let far = approach(&h, 1.0);
    let third = fine().without_morphs().amortised(1.0 / 3.0);
    let first = cam.refine(&h, &far, &third).expect("refine");
    assert!(first.nodes_visited <= n.div_ceil(3) + first.operations());
    settle_amortised(&h, &mut cam, &far, &third);
    let mut plain_memory = vec![0u32; CameraState::words_needed(&h)];
    let mut plain = CameraState::new(&h, &mut plain_memory).expect("memory");
    settle(&h, &mut plain, &far, &fine().without_morphs());
    assert_eq!(sorted_front(&cam), sorted_front(&plain));
}

#[test]
fn a_still_front_compacts_in_steps_to_the_full_compactions_order() {
    let h = golden_hierarchy();
    let mut memory = vec![0u32; CameraState::words_needed(&h)];
    let mut cam = CameraState::new(&h, &mut memory).expect("memory");
    // Scatter the arrays: refine near, far and near again.
    for k in [0.0, 0.6, 0.1, 0.8, 0.0] {
        settle(&h, &mut cam, &approach(&h, k), &fine().without_morphs());
    }
    let before = emit_checked(&h, &cam);
    let scattered = order(&h, &cam);
    let steps = finish_cycle(&h, &mut cam, 64);
    assert!(steps > 1, "a cycle takes several steps of 64");
    assert_eq!(emit_checked(&h, &cam), before);
    let stepped = order(&h, &cam);
    assert_ne!(stepped, scattered, "the flight scattered the arrays");
    cam.compact(&h);
    assert_eq!(order(&h, &cam), stepped);
    assert!(!cam.compacting());
}

proptest! {
    #![proptest_config(common::proptest_config(48, 2))]

    /// After any flight with any visit budgets (and incremental compaction steps between
    /// frames), an amortised camera held still settles at the front a camera refined by full
    /// passes settles at, and a full pass then finds nothing to do.
    #[test]
    fn amortised_refinement_converges_to_the_full_front(
        frames in prop::collection::vec(
            (0usize..12, prop::sample::select(vec![0.05f32, 0.3, 2.0]),
             prop::sample::select(vec![0.05f32, 1.0 / 3.0, 0.7, 1.0]),
             prop::sample::select(vec![u32::MAX, 1, 9, 200]),
             prop::sample::select(vec![0u32, 1, 40, 5000])),
            flight_len(30)),
    ) {
        let h = golden_hierarchy();
        let all = all_views(&h);
        let mut memory = vec![0u32; CameraState::words_needed(&h)];
        let mut cam = CameraState::new(&h, &mut memory).expect("memory");
        let mut plain_memory = vec![0u32; CameraState::words_needed(&h)];
        let mut plain = CameraState::new(&h, &mut plain_memory).expect("memory");
        let mut last = None;
        for &(v, tolerance_px, share, max_visits, compact) in &frames {
            let full = RefineParams { tolerance_px, ..RefineParams::default() };
            let p = RefineParams { visit_fraction: share, max_visits, ..full };
            plain.refine(&h, &all[v], &full).expect("refine");
            let st = cam.refine(&h, &all[v], &p).expect("refine");
            prop_assert!(st.nodes_visited <= max_visits.saturating_add(st.operations()));
            if compact > 0 {
                let before = emit_checked(&h, &cam);
                cam.compact_step(&h, compact);
                prop_assert_eq!(emit_checked(&h, &cam), before);
            }
            last = Some((v, p, full));
        }
        let (v, p, full) = last.expect("a frame");
        settle_amortised(&h, &mut cam, &all[v], &p);
        settle(&h, &mut plain, &all[v], &full);
        prop_assert_eq!(sorted_front(&cam), sorted_front(&plain));
        prop_assert_eq!(triangles(&h, &cam), triangles(&h, &plain));
        prop_assert_eq!(cam.refine(&h, &all[v], &full).expect("refine").operations(), 0);
    }

    /// With geomorphs: over any flight an amortised camera's morphs stay between their
    /// endpoints, and held still it ends every morph at the front of a camera without
    /// morphs refined by full passes.
    #[test]
    fn amortised_morphing_converges_to_the_full_front(
        max_morphs in 1u32..40,
        frames in prop::collection::vec(
            (0usize..12, prop::sample::select(vec![0.0f32, 1.0 / 60.0, 0.4]),
             prop::sample::select(vec![0.05f32, 0.3, 2.0]),
             prop::sample::select(vec![0.1f32, 1.0 / 3.0, 1.0])),
            flight_len(30)),
    ) {
        let h = golden_hierarchy();
        let pos = position_of_vertex(&h);
        let all = all_views(&h);
        let config = morph_config(&h, max_morphs);
        let mut memory = vec![0u32; CameraState::words_needed_for(&h, &config)];
        let mut cam = CameraState::with_config(&h, &mut memory, &config).expect("memory");
        let mut plain_memory = vec![0u32; CameraState::words_needed(&h)];
        let mut plain = CameraState::new(&h, &mut plain_memory).expect("memory");
        let mut last = None;
        for &(v, dt_s, tolerance_px, share) in &frames {
            // No guard band: the camera without morphs refines against the view itself.
            let full = RefineParams {
                dt_s,
                tolerance_px,
                morph_guard_rad: 0.0,
                ..RefineParams::default()
            };
            plain.refine(&h, &all[v], &full).expect("refine");
            cam.refine(&h, &all[v], &full.amortised(share)).expect("refine");
            check_morphs(&h, &cam, &pos);
            last = Some((v, full, share));
        }
        let (v, full, share) = last.expect("a frame");
        // Without the speed limit, so morphs near the eye end within the settling calls.
        let full = RefineParams { dt_s: 1.0 / 60.0, morph_speed_px_s: 0.0, ..full };
        settle_amortised(&h, &mut cam, &all[v], &full.amortised(share));
        settle(&h, &mut plain, &all[v], &full);
        prop_assert!(cam.morph_vertices().is_empty());
        prop_assert_eq!(sorted_front(&cam), sorted_front(&plain));
        prop_assert_eq!(triangles(&h, &cam), triangles(&h, &plain));
    }

    /// Any interleaving of compaction steps (any budget), full compactions and amortised or
    /// full refinement, with morphs: every step leaves the counts, the emitted triangles
    /// and the morphs as they were; held still, the next whole cycle ends in the full
    /// compaction's order.
    #[test]
    fn compaction_steps_leave_the_front_whatever_refinement_does_between(
        max_morphs in prop::sample::select(vec![0u32, 12]),
        steps in prop::collection::vec(
            (0usize..12, prop::sample::select(vec![0.05f32, 0.3, 2.0]),
             prop::sample::select(vec![1.0 / 3.0, 1.0f32]),
             prop::sample::select(vec![0u32, 1, 3, 17, 200, 100_000])),
            flight_len(40)),
        // A cycle in steps of 1 takes thousands of calls: too slow for miri.
        budget in prop::sample::select(if cfg!(miri) { vec![300u32] } else { vec![1u32, 7, 300] }),
    ) {
        let h = golden_hierarchy();
        let pos = position_of_vertex(&h);
        let all = all_views(&h);
        let config = morph_config(&h, max_morphs);
        let mut memory = vec![0u32; CameraState::words_needed_for(&h, &config)];
        let mut cam = CameraState::with_config(&h, &mut memory, &config).expect("memory");
        for (i, &(v, tolerance_px, share, compact)) in steps.iter().enumerate() {
            let p = RefineParams { tolerance_px, ..RefineParams::default() }.amortised(share);
            cam.refine(&h, &all[v], &p).expect("refine");
            let counts = (cam.active_node_count(), cam.active_polygon_count(), cam.split_count());
            let before = (emit_checked(&h, &cam), morphed_triangles(&h, &cam));
            if i % 11 == 10 {
                cam.compact(&h);
            } else if compact > 0 {
                cam.compact_step(&h, compact);
            }
            let after = (emit_checked(&h, &cam), morphed_triangles(&h, &cam));
            prop_assert_eq!(
                counts,
                (cam.active_node_count(), cam.active_polygon_count(), cam.split_count())
            );
            prop_assert_eq!(after, before);
            check_morphs(&h, &cam, &pos);
        }
        // Held still (refinement settled, morphs ended): the cycle under way may have been
        // changed under; the next one sorts completely.
        let (v, tolerance_px, _, _) = steps[steps.len() - 1];
        let p = RefineParams { tolerance_px, morph_speed_px_s: 0.0, ..RefineParams::default() };
        settle(&h, &mut cam, &all[v], &p);
        if cam.compacting() {
            finish_cycle(&h, &mut cam, budget);
        }
        let front = emit_checked(&h, &cam);
        finish_cycle(&h, &mut cam, budget);
        prop_assert_eq!(emit_checked(&h, &cam), front);
        let stepped = order(&h, &cam);
        cam.compact(&h);
        prop_assert_eq!(order(&h, &cam), stepped);
    }
}

/// The frame loop's policy: nothing while the churn since the last cycle stays under a
/// quarter of the front, then bounded steps every frame until the cycle ends, in the full
/// compaction's order when the front held still.
#[test]
fn compaction_as_needed_starts_on_churn_and_steps_until_done() {
    let h = golden_hierarchy();
    let mut memory = vec![0u32; CameraState::words_needed(&h)];
    let mut cam = CameraState::new(&h, &mut memory).expect("memory");
    let p = fine().without_morphs();
    settle(&h, &mut cam, &approach(&h, 1.0), &p);
    cam.compact(&h);
    assert_eq!(cam.churn(), 0);
    let idle = cam.compact_as_needed(&h, 64);
    assert_eq!((idle.work, idle.finished), (0, false));
    assert!(!cam.compacting());
    // Coming close churns the front past a quarter of it.
    let near = approach(&h, 0.0);
    settle(&h, &mut cam, &near, &p);
    assert!(
        cam.churn() >= cam.active_node_count() / 4,
        "the view churns the front: {} of {}",
        cam.churn(),
        cam.active_node_count()
    );
    let mut twin_memory = vec![0u32; CameraState::words_needed(&h)];
    let mut twin = CameraState::new(&h, &mut twin_memory).expect("memory");
    settle(&h, &mut twin, &approach(&h, 1.0), &p);
    settle(&h, &mut twin, &near, &p);
    twin.compact(&h);
    let mut steps = 0;
    loop {
        let done = cam.compact_as_needed(&h, 64);
        steps += 1;
        assert!(
            done.work > 0 && done.work <= 64 + 64,
            "a bounded step: {done:?}"
        );
        if done.finished {
            break;
        }
        assert!(cam.compacting());
        assert!(steps < 1_000_000, "the cycle ends");
    }
    assert!(steps > 1, "a cycle takes several bounded steps");
    assert_eq!(order(&h, &cam), order(&h, &twin));
    let after = cam.compact_as_needed(&h, 64);
    assert_eq!(
        (after.work, after.finished),
        (0, false),
        "no churn since the cycle began"
    );
}
