//! Materials and vertex colours: written beside the golden hierarchy and read back, every
//! validation failure as a typed error from the writer and from the reader, and files
//! without the sections loading as before.

mod common;

use caveclod_core::format::materials::{
    material_tags, vertex_colour_section, AlphaMode, BlobRef, MaterialParts, MaterialRecord,
    TextureKind, TextureRef, DOUBLE_SIDED,
};
use caveclod_core::format::{
    serialized_len, write_into, ExtraSection, FileHeader, Meta, SectionEntry, Tag, WriteError,
};
use caveclod_core::{FormatError, Hierarchy};
use common::{fix_checksum, golden, header, AlignedBytes};

/// Records and blob built string by string, as a baker would.
#[derive(Default)]
struct Builder {
    records: Vec<MaterialRecord>,
    blob: Vec<u8>,
}

impl Builder {
    fn put(&mut self, bytes: &[u8]) -> BlobRef {
        let r = BlobRef::new(self.blob.len() as u32, bytes.len() as u32);
        self.blob.extend_from_slice(bytes);
        r
    }

    fn material(&mut self, name: &str, texture: Option<TextureRef<'_>>, alpha: AlphaMode) {
        let name = self.put(name.as_bytes());
        let (kind, texture, mime) = match texture {
            None => (TextureKind::None, BlobRef::EMPTY, BlobRef::EMPTY),
            Some(TextureRef::Path(p)) => {
                (TextureKind::Path, self.put(p.as_bytes()), BlobRef::EMPTY)
            }
            Some(TextureRef::Embedded { mime, bytes }) => {
                let b = self.put(bytes);
                (TextureKind::Embedded, b, self.put(mime.as_bytes()))
            }
        };
        self.records.push(MaterialRecord {
            name,
            base_colour: [0.5, 0.25, 1.0, 0.75],
            texture_kind: kind as u32,
            texture,
            mime,
            alpha_mode: alpha.code(),
            alpha_cutoff: alpha.cutoff(),
            flags: 0,
            reserved: [0; 2],
        });
    }

    fn parts(&self) -> MaterialParts<'_> {
        MaterialParts {
            records: &self.records,
            blob: &self.blob,
        }
    }
}

/// Surfaces of the hierarchy the tests write: the golden one's polygons, with surfaces that
/// no polygon uses added (a valid hierarchy), so that every kind of material has one.
const SURFACES: usize = 3;

/// The golden hierarchy with [`SURFACES`] surfaces and `extra` sections, or the writer's
/// error.
fn write(extra: &[ExtraSection<'_>]) -> Result<AlignedBytes, WriteError> {
    write_with(SURFACES, extra)
}

/// The golden hierarchy with `surfaces` surfaces and `extra` sections.
fn write_with(surfaces: usize, extra: &[ExtraSection<'_>]) -> Result<AlignedBytes, WriteError> {
    let g = golden();
    let h = Hierarchy::from_bytes(g.bytes()).expect("golden");
    assert!(h.surface_count() <= surfaces);
    let mut parts = *h.parts();
    parts.surface_count = surfaces as u32;
    let mut out = AlignedBytes::zeroed(serialized_len(&parts, extra));
    write_into(&parts, extra, out.bytes_mut())?;
    Ok(out)
}

fn surface_count() -> usize {
    SURFACES
}

fn vertex_count() -> usize {
    Hierarchy::from_bytes(golden().bytes())
        .expect("golden")
        .vertices()
        .len()
}

/// One material per surface: the first textured by path, the second (if any) embedded.
fn full_set() -> Builder {
    let mut b = Builder::default();
    for s in 0..surface_count() {
        match s % 3 {
            0 => b.material(
                "Stone wall",
                Some(TextureRef::Path("../textures/stone wall.png")),
                AlphaMode::Mask { cutoff: 0.5 },
            ),
            1 => b.material(
                "Glass",
                Some(TextureRef::Embedded {
                    mime: "image/png",
                    bytes: b"\x89PNG\r\n\x1a\n fake",
                }),
                AlphaMode::Blend,
            ),
            _ => b.material("", None, AlphaMode::Opaque),
        }
    }
    b.records[0].flags = DOUBLE_SIDED;
    b
}

fn colours() -> Vec<[u8; 4]> {
    (0..vertex_count())
        .map(|i| [i as u8, (i * 7) as u8, 255, 128])
        .collect()
}

/// The writer's validation error for these sections.
fn refused(extra: &[ExtraSection<'_>]) -> FormatError {
    match write(extra) {
        Err(WriteError::Invalid(e)) => e,
        Err(other) => panic!("expected a validation error, got {other:?}"),
        Ok(_) => panic!("the writer accepted invalid sections"),
    }
}

/// The validation error for one changed record of the full set.
fn refused_record(change: impl FnOnce(&mut Builder)) -> FormatError {
    let mut b = full_set();
    change(&mut b);
    refused(&b.parts().sections())
}

#[test]
fn materials_and_colours_round_trip() {
    let b = full_set();
    let c = colours();
    let [m, blob] = b.parts().sections();
    let file = write(&[m, blob, vertex_colour_section(&c)]).expect("valid sections");
    let h = Hierarchy::from_bytes(file.bytes()).expect("loads");
    let materials = h.materials().expect("materials");
    assert_eq!(materials.len(), h.surface_count());
    let first = materials.get(0).expect("surface 0");
    assert_eq!(first.name, "Stone wall");
    assert_eq!(first.base_colour, [0.5, 0.25, 1.0, 0.75]);
    assert_eq!(
        first.texture,
        Some(TextureRef::Path("../textures/stone wall.png"))
    );
    assert_eq!(first.alpha, AlphaMode::Mask { cutoff: 0.5 });
    assert!(first.double_sided);
    for (s, got) in materials.iter().enumerate().skip(1) {
        assert!(!got.double_sided);
        match s % 3 {
            1 => {
                assert_eq!(got.name, "Glass");
                assert_eq!(got.alpha, AlphaMode::Blend);
                assert_eq!(
                    got.texture,
                    Some(TextureRef::Embedded {
                        mime: "image/png",
                        bytes: b"\x89PNG\r\n\x1a\n fake",
                    })
                );
            }
            _ => assert_eq!(
                (got.name, got.texture, got.alpha),
                ("", None, AlphaMode::Opaque)
            ),
        }
    }
    assert_eq!(materials.get(h.surface_count()), None);
    assert_eq!(h.vertex_colours(), Some(&c[..]));
    // The hierarchy itself is the golden one.
    let g = golden();
    let old = Hierarchy::from_bytes(g.bytes()).unwrap();
    assert_eq!(h.polygons(), old.polygons());
    assert_eq!(h.vertices(), old.vertices());
}

#[cfg(feature = "alloc")]
#[test]
fn owned_hierarchies_keep_their_materials() {
    let b = full_set();
    let file = write(&b.parts().sections()).expect("valid sections");
    let buf = caveclod_core::HierarchyBuf::from_bytes(file.bytes()).expect("loads");
    let h = buf.hierarchy().expect("view");
    assert_eq!(
        h.materials().and_then(|m| m.get(0)).map(|m| m.name),
        Some("Stone wall")
    );
}

#[test]
fn files_without_the_sections_load_as_before() {
    let g = golden();
    let h = Hierarchy::from_bytes(g.bytes()).expect("an old-style file loads");
    assert!(h.materials().is_none());
    assert!(h.vertex_colours().is_none());
    // Rewriting it without appearance sections gives the same bytes.
    let again = write_with(h.surface_count(), &[]).expect("valid");
    assert_eq!(again.bytes(), g.bytes());
}

#[test]
fn blob_ranges_out_of_bounds_are_refused() {
    let len = full_set().blob.len() as u32;
    let e = refused_record(|b| b.records[0].name = BlobRef::new(len - 2, 3));
    assert_eq!(
        e,
        FormatError::BlobRange {
            tag: material_tags::MATERIALS,
            record: 0,
            field: "name",
            offset: len - 2,
            len: 3,
            blob_len: len as u64,
        }
    );
    let e = refused_record(|b| b.records[0].texture = BlobRef::new(u32::MAX, u32::MAX));
    assert!(
        matches!(
            e,
            FormatError::BlobRange {
                record: 0,
                field: "texture",
                ..
            }
        ),
        "{e}"
    );
    let e = refused_record(|b| b.records[1].mime = BlobRef::new(len, 1));
    assert!(
        matches!(
            e,
            FormatError::BlobRange {
                record: 1,
                field: "mime",
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn strings_that_are_not_utf8_are_refused() {
    let e = refused_record(|b| {
        b.records[0].name = b.put(&[0x66, 0xff, 0x66]);
    });
    assert_eq!(
        e,
        FormatError::NotUtf8 {
            tag: material_tags::MATERIALS,
            record: 0,
            field: "name"
        }
    );
    let e = refused_record(|b| b.records[0].texture = b.put(&[0xc3]));
    assert!(
        matches!(
            e,
            FormatError::NotUtf8 {
                field: "texture",
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn absolute_and_malformed_paths_are_refused() {
    for (path, problem) in [
        ("/home/me/t.png", "absolute path"),
        ("C:/t.png", "drive or URI scheme"),
        ("file:t.png", "drive or URI scheme"),
        ("tex\\t.png", "backslash"),
        ("", "empty path"),
    ] {
        let e = refused_record(|b| b.records[0].texture = b.put(path.as_bytes()));
        match e {
            FormatError::BadPath {
                tag,
                record: 0,
                problem: p,
            } if tag == material_tags::MATERIALS && p.starts_with(problem) => {}
            other => panic!("{path:?}: expected a bad-path error, got {other}"),
        }
    }
}

#[test]
fn counts_must_match_surfaces_and_vertices() {
    let mut b = full_set();
    b.material("one too many", None, AlphaMode::Opaque);
    assert_eq!(
        refused(&b.parts().sections()),
        FormatError::Count {
            tag: material_tags::MATERIALS,
            expected: surface_count() as u64,
            found: surface_count() as u64 + 1,
        }
    );
    let mut c = colours();
    c.pop();
    assert_eq!(
        refused(&[vertex_colour_section(&c)]),
        FormatError::Count {
            tag: material_tags::VERTEX_COLOURS,
            expected: vertex_count() as u64,
            found: vertex_count() as u64 - 1,
        }
    );
}

#[test]
fn materials_and_blob_come_together() {
    let b = full_set();
    let [m, blob] = b.parts().sections();
    assert_eq!(
        refused(&[m]),
        FormatError::MissingSection {
            tag: material_tags::BLOB
        }
    );
    assert_eq!(
        refused(&[blob]),
        FormatError::MissingSection {
            tag: material_tags::MATERIALS
        }
    );
    assert_eq!(
        refused(&[m, blob, blob]),
        FormatError::DuplicateSection {
            tag: material_tags::BLOB
        }
    );
    let short = ExtraSection {
        record_size: 32,
        ..m
    };
    assert!(matches!(
        refused(&[short, blob]),
        FormatError::RecordSize { .. }
    ));
}

#[test]
fn record_fields_are_checked() {
    let field =
        |change: fn(&mut MaterialRecord)| match refused_record(|b| change(&mut b.records[0])) {
            FormatError::Invalid {
                tag,
                record: 0,
                field,
                ..
            } if tag == material_tags::MATERIALS => field,
            other => panic!("expected an invalid-field error, got {other}"),
        };
    assert_eq!(field(|r| r.base_colour[2] = f32::NAN), "base_colour");
    assert_eq!(field(|r| r.texture_kind = 3), "texture_kind");
    assert_eq!(field(|r| r.mime = BlobRef::new(0, 1)), "mime");
    assert_eq!(field(|r| r.alpha_mode = 7), "alpha_mode");
    assert_eq!(field(|r| r.alpha_cutoff = -1.0), "alpha_cutoff");
    assert_eq!(field(|r| r.flags = 2), "flags");
    assert_eq!(field(|r| r.reserved[1] = 1), "reserved");
    assert_eq!(
        field(|r| {
            r.texture_kind = TextureKind::None as u32;
        }),
        "texture"
    );
    assert_eq!(
        field(|r| {
            r.alpha_mode = AlphaMode::Opaque.code();
        }),
        "alpha_cutoff"
    );
    assert_eq!(
        field(|r| {
            r.texture_kind = TextureKind::Embedded as u32;
        }),
        "mime"
    );
}

/// The section-table entry of `tag` in a written file.
fn entry(bytes: &[u8], tag: Tag) -> SectionEntry {
    let count = header(bytes).section_count as usize;
    (0..count)
        .map(|i| {
            let at = size_of::<FileHeader>() + i * size_of::<SectionEntry>();
            bytemuck::pod_read_unaligned::<SectionEntry>(&bytes[at..at + size_of::<SectionEntry>()])
        })
        .find(|e| e.tag == tag)
        .expect("section present")
}

/// The golden file with the full set of materials and colours, changed by `damage` (the
/// checksum fixed afterwards, so the validator is reached), as the reader sees it.
fn load_damaged(damage: impl FnOnce(&mut [u8])) -> FormatError {
    let b = full_set();
    let c = colours();
    let [m, blob] = b.parts().sections();
    let mut file = write(&[m, blob, vertex_colour_section(&c)]).expect("valid");
    damage(file.bytes_mut());
    fix_checksum(file.bytes_mut());
    Hierarchy::from_bytes(file.bytes()).expect_err("damaged")
}

#[test]
fn the_reader_refuses_damaged_sections() {
    // The first record's name length, past the blob's end.
    let e = load_damaged(|bytes| {
        let at = entry(bytes, material_tags::MATERIALS).offset as usize + 4;
        bytes[at..at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
    });
    assert!(
        matches!(
            e,
            FormatError::BlobRange {
                record: 0,
                field: "name",
                ..
            }
        ),
        "{e}"
    );
    // The first name's first byte, not UTF-8.
    let e = load_damaged(|bytes| {
        let at = entry(bytes, material_tags::BLOB).offset as usize;
        bytes[at] = 0xff;
    });
    assert!(
        matches!(
            e,
            FormatError::NotUtf8 {
                record: 0,
                field: "name",
                ..
            }
        ),
        "{e}"
    );
    // One more surface in META than there are materials (the hierarchy itself stays valid).
    let e = load_damaged(|bytes| {
        let at = entry(bytes, caveclod_core::format::tags::META).offset as usize;
        let mut meta: Meta = bytemuck::pod_read_unaligned(&bytes[at..at + size_of::<Meta>()]);
        meta.surface_count += 1;
        bytes[at..at + size_of::<Meta>()].copy_from_slice(bytemuck::bytes_of(&meta));
    });
    assert!(
        matches!(e, FormatError::Count { tag, .. } if tag == material_tags::MATERIALS),
        "{e}"
    );
    // A colour section one record short.
    let e = load_damaged(|bytes| {
        let count = header(bytes).section_count as usize;
        for i in 0..count {
            let at = size_of::<FileHeader>() + i * size_of::<SectionEntry>();
            let mut e: SectionEntry =
                bytemuck::pod_read_unaligned(&bytes[at..at + size_of::<SectionEntry>()]);
            if e.tag == material_tags::VERTEX_COLOURS {
                e.record_count -= 1;
                bytes[at..at + size_of::<SectionEntry>()].copy_from_slice(bytemuck::bytes_of(&e));
            }
        }
    });
    assert!(
        matches!(e, FormatError::Count { tag, .. } if tag == material_tags::VERTEX_COLOURS),
        "{e}"
    );
}

#[test]
fn damaged_appearance_sections_never_panic() {
    let b = full_set();
    let c = colours();
    let [m, blob] = b.parts().sections();
    let file = write(&[m, blob, vertex_colour_section(&c)]).expect("valid");
    // Every byte of the three sections, one flip each (a sample under miri), the checksum
    // fixed so the validator is reached.
    let mut ranges = Vec::new();
    for tag in [
        material_tags::MATERIALS,
        material_tags::BLOB,
        material_tags::VERTEX_COLOURS,
    ] {
        let e = entry(file.bytes(), tag);
        let start = e.offset as usize;
        ranges.push(start..start + (e.record_size as u64 * e.record_count) as usize);
    }
    let step = if cfg!(miri) { 37 } else { 1 };
    let (mut loaded, mut refused) = (0, 0);
    let mut rng = common::Rng::new(7);
    for at in ranges.into_iter().flatten().step_by(step) {
        let mut damaged = file.clone();
        damaged.bytes_mut()[at] ^= 1 << (rng.next_u64() % 8);
        fix_checksum(damaged.bytes_mut());
        match Hierarchy::from_bytes(damaged.bytes()) {
            Ok(h) => {
                loaded += 1;
                // What loads is readable in full.
                let m = h.materials().expect("still has materials");
                assert_eq!(m.iter().count(), h.surface_count(), "flip at {at}");
                assert_eq!(h.vertex_colours().map(<[_]>::len), Some(h.vertices().len()));
            }
            Err(_) => refused += 1,
        }
    }
    assert!(
        loaded > 0 && refused > 0,
        "{loaded} loaded, {refused} refused"
    );
}
