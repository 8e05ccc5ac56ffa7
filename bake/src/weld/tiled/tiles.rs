//! What a tiled weld reads: the input's triangles ([`TileTriangle`]) cut into tiles
//! ([`Tiles`]), and what the input tells besides ([`TiledMesh`]).

use std::io;

use bytemuck::{Pod, Zeroable};

use crate::weld::welded::NONE;

/// One input triangle: its welded positions and its corners' attributes as imported.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TileTriangle {
    /// The triangle's number in the input (the order the in-core weld reads triangles in).
    pub index: u32,
    /// Welded positions, counter-clockwise.
    pub p: [u32; 3],
    /// Per corner: normal (where [`TileTriangle::has`] says so).
    pub normal: [[f32; 3]; 3],
    /// Per corner: texture coordinates.
    pub uv: [[f32; 2]; 3],
    /// Per corner: linear RGBA colour.
    pub color: [[f32; 4]; 3],
    /// Bit `k`: corner `k` has a normal; bit `3 + k` texture coordinates; bit `6 + k` a colour.
    pub has: u16,
    /// Surface.
    pub surface: u16,
}

impl TileTriangle {
    /// Whether corner `k` has a normal.
    pub fn has_normal(&self, k: usize) -> bool {
        self.has & 1 << k != 0
    }

    /// Whether corner `k` has texture coordinates.
    pub fn has_uv(&self, k: usize) -> bool {
        self.has & 1 << (3 + k) != 0
    }

    /// Whether corner `k` has a colour.
    pub fn has_color(&self, k: usize) -> bool {
        self.has & 1 << (6 + k) != 0
    }
}

/// What a tiled input tells besides its tiles.
#[derive(Clone, Debug, Default)]
pub struct TiledMesh {
    /// The welded positions.
    pub positions: Vec<[f32; 3]>,
    /// Per position: the tile whose triangles use it, [`SHARED`] when triangles of several
    /// tiles do, `u32::MAX` when none does.
    pub owner: Vec<u32>,
    /// Input points merged into an identical one (step 1).
    pub welded_positions: u64,
    /// Surfaces of the input (at least one).
    pub surface_count: u32,
    /// Whether any input triangle has a colour.
    pub has_colors: bool,
}

/// A position used by triangles of several tiles.
pub const SHARED: u32 = NONE - 1;

/// A mesh cut into tiles.
pub trait Tiles {
    /// The positions and what else the whole input tells.
    fn mesh(&self) -> &TiledMesh;
    /// Number of tiles.
    fn tile_count(&self) -> usize;
    /// The triangles of tile `tile`, in input order, into `out` (cleared first).
    fn read(&mut self, tile: usize, out: &mut Vec<TileTriangle>) -> io::Result<()>;
}
