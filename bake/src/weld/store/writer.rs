//! Making a [`WeldedStore`]: the pieces of a welded mesh pushed in any order go to spool
//! files as they come; [`StoreWriter::finish`] orders them (see the module's doc) in a few
//! sequential passes over the spools, holding per position its coordinates and two ids and
//! per triangle its tile, never a whole array of records of the result.

use caveclod_core::format::PositionClass;

use super::column::{Column, ColumnWriter};
use super::records::{Origins, StoredAttributes, StoredTri};
use super::tiles::{side_for, Grid};
use super::welded_store::WeldedStore;
use crate::weld::{Attributes, WeldInfo, Welded};

const NONE: u32 = u32::MAX;

/// Records a pass over a spool reads at a time.
const CHUNK: usize = 1 << 16;

/// Triangles one pass of the ordering places (a window of the result, 20 bytes each).
const WINDOW_TRIANGLES: usize = 1 << 22;

/// Attribute sets one pass of the ordering places (40 bytes each).
const WINDOW_ATTRIBUTES: usize = 1 << 21;

/// The pieces of a welded mesh as a producer pushes them: positions (each with its class and
/// vertex list) and attribute sets numbered by the order they are pushed in, triangles in any
/// order, naming them by those numbers; the three kinds may interleave.
pub struct StoreWriter {
    positions: ColumnWriter<[f32; 3]>,
    classes: ColumnWriter<u8>,
    /// Per position, its vertex list's length.
    list_lens: ColumnWriter<u32>,
    lists: ColumnWriter<[u32; 2]>,
    attributes: ColumnWriter<StoredAttributes>,
    triangles: ColumnWriter<StoredTri>,
    lo: [f32; 3],
    hi: [f32; 3],
}

/// A store's pieces that break its invariants.
fn invalid(what: String) -> std::io::Error {
    std::io::Error::new(
        std::io::ErrorKind::InvalidData,
        format!("welded store: {what}"),
    )
}

impl StoreWriter {
    /// An empty store.
    pub fn new() -> std::io::Result<Self> {
        Ok(Self {
            positions: ColumnWriter::new()?,
            classes: ColumnWriter::new()?,
            list_lens: ColumnWriter::new()?,
            lists: ColumnWriter::new()?,
            attributes: ColumnWriter::new()?,
            triangles: ColumnWriter::new()?,
            lo: [f32::INFINITY; 3],
            hi: [f32::NEG_INFINITY; 3],
        })
    }

    /// The next position (its id: the positions pushed before it), its class and its vertex
    /// list: `[surface group, attribute set]` of each group with a vertex there, sorted by
    /// group, each group once.
    pub fn push_position(
        &mut self,
        xyz: [f32; 3],
        class: PositionClass,
        vertices: &[[u32; 2]],
    ) -> std::io::Result<()> {
        for k in 0..3 {
            self.lo[k] = self.lo[k].min(xyz[k]);
            self.hi[k] = self.hi[k].max(xyz[k]);
        }
        self.positions.push_one(xyz)?;
        self.classes.push_one(class as u8)?;
        self.list_lens.push_one(vertices.len() as u32)?;
        self.lists.push(vertices)
    }

    /// The next attribute sets (ids in push order).
    pub fn push_attributes(&mut self, attributes: &[Attributes]) -> std::io::Result<()> {
        let stored: Vec<StoredAttributes> = attributes.iter().map(Into::into).collect();
        self.attributes.push(&stored)
    }

    /// Triangles, in any order (within a tile, the store keeps the order they come in).
    pub fn push_triangles(&mut self, triangles: &[StoredTri]) -> std::io::Result<()> {
        self.triangles.push(triangles)
    }

    /// The store in block order for first-level tiles of about `block_triangles` triangles
    /// ([`crate::blocked::BlockedOptions::block_triangles`]), with `info`; keeps the
    /// [`Origins`] when `keep_origins`. An id out of range is an `InvalidData` error naming
    /// the element.
    pub fn finish(
        self,
        info: WeldInfo,
        block_triangles: usize,
        keep_origins: bool,
    ) -> std::io::Result<WeldedStore> {
        let positions = self.positions.finish()?;
        let classes = self.classes.finish()?;
        let list_lens = self.list_lens.finish()?;
        let lists = self.lists.finish()?;
        let attributes = self.attributes.finish()?;
        let triangles = self.triangles.finish()?;
        let bounds = if positions.len() == 0 {
            ([0.0; 3], [0.0; 3])
        } else {
            (self.lo, self.hi)
        };
        let side = side_for(triangles.len(), block_triangles);
        let grid = Grid::new(bounds.0, bounds.1, side);
        let xyz = positions.read_all()?;
        let (tile, tile_start) = tiles(&triangles, &xyz, &grid, &info)?;
        let placed = place_triangles(&triangles, &tile, &tile_start, xyz.len(), keep_origins)?;
        drop((tile, triangles));
        let order = position_order(&placed.new_position);
        let (positions, classes) = positions_in_order(&xyz, &classes, &order)?;
        drop(xyz);
        let (vertex_start, vertices, new_attribute) = lists_in_order(
            &list_lens,
            &lists,
            &order,
            attributes.len(),
            info.group_count,
        )?;
        drop((list_lens, lists));
        let attributes = attributes_in_order(&attributes, &new_attribute)?;
        Ok(WeldedStore {
            positions,
            classes,
            vertex_start,
            vertices,
            attributes,
            triangles: placed.triangles,
            info,
            bounds,
            side,
            tile_start,
            origins: placed.origins.map(|triangles| Origins {
                triangles,
                positions: order,
            }),
        })
    }
}

impl WeldedStore {
    /// Stores `w` in block order for first-level tiles of about `block_triangles` triangles
    /// (keeping the [`Origins`] when `keep_origins`), freeing each of its arrays once
    /// stored.
    pub fn from_welded(
        w: Welded,
        block_triangles: usize,
        keep_origins: bool,
    ) -> std::io::Result<Self> {
        let info = WeldInfo::of(&w);
        let Welded {
            positions,
            classes,
            attributes,
            triangles,
            vertices,
            group_surfaces,
            ..
        } = w;
        let mut out = StoreWriter::new()?;
        for (x, (p, c)) in positions.iter().zip(&classes).enumerate() {
            let list: Vec<[u32; 2]> = vertices[x].iter().map(|&(g, a)| [g, a]).collect();
            out.push_position(*p, *c, &list)?;
        }
        drop((positions, classes, vertices));
        for a in attributes.chunks(1 << 16) {
            out.push_attributes(a)?;
        }
        drop(attributes);
        let mut stored = Vec::with_capacity(1 << 16);
        for chunk in triangles.chunks(1 << 16) {
            stored.clear();
            stored.extend(
                chunk
                    .iter()
                    .map(|t| StoredTri::of(t, group_surfaces[t.group as usize])),
            );
            out.push_triangles(&stored)?;
        }
        drop(triangles);
        out.finish(info, block_triangles, keep_origins)
    }
}

/// Each triangle's tile (Z order) and where each tile's triangles start in the result; a
/// triangle naming a position, group or surface that `info` does not have is an error.
fn tiles(
    triangles: &Column<StoredTri>,
    xyz: &[[f32; 3]],
    grid: &Grid,
    info: &WeldInfo,
) -> std::io::Result<(Vec<u32>, Vec<u32>)> {
    let mut tile = Vec::with_capacity(triangles.len());
    let mut count = vec![0u32; (grid.side * grid.side) as usize + 1];
    triangles.for_each_chunk::<std::io::Error>(CHUNK, |start, chunk| {
        for (i, t) in chunk.iter().enumerate() {
            let f = start + i;
            if t.group >= info.group_count || u32::from(t.surface) >= info.surface_count {
                return Err(invalid(format!(
                    "triangle {f} has group {} of {} and surface {} of {}",
                    t.group, info.group_count, t.surface, info.surface_count
                )));
            }
            let mut p = [[0.0; 3]; 3];
            for k in 0..3 {
                p[k] = *xyz.get(t.p[k] as usize).ok_or_else(|| {
                    invalid(format!(
                        "triangle {f} names position {} of {}",
                        t.p[k],
                        xyz.len()
                    ))
                })?;
            }
            let code = grid.tile_of(p);
            count[code as usize + 1] += 1;
            tile.push(code);
        }
        Ok(())
    })?;
    for c in 1..count.len() {
        count[c] += count[c - 1];
    }
    Ok((tile, count))
}

/// The triangles in block order, their positions renamed by first use.
struct Placed {
    triangles: Column<StoredTri>,
    /// The new id of each pushed position (`NONE`: no triangle uses it).
    new_position: Vec<u32>,
    /// The pushed index of each placed triangle, if kept.
    origins: Option<Vec<u32>>,
}

/// Writes the triangles in tile order (push order within a tile), a window of the result
/// per pass over the spool, naming positions by first use as each window is written.
fn place_triangles(
    spool: &Column<StoredTri>,
    tile: &[u32],
    tile_start: &[u32],
    positions: usize,
    keep_origins: bool,
) -> std::io::Result<Placed> {
    let nt = spool.len();
    let mut out = ColumnWriter::new()?;
    let mut new_position = vec![NONE; positions];
    let mut next = 0u32;
    let mut origins = keep_origins.then(|| Vec::with_capacity(nt));
    let mut window = Vec::new();
    let mut from = Vec::new();
    for w0 in (0..nt).step_by(WINDOW_TRIANGLES) {
        let n = WINDOW_TRIANGLES.min(nt - w0);
        window.clear();
        window.resize(n, StoredTri::default());
        from.clear();
        from.resize(n, 0u32);
        let mut fill = tile_start.to_vec();
        spool.for_each_chunk::<std::io::Error>(CHUNK, |start, chunk| {
            for (i, t) in chunk.iter().enumerate() {
                let slot = &mut fill[tile[start + i] as usize];
                let at = *slot as usize;
                *slot += 1;
                if (w0..w0 + n).contains(&at) {
                    window[at - w0] = *t;
                    from[at - w0] = (start + i) as u32;
                }
            }
            Ok(())
        })?;
        for t in &mut window {
            t.p = t.p.map(|x| {
                let id = &mut new_position[x as usize];
                if *id == NONE {
                    *id = next;
                    next += 1;
                }
                *id
            });
        }
        out.push(&window)?;
        if let Some(o) = &mut origins {
            o.extend_from_slice(&from);
        }
    }
    Ok(Placed {
        triangles: out.finish()?,
        new_position,
        origins,
    })
}

/// The pushed id of each new position: those triangles use by first use, then the others
/// in push order.
fn position_order(new_position: &[u32]) -> Vec<u32> {
    let used = new_position.iter().filter(|&&x| x != NONE).count();
    let mut order = vec![NONE; new_position.len()];
    let mut unused = used;
    for (old, &new) in new_position.iter().enumerate() {
        if new == NONE {
            order[unused] = old as u32;
            unused += 1;
        } else {
            order[new as usize] = old as u32;
        }
    }
    order
}

/// The positions and classes in the new order.
fn positions_in_order(
    xyz: &[[f32; 3]],
    classes: &Column<u8>,
    order: &[u32],
) -> std::io::Result<(Column<[f32; 3]>, Column<u8>)> {
    let classes = classes.read_all()?;
    let mut p = ColumnWriter::new()?;
    let mut c = ColumnWriter::new()?;
    for chunk in order.chunks(CHUNK) {
        let xs: Vec<[f32; 3]> = chunk.iter().map(|&o| xyz[o as usize]).collect();
        let cs: Vec<u8> = chunk.iter().map(|&o| classes[o as usize]).collect();
        p.push(&xs)?;
        c.push(&cs)?;
    }
    Ok((p.finish()?, c.finish()?))
}

/// The vertex lists in the new position order, the attribute sets renamed by first use in
/// them; the new id of each pushed attribute set (those no list names last). A list naming
/// an attribute set or a group (of `groups`) that does not exist is an error.
#[allow(clippy::type_complexity)]
fn lists_in_order(
    lens: &Column<u32>,
    lists: &Column<[u32; 2]>,
    order: &[u32],
    attributes: usize,
    groups: u32,
) -> std::io::Result<(Column<u32>, Column<[u32; 2]>, Vec<u32>)> {
    let mut start = Vec::with_capacity(lens.len() + 1);
    start.push(0u32);
    lens.for_each_chunk::<std::io::Error>(CHUNK, |_, chunk| {
        for &n in chunk {
            start.push(start[start.len() - 1] + n);
        }
        Ok(())
    })?;
    let entries = lists.read_all()?;
    let mut new_attribute = vec![NONE; attributes];
    let mut next = 0u32;
    let mut starts = ColumnWriter::new()?;
    let mut out = ColumnWriter::new()?;
    let mut at = 0u32;
    starts.push_one(0)?;
    for (x, &old) in order.iter().enumerate() {
        let list = &entries[start[old as usize] as usize..start[old as usize + 1] as usize];
        let mut renamed = Vec::with_capacity(list.len());
        for &[g, a] in list {
            if g >= groups {
                return Err(invalid(format!(
                    "position {old} (stored {x}) has a vertex of group {g} of {groups}"
                )));
            }
            let id = new_attribute.get_mut(a as usize).ok_or_else(|| {
                invalid(format!(
                    "position {old} (stored {x}) names attribute set {a} of {attributes}"
                ))
            })?;
            if *id == NONE {
                *id = next;
                next += 1;
            }
            renamed.push([g, *id]);
        }
        out.push(&renamed)?;
        at += list.len() as u32;
        starts.push_one(at)?;
    }
    for id in new_attribute.iter_mut().filter(|id| **id == NONE) {
        *id = next;
        next += 1;
    }
    Ok((starts.finish()?, out.finish()?, new_attribute))
}

/// The attribute sets in their new order, a window of the result per pass over the spool.
fn attributes_in_order(
    spool: &Column<StoredAttributes>,
    new_id: &[u32],
) -> std::io::Result<Column<StoredAttributes>> {
    let na = spool.len();
    let mut out = ColumnWriter::new()?;
    let mut window = Vec::new();
    for w0 in (0..na).step_by(WINDOW_ATTRIBUTES) {
        let n = WINDOW_ATTRIBUTES.min(na - w0);
        window.clear();
        window.resize(n, StoredAttributes::default());
        spool.for_each_chunk::<std::io::Error>(CHUNK, |start, chunk| {
            for (i, a) in chunk.iter().enumerate() {
                let at = new_id[start + i] as usize;
                if (w0..w0 + n).contains(&at) {
                    window[at - w0] = *a;
                }
            }
            Ok(())
        })?;
        out.push(&window)?;
    }
    out.finish()
}
