//! Where a page's arrays lie, from its counts alone, and how a page-major id splits.

use core::ops::Range;

use crate::format::records::{Node, Polygon, Position, Split, SplitBounds, Vertex, VertexKey};
use crate::format::{align_up, SECTION_ALIGN};

/// The kinds of record a page counts, in the order of [`PageEntry::counts`](super::PageEntry).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RecordKind {
    /// Nodes ([`Node`]); the first [`Splits`](Self::Splits) of them can be split.
    Nodes = 0,
    /// Split records ([`Split`] and [`SplitBounds`]).
    Splits = 1,
    /// Polygons ([`Polygon`]).
    Polygons = 2,
    /// Node positions ([`Position`]), each with a vertex-table offset.
    Positions = 3,
    /// Vertex-table entries ([`VertexKey`]).
    VertexKeys = 4,
    /// Vertices ([`Vertex`]), and colours when the page has them.
    Vertices = 5,
}

impl RecordKind {
    /// Every kind, in count order.
    pub const ALL: [Self; 6] = [
        Self::Nodes,
        Self::Splits,
        Self::Polygons,
        Self::Positions,
        Self::VertexKeys,
        Self::Vertices,
    ];

    /// The kind's name in messages.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Nodes => "nodes",
            Self::Splits => "splits",
            Self::Polygons => "polygons",
            Self::Positions => "positions",
            Self::VertexKeys => "vertex keys",
            Self::Vertices => "vertices",
        }
    }
}

/// The arrays a page holds, in layout order (the colours, which refinement does not read,
/// left out).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PageArray {
    /// [`Node`] per node.
    Nodes = 0,
    /// [`Split`] per split.
    Splits = 1,
    /// [`SplitBounds`] per split.
    Bounds = 2,
    /// [`Polygon`] per polygon.
    Polygons = 3,
    /// [`Position`] per position.
    Positions = 4,
    /// `u32` per position plus one: where each position's vertex-table entries start.
    VertexTableOffsets = 5,
    /// [`VertexKey`] per entry.
    VertexTable = 6,
    /// [`Vertex`] per vertex.
    Vertices = 7,
}

impl PageArray {
    /// How many there are.
    pub const COUNT: usize = 8;
}

/// The byte ranges of a page's arrays, each starting on 64 bytes, in this order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PageLayout {
    /// [`Node`] per node.
    pub nodes: Range<usize>,
    /// [`Split`] per split.
    pub splits: Range<usize>,
    /// [`SplitBounds`] per split.
    pub bounds: Range<usize>,
    /// [`Polygon`] per polygon.
    pub polygons: Range<usize>,
    /// [`Position`] per position.
    pub positions: Range<usize>,
    /// `u32` per position plus one: where each position's vertex-table entries start, within
    /// the page.
    pub vertex_table_offsets: Range<usize>,
    /// [`VertexKey`] per entry.
    pub vertex_table: Range<usize>,
    /// [`Vertex`] per vertex.
    pub vertices: Range<usize>,
    /// RGBA8 per vertex, or empty.
    pub colours: Range<usize>,
    /// The page's length: the end of its last array, on 64 bytes.
    pub len: usize,
}

impl PageLayout {
    /// The byte ranges of the arrays of [`PageArray`], in its order.
    pub fn arrays(&self) -> [&Range<usize>; PageArray::COUNT] {
        [
            &self.nodes,
            &self.splits,
            &self.bounds,
            &self.polygons,
            &self.positions,
            &self.vertex_table_offsets,
            &self.vertex_table,
            &self.vertices,
        ]
    }

    /// The layout of a page with `counts` (in [`RecordKind`] order) and colours or not;
    /// `None` if it would not fit in `usize` or a split count exceeds the node count.
    pub fn new(counts: [u32; 6], colours: bool) -> Option<Self> {
        let [n, s, p, q, k, v] = counts.map(|c| c as usize);
        if s > n {
            return None;
        }
        let mut at = 0usize;
        let mut next = |len: Option<usize>| -> Option<Range<usize>> {
            let start = align_up(at);
            let end = start.checked_add(len?)?;
            at = end;
            Some(start..end)
        };
        let size = core::mem::size_of::<u32>();
        Some(Self {
            nodes: next(n.checked_mul(core::mem::size_of::<Node>()))?,
            splits: next(s.checked_mul(core::mem::size_of::<Split>()))?,
            bounds: next(s.checked_mul(core::mem::size_of::<SplitBounds>()))?,
            polygons: next(p.checked_mul(core::mem::size_of::<Polygon>()))?,
            positions: next(q.checked_mul(core::mem::size_of::<Position>()))?,
            vertex_table_offsets: next(q.checked_add(1)?.checked_mul(size))?,
            vertex_table: next(k.checked_mul(core::mem::size_of::<VertexKey>()))?,
            vertices: next(v.checked_mul(core::mem::size_of::<Vertex>()))?,
            colours: next(Some(if colours { v.checked_mul(4)? } else { 0 }))?,
            len: at.checked_add(SECTION_ALIGN - 1)? & !(SECTION_ALIGN - 1),
        })
    }
}

/// How page-major ids split: `(page << page_bits) | index`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SegmentedId {
    bits: u32,
}

impl SegmentedId {
    /// Ids with 31 bits of index: one page.
    pub const MAX: Self = Self { bits: 31 };

    /// Ids with `page_bits` bits of index (at most 31).
    pub const fn new(page_bits: u32) -> Option<Self> {
        if page_bits == 0 || page_bits > 31 {
            None
        } else {
            Some(Self { bits: page_bits })
        }
    }

    /// Bits of index.
    #[inline]
    pub const fn bits(self) -> u32 {
        self.bits
    }

    /// The page of `id`.
    #[inline(always)]
    pub const fn page(self, id: u32) -> u32 {
        id >> self.bits
    }

    /// The index of `id` within its page.
    #[inline(always)]
    pub const fn index(self, id: u32) -> u32 {
        id & ((1 << self.bits) - 1)
    }

    /// The id of record `index` of page `page`; `None` if it does not fit 32 bits.
    #[inline]
    pub const fn id(self, page: u32, index: u32) -> Option<u32> {
        if index >> self.bits != 0 || page > (u32::MAX >> self.bits) {
            None
        } else {
            Some((page << self.bits) | index)
        }
    }
}
