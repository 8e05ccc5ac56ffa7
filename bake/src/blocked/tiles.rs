//! The blocks: square tiles over the mesh's two widest axes, a triangle in the tile of its
//! centroid; a level's tiles merge two by two on each axis into the next level's.

use crate::weld::Welded;

/// A grid of `side × side` tiles over the plane of the bounding box's two widest axes.
#[derive(Clone, Copy, Debug)]
pub(super) struct Grid {
    /// Tiles along each axis (a power of two).
    pub(super) side: u32,
    /// The two axes the tiles divide.
    axes: [usize; 2],
    lo: [f32; 2],
    size: [f32; 2],
}

impl Grid {
    /// The grid of `side × side` tiles over `w`'s bounding box.
    pub(super) fn new(w: &Welded, side: u32) -> Self {
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        for p in &w.positions {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let mut order = [0usize, 1, 2];
        order.sort_by(|&a, &b| (hi[b] - lo[b]).total_cmp(&(hi[a] - lo[a])));
        let axes = [order[0], order[1]];
        Self {
            side,
            axes,
            lo: axes.map(|a| lo[a]),
            size: axes.map(|a| (hi[a] - lo[a]).max(f32::MIN_POSITIVE)),
        }
    }

    /// The tile (`x + y × side`) of the triangle with corners `p`.
    pub(super) fn tile_of(&self, p: [[f32; 3]; 3]) -> u32 {
        let cell = |k: usize| {
            let a = self.axes[k];
            let c = (p[0][a] + p[1][a] + p[2][a]) / 3.0;
            let t = ((c - self.lo[k]) / self.size[k] * self.side as f32).floor();
            (t.max(0.0) as u32).min(self.side - 1)
        };
        cell(0) + cell(1) * self.side
    }
}

/// The tile of the next level (a grid of half the side) that holds tile `tile` of a grid of
/// side `side`.
pub(super) fn merged(tile: u32, side: u32) -> u32 {
    let (x, y) = (tile % side, tile / side);
    x / 2 + y / 2 * (side / 2).max(1)
}

/// Tiles along each axis for blocks of about `block_triangles` triangles out of
/// `triangles`: the smallest power of two whose square of tiles leaves each at most that
/// many on average.
pub(super) fn side_for(triangles: usize, block_triangles: usize) -> u32 {
    let mut side = 1u32;
    while (triangles as u64).div_ceil(u64::from(side) * u64::from(side))
        > block_triangles.max(1) as u64
        && side < 1 << 12
    {
        side *= 2;
    }
    side
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_merge_two_by_two_and_sides_cover_the_blocks() {
        assert_eq!(merged(0, 4), 0);
        assert_eq!(merged(1, 4), 0);
        assert_eq!(merged(4, 4), 0);
        assert_eq!(merged(5, 4), 0);
        assert_eq!(merged(2, 4), 1);
        assert_eq!(merged(15, 4), 3);
        assert_eq!(merged(3, 2), 0);
        assert_eq!(side_for(100, 100), 1);
        assert_eq!(side_for(101, 100), 2);
        assert_eq!(side_for(1600, 100), 4);
        assert_eq!(side_for(1601, 100), 8);
    }
}
