use super::geometry::{point_triangle_d2, V3};
use super::pass::PASS_SHARE;
use super::types::{NONE, PARALLEL_MIN};
use super::*;
use crate::mesh::{Mesh, Surface, Triangle, NO_ATTRIBUTE};

#[test]
fn point_triangle_distance_in_every_region() {
    let (a, b, c) = ([0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]);
    let d = |x: V3| point_triangle_d2(x, a, b, c).sqrt();
    let close = |x: f64, y: f64| (x - y).abs() < 1e-12;
    assert!(close(d([0.5, 0.5, 3.0]), 3.0)); // inside, above
    assert!(close(d([-1.0, -1.0, 0.0]), 2f64.sqrt())); // corner a
    assert!(close(d([3.0, 0.0, 0.0]), 1.0)); // corner b
    assert!(close(d([0.0, 3.0, 4.0]), 17f64.sqrt())); // corner c
    assert!(close(d([1.0, -2.0, 0.0]), 2.0)); // edge ab
    assert!(close(d([-2.0, 1.0, 0.0]), 2.0)); // edge ac
    assert!(close(d([2.0, 2.0, 0.0]), 2f64.sqrt())); // edge bc
                                                     // Degenerate (a segment): the nearest corner at worst.
    assert!(point_triangle_d2([1.0, 1.0, 0.0], a, b, b) <= 2.0 + 1e-12);
}

/// A bumpy height field of `n × n` posts with a border.
fn terrain(n: u32) -> Mesh {
    let mut m = Mesh {
        surfaces: vec![Surface::default()],
        ..Mesh::default()
    };
    for row in 0..n {
        for col in 0..n {
            let (x, z) = (col as f32, row as f32);
            let h = (x * 0.7).sin() * (z * 0.4).cos() * 2.0 + ((x * z) * 0.37).sin() * 0.3;
            m.positions.push([x, h, z]);
        }
    }
    for row in 0..n - 1 {
        for col in 0..n - 1 {
            let i = row * n + col;
            for position in [[i, i + n, i + n + 1], [i, i + n + 1, i + 1]] {
                m.triangles.push(Triangle {
                    position,
                    normal: [NO_ATTRIBUTE; 3],
                    uv: [NO_ATTRIBUTE; 3],
                    color: [NO_ATTRIBUTE; 3],
                    surface: 0,
                });
            }
        }
    }
    m
}

#[test]
fn every_input_position_is_within_the_roots_error_of_the_base_mesh() {
    let w = crate::weld::weld(&terrain(24)).expect("weld");
    let h = build(&w, &AttributeWeights::default(), &mut |_, _| {}).expect("build");
    let point = |node: u32| w.positions[h.node_position[node as usize] as usize].map(f64::from);
    let base: Vec<[V3; 3]> = h
        .corners
        .iter()
        .zip(&h.alive)
        .filter(|(_, &alive)| alive)
        .map(|(c, _)| c.map(point))
        .collect();
    assert!(
        base.len() < w.triangles.len() / 10,
        "{} base triangles",
        base.len()
    );
    let root_error = h
        .parent
        .iter()
        .zip(&h.error)
        .filter(|(&p, _)| p == NONE)
        .map(|(_, &e)| e as f64)
        .fold(0.0, f64::max);
    let worst = w
        .positions
        .iter()
        .map(|p| {
            let x = p.map(f64::from);
            base.iter()
                .map(|&[a, b, c]| point_triangle_d2(x, a, b, c))
                .fold(f64::INFINITY, f64::min)
                .sqrt()
        })
        .fold(0.0, f64::max);
    assert!(worst > 0.1, "the base mesh should not be exact: {worst}");
    assert!(worst <= root_error * (1.0 + 1e-5), "{worst} > {root_error}");
    // A parent's error is at least its children's.
    for (v, &p) in h.parent.iter().enumerate() {
        if p != NONE {
            assert!(h.error[p as usize] >= h.error[v]);
        }
    }
}

/// A pass over every ranked collapse has no limit, with few candidates (sorted at once) and
/// with many (bucketed): an edge's other direction, queued during the pass, may be dearer
/// than every ranked collapse and must not be cut (a full pass that applied nothing while
/// cutting one was repeated forever).
#[test]
fn a_full_share_cuts_nothing() {
    use super::rank::{order_key, Ranked, Slots};
    use super::records::Tri;
    for n in [100usize, 10_000] {
        // A triangle per candidate, its first slot allowed in one direction.
        let mut slots = Slots::new(n);
        let tris = vec![
            Tri {
                c: [0, 1, 2],
                o: [NONE; 3]
            };
            n
        ];
        for i in 0..n {
            let none = [f64::INFINITY; 2];
            slots.set(i, [[1.0 + i as f64, f64::INFINITY], none, none]);
        }
        let mut ranked = Ranked::default();
        assert_eq!(
            ranked.start(&slots, &tris, n, 1.0, 2),
            u64::MAX,
            "{n} candidates"
        );
        // Half: the limit covers the cheapest half and leaves out the dearest.
        let half = ranked.start(&slots, &tris, n, PASS_SHARE, 2);
        assert!(half >= order_key(n as f64 / 2.0), "{n} candidates");
        assert!(half < order_key(n as f64), "{n} candidates");
    }
}

/// The hierarchy of a mesh large enough to be split into parallel parts, built in a rayon
/// pool of `threads` threads.
fn build_on(threads: usize, w: &crate::weld::Welded) -> Hierarchy {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool")
        .install(|| build(w, &AttributeWeights::default(), &mut |_, _| {}).expect("build"))
}

#[test]
fn the_hierarchy_is_the_same_on_one_thread_and_on_several() {
    // 2 × 79² triangles: above PARALLEL_MIN, so the parallel steps split their work.
    let w = crate::weld::weld(&terrain(80)).expect("weld");
    assert!(w.triangles.len() > 2 * PARALLEL_MIN);
    let (one, three) = (build_on(1, &w), build_on(3, &w));
    assert!(one.collapses.len() > 1000);
    assert!(
        hierarchy_key(&one) == hierarchy_key(&three),
        "the thread count changed the hierarchy"
    );
}

/// What two builds of the same mesh must agree on, to the bit.
#[allow(clippy::type_complexity)]
fn hierarchy_key(
    h: &Hierarchy,
) -> (
    Vec<(u32, u32, u32, u32, [u32; 4])>,
    Vec<u32>,
    Vec<u32>,
    Vec<u32>,
    Vec<[u32; 3]>,
    Vec<bool>,
    u32,
) {
    (
        h.collapses
            .iter()
            .map(|c| (c.t, c.u, c.fl, c.fr, c.neighbours))
            .collect(),
        h.parent.clone(),
        h.error.iter().map(|e| e.to_bits()).collect(),
        h.radius.iter().map(|r| r.to_bits()).collect(),
        h.corners.clone(),
        h.alive.clone(),
        h.passes,
    )
}

/// The hierarchy of `w` with the points settled every `segment` collapses of a pass, on
/// `threads` threads.
fn build_segmented(threads: usize, segment: u64, w: &crate::weld::Welded) -> Hierarchy {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool")
        .install(|| {
            let mut work = super::setup::work(w, &AttributeWeights::default(), &[], threads);
            super::pass::collapse_all(&mut work, (threads, segment), 0, &mut |_, _| {})
                .expect("build");
            work.into_hierarchy()
        })
}

#[test]
fn settling_beside_the_pass_gives_what_settling_after_it_gives() {
    let w = crate::weld::weld(&terrain(80)).expect("weld");
    let after = build_segmented(1, u64::MAX, &w);
    assert!(after.collapses.len() > 1000);
    for (threads, segment) in [(1, 7), (2, 7), (3, 64), (2, super::pass::SEGMENT)] {
        let beside = build_segmented(threads, segment, &w);
        assert!(
            hierarchy_key(&beside) == hierarchy_key(&after),
            "settled every {segment} collapses on {threads} threads"
        );
    }
}

/// A collapse of two leaves moves the input's own triangles around its removed child: the
/// new node's error covers how far their points (centroids and edge midpoints) then lie from
/// the input surface, not only how far the input's points lie from them.
#[test]
fn a_first_collapse_bounds_how_far_it_moves_the_surface() {
    let w = crate::weld::weld(&terrain(24)).expect("weld");
    let h = build(&w, &AttributeWeights::default(), &mut |_, _| {}).expect("build");
    let at = |x: u32| w.positions[x as usize].map(f64::from);
    let input: Vec<[u32; 3]> = w.triangles.iter().map(|t| t.p).collect();
    let positions = w.positions.len();
    let mut checked = 0;
    for (i, c) in h.collapses.iter().enumerate() {
        if c.t as usize >= positions || c.u as usize >= positions {
            continue;
        }
        let node = (positions + i) as u32;
        // Only collapses whose neighbourhood is still the input's: no corner of a triangle
        // at `t` or `u` was collapsed before.
        let untouched = input
            .iter()
            .filter(|t| t.contains(&c.t) || t.contains(&c.u))
            .flatten()
            .all(|&x| h.parent[x as usize] == NONE || h.parent[x as usize] >= node);
        if !untouched {
            continue;
        }
        let error = f64::from(h.error[node as usize]);
        let moved = input
            .iter()
            .enumerate()
            .filter(|&(f, t)| t.contains(&c.u) && f as u32 != c.fl && f as u32 != c.fr);
        for (_, t) in moved {
            let [a, b, d] = t.map(|x| at(if x == c.u { c.t } else { x }));
            let mid = |x: V3, y: V3| {
                [
                    0.5 * (x[0] + y[0]),
                    0.5 * (x[1] + y[1]),
                    0.5 * (x[2] + y[2]),
                ]
            };
            let centroid = [0, 1, 2].map(|k| (a[k] + b[k] + d[k]) / 3.0);
            for x in [centroid, mid(a, b), mid(b, d), mid(d, a)] {
                let near = input
                    .iter()
                    .map(|t| point_triangle_d2(x, at(t[0]), at(t[1]), at(t[2])))
                    .fold(f64::INFINITY, f64::min)
                    .sqrt();
                assert!(
                    near <= error * (1.0 + 1e-5) + 1e-9,
                    "collapse {i}: {near} > {error}"
                );
            }
        }
        checked += 1;
    }
    assert!(checked > 20, "{checked} collapses of two leaves");
}

/// A release's runs: the wedges of the kept positions between removed ones move down in
/// order, and a removed position's range becomes empty at the next kept one's start.
#[test]
fn kept_runs_move_the_kept_positions_wedges_down() {
    use super::work::kept_runs;
    // Wedges per position: 1, 2, 1, 0, 1, 1, 2 (starts 0, 1, 3, 4, 4, 5, 6, 8).
    let starts = [0u32, 1, 3, 4, 4, 5, 6, 8];
    let gone = [false, true, false, false, true, true, false];
    let (runs, start) = kept_runs(&gone, &starts);
    assert_eq!(runs, vec![(0..1, 0), (3..4, 1), (6..8, 2)]);
    assert_eq!(start, vec![0, 1, 1, 2, 2, 2, 2, 4]);
    // Moving the runs keeps each kept position's wedges, in order.
    let mut wedges: Vec<u32> = (0..8).collect();
    for (from, to) in runs {
        wedges.copy_within(from, to);
    }
    wedges.truncate(4);
    assert_eq!(wedges, [0, 3, 6, 7]);
    // Nothing gone: one run that stays; everything gone: none.
    assert_eq!(kept_runs(&[false; 7], &starts).0, vec![(0..8, 0)]);
    let (none, start) = kept_runs(&[true; 7], &starts);
    assert!(none.is_empty() && start.iter().all(|&s| s == 0));
}

/// The live list, made when a pass first removes triangles, gives the slots the same
/// triangles, numbers and rankings as the list of every triangle did.
#[test]
fn the_live_list_made_on_the_first_removal_keeps_the_slots() {
    use super::rank::Slots;
    let n = 10usize;
    let mut slots = Slots::new(n);
    for i in 0..n {
        let none = [f64::INFINITY; 2];
        slots.set(i, [[i as f64, f64::INFINITY], none, none]);
    }
    assert_eq!((slots.slot(3 * 7 + 2), slots.number(7, 2)), ((7, 2), 23));
    // Nothing removed: the slots stay as they are.
    slots.retain_alive(&[true; 10]);
    assert_eq!((slots.slot(3 * 7 + 2), slots.number(7, 2)), ((7, 2), 23));
    let alive: Vec<bool> = (0..n).map(|f| f % 3 != 0).collect();
    slots.retain_alive(&alive);
    // Triangles 1, 2, 4, 5, 7, 8 are left, with their rankings.
    let tris = vec![
        super::records::Tri {
            c: [0, 1, 2],
            o: [NONE; 3]
        };
        n
    ];
    for (place, f) in [1u32, 2, 4, 5, 7, 8].into_iter().enumerate() {
        assert_eq!(slots.slot(3 * place), (f, 0));
        assert_eq!(slots.number(f, 1), 3 * place + 1);
        assert_eq!(slots.get(&tris, 3 * place).cost, f as f64);
    }
    // A second removal works on the list.
    let alive: Vec<bool> = (0..n).map(|f| f % 3 != 0 && f != 5).collect();
    slots.retain_alive(&alive);
    assert_eq!(slots.slot(3 * 3), (7, 0));
    assert_eq!(slots.get(&tris, 3 * 3).cost, 7.0);
}
