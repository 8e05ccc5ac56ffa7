//! The caveclod shaders, compiled to SPIR-V by rust-gpu (`shaders/builder`) into
//! `vulkan/spirv/caveclod_shaders.spv`.
//!
//! Entry points only move data: the math is [`caveclod_core::gpu`], which the CPU runs and
//! tests too. Every interface variable carries an explicit location, binding or push-constant
//! block so the interface can be read off this file; `vulkan/spirv/INTERFACE.md` is the
//! contract the Vulkan host follows.
//!
//! - `draw_vs` + `draw_fs`: draw a mesh of `caveclod_core::Vertex` with a view-projection
//!   matrix and a colour ([`DrawPush`]) through [`shade`].
//! - `geomorph_vs` (+ `draw_fs`): draw the geomorph of two vertex streams at a per-instance
//!   `t`, placed by the instance's offset and scale ([`caveclod_core::gpu::MorphInstance`]).
//! - `geomorph_cs`: write [`morph_vertex`] of two vertex buffers into a third ([`MorphPush`]).
#![cfg_attr(target_arch = "spirv", no_std)]
#![deny(missing_docs)]

use caveclod_core::gpu::{morph_vertex, shade, DrawPush, MorphPush};
use caveclod_core::Vertex;
use spirv_std::glam::{Mat4, UVec3, Vec2, Vec3, Vec4};
use spirv_std::spirv;

/// Floats per vertex in the compute stage's buffers (the 32-byte `Vertex` layout).
const VERTEX_FLOATS: usize = 8;

/// The vertex from three attribute inputs.
fn vertex(position: Vec3, normal: Vec3, uv: Vec2) -> Vertex {
    Vertex {
        position: position.to_array(),
        normal: normal.to_array(),
        uv: uv.to_array(),
    }
}

/// Vertex stage for drawing: binding 0 holds `Vertex` records (stride 32).
#[spirv(vertex)]
pub fn draw_vs(
    #[spirv(location = 0)] position: Vec3,
    #[spirv(location = 1)] normal: Vec3,
    #[spirv(location = 2)] uv: Vec2,
    #[spirv(push_constant)] push: &DrawPush,
    #[spirv(position)] out_position: &mut Vec4,
    #[spirv(location = 0)] out_normal: &mut Vec3,
    #[spirv(location = 1)] out_uv: &mut Vec2,
) {
    *out_position = Mat4::from_cols_array(&push.view_proj) * position.extend(1.0);
    *out_normal = normal;
    *out_uv = uv;
}

/// Fragment stage for `draw_vs` and `geomorph_vs`: [`shade`] with the push-constant colour.
#[spirv(fragment)]
pub fn draw_fs(
    #[spirv(location = 0)] normal: Vec3,
    #[spirv(location = 1)] uv: Vec2,
    #[spirv(push_constant)] push: &DrawPush,
    #[spirv(location = 0)] out_colour: &mut Vec4,
) {
    *out_colour = shade(normal, uv, Vec4::from_array(push.colour));
}

/// Vertex stage for geomorphing: binding 0 holds the coarse vertices `a` (locations 0-2),
/// binding 1 the fine vertices `b` (locations 3-5), binding 2 one `MorphInstance` per
/// instance (location 6: offset and scale, location 7: `t`).
#[allow(clippy::too_many_arguments)]
#[spirv(vertex)]
pub fn geomorph_vs(
    #[spirv(location = 0)] a_position: Vec3,
    #[spirv(location = 1)] a_normal: Vec3,
    #[spirv(location = 2)] a_uv: Vec2,
    #[spirv(location = 3)] b_position: Vec3,
    #[spirv(location = 4)] b_normal: Vec3,
    #[spirv(location = 5)] b_uv: Vec2,
    #[spirv(location = 6)] offset_scale: Vec4,
    #[spirv(location = 7)] t: f32,
    #[spirv(push_constant)] push: &DrawPush,
    #[spirv(position)] out_position: &mut Vec4,
    #[spirv(location = 0)] out_normal: &mut Vec3,
    #[spirv(location = 1)] out_uv: &mut Vec2,
) {
    let v = morph_vertex(
        vertex(a_position, a_normal, a_uv),
        vertex(b_position, b_normal, b_uv),
        t,
    );
    let world = Vec3::from_array(v.position) * offset_scale.w + offset_scale.truncate();
    *out_position = Mat4::from_cols_array(&push.view_proj) * world.extend(1.0);
    *out_normal = Vec3::from_array(v.normal);
    *out_uv = Vec2::from_array(v.uv);
}

/// The first float of vertex `index` in a buffer of `len` floats, if the whole vertex is
/// inside it.
fn vertex_start(len: usize, index: u32) -> Option<usize> {
    // `index < len / 8` is `index * 8 + 8 <= len` without overflow.
    let index = index as usize;
    if index < len / VERTEX_FLOATS {
        Some(index * VERTEX_FLOATS)
    } else {
        None
    }
}

/// The vertex whose floats start at `start` (from [`vertex_start`]).
fn read_vertex(buffer: &[f32], start: usize) -> Vertex {
    Vertex {
        position: [buffer[start], buffer[start + 1], buffer[start + 2]],
        normal: [buffer[start + 3], buffer[start + 4], buffer[start + 5]],
        uv: [buffer[start + 6], buffer[start + 7]],
    }
}

/// Writes `v` as the floats starting at `start` (from [`vertex_start`]).
fn write_vertex(buffer: &mut [f32], start: usize, v: Vertex) {
    buffer[start] = v.position[0];
    buffer[start + 1] = v.position[1];
    buffer[start + 2] = v.position[2];
    buffer[start + 3] = v.normal[0];
    buffer[start + 4] = v.normal[1];
    buffer[start + 5] = v.normal[2];
    buffer[start + 6] = v.uv[0];
    buffer[start + 7] = v.uv[1];
}

/// Compute stage for geomorphing (64 invocations per workgroup): invocation `i < count`
/// writes `morph_vertex(a[src_offset + i], b[src_offset + i], t)` to
/// `out[dst_offset + i]`. Indices past the end of a buffer are skipped rather than read or
/// written.
#[spirv(compute(threads(64)))]
pub fn geomorph_cs(
    #[spirv(global_invocation_id)] id: UVec3,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] a: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] b: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] out: &mut [f32],
    #[spirv(push_constant)] push: &MorphPush,
) {
    let i = id.x;
    if i >= push.count {
        return;
    }
    // Offsets past `u32::MAX` are past the end of every buffer: skip them. (rust-gpu 0.11
    // has no `saturating_add`; a wrapped sum is smaller than the index added.)
    let src = push.src_offset.wrapping_add(i);
    let dst = push.dst_offset.wrapping_add(i);
    if src < i || dst < i {
        return;
    }
    let (Some(sa), Some(sb), Some(so)) = (
        vertex_start(a.len(), src),
        vertex_start(b.len(), src),
        vertex_start(out.len(), dst),
    ) else {
        return;
    };
    let v = morph_vertex(read_vertex(a, sa), read_vertex(b, sb), push.t);
    write_vertex(out, so, v);
}
