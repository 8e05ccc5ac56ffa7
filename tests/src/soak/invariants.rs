//! The full invariants of a camera's front, derived from scratch, without allocating: the
//! soak checks them inside its frame loop, under a counting allocator that must stay at zero.
//!
//! What [`check_front`](crate::check::check_front) checks, with scratch arrays sized once
//! from the hierarchy instead of hash sets, plus the geomorphs:
//! - the active nodes are exactly those derived from the split state alone (created: a root
//!   or a split parent; not split), each listed once, and the counts agree;
//! - the active polygons are exactly the base polygons and the `f_l`, `f_r` of split nodes,
//!   each once in slot order;
//! - every corner is active and an ancestor of the polygon's full-resolution corner;
//! - every neighbour link is symmetric across the shared edge;
//! - emission writes per surface, in slot order, for each corner the vertex of the polygon's
//!   surface group at the corner's position;
//! - every live morph slot has `t` in `[0, 1]`, `to` at an active node's position, `coarse`
//!   at the position of the split parent whose floating child that is, `from` naming
//!   `coarse`'s slot while `coarse` morphs and `coarse` otherwise, no vertex in two slots;
//!   and morphed emission is the plain one with exactly the morphing vertices replaced by
//!   `vertex_count + slot`.

use caveclod_core::{CameraState, Hierarchy, NodeId, PolyId};

const NONE: u32 = u32::MAX;

/// What one check looked at.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Checked {
    /// Active nodes.
    pub nodes: u64,
    /// Active polygons.
    pub polygons: u64,
    /// Neighbour links followed both ways.
    pub links: u64,
    /// Indices emitted (plain and morphed).
    pub indices: u64,
    /// Live morph vertex slots.
    pub morph_slots: u64,
}

/// Scratch memory for [`FrontChecker::check`], sized for one hierarchy.
#[derive(Debug)]
pub struct FrontChecker {
    /// Per node: 0 inactive, 1 derived active, 2 derived active and listed by the camera.
    node_mark: Vec<u8>,
    /// Per polygon, the same for polygons.
    poly_mark: Vec<u8>,
    /// Per position: the active node standing there, or `NONE`.
    active_at: Vec<u32>,
    /// Per vertex: its position.
    vertex_position: Vec<u32>,
    /// Per vertex: its morph slot + 1, or 0.
    vertex_slot: Vec<u32>,
    plain: Vec<u32>,
    morphed: Vec<u32>,
    offsets: Vec<u32>,
    morphed_offsets: Vec<u32>,
    cursor: Vec<u32>,
}

impl FrontChecker {
    /// Scratch for cameras over `h` (the only allocations; [`check`](Self::check) makes
    /// none while the camera holds, and describes a violation in an allocated string).
    pub fn new(h: &Hierarchy<'_>) -> Self {
        let parts = h.parts();
        let mut vertex_position = vec![NONE; h.vertices().len()];
        for (p, w) in parts.vertex_table_offsets.windows(2).enumerate() {
            for key in &parts.vertex_table[w[0] as usize..w[1] as usize] {
                vertex_position[key.vertex as usize] = p as u32;
            }
        }
        let ns = h.surface_count();
        Self {
            node_mark: vec![0; h.node_count()],
            poly_mark: vec![0; h.polygon_count()],
            active_at: vec![NONE; h.positions().len()],
            vertex_position,
            vertex_slot: vec![0; h.vertices().len()],
            plain: vec![0; 3 * h.polygon_count()],
            morphed: vec![0; 3 * h.polygon_count()],
            offsets: vec![0; ns + 1],
            morphed_offsets: vec![0; ns + 1],
            cursor: vec![0; ns + 1],
        }
    }

    /// Checks every invariant of `cam` over `h`; the first violation, described.
    pub fn check(&mut self, h: &Hierarchy<'_>, cam: &CameraState<'_>) -> Result<Checked, String> {
        let mut done = Checked::default();
        self.derive(h, cam);
        self.check_nodes(h, cam, &mut done)?;
        self.check_polygons(h, cam, &mut done)?;
        self.check_emission(h, cam, &mut done)?;
        self.check_morphs(h, cam, &mut done)?;
        Ok(done)
    }

    /// Marks the active nodes and polygons derived from the split state alone.
    fn derive(&mut self, h: &Hierarchy<'_>, cam: &CameraState<'_>) {
        for (i, n) in h.nodes().iter().enumerate() {
            let v = NodeId(i as u32);
            let created = n.parent.is_none() || cam.is_split(n.parent);
            let split = h.split(v).is_some() && cam.is_split(v);
            self.node_mark[i] = u8::from(created && !split);
        }
        self.poly_mark.fill(0);
        self.poly_mark[..h.base_polygon_count()].fill(1);
        for (i, s) in h.splits().iter().enumerate() {
            if cam.is_split(NodeId(i as u32)) {
                self.poly_mark[s.f_l.index()] = 1;
                if s.f_r.is_some() {
                    self.poly_mark[s.f_r.index()] = 1;
                }
            }
        }
    }

    fn check_nodes(
        &mut self,
        h: &Hierarchy<'_>,
        cam: &CameraState<'_>,
        done: &mut Checked,
    ) -> Result<(), String> {
        self.active_at.fill(NONE);
        let mut listed = 0u64;
        for v in cam.active_nodes() {
            let mark = self
                .node_mark
                .get_mut(v.index())
                .ok_or_else(|| format!("{v} out of range"))?;
            match *mark {
                0 => return Err(format!("{v} is listed active but derived inactive")),
                2 => return Err(format!("{v} is listed twice")),
                _ => *mark = 2,
            }
            let p = h.nodes()[v.index()].position.index();
            if self.active_at[p] != NONE {
                return Err(format!(
                    "{v} and {} stand at one position",
                    self.active_at[p]
                ));
            }
            self.active_at[p] = v.0;
            listed += 1;
        }
        if let Some(i) = self.node_mark.iter().position(|&m| m == 1) {
            return Err(format!(
                "{} is derived active but not listed",
                NodeId(i as u32)
            ));
        }
        if listed != u64::from(cam.active_node_count()) {
            return Err(format!(
                "{listed} active nodes listed, active_node_count {}",
                cam.active_node_count()
            ));
        }
        for (i, &m) in self.node_mark.iter().enumerate() {
            let v = NodeId(i as u32);
            if cam.is_node_active(h, v) != (m == 2) {
                return Err(format!("is_node_active({v}) differs from the derivation"));
            }
        }
        done.nodes += listed;
        Ok(())
    }

    fn check_polygons(
        &mut self,
        h: &Hierarchy<'_>,
        cam: &CameraState<'_>,
        done: &mut Checked,
    ) -> Result<(), String> {
        let mut listed = 0u64;
        for f in cam.active_polygons(h) {
            let mark = self
                .poly_mark
                .get_mut(f.index())
                .ok_or_else(|| format!("{f} out of range"))?;
            match *mark {
                0 => return Err(format!("{f} is listed active but derived inactive")),
                2 => return Err(format!("{f} is listed twice")),
                _ => *mark = 2,
            }
            listed += 1;
            if !cam.is_polygon_active(h, f) {
                return Err(format!("{f} listed but is_polygon_active is false"));
            }
            let corners = cam
                .polygon_corners(h, f)
                .ok_or_else(|| format!("{f} has no corners"))?;
            self.check_corners(h, f, corners)?;
            let nbrs = cam
                .polygon_neighbours(h, f)
                .ok_or_else(|| format!("{f} has no neighbours"))?;
            for j in 0..3 {
                if nbrs[j].is_some() {
                    check_link(h, cam, f, corners, j, nbrs[j])?;
                    done.links += 1;
                }
            }
        }
        if let Some(i) = self.poly_mark.iter().position(|&m| m == 1) {
            return Err(format!(
                "{} is derived active but not listed",
                PolyId(i as u32)
            ));
        }
        if listed != u64::from(cam.active_polygon_count()) {
            return Err(format!(
                "{listed} active polygons listed, active_polygon_count {}",
                cam.active_polygon_count()
            ));
        }
        done.polygons += listed;
        Ok(())
    }

    /// Every corner active, and the active ancestor of the full-resolution corner.
    fn check_corners(
        &self,
        h: &Hierarchy<'_>,
        f: PolyId,
        corners: [NodeId; 3],
    ) -> Result<(), String> {
        let full = h.polygons()[f.index()].nodes;
        for k in 0..3 {
            if self.node_mark.get(corners[k].index()) != Some(&2) {
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
        Ok(())
    }

    /// Plain emission: per surface in slot order, each corner the vertex of the polygon's
    /// group at the corner's position.
    fn check_emission(
        &mut self,
        h: &Hierarchy<'_>,
        cam: &CameraState<'_>,
        done: &mut Checked,
    ) -> Result<(), String> {
        let ns = h.surface_count();
        let total = cam.total_index_count();
        let n = cam
            .emit_indices_packed(h, &mut self.plain[..total], &mut self.offsets)
            .map_err(|e| format!("plain emission: {e}"))?;
        if n != total {
            return Err(format!("emitted {n} indices, {total} expected"));
        }
        self.cursor.copy_from_slice(&self.offsets);
        for f in cam.active_polygons(h) {
            let poly = h.polygons()[f.index()];
            let s = poly.surface.index();
            let corners = cam
                .polygon_corners(h, f)
                .ok_or_else(|| format!("{f} has no corners"))?;
            for k in 0..3 {
                let at = self.cursor[s] as usize + k;
                if at >= self.offsets[s + 1] as usize {
                    return Err(format!("surface {s}: more polygons than its range holds"));
                }
                let idx = self.plain[at];
                let pos = h.nodes()[corners[k].index()].position;
                let ok = h
                    .vertex_keys(pos)
                    .iter()
                    .any(|key| key.vertex == idx && key.group == poly.group);
                if !ok {
                    return Err(format!(
                        "{f} corner {k}: index {idx} is not group {}'s vertex at {pos}",
                        poly.group.0
                    ));
                }
            }
            self.cursor[s] += 3;
        }
        for s in 0..ns {
            if self.cursor[s] != self.offsets[s + 1] {
                return Err(format!(
                    "surface {s}: {} indices emitted, {} expected",
                    self.offsets[s + 1] - self.offsets[s],
                    self.cursor[s] - self.offsets[s]
                ));
            }
        }
        done.indices += n as u64;
        Ok(())
    }

    /// The morph slots, and morphed emission against the plain one.
    fn check_morphs(
        &mut self,
        h: &Hierarchy<'_>,
        cam: &CameraState<'_>,
        done: &mut Checked,
    ) -> Result<(), String> {
        let vc = h.vertices().len();
        let slots = cam.morph_vertices();
        if slots.len() > 2 * cam.max_morphs() as usize {
            return Err(format!(
                "{} morph slots, room for {}",
                slots.len(),
                2 * cam.max_morphs()
            ));
        }
        if (cam.morph_count() == 0) != slots.is_empty() {
            return Err(format!(
                "{} morphs but {} slots in use",
                cam.morph_count(),
                slots.len()
            ));
        }
        let mut live = 0u64;
        let result = self.check_slots(h, cam, &mut live);
        let result = result.and_then(|()| self.check_morphed_emission(h, cam, vc, done));
        // Leave the per-vertex slots clear for the next check, whatever happened.
        for m in slots {
            if let Some(s) = self.vertex_slot.get_mut(m.to as usize) {
                *s = 0;
            }
        }
        result?;
        let morphs = u64::from(cam.morph_count());
        if live < morphs || live > 2 * morphs {
            return Err(format!("{live} live slots for {morphs} morphs"));
        }
        done.morph_slots += live;
        Ok(())
    }

    fn check_slots(
        &mut self,
        h: &Hierarchy<'_>,
        cam: &CameraState<'_>,
        live: &mut u64,
    ) -> Result<(), String> {
        let vc = h.vertices().len();
        for (s, m) in cam.morph_vertices().iter().enumerate() {
            if m.is_idle() {
                continue;
            }
            *live += 1;
            if !(0.0..=1.0).contains(&m.t) {
                return Err(format!("morph slot {s}: t {}", m.t));
            }
            if m.coarse as usize >= vc || m.to as usize >= vc {
                return Err(format!("morph slot {s}: {m:?} out of range"));
            }
            if self.vertex_slot[m.to as usize] != 0 {
                return Err(format!("vertex {} in two morph slots", m.to));
            }
            self.vertex_slot[m.to as usize] = s as u32 + 1;
            let to_pos = self.vertex_position[m.to as usize];
            let u = *self
                .active_at
                .get(to_pos as usize)
                .ok_or_else(|| format!("morph slot {s}: vertex {} has no position", m.to))?;
            if u == NONE {
                return Err(format!("morph slot {s}: no active node at vertex {}", m.to));
            }
            // Up the stationary ancestors (which share the position) to the floating child.
            let (mut child, mut depth) = (NodeId(u), 0);
            let parent = loop {
                let p = h.nodes()[child.index()].parent;
                if p.is_none() || depth > h.meta().max_depth {
                    return Err(format!(
                        "morph slot {s}: vertex {} belongs to no split",
                        m.to
                    ));
                }
                if h.nodes()[p.index()].position.0 != to_pos {
                    break p;
                }
                child = p;
                depth += 1;
            };
            if h.split(parent).map(|sp| sp.floating) != Some(child) {
                return Err(format!(
                    "morph slot {s}: {child} is not {parent}'s floating child"
                ));
            }
            if self.vertex_position[m.coarse as usize] != h.nodes()[parent.index()].position.0 {
                return Err(format!(
                    "morph slot {s}: coarse {} not at {parent}",
                    m.coarse
                ));
            }
            if !cam.is_split(parent) {
                return Err(format!("morph slot {s}: {parent} is not split"));
            }
        }
        // `from` is `coarse`, or the slot of `coarse` while that vertex morphs too.
        for (s, m) in cam.morph_vertices().iter().enumerate() {
            if m.is_idle() {
                continue;
            }
            let want = match self.vertex_slot[m.coarse as usize] {
                0 => m.coarse as usize,
                k => vc + k as usize - 1,
            };
            if m.from as usize != want {
                return Err(format!("morph slot {s}: from {} for {want}", m.from));
            }
        }
        Ok(())
    }

    fn check_morphed_emission(
        &mut self,
        h: &Hierarchy<'_>,
        cam: &CameraState<'_>,
        vc: usize,
        done: &mut Checked,
    ) -> Result<(), String> {
        let total = cam.total_index_count();
        let n = cam
            .emit_indices_packed_morphed(h, &mut self.morphed[..total], &mut self.morphed_offsets)
            .map_err(|e| format!("morphed emission: {e}"))?;
        if n != total || self.morphed_offsets != self.offsets {
            return Err("morphed emission's ranges differ from the plain one's".to_string());
        }
        for k in 0..total {
            let (i, j) = (self.plain[k], self.morphed[k]);
            let want = match self.vertex_slot[i as usize] {
                0 => i as usize,
                s => vc + s as usize - 1,
            };
            if j as usize != want {
                return Err(format!(
                    "morphed index {k}: {j}, {want} expected (plain {i})"
                ));
            }
        }
        done.indices += n as u64;
        Ok(())
    }
}

/// The link from `f` across the edge opposite corner `j` to `g` is mirrored by `g`.
fn check_link(
    h: &Hierarchy<'_>,
    cam: &CameraState<'_>,
    f: PolyId,
    corners: [NodeId; 3],
    j: usize,
    g: PolyId,
) -> Result<(), String> {
    let (a, b) = (corners[(j + 1) % 3], corners[(j + 2) % 3]);
    let gc = cam
        .polygon_corners(h, g)
        .ok_or_else(|| format!("{f} neighbour {g} inactive"))?;
    let gn = cam
        .polygon_neighbours(h, g)
        .ok_or_else(|| format!("{g} has no neighbours"))?;
    let back = (0..3).find(|&m| gc[m] != a && gc[m] != b);
    if !gc.contains(&a) || !gc.contains(&b) || back.map(|m| gn[m]) != Some(f) {
        return Err(format!(
            "neighbour link {f} -> {g} across ({a}, {b}) not symmetric"
        ));
    }
    Ok(())
}
