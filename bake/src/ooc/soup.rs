//! The triangle-soup record every stage after the readers works on.
//!
//! A [`SoupTriangle`] carries everything clustering needs, so no stage ever looks a vertex up
//! again: its three corners (position, texture coordinates, octahedral 16-bit normal, 8-bit
//! sRGB colour), its surface, which attributes the input had, and the spatial sort key: the
//! Morton code of its centroid on a 2^21 grid over the input's bounding cube. Sorting by the key
//! puts the triangles of every octree cell next to each other at every depth, so an octree node
//! is a range of the sorted file. The record is 96 bytes, `Pod`, written and read as raw bytes.

use bytemuck::{Pod, Zeroable};

pub use crate::base::colour::{linear_to_srgb8, srgb8_table};

/// Levels of the Morton key (3 bits each).
pub const KEY_LEVELS: u32 = 21;

/// Has per-corner normals.
pub const HAS_NORMAL: u16 = 1;
/// Has per-corner texture coordinates.
pub const HAS_UV: u16 = 2;
/// Has per-corner colours.
pub const HAS_COLOR: u16 = 4;

/// One corner of a soup triangle.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Corner {
    /// Position.
    pub position: [f32; 3],
    /// Texture coordinates (`v = 0` at the top row, as in [`crate::mesh::Mesh::uvs`]).
    pub uv: [f32; 2],
    /// Normal, octahedral-encoded in snorm16 ([`encode_normal`]).
    pub normal: [i16; 2],
    /// sRGB-encoded RGBA8 colour (alpha linear).
    pub color: [u8; 4],
}

/// One triangle of the soup (96 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SoupTriangle {
    /// Morton code of the centroid ([`Cube::key`]).
    pub key: u64,
    /// Surface id.
    pub surface: u16,
    /// [`HAS_NORMAL`] | [`HAS_UV`] | [`HAS_COLOR`].
    pub flags: u16,
    /// Corners, counter-clockwise.
    pub corners: [Corner; 3],
}

/// Bytes of one record.
pub const RECORD_BYTES: usize = std::mem::size_of::<SoupTriangle>();

/// The bounding cube the keys and cluster cells are taken on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cube {
    /// Lowest corner.
    pub origin: [f64; 3],
    /// Side (positive).
    pub size: f64,
}

impl Cube {
    /// The cube around a bounding box (`min`, `max`), slightly enlarged so that `max` falls
    /// inside the last cell.
    pub fn around(min: [f32; 3], max: [f32; 3]) -> Self {
        let min = min.map(f64::from);
        let max = max.map(f64::from);
        let extent = (0..3).map(|k| max[k] - min[k]).fold(0.0, f64::max);
        let size = if extent > 0.0 {
            extent * 1.000_001
        } else {
            1.0
        };
        Self { origin: min, size }
    }

    /// Integer cell of `p` at `level` (`2^level` cells per axis), clamped into the cube.
    pub fn cell(&self, p: [f32; 3], level: u32) -> [u32; 3] {
        let scale = (1u64 << level) as f64 / self.size;
        let top = (1u64 << level) - 1;
        // Truncation is the floor for the non-negative values that matter.
        [0, 1, 2].map(|k| {
            let t = (f64::from(p[k]) - self.origin[k]) * scale;
            (t.max(0.0) as u64).min(top) as u32
        })
    }

    /// Centre of a cell at `level`.
    pub fn cell_center(&self, c: [u32; 3], level: u32) -> [f64; 3] {
        let s = self.size / (1u64 << level) as f64;
        [0, 1, 2].map(|k| self.origin[k] + (f64::from(c[k]) + 0.5) * s)
    }

    /// Morton key of the centroid of three points at [`KEY_LEVELS`].
    pub fn key(&self, p: &[[f32; 3]; 3]) -> u64 {
        self.keyer().key(p)
    }

    /// [`Cube::key`] with the scale worked out once, for keying many triangles.
    pub fn keyer(&self) -> Keyer {
        Keyer {
            origin: self.origin,
            scale: (1u64 << KEY_LEVELS) as f64 / self.size,
        }
    }
}

/// Keys triangles on a cube ([`Cube::keyer`]): the same keys as [`Cube::key`], without its
/// division per call.
#[derive(Clone, Copy, Debug)]
pub struct Keyer {
    origin: [f64; 3],
    scale: f64,
}

impl Keyer {
    /// Morton key of the centroid of three points at [`KEY_LEVELS`].
    #[inline]
    pub fn key(&self, p: &[[f32; 3]; 3]) -> u64 {
        let top = (1u64 << KEY_LEVELS) - 1;
        // As in `Cube::cell`: truncation is the floor for the non-negative values that matter.
        let c = [0, 1, 2].map(|k| {
            let c = (p[0][k] + p[1][k] + p[2][k]) / 3.0;
            let t = (f64::from(c) - self.origin[k]) * self.scale;
            (t.max(0.0) as u64).min(top) as u32
        });
        morton(c)
    }
}

/// Spreads the low 21 bits of `v` to every third bit.
fn spread(v: u32) -> u64 {
    let mut x = u64::from(v) & 0x1f_ffff;
    x = (x | x << 32) & 0x1f_0000_0000_ffff;
    x = (x | x << 16) & 0x1f_0000_ff00_00ff;
    x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
    x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
    x = (x | x << 2) & 0x1249_2492_4924_9249;
    x
}

/// Morton code of a cell at [`KEY_LEVELS`] (x in the lowest bit of each triple).
pub fn morton(c: [u32; 3]) -> u64 {
    spread(c[0]) | spread(c[1]) << 1 | spread(c[2]) << 2
}

/// The octree cell of depth `depth` a key lies in (its top `3 * depth` bits).
pub fn key_prefix(key: u64, depth: u32) -> u64 {
    key >> (3 * (KEY_LEVELS - depth))
}

/// Octahedral encoding of a unit normal in snorm16 (zero for a zero vector).
pub fn encode_normal(n: [f32; 3]) -> [i16; 2] {
    let l1 = n[0].abs() + n[1].abs() + n[2].abs();
    if l1.is_nan() || l1 <= 0.0 {
        return [0, 0];
    }
    let (mut x, mut y) = (n[0] / l1, n[1] / l1);
    if n[2] < 0.0 {
        let (ox, oy) = (x, y);
        x = (1.0 - oy.abs()) * ox.signum();
        y = (1.0 - ox.abs()) * oy.signum();
    }
    let q = |v: f32| (v.clamp(-1.0, 1.0) * 32767.0).round() as i16;
    [q(x), q(y)]
}

/// Unit normal of an octahedral code.
pub fn decode_normal(e: [i16; 2]) -> [f32; 3] {
    let x = f32::from(e[0]) / 32767.0;
    let y = f32::from(e[1]) / 32767.0;
    let z = 1.0 - x.abs() - y.abs();
    let (x, y) = if z < 0.0 {
        ((1.0 - y.abs()) * x.signum(), (1.0 - x.abs()) * y.signum())
    } else {
        (x, y)
    };
    let l = (x * x + y * y + z * z).sqrt();
    if l > 0.0 {
        [x / l, y / l, z / l]
    } else {
        [0.0, 0.0, 1.0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn record_is_96_bytes() {
        assert_eq!(RECORD_BYTES, 96);
    }

    #[test]
    fn normals_round_trip_closely() {
        for n in [
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
            [0.6, -0.8, 0.0],
            [-0.48, 0.6, -0.64],
            [0.267_261_24, 0.534_522_5, 0.801_783_7],
        ] {
            let d = decode_normal(encode_normal(n));
            for k in 0..3 {
                assert!((d[k] - n[k]).abs() < 2e-4, "{n:?} -> {d:?}");
            }
        }
    }

    #[test]
    fn morton_prefixes_are_octree_cells() {
        let cube = Cube::around([0.0; 3], [1.0; 3]);
        let a = morton(cube.cell([0.1, 0.1, 0.1], KEY_LEVELS));
        let b = morton(cube.cell([0.2, 0.3, 0.4], KEY_LEVELS));
        let c = morton(cube.cell([0.9, 0.1, 0.1], KEY_LEVELS));
        assert_eq!(key_prefix(a, 1), key_prefix(b, 1));
        assert_eq!(key_prefix(c, 1), 1);
        assert_ne!(key_prefix(a, 2), key_prefix(b, 2));
        assert_eq!(morton([1, 0, 0]), 1);
        assert_eq!(morton([0, 1, 0]), 2);
        assert_eq!(morton([0, 0, 1]), 4);
        assert_eq!(morton([(1 << 21) - 1; 3]), (1 << 63) - 1);
    }
}
