//! The tiles the store orders its triangles by, which are the blocked build's first-level
//! blocks: square tiles over the mesh's two widest axes, a triangle in the tile of its
//! centroid, tiles numbered in Z (Morton) order, so that a level's tiles merge two by two on
//! each axis into the next level's by dropping two bits of the code, and the four tiles of
//! one are consecutive.

/// A grid of `side × side` tiles over the plane of the bounding box's two widest axes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Grid {
    /// Tiles along each axis (a power of two).
    pub(crate) side: u32,
    /// The two axes the tiles divide.
    axes: [usize; 2],
    lo: [f32; 2],
    size: [f32; 2],
}

impl Grid {
    /// The grid of `side × side` tiles over the box `lo..hi`.
    pub(crate) fn new(lo: [f32; 3], hi: [f32; 3], side: u32) -> Self {
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

    /// The tile of the triangle with corners `p`, as its Z-order code ([`z_order`]).
    pub(crate) fn tile_of(&self, p: [[f32; 3]; 3]) -> u32 {
        let cell = |k: usize| {
            let a = self.axes[k];
            let c = (p[0][a] + p[1][a] + p[2][a]) / 3.0;
            let t = ((c - self.lo[k]) / self.size[k] * self.side as f32).floor();
            (t.max(0.0) as u32).min(self.side - 1)
        };
        z_order(cell(0), cell(1))
    }
}

/// The Z-order code of tile `(x, y)`: their bits interleaved, `x`'s in the even places. The
/// tile of the next level holding it is `code >> 2`.
pub(crate) fn z_order(x: u32, y: u32) -> u32 {
    let spread = |v: u32| {
        let mut v = v & 0xffff;
        v = (v | v << 8) & 0x00ff_00ff;
        v = (v | v << 4) & 0x0f0f_0f0f;
        v = (v | v << 2) & 0x3333_3333;
        (v | v << 1) & 0x5555_5555
    };
    spread(x) | spread(y) << 1
}

/// Tiles along each axis for blocks of about `block_triangles` triangles out of
/// `triangles`: the smallest power of two whose square of tiles leaves each at most that
/// many on average.
pub(crate) fn side_for(triangles: usize, block_triangles: usize) -> u32 {
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
    fn z_order_codes_merge_two_by_two_and_sides_cover_the_blocks() {
        assert_eq!(z_order(0, 0), 0);
        assert_eq!(z_order(1, 0), 1);
        assert_eq!(z_order(0, 1), 2);
        assert_eq!(z_order(1, 1), 3);
        assert_eq!(z_order(2, 0), 4);
        assert_eq!(z_order(3, 3), 15);
        for (x, y) in [(5, 9), (4095, 17), (0, 4095)] {
            assert_eq!(z_order(x, y) >> 2, z_order(x / 2, y / 2));
        }
        assert_eq!(side_for(100, 100), 1);
        assert_eq!(side_for(101, 100), 2);
        assert_eq!(side_for(1600, 100), 4);
        assert_eq!(side_for(1601, 100), 8);
    }
}
