//! The `.clod` container: unknown sections are skipped and readable by tag, reserved tags
//! are refused as extras, and the writer refuses invalid hierarchies.

use caveclod_core::format::{serialized_len, tags, write_into, ExtraSection, Tag, WriteError};
use caveclod_core::{FormatError, Hierarchy, NodeId};
use caveclod_tests::{bake, meshes, AlignedBytes};

#[test]
fn unknown_sections_are_skipped_and_found_by_tag() {
    let baked = bake(&meshes::terrain(6, 5, 1));
    let parts = baked.parts();
    let payload: Vec<u8> = (0u8..=250).collect();
    let extra = [ExtraSection {
        tag: Tag(*b"GMSH"),
        record_size: 1,
        bytes: &payload,
    }];
    let mut bytes = AlignedBytes::zeroed(serialized_len(&parts, &extra));
    let written = write_into(&parts, &extra, &mut bytes).expect("valid");
    assert_eq!(written, bytes.len());
    let h = Hierarchy::from_bytes(&bytes).expect("an unknown section does not stop the reader");
    assert_eq!(h.section(Tag(*b"GMSH")), Some(&payload[..]));
    assert_eq!(h.section(Tag(*b"NOPE")), None);
    assert_eq!(h.meta(), baked.hierarchy().meta());
}

#[test]
fn reserved_tags_and_ragged_extras_are_refused() {
    let baked = bake(&meshes::terrain(4, 4, 1));
    let parts = baked.parts();
    for extra in [
        ExtraSection {
            tag: tags::NODES,
            record_size: 1,
            bytes: &[0; 8],
        },
        ExtraSection {
            tag: Tag(*b"ODD_"),
            record_size: 3,
            bytes: &[0; 8],
        },
    ] {
        let mut out = AlignedBytes::zeroed(serialized_len(&parts, &[extra]));
        assert_eq!(
            write_into(&parts, &[extra], &mut out),
            Err(WriteError::BadExtraSection { tag: extra.tag })
        );
    }
}

#[test]
fn the_writer_refuses_invalid_parts_and_short_buffers() {
    let baked = bake(&meshes::terrain(4, 4, 1));
    let mut nodes = baked.nodes.clone();
    let last = nodes.len() - 1;
    nodes[last].parent = NodeId(last as u32 + 5);
    let mut parts = baked.parts();
    parts.nodes = &nodes;
    let mut out = AlignedBytes::zeroed(serialized_len(&parts, &[]));
    match write_into(&parts, &[], &mut out) {
        Err(WriteError::Invalid(FormatError::Invalid {
            tag, record, field, ..
        })) => {
            assert_eq!((tag, record, field), (tags::NODES, last as u64, "parent"));
        }
        other => panic!("expected a NODE parent error, got {other:?}"),
    }
    let parts = baked.parts();
    let needed = serialized_len(&parts, &[]);
    let mut short = AlignedBytes::zeroed(needed - 1);
    assert_eq!(
        write_into(&parts, &[], &mut short),
        Err(WriteError::BufferTooSmall {
            needed,
            given: needed - 1
        })
    );
}

#[test]
fn errors_name_section_record_and_field() {
    let baked = bake(&meshes::terrain(4, 4, 1));
    let mut bounds = baked.bounds.clone();
    bounds[0].uni_error = f32::NAN;
    let mut parts = baked.parts();
    parts.bounds = &bounds;
    let e = Hierarchy::from_parts(parts).expect_err("NaN error bound");
    assert_eq!(
        e.to_string(),
        format!(
            "section BNDS record 0 field `uni_error`: not a finite, non-negative number (value {})",
            f32::NAN.to_bits()
        )
    );
}
