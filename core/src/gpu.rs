//! The math the GPU shaders run, shared with the CPU, and the plain-old-data blocks the host
//! hands to them.
//!
//! The rust-gpu shader crate (`shaders/caveclod-shaders`) depends on this crate and its entry
//! points only move data in and out: the arithmetic lives here, so the same function runs on
//! the CPU (unit tests, reference images, the geomorph read-back comparison) and on the GPU.
//!
//! Design decisions:
//! - Everything here compiles for `target_arch = "spirv"`: no allocation, no slices of
//!   unknown origin, no panicking paths, and only float operations that rust-gpu maps to
//!   GLSL.std.450 instructions (rust-gpu turns calls of the `libm` crate such as `sqrtf` and
//!   `floorf`, which glam uses too, into `Sqrt` and `Floor`).
//! - Formulas are written out step by step (`a + (b - a) * t`, `v / |v|`) rather than
//!   through glam helpers, so the CPU and GPU evaluate the same operations in the same order.
//! - [`checker`] decides parity with exact float operations (multiplying by 8 and halving
//!   are exact, `floor` is exact), never with a float-to-int cast, whose out-of-range
//!   behaviour differs between Rust (saturating) and SPIR-V (undefined).
//! - The push-constant and instance blocks are `#[repr(C)]` [`bytemuck::Pod`] structs whose
//!   sizes are checked at compile time against the shader interface (`vulkan/spirv/`).
//!
//! The interface between host and shaders (entry points, locations, bindings, push-constant
//! offsets) is described in `vulkan/spirv/INTERFACE.md` and in `shaders/README.md`.

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec2, Vec3, Vec4};

use crate::records::Vertex;

/// Push constants of the drawing stages (`draw_vs`, `draw_fs`, `geomorph_vs`): 80 bytes at
/// offset 0, visible to the vertex and fragment stages.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct DrawPush {
    /// The view-projection matrix, column-major (glam's `Mat4::to_cols_array`).
    pub view_proj: [f32; 16],
    /// The surface colour, linear RGBA; alpha is written through unchanged.
    pub colour: [f32; 4],
}

impl DrawPush {
    /// The block for a view-projection matrix and a colour.
    pub fn new(view_proj: Mat4, colour: Vec4) -> Self {
        Self {
            view_proj: view_proj.to_cols_array(),
            colour: colour.to_array(),
        }
    }
}

/// One instance of the geomorphing vertex stage (`geomorph_vs`, vertex binding 2, per
/// instance, stride 32): where to place the morphed vertices and how far to morph.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct MorphInstance {
    /// `xyz`: translation added after scaling; `w`: uniform scale (location 6, offset 0).
    pub offset_scale: [f32; 4],
    /// Morph parameter: 0 gives the coarse vertex, 1 the fine one (location 7, offset 16).
    pub t: f32,
    /// Padding to 32 bytes; zero.
    pub _pad: [f32; 3],
}

/// Push constants of the geomorphing compute stage (`geomorph_cs`): 16 bytes at offset 0.
/// Offsets and the count are in vertices (8 `f32` each).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct MorphPush {
    /// Morph parameter: 0 gives the vertices of the first input, 1 those of the second.
    pub t: f32,
    /// How many vertices to morph.
    pub count: u32,
    /// First vertex read from both input buffers.
    pub src_offset: u32,
    /// First vertex written in the output buffer.
    pub dst_offset: u32,
}

/// The sizes the shader interface declares; the shaders and the Vulkan host rely on them.
const _: () = {
    assert!(core::mem::size_of::<Vertex>() == 32);
    assert!(core::mem::size_of::<DrawPush>() == 80);
    assert!(core::mem::size_of::<MorphInstance>() == 32);
    assert!(core::mem::size_of::<MorphPush>() == 16);
};

/// `v` divided by its length, or `zero` when the length is zero (or not finite).
#[inline]
fn normalize_or(v: Vec3, zero: Vec3) -> Vec3 {
    let length = libm::sqrtf(v.dot(v));
    if length > 0.0 && length.is_finite() {
        v / length
    } else {
        zero
    }
}

/// The geomorph between a coarse vertex `a` and a fine vertex `b` at `t` (0 gives `a`,
/// 1 gives `b`): position and uv are `a + (b - a) * t`; the normal is interpolated the same
/// way and then normalised, unless the interpolated normal has zero length, in which case it
/// is returned unchanged.
#[inline]
pub fn morph_vertex(a: Vertex, b: Vertex, t: f32) -> Vertex {
    let pa = Vec3::from_array(a.position);
    let pb = Vec3::from_array(b.position);
    let na = Vec3::from_array(a.normal);
    let nb = Vec3::from_array(b.normal);
    let ua = Vec2::from_array(a.uv);
    let ub = Vec2::from_array(b.uv);
    let n = na + (nb - na) * t;
    Vertex {
        position: (pa + (pb - pa) * t).to_array(),
        normal: normalize_or(n, n).to_array(),
        uv: (ua + (ub - ua) * t).to_array(),
    }
}

/// The checkerboard of the shading: 1.0 where `floor(8u) + floor(8v)` is even, else 0.0
/// (eight squares per unit of texture coordinate).
#[inline]
pub fn checker(uv: Vec2) -> f32 {
    let cells = (uv * 8.0).floor();
    let sum = cells.x + cells.y;
    // `sum` is an integer; halving and doubling it is exact, so this is `sum mod 2`.
    let odd = sum - libm::floorf(sum * 0.5) * 2.0;
    if odd == 0.0 {
        1.0
    } else {
        0.0
    }
}

/// The direction towards the light (unnormalised; [`shade`] normalises it).
pub const LIGHT_DIRECTION: [f32; 3] = [0.3, 0.5, 0.8];

/// The colour of a surface point: Lambert lighting from [`LIGHT_DIRECTION`] with an ambient
/// floor, times a faint [`checker`] pattern so texture coordinates show.
///
/// `n = normalize(normal)` (zero length gives `(0, 0, 1)`), `l = normalize(LIGHT_DIRECTION)`,
/// `lambert = max(n · l, 0)`,
/// `rgb = colour.rgb * (0.25 + 0.75 * lambert) * (0.85 + 0.15 * checker(uv))`,
/// alpha is `colour.a`.
#[inline]
pub fn shade(normal: Vec3, uv: Vec2, colour: Vec4) -> Vec4 {
    let n = normalize_or(normal, Vec3::Z);
    let l = normalize_or(Vec3::from_array(LIGHT_DIRECTION), Vec3::Z);
    let lambert = n.dot(l).max(0.0);
    let rgb = colour.truncate() * (0.25 + 0.75 * lambert) * (0.85 + 0.15 * checker(uv));
    rgb.extend(colour.w)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vertex(p: [f32; 3], n: [f32; 3], uv: [f32; 2]) -> Vertex {
        Vertex {
            position: p,
            normal: n,
            uv,
        }
    }

    fn close(a: f32, b: f32) -> bool {
        (a - b).abs() <= 1e-6 * a.abs().max(b.abs()).max(1.0)
    }

    #[test]
    fn morph_ends_are_the_inputs() {
        let a = vertex([1.0, 2.0, 3.0], [0.0, 1.0, 0.0], [0.25, 0.5]);
        let b = vertex([-4.0, 0.5, 9.0], [1.0, 0.0, 0.0], [0.75, -0.5]);
        assert_eq!(morph_vertex(a, b, 0.0), a);
        assert_eq!(morph_vertex(a, b, 1.0), b);
    }

    #[test]
    fn morph_midpoint_lerps_and_normalises() {
        let a = vertex([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0]);
        let b = vertex([2.0, 4.0, -6.0], [1.0, 0.0, 0.0], [1.0, 2.0]);
        let m = morph_vertex(a, b, 0.5);
        assert_eq!(m.position, [1.0, 2.0, -3.0]);
        assert_eq!(m.uv, [0.5, 1.0]);
        let h = core::f32::consts::FRAC_1_SQRT_2;
        assert!(close(m.normal[0], h) && close(m.normal[1], h) && m.normal[2] == 0.0);
    }

    #[test]
    fn morph_keeps_a_zero_normal() {
        let a = vertex([0.0; 3], [0.0, 0.0, 1.0], [0.0; 2]);
        let b = vertex([0.0; 3], [0.0, 0.0, -1.0], [0.0; 2]);
        assert_eq!(morph_vertex(a, b, 0.5).normal, [0.0, 0.0, 0.0]);
    }

    #[test]
    fn morph_extrapolates_linearly() {
        let a = vertex([1.0, 1.0, 1.0], [0.0, 0.0, 2.0], [0.0, 0.0]);
        let b = vertex([3.0, 1.0, 1.0], [0.0, 0.0, 2.0], [1.0, 0.0]);
        let m = morph_vertex(a, b, 2.0);
        assert_eq!(m.position, [5.0, 1.0, 1.0]);
        assert_eq!(m.uv, [2.0, 0.0]);
        assert_eq!(m.normal, [0.0, 0.0, 1.0]);
    }

    #[test]
    fn checker_alternates_per_eighth() {
        assert_eq!(checker(Vec2::new(0.01, 0.01)), 1.0);
        assert_eq!(checker(Vec2::new(0.13, 0.01)), 0.0);
        assert_eq!(checker(Vec2::new(0.13, 0.13)), 1.0);
        assert_eq!(checker(Vec2::new(0.01, 0.26)), 1.0);
        // floor(-0.8) = -1: odd.
        assert_eq!(checker(Vec2::new(-0.1, 0.01)), 0.0);
        assert_eq!(checker(Vec2::new(-0.1, -0.1)), 1.0);
        // Large even and odd cell sums.
        assert_eq!(checker(Vec2::new(1000.0, 0.125)), 0.0);
        assert_eq!(checker(Vec2::new(1000.0, 0.25)), 1.0);
    }

    #[test]
    fn shade_facing_the_light_is_full_colour() {
        let colour = Vec4::new(0.5, 0.25, 1.0, 0.75);
        let l = Vec3::from_array(LIGHT_DIRECTION);
        // Checker 1 at uv 0: factor 1.0 * 1.0.
        let lit = shade(l * 3.0, Vec2::ZERO, colour);
        for (got, want) in lit.to_array().iter().zip(colour.to_array()) {
            assert!(close(*got, want), "{got} vs {want}");
        }
    }

    #[test]
    fn shade_facing_away_is_ambient_and_checker_dims() {
        let colour = Vec4::new(1.0, 1.0, 1.0, 1.0);
        let l = Vec3::from_array(LIGHT_DIRECTION);
        let dark_even = shade(-l, Vec2::ZERO, colour);
        assert!(close(dark_even.x, 0.25) && dark_even.w == 1.0);
        let dark_odd = shade(-l, Vec2::new(0.13, 0.0), colour);
        assert!(close(dark_odd.y, 0.25 * 0.85));
    }

    #[test]
    fn shade_zero_normal_faces_z() {
        let colour = Vec4::new(1.0, 0.5, 0.25, 1.0);
        let l = Vec3::from_array(LIGHT_DIRECTION).normalize();
        let want = 0.25 + 0.75 * l.z;
        let got = shade(Vec3::ZERO, Vec2::ZERO, colour);
        assert!(close(got.x, want) && close(got.y, 0.5 * want) && close(got.z, 0.25 * want));
    }

    #[test]
    fn blocks_cast_to_the_interface_bytes() {
        let push = DrawPush::new(Mat4::IDENTITY, Vec4::new(1.0, 2.0, 3.0, 4.0));
        let bytes = bytemuck::bytes_of(&push);
        assert_eq!(bytes.len(), 80);
        assert_eq!(&bytes[64..68], &1.0f32.to_ne_bytes());
        let morph = MorphPush {
            t: 0.5,
            count: 7,
            src_offset: 3,
            dst_offset: 9,
        };
        let words: [u32; 4] = bytemuck::cast(morph);
        assert_eq!(words, [0.5f32.to_bits(), 7, 3, 9]);
        let inst = MorphInstance {
            offset_scale: [1.0, 2.0, 3.0, 4.0],
            t: 0.25,
            _pad: [0.0; 3],
        };
        assert_eq!(&bytemuck::bytes_of(&inst)[16..20], &0.25f32.to_ne_bytes());
    }
}
