//! Invariant checks of a camera's front against the hierarchy, derived from scratch.

use std::collections::HashSet;

use caveclod_core::{CameraState, Hierarchy, HierarchyRecords, NodeId, PolyId};

/// Checks every invariant of `cam` over `h`; returns a description of the first violation.
pub fn check_front(h: &Hierarchy<'_>, cam: &CameraState<'_>) -> Result<(), String> {
    let (want_nodes, want_polys) = derived_front(h, cam);
    let polys = check_active_sets(h, cam, &want_nodes, &want_polys)?;
    for &f in &polys {
        let corners = check_corners(h, cam, f, &want_nodes)?;
        check_neighbours(h, cam, f, corners)?;
    }
    check_emission(h, cam, &polys)
}

/// The active nodes and polygons derived from scratch from the split state alone.
fn derived_front(h: &Hierarchy<'_>, cam: &CameraState<'_>) -> (HashSet<NodeId>, HashSet<PolyId>) {
    let split = |v: NodeId| cam.is_split(v);
    let mut want_nodes = HashSet::new();
    for (i, n) in h.nodes().iter().enumerate() {
        let v = NodeId(i as u32);
        let created = n.parent.is_none() || split(n.parent);
        if created && !(h.split(v).is_some() && split(v)) {
            want_nodes.insert(v);
        }
    }
    let mut want_polys: HashSet<PolyId> = (0..h.base_polygon_count() as u32).map(PolyId).collect();
    for (i, s) in h.splits().iter().enumerate() {
        if split(NodeId(i as u32)) {
            want_polys.insert(s.f_l);
            if s.f_r.is_some() {
                want_polys.insert(s.f_r);
            }
        }
    }
    (want_nodes, want_polys)
}

/// The camera's active nodes and polygons, their counts and `is_node_active` against the
/// derived sets; returns the active polygons in the camera's order.
fn check_active_sets(
    h: &Hierarchy<'_>,
    cam: &CameraState<'_>,
    want_nodes: &HashSet<NodeId>,
    want_polys: &HashSet<PolyId>,
) -> Result<Vec<PolyId>, String> {
    let polys = compare_active_sets(h, cam, want_nodes, want_polys)?;
    for v in h.nodes().iter().enumerate().map(|(i, _)| NodeId(i as u32)) {
        if cam.is_node_active(h, v) != want_nodes.contains(&v) {
            return Err(format!("is_node_active({v}) wrong"));
        }
    }
    Ok(polys)
}

/// The camera's active nodes and polygons, each listed once and counted, against the
/// derived sets; returns the active polygons in the camera's order.
fn compare_active_sets(
    h: &impl HierarchyRecords,
    cam: &CameraState<'_>,
    want_nodes: &HashSet<NodeId>,
    want_polys: &HashSet<PolyId>,
) -> Result<Vec<PolyId>, String> {
    let nodes: HashSet<NodeId> = cam.active_nodes().collect();
    if nodes.len() != cam.active_node_count() as usize || &nodes != want_nodes {
        return Err(format!(
            "active nodes {} (count {}) differ from the derived {}",
            nodes.len(),
            cam.active_node_count(),
            want_nodes.len()
        ));
    }
    let polys: Vec<PolyId> = cam.active_polygons(h).collect();
    let poly_set: HashSet<PolyId> = polys.iter().copied().collect();
    if polys.len() != poly_set.len()
        || &poly_set != want_polys
        || polys.len() != cam.active_polygon_count() as usize
    {
        return Err(format!(
            "active polygons {} differ from the derived {}",
            polys.len(),
            want_polys.len()
        ));
    }
    Ok(polys)
}

/// Each corner of `f` is active and the active ancestor of its full-resolution corner;
/// returns the corners.
fn check_corners(
    h: &Hierarchy<'_>,
    cam: &CameraState<'_>,
    f: PolyId,
    want_nodes: &HashSet<NodeId>,
) -> Result<[NodeId; 3], String> {
    let corners = cam
        .polygon_corners(h, f)
        .ok_or(format!("{f} has no corners"))?;
    let full = h.polygons()[f.index()].nodes;
    for k in 0..3 {
        if !want_nodes.contains(&corners[k]) {
            return Err(format!("{f} corner {k} = {} is not active", corners[k]));
        }
        let mut a = full[k];
        while a != corners[k] {
            a = h.nodes()[a.index()].parent;
            if a.is_none() {
                return Err(format!(
                    "{f} corner {k} = {} is not above its leaf {}",
                    corners[k], full[k]
                ));
            }
        }
    }
    Ok(corners)
}

/// Every neighbour link of `f` is symmetric, across the edge the two share.
fn check_neighbours(
    h: &impl HierarchyRecords,
    cam: &CameraState<'_>,
    f: PolyId,
    corners: [NodeId; 3],
) -> Result<(), String> {
    let nbrs = cam
        .polygon_neighbours(h, f)
        .ok_or(format!("{f} has no neighbours"))?;
    for j in 0..3 {
        let g = nbrs[j];
        if g.is_none() {
            continue;
        }
        let (a, b) = (corners[(j + 1) % 3], corners[(j + 2) % 3]);
        let gc = cam
            .polygon_corners(h, g)
            .ok_or(format!("{f} neighbour {g} inactive"))?;
        let gn = cam
            .polygon_neighbours(h, g)
            .ok_or(format!("{g} has no neighbours"))?;
        let back = (0..3).find(|&m| gc[m] != a && gc[m] != b);
        if !gc.contains(&a) || !gc.contains(&b) || back.map(|m| gn[m]) != Some(f) {
            return Err(format!(
                "neighbour link {f} -> {g} across ({a}, {b}) not symmetric"
            ));
        }
    }
    Ok(())
}

/// Emission: every index is the vertex of the polygon's group at the corner's position, and
/// each surface's list holds exactly its polygons.
fn check_emission(
    h: &impl HierarchyRecords,
    cam: &CameraState<'_>,
    polys: &[PolyId],
) -> Result<(), String> {
    let ns = h.surface_count();
    let total: usize = (0..ns).map(|s| cam.index_count(s)).sum();
    let mut out = vec![0u32; total];
    let mut offsets = vec![0u32; ns + 1];
    cam.emit_indices_packed(h, &mut out, &mut offsets)
        .map_err(|e| e.to_string())?;
    let mut cursor = offsets.clone();
    for &f in polys {
        let poly = *h.polygon(f).ok_or(format!("{f} has no record"))?;
        let s = poly.surface.index();
        let corners = cam.polygon_corners(h, f).ok_or("corners")?;
        for k in 0..3 {
            let idx = out[cursor[s] as usize + k];
            let pos = h
                .node(corners[k])
                .ok_or(format!("{f} corner {k} has no record"))?
                .position;
            let keys = h.vertex_keys(pos);
            if !keys
                .iter()
                .any(|key| key.vertex == idx && key.group == poly.group)
            {
                return Err(format!(
                    "{f} corner {k}: index {idx} is not group {}'s vertex at {pos}",
                    poly.group.0
                ));
            }
            let at = h.position(pos).map(|p| p.xyz);
            if h.vertex(idx).map(|v| v.position) != at || at.is_none() {
                return Err(format!(
                    "{f} corner {k}: vertex {idx} not at the corner's position"
                ));
            }
        }
        cursor[s] += 3;
    }
    for s in 0..ns {
        if cursor[s] != offsets[s + 1] {
            return Err(format!(
                "surface {s}: emitted {} indices, {} expected",
                offsets[s + 1] - offsets[s],
                cursor[s] - offsets[s]
            ));
        }
    }
    Ok(())
}

/// Every invariant of `cam` over records that may be streamed (only what the front stands
/// on is read): the active nodes are exactly those found by descending from the roots
/// through the split nodes, the active polygons exactly the base polygons and those the
/// splits made, each listed once and counted; every corner is active; every neighbour link
/// is symmetric; emission gives each corner its group's vertex at the corner's position.
pub fn check_records_front(h: &impl HierarchyRecords, cam: &CameraState<'_>) -> Result<(), String> {
    let mut want_nodes = HashSet::new();
    let mut want_polys: HashSet<PolyId> = (0..h.base_polygon_count() as u32).map(PolyId).collect();
    let mut stack: Vec<NodeId> = h.roots().to_vec();
    while let Some(v) = stack.pop() {
        if !cam.is_split(v) {
            want_nodes.insert(v);
            continue;
        }
        let s = h
            .split(v)
            .ok_or(format!("split node {v} has no split record"))?;
        want_polys.insert(s.f_l);
        if s.f_r.is_some() {
            want_polys.insert(s.f_r);
        }
        stack.extend([s.stationary, s.floating]);
    }
    let polys = compare_active_sets(h, cam, &want_nodes, &want_polys)?;
    for &f in &polys {
        let corners = cam
            .polygon_corners(h, f)
            .ok_or(format!("{f} has no corners"))?;
        if let Some(k) = (0..3).find(|&k| !want_nodes.contains(&corners[k])) {
            return Err(format!("{f} corner {k} = {} is not active", corners[k]));
        }
        check_neighbours(h, cam, f, corners)?;
    }
    check_emission(h, cam, &polys)
}

/// Splits everything (forcing as needed) until no active node can be split.
pub fn split_all(h: &Hierarchy<'_>, cam: &mut CameraState<'_>) {
    let mut stack = vec![NodeId::NONE; 4096];
    loop {
        let todo: Vec<NodeId> = cam
            .active_nodes()
            .filter(|&v| h.split(v).is_some())
            .collect();
        if todo.is_empty() {
            return;
        }
        for v in todo {
            if !cam.is_split(v) {
                if let Err(e) = cam.force_split(h, v, &mut stack) {
                    panic!("force_split({v}): {e}");
                }
            }
        }
    }
}

/// Collapses until no collapse is legal; returns the number applied.
pub fn collapse_all(h: &Hierarchy<'_>, cam: &mut CameraState<'_>) -> usize {
    let mut n = 0;
    loop {
        let mut any = false;
        for i in 0..h.splits().len() {
            let v = NodeId(i as u32);
            if cam.can_collapse(h, v) {
                if let Err(e) = cam.collapse(h, v) {
                    panic!("collapse({v}): {e}");
                }
                n += 1;
                any = true;
            }
        }
        if !any {
            return n;
        }
    }
}
