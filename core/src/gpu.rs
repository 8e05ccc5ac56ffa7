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

use crate::format::Vertex;

/// Push constants of the drawing stages (`draw_vs`, `draw_fs`, `geomorph_vs`): 96 bytes at
/// offset 0, visible to the vertex and fragment stages.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct DrawPush {
    /// The view-projection matrix, column-major (glam's `Mat4::to_cols_array`).
    pub view_proj: [f32; 16],
    /// The surface colour (a material's base colour factor, or a palette colour), linear
    /// RGBA; multiplied with the base-colour texel.
    pub colour: [f32; 4],
    /// `x`: weight of the [`checker`] pattern (0 for materials); `y`: alpha cutoff (a
    /// fragment whose alpha is below it is discarded; 0 keeps every fragment); `z`, `w`: 0.
    pub shading: [f32; 4],
}

/// The checker weight of palette colours: texture coordinates show faintly.
pub const PALETTE_CHECKER: f32 = 0.15;

impl DrawPush {
    /// The block for a view-projection matrix and a palette colour (faint checker, no
    /// cutoff).
    pub fn new(view_proj: Mat4, colour: Vec4) -> Self {
        Self {
            view_proj: view_proj.to_cols_array(),
            colour: colour.to_array(),
            shading: [PALETTE_CHECKER, 0.0, 0.0, 0.0],
        }
    }

    /// The block for a material: its base colour factor and alpha cutoff (0 for opaque or
    /// blended materials), no checker.
    pub fn material(view_proj: Mat4, factor: Vec4, alpha_cutoff: f32) -> Self {
        Self {
            view_proj: view_proj.to_cols_array(),
            colour: factor.to_array(),
            shading: [0.0, alpha_cutoff, 0.0, 0.0],
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

/// Push constants of the morphing vertex stage (`morphing_vs`, which draws a camera's front
/// with its refinement geomorphs): the drawing block at offset 0 (which `draw_fs` reads too),
/// then how to find the camera's morphing vertices. 112 bytes, vertex and fragment stages.
///
/// An index below `vertex_count` is a persistent vertex; index `vertex_count + s` is morph
/// slot `s` ([`MorphVertex`], as [`CameraState::morph_vertices`] lists them and morphed
/// emission points at them).
///
/// [`CameraState::morph_vertices`]: crate::CameraState::morph_vertices
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct MorphingPush {
    /// The drawing block.
    pub draw: DrawPush,
    /// Vertices in the persistent vertex buffer.
    pub vertex_count: u32,
    /// Morph slots the slot buffer holds this frame (a slot at or past it is not read).
    pub slot_count: u32,
    /// [`MORPH_IN_VERTEX_STAGE`]: blend each morphing corner from its slot here;
    /// [`MORPH_BLENDED`]: read the vertex the compute stage (or the host) blended into the
    /// camera's blended buffer.
    pub source: u32,
    /// 1: a vertex colour per persistent vertex (RGBA8, binding 3); 0: white.
    pub colours: u32,
}

/// [`MorphingPush::source`]: the vertex stage blends morphing corners from their slots.
pub const MORPH_IN_VERTEX_STAGE: u32 = 0;
/// [`MorphingPush::source`]: the vertex stage reads morphing corners from the blended buffer.
pub const MORPH_BLENDED: u32 = 1;

/// Push constants of the refinement-geomorph compute stage (`morphing_cs`): 16 bytes at
/// offset 0.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct MorphSlotsPush {
    /// Slots to blend: invocation `s < slot_count` writes slot `s`.
    pub slot_count: u32,
    /// Vertices in the persistent vertex buffer: a slot's `from` at or past it names
    /// another slot ([`MorphVertex::from`]).
    pub vertex_count: u32,
    /// Zero; pads the block to 16 bytes.
    pub _pad: [u32; 2],
}

/// One morphing vertex as the GPU reads it: blend from `from` towards persistent vertex `to`
/// at `t` ([`morph_slot_vertex`]) and write the result
/// where morphed emission points, `vertex_count + slot`. An idle slot has
/// `from == to == u32::MAX` ([`MorphVertex::IDLE`]): nothing points at it and it is skipped.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct MorphVertex {
    /// Where the blend starts: the persistent vertex `coarse` (`< vertex_count`), or, while
    /// `coarse` itself morphs, `vertex_count + s`: the blend of slot `s`, so a vertex that
    /// splits again while it morphs starts its child where it is drawn (chains span at most
    /// [`MAX_MORPH_CHAIN`] slots).
    pub from: u32,
    /// The fine vertex: the floating child's own.
    pub to: u32,
    /// 0 gives `from`, 1 gives `to`.
    pub t: f32,
    /// The coarse persistent vertex: the parent's, in the same surface group where it has
    /// one. `from` once `coarse` no longer morphs.
    pub coarse: u32,
}

impl MorphVertex {
    /// A slot without a morphing vertex.
    pub const IDLE: Self = Self {
        from: u32::MAX,
        to: u32::MAX,
        t: 0.0,
        coarse: u32::MAX,
    };

    /// `true` for a slot without a morphing vertex.
    pub fn is_idle(&self) -> bool {
        self.to == u32::MAX
    }
}

/// The sizes the shader interface declares; the shaders and the Vulkan host rely on them.
const _: () = {
    assert!(core::mem::size_of::<Vertex>() == 32);
    assert!(core::mem::size_of::<DrawPush>() == 96);
    assert!(core::mem::size_of::<MorphInstance>() == 32);
    assert!(core::mem::size_of::<MorphPush>() == 16);
    assert!(core::mem::size_of::<MorphingPush>() == 112);
    assert!(core::mem::size_of::<MorphSlotsPush>() == 16);
    assert!(core::mem::size_of::<MorphVertex>() == 16);
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

/// Most slots one morph chain blends (see [`MorphVertex::from`]): a slot whose chain runs
/// longer starts, at the last slot within the limit, from that slot's persistent
/// [`coarse`](MorphVertex::coarse) vertex. Refinement keeps its chains within it.
pub const MAX_MORPH_CHAIN: u32 = 8;

/// What a morph slot's blend reads: the camera's slots and the persistent vertices, as the
/// CPU holds them (slices) or a shader reads them (storage buffers).
pub trait MorphInputs {
    /// Vertices in the persistent vertex buffer.
    fn vertex_count(&self) -> u32;
    /// Slot `s`; `None` for an idle slot or one past the end.
    fn slot(&self, s: u32) -> Option<MorphVertex>;
    /// Persistent vertex `index`; `None` past the end.
    fn vertex(&self, index: u32) -> Option<Vertex>;
}

/// The CPU's morph inputs: a camera's [`morph_vertices`](crate::CameraState::morph_vertices)
/// and the hierarchy's vertices.
#[derive(Clone, Copy, Debug)]
pub struct MorphSlices<'a> {
    /// The persistent vertices.
    pub vertices: &'a [Vertex],
    /// The camera's morph slots.
    pub slots: &'a [MorphVertex],
}

impl MorphInputs for MorphSlices<'_> {
    #[inline]
    fn vertex_count(&self) -> u32 {
        self.vertices.len() as u32
    }

    #[inline]
    fn slot(&self, s: u32) -> Option<MorphVertex> {
        self.slots.get(s as usize).copied().filter(|m| !m.is_idle())
    }

    #[inline]
    fn vertex(&self, index: u32) -> Option<Vertex> {
        self.vertices.get(index as usize).copied()
    }
}

/// The chain of slot `s`: how many slots its blend passes through (at least 1) and the
/// persistent vertex it starts from. A `from` naming an idle slot, or a chain longer than
/// [`MAX_MORPH_CHAIN`], starts from the last slot's `coarse` vertex.
#[inline]
pub fn morph_chain<I: MorphInputs + ?Sized>(inputs: &I, s: u32) -> Option<(u32, u32)> {
    let vertex_count = inputs.vertex_count();
    let mut m = inputs.slot(s)?;
    let mut len = 1;
    loop {
        if m.from < vertex_count {
            return Some((len, m.from));
        }
        if len >= MAX_MORPH_CHAIN {
            return Some((len, m.coarse));
        }
        match inputs.slot(m.from - vertex_count) {
            Some(next) => {
                m = next;
                len += 1;
            }
            None => return Some((len, m.coarse)),
        }
    }
}

/// The slot `k` links along slot `s`'s chain (`k` below the chain's length).
#[inline]
fn chain_link<I: MorphInputs + ?Sized>(inputs: &I, s: u32, k: u32) -> Option<MorphVertex> {
    let vertex_count = inputs.vertex_count();
    let mut m = inputs.slot(s)?;
    let mut i = 0;
    while i < k {
        m = inputs.slot(m.from.checked_sub(vertex_count)?)?;
        i += 1;
    }
    Some(m)
}

/// The vertex refinement-geomorph slot `s` stands for: its chain's persistent start, then
/// [`morph_vertex`] towards each slot's `to` at its `t`, from the chain's far end back to
/// `s` (for a slot whose `from` is persistent, `morph_vertex(from, to, t)`). `None` for an
/// idle slot or one whose chain names a vertex past the end. What the compute stage writes
/// per slot and the vertex stage computes per morphing corner.
#[inline]
pub fn morph_slot_vertex<I: MorphInputs + ?Sized>(inputs: &I, s: u32) -> Option<Vertex> {
    let (len, base) = morph_chain(inputs, s)?;
    let mut v = inputs.vertex(base)?;
    let mut k = len;
    while k > 0 {
        k -= 1;
        let m = chain_link(inputs, s, k)?;
        v = morph_vertex(v, inputs.vertex(m.to)?, m.t);
    }
    Some(v)
}

/// The linear colour of morph slot `s`, blended along its chain as
/// [`morph_slot_vertex`] blends its vertex: `colour(i)` is persistent vertex `i`'s stored
/// (sRGB-encoded) colour, decoded by [`vertex_colour`]; each step is `a + (b - a) * t`.
/// White for an idle slot.
#[inline]
pub fn morph_slot_colour<I, C>(inputs: &I, s: u32, colour: C) -> Vec4
where
    I: MorphInputs + ?Sized,
    C: Fn(u32) -> Vec4,
{
    let Some((len, base)) = morph_chain(inputs, s) else {
        return Vec4::ONE;
    };
    let mut c = vertex_colour(colour(base));
    let mut k = len;
    while k > 0 {
        k -= 1;
        if let Some(m) = chain_link(inputs, s, k) {
            let b = vertex_colour(colour(m.to));
            c = c + (b - c) * m.t;
        }
    }
    c
}

/// The linear colour of a morphing vertex: the stored (sRGB-encoded) colours `from` and `to`
/// decoded by [`vertex_colour`], then `a + (b - a) * t`.
#[inline]
pub fn morph_colour(from: Vec4, to: Vec4, t: f32) -> Vec4 {
    let a = vertex_colour(from);
    let b = vertex_colour(to);
    a + (b - a) * t
}

/// An RGBA8 vertex colour (`R` in the low byte, as the file stores it) as the UNORM
/// vector the drawing stage's vertex input reads.
#[inline]
pub fn unpack_colour(packed: u32) -> Vec4 {
    let channel = |shift: u32| ((packed >> shift) & 0xff) as f32 / 255.0;
    Vec4::new(channel(0), channel(8), channel(16), channel(24))
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

/// The ambient floor of [`shade`]: the part of the colour a surface facing away from the
/// light keeps.
pub const AMBIENT: f32 = 0.25;

/// The colour of a surface point: one directional light from [`LIGHT_DIRECTION`] plus
/// [`AMBIENT`], lit on both sides (a back face is lit by its reversed normal, so no side is
/// black), times a [`checker`] pattern of weight `checker_weight` so texture coordinates
/// show (0 for none).
///
/// `n = normalize(normal)` (zero length gives `(0, 0, 1)`), negated when `!front_facing`;
/// `l = normalize(LIGHT_DIRECTION)`, `lambert = max(n · l, 0)`,
/// `rgb = colour.rgb * (AMBIENT + (1 - AMBIENT) * lambert)
///        * (1 - checker_weight + checker_weight * checker(uv))`,
/// alpha is `colour.a`.
#[inline]
pub fn shade(
    normal: Vec3,
    front_facing: bool,
    uv: Vec2,
    colour: Vec4,
    checker_weight: f32,
) -> Vec4 {
    let mut n = normalize_or(normal, Vec3::Z);
    if !front_facing {
        n = -n;
    }
    let l = normalize_or(Vec3::from_array(LIGHT_DIRECTION), Vec3::Z);
    let lambert = n.dot(l).max(0.0);
    let pattern = 1.0 - checker_weight + checker_weight * checker(uv);
    let rgb = colour.truncate() * (AMBIENT + (1.0 - AMBIENT) * lambert) * pattern;
    rgb.extend(colour.w)
}

/// The base colour of a fragment: the sampled base-colour `texel` times the interpolated
/// (linear) vertex colour times the push block's colour, component-wise.
#[inline]
pub fn base_colour(texel: Vec4, vertex: Vec4, push: &DrawPush) -> Vec4 {
    texel * vertex * Vec4::from_array(push.colour)
}

/// One sRGB-encoded channel in `0..=1` as linear light (the sRGB transfer function).
#[inline]
fn srgb_channel(s: f32) -> f32 {
    if s <= 0.04045 {
        s / 12.92
    } else {
        libm::powf((s + 0.055) / 1.055, 2.4)
    }
}

/// A stored vertex colour as the vertex stage reads it (RGBA8 as UNORM: sRGB-encoded colour,
/// linear alpha) in linear RGBA.
#[inline]
pub fn vertex_colour(encoded: Vec4) -> Vec4 {
    Vec4::new(
        srgb_channel(encoded.x),
        srgb_channel(encoded.y),
        srgb_channel(encoded.z),
        encoded.w,
    )
}

/// Whether a fragment of base colour `base` is discarded: its alpha is below the push
/// block's cutoff.
#[inline]
pub fn cut(base: Vec4, push: &DrawPush) -> bool {
    base.w < push.shading[1]
}

/// The colour the drawing stages write for a fragment of base colour `base` (see
/// [`base_colour`]; [`cut`] decides first whether it is written at all): [`shade`] with
/// the block's checker weight.
#[inline]
pub fn fragment(normal: Vec3, front_facing: bool, uv: Vec2, base: Vec4, push: &DrawPush) -> Vec4 {
    shade(normal, front_facing, uv, base, push.shading[0])
}

#[cfg(test)]
mod tests;
