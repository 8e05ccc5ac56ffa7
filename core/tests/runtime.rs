//! The runtime on the golden hierarchy: full split reaches exactly the full-resolution mesh,
//! full collapse returns exactly to the base mesh, emitted indices match their polygons'
//! surface groups, and misuse is refused with typed errors.

mod common;

use std::collections::HashMap;

use caveclod_core::{
    CameraError, CameraState, EmitError, Hierarchy, NodeId, OpError, PolyId, RefineParams,
    SurfaceId,
};
use common::{collapse_all, golden_hierarchy, params, views};

/// Force-splits every active splittable node until none is left; returns the splits applied.
fn split_all(h: &Hierarchy<'_>, cam: &mut CameraState<'_>) -> u32 {
    let mut applied = 0;
    for _ in 0..=h.splits().len() {
        let todo: Vec<NodeId> = cam
            .active_nodes()
            .filter(|&v| h.split(v).is_some())
            .collect();
        if todo.is_empty() {
            break;
        }
        for v in todo {
            if cam.is_node_active(h, v) {
                applied += cam
                    .force_split_own_stack(h, v)
                    .unwrap_or_else(|e| panic!("force split of {v:?}: {e}"));
            }
        }
    }
    applied
}

fn assert_full_resolution(h: &Hierarchy<'_>, cam: &CameraState<'_>) {
    assert_eq!(cam.split_count() as usize, h.splits().len());
    assert_eq!(cam.active_polygon_count() as usize, h.polygon_count());
    assert_eq!(
        cam.active_node_count() as usize,
        h.node_count() - h.splits().len(),
        "every leaf, and only leaves, active"
    );
    for (i, poly) in h.polygons().iter().enumerate() {
        let id = PolyId(i as u32);
        assert!(cam.is_polygon_active(h, id), "{id:?} inactive");
        assert_eq!(cam.polygon_corners(h, id), Some(poly.nodes), "{id:?}");
    }
    let mut active: Vec<NodeId> = cam.active_nodes().collect();
    active.sort();
    let leaves: Vec<NodeId> = (h.splits().len()..h.node_count())
        .map(|i| NodeId(i as u32))
        .collect();
    assert_eq!(active, leaves);
}

fn assert_base_mesh(h: &Hierarchy<'_>, cam: &CameraState<'_>) {
    assert_eq!(cam.split_count(), 0);
    assert_eq!(cam.active_polygon_count() as usize, h.base_polygon_count());
    let mut active: Vec<NodeId> = cam.active_nodes().collect();
    active.sort();
    assert_eq!(active, h.roots());
    for (i, base) in h.base().iter().enumerate() {
        let id = PolyId(i as u32);
        assert_eq!(cam.polygon_corners(h, id), Some(base.corners), "{id:?}");
        assert_eq!(
            cam.polygon_neighbours(h, id),
            Some(base.neighbours),
            "{id:?}"
        );
    }
    for i in h.base_polygon_count()..h.polygon_count() {
        assert!(!cam.is_polygon_active(h, PolyId(i as u32)));
    }
}

/// Every emitted index of surface `s` is the vertex of its polygon's surface group at its
/// corner's position, and that vertex is keyed to that group in the vertex table.
fn assert_emission_matches_groups(h: &Hierarchy<'_>, cam: &CameraState<'_>) {
    let mut group_of_vertex = HashMap::new();
    let offsets = &h.parts().vertex_table_offsets;
    for (p, w) in offsets.windows(2).enumerate() {
        for key in &h.parts().vertex_table[w[0] as usize..w[1] as usize] {
            let old = group_of_vertex.insert(key.vertex, (key.group, p));
            assert!(old.is_none(), "vertex {} keyed twice", key.vertex);
        }
    }
    let total: usize = (0..h.surface_count()).map(|s| cam.index_count(s)).sum();
    let mut out = vec![0u32; total];
    let mut offsets = vec![0u32; h.surface_count() + 1];
    assert_eq!(
        cam.emit_indices_packed(h, &mut out, &mut offsets),
        Ok(total)
    );
    assert_eq!(total, 3 * cam.active_polygon_count() as usize);

    // Emission is in slot order, the order of `active_polygons`.
    let mut cursor = offsets[..h.surface_count()].to_vec();
    for poly_id in cam.active_polygons(h) {
        let poly = &h.polygons()[poly_id.index()];
        let s = poly.surface.index();
        let at = cursor[s] as usize;
        let tri = &out[at..at + 3];
        cursor[s] += 3;
        let corners = cam.polygon_corners(h, poly_id).expect("active");
        for k in 0..3 {
            let position = h.nodes()[corners[k].index()].position;
            let (group, keyed_at) = group_of_vertex[&tri[k]];
            assert_eq!(group, poly.group, "{poly_id:?} corner {k}: wrong group");
            assert_eq!(keyed_at, position.index(), "{poly_id:?} corner {k}");
            assert_eq!(h.vertex_index(poly.group, position), Some(tri[k]));
            assert_eq!(
                h.vertices()[tri[k] as usize].position,
                h.positions()[position.index()].xyz
            );
        }
    }
    for s in 0..h.surface_count() {
        assert_eq!(cursor[s], offsets[s + 1], "surface {s} fully accounted for");
    }

    // The unpacked form writes the same lists.
    let mut lists: Vec<Vec<u32>> = (0..h.surface_count())
        .map(|s| vec![0; cam.index_count(s)])
        .collect();
    let mut slices: Vec<&mut [u32]> = lists.iter_mut().map(|l| l.as_mut_slice()).collect();
    let mut written = vec![0u32; h.surface_count()];
    assert_eq!(cam.emit_indices(h, &mut slices, &mut written), Ok(total));
    for s in 0..h.surface_count() {
        assert_eq!(written[s] as usize, lists[s].len());
        assert_eq!(
            lists[s][..],
            out[offsets[s] as usize..offsets[s + 1] as usize]
        );
    }
}

#[test]
fn full_split_reaches_the_full_resolution_mesh_and_full_collapse_the_base_mesh() {
    let h = golden_hierarchy();
    let mut memory = vec![0u32; CameraState::words_needed(&h)];
    let mut cam = CameraState::new(&h, &mut memory).expect("memory");
    assert_base_mesh(&h, &cam);
    assert_emission_matches_groups(&h, &cam);

    let applied = split_all(&h, &mut cam);
    assert_eq!(applied as usize, h.splits().len());
    assert_full_resolution(&h, &cam);
    assert_emission_matches_groups(&h, &cam);

    let collapsed = collapse_all(&h, &mut cam);
    assert_eq!(collapsed, h.splits().len());
    assert_base_mesh(&h, &cam);

    // And again after refinement moved the front around: split, collapse, split.
    // Compaction in between re-orders the camera's arrays but not the front.
    for (i, view) in views(&h, 8).iter().enumerate() {
        cam.refine(&h, view, &params(i)).expect("refine");
        assert_emission_matches_groups(&h, &cam);
        cam.compact(&h);
        assert_emission_matches_groups(&h, &cam);
    }
    split_all(&h, &mut cam);
    assert_full_resolution(&h, &cam);
    cam.compact(&h);
    assert_full_resolution(&h, &cam);
    collapse_all(&h, &mut cam);
    assert_base_mesh(&h, &cam);
}

/// Every surface's indices, packed, with the offsets.
fn emitted(h: &Hierarchy<'_>, cam: &CameraState<'_>) -> (Vec<u32>, Vec<u32>) {
    let total = (0..h.surface_count()).map(|s| cam.index_count(s)).sum();
    let mut out = vec![0u32; total];
    let mut offsets = vec![0u32; h.surface_count() + 1];
    assert_eq!(
        cam.emit_indices_packed(h, &mut out, &mut offsets),
        Ok(total)
    );
    (out, offsets)
}

/// A camera with the index cache emits exactly what one without it looks up through the
/// hierarchy, after splits, collapses, refinement and compaction, and costs 16 bytes per
/// polygon slot more.
#[test]
fn the_index_cache_changes_no_index() {
    let h = golden_hierarchy();
    let plain_config = caveclod_core::CameraConfig {
        index_cache: false,
        ..caveclod_core::CameraConfig::full(&h)
    };
    let mut memory = vec![0u32; CameraState::words_needed(&h)];
    let mut plain_memory = vec![0u32; CameraState::words_needed_for(&h, &plain_config)];
    let slots = h.base_polygon_count() + 2 * h.splits().len();
    assert_eq!(memory.len() - plain_memory.len(), 4 * slots);
    let mut cam = CameraState::new(&h, &mut memory).expect("memory");
    let mut plain = CameraState::with_config(&h, &mut plain_memory, &plain_config).expect("memory");
    assert_eq!(cam.bytes() - plain.bytes(), 16 * slots);
    assert_eq!(emitted(&h, &cam), emitted(&h, &plain));
    for (i, view) in views(&h, 8).iter().enumerate() {
        let st = cam.refine(&h, view, &params(i)).expect("refine");
        assert_eq!(plain.refine(&h, view, &params(i)), Ok(st));
        assert_eq!(emitted(&h, &cam), emitted(&h, &plain), "view {i}");
        if i % 3 == 2 {
            cam.compact(&h);
            plain.compact(&h);
            assert_eq!(
                emitted(&h, &cam),
                emitted(&h, &plain),
                "compacted, view {i}"
            );
        }
    }
    split_all(&h, &mut cam);
    split_all(&h, &mut plain);
    assert_eq!(emitted(&h, &cam), emitted(&h, &plain));
    collapse_all(&h, &mut cam);
    collapse_all(&h, &mut plain);
    assert_eq!(emitted(&h, &cam), emitted(&h, &plain));
}

#[test]
fn refinement_settles_and_coarsens_again() {
    let h = golden_hierarchy();
    let mut memory = vec![0u32; CameraState::words_needed(&h)];
    let mut cam = CameraState::new(&h, &mut memory).expect("memory");
    let m = h.meta();
    let lo = caveclod_core::glam::Vec3::from_array(m.bounds_min);
    let hi = caveclod_core::glam::Vec3::from_array(m.bounds_max);
    let centre = (lo + hi) * 0.5;
    let size = (hi - lo).length();
    let exact = RefineParams {
        tolerance_px: 1e-6,
        frustum_culling: false,
        backface_culling: false,
        ..RefineParams::default()
    };
    // A tiny tolerance from close by wants every split the errors justify.
    let near = caveclod_core::View::without_frustum(centre + size * 0.1, 1e6);
    // From the base mesh, one pass applies every wanted split (each split's children are
    // looked at in the same pass); a second pass has nothing to do.
    let first = cam.refine(&h, &near, &exact).expect("refine");
    assert!(first.splits > 0, "{first:?}");
    assert_eq!(first.collapses, 0, "{first:?}");
    let again = cam.refine(&h, &near, &exact).expect("refine");
    assert_eq!(again.operations(), 0, "{again:?}");
    let splits = first.splits;
    assert_emission_matches_groups(&h, &cam);
    // From very far with a coarse tolerance, refinement collapses back to the base mesh.
    let far = caveclod_core::View::without_frustum(centre + size * 1e6, 1.0);
    let coarse = RefineParams {
        tolerance_px: 1e6,
        ..exact
    };
    let back = settle(&h, &mut cam, &far, &coarse);
    assert_eq!(back.collapses, splits, "{back:?}");
    assert_eq!(back.splits, 0, "{back:?}");
    assert_base_mesh(&h, &cam);
}

/// Refines from one view until a pass changes nothing (temporal coherence: a still camera
/// settles). One pass walks the active list once, so coarsening a chain of collapses can take
/// up to one pass per level: `max_depth + 2` passes bound it. Returns the summed statistics.
fn settle(
    h: &Hierarchy<'_>,
    cam: &mut CameraState<'_>,
    view: &caveclod_core::View,
    params: &RefineParams,
) -> caveclod_core::RefineStats {
    let mut sum = caveclod_core::RefineStats::default();
    let passes = h.meta().max_depth + 2;
    for _ in 0..passes {
        let st = cam.refine(h, view, params).expect("refine");
        if st.operations() == 0 {
            return sum;
        }
        sum.splits += st.splits;
        sum.collapses += st.collapses;
    }
    panic!("refinement from a fixed view did not settle in {passes} passes: {sum:?}");
}

#[test]
fn too_small_emit_outputs_are_refused() {
    let h = golden_hierarchy();
    let mut memory = vec![0u32; CameraState::words_needed(&h)];
    let mut cam = CameraState::new(&h, &mut memory).expect("memory");
    split_all(&h, &mut cam);
    let ns = h.surface_count();
    let total: usize = (0..ns).map(|s| cam.index_count(s)).sum();
    assert!(total > 0);

    let mut out = vec![0u32; total - 1];
    let mut offsets = vec![0u32; ns + 1];
    assert_eq!(
        cam.emit_indices_packed(&h, &mut out, &mut offsets),
        Err(EmitError::OutputTooSmall {
            surface: None,
            needed: total,
            given: total - 1
        })
    );
    let mut out = vec![0u32; total];
    let mut short_offsets = vec![0u32; ns];
    assert_eq!(
        cam.emit_indices_packed(&h, &mut out, &mut short_offsets),
        Err(EmitError::TooFewOutputs {
            needed: ns + 1,
            given: ns
        })
    );

    // Unpacked: the last surface's list one index short, then one list missing.
    let mut lists: Vec<Vec<u32>> = (0..ns).map(|s| vec![0; cam.index_count(s)]).collect();
    let last = ns - 1;
    let needed = cam.index_count(last);
    assert!(needed > 0);
    lists[last].pop();
    let mut written = vec![0u32; ns];
    {
        let mut slices: Vec<&mut [u32]> = lists.iter_mut().map(|l| l.as_mut_slice()).collect();
        assert_eq!(
            cam.emit_indices(&h, &mut slices, &mut written),
            Err(EmitError::OutputTooSmall {
                surface: Some(SurfaceId(last as u16)),
                needed,
                given: needed - 1
            })
        );
        let (_, fewer) = slices.split_last_mut().expect("surfaces");
        assert_eq!(
            cam.emit_indices(&h, fewer, &mut written),
            Err(EmitError::TooFewOutputs {
                needed: ns,
                given: ns - 1
            })
        );
    }
}

#[test]
fn too_little_camera_memory_is_refused() {
    let h = golden_hierarchy();
    let needed = CameraState::words_needed(&h);
    let mut memory = vec![0u32; needed - 1];
    assert_eq!(
        CameraState::new(&h, &mut memory).err(),
        Some(CameraError::Capacity {
            needed,
            given: needed - 1
        })
    );
    let mut memory = vec![0u32; needed + 10];
    assert!(
        CameraState::new(&h, &mut memory).is_ok(),
        "extra words are fine"
    );

    let ns = h.splits().len() as u32;
    let config = caveclod_core::CameraConfig {
        max_pairs: ns + 1,
        stack_len: 64,
        index_cache: true,
        hashed_pair_map: false,
        max_morphs: 0,
        edit_list: 0,
    };
    assert_eq!(
        CameraState::with_config(&h, &mut memory, &config).err(),
        Some(CameraError::TooManyPairs {
            max_pairs: ns + 1,
            split_count: ns
        })
    );
}

#[test]
fn a_full_camera_refuses_splits_without_failing() {
    let h = golden_hierarchy();
    let config = caveclod_core::CameraConfig {
        max_pairs: 3,
        stack_len: 256,
        index_cache: true,
        hashed_pair_map: true,
        max_morphs: 0,
        edit_list: 0,
    };
    let mut memory = vec![0u32; CameraState::words_needed_for(&h, &config)];
    let mut cam = CameraState::with_config(&h, &mut memory, &config).expect("memory");
    let m = h.meta();
    let centre = (caveclod_core::glam::Vec3::from_array(m.bounds_min)
        + caveclod_core::glam::Vec3::from_array(m.bounds_max))
        * 0.5;
    let view = caveclod_core::View::without_frustum(centre, 1e6);
    let stats = cam
        .refine(
            &h,
            &view,
            &RefineParams {
                tolerance_px: 1e-6,
                backface_culling: false,
                ..RefineParams::default()
            },
        )
        .expect("refine");
    assert_eq!(cam.split_count(), 3);
    assert!(stats.capacity_refusals > 0, "{stats:?}");
    assert_emission_matches_groups(&h, &cam);
    let next = cam
        .active_nodes()
        .find(|&v| cam.can_split(&h, v))
        .expect("a legal split left");
    assert_eq!(
        cam.split(&h, next),
        Err(OpError::CapacityFull { max_pairs: 3 })
    );
}

#[test]
fn a_camera_is_refused_by_another_hierarchy() {
    let h = golden_hierarchy();
    // The same arrays, validated in memory: a different identity.
    let other = Hierarchy::from_parts(*h.parts()).expect("same parts");
    assert_ne!(h.checksum(), other.checksum());
    let mut memory = vec![0u32; CameraState::words_needed(&h)];
    let mut cam = CameraState::new(&h, &mut memory).expect("memory");
    assert!(cam.is_for(&h));
    assert!(!cam.is_for(&other));

    let root = h.roots()[0];
    let splittable = cam
        .active_nodes()
        .find(|&v| cam.can_split(&h, v))
        .expect("a legal split");
    assert!(!cam.can_split(&other, splittable));
    assert_eq!(cam.split(&other, splittable), Err(OpError::WrongHierarchy));
    assert_eq!(cam.collapse(&other, root), Err(OpError::WrongHierarchy));
    assert_eq!(
        cam.force_split_own_stack(&other, splittable),
        Err(OpError::WrongHierarchy)
    );
    let view = views(&h, 1)[0];
    assert_eq!(
        cam.refine(&other, &view, &RefineParams::default()),
        Err(OpError::WrongHierarchy)
    );
    assert_eq!(
        cam.lag(&other, &view, &RefineParams::default()),
        Err(OpError::WrongHierarchy)
    );
    let mut out = vec![0u32; 3 * h.polygon_count()];
    let mut offsets = vec![0u32; h.surface_count() + 1];
    assert_eq!(
        cam.emit_indices_packed(&other, &mut out, &mut offsets),
        Err(EmitError::WrongHierarchy)
    );
    // Nothing changed, and the right hierarchy still works.
    assert_eq!(cam.split_count(), 0);
    cam.split(&h, splittable).expect("legal split");
    assert_eq!(cam.split_count(), 1);
}

#[test]
fn operations_on_the_wrong_nodes_are_refused() {
    let h = golden_hierarchy();
    let mut memory = vec![0u32; CameraState::words_needed(&h)];
    let mut cam = CameraState::new(&h, &mut memory).expect("memory");
    let leaf = NodeId(h.node_count() as u32 - 1);
    assert_eq!(cam.split(&h, leaf), Err(OpError::Leaf { node: leaf }));
    let beyond = NodeId(h.node_count() as u32 + 7);
    assert_eq!(
        cam.split(&h, beyond),
        Err(OpError::NotActive { node: beyond })
    );
    let root = h.roots()[0];
    if h.split(root).is_some() {
        assert_eq!(
            cam.collapse(&h, root),
            Err(OpError::NotSplit { node: root })
        );
    }
    // A node below the front is not active; a collapse of an unsplit node is refused.
    if let Some(s) = h.split(root) {
        for child in [s.stationary, s.floating] {
            if h.split(child).is_some() {
                assert_eq!(
                    cam.split(&h, child),
                    Err(OpError::NotActive { node: child })
                );
            }
        }
    }
    assert_eq!(cam.split_count(), 0);
}

/// From the base mesh a pass only splits, so the splits it reports must be the splits the
/// camera holds afterwards, also when a chain of forced splits runs into `CapacityFull`
/// part-way (the splits applied before the refusal stay, as `force_split` documents). They
/// used to be left out of `RefineStats::splits` and of the `max_ops` count: on the golden
/// file, `max_pairs` 2 to 4 reported 1 split for 2 to 4 applied (found as a bug, fixed).
#[test]
fn refine_stats_count_every_split_applied() {
    let h = golden_hierarchy();
    let m = h.meta();
    let centre = (caveclod_core::glam::Vec3::from_array(m.bounds_min)
        + caveclod_core::glam::Vec3::from_array(m.bounds_max))
        * 0.5;
    let view = caveclod_core::View::without_frustum(centre, 1e6);
    let params = RefineParams {
        tolerance_px: 1e-6,
        backface_culling: false,
        ..RefineParams::default()
    };
    for max_pairs in 1..=8 {
        let config = caveclod_core::CameraConfig {
            max_pairs,
            stack_len: 256,
            index_cache: true,
            // Both layouts of the pair map (small budgets hash where asked).
            hashed_pair_map: max_pairs % 2 == 0,
            max_morphs: 0,
            edit_list: 0,
        };
        let mut memory = vec![0u32; CameraState::words_needed_for(&h, &config)];
        let mut cam = CameraState::with_config(&h, &mut memory, &config).expect("memory");
        let stats = cam.refine(&h, &view, &params).expect("refine");
        assert_eq!(
            stats.splits,
            cam.split_count(),
            "max_pairs {max_pairs}: {stats:?}"
        );
    }
}
