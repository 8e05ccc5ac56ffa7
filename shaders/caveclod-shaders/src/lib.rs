//! The caveclod shaders, compiled to SPIR-V by rust-gpu (`shaders/builder`) into
//! `vulkan/spirv/caveclod_shaders.spv`.
//!
//! Entry points only move data: the math is [`caveclod_core::gpu`], which the CPU runs and
//! tests too. Every interface variable carries an explicit location, binding or push-constant
//! block so the interface can be read off this file; `vulkan/spirv/INTERFACE.md` is the
//! contract the Vulkan host follows.
//!
//! - `draw_vs` + `draw_fs`: draw a mesh of `caveclod_core::format::Vertex` with a view-projection
//!   matrix, a colour and shading parameters ([`DrawPush`]), the base-colour texture of set 0
//!   sampled and lit through [`fragment`].
//! - `geomorph_vs` (+ `draw_fs`): draw the geomorph of two vertex streams at a per-instance
//!   `t`, placed by the instance's offset and scale ([`caveclod_core::gpu::MorphInstance`]).
//! - `geomorph_cs`: write [`morph_vertex`] of two vertex buffers into a third ([`MorphPush`]).
//! - `morphing_vs` (+ `draw_fs`): draw a camera's front with its refinement geomorphs,
//!   pulling vertices from storage buffers: an index past the persistent vertices is a morph
//!   slot, blended here or read from what `morphing_cs` wrote ([`MorphingPush`]).
//! - `morphing_cs`: write each morph slot's blended vertex
//!   ([`caveclod_core::gpu::morph_slot_vertex`]) into the
//!   camera's blended buffer ([`MorphSlotsPush`]).
#![cfg_attr(target_arch = "spirv", no_std)]
#![deny(missing_docs)]

use caveclod_core::MorphVertex;
use caveclod_core::format::Vertex;
use caveclod_core::gpu::{
    base_colour, cut, fragment, morph_slot_colour, morph_slot_vertex, morph_vertex,
    unpack_colour, vertex_colour, DrawPush, MorphInputs, MorphPush, MorphSlotsPush, MorphingPush,
    MORPH_BLENDED,
};
use spirv_std::glam::{Mat4, UVec3, Vec2, Vec3, Vec4};
use spirv_std::image::Image2d;
use spirv_std::{spirv, Sampler};

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

/// Vertex stage for drawing: binding 0 holds `Vertex` records (stride 32), binding 1 the
/// vertex colours (RGBA8 read as UNORM, sRGB-encoded; stride 4, or 0 for one colour for
/// every vertex).
#[allow(clippy::too_many_arguments)]
#[spirv(vertex)]
pub fn draw_vs(
    #[spirv(location = 0)] position: Vec3,
    #[spirv(location = 1)] normal: Vec3,
    #[spirv(location = 2)] uv: Vec2,
    #[spirv(location = 3)] colour: Vec4,
    #[spirv(push_constant)] push: &DrawPush,
    #[spirv(position)] out_position: &mut Vec4,
    #[spirv(location = 0)] out_normal: &mut Vec3,
    #[spirv(location = 1)] out_uv: &mut Vec2,
    #[spirv(location = 2)] out_colour: &mut Vec4,
) {
    *out_position = Mat4::from_cols_array(&push.view_proj) * position.extend(1.0);
    *out_normal = normal;
    *out_uv = uv;
    *out_colour = vertex_colour(colour);
}

/// Fragment stage for `draw_vs` and `geomorph_vs`: the base-colour texture (set 0, binding
/// 0, sampled with the sampler of binding 1) at `uv` times the push colour
/// ([`base_colour`]), discarded below the alpha cutoff ([`cut`]), lit by [`fragment`].
#[spirv(fragment)]
pub fn draw_fs(
    #[spirv(location = 0)] normal: Vec3,
    #[spirv(location = 1)] uv: Vec2,
    #[spirv(location = 2)] vertex: Vec4,
    #[spirv(front_facing)] front_facing: bool,
    #[spirv(descriptor_set = 0, binding = 0)] texture: &Image2d,
    #[spirv(descriptor_set = 0, binding = 1)] sampler: &Sampler,
    #[spirv(push_constant)] push: &DrawPush,
    #[spirv(location = 0)] out_colour: &mut Vec4,
) {
    let texel: Vec4 = texture.sample(*sampler, uv);
    let base = base_colour(texel, vertex, push);
    if cut(base, push) {
        spirv_std::arch::kill();
    }
    *out_colour = fragment(normal, front_facing, uv, base, push);
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
    #[spirv(location = 2)] out_colour: &mut Vec4,
) {
    *out_colour = Vec4::ONE;
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

/// Words per morph slot in a slot buffer: a [`MorphVertex`] (`from`, `to`, `t`'s bits,
/// `coarse`).
const SLOT_WORDS: usize = 4;

/// Morph slot `slot` of a slot buffer, if it lies wholly inside it and is not idle.
fn read_slot(slots: &[u32], slot: u32) -> Option<MorphVertex> {
    let s = slot as usize;
    if s >= slots.len() / SLOT_WORDS {
        return None;
    }
    let w = s * SLOT_WORDS;
    let m = MorphVertex {
        from: slots[w],
        to: slots[w + 1],
        t: f32::from_bits(slots[w + 2]),
        coarse: slots[w + 3],
    };
    if m.is_idle() {
        None
    } else {
        Some(m)
    }
}

/// What a slot's blend reads in the shaders: the slot buffer (the first `slot_count`
/// slots) and the persistent vertices.
struct SlotBuffers<'a> {
    vertices: &'a [f32],
    slots: &'a [u32],
    slot_count: u32,
    vertex_count: u32,
}

impl MorphInputs for SlotBuffers<'_> {
    fn vertex_count(&self) -> u32 {
        self.vertex_count
    }

    fn slot(&self, s: u32) -> Option<MorphVertex> {
        if s < self.slot_count {
            read_slot(self.slots, s)
        } else {
            None
        }
    }

    fn vertex(&self, index: u32) -> Option<Vertex> {
        vertex_start(self.vertices.len(), index).map(|start| read_vertex(self.vertices, start))
    }
}

/// Vertex `index` of a buffer of `f32`s, or the zero vertex past its end.
fn vertex_at(buffer: &[f32], index: u32) -> Vertex {
    match vertex_start(buffer.len(), index) {
        Some(start) => read_vertex(buffer, start),
        None => vertex(Vec3::ZERO, Vec3::ZERO, Vec2::ZERO),
    }
}

/// The stored (sRGB-encoded) colour of persistent vertex `index`: white without colours or
/// past the end of the buffer.
fn colour_at(colours: &[u32], on: bool, index: u32) -> Vec4 {
    let i = index as usize;
    if on && i < colours.len() {
        unpack_colour(colours[i])
    } else {
        Vec4::ONE
    }
}

/// The vertex and linear colour `morphing_vs` draws for index `index` (see [`MorphingPush`]):
/// a persistent vertex as stored, or a morph slot's blend along its chain
/// ([`morph_slot_vertex`], computed here, or read from `blended`), with its colours blended
/// alike ([`morph_slot_colour`]). An index past the slots, or an idle slot, gives the zero
/// vertex.
fn pulled_vertex(
    index: u32,
    vertices: &[f32],
    slots: &[u32],
    blended: &[f32],
    colours: &[u32],
    push: &MorphingPush,
) -> (Vertex, Vec4) {
    let has_colours = push.colours != 0;
    if index < push.vertex_count {
        let colour = vertex_colour(colour_at(colours, has_colours, index));
        return (vertex_at(vertices, index), colour);
    }
    let slot = index - push.vertex_count;
    let inputs = SlotBuffers {
        vertices,
        slots,
        slot_count: push.slot_count,
        vertex_count: push.vertex_count,
    };
    if inputs.slot(slot).is_none() {
        return (vertex(Vec3::ZERO, Vec3::ZERO, Vec2::ZERO), Vec4::ONE);
    }
    let v = if push.source == MORPH_BLENDED {
        vertex_at(blended, slot)
    } else {
        match morph_slot_vertex(&inputs, slot) {
            Some(v) => v,
            None => vertex(Vec3::ZERO, Vec3::ZERO, Vec2::ZERO),
        }
    };
    let colour = morph_slot_colour(&inputs, slot, |i| colour_at(colours, has_colours, i));
    (v, colour)
}

/// Vertex stage for a camera's front with refinement geomorphs. Vertices are pulled from
/// set 1: binding 0 the persistent vertices (`f32`s, 8 per vertex), binding 1 the camera's
/// morph slots (`u32`s, 4 per slot), binding 2 its blended vertices (`f32`s, 8 per slot),
/// binding 3 the vertex colours (one RGBA8 `u32` per vertex); [`pulled_vertex`] says what
/// an index stands for. Outputs as `draw_vs`.
#[allow(clippy::too_many_arguments)]
#[spirv(vertex)]
pub fn morphing_vs(
    #[spirv(vertex_index)] index: i32,
    #[spirv(storage_buffer, descriptor_set = 1, binding = 0)] vertices: &[f32],
    #[spirv(storage_buffer, descriptor_set = 1, binding = 1)] slots: &[u32],
    #[spirv(storage_buffer, descriptor_set = 1, binding = 2)] blended: &[f32],
    #[spirv(storage_buffer, descriptor_set = 1, binding = 3)] colours: &[u32],
    #[spirv(push_constant)] push: &MorphingPush,
    #[spirv(position)] out_position: &mut Vec4,
    #[spirv(location = 0)] out_normal: &mut Vec3,
    #[spirv(location = 1)] out_uv: &mut Vec2,
    #[spirv(location = 2)] out_colour: &mut Vec4,
) {
    let (v, colour) = pulled_vertex(index as u32, vertices, slots, blended, colours, push);
    let position = Vec3::from_array(v.position);
    *out_position = Mat4::from_cols_array(&push.draw.view_proj) * position.extend(1.0);
    *out_normal = Vec3::from_array(v.normal);
    *out_uv = Vec2::from_array(v.uv);
    *out_colour = colour;
}

/// Compute stage for refinement geomorphs (64 invocations per workgroup): invocation
/// `s < slot_count` writes morph slot `s`'s vertex, [`morph_slot_vertex`] (its chain's
/// persistent start blended towards each slot's `to`), to `blended[s]`. Idle slots, and
/// slots or vertices not wholly inside their buffers, are skipped.
#[spirv(compute(threads(64)))]
pub fn morphing_cs(
    #[spirv(global_invocation_id)] id: UVec3,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] vertices: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] slots: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] blended: &mut [f32],
    #[spirv(push_constant)] push: &MorphSlotsPush,
) {
    let s = id.x;
    let inputs = SlotBuffers {
        vertices,
        slots,
        slot_count: push.slot_count,
        vertex_count: push.vertex_count,
    };
    let (Some(v), Some(out)) = (
        morph_slot_vertex(&inputs, s),
        vertex_start(blended.len(), s),
    ) else {
        return;
    };
    write_vertex(blended, out, v);
}

/// The entry points run on the CPU as plain functions (the builder runs these tests before
/// compiling to SPIR-V).
#[cfg(all(test, not(target_arch = "spirv")))]
mod tests {
    use super::*;
    use caveclod_core::gpu::MorphInstance;

    fn floats(vertices: &[Vertex]) -> Vec<f32> {
        vertices
            .iter()
            .flat_map(|v| {
                v.position
                    .iter()
                    .chain(v.normal.iter())
                    .chain(v.uv.iter())
                    .copied()
                    .collect::<Vec<_>>()
            })
            .collect()
    }

    fn vertices(seed: f32, count: usize) -> Vec<Vertex> {
        (0..count)
            .map(|i| {
                let x = seed + i as f32;
                Vertex {
                    position: [x, -x * 0.5, 2.0 * x],
                    normal: [1.0, x, 0.25],
                    uv: [x * 0.125, 1.0 - x * 0.25],
                }
            })
            .collect()
    }

    fn run_cs(a: &[f32], b: &[f32], out: &mut [f32], push: MorphPush, invocations: u32) {
        for x in 0..invocations {
            geomorph_cs(UVec3::new(x, 0, 0), a, b, out, &push);
        }
    }

    #[test]
    fn geomorph_cs_writes_the_cpu_morph_at_the_offsets() {
        let (va, vb) = (vertices(1.0, 6), vertices(-3.0, 6));
        let (a, b) = (floats(&va), floats(&vb));
        let mut out = vec![-7.0f32; 8 * 5];
        let push = MorphPush {
            t: 0.25,
            count: 3,
            src_offset: 2,
            dst_offset: 1,
        };
        run_cs(&a, &b, &mut out, push, 64);
        let untouched = [-7.0f32; 8];
        assert_eq!(out[0..8], untouched);
        for i in 0..3 {
            let want = floats(&[morph_vertex(va[2 + i], vb[2 + i], 0.25)]);
            assert_eq!(out[8 * (1 + i)..8 * (2 + i)], want[..], "vertex {i}");
        }
        assert_eq!(out[32..40], untouched);
    }

    #[test]
    fn geomorph_cs_skips_vertices_past_a_buffer_end() {
        let (va, vb) = (vertices(1.0, 4), vertices(2.0, 3));
        let (a, b) = (floats(&va), floats(&vb));
        let mut out = vec![-7.0f32; 8 * 4 + 5];
        let push = MorphPush {
            t: 0.5,
            count: 4,
            src_offset: 0,
            dst_offset: 1,
        };
        run_cs(&a, &b, &mut out, push, 64);
        // b has 3 vertices: the fourth is skipped; the output holds vertices 1..=3 whole,
        // its last 5 floats are not a whole vertex.
        for i in 0..3 {
            let want = floats(&[morph_vertex(va[i], vb[i], 0.5)]);
            assert_eq!(out[8 * (1 + i)..8 * (2 + i)], want[..], "vertex {i}");
        }
        assert!(out[..8].iter().chain(&out[32..]).all(|&f| f == -7.0));
        // Offsets that overflow u32 are skipped, not wrapped around.
        let mut out = vec![-7.0f32; 8];
        let push = MorphPush {
            t: 0.5,
            count: 2,
            src_offset: 0,
            dst_offset: u32::MAX,
        };
        run_cs(&a, &b, &mut out, push, 2);
        assert!(out.iter().all(|&f| f == -7.0));
    }

    fn slot_words(slots: &[MorphVertex]) -> Vec<u32> {
        slots
            .iter()
            .flat_map(|m| [m.from, m.to, m.t.to_bits(), m.coarse])
            .collect()
    }

    fn morph_slots() -> Vec<MorphVertex> {
        let slot = |from, to, t, coarse| MorphVertex {
            from,
            to,
            t,
            coarse,
        };
        // Slot 4 starts from slot 0's blend (index 5 + 0 of 5 vertices).
        vec![
            slot(0, 3, 0.25, 0),
            MorphVertex::IDLE,
            slot(4, 1, 0.75, 4),
            slot(2, 9, 0.5, 2),
            slot(5, 2, 0.5, 3),
        ]
    }

    fn cpu(vs: &[Vertex], m: &[MorphVertex], s: u32) -> Option<Vertex> {
        let inputs = caveclod_core::gpu::MorphSlices {
            vertices: vs,
            slots: m,
        };
        morph_slot_vertex(&inputs, s)
    }

    #[test]
    fn morphing_cs_writes_each_live_slot_as_the_cpu_blends_it() {
        let vs = vertices(0.5, 5);
        let (v, m) = (floats(&vs), morph_slots());
        let words = slot_words(&m);
        let mut out = vec![-7.0f32; 8 * 5];
        let push = MorphSlotsPush {
            slot_count: 5,
            vertex_count: 5,
            _pad: [0; 2],
        };
        for x in 0..64 {
            morphing_cs(UVec3::new(x, 0, 0), &v, &words, &mut out, &push);
        }
        for (s, slot) in m.iter().enumerate() {
            let got = &out[8 * s..8 * s + 8];
            match cpu(&vs, &m, s as u32) {
                Some(want) => assert_eq!(got, &floats(&[want])[..], "slot {s}: {slot:?}"),
                // Idle, or naming vertex 9 of 5: untouched.
                None => assert!(got.iter().all(|&f| f == -7.0), "slot {s}"),
            }
        }
        // A count below the slots leaves the rest alone.
        let mut out = vec![-7.0f32; 8 * 5];
        let push = MorphSlotsPush {
            slot_count: 1,
            vertex_count: 5,
            _pad: [0; 2],
        };
        for x in 0..64 {
            morphing_cs(UVec3::new(x, 0, 0), &v, &words, &mut out, &push);
        }
        assert!(out[8..].iter().all(|&f| f == -7.0));
    }

    #[test]
    fn morphing_vs_draws_persistent_vertices_and_slots_from_either_source() {
        let vs = vertices(0.5, 5);
        let (v, m) = (floats(&vs), morph_slots());
        let words = slot_words(&m);
        let colours: Vec<u32> = (0..5u32).map(|i| 0x8000_0000 | (i * 40)).collect();
        // What the compute stage would have written.
        let blended: Vec<f32> = (0..m.len() as u32)
            .flat_map(|s| {
                let b = cpu(&vs, &m, s);
                floats(&[b.unwrap_or(vertex(Vec3::ZERO, Vec3::ZERO, Vec2::ZERO))])
            })
            .collect();
        let draw = DrawPush::new(Mat4::IDENTITY, Vec4::ONE);
        for source in [caveclod_core::gpu::MORPH_IN_VERTEX_STAGE, MORPH_BLENDED] {
            let push = MorphingPush {
                draw,
                vertex_count: 5,
                slot_count: 5,
                source,
                colours: 1,
            };
            let run = |index: i32| {
                let (mut pos, mut n, mut uv, mut c) = (Vec4::ZERO, Vec3::ZERO, Vec2::ZERO, Vec4::ZERO);
                morphing_vs(
                    index, &v, &words, &blended, &colours, &push, &mut pos, &mut n, &mut uv, &mut c,
                );
                (pos, n, uv, c)
            };
            // A persistent vertex, as stored, with its decoded colour.
            let (pos, n, uv, c) = run(2);
            assert_eq!(pos, Vec3::from_array(vs[2].position).extend(1.0));
            assert_eq!((n, uv), (Vec3::from_array(vs[2].normal), Vec2::from_array(vs[2].uv)));
            assert_eq!(c, vertex_colour(unpack_colour(colours[2])));
            // Slot 2 (index 7): vertex 4 towards vertex 1 at 0.75, colours blended alike.
            let want = morph_vertex(vs[4], vs[1], 0.75);
            let (pos, n, uv, c) = run(7);
            assert_eq!(pos, Vec3::from_array(want.position).extend(1.0), "source {source}");
            assert_eq!((n, uv), (Vec3::from_array(want.normal), Vec2::from_array(want.uv)));
            let want_colour = caveclod_core::gpu::morph_colour(
                unpack_colour(colours[4]),
                unpack_colour(colours[1]),
                0.75,
            );
            assert_eq!(c, want_colour);
            // Slot 4 (index 9): from slot 0's blend towards vertex 2.
            let want = morph_vertex(morph_vertex(vs[0], vs[3], 0.25), vs[2], 0.5);
            let (pos, _, _, c) = run(9);
            assert_eq!(pos, Vec3::from_array(want.position).extend(1.0), "source {source}");
            let start = caveclod_core::gpu::morph_colour(
                unpack_colour(colours[0]),
                unpack_colour(colours[3]),
                0.25,
            );
            let end = vertex_colour(unpack_colour(colours[2]));
            assert_eq!(c, start + (end - start) * 0.5);
            // An idle slot and an index past the slots: the zero vertex.
            for idle in [6, 10] {
                assert_eq!(run(idle).0, Vec4::new(0.0, 0.0, 0.0, 1.0), "index {idle}");
            }
        }
    }

    #[test]
    fn vertex_start_needs_the_whole_vertex() {
        assert_eq!(vertex_start(16, 0), Some(0));
        assert_eq!(vertex_start(16, 1), Some(8));
        assert_eq!(vertex_start(15, 1), None);
        assert_eq!(vertex_start(16, 2), None);
        assert_eq!(vertex_start(0, 0), None);
        assert_eq!(
            vertex_start(usize::MAX, u32::MAX),
            Some(u32::MAX as usize * 8)
        );
    }

    #[test]
    fn vertex_stages_place_and_morph() {
        let push = DrawPush::new(
            Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0)),
            Vec4::new(0.5, 0.5, 0.5, 1.0),
        );
        let (mut pos, mut n, mut uv, mut colour) = (Vec4::ZERO, Vec3::ZERO, Vec2::ZERO, Vec4::ZERO);
        let normal = Vec3::new(0.0, 2.0, 0.0);
        let encoded = Vec4::new(1.0, 0.5, 0.0, 0.25);
        draw_vs(
            Vec3::new(1.0, 1.0, 1.0),
            normal,
            Vec2::new(0.5, 0.25),
            encoded,
            &push,
            &mut pos,
            &mut n,
            &mut uv,
            &mut colour,
        );
        assert_eq!(pos, Vec4::new(2.0, 3.0, 4.0, 1.0));
        assert_eq!((n, uv), (normal, Vec2::new(0.5, 0.25)));
        assert_eq!(colour, vertex_colour(encoded));

        let inst = MorphInstance {
            offset_scale: [10.0, 0.0, 0.0, 2.0],
            t: 0.5,
            _pad: [0.0; 3],
        };
        geomorph_vs(
            Vec3::ZERO,
            Vec3::X,
            Vec2::ZERO,
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::Y,
            Vec2::ONE,
            Vec4::from_array(inst.offset_scale),
            inst.t,
            &push,
            &mut pos,
            &mut n,
            &mut uv,
            &mut colour,
        );
        assert_eq!(colour, Vec4::ONE);
        // morphed position (1, 0, 0) * 2 + (10, 0, 0), then translated by (1, 2, 3).
        assert_eq!(pos, Vec4::new(13.0, 2.0, 3.0, 1.0));
        let h = core::f32::consts::FRAC_1_SQRT_2;
        assert!((n - Vec3::new(h, h, 0.0)).length() < 1e-6);
        assert_eq!(uv, Vec2::splat(0.5));

        // `draw_fs` samples a texture, which only the GPU can; its arithmetic is
        // `fragment`, tested in caveclod-core.
        let base = base_colour(Vec4::ONE, colour, &push);
        assert!(!cut(base, &push));
        assert_eq!(
            fragment(n, true, uv, base, &push),
            caveclod_core::gpu::shade(
                n,
                true,
                uv,
                Vec4::new(0.5, 0.5, 0.5, 1.0),
                caveclod_core::gpu::PALETTE_CHECKER
            )
        );
    }
}
