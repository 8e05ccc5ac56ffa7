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
        surfaces: vec![Surface::plain("a"), Surface::plain("b")],
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
    // Nodes on both sides of a block border hold the triangles crossing it.
    v.dedup();
    v
}

fn level_triangles(o: &multires::MultiresOctree, level: u32) -> Vec<[[f32; 3]; 3]> {
    let mut out = Vec::new();
    for n in o.nodes.iter().filter(|n| n.level == level) {
        for r in &o.ranges[n.first_range as usize..(n.first_range + n.range_count) as usize] {
            for t in o.indices[r.first_index as usize..(r.first_index + r.index_count) as usize]
                .chunks(3)
            {
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
            assert!(
                w[0].surface < w[1].surface,
                "surfaces ascending in node {i}"
            );
        }
        for r in ranges {
            assert!(r.surface < 2 && r.index_count > 0 && r.index_count % 3 == 0);
            assert!((r.first_index + r.index_count) as usize <= o.indices.len());
        }
    }
    assert_eq!(next as usize, o.nodes.len());
    // And the core validates it.
    caveclod_core::Octree::new(o.parts()).expect("the core accepts the octree");
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
fn every_input_vertex_lies_within_its_nodes_error_of_the_level() {
    let mesh = field(40, true, false);
    let (_, finest) = cluster_mesh_in(&mesh, cube(), ClusterOptions::at_resolution(32));
    // Blocks of 4 cells: nodes inside the field and nodes on its border.
    let options = MultiresOptions {
        block_levels: 2,
        coarsest_triangles: 20,
    };
    let o = multires::build(finest, 2, &options);
    assert!(o.level_count >= 3);
    for level in 0..o.level_count {
        let nodes: Vec<_> = o.nodes.iter().filter(|n| n.level == level).collect();
        let tris = level_triangles(&o, level);
        let on_border = |n: &&caveclod_core::octree::OctreeNode| {
            n.min[0] <= 0.0 || n.min[2] <= 0.0 || n.max[0] >= 1.0 || n.max[2] >= 1.0
        };
        let border_error = nodes
            .iter()
            .filter(|n| on_border(n))
            .map(|n| n.error)
            .fold(0.0f32, f32::max);
        for p in &mesh.positions {
            let d = tris
                .iter()
                .map(|&t| point_triangle_distance(*p, t))
                .fold(f32::MAX, f32::min);
            // The largest error of the nodes whose box holds the vertex.
            let bound = nodes
                .iter()
                .filter(|n| (0..3).all(|a| p[a] >= n.min[a] - 1e-6 && p[a] <= n.max[a] + 1e-6))
                .map(|n| n.error)
                .fold(0.0f32, f32::max);
            assert!(
                d <= bound,
                "level {level}: input vertex {p:?} is {d} from the level, its nodes' bound {bound}"
            );
        }
        // The bounds are not vacuous: a few cells of the level on the field's border (where
        // the surface shrinks), mostly a fraction of that inside it, where only the deviation
        // across the surface counts.
        let cell = cube().size as f32 / 32.0 * (1u32 << level) as f32;
        assert!(
            border_error <= 3.0 * cell,
            "level {level}: {border_error} vs cell {cell}"
        );
        let mut inside: Vec<f32> = nodes
            .iter()
            .filter(|n| !on_border(n))
            .map(|n| n.error)
            .collect();
        inside.sort_by(f32::total_cmp);
        if let Some(median) = inside.get(inside.len() / 2) {
            assert!(
                *median <= 0.5 * border_error,
                "level {level}: inside {inside:?}, border {border_error}, cell {cell}"
            );
        }
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
                for &i in
                    &o.indices[r.first_index as usize..(r.first_index + r.index_count) as usize]
                {
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

/// Aligned copy of `.clod` bytes (the format is read in place).
fn aligned(bytes: &[u8]) -> Vec<u64> {
    let mut words = vec![0u64; bytes.len().div_ceil(8)];
    bytemuck::cast_slice_mut::<u64, u8>(&mut words)[..bytes.len()].copy_from_slice(bytes);
    words
}

#[test]
fn an_out_of_core_bake_stores_the_octree_and_cameras_cut_it_by_distance() {
    use caveclod_bake::pipeline;
    use caveclod_core::glam::Vec3;
    use caveclod_core::{Hierarchy, LookAt, Octree, OctreeCut};
    use caveclod_tests::generate;

    let dir = tempfile::tempdir().unwrap();
    let temp = tempfile::tempdir().unwrap();
    let input = dir.path().join("terrain.ply");
    generate::terrain(&input, 60_000, &mut |_, _| {}).unwrap();
    let options = caveclod_bake::ooc::OocOptions {
        temp_dir: Some(temp.path().to_path_buf()),
        leaf_triangles: 1 << 10,
        target_triangles: Some(8000),
        octree: Some(MultiresOptions {
            block_levels: 3,
            coarsest_triangles: 256,
        }),
        ..caveclod_bake::ooc::OocOptions::with_budget(8 << 20)
    };
    let out = pipeline::bake_out_of_core(&input, &options, &mut |_| {}, &mut |_| {}).unwrap();
    let octree = out.octree.as_ref().expect("the octree was asked for");
    // The finest level is the mesh handed to the hierarchy.
    assert_eq!(octree.level_triangles[0], out.stats.output_triangles);
    assert_eq!(out.stats.lod_levels, octree.level_count);
    let bytes = out.baked.to_bytes(&octree.parts().sections()).unwrap();
    let words = aligned(&bytes);
    let bytes = &bytemuck::cast_slice::<u64, u8>(&words)[..bytes.len()];
    let h = Hierarchy::from_bytes(bytes).unwrap();
    let t = Octree::from_hierarchy(&h)
        .unwrap()
        .expect("octree sections");
    assert_eq!(t.surface_count(), h.surface_count());
    assert!(t.level_count() >= 4, "{}", t.level_count());

    let size = generate::TERRAIN_SIZE;
    let centre = Vec3::new(size * 0.5, 0.0, size * 0.5);
    let view = |eye: Vec3, target: Vec3| {
        LookAt {
            eye,
            target,
            up: Vec3::Y,
            fov_y: 1.0,
            near: 0.1,
            far: 1e8,
        }
        .view(1000, 1000)
    };
    let far = view(centre + Vec3::new(0.0, 1000.0 * size, 0.1), centre);
    let near = view(Vec3::new(-0.05 * size, 0.03 * size, -0.05 * size), centre);
    let away = view(
        centre + Vec3::new(0.0, size, 0.0),
        centre + Vec3::new(0.0, 2.0 * size, 0.0),
    );
    let mut memory = [
        vec![0u32; OctreeCut::words_needed(&t)],
        vec![0u32; OctreeCut::words_needed(&t)],
    ];
    let [m0, m1] = &mut memory;
    let mut a = OctreeCut::new(&t, m0).unwrap();
    let mut b = OctreeCut::new(&t, m1).unwrap();
    let sa = a.select(&t, &far, 1.0).unwrap();
    // The test terrain's finest level is coarse (8,000 triangles, error bounds of about 50 m
    // for a 1 km square), so a coarse tolerance is what shows several levels in one view.
    let sb = b.select(&t, &near, 200.0).unwrap();
    let levels = |cut: &OctreeCut<'_>| -> Vec<u32> {
        cut.selected()
            .iter()
            .map(|&n| t.nodes()[n as usize].level)
            .collect()
    };
    // Far above (the terrain about a pixel wide): the root alone; near a corner: the finest
    // level near it, coarser far away.
    assert_eq!(a.selected(), &[0], "{:?}", levels(&a));
    assert!(sb.triangles > 4 * sa.triangles, "{sa:?} {sb:?}");
    let lb = levels(&b);
    assert!(lb.contains(&0), "{lb:?}");
    assert!(lb.iter().any(|&l| l >= 2), "{lb:?}");
    // Near nodes are finer than far ones.
    let dist = |n: u32| {
        let node = &t.nodes()[n as usize];
        let c = (Vec3::from_array(node.min) + Vec3::from_array(node.max)) * 0.5;
        c.distance(near.eye)
    };
    let (mut fine, mut coarse) = (Vec::new(), Vec::new());
    for &n in b.selected() {
        if t.nodes()[n as usize].level == 0 {
            fine.push(dist(n));
        } else if t.nodes()[n as usize].level >= 2 {
            coarse.push(dist(n));
        }
    }
    let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len() as f32;
    assert!(mean(&fine) < mean(&coarse), "{fine:?} {coarse:?}");
    // Emission: each surface's list is its ranges of the selected nodes, in node order.
    let mut indices = vec![0u32; b.total_index_count()];
    let mut offsets = vec![0u32; t.surface_count() + 1];
    let n = b
        .emit_indices_packed(&t, &mut indices, &mut offsets)
        .unwrap();
    assert_eq!(n, 3 * sb.triangles as usize);
    for s in 0..t.surface_count() {
        let want: Vec<u32> = b
            .selected()
            .iter()
            .flat_map(|&id| t.node_ranges(id).iter().filter(|r| r.surface as usize == s))
            .flat_map(|r| t.range_indices(r).iter().copied())
            .collect();
        assert_eq!(
            &indices[offsets[s] as usize..offsets[s + 1] as usize],
            &want[..]
        );
    }
    assert!(indices.iter().all(|&i| (i as usize) < t.vertices().len()));
    // Looking away: nothing; the other camera's cut is untouched.
    let before = b.selected().to_vec();
    let s = a.select(&t, &away, 1.0).unwrap();
    assert_eq!(s.selected, 0);
    assert_eq!(b.selected(), &before[..]);
}

#[test]
fn a_mesh_below_the_target_gets_a_few_levels_not_one_per_grid_halving() {
    // Clustered at 2^21 cells per axis (what an input below the target gets): every triangle
    // kept; the octree starts where coarsening begins to merge.
    let mesh = field(40, false, false);
    let (_, finest) = cluster_mesh_in(&mesh, cube(), ClusterOptions::at_resolution(1 << 21));
    let o = multires::build(finest, 2, &MultiresOptions::default());
    assert!(o.level_count <= 6, "{} levels", o.level_count);
    assert!(o.nodes.len() < 100, "{} nodes", o.nodes.len());
    assert!(o.level_triangles[0] as f64 >= 0.95 * mesh.triangles.len() as f64);
    caveclod_core::Octree::new(o.parts()).expect("valid");
}
