//! The shader math against its plain definitions: shading, colours, the checker, and
//! morph chains.

use super::*;

#[test]
fn back_faces_are_lit_by_their_reversed_normal() {
    let l = Vec3::from_array(LIGHT_DIRECTION).normalize();
    let c = Vec4::new(0.8, 0.6, 0.4, 1.0);
    let front = shade(l, true, Vec2::ZERO, c, 0.0);
    let back = shade(-l, false, Vec2::ZERO, c, 0.0);
    assert!((front - back).abs().max_element() < 1e-6);
    assert!((front.truncate() - c.truncate()).abs().max_element() < 1e-6);
    // Facing away from the light, either side keeps the ambient floor.
    let away = shade(-l, true, Vec2::ZERO, c, 0.0);
    assert!(
        (away.truncate() - c.truncate() * AMBIENT)
            .abs()
            .max_element()
            < 1e-6
    );
    assert_eq!(away.w, 1.0);
}

#[test]
fn the_checker_weight_scales_the_pattern() {
    let c = Vec4::ONE;
    let n = Vec3::from_array(LIGHT_DIRECTION);
    let on = Vec2::new(0.01, 0.01);
    let off = Vec2::new(0.13, 0.01);
    assert_eq!(checker(on), 1.0);
    assert_eq!(checker(off), 0.0);
    let dark = shade(n, true, off, c, PALETTE_CHECKER);
    assert!((dark.x - (1.0 - PALETTE_CHECKER)).abs() < 1e-6);
    assert_eq!(shade(n, true, off, c, 0.0), shade(n, true, on, c, 0.0));
}

#[test]
fn fragment_multiplies_texel_and_factor_and_cuts_alpha() {
    let push = DrawPush::material(Mat4::IDENTITY, Vec4::new(1.0, 0.5, 0.5, 0.8), 0.5);
    let n = Vec3::from_array(LIGHT_DIRECTION);
    let texel = Vec4::new(0.5, 1.0, 0.2, 1.0);
    let base = base_colour(texel, Vec4::ONE, &push);
    assert_eq!(base, Vec4::new(0.5, 0.5, 0.1, 0.8));
    let tinted = base_colour(texel, Vec4::new(1.0, 0.5, 1.0, 0.5), &push);
    assert_eq!(tinted, Vec4::new(0.5, 0.25, 0.1, 0.4));
    assert!(!cut(base, &push));
    let want = shade(n, true, Vec2::ZERO, base, 0.0);
    assert_eq!(fragment(n, true, Vec2::ZERO, base, &push), want);
    // 0.5 * 0.8 = 0.4 is below the cutoff.
    let faint = base_colour(Vec4::new(1.0, 1.0, 1.0, 0.5), Vec4::ONE, &push);
    assert!(cut(faint, &push));
    // Palette blocks never discard.
    let palette = DrawPush::new(Mat4::IDENTITY, Vec4::ONE);
    assert!(!cut(base_colour(Vec4::ZERO, Vec4::ONE, &palette), &palette));
}

fn v(x: f32) -> Vertex {
    Vertex {
        position: [x, 2.0 * x, 0.0],
        normal: [0.0, 0.0, 1.0],
        uv: [x, 0.0],
    }
}

fn slot(from: u32, to: u32, t: f32, coarse: u32) -> MorphVertex {
    MorphVertex {
        from,
        to,
        t,
        coarse,
    }
}

#[test]
fn a_morph_slot_blends_its_two_persistent_vertices() {
    let vertices = [v(0.0), v(1.0), v(4.0)];
    let slots = [slot(0, 2, 0.25, 0), MorphVertex::IDLE, slot(0, 3, 0.5, 0)];
    let inputs = MorphSlices {
        vertices: &vertices,
        slots: &slots,
    };
    assert_eq!(
        morph_slot_vertex(&inputs, 0),
        Some(morph_vertex(v(0.0), v(4.0), 0.25))
    );
    assert_eq!(morph_slot_vertex(&inputs, 1), None);
    assert_eq!(morph_slot_vertex(&inputs, 2), None, "a vertex past the end");
    assert_eq!(morph_slot_vertex(&inputs, 3), None, "a slot past the end");
}

/// A slot whose `from` names another slot starts from that slot's blend: the vertex
/// stands where its parent is drawn at `t = 0`, and blends on from there.
#[test]
fn a_chained_slot_starts_from_the_slot_it_names() {
    let vertices = [v(0.0), v(1.0), v(4.0), v(9.0)];
    let n = vertices.len() as u32;
    // Slot 0: vertex 1 morphing from 0; slot 1: vertex 2 from slot 0 (coarse 1);
    // slot 2: vertex 3 from slot 1 (coarse 2).
    let slots = [
        slot(0, 1, 0.5, 0),
        slot(n, 2, 0.25, 1),
        slot(n + 1, 3, 0.0, 2),
    ];
    let inputs = MorphSlices {
        vertices: &vertices,
        slots: &slots,
    };
    let parent = morph_vertex(v(0.0), v(1.0), 0.5);
    let child = morph_vertex(parent, v(4.0), 0.25);
    assert_eq!(morph_chain(&inputs, 2), Some((3, 0)));
    assert_eq!(morph_slot_vertex(&inputs, 0), Some(parent));
    assert_eq!(morph_slot_vertex(&inputs, 1), Some(child));
    assert_eq!(
        morph_slot_vertex(&inputs, 2),
        Some(child),
        "t = 0: where it starts"
    );
    // Colours blend along the chain in linear light.
    let colour = |i: u32| Vec4::splat(i as f32 / 4.0);
    let c0 = morph_colour(colour(0), colour(1), 0.5);
    assert_eq!(morph_slot_colour(&inputs, 0, colour), c0);
    let c1 = c0 + (vertex_colour(colour(2)) - c0) * 0.25;
    assert_eq!(morph_slot_colour(&inputs, 1, colour), c1);
    // A `from` naming an idle slot starts from the slot's coarse vertex.
    let broken = [MorphVertex::IDLE, slot(n, 2, 0.25, 1)];
    let inputs = MorphSlices {
        vertices: &vertices,
        slots: &broken,
    };
    assert_eq!(
        morph_slot_vertex(&inputs, 1),
        Some(morph_vertex(v(1.0), v(4.0), 0.25))
    );
}

/// A cycle of slots (which refinement never makes) ends at the chain limit.
#[test]
fn a_chain_ends_at_its_limit() {
    let vertices = [v(0.0), v(1.0)];
    let n = vertices.len() as u32;
    let slots = [slot(n + 1, 1, 0.5, 0), slot(n, 1, 0.5, 0)];
    let inputs = MorphSlices {
        vertices: &vertices,
        slots: &slots,
    };
    assert_eq!(morph_chain(&inputs, 0), Some((MAX_MORPH_CHAIN, 0)));
    assert!(morph_slot_vertex(&inputs, 0).is_some());
}

#[test]
fn morph_colours_blend_in_linear_light() {
    let red = unpack_colour(0xff00_00ff);
    assert_eq!(red, Vec4::new(1.0, 0.0, 0.0, 1.0));
    let grey = unpack_colour(0x8080_8080);
    assert_eq!(morph_colour(red, grey, 0.0), vertex_colour(red));
    let end = morph_colour(red, grey, 1.0) - vertex_colour(grey);
    assert!(end.abs().max_element() < 1e-6, "{end}");
    let half = morph_colour(red, grey, 0.5);
    let want = (vertex_colour(red) + vertex_colour(grey)) * 0.5;
    assert!((half - want).abs().max_element() < 1e-6);
}

#[test]
fn vertex_colours_decode_as_the_file_format_does() {
    for v in [0u8, 1, 10, 11, 64, 128, 200, 254, 255] {
        let c = [v, 255 - v, v / 2, v];
        let encoded = Vec4::new(
            f32::from(c[0]) / 255.0,
            f32::from(c[1]) / 255.0,
            f32::from(c[2]) / 255.0,
            f32::from(c[3]) / 255.0,
        );
        let want = Vec4::from_array(crate::format::materials::vertex_colour_linear(c));
        assert!(
            (vertex_colour(encoded) - want).abs().max_element() < 1e-6,
            "{c:?}"
        );
    }
}
