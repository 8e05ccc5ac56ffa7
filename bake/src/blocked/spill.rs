//! The blocked build's collapses on disk: each stitched collapse appends one record (the
//! collapse, its node's position and bounds) to an anonymous temporary file, so the build
//! keeps in memory only what stitching and numbering need — per node its parent, per
//! position the node standing there and that node's bounds, per triangle its corners and
//! whether it lives. The writer ([`super::write`]) reads the records back in chunks, last
//! first; [`Spilled::into_hierarchy`] reads them into an in-memory
//! [`Hierarchy`] for the callers that want one.
//!
//! The file is created unlinked ([`tempfile::tempfile`]), so it is gone when its handle is
//! dropped, whether the bake ends or fails.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::os::unix::fs::FileExt;

use bytemuck::{Pod, Zeroable};

use crate::clod_file::CHUNK_RECORDS as CHUNK;
use crate::hierarchy::{Collapse, Hierarchy};

/// A node's refinement bounds: sphere radius, normal cone, error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Bounds {
    pub(super) radius: f32,
    pub(super) cone: ([f32; 3], f32),
    pub(super) error: f32,
}

impl Bounds {
    /// A leaf before any block has bounded it.
    pub(super) const LEAF: Self = Self {
        radius: 0.0,
        cone: ([0.0, 0.0, 1.0], 0.0),
        error: 0.0,
    };
}

/// One collapse of the whole mesh as stored: what the file's node, split, bounds and polygon
/// arrays need of it.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub(crate) struct Record {
    /// The stationary and floating children (whole-mesh node ids).
    pub(crate) t: u32,
    pub(crate) u: u32,
    /// The triangles that die, `fr` `NONE` on a border.
    pub(crate) fl: u32,
    pub(crate) fr: u32,
    /// `[fl_ccw, fl_clw, fr_clw, fr_ccw]`.
    pub(crate) neighbours: [u32; 4],
    /// The created node's position (its stationary child's).
    pub(crate) position: u32,
    pub(crate) radius: f32,
    pub(crate) axis: [f32; 3],
    pub(crate) angle: f32,
    pub(crate) error: f32,
    /// Corners of `fl` and `fr` holding `t`.
    pub(crate) rot: [u8; 4],
}

impl Record {
    pub(super) fn new(c: &Collapse, position: u32, b: &Bounds) -> Self {
        Self {
            t: c.t,
            u: c.u,
            fl: c.fl,
            fr: c.fr,
            neighbours: c.neighbours,
            position,
            radius: b.radius,
            axis: b.cone.0,
            angle: b.cone.1,
            error: b.error,
            rot: [c.rot_l, c.rot_r, 0, 0],
        }
    }

    pub(crate) fn collapse(&self) -> Collapse {
        Collapse {
            t: self.t,
            u: self.u,
            fl: self.fl,
            fr: self.fr,
            neighbours: self.neighbours,
            rot_l: self.rot[0],
            rot_r: self.rot[1],
        }
    }
}

/// The records as they are appended.
pub(super) struct SpillWriter {
    out: BufWriter<File>,
    count: usize,
}

impl SpillWriter {
    /// A new, empty, unlinked temporary file.
    pub(super) fn new() -> std::io::Result<Self> {
        Ok(Self {
            out: BufWriter::with_capacity(1 << 20, tempfile::tempfile()?),
            count: 0,
        })
    }

    pub(super) fn push(&mut self, r: &Record) -> std::io::Result<()> {
        self.count += 1;
        self.out.write_all(bytemuck::bytes_of(r))
    }

    /// Records so far.
    pub(super) fn len(&self) -> usize {
        self.count
    }

    fn finish(self) -> std::io::Result<(File, usize)> {
        let file = self.out.into_inner().map_err(|e| e.into_error())?;
        Ok((file, self.count))
    }
}

/// The whole hierarchy of a blocked build with its collapses on disk: collapse `c` creates
/// node `positions + c`, as in a [`Hierarchy`].
#[derive(Debug)]
pub struct Spilled {
    file: File,
    /// Collapses (records).
    count: usize,
    /// Leaves (welded positions).
    pub(crate) positions: usize,
    /// Parent of every node, `NONE` for roots.
    pub(crate) parent: Vec<u32>,
    /// Per triangle, the positions of its corners at the end (alive triangles: the base
    /// mesh's, whose nodes are those standing at the positions at the end).
    pub(crate) corners: Vec<[u32; 3]>,
    /// Which triangles are in the base mesh.
    pub(crate) alive: Vec<bool>,
    /// The node standing at each position at the end.
    pub(crate) current: Vec<u32>,
    /// Batches (passes) of the blocks' builds.
    pub passes: u32,
}

impl Spilled {
    pub(super) fn new(
        spill: SpillWriter,
        parent: Vec<u32>,
        corners: Vec<[u32; 3]>,
        alive: Vec<bool>,
        current: Vec<u32>,
        passes: u32,
    ) -> std::io::Result<Self> {
        let (file, count) = spill.finish()?;
        Ok(Self {
            file,
            count,
            positions: current.len(),
            parent,
            corners,
            alive,
            current,
            passes,
        })
    }

    /// Collapses.
    pub fn len(&self) -> usize {
        self.count
    }

    /// No collapse at all.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Records `start..start + n`.
    fn read(&self, start: usize, n: usize) -> std::io::Result<Vec<Record>> {
        let mut records = vec![Record::zeroed(); n];
        let size = std::mem::size_of::<Record>();
        self.file.read_exact_at(
            bytemuck::cast_slice_mut(&mut records),
            (start * size) as u64,
        )?;
        Ok(records)
    }

    /// Calls `f` with the records in chunks, in creation order (`last_first` false) or last
    /// first, each chunk in that order too; the first record of each chunk comes with its
    /// collapse index. A failed read is `io`'s error.
    pub(crate) fn for_each_chunk<E>(
        &self,
        last_first: bool,
        io: impl Fn(std::io::Error) -> E,
        mut f: impl FnMut(usize, &[Record]) -> Result<(), E>,
    ) -> Result<(), E> {
        let mut done = 0;
        while done < self.count {
            let n = CHUNK.min(self.count - done);
            if last_first {
                let start = self.count - done - n;
                let mut chunk = self.read(start, n).map_err(&io)?;
                chunk.reverse();
                f(start + n - 1, &chunk)?;
            } else {
                f(done, &self.read(done, n).map_err(&io)?)?;
            }
            done += n;
        }
        Ok(())
    }

    /// The hierarchy in memory, as [`crate::hierarchy::build`] hands one over. The file holds
    /// no bounds for leaves (it has no use for them), so the leaves have none (zero radius and
    /// error, a cone of no spread about +z); the corners of triangles that died are their
    /// leaves'.
    pub fn into_hierarchy(mut self) -> std::io::Result<Hierarchy> {
        let np = self.positions;
        let total = np + self.count;
        let mut h = Hierarchy {
            collapses: Vec::with_capacity(self.count),
            parent: std::mem::take(&mut self.parent),
            node_position: Vec::with_capacity(total),
            radius: vec![Bounds::LEAF.radius; np],
            cone: vec![Bounds::LEAF.cone; np],
            error: vec![Bounds::LEAF.error; np],
            corners: Vec::new(),
            alive: Vec::new(),
            passes: self.passes,
        };
        h.node_position.extend(0..np as u32);
        self.for_each_chunk(
            false,
            |e| e,
            |_, chunk| {
                for r in chunk {
                    h.collapses.push(r.collapse());
                    h.node_position.push(r.position);
                    h.radius.push(r.radius);
                    h.cone.push((r.axis, r.angle));
                    h.error.push(r.error);
                }
                Ok(())
            },
        )?;
        h.corners = self
            .corners
            .iter()
            .zip(&self.alive)
            .map(|(c, &a)| {
                if a {
                    c.map(|x| self.current[x as usize])
                } else {
                    *c
                }
            })
            .collect();
        h.alive = self.alive;
        debug_assert_eq!(h.parent.len(), total);
        Ok(h)
    }
}
