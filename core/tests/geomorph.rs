//! Geomorphs of view-dependent refinement on the golden hierarchy: every morphing vertex lies
//! between where its start is drawn and its own vertex, a split of a morphing vertex starts
//! its child where it is drawn, no vertex glides faster than the speed limit, morphed emission points exactly the
//! morphing corners at their slots, morphs last their duration in seconds whatever the frame
//! rate, aborted coarsen morphs return to the fine state, a camera whose morphs have all
//! finished emits what a camera without morphs emits, zero durations decide exactly as a
//! camera without morph memory, and a full morph memory drops morphs without failing.

mod common;

use std::collections::HashMap;

use caveclod_core::glam::{Vec3, Vec4Swizzles};
use caveclod_core::gpu::{morph_slot_vertex, MorphSlices};
use caveclod_core::{
    CameraConfig, CameraError, CameraState, Hierarchy, LookAt, NodeId, RefineParams, RefineStats,
};
use common::morphs::*;
use common::{golden_hierarchy, views};
use proptest::prelude::*;

#[test]
fn morph_memory_is_sized_and_bounded() {
    let h = golden_hierarchy();
    let plain = CameraState::words_needed_for(&h, &CameraConfig::full(&h));
    assert_eq!(plain, CameraState::words_needed(&h));
    for n in [1u32, 7, 300] {
        let words = CameraState::words_needed_for(&h, &morph_config(&h, n));
        let bits = h.vertices().len().div_ceil(32) + h.splits().len().div_ceil(32);
        let free = (n as usize).div_ceil(32);
        assert_eq!(
            words - plain,
            18 * n as usize + 2 + bits + free,
            "{n} morphs"
        );
    }
    let huge = morph_config(&h, u32::MAX / 2);
    let mut memory = vec![0u32; 16];
    assert_eq!(
        CameraState::with_config(&h, &mut memory, &huge).err(),
        Some(CameraError::TooManyMorphs {
            max_morphs: u32::MAX / 2,
            vertex_count: h.vertices().len() as u32,
        })
    );
    let mut memory = vec![0u32; CameraState::words_needed_for(&h, &morph_config(&h, 5))];
    let cam = CameraState::with_config(&h, &mut memory, &morph_config(&h, 5)).expect("memory");
    assert_eq!((cam.max_morphs(), cam.morph_count()), (5, 0));
    assert!(cam.morph_vertices().is_empty());
}

/// With both durations zero a camera with morph memory takes every decision a camera
/// without it takes, pass for pass, and emits the same indices in the same order.
#[test]
fn zero_durations_decide_as_a_camera_without_morphs() {
    let h = golden_hierarchy();
    let mut mem_m = MorphMemory::new(&h, 8);
    let mut mem_p = vec![0u32; CameraState::words_needed(&h)];
    let mut morphing = mem_m.camera(&h);
    let mut plain = CameraState::new(&h, &mut mem_p).expect("memory");
    let all = views(&h, 24);
    for (i, view) in all.iter().chain(all.iter().rev()).enumerate() {
        let p = common::params(i).without_morphs();
        let a = morphing.refine(&h, view, &p).expect("refine");
        let b = plain.refine(&h, view, &p).expect("refine");
        assert_eq!(a, b, "pass {i}");
        assert_eq!(a.morphs_started + a.morphs_dropped + a.morphing, 0);
        assert_eq!(packed(&h, &morphing, false), packed(&h, &plain, false));
        assert_eq!(packed(&h, &morphing, true), packed(&h, &plain, false));
        if i % 5 == 4 {
            morphing.compact(&h);
            plain.compact(&h);
        }
    }
}

/// With the view still after the pass that refined, every morph it started rises by
/// `dt / refine_morph_s` per pass, and ends after the same number of seconds at 30 and at
/// 60 passes per second.
#[test]
fn morphs_last_their_duration_in_seconds() {
    let h = golden_hierarchy();
    let view = approach(&h, 0.6);
    let mut passes_needed = Vec::new();
    for fps in [30.0f32, 60.0] {
        let mut memory = MorphMemory::new(&h, 256);
        let mut cam = memory.camera(&h);
        let p = RefineParams {
            dt_s: 1.0 / fps,
            ..fine()
        };
        let first = cam.refine(&h, &view, &p).expect("refine");
        assert!(first.splits > 0 && first.morphs_started > 0, "{first:?}");
        assert_eq!(first.morphs_dropped, 0);
        assert!(cam
            .morph_vertices()
            .iter()
            .all(|m| m.is_idle() || m.t == 0.0));
        let mut passes = 0;
        while cam.morph_count() > 0 {
            let st = cam.refine(&h, &view, &p).expect("refine");
            assert_eq!(st.operations(), 0, "one pass settles refinement: {st:?}");
            passes += 1;
            let want = (passes as f32 * p.dt_s / p.refine_morph_s).min(1.0);
            for m in cam.morph_vertices().iter().filter(|m| !m.is_idle()) {
                assert!(
                    (m.t - want).abs() < 1e-4,
                    "pass {passes}: {} for {want}",
                    m.t
                );
            }
            assert!(passes < 1000);
        }
        passes_needed.push(passes as f32 / fps);
    }
    let seconds = fine().refine_morph_s;
    for s in &passes_needed {
        assert!(
            (s - seconds).abs() <= 1.0 / 30.0 + 1e-4,
            "{passes_needed:?}"
        );
    }
}

/// A camera whose morphs have all finished emits exactly what it emits without morphing,
/// and the front (and its triangles) a camera without morph memory settles at.
#[test]
fn finished_morphs_emit_what_a_camera_without_morphs_emits() {
    let h = golden_hierarchy();
    let mut mem_m = MorphMemory::new(&h, 64);
    let mut mem_p = vec![0u32; CameraState::words_needed(&h)];
    let mut morphing = mem_m.camera(&h);
    let mut plain = CameraState::new(&h, &mut mem_p).expect("memory");
    let p = fine();
    let pos = position_of_vertex(&h);
    let mut seen = RefineStats::default();
    let mut on_seams = 0;
    // Under miri, one move in and one out (each view settles a fine front).
    let ks: &[f32] = if cfg!(miri) {
        &[0.4, 1.0]
    } else {
        &[0.0, 0.4, 1.0, 0.1, 0.7, 0.0]
    };
    for &k in ks {
        let view = approach(&h, k);
        // A few frames at this view, then settled.
        for _ in 0..6 {
            let st = morphing.refine(&h, &view, &p).expect("refine");
            on_seams += check_morphs(&h, &morphing, &pos);
            seen.morphs_started += st.morphs_started;
            seen.morphs_finished += st.morphs_finished;
        }
        seen.morphs_finished += settle(&h, &mut morphing, &view, &p);
        settle(&h, &mut plain, &view, &p);
        assert_eq!(morphing.morph_count(), 0);
        assert!(morphing.morph_vertices().is_empty());
        assert_eq!(packed(&h, &morphing, true), packed(&h, &morphing, false));
        assert_eq!(sorted_front(&morphing), sorted_front(&plain), "view {k}");
        assert_eq!(triangles(&h, &morphing), triangles(&h, &plain), "view {k}");
    }
    assert!(
        seen.morphs_started > 0 && seen.morphs_finished > 0,
        "{seen:?}"
    );
    assert!(
        on_seams > 0,
        "the golden terrain's seams morph two vertices per floating child"
    );
}

/// Moving away starts coarsen morphs; moving back before they end aborts them: each
/// returns to `t = 1` without a collapse and stops, and the camera is back at the fine
/// front.
#[test]
fn aborted_coarsen_morphs_return_to_the_fine_state() {
    let h = golden_hierarchy();
    let mut memory = MorphMemory::new(&h, 256);
    let mut cam = memory.camera(&h);
    let p = fine();
    let pos = position_of_vertex(&h);
    let (near, far) = (approach(&h, 0.0), approach(&h, 1.0));
    settle(&h, &mut cam, &near, &p);
    let fine_front = sorted_front(&cam);
    let fine_splits = cam.split_count();
    // Away for a few frames: coarsen morphs start (at 1) and fall, no collapse yet.
    let st = cam.refine(&h, &far, &p).expect("refine");
    assert!(st.morphs_started > 0, "{st:?}");
    assert_eq!(st.collapses, 0, "{st:?}");
    for _ in 0..3 {
        let st = cam.refine(&h, &far, &p).expect("refine");
        assert_eq!(st.collapses, 0, "{st:?}");
        check_morphs(&h, &cam, &pos);
    }
    let coarsening: HashMap<u32, f32> = cam
        .morph_vertices()
        .iter()
        .filter(|m| !m.is_idle())
        .map(|m| (m.to, m.t))
        .collect();
    assert!(!coarsening.is_empty());
    assert!(coarsening.values().all(|&t| t < 1.0), "{coarsening:?}");
    // Every morph coarsens, and its collapse still waits: the settled count leaves out
    // both polygons of each.
    assert_eq!(cam.coarsening_count(), cam.morph_count());
    assert_eq!(
        cam.settled_polygon_count(),
        cam.active_polygon_count() - 2 * cam.coarsening_count()
    );
    // Back: every coarsen morph aborts, rises, and ends at the fine position.
    let st = cam.refine(&h, &near, &p).expect("refine");
    assert_eq!(
        st.morphs_aborted as usize,
        cam.morph_count() as usize + st.morphs_finished as usize
    );
    assert!(st.morphs_aborted > 0, "{st:?}");
    assert_eq!(cam.coarsening_count(), 0, "every coarsen morph turned back");
    assert_eq!(cam.settled_polygon_count(), cam.active_polygon_count());
    let mut last = coarsening.clone();
    while cam.morph_count() > 0 {
        let st = cam.refine(&h, &near, &p).expect("refine");
        assert_eq!(st.collapses, 0, "{st:?}");
        check_morphs(&h, &cam, &pos);
        for m in cam.morph_vertices().iter().filter(|m| !m.is_idle()) {
            let before = last.insert(m.to, m.t).expect("no new morph");
            assert!(m.t >= before, "{} after {before}", m.t);
        }
    }
    assert_eq!(cam.split_count(), fine_splits);
    assert_eq!(sorted_front(&cam), fine_front);
}

/// A split nearby that makes a pending collapse illegal aborts its coarsen morph on the next
/// pass, before the vertex moves on; so does a split of the floating child itself.
#[test]
fn an_illegal_collapse_aborts_its_coarsen_morph() {
    let h = golden_hierarchy();
    let mut memory = MorphMemory::new(&h, 256);
    let mut cam = memory.camera(&h);
    let pos = position_of_vertex(&h);
    let far = approach(&h, 1.0);
    let mut neighbour_aborts = 0;
    let mut child_aborts = 0;
    // Each round: settle at a front partly refined, start coarsen morphs far, then make one
    // pending collapse illegal, by a neighbour's split in even rounds and by the floating
    // child's in odd ones.
    // Under miri, the coarsest tolerance alone (each round settles a front).
    let tolerances: &[f32] = if cfg!(miri) {
        &[2.0]
    } else {
        &[0.2, 0.5, 1.0, 2.0]
    };
    let rounds = tolerances.iter().flat_map(|&tol| {
        [0.0f32, 0.1, 0.3]
            .map(|k| (tol, k))
            .into_iter()
            .flat_map(|c| [c, c])
    });
    for (round, (tolerance_px, k)) in rounds.enumerate() {
        let p = RefineParams {
            tolerance_px,
            ..fine()
        };
        cam.reset(&h);
        settle(&h, &mut cam, &approach(&h, k), &p);
        cam.refine(&h, &far, &p).expect("refine");
        cam.refine(&h, &far, &p).expect("refine");
        let pending: Vec<(u32, f32)> = cam
            .morph_vertices()
            .iter()
            .filter(|m| !m.is_idle() && m.t < 1.0)
            .map(|m| (m.to, m.t))
            .collect();
        let by_child = round % 2 == 1;
        let mut target = None;
        'search: for &(to, t) in &pending {
            let (parent, floating) = morph_pair(&h, &cam, &pos, to);
            assert!(cam.can_collapse(&h, parent));
            if by_child {
                if h.split(floating).is_some() {
                    cam.force_split_own_stack(&h, floating)
                        .expect("forced split");
                    target = Some((to, t));
                    break 'search;
                }
                continue;
            }
            let sp = h.split(parent).expect("a split");
            let nodes: Vec<NodeId> = cam.active_nodes().collect();
            for w in nodes {
                if w == sp.stationary || w == sp.floating || !cam.can_split(&h, w) {
                    continue;
                }
                cam.split(&h, w).expect("legal split");
                if !cam.can_collapse(&h, parent) {
                    target = Some((to, t));
                    break 'search;
                }
                cam.collapse(&h, w).expect("undo");
            }
        }
        let Some((to, t)) = target else {
            continue;
        };
        let st = cam.refine(&h, &far, &p).expect("refine");
        assert!(st.morphs_aborted > 0, "round {round}: {st:?}");
        let now = cam
            .morph_vertices()
            .iter()
            .find(|m| m.to == to)
            .map_or(1.0, |m| m.t);
        assert!(
            now > t,
            "round {round}: the aborted morph rises ({t} -> {now})"
        );
        check_morphs(&h, &cam, &pos);
        if by_child {
            child_aborts += 1;
        } else {
            neighbour_aborts += 1;
        }
    }
    assert!(
        neighbour_aborts > 0 && child_aborts > 0,
        "{neighbour_aborts} {child_aborts}"
    );
}

/// Coarsen morphs that reach 0 collapse; moving away for good ends at the far front of a
/// camera without morphs, and every collapse on the way came after its morph.
#[test]
fn coarsen_morphs_collapse_when_they_end() {
    let h = golden_hierarchy();
    let mut memory = MorphMemory::new(&h, 256);
    let mut cam = memory.camera(&h);
    let mut plain_memory = vec![0u32; CameraState::words_needed(&h)];
    let mut plain = CameraState::new(&h, &mut plain_memory).expect("memory");
    let p = fine();
    let (near, far) = (approach(&h, 0.0), approach(&h, 1.0));
    settle(&h, &mut cam, &near, &p);
    settle(&h, &mut plain, &far, &p);
    let mut total = RefineStats::default();
    for _ in 0..2000 {
        let before = cam.active_polygon_count();
        let st = cam.refine(&h, &far, &p).expect("refine");
        assert!(cam.coarsening_count() <= cam.morph_count());
        // Moving away only collapses: the polygons on the screen never grow.
        assert!(cam.active_polygon_count() <= before);
        total.collapses += st.collapses;
        total.morphs_started += st.morphs_started;
        total.morphs_finished += st.morphs_finished;
        if st.operations() == 0 && st.morphing == 0 {
            break;
        }
    }
    assert!(total.collapses > 0);
    assert_eq!(cam.coarsening_count(), 0);
    assert_eq!(cam.settled_polygon_count(), cam.active_polygon_count());
    // The view is in the frustum, so every collapse waited for its coarsen morph.
    assert_eq!(total.morphs_finished, total.collapses, "{total:?}");
    assert_eq!(sorted_front(&cam), sorted_front(&plain));
}

/// A morph memory of one morph holds one at a time; every other split of a visible node
/// happens at once and is counted, and the splits are those a camera without morphs makes.
#[test]
fn a_full_morph_memory_drops_morphs_and_counts_them() {
    let h = golden_hierarchy();
    let mut memory = MorphMemory::new(&h, 1);
    let mut cam = memory.camera(&h);
    let mut plain_memory = vec![0u32; CameraState::words_needed(&h)];
    let mut plain = CameraState::new(&h, &mut plain_memory).expect("memory");
    let p = fine();
    let view = approach(&h, 0.6);
    let a = cam.refine(&h, &view, &p).expect("refine");
    let b = plain.refine(&h, &view, &p).expect("refine");
    assert_eq!(without_morph_counts(a), b);
    assert_eq!((a.morphs_started, a.morphing), (1, 1), "{a:?}");
    assert!(a.morphs_dropped > 0, "{a:?}");
    assert!(a.morphs_started + a.morphs_dropped <= a.splits, "{a:?}");
    assert!(cam.morph_vertices().len() <= 2);
    check_morphs(&h, &cam, &position_of_vertex(&h));
}

/// Splits and collapses outside the view (of positions that do not morph) happen at once:
/// with the terrain behind the eye nothing morphs.
#[test]
fn nodes_outside_the_view_split_and_collapse_at_once() {
    let h = golden_hierarchy();
    let mut memory = MorphMemory::new(&h, 256);
    let mut cam = memory.camera(&h);
    let p = fine();
    // Far enough that no bounding sphere holds the eye.
    let view = approach(&h, 0.6);
    let st = cam.refine(&h, &view, &p).expect("refine");
    assert!(st.morphs_started > 0 && st.splits > 0, "{st:?}");
    // A position still morphing is drawn away from its node's bounds, so its operations
    // morph wherever the node is: end the morphs, then no position morphs.
    cam.finish_morphs();
    // The same eye looking the other way: everything leaves the frustum.
    let m = h.meta();
    let centre = (Vec3::from_array(m.bounds_min) + Vec3::from_array(m.bounds_max)) * 0.5;
    let size = (Vec3::from_array(m.bounds_max) - Vec3::from_array(m.bounds_min)).length();
    let away = LookAt {
        eye: view.eye,
        target: view.eye + (view.eye - centre),
        up: Vec3::Y,
        fov_y: 1.2,
        near: size * 1e-3,
        far: size * 100.0,
    }
    .view(1280, 720);
    // Coarsening takes a pass per level (a collapse waits for its children's).
    let mut passes = 0;
    loop {
        let st = cam.refine(&h, &away, &p).expect("refine");
        assert_eq!(st.morphs_started + st.morphs_dropped, 0, "{st:?}");
        if st.operations() == 0 {
            break;
        }
        passes += 1;
        assert!(passes < 100);
    }
    assert!(passes > 0);
    assert_eq!(cam.split_count(), 0, "nothing visible stays refined");
    assert_eq!(cam.morph_count(), 0);
}

/// Turning morphs off ends them in one pass: refine morphs snap to the fine position,
/// coarsen morphs collapse.
#[test]
fn durations_set_to_zero_end_every_morph() {
    let h = golden_hierarchy();
    let mut memory = MorphMemory::new(&h, 256);
    let mut cam = memory.camera(&h);
    let p = fine();
    let (near, mid) = (approach(&h, 0.0), approach(&h, 0.3));
    settle(&h, &mut cam, &near, &p);
    cam.refine(&h, &mid, &p).expect("refine");
    assert!(cam.morph_count() > 0);
    let st = cam.refine(&h, &mid, &p.without_morphs()).expect("refine");
    assert_eq!(st.morphing, 0, "{st:?}");
    assert!(cam.morph_vertices().is_empty());
    // And `finish_morphs` ends them without refining.
    cam.refine(&h, &near, &p).expect("refine");
    assert!(cam.morph_count() > 0);
    let front = sorted_front(&cam);
    cam.finish_morphs();
    assert_eq!(cam.morph_count(), 0);
    assert_eq!(sorted_front(&cam), front);
    assert_eq!(packed(&h, &cam, true), packed(&h, &cam, false));
}

/// 64 cases; under miri 2, and no regression file (miri isolates the file system).
/// Where each morphing vertex (by its `to`) is drawn.
fn drawn(h: &Hierarchy<'_>, cam: &CameraState<'_>) -> HashMap<u32, Vec3> {
    let inputs = MorphSlices {
        vertices: h.vertices(),
        slots: cam.morph_vertices(),
    };
    inputs
        .slots
        .iter()
        .enumerate()
        .filter(|(_, m)| !m.is_idle())
        .map(|(s, m)| {
            let v = morph_slot_vertex(&inputs, s as u32).expect("a live slot");
            (m.to, Vec3::from_array(v.position))
        })
        .collect()
}

/// Views along one approach, nearer each frame.
fn closing_in(h: &Hierarchy<'_>, frames: usize) -> Vec<LookAt> {
    (0..frames)
        .map(|f| approach_look(h, 3.0 - 2.6 * f as f32 / frames as f32))
        .collect()
}

/// A split of a vertex that still morphs starts its floating child where that vertex is
/// drawn (its slot's `from` names the parent's slot), so the child appears without a jump.
#[test]
fn a_split_of_a_morphing_vertex_starts_where_it_is_drawn() {
    let h = golden_hierarchy();
    let mut memory = MorphMemory::new(&h, 512);
    let mut cam = memory.camera(&h);
    let pos = position_of_vertex(&h);
    let vc = h.vertices().len() as u32;
    let p = fine();
    let mut chained = 0;
    let mut before = drawn(&h, &cam);
    // Miri runs a few frames of the approach: the invariants, not the occurrence.
    let frames = if cfg!(miri) { 6 } else { 120 };
    for look in closing_in(&h, frames) {
        cam.refine(&h, &look.view(1280, 720), &p).expect("refine");
        check_morphs(&h, &cam, &pos);
        let now = drawn(&h, &cam);
        for m in cam
            .morph_vertices()
            .iter()
            .filter(|m| !m.is_idle() && m.t == 0.0)
        {
            if before.contains_key(&m.to) || m.from < vc {
                continue;
            }
            // Started this pass from a morphing vertex: it stands where that one stands.
            let parent = now[&m.coarse];
            assert!((now[&m.to] - parent).length() <= 1e-5 * (1.0 + parent.length()));
            chained += 1;
        }
        before = now;
    }
    assert!(chained > 0 || cfg!(miri), "no split of a morphing vertex");
}

/// However far a floating child lies from its parent on the screen, its vertex moves no
/// more than the speed limit allows per pass (twice that for chains, whose links each take
/// half their parent's share), measured in the view's own pixels.
#[test]
#[cfg_attr(
    miri,
    ignore = "screen measures over many passes; the chains' memory safety is the proptest's"
)]
fn morphs_glide_no_faster_than_the_speed_limit() {
    let h = golden_hierarchy();
    let mut memory = MorphMemory::new(&h, 512);
    let mut cam = memory.camera(&h);
    let speed = 30.0;
    let p = RefineParams {
        morph_speed_px_s: speed,
        ..fine()
    };
    let looks = closing_in(&h, 60);
    let (w, hgt) = (1280u32, 720u32);
    let pixel = |look: &LookAt, x: Vec3| {
        let c = look.view_projection(w as f32 / hgt as f32) * x.extend(1.0);
        (c.xy() / c.w) * caveclod_core::glam::Vec2::new(w as f32, hgt as f32) * 0.5
    };
    let mut slowed = false;
    let mut before = HashMap::new();
    for (f, look) in looks.iter().enumerate() {
        // Hold every other view for a few passes so morphs run under a still view.
        for _ in 0..if f % 2 == 0 { 1 } else { 8 } {
            cam.refine(&h, &look.view(w, hgt), &p).expect("refine");
            let now = drawn(&h, &cam);
            for (to, &b) in &now {
                if let Some(&a) = before.get(to) {
                    let moved = (pixel(look, b) - pixel(look, a)).length();
                    assert!(moved <= 2.0 * speed * p.dt_s * 1.01, "{moved} px");
                }
            }
            before = now;
        }
        // A morph slower than its duration: the limit bites somewhere.
        slowed |= cam
            .morph_vertices()
            .iter()
            .any(|m| !m.is_idle() && m.t > 0.0 && m.t < 0.5 * p.dt_s / p.refine_morph_s);
    }
    assert!(slowed, "the speed limit never slowed a morph");
}

/// One frame of a random flight: a view, a frame time, a tolerance, an operation budget.
fn frame() -> impl Strategy<Value = (usize, f32, f32, u32)> {
    (
        0usize..12,
        prop::sample::select(vec![0.0f32, 1.0 / 240.0, 1.0 / 60.0, 1.0 / 20.0, 0.4]),
        prop::sample::select(vec![0.05f32, 0.3, 2.0]),
        prop::sample::select(vec![u32::MAX, 3, 20]),
    )
}

/// With a bound on the nodes' screen radius, a settled morphing camera leaves no visible
/// node whose sphere projects larger than the bound allows, splitting nodes that its errors
/// alone would leave; without morph memory, or with the bound off, the errors alone decide.
#[test]
fn the_radius_bound_splits_nodes_large_on_the_screen() {
    let h = golden_hierarchy();
    let view = approach(&h, 0.6);
    let bound = 4.0;
    let p = RefineParams {
        tolerance_px: 3.0,
        morph_radius_tolerances: bound,
        ..fine()
    };
    let mut memory = MorphMemory::new(&h, 256);
    let mut cam = memory.camera(&h);
    settle(&h, &mut cam, &view, &p);
    let mut plain_memory = vec![0u32; CameraState::words_needed(&h)];
    let mut plain = CameraState::new(&h, &mut plain_memory).expect("memory");
    settle(&h, &mut plain, &view, &p);
    let mut unbounded_memory = MorphMemory::new(&h, 256);
    let mut unbounded = unbounded_memory.camera(&h);
    let off = RefineParams {
        morph_radius_tolerances: f32::INFINITY,
        ..p
    };
    settle(&h, &mut unbounded, &view, &off);
    assert_eq!(sorted_front(&unbounded), sorted_front(&plain));
    assert!(
        cam.active_node_count() > plain.active_node_count(),
        "{} against {}",
        cam.active_node_count(),
        plain.active_node_count()
    );
    let mut bounded = 0;
    for node in cam.active_nodes() {
        let Some(b) = h.split_bounds(node) else {
            continue;
        };
        let centre = Vec3::from_array(b.point);
        if !view.sphere_visible(centre, b.radius) {
            continue;
        }
        let px = b.radius * view.pixels_per_radian / (centre - view.eye).length();
        assert!(px <= bound * p.tolerance_px * 1.001, "{node:?}: {px} px");
        bounded += 1;
    }
    let with_bounds = cam
        .active_nodes()
        .filter(|&n| h.split_bounds(n).is_some())
        .count();
    assert!(
        bounded > 0,
        "no visible node left to check: {} active, {with_bounds} with bounds, plain {}",
        cam.active_node_count(),
        plain.active_node_count()
    );
}

proptest! {
    #![proptest_config(common::proptest_config(64, 2))]

    /// Over any flight, any frame times and any morph memory, every morphing vertex lies
    /// between its endpoints and morphed emission agrees with the plain one; once the
    /// camera holds still every morph ends, at the front a camera without morph memory
    /// settles at after the same flight against the views widened by the guard band.
    #[test]
    fn morphs_stay_between_their_endpoints(
        max_morphs in 1u32..40,
        frames in prop::collection::vec(frame(), 1..if cfg!(miri) { 4 } else { 40 }),
    ) {
        let h = golden_hierarchy();
        let pos = position_of_vertex(&h);
        let mut all = views(&h, 6);
        all.extend((0..6).map(|k| approach(&h, k as f32 / 5.0)));
        let mut memory = MorphMemory::new(&h, max_morphs);
        let mut cam = memory.camera(&h);
        let mut plain_memory = vec![0u32; CameraState::words_needed(&h)];
        let mut plain = CameraState::new(&h, &mut plain_memory).expect("memory");
        let mut last = None;
        for (i, &(v, dt_s, tolerance_px, max_ops)) in frames.iter().enumerate() {
            let p = RefineParams { dt_s, tolerance_px, max_ops, ..RefineParams::default() };
            plain.refine(&h, &all[v].widened(p.morph_guard_rad), &p).expect("refine");
            let st = cam.refine(&h, &all[v], &p).expect("refine");
            prop_assert_eq!(st.morphing, cam.morph_count());
            prop_assert!(cam.morph_count() <= max_morphs);
            prop_assert!(cam.coarsening_count() <= cam.morph_count());
            prop_assert!(cam.settled_polygon_count() <= cam.active_polygon_count());
            check_morphs(&h, &cam, &pos);
            if i % 7 == 6 {
                cam.compact(&h);
                check_morphs(&h, &cam, &pos);
            }
            last = Some((v, p));
        }
        let (v, p) = last.expect("a frame");
        // Without the speed limit, so morphs near the eye end within the settling passes.
        let p = RefineParams { dt_s: 1.0 / 60.0, max_ops: u32::MAX, morph_speed_px_s: 0.0, ..p };
        settle(&h, &mut cam, &all[v], &p);
        settle(&h, &mut plain, &all[v].widened(p.morph_guard_rad), &p);
        prop_assert!(cam.morph_vertices().is_empty());
        prop_assert_eq!(cam.coarsening_count(), 0);
        prop_assert_eq!(packed(&h, &cam, true), packed(&h, &cam, false));
        prop_assert_eq!(sorted_front(&cam), sorted_front(&plain));
        prop_assert_eq!(triangles(&h, &cam), triangles(&h, &plain));
    }
}
