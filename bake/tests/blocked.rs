//! The hierarchy built in blocks: a frozen position is never removed; the blocked build of a
//! terrain (with holes and a texture seam) is one valid hierarchy over every input triangle,
//! as deep as its levels make it, whose bounds hold what the levels below lost.

use caveclod_bake::baked::Baked;
use caveclod_bake::blocked::{self, BlockedOptions};
use caveclod_bake::hierarchy::{self, AttributeWeights};
use caveclod_bake::weld::{self, Welded};
use std::collections::HashMap;

use caveclod_bake::hierarchy::Hierarchy;
use caveclod_tests::{meshes, to_mesh};

const NONE: u32 = u32::MAX;

fn welded(nx: u32, holed: bool) -> Welded {
    let t = if holed {
        meshes::holed_terrain(nx, nx, 7)
    } else {
        meshes::terrain(nx, nx, 7)
    };
    weld::weld(&to_mesh(&t)).expect("weld")
}

#[test]
fn a_frozen_position_is_never_removed_but_others_collapse_onto_it() {
    let w = welded(20, false);
    let frozen: Vec<bool> = (0..w.positions.len()).map(|x| x % 3 == 0).collect();
    let h = hierarchy::build_frozen(&w, &AttributeWeights::default(), &frozen, 0, &mut |_, _| {})
        .expect("build");
    assert!(h.collapses.len() > w.positions.len() / 3);
    let mut onto_frozen = 0;
    for c in &h.collapses {
        assert!(!frozen[h.node_position[c.u as usize] as usize]);
        onto_frozen += usize::from(frozen[h.node_position[c.t as usize] as usize]);
    }
    assert!(onto_frozen > 0);
}

/// Distance from `p` to the segment `a`–`b`, squared.
fn segment_d2(p: [f64; 3], a: [f64; 3], b: [f64; 3]) -> f64 {
    let ab = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let ap = [p[0] - a[0], p[1] - a[1], p[2] - a[2]];
    let l = ab.iter().map(|x| x * x).sum::<f64>();
    let t = if l > 0.0 {
        ((0..3).map(|k| ab[k] * ap[k]).sum::<f64>() / l).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (0..3).map(|k| (p[k] - a[k] - t * ab[k]).powi(2)).sum()
}

/// Distance from `p` to the triangle `t`, squared (inside its prism: to its plane; else to
/// its nearest edge).
fn triangle_d2(p: [f64; 3], t: [[f64; 3]; 3]) -> f64 {
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let n = cross(sub(t[1], t[0]), sub(t[2], t[0]));
    let inside = (0..3).all(|k| dot(cross(sub(t[(k + 1) % 3], t[k]), sub(p, t[k])), n) >= 0.0);
    let nn = dot(n, n);
    if inside && nn > 0.0 {
        dot(sub(p, t[0]), n).powi(2) / nn
    } else {
        (0..3)
            .map(|k| segment_d2(p, t[k], t[(k + 1) % 3]))
            .fold(f64::INFINITY, f64::min)
    }
}

/// Replays the collapses on the input mesh in order and checks each against the mesh as it
/// stands then: `f_l` holds `t → u` at its corner `rot_l` (`f_r` the edge back), and each of
/// Hoppe's neighbours is the triangle across its edge (`fl_ccw` across `x → t`, `fl_clw`
/// across `u → x`, `fr_clw` across `t → y`, `fr_ccw` across `y → u`); the mesh left is the
/// base mesh the hierarchy gives.
fn replay_matches(w: &Welded, h: &Hierarchy) {
    let np = w.positions.len() as u32;
    let mut corners: Vec<[u32; 3]> = w.triangles.iter().map(|t| t.p).collect();
    let mut alive = vec![true; corners.len()];
    let mut edge: HashMap<(u32, u32), u32> = HashMap::new();
    let mut faces: Vec<Vec<u32>> = vec![Vec::new(); h.parent.len()];
    for (f, c) in corners.iter().enumerate() {
        for k in 0..3 {
            edge.insert((c[k], c[(k + 1) % 3]), f as u32);
            faces[c[k] as usize].push(f as u32);
        }
    }
    let across = |edge: &HashMap<(u32, u32), u32>, a: u32, b: u32| {
        edge.get(&(b, a)).copied().unwrap_or(NONE)
    };
    for (i, c) in h.collapses.iter().enumerate() {
        let n = np + i as u32;
        let (jl, jr) = (c.rot_l as usize, c.rot_r as usize);
        let l = corners[c.fl as usize];
        assert!(alive[c.fl as usize]);
        assert_eq!((l[jl], l[(jl + 1) % 3]), (c.t, c.u), "collapse {i}");
        let x = l[(jl + 2) % 3];
        let mut expected = [across(&edge, x, c.t), across(&edge, c.u, x), NONE, NONE];
        assert_eq!(across(&edge, c.t, c.u), c.fr, "collapse {i}");
        if c.fr != NONE {
            let r = corners[c.fr as usize];
            assert_eq!((r[jr], r[(jr + 2) % 3]), (c.t, c.u), "collapse {i}");
            let y = r[(jr + 1) % 3];
            expected[2] = across(&edge, c.t, y);
            expected[3] = across(&edge, y, c.u);
        }
        assert_eq!(c.neighbours, expected, "collapse {i}");
        for f in [c.fl, c.fr] {
            if f != NONE {
                alive[f as usize] = false;
                let k = corners[f as usize];
                for j in 0..3 {
                    edge.remove(&(k[j], k[(j + 1) % 3]));
                }
            }
        }
        let around: Vec<u32> = faces[c.t as usize]
            .iter()
            .chain(&faces[c.u as usize])
            .copied()
            .filter(|&f| alive[f as usize])
            .collect();
        for &f in &around {
            let k = corners[f as usize];
            for j in 0..3 {
                edge.remove(&(k[j], k[(j + 1) % 3]));
            }
        }
        for &f in &around {
            let k = corners[f as usize].map(|v| if v == c.t || v == c.u { n } else { v });
            corners[f as usize] = k;
            for j in 0..3 {
                assert!(
                    edge.insert((k[j], k[(j + 1) % 3]), f).is_none(),
                    "collapse {i}"
                );
            }
        }
        faces[n as usize] = around;
    }
    assert_eq!(alive, h.alive);
    for (f, &a) in alive.iter().enumerate() {
        if a {
            assert_eq!(corners[f], h.corners[f]);
        }
    }
}

#[test]
fn the_in_core_build_replays_as_the_check_expects() {
    let w = welded(24, true);
    let h = hierarchy::build(&w, &AttributeWeights::default(), &mut |_, _| {}).expect("build");
    replay_matches(&w, &h);
}

#[test]
fn a_blocked_terrain_is_one_valid_hierarchy_whose_roots_bound_the_input() {
    for holed in [false, true] {
        let w = welded(48, holed);
        let options = BlockedOptions {
            block_triangles: 300,
        };
        let mut reports = 0;
        let b = blocked::build(&w, &AttributeWeights::default(), &options, &mut |_, _| {
            reports += 1
        })
        .expect("blocked build");
        let h = &b.hierarchy;
        replay_matches(&w, h);
        // 4608 triangles in blocks of at most 300 on average: 4 × 4 tiles, then 2 × 2, then one.
        assert_eq!(b.levels.len(), 3, "{:?}", b.levels);
        assert_eq!(reports, b.levels.len());
        assert_eq!(b.levels[0].blocks, 16);
        assert_eq!(b.levels[1].blocks, 4);
        assert_eq!(b.levels[2].blocks, 1);
        assert!(b.levels.iter().all(|l| l.collapses > 0), "{:?}", b.levels);
        assert_eq!(
            b.levels.iter().map(|l| l.collapses).sum::<usize>(),
            h.collapses.len()
        );
        assert_eq!(h.parent.len(), w.positions.len() + h.collapses.len());
        let base = h.alive.iter().filter(|&&a| a).count();
        assert!(base < w.triangles.len() / 20, "{base} base triangles");
        // The arrays of the whole validate as the core reads them.
        let baked = Baked::new(&w, h);
        let file = baked.hierarchy().expect("a valid hierarchy");
        assert_eq!(file.polygon_count(), w.triangles.len());
        // Every input position lies within the roots' error of the base mesh, and a parent's
        // bounds hold its children's.
        let point = |v: u32| w.positions[h.node_position[v as usize] as usize].map(f64::from);
        let base: Vec<[[f64; 3]; 3]> = h
            .corners
            .iter()
            .zip(&h.alive)
            .filter(|(_, &a)| a)
            .map(|(c, _)| c.map(point))
            .collect();
        let root_error = (0..h.parent.len())
            .filter(|&v| h.parent[v] == NONE)
            .map(|v| f64::from(h.error[v]))
            .fold(0.0, f64::max);
        let worst = w
            .positions
            .iter()
            .map(|p| {
                base.iter()
                    .map(|&t| triangle_d2(p.map(f64::from), t))
                    .fold(f64::INFINITY, f64::min)
                    .sqrt()
            })
            .fold(0.0, f64::max);
        assert!(worst <= root_error * (1.0 + 1e-5), "{worst} > {root_error}");
        for (v, &p) in h.parent.iter().enumerate() {
            if p != NONE {
                assert!(h.error[p as usize] >= h.error[v]);
                assert!(h.radius[p as usize] >= h.radius[v]);
            }
        }
    }
}

#[test]
fn the_blocked_hierarchy_is_the_same_on_one_thread_and_on_several() {
    let w = welded(40, true);
    let options = BlockedOptions {
        block_triangles: 400,
    };
    let on = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool")
            .install(|| {
                blocked::build(&w, &AttributeWeights::default(), &options, &mut |_, _| {})
                    .expect("blocked build")
            })
    };
    let (one, four) = (on(1), on(4));
    let key = |h: &Hierarchy| -> Vec<_> {
        h.collapses
            .iter()
            .map(|c| (c.t, c.u, c.fl, c.fr, c.neighbours, c.rot_l, c.rot_r))
            .collect()
    };
    assert_eq!(key(&one.hierarchy), key(&four.hierarchy));
    assert_eq!(one.hierarchy.error, four.hierarchy.error);
    assert_eq!(one.hierarchy.radius, four.hierarchy.radius);
    assert_eq!(one.levels, four.levels);
}

#[test]
fn a_build_stopped_early_is_the_start_of_the_full_one() {
    let w = welded(24, true);
    let frozen: Vec<bool> = (0..w.positions.len()).map(|x| x % 7 == 0).collect();
    let weights = AttributeWeights::default();
    let full = hierarchy::build_frozen(&w, &weights, &frozen, 0, &mut |_, _| {}).expect("full");
    let stop_at = w.triangles.len() / 4;
    let part =
        hierarchy::build_frozen(&w, &weights, &frozen, stop_at, &mut |_, _| {}).expect("part");
    assert!(part.collapses.len() < full.collapses.len());
    let live = part.alive.iter().filter(|&&a| a).count();
    assert!(live <= stop_at, "{live} > {stop_at}");
    for (a, b) in part.collapses.iter().zip(&full.collapses) {
        assert_eq!(
            (a.t, a.u, a.fl, a.fr, a.neighbours),
            (b.t, b.u, b.fl, b.fr, b.neighbours)
        );
    }
    let nodes = w.positions.len() + part.collapses.len();
    assert_eq!(part.error[..], full.error[..nodes]);
    assert_eq!(part.radius[..], full.radius[..nodes]);
}
