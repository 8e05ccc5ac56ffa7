//! Popping, measured: how far on the screen each drawn vertex moves from one frame to the
//! next because of refinement.
//!
//! A position of the hierarchy is drawn where its vertices stand: its own point while its
//! node is active (a position is held by the chain of stationary children below the node
//! that introduced it, so the created positions are exactly those of the active nodes), the
//! blend of a geomorph (along its chain) while its floating child morphs, and, once collapsed, where the
//! position it collapsed into is drawn. Without geomorphs a split moves the floating child
//! from its parent's point to its own in one frame, and a collapse moves it back in one
//! frame; with geomorphs a morphing vertex moves by the blend's step. Every position drawn
//! somewhere else than in the previous frame is one displacement, projected with the current
//! frame's view-projection (so the camera's own motion is not counted), in pixels. Only
//! displacements with an end inside the view (inside the viewport and the depth range) count.

use std::sync::Arc;

use caveclod_core::format::Vertex;
use caveclod_core::glam::{Mat4, Vec2, Vec3, Vec4};
use caveclod_core::gpu::{morph_slot_vertex, MorphSlices};
use caveclod_core::{CameraState, Hierarchy};

use super::routes::{HEIGHT, WIDTH};

const NONE: u32 = u32::MAX;

/// What the meter reads of a hierarchy, computed once and shared by every camera's meter.
pub struct PopTables {
    /// Per position, its point.
    point: Vec<Vec3>,
    /// Per position, the position it collapses into (`NONE` for a base-mesh position).
    parent: Vec<u32>,
    /// Per position, the normal of (one of) its vertices.
    normal: Vec<Vec3>,
    /// Per vertex, its position.
    position_of_vertex: Vec<u32>,
    /// The persistent vertices (morph slots blend them).
    vertices: Vec<Vertex>,
    /// Per node, its position.
    position_of_node: Vec<u32>,
}

impl PopTables {
    /// The tables of `h`.
    pub fn new(h: &Hierarchy<'_>) -> Self {
        let point: Vec<Vec3> = h.positions().iter().map(|p| Vec3::from(p.xyz)).collect();
        let nodes = h.nodes();
        let position_of_node: Vec<u32> = nodes.iter().map(|n| n.position.0).collect();
        let mut parent = vec![NONE; point.len()];
        for n in nodes {
            let Some(up) = h.node(n.parent) else { continue };
            if up.position != n.position {
                if let Some(p) = parent.get_mut(n.position.index()) {
                    *p = up.position.0;
                }
            }
        }
        let mut position_of_vertex = vec![NONE; h.vertices().len()];
        for p in 0..point.len() {
            let id = caveclod_core::PositionId(p as u32);
            for key in h.vertex_keys(id) {
                if let Some(v) = position_of_vertex.get_mut(key.vertex as usize) {
                    *v = p as u32;
                }
            }
        }
        let vertices = h.vertices().to_vec();
        let mut normal = vec![Vec3::ZERO; point.len()];
        for (v, &p) in h.vertices().iter().zip(&position_of_vertex) {
            if let Some(n) = normal.get_mut(p as usize) {
                *n = Vec3::from(v.normal);
            }
        }
        Self {
            normal,
            point,
            parent,
            position_of_vertex,
            vertices,
            position_of_node,
        }
    }
}

/// Where a camera drew its positions in one frame.
struct Drawn {
    /// Per position, where it was drawn (valid where `stamp` is this frame's).
    at: Vec<Vec3>,
    /// Per position, the frame (plus one) it was last drawn in.
    stamp: Vec<u32>,
    /// The positions drawn, once each.
    list: Vec<u32>,
    /// This frame's stamp (0: none yet).
    frame: u32,
}

impl Drawn {
    fn new(positions: usize) -> Self {
        Self {
            at: vec![Vec3::ZERO; positions],
            stamp: vec![0; positions],
            list: Vec::new(),
            frame: 0,
        }
    }

    fn holds(&self, p: u32) -> bool {
        self.stamp.get(p as usize) == Some(&self.frame)
    }

    /// Where position `p` is drawn: its own place, or where the position it collapsed into
    /// is drawn.
    fn place(&self, t: &PopTables, mut p: u32) -> Vec3 {
        loop {
            if self.holds(p) {
                return self.at[p as usize];
            }
            match t.parent.get(p as usize) {
                Some(&up) if up != NONE => p = up,
                _ => return t.point.get(p as usize).copied().unwrap_or(Vec3::ZERO),
            }
        }
    }
}

/// One camera's popping over a flight.
pub struct PopMeter {
    tables: Arc<PopTables>,
    prev: Drawn,
    cur: Drawn,
    /// Every displacement in view over the flight, in pixels.
    pub jumps: Vec<f32>,
    /// The part of each of `jumps` along the vertex's normal, in pixels: how far the drawn
    /// surface moves, where `jumps` also counts a vertex sliding within the surface.
    pub surface_jumps: Vec<f32>,
}

impl PopMeter {
    /// A meter for a camera over the hierarchy of `tables`.
    pub fn new(tables: Arc<PopTables>) -> Self {
        let n = tables.point.len();
        Self {
            tables,
            prev: Drawn::new(n),
            cur: Drawn::new(n),
            jumps: Vec::new(),
            surface_jumps: Vec::new(),
        }
    }

    /// Reads where `cam` draws its positions this frame, and records the displacement of
    /// each position drawn elsewhere than in the previous frame, projected on `screen`
    /// (this frame's).
    pub fn observe(&mut self, cam: &CameraState<'_>, screen: &Screen) {
        std::mem::swap(&mut self.prev, &mut self.cur);
        let frame = self.prev.frame + 1;
        self.read(cam, frame);
        if self.prev.frame == 0 {
            return;
        }
        let (t, prev, cur) = (&*self.tables, &self.prev, &self.cur);
        let moves = cur
            .list
            .iter()
            .map(|&p| (p, prev.place(t, p), cur.at[p as usize]))
            .chain(
                prev.list
                    .iter()
                    .filter(|&&p| !cur.holds(p))
                    .map(|&p| (p, prev.at[p as usize], cur.place(t, p))),
            );
        for (p, a, b) in moves.filter(|(_, a, b)| a != b) {
            let normal = t.normal.get(p as usize).copied().unwrap_or(Vec3::ZERO);
            if let Some((vertex, surface)) = screen.jump(a, b, normal) {
                self.jumps.push(vertex);
                self.surface_jumps.push(surface);
            }
        }
    }

    /// Fills `cur` with frame `frame`'s drawn positions.
    fn read(&mut self, cam: &CameraState<'_>, frame: u32) {
        let t = &*self.tables;
        let d = &mut self.cur;
        d.frame = frame;
        d.list.clear();
        for node in cam.active_nodes() {
            let Some(&p) = t.position_of_node.get(node.index()) else {
                continue;
            };
            if let Some(s) = d.stamp.get_mut(p as usize) {
                if *s != frame {
                    *s = frame;
                    d.at[p as usize] = t.point[p as usize];
                    d.list.push(p);
                }
            }
        }
        let inputs = MorphSlices {
            vertices: &t.vertices,
            slots: cam.morph_vertices(),
        };
        for (s, m) in inputs.slots.iter().enumerate() {
            let Some(&p) = t.position_of_vertex.get(m.to as usize) else {
                continue; // idle
            };
            let Some(v) = morph_slot_vertex(&inputs, s as u32) else {
                continue;
            };
            if d.stamp.get(p as usize) == Some(&frame) {
                d.at[p as usize] = Vec3::from(v.position);
            }
        }
    }

    /// The largest displacement, in pixels (0 for none).
    pub fn max_px(&self) -> f32 {
        self.jumps.iter().copied().fold(0.0, f32::max)
    }

    /// The 99th percentile of the displacements (nearest rank; 0 for none).
    pub fn p99_px(&self) -> f32 {
        quantile(&self.jumps, 0.99)
    }

    /// The largest move of the surface, in pixels (0 for none).
    pub fn surface_max_px(&self) -> f32 {
        self.surface_jumps.iter().copied().fold(0.0, f32::max)
    }

    /// The 99th percentile of the surface's moves (nearest rank; 0 for none).
    pub fn surface_p99_px(&self) -> f32 {
        quantile(&self.surface_jumps, 0.99)
    }
}

/// The `q`-quantile of `v` (nearest rank; 0 for none).
pub fn quantile(v: &[f32], q: f64) -> f32 {
    if v.is_empty() {
        return 0.0;
    }
    let mut s = v.to_vec();
    s.sort_unstable_by(f32::total_cmp);
    let i = ((s.len() as f64 * q).ceil() as usize).clamp(1, s.len()) - 1;
    s[i]
}

/// A frame's view-projection and eye, and the fly-over's viewport.
pub struct Screen {
    /// The view-projection matrix (Vulkan clip space).
    pub view_proj: Mat4,
    /// The eye point.
    pub eye: Vec3,
}

impl Screen {
    /// Pixel coordinates of `p` and whether it is inside the viewport and depth range;
    /// `None` behind the eye.
    fn pixel(&self, p: Vec3) -> Option<(Vec2, bool)> {
        let c: Vec4 = self.view_proj * p.extend(1.0);
        if c.w <= 0.0 {
            return None;
        }
        let (x, y, z) = (c.x / c.w, c.y / c.w, c.z / c.w);
        let px = Vec2::new((x * 0.5 + 0.5) * WIDTH, (y * 0.5 + 0.5) * HEIGHT);
        let inside = x.abs() <= 1.0 && y.abs() <= 1.0 && (0.0..=1.0).contains(&z);
        Some((px, inside))
    }

    /// A vertex with normal `normal` moving from `a` to `b`: its on-screen move and that of
    /// the move's part along the normal, in pixels, if an end of it is in view (inside the
    /// viewport, facing the eye) and both ends are in front of the eye.
    pub fn jump(&self, a: Vec3, b: Vec3, normal: Vec3) -> Option<(f32, f32)> {
        let ((pa, ia), (pb, ib)) = (self.pixel(a)?, self.pixel(b)?);
        let facing = |p: Vec3| normal.dot(self.eye - p) > 0.0;
        if !((ia && facing(a)) || (ib && facing(b))) {
            return None;
        }
        let n = normal.normalize_or_zero();
        let (ps, _) = self.pixel(a + n * n.dot(b - a))?;
        Some((pa.distance(pb), pa.distance(ps)))
    }
}
