//! The multiresolution octree of the out-of-core bake: coarser levels derived from the finest
//! clustering equal a direct clustering on the coarser grid, the tree's invariants, honest
//! error bounds, UV seams kept at every level.

use caveclod_bake::mesh::{Mesh, Surface, Triangle, NO_ATTRIBUTE};
use caveclod_bake::ooc::{cluster_mesh_in, multires, ClusterOptions, Cube, MultiresOptions};

/// A bumpy height field over `[0, 1]^2` with `n x n` quads; UVs (when asked) with a seam down
/// the middle (the right half's UVs shifted by 0.5), two surfaces (left and right halves) when
/// asked.
fn field(n: u32, with_uv: bool, two_surfaces: bool) -> Mesh {
    let mut m = Mesh {
        surfaces: vec![
            Surface {
                name: "a".into(),
                base_color: [1.0; 4],
                texture: None,
            },
            Surface {
                name: "b".into(),
                base_color: [1.0; 4],
                texture: None,
            },
        ],
        ..Default::default()
    };
    let h = |x: f32, y: f32| 0.08 * (7.0 * x).sin() * (5.0 * y).cos() + 0.03 * (19.0 * x * y).sin();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f32 / n as f32, j as f32 / n as f32);
            m.positions.push([x, h(x, y), y]);
        }
    }
    let v = |i: u32, j: u32| j * (n + 1) + i;
    // Two UV sets per position: left chart and right chart (shifted), for the seam.
    if with_uv {
        for shift in [0.0f32, 0.5] {
            for j in 0..=n {
                for i in 0..=n {
                    m.uvs
                        .push([i as f32 / n as f32 + shift, j as f32 / n as f32]);
                }
            }
        }
    }
    let stride = (n + 1) * (n + 1);
    for j in 0..n {
        for i in 0..n {
            let right = i >= n / 2;
            let uv_off = if right { stride } else { 0 };
            let surface = u16::from(two_surfaces && right);
            for t in [
                [v(i, j), v(i, j + 1), v(i + 1, j)],
                [v(i + 1, j), v(i, j + 1), v(i + 1, j + 1)],
            ] {
                m.triangles.push(Triangle {
                    position: t,
                    normal: [NO_ATTRIBUTE; 3],
                    uv: if with_uv {
                        t.map(|k| k + uv_off)
                    } else {
                        [NO_ATTRIBUTE; 3]
                    },
                    color: [NO_ATTRIBUTE; 3],
                    surface,
                });
            }
        }
    }
    m
}

fn cube() -> Cube {
    Cube::around([0.0, -0.5, 0.0], [1.0, 0.5, 1.0])
}

/// Triangles as sorted position triples, rounded to 1e-4.
fn triangle_set(tris: impl Iterator<Item = [[f32; 3]; 3]>) -> Vec<[[i64; 3]; 3]> {
    let mut v: Vec<[[i64; 3]; 3]> = tris
        .map(|t| {
            let mut t = t.map(|p| p.map(|c| (c * 1e4).round() as i64));
            t.sort_unstable();
            t
        })
        .collect();
    v.sort_unstable();
    v
}

fn level_triangles(o: &multires::MultiresOctree, level: u32) -> Vec<[[f32; 3]; 3]> {
    let mut out = Vec::new();
    for n in o.nodes.iter().filter(|n| n.level == level) {
        for r in &o.ranges[n.first_range as usize..(n.first_range + n.range_count) as usize] {
            for t in o.indices[r[1] as usize..(r[1] + r[2]) as usize].chunks(3) {
                out.push([0, 1, 2].map(|k| o.vertices[t[k] as usize].position));
            }
        }
    }
    out
}

#[test]
fn coarser_levels_equal_a_direct_clustering_on_the_coarser_grid() {
    let mesh = field(96, false, false);
    let (_, finest) = cluster_mesh_in(&mesh, cube(), ClusterOptions::at_resolution(64));
    let options = MultiresOptions {
        coarsest_triangles: 50,
        ..Default::default()
    };
    let o = multires::build(finest, 2, &options);
    assert!(o.level_count >= 4, "{}", o.level_count);
    for (level, resolution) in [(1u32, 32u32), (2, 16), (3, 8)] {
        let (direct, _) = cluster_mesh_in(&mesh, cube(), ClusterOptions::at_resolution(resolution));
        let want = triangle_set(
            direct
                .triangles
                .iter()
                .map(|t| t.position.map(|p| direct.positions[p as usize])),
        );
        let got = triangle_set(level_triangles(&o, level).into_iter());
        assert_eq!(got.len(), want.len(), "level {level}");
        // Positions agree to rounding (the quadrics are summed in another order).
        let mut differ = 0;
        for (g, w) in got.iter().zip(&want) {
            let d = (0..3)
                .flat_map(|a| (0..3).map(move |b| (g[a][b] - w[a][b]).abs()))
                .max()
                .unwrap_or(0);
            if d > 2 {
                differ += 1;
            }
        }
        assert_eq!(differ, 0, "level {level}: {differ} triangles moved");
    }
}

#[test]
fn the_tree_is_breadth_first_with_monotone_errors_and_valid_ranges() {
    let mesh = field(128, true, true);
    let (_, finest) = cluster_mesh_in(&mesh, cube(), ClusterOptions::at_resolution(128));
    let options = MultiresOptions {
        block_levels: 3,
        coarsest_triangles: 200,
    };
    let o = multires::build(finest, 2, &options);
    assert!(o.nodes.len() > 20, "{}", o.nodes.len());
    assert_eq!(o.nodes[0].level, o.level_count - 1);
    // Children ranges cover 1..n in order; levels step down by one; errors never grow down.
    let mut next = 1;
    for (i, n) in o.nodes.iter().enumerate() {
        assert!(n.min.iter().zip(&n.max).all(|(a, b)| a <= b), "node {i}");
        assert!(n.error.is_finite() && n.error >= 0.0);
        if n.level == 0 {
            assert_eq!(n.child_count, 0, "node {i}");
        } else {
            assert!(n.child_count > 0, "node {i} at level {}", n.level);
            assert_eq!(n.first_child, next, "node {i}");
            next += n.child_count;
            for c in &o.nodes[n.first_child as usize..(n.first_child + n.child_count) as usize] {
                assert_eq!(c.level + 1, n.level);
                assert!(c.error <= n.error);
                for a in 0..3 {
                    assert!(c.min[a] >= n.min[a] && c.max[a] <= n.max[a]);
                }
            }
        }
        let ranges = &o.ranges[n.first_range as usize..(n.first_range + n.range_count) as usize];
        for w in ranges.windows(2) {
            assert!(w[0][0] < w[1][0], "surfaces ascending in node {i}");
        }
        for r in ranges {
            assert!(r[0] < 2 && r[2] > 0 && r[2] % 3 == 0);
            assert!((r[1] + r[2]) as usize <= o.indices.len());
        }
    }
    assert_eq!(next as usize, o.nodes.len());
    assert!(o.indices.iter().all(|&i| (i as usize) < o.vertices.len()));
    // Levels shrink; the root holds the coarsest level within the limit.
    for w in o.level_triangles.windows(2) {
        assert!(w[1] < w[0], "{:?}", o.level_triangles);
    }
    assert!(*o.level_triangles.last().unwrap() <= 200);
    // Every vertex is used and has a unit normal.
    let mut used = vec![false; o.vertices.len()];
    for &i in &o.indices {
        used[i as usize] = true;
    }
    assert!(used.iter().all(|&u| u));
    for v in &o.vertices {
        let l: f32 = v.normal.iter().map(|c| c * c).sum();
        assert!((l - 1.0).abs() < 1e-3, "{v:?}");
    }
}

/// Distance from `p` to the triangle `t` (Ericson's closest point on a triangle).
fn point_triangle_distance(p: [f32; 3], t: [[f32; 3]; 3]) -> f32 {
    let sub = |a: [f32; 3], b: [f32; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: [f32; 3], b: [f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let along =
        |a: [f32; 3], d: [f32; 3], s: f32| [a[0] + s * d[0], a[1] + s * d[1], a[2] + s * d[2]];
    let [a, b, c] = t;
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(p, a));
    let (d1, d2) = (dot(ab, ap), dot(ac, ap));
    let q = if d1 <= 0.0 && d2 <= 0.0 {
        a
    } else {
        let bp = sub(p, b);
        let (d3, d4) = (dot(ab, bp), dot(ac, bp));
        let cp = sub(p, c);
        let (d5, d6) = (dot(ab, cp), dot(ac, cp));
        let vc = d1 * d4 - d3 * d2;
        let vb = d5 * d2 - d1 * d6;
        let va = d3 * d6 - d5 * d4;
        if d3 >= 0.0 && d4 <= d3 {
            b
        } else if d6 >= 0.0 && d5 <= d6 {
            c
        } else if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            along(a, ab, d1 / (d1 - d3))
        } else if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            along(a, ac, d2 / (d2 - d6))
        } else if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
            along(b, sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6)))
        } else {
            let denom = 1.0 / (va + vb + vc);
            let (v, w) = (vb * denom, vc * denom);
            [0, 1, 2].map(|k| a[k] + ab[k] * v + ac[k] * w)
        }
    };
    let d = sub(p, q);
    dot(d, d).sqrt()
}

#[test]
fn every_input_vertex_lies_within_its_levels_error_of_the_level() {
    let mesh = field(40, true, false);
    let (_, finest) = cluster_mesh_in(&mesh, cube(), ClusterOptions::at_resolution(32));
    let options = MultiresOptions {
        coarsest_triangles: 20,
        ..Default::default()
    };
    let o = multires::build(finest, 2, &options);
    assert!(o.level_count >= 3);
    for level in 0..o.level_count {
        let error = o
            .nodes
            .iter()
            .filter(|n| n.level == level)
            .map(|n| n.error)
            .fold(0.0f32, f32::max);
        let tris = level_triangles(&o, level);
        let mut worst = 0.0f32;
        for p in &mesh.positions {
            let d = tris
                .iter()
                .map(|&t| point_triangle_distance(*p, t))
                .fold(f32::MAX, f32::min);
            worst = worst.max(d);
        }
        assert!(
            worst <= error,
            "level {level}: an input vertex is {worst} from the level, error bound {error}"
        );
        // And the bound is not vacuous: within a few cells of the level.
        let cell = cube().size as f32 / 32.0 * (1u32 << level) as f32;
        assert!(error <= 3.0 * cell, "level {level}: {error} vs cell {cell}");
    }
}

#[test]
fn uv_seams_stay_seams_at_every_level() {
    let mesh = field(64, true, false);
    let (_, finest) = cluster_mesh_in(&mesh, cube(), ClusterOptions::at_resolution(32));
    let o = multires::build(finest, 2, &MultiresOptions::default());
    for level in 0..o.level_count {
        // Vertices of the level near the seam (x = 0.5) come in pairs: one per chart.
        let mut left = 0;
        let mut right = 0;
        for n in o.nodes.iter().filter(|n| n.level == level) {
            for r in &o.ranges[n.first_range as usize..(n.first_range + n.range_count) as usize] {
                for &i in &o.indices[r[1] as usize..(r[1] + r[2]) as usize] {
                    let v = o.vertices[i as usize];
                    // Chart from the UV: the right chart's u is shifted by 0.5.
                    let u_expected_left = v.position[0];
                    if (v.uv[0] - u_expected_left).abs() < 0.2 {
                        left += 1;
                    } else if (v.uv[0] - (u_expected_left + 0.5)).abs() < 0.2 {
                        right += 1;
                    } else {
                        panic!("level {level}: a UV mixes the two charts: {v:?}");
                    }
                }
            }
        }
        if left + right > 0 {
            assert!(left > 0 && right > 0, "level {level}: {left} {right}");
        }
    }
}
