//! Criterion benchmarks of the runtime on a terrain of about a million polygons
//! (`terrain(708, 708)`: 1,002,528 triangles), baked once per run outside the timed code.
//!
//! - `ops/split_collapse`: a precomputed legal sequence of every split of the hierarchy,
//!   then the collapses in reverse order (throughput: operations).
//! - `ops/refine_near_far`: refinement from the settled far front to the settled near front
//!   and back: splits (forced ones included) and collapses in the order refinement makes
//!   them, with the visits around them (throughput: operations).
//! - `refine/settled_pass`: one refine pass over the settled near front (at least 100k active
//!   polygons) from the same view: temporal coherence at rest (throughput: active polygons).
//! - `refine/moving_pass`: one refine pass per iteration while the camera flies a small step
//!   per iteration (throughput: active polygons).
//! - `emit/packed`: index emission of the settled near front (throughput: polygons).
//! - `frame/moving_refine_emit`: a moving refine pass plus emission, Hoppe's "faces per
//!   second including refinement" (throughput: active polygons).
//! - `geomorph/moving_pass`, `geomorph/emit_packed_morphed`: the moving pass and the
//!   emission of a camera with morph memory at the default durations and 60 passes per
//!   second; its baseline is `refine/moving_pass` and `emit/packed` (throughput: active
//!   polygons).
//! - `cameras/round_robin`, `cameras/one_at_a_time`: four budgeted cameras over four
//!   stretches of the terrain, the same passes in turn or each camera several in a row
//!   (throughput: active polygons).
//!
//! `cargo bench -p caveclod-benches`; `CAVECLOD_BENCH_SIZE=N` changes the terrain. Without
//! `--bench` (as `cargo test --benches` runs it) each benchmark runs once on a small terrain.

use std::cell::Cell;
use std::time::{Duration, Instant};

use caveclod_benches::low_pass_view;
use caveclod_core::glam::Vec3;
use caveclod_core::{
    CameraConfig, CameraState, Hierarchy, LookAt, NodeId, RefineParams, RefineStats, View,
};
use caveclod_io::CameraPool;
use caveclod_tests::{bake, meshes};
use criterion::{Criterion, Throughput};

const SEED: u64 = 7;
const HEIGHT: f32 = 720.0;
const ASPECT: f32 = 1280.0 / 720.0;
const FOV_Y_DEG: f32 = 60.0;

/// Terrain heights on the grid.
struct Ground {
    n: u32,
    heights: Vec<f32>,
}

impl Ground {
    fn at(&self, x: f32, z: f32) -> f32 {
        let i = (x.round().max(0.0) as u32).min(self.n);
        let j = (z.round().max(0.0) as u32).min(self.n);
        self.heights
            .get((j * (self.n + 1) + i) as usize)
            .copied()
            .unwrap_or(0.0)
    }
}

/// A low camera at fraction `u` of the terrain's diagonal, flying along it, looking ahead
/// and 15 degrees down: the flyover's straight pass.
fn view_at(u: f32, size: f32, ground: &Ground) -> View {
    let p = size * (0.15 + 0.7 * u);
    let forward = Vec3::new(1.0, 0.0, 1.0).normalize();
    let mut floor = f32::MIN;
    for k in 0..=6 {
        let d = 0.03 * size * k as f32 / 6.0;
        floor = floor.max(ground.at(p + forward.x * d, p + forward.z * d));
    }
    let eye = Vec3::new(p, floor + 0.015 * size, p);
    low_pass_view(eye, forward, 2.0 * size)
}

/// A view from far above the terrain's centre, where the base mesh is nearly enough.
fn far_view(size: f32) -> View {
    let c = 0.5 * size;
    let eye = Vec3::new(c, 40.0 * size, c + 1.0);
    let look = LookAt {
        eye,
        target: Vec3::new(c, 0.0, c),
        up: Vec3::Y,
        fov_y: FOV_Y_DEG.to_radians(),
        near: 1.0,
        far: 100.0 * size,
    };
    look.view((HEIGHT * ASPECT) as u32, HEIGHT as u32)
}

/// Frames of the moving path between two compactions in the `compact/` benches: the demo
/// compacts every 30 frames.
const CHURN_FRAMES: usize = 30;

/// Refines until a pass changes nothing; returns the operations applied.
fn settle(cam: &mut CameraState<'_>, h: &Hierarchy<'_>, view: &View, p: &RefineParams) -> u64 {
    let mut ops = 0;
    for _ in 0..1000 {
        let st = must(cam.refine(h, view, p));
        ops += u64::from(st.operations());
        if st.operations() == 0 {
            return ops;
        }
    }
    panic!("refinement did not settle in 1000 passes");
}

/// Refines once at every view of `moving` in turn (untimed, back to the first view's
/// neighbourhood); returns the mean number of active polygons.
fn lap(cam: &mut CameraState<'_>, h: &Hierarchy<'_>, moving: &[View], p: &RefineParams) -> u64 {
    let mut sum = 0u64;
    for v in moving.iter().skip(1).chain(moving.first()) {
        sum += u64::from(must(cam.refine(h, v, p)).active_polygons);
    }
    eprintln!(
        "moving path: {} views, {:.0} active polygons on average",
        moving.len(),
        sum as f64 / moving.len() as f64
    );
    sum / moving.len().max(1) as u64
}

fn must<T, E: std::fmt::Display>(r: Result<T, E>) -> T {
    r.unwrap_or_else(|e| panic!("{e}"))
}

/// Every split of the hierarchy in a legal order: rounds over the waiting nodes, splitting
/// each one whose neighbours are active (no forced splits needed).
fn split_sequence(h: &Hierarchy<'_>, cam: &mut CameraState<'_>) -> Vec<NodeId> {
    cam.reset(h);
    let mut seq = Vec::with_capacity(h.splits().len());
    let mut waiting: Vec<NodeId> = h.roots().to_vec();
    loop {
        let mut next = Vec::with_capacity(waiting.len() * 2);
        let before = seq.len();
        for v in waiting {
            let Some(s) = h.split(v) else { continue };
            if cam.can_split(h, v) {
                must(cam.split(h, v));
                seq.push(v);
                next.push(s.stationary);
                next.push(s.floating);
            } else {
                next.push(v);
            }
        }
        waiting = next;
        if seq.len() == before {
            break;
        }
    }
    cam.reset(h);
    seq
}

fn bench_ops(c: &mut Criterion, h: &Hierarchy<'_>, near: &View, far: &View) {
    let mut memory = vec![0u32; CameraState::words_needed(h)];
    let mut cam = must(CameraState::new(h, &mut memory));
    let t = Instant::now();
    let seq = split_sequence(h, &mut cam);
    eprintln!(
        "split sequence: {} of {} splits, found in {:.2} s",
        seq.len(),
        h.splits().len(),
        t.elapsed().as_secs_f64()
    );
    let mut g = c.benchmark_group("ops");
    g.throughput(Throughput::Elements(2 * seq.len() as u64));
    g.bench_function("split_collapse", |b| {
        b.iter(|| {
            let mut failed = 0u32;
            for &v in &seq {
                failed += u32::from(cam.split(h, v).is_err());
            }
            for &v in seq.iter().rev() {
                failed += u32::from(cam.collapse(h, v).is_err());
            }
            failed
        })
    });
    // Correctness of what was timed, checked outside the timing.
    for &v in &seq {
        must(cam.split(h, v));
    }
    assert_eq!(cam.split_count() as usize, seq.len());
    for &v in seq.iter().rev() {
        must(cam.collapse(h, v));
    }
    assert_eq!(cam.split_count(), 0);

    // Refinement-driven operations: far front <-> near front.
    let p = RefineParams::default();
    cam.reset(h);
    settle(&mut cam, h, far, &p);
    let round = |cam: &mut CameraState<'_>| settle(cam, h, near, &p) + settle(cam, h, far, &p);
    let ops_per_round = round(&mut cam);
    let total = Cell::new((0u64, Duration::ZERO));
    g.throughput(Throughput::Elements(ops_per_round));
    g.bench_function("refine_near_far", |b| {
        b.iter_custom(|iters| {
            let start = Instant::now();
            let mut ops = 0;
            for _ in 0..iters {
                ops += round(&mut cam);
            }
            let el = start.elapsed();
            let (o, d) = total.get();
            total.set((o + ops, d + el));
            el
        })
    });
    g.finish();
    let (ops, d) = total.get();
    if ops > 0 {
        eprintln!(
            "ops/refine_near_far: {ops_per_round} ops per round (far -> near -> far); measured \
             over all iterations: {:.2} M ops/s",
            ops as f64 / d.as_secs_f64() / 1e6
        );
    }
}

fn bench_refine(c: &mut Criterion, h: &Hierarchy<'_>, near: &View, moving: &[View]) {
    let p = RefineParams::default();
    let mut memory = vec![0u32; CameraState::words_needed(h)];
    let mut cam = must(CameraState::new(h, &mut memory));
    let t = Instant::now();
    let ops = settle(&mut cam, h, near, &p);
    let active = cam.active_polygon_count();
    eprintln!(
        "settled near front: {active} active polygons, {} active nodes ({ops} ops, {:.3} s)",
        cam.active_node_count(),
        t.elapsed().as_secs_f64()
    );
    let mut g = c.benchmark_group("refine");
    g.throughput(Throughput::Elements(u64::from(active)));
    g.bench_function("settled_pass", |b| b.iter(|| must(cam.refine(h, near, &p))));
    // The baseline in the same run: every pass forgets the certificates first, so it reads
    // every bound it asks about (plus one sweep of the records to forget them).
    g.bench_function("settled_pass_uncertified", |b| {
        b.iter(|| {
            cam.forget_certificates();
            must(cam.refine(h, near, &p))
        })
    });

    // Moving camera: start settled at the first view, then one step per iteration. One
    // untimed lap of the path measures the front it carries on average.
    cam.reset(h);
    settle(&mut cam, h, &moving[0], &p);
    let mean_front = lap(&mut cam, h, moving, &p);
    g.throughput(Throughput::Elements(mean_front));
    let mut k = 0usize;
    let acc = Cell::new((0u64, 0u64, 0u64));
    let mut step = |cam: &mut CameraState<'_>| -> RefineStats {
        k = (k + 1) % moving.len();
        let st = must(cam.refine(h, &moving[k], &p));
        let (n, o, a) = acc.get();
        acc.set((
            n + 1,
            o + u64::from(st.operations()),
            a + u64::from(st.active_polygons),
        ));
        st
    };
    g.bench_function("moving_pass", |b| b.iter(|| step(&mut cam)));
    g.bench_function("moving_pass_uncertified", |b| {
        b.iter(|| {
            cam.forget_certificates();
            step(&mut cam)
        })
    });
    g.finish();
    let (n, o, a) = acc.get();
    if n > 0 {
        eprintln!(
            "refine/moving_pass: {:.1} ops and {:.0} active polygons per pass on average ({n} \
             passes)",
            o as f64 / n as f64,
            a as f64 / n as f64
        );
    }
}

/// Budgeted cameras, as the demo sizes them (the largest front of a lap of the moving path,
/// plus 10%): one with the split-to-pair map as an array by node (the default), one with it
/// hashed (`CameraConfig::hashed_pair_map`), each stepping along the moving path; the
/// array is the hashed map's baseline in the same run.
/// The largest front a full-capacity camera reaches over one lap of each path, each from
/// the front settled for the path's first view: what the demo sizes its cameras by.
fn largest_front(h: &Hierarchy<'_>, paths: &[&[View]], p: &RefineParams) -> u32 {
    let mut memory = vec![0u32; CameraState::words_needed(h)];
    let mut full = must(CameraState::new(h, &mut memory));
    let mut largest = 0;
    for path in paths {
        full.reset(h);
        settle(&mut full, h, &path[0], p);
        largest = largest.max(full.active_polygon_count());
        for v in path.iter().skip(1).chain(path.first()) {
            largest = largest.max(must(full.refine(h, v, p)).active_polygons);
        }
    }
    largest
}

fn bench_budgeted(c: &mut Criterion, h: &Hierarchy<'_>, moving: &[View]) {
    let p = RefineParams::default();
    let largest = largest_front(h, &[moving], &p);
    let array = CameraConfig::with_polygon_budget(h, largest + largest / 10);
    let hashed = CameraConfig {
        hashed_pair_map: true,
        ..array
    };
    let mut mem_a = vec![0u32; CameraState::words_needed_for(h, &array)];
    let mut mem_h = vec![0u32; CameraState::words_needed_for(h, &hashed)];
    let mut a = must(CameraState::with_config(h, &mut mem_a, &array));
    let mut b = must(CameraState::with_config(h, &mut mem_h, &hashed));
    eprintln!(
        "budgeted cameras: {} polygons, {} bytes with the array, {} hashed",
        largest + largest / 10,
        a.bytes(),
        b.bytes()
    );
    if b.bytes() >= a.bytes() {
        // A small terrain (as `cargo test --benches` runs it) fronts too much of the
        // hierarchy for a table to be smaller: both cameras then keep the array.
        eprintln!("the budget is too large to hash here: both cameras keep the array");
    }
    let mut g = c.benchmark_group("budgeted");
    for (name, cam) in [
        ("moving_pass", &mut a),
        ("moving_pass_hashed_pair_map", &mut b),
    ] {
        settle(cam, h, &moving[0], &p);
        let mean_front = lap(cam, h, moving, &p);
        g.throughput(Throughput::Elements(mean_front));
        let mut k = 0usize;
        g.bench_function(name, |bch| {
            bch.iter(|| {
                k = (k + 1) % moving.len();
                must(cam.refine(h, &moving[k], &p))
            })
        });
    }
    g.finish();
    // The same steps for both cameras, then the same emission.
    for cam in [&mut a, &mut b] {
        cam.reset(h);
        settle(cam, h, &moving[0], &p);
        lap(cam, h, moving, &p);
    }
    same_emission(h, &a, &b, "the pair map's layout changes no index");
}

fn bench_emit(c: &mut Criterion, h: &Hierarchy<'_>, near: &View, moving: &[View]) {
    let p = RefineParams::default();
    let mut memory = vec![0u32; CameraState::words_needed(h)];
    let mut cam = must(CameraState::new(h, &mut memory));
    // The same-run baseline: a camera without the index cache looks every polygon up.
    let plain_config = CameraConfig {
        index_cache: false,
        ..CameraConfig::full(h)
    };
    let mut plain_memory = vec![0u32; CameraState::words_needed_for(h, &plain_config)];
    let mut plain = must(CameraState::with_config(
        h,
        &mut plain_memory,
        &plain_config,
    ));
    settle(&mut cam, h, near, &p);
    settle(&mut plain, h, near, &p);
    let polys = cam.active_polygon_count();
    let mut out = vec![0u32; 3 * h.polygon_count()];
    let mut offsets = vec![0u32; h.surface_count() + 1];
    let mut g = c.benchmark_group("emit");
    g.throughput(Throughput::Elements(u64::from(polys)));
    g.bench_function("packed", |b| {
        b.iter(|| must(cam.emit_indices_packed(h, &mut out, &mut offsets)))
    });
    g.bench_function("packed_looked_up", |b| {
        b.iter(|| must(plain.emit_indices_packed(h, &mut out, &mut offsets)))
    });
    g.finish();
    let n = same_emission(h, &cam, &plain, "the index cache emits what a lookup finds");
    assert_eq!(n, 3 * polys as usize);

    // A whole frame of a moving camera: refine, then emit.
    let mut g = c.benchmark_group("frame");
    for (name, cam) in [
        ("moving_refine_emit", &mut cam),
        ("moving_refine_emit_looked_up", &mut plain),
    ] {
        cam.reset(h);
        settle(cam, h, &moving[0], &p);
        let mean_front = lap(cam, h, moving, &p);
        let mut k = 0usize;
        let acc = Cell::new((0u64, 0u64));
        g.throughput(Throughput::Elements(mean_front));
        g.bench_function(name, |b| {
            b.iter(|| {
                k = (k + 1) % moving.len();
                must(cam.refine(h, &moving[k], &p));
                let n = must(cam.emit_indices_packed(h, &mut out, &mut offsets));
                let (f, t) = acc.get();
                acc.set((f + 1, t + n as u64 / 3));
                n
            })
        });
        let (f, t) = acc.get();
        if f > 0 {
            eprintln!(
                "frame/{name}: {:.0} polygons emitted per frame on average (throughput above \
                 uses the lap's mean front, {mean_front})",
                t as f64 / f as f64
            );
        }
    }
    g.finish();

    // Compaction of a front churned as the demo churns it between compactions: each
    // iteration refines through the next 30 views of the moving path (untimed), then
    // compacts (timed). With the index cache the pairs' entries move with them.
    let mut g = c.benchmark_group("compact");
    for (name, cam) in [("front", &mut cam), ("front_without_cache", &mut plain)] {
        cam.reset(h);
        settle(cam, h, &moving[0], &p);
        let mean_front = lap(cam, h, moving, &p);
        g.throughput(Throughput::Elements(mean_front));
        let mut next = 0usize;
        g.bench_function(name, |b| {
            b.iter_custom(|iters| {
                let mut timed = Duration::ZERO;
                for _ in 0..iters {
                    for _ in 0..CHURN_FRAMES {
                        next = (next + 1) % moving.len();
                        must(cam.refine(h, &moving[next], &p));
                    }
                    let t = Instant::now();
                    cam.compact(h);
                    timed += t.elapsed();
                }
                timed
            })
        });
    }
    g.finish();
    // The same steps for both cameras, then the same emission.
    for cam in [&mut cam, &mut plain] {
        cam.reset(h);
        settle(cam, h, &moving[0], &p);
        lap(cam, h, moving, &p);
        cam.compact(h);
    }
    same_emission(h, &cam, &plain, "compaction keeps the two cameras alike");
}

/// Morphs a camera on the moving path holds at most: the splits and collapses of visible
/// nodes within a morph's duration, with room to spare.
const MAX_MORPHS: u32 = 4096;

fn bench_geomorphs(c: &mut Criterion, h: &Hierarchy<'_>, moving: &[View]) {
    let p = RefineParams::default();
    let config = CameraConfig::full(h).with_morphs(MAX_MORPHS);
    let mut memory = vec![0u32; CameraState::words_needed_for(h, &config)];
    let mut cam = must(CameraState::with_config(h, &mut memory, &config));
    settle(&mut cam, h, &moving[0], &p);
    let mean_front = lap(&mut cam, h, moving, &p);
    let mut g = c.benchmark_group("geomorph");
    g.throughput(Throughput::Elements(mean_front));
    let mut k = 0usize;
    let acc = Cell::new((0u64, 0u64, 0u64));
    g.bench_function("moving_pass", |b| {
        b.iter(|| {
            k = (k + 1) % moving.len();
            let st = must(cam.refine(h, &moving[k], &p));
            let (n, m, d) = acc.get();
            acc.set((
                n + 1,
                m + u64::from(st.morphing),
                d + u64::from(st.morphs_dropped),
            ));
            st
        })
    });
    let mut out = vec![0u32; 3 * h.polygon_count()];
    let mut offsets = vec![0u32; h.surface_count() + 1];
    let morphing = cam.morph_count();
    g.bench_function("emit_packed_morphed", |b| {
        b.iter(|| must(cam.emit_indices_packed_morphed(h, &mut out, &mut offsets)))
    });
    g.finish();
    let (n, m, d) = acc.get();
    if n > 0 {
        eprintln!(
            "geomorph/moving_pass: {:.0} morphs in progress and {:.1} dropped per pass on \
             average ({n} passes); emission timed with {morphing} morphs",
            m as f64 / n as f64,
            d as f64 / n as f64
        );
    }
    // What was timed: morphed emission is the plain one with the morphing corners at their
    // slots, and with the morphs ended it is the plain one.
    let n = must(cam.emit_indices_packed_morphed(h, &mut out, &mut offsets));
    let mut plain = vec![0u32; n];
    must(cam.emit_indices_packed(h, &mut plain, &mut offsets));
    let vertices = h.vertices().len();
    let slots = cam.morph_vertices();
    for (&morphed, &i) in out[..n].iter().zip(&plain) {
        if morphed as usize >= vertices {
            assert_eq!(
                slots[morphed as usize - vertices].to,
                i,
                "a morph slot's vertex"
            );
        } else {
            assert_eq!(morphed, i);
        }
    }
    cam.finish_morphs();
    must(cam.emit_indices_packed_morphed(h, &mut out, &mut offsets));
    assert!(
        out[..n] == plain[..],
        "finished morphs emit the plain indices"
    );
}

/// Asserts that two cameras emit the same indices; returns how many.
fn same_emission(h: &Hierarchy<'_>, a: &CameraState<'_>, b: &CameraState<'_>, what: &str) -> usize {
    let emit = |cam: &CameraState<'_>| {
        let mut out = vec![0u32; 3 * h.polygon_count()];
        let mut offsets = vec![0u32; h.surface_count() + 1];
        let n = must(cam.emit_indices_packed(h, &mut out, &mut offsets));
        out.truncate(n);
        (out, offsets)
    };
    let (x, y) = (emit(a), emit(b));
    assert!(x == y, "{what}");
    x.0.len()
}

/// Passes of a camera in a row in `cameras/one_at_a_time`.
const RUN: usize = 8;

/// Four budgeted cameras, each flying the back-and-forth path over its own stretch of the
/// diagonal, refined one pass each in turn (`cameras/round_robin`, as a renderer with four
/// views refines them) or each for [`RUN`] passes in a row (`cameras/one_at_a_time`, each
/// camera with the caches to itself for a while, as when flown alone): the same passes of
/// the same cameras in another order, so the ratio of the two is what sharing the caches
/// among four cameras costs, the demo's "4 cameras / 1" over 4. The cameras' memory is one
/// [`CameraPool`], as the fly-over's.
fn bench_cameras(c: &mut Criterion, h: &Hierarchy<'_>, s: f32, ground: &Ground) {
    let p = RefineParams::default();
    let steps = 100;
    let paths: Vec<Vec<View>> = (0..4)
        .map(|k| {
            (0..2 * steps)
                .map(|i| {
                    let u = if i < steps { i } else { 2 * steps - i } as f32 / 600.0;
                    view_at(0.2 * k as f32 + u, s, ground)
                })
                .collect()
        })
        .collect();
    let path_slices: Vec<&[View]> = paths.iter().map(Vec::as_slice).collect();
    let largest = largest_front(h, &path_slices, &p);
    let config = CameraConfig::with_polygon_budget(h, largest + largest / 10);
    let mut pool = CameraPool::new(CameraState::words_needed_for(h, &config), 4);
    let mut cams: Vec<CameraState<'_>> = pool
        .memories()
        .map(|m| must(CameraState::with_config(h, m, &config)))
        .collect();
    let fronts: Vec<u64> = cams
        .iter_mut()
        .zip(&paths)
        .map(|(cam, path)| {
            settle(cam, h, &path[0], &p);
            lap(cam, h, path, &p)
        })
        .collect();
    eprintln!(
        "four cameras, {} polygons each at most: mean fronts {fronts:?} polygons",
        largest + largest / 10
    );
    let fronts_sum: u64 = fronts.iter().sum();
    let mut g = c.benchmark_group("cameras");
    g.throughput(Throughput::Elements(RUN as u64 * fronts_sum));
    let step = Cell::new(0usize);
    let refusals = Cell::new(0u32);
    let pass = |cam: &mut CameraState<'_>, path: &[View], r: usize| {
        let st = must(cam.refine(h, &path[(step.get() + r) % path.len()], &p));
        refusals.set(refusals.get() + st.capacity_refusals);
    };
    g.bench_function("round_robin", |b| {
        b.iter(|| {
            for r in 0..RUN {
                for (cam, path) in cams.iter_mut().zip(&paths) {
                    pass(cam, path, r);
                }
            }
            step.set(step.get() + RUN);
        })
    });
    g.bench_function("one_at_a_time", |b| {
        b.iter(|| {
            for (cam, path) in cams.iter_mut().zip(&paths) {
                for r in 0..RUN {
                    pass(cam, path, r);
                }
            }
            step.set(step.get() + RUN);
        })
    });
    g.finish();
    // Every pass was a legal refinement (`must`), and the budget held every front.
    assert_eq!(refusals.get(), 0, "the budget held every camera's front");
}

/// Work per call of the incremental compaction in `budget/compact_step` (the fly-over's
/// default).
const COMPACT_STEP: u32 = 4_096;

/// Bounded frame cost, each form beside its baseline in the same run: a moving pass that
/// visits a third of the active list (Hoppe's amortisation) against a full one; one call of
/// `compact_step` per moving pass (a cycle started whenever none is under way) against the
/// whole `compact` of a front churned by 30 passes; and a whole incremental cycle after
/// that churn, for its total cost.
fn bench_budget(c: &mut Criterion, h: &Hierarchy<'_>, moving: &[View]) {
    let full = RefineParams::default();
    let third = full.amortised(1.0 / 3.0);
    let mut memory = vec![0u32; CameraState::words_needed(h)];
    let mut cam = must(CameraState::new(h, &mut memory));
    let mut g = c.benchmark_group("budget");
    for (name, p) in [("moving_pass_full", &full), ("moving_pass_third", &third)] {
        cam.reset(h);
        settle(&mut cam, h, &moving[0], &full);
        g.throughput(Throughput::Elements(lap(&mut cam, h, moving, p)));
        let mut k = 0usize;
        g.bench_function(name, |b| {
            b.iter(|| {
                k = (k + 1) % moving.len();
                must(cam.refine(h, &moving[k], p))
            })
        });
    }
    cam.reset(h);
    settle(&mut cam, h, &moving[0], &full);
    g.throughput(Throughput::Elements(lap(&mut cam, h, moving, &full)));
    let mut k = 0usize;
    let mut churn = |cam: &mut CameraState<'_>, frames: usize| {
        for _ in 0..frames {
            k = (k + 1) % moving.len();
            must(cam.refine(h, &moving[k], &full));
        }
    };
    g.bench_function("compact_full", |b| {
        b.iter_custom(|iters| {
            let mut timed = Duration::ZERO;
            for _ in 0..iters {
                churn(&mut cam, CHURN_FRAMES);
                let t = Instant::now();
                cam.compact(h);
                timed += t.elapsed();
            }
            timed
        })
    });
    let cycles = Cell::new((0u64, 0u64));
    g.bench_function("compact_step", |b| {
        b.iter_custom(|iters| {
            let mut timed = Duration::ZERO;
            for _ in 0..iters {
                churn(&mut cam, 1);
                let t = Instant::now();
                let done = cam.compact_step(h, COMPACT_STEP);
                timed += t.elapsed();
                let (n, ended) = cycles.get();
                cycles.set((n + 1, ended + u64::from(done.finished)));
            }
            timed
        })
    });
    g.bench_function("compact_cycle", |b| {
        b.iter_custom(|iters| {
            let mut timed = Duration::ZERO;
            for _ in 0..iters {
                churn(&mut cam, CHURN_FRAMES);
                let t = Instant::now();
                while !cam.compact_step(h, COMPACT_STEP).finished {}
                timed += t.elapsed();
            }
            timed
        })
    });
    g.finish();
    let (n, ended) = cycles.get();
    if ended > 0 {
        eprintln!(
            "budget/compact_step: a cycle every {:.0} steps of {COMPACT_STEP} while moving",
            n as f64 / ended as f64
        );
    }
    // What the incremental and the whole compaction leave behind is the same front.
    let mut plain_memory = vec![0u32; CameraState::words_needed(h)];
    let mut plain = must(CameraState::new(h, &mut plain_memory));
    for (cam, step) in [(&mut cam, true), (&mut plain, false)] {
        cam.reset(h);
        settle(cam, h, &moving[0], &full);
        lap(cam, h, moving, &full);
        if step {
            while !cam.compact_step(h, COMPACT_STEP).finished {}
        } else {
            cam.compact(h);
        }
    }
    same_emission(h, &cam, &plain, "incremental and whole compaction agree");
}

fn main() {
    let benchmarking = std::env::args().any(|a| a == "--bench");
    let size: u32 = std::env::var("CAVECLOD_BENCH_SIZE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(if benchmarking { 708 } else { 48 });
    let t = Instant::now();
    let mesh = meshes::terrain(size, size, SEED);
    let ground = Ground {
        n: size,
        heights: mesh.positions.iter().map(|p| p[1]).collect(),
    };
    let baked = bake(&mesh);
    let polygons = mesh.triangles.len();
    drop(mesh);
    let h = baked.hierarchy();
    eprintln!(
        "terrain {size} x {size}: {polygons} polygons, {} nodes, {} splits; baked in {:.2} s",
        h.node_count(),
        h.splits().len(),
        t.elapsed().as_secs_f64()
    );
    let s = size as f32;
    let near = view_at(0.0, s, &ground);
    let far = far_view(s);
    // Ping-pong over the first sixth of the diagonal, about s / 600 world units per step (the
    // flyover's speed): 200 views, short enough that the timed iterations cover the loop,
    // so the lap's mean front is the front the timed passes see.
    let steps = 100;
    let moving: Vec<View> = (0..2 * steps)
        .map(|i| {
            let u = if i < steps { i } else { 2 * steps - i } as f32 / 600.0;
            view_at(u, s, &ground)
        })
        .collect();

    let mut c = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4))
        .configure_from_args();
    bench_ops(&mut c, &h, &near, &far);
    bench_refine(&mut c, &h, &near, &moving);
    bench_budget(&mut c, &h, &moving);
    bench_budgeted(&mut c, &h, &moving);
    bench_cameras(&mut c, &h, s, &ground);
    bench_emit(&mut c, &h, &near, &moving);
    bench_geomorphs(&mut c, &h, &moving);
    c.final_summary();
}
