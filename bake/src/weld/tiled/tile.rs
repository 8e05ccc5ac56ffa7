//! One tile welded with its halo by [`crate::weld::weld`], and what of it the join needs:
//! its own triangles, where their positions come from, and what the tile could not decide
//! alone (edges and groups across its border, classes where groups or tiles meet).

use caveclod_core::format::PositionClass;

use super::tiles::{TileTriangle, TiledMesh, SHARED};
use crate::base::fxhash::{map_with_capacity, FxHashMap};
use crate::mesh::{Mesh, Surface, Triangle, NO_ATTRIBUTE};
use crate::weld::in_core::{weld_traced, Trace};
use crate::weld::vector::{cross, dot, sub};
use crate::weld::vertex_lists::VertexLists;
use crate::weld::welded::{Attributes, Repairs, WeldError, Welded, GEOMETRIC_NORMAL_DEGREES, NONE};

/// A copy's key: the first triangle (input number) of the fan that uses it and the corner
/// there, flagged; a welded position's key is its id.
pub(super) const COPY: u64 = 1 << 63;

/// What lies across an edge of a tile's own triangle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Across {
    /// Nothing: a border of the mesh.
    Nothing,
    /// A triangle of the same tile, in this local group.
    Group(u32),
    /// A triangle of another tile, by input number.
    Triangle(u32),
}

/// An edge of a tile's own triangle at a position whose class the join counts.
#[derive(Clone, Copy, Debug)]
pub(super) struct ClassEdge {
    /// Its ends (local positions).
    pub(super) ends: [u32; 2],
    /// The local group of the triangle.
    pub(super) group: u32,
    /// What is across.
    pub(super) across: Across,
}

/// A position of the tile's weld that its own triangles use.
#[derive(Clone, Copy, Debug)]
pub(super) struct LocalPosition {
    /// Its key ([`COPY`]).
    pub(super) key: u64,
    /// Its coordinates.
    pub(super) position: [f32; 3],
    /// Whether it is a copy from a split vertex (step 4), which the join counts once.
    pub(super) split: bool,
    /// Whether the join counts its class and collects its vertices from the corners: a
    /// border position, or one where several local groups meet.
    pub(super) watched: bool,
}

/// A kept triangle of the tile's own.
#[derive(Clone, Copy, Debug)]
pub(super) struct OwnTriangle {
    pub(super) index: u32,
    pub(super) p: [u32; 3],
    pub(super) a: [u32; 3],
    pub(super) surface: u16,
    pub(super) group: u32,
}

/// What the join takes from one tile.
pub(super) struct TileWeld {
    /// Local groups (of the tile's mesh with its halo).
    pub(super) group_count: u32,
    /// Per local position (`None` where no own triangle uses it).
    pub(super) positions: Vec<Option<LocalPosition>>,
    /// Local attribute sets, `normal_from_geometry` over the own corners alone.
    pub(super) attributes: Vec<Attributes>,
    /// Local classes (right where the position is not watched).
    pub(super) classes: Vec<PositionClass>,
    /// Local vertices (right where the position is not watched).
    pub(super) vertices: VertexLists,
    pub(super) triangles: Vec<OwnTriangle>,
    /// Edges at watched positions, each once over the whole mesh.
    pub(super) class_edges: Vec<ClassEdge>,
    /// `(local group, input number)` of the other tile's triangle across a matching edge.
    pub(super) joins: Vec<(u32, u32)>,
    /// `(input number, local group)` of the own triangles in the band.
    pub(super) band_groups: Vec<(u32, u32)>,
    pub(super) repairs: Repairs,
}

/// Welds a tile (its triangles `core`, its halo `halo`, both in input order).
pub(super) fn weld_tile(
    mesh: &TiledMesh,
    core: &[TileTriangle],
    halo: &[TileTriangle],
) -> Result<TileWeld, WeldError> {
    let all = merge_by_index(core, halo);
    let (local_mesh, base) = local_mesh(mesh, &all);
    let (w, trace) = match weld_traced(&local_mesh) {
        Ok(r) => r,
        Err(WeldError::Empty { .. }) => return Ok(TileWeld::dropped(core, &mesh.positions)),
        Err(e) => return Err(e),
    };
    let source: Vec<&TileTriangle> = trace.source.iter().map(|&i| &all[i as usize].0).collect();
    let own_tri = |f: usize| all[trace.source[f] as usize].1;
    let mut repairs = own_repairs(&all, &w, &trace, &own_tri, &mesh.positions);
    let positions = local_positions(&w, &trace, &base, &source, &own_tri, mesh);
    let attributes = own_attributes(&w, &source, &own_tri, &mut repairs);
    let own = own_parts(&w, mesh, &positions, &source, &own_tri);
    Ok(TileWeld {
        group_count: w.group_count,
        positions,
        attributes,
        classes: w.classes,
        vertices: w.vertices,
        triangles: own.triangles,
        class_edges: own.class_edges,
        joins: own.joins,
        band_groups: own.band_groups,
        repairs,
    })
}

impl TileWeld {
    /// What a tile gives when its weld keeps nothing: its triangles, counted as dropped.
    fn dropped(core: &[TileTriangle], positions: &[[f32; 3]]) -> Self {
        let mut repairs = Repairs::default();
        for t in core {
            count_dropped(t, positions, &mut repairs);
        }
        TileWeld {
            group_count: 0,
            positions: Vec::new(),
            attributes: Vec::new(),
            classes: Vec::new(),
            vertices: VertexLists::default(),
            triangles: Vec::new(),
            class_edges: Vec::new(),
            joins: Vec::new(),
            band_groups: Vec::new(),
            repairs,
        }
    }
}

/// The repairs of the tile's own triangles (`all[i].1`) in the weld `w`: those it dropped
/// as degenerate or duplicate, and the edges it cut (the computed normals are counted with
/// the attributes, [`own_attributes`]). `own_tri(f)`: whether welded triangle `f` is own.
fn own_repairs(
    all: &[(TileTriangle, bool)],
    w: &Welded,
    trace: &Trace,
    own_tri: &dyn Fn(usize) -> bool,
    positions: &[[f32; 3]],
) -> Repairs {
    let mut repairs = Repairs::default();
    let mut kept_own = vec![false; all.len()];
    for f in 0..w.triangles.len() {
        kept_own[trace.source[f] as usize] = own_tri(f);
    }
    for (i, (t, own)) in all.iter().enumerate() {
        if *own && !kept_own[i] {
            count_dropped(t, positions, &mut repairs);
        }
    }
    for &(f, n) in &trace.cut {
        if own_tri(f as usize) {
            repairs.non_manifold_edges += u64::from(n);
        }
    }
    repairs
}

/// The weld's attribute sets, each one's `normal_from_geometry` decided over the own
/// corners alone (as the in-core weld decides it over the whole mesh's); counts in
/// `repairs` the own corners whose normal was computed.
fn own_attributes(
    w: &Welded,
    source: &[&TileTriangle],
    own_tri: &dyn Fn(usize) -> bool,
    repairs: &mut Repairs,
) -> Vec<Attributes> {
    let normals = area_normals(w);
    let min_cos = GEOMETRIC_NORMAL_DEGREES.to_radians().cos();
    let mut attributes = w.attributes.clone();
    for a in &mut attributes {
        a.normal_from_geometry = true;
    }
    for (f, t) in w.triangles.iter().enumerate() {
        if !own_tri(f) {
            continue;
        }
        let src = source[f];
        let ta = w.corner_attributes(t);
        // The welded triangle keeps the source's corner order.
        for k in 0..3 {
            let given = src.has_normal(k);
            if !given {
                repairs.computed_normals += 1;
            }
            let from_geometry = !given || {
                let g = normals[t.p[k] as usize];
                let n = src.normal[k].map(f64::from);
                dot(n, g) >= min_cos * (dot(n, n) * dot(g, g)).sqrt()
            };
            attributes[ta[k] as usize].normal_from_geometry &= from_geometry;
        }
    }
    attributes
}

/// What the tile's own triangles give the join besides their attributes.
#[derive(Default)]
struct OwnParts {
    triangles: Vec<OwnTriangle>,
    class_edges: Vec<ClassEdge>,
    joins: Vec<(u32, u32)>,
    band_groups: Vec<(u32, u32)>,
}

/// The own triangles of the weld `w`, the groups of those in the band, and what lies across
/// their edges at watched positions: the edges whose classes the join counts, and the
/// matching edges to other tiles' triangles, along which it joins groups.
fn own_parts(
    w: &Welded,
    mesh: &TiledMesh,
    positions: &[Option<LocalPosition>],
    source: &[&TileTriangle],
    own_tri: &dyn Fn(usize) -> bool,
) -> OwnParts {
    let watched = |x: u32| positions[x as usize].is_some_and(|p| p.watched);
    let by_edge = triangles_by_edge(w, &watched);
    let mut own = OwnParts::default();
    for (f, t) in w.triangles.iter().enumerate() {
        if !own_tri(f) {
            continue;
        }
        let src = source[f];
        let ta = w.corner_attributes(t);
        if src.p.iter().any(|&x| mesh.owner[x as usize] == SHARED) {
            own.band_groups.push((src.index, t.group));
        }
        for k in 0..3 {
            let (a, b) = (t.p[k], t.p[(k + 1) % 3]);
            if !(watched(a) || watched(b)) {
                continue;
            }
            let o = by_edge.get(&(b, a)).copied().unwrap_or(NONE);
            let across = if o == NONE {
                Across::Nothing
            } else if own_tri(o as usize) {
                Across::Group(w.triangles[o as usize].group)
            } else {
                let ot = &w.triangles[o as usize];
                let oa = w.corner_attributes(ot);
                let corner = |x: u32| ot.p.iter().position(|&y| y == x).map(|j| oa[j]);
                let matching = w.surface_of(ot) == w.surface_of(t)
                    && corner(a) == Some(ta[k])
                    && corner(b) == Some(ta[(k + 1) % 3]);
                if matching {
                    own.joins.push((t.group, source[o as usize].index));
                }
                Across::Triangle(source[o as usize].index)
            };
            let once = match across {
                Across::Nothing => true,
                _ => src.index < source[o as usize].index,
            };
            if once {
                own.class_edges.push(ClassEdge {
                    ends: [a, b],
                    group: t.group,
                    across,
                });
            }
        }
        own.triangles.push(OwnTriangle {
            index: src.index,
            p: t.p,
            a: ta,
            surface: w.surface_of(t),
            group: t.group,
        });
    }
    own
}

/// The triangle of every directed edge at a watched position: only there does what lies
/// across an own triangle's edge matter (an edge to another tile's triangle has both ends on
/// the border, which is watched).
fn triangles_by_edge(w: &Welded, watched: &dyn Fn(u32) -> bool) -> FxHashMap<(u32, u32), u32> {
    let mut by_edge: FxHashMap<(u32, u32), u32> = map_with_capacity(0);
    for (f, t) in w.triangles.iter().enumerate() {
        if t.p.iter().any(|&x| watched(x)) {
            for k in 0..3 {
                by_edge.insert((t.p[k], t.p[(k + 1) % 3]), f as u32);
            }
        }
    }
    by_edge
}

/// The tile's triangles and its halo, in input order, each marked whether it is the tile's.
fn merge_by_index(core: &[TileTriangle], halo: &[TileTriangle]) -> Vec<(TileTriangle, bool)> {
    let mut all: Vec<(TileTriangle, bool)> = core
        .iter()
        .map(|&t| (t, true))
        .chain(halo.iter().map(|&t| (t, false)))
        .collect();
    all.sort_unstable_by_key(|(t, _)| t.index);
    all
}

/// The tile's mesh: its positions (the welded ones its triangles use, in id order, so
/// [`weld_traced`] keeps their order) and a stream entry per corner attribute. Returns the
/// mesh and the welded id of each of its positions.
fn local_mesh(mesh: &TiledMesh, all: &[(TileTriangle, bool)]) -> (Mesh, Vec<u32>) {
    let mut base: Vec<u32> = all.iter().flat_map(|(t, _)| t.p).collect();
    base.sort_unstable();
    base.dedup();
    let local = |x: u32| base.binary_search(&x).unwrap_or(0) as u32;
    let mut m = Mesh {
        positions: base.iter().map(|&x| mesh.positions[x as usize]).collect(),
        surfaces: vec![Surface::plain("tile"); mesh.surface_count.max(1) as usize],
        ..Mesh::default()
    };
    for (t, _) in all {
        let mut tri = Triangle {
            position: t.p.map(local),
            normal: [NO_ATTRIBUTE; 3],
            uv: [NO_ATTRIBUTE; 3],
            color: [NO_ATTRIBUTE; 3],
            surface: t.surface,
        };
        for k in 0..3 {
            if t.has_normal(k) {
                tri.normal[k] = m.normals.len() as u32;
                m.normals.push(t.normal[k]);
            }
            if t.has_uv(k) {
                tri.uv[k] = m.uvs.len() as u32;
                m.uvs.push(t.uv[k]);
            }
            if t.has_color(k) {
                tri.color[k] = m.colors.len() as u32;
                m.colors.push(t.color[k]);
            }
        }
        m.triangles.push(tri);
    }
    (m, base)
}

/// Counts a dropped triangle as degenerate or, when it is not, as a duplicate.
fn count_dropped(t: &TileTriangle, positions: &[[f32; 3]], repairs: &mut Repairs) {
    let p = t.p;
    let degenerate = p[0] == p[1] || p[1] == p[2] || p[0] == p[2] || {
        let [a, b, c] = p.map(|x| positions[x as usize]);
        cross(sub(b, a), sub(c, a)) == [0.0; 3]
    };
    if degenerate {
        repairs.degenerate_triangles += 1;
    } else {
        repairs.duplicate_triangles += 1;
    }
}

/// The area-weighted normal at every position of the weld (unnormalised), summed in the
/// in-core weld's order: at a position the tile's triangles use, the same sum.
fn area_normals(w: &Welded) -> Vec<[f64; 3]> {
    let mut n = vec![[0f64; 3]; w.positions.len()];
    for t in &w.triangles {
        let [a, b, c] = t.p.map(|x| w.positions[x as usize]);
        let c = cross(sub(b, a), sub(c, a));
        for &v in &t.p {
            for k in 0..3 {
                n[v as usize][k] += c[k];
            }
        }
    }
    n
}

/// Every local position the own triangles use: its key (a welded id, or a copy named by the
/// first triangle of its fan and the corner there) and whether the join watches it.
fn local_positions(
    w: &Welded,
    trace: &Trace,
    base: &[u32],
    source: &[&TileTriangle],
    own_tri: &dyn Fn(usize) -> bool,
    mesh: &TiledMesh,
) -> Vec<Option<LocalPosition>> {
    let n = w.positions.len();
    let mut used = vec![false; n];
    // For copies: the first triangle (input number) using it, and its corner there.
    let mut first = vec![(u32::MAX, 0u8); n];
    for (f, t) in w.triangles.iter().enumerate() {
        for k in 0..3 {
            let x = t.p[k] as usize;
            used[x] |= own_tri(f);
            if source[f].index < first[x].0 {
                first[x] = (source[f].index, k as u8);
            }
        }
    }
    // A copy's welded origin: the welded position with its coordinates (step 1 left one
    // position per coordinate triple).
    let mut origin_of: FxHashMap<[u32; 3], u32> = map_with_capacity(0);
    if (trace.welded_positions as usize) < n {
        for (i, p) in w.positions[..trace.welded_positions as usize]
            .iter()
            .enumerate()
        {
            origin_of.insert(p.map(|x| (x + 0.0).to_bits()), base[i]);
        }
    }
    (0..n)
        .map(|x| {
            if !used[x] {
                return None;
            }
            let welded = x < trace.welded_positions as usize;
            let origin = if welded {
                base[x]
            } else {
                let bits = w.positions[x].map(|c| (c + 0.0).to_bits());
                origin_of.get(&bits).copied().unwrap_or(NONE)
            };
            let key = if welded {
                u64::from(base[x])
            } else {
                COPY | u64::from(first[x].0) << 2 | u64::from(first[x].1)
            };
            let border = origin == NONE || mesh.owner[origin as usize] == SHARED;
            Some(LocalPosition {
                key,
                position: w.positions[x],
                split: x >= trace.cut_positions as usize,
                watched: border || w.vertices[x].len() > 1,
            })
        })
        .collect()
}
