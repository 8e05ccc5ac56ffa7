//! `Hierarchy::from_bytes` on damaged files: every truncation, thousands of seeded byte
//! flips (with and without the checksum rewritten, so the validator itself is reached), and
//! targeted corruptions that must be refused with the right typed error. A damaged file must
//! give `Err`, or `Ok` with a hierarchy the runtime can use without panicking.
//!
//! Under miri only a sample runs (the full sweep would take hours there).

mod common;

use std::collections::BTreeMap;

use caveclod_core::format::{tags, FileHeader, Node, Pieces, Position, SectionEntry, Split, Tag};
use caveclod_core::{FormatError, Hierarchy, PolyKey};
use common::{exercise, fix_checksum, golden, header, set_header, AlignedBytes, Rng};

const HEADER_LEN: usize = size_of::<FileHeader>();

/// Truncations tried: all of them, or an even sample under miri.
fn truncation_lengths(len: usize) -> Vec<usize> {
    if cfg!(miri) {
        let step = len.div_ceil(50).max(1);
        (0..len).step_by(step).collect()
    } else {
        (0..len).collect()
    }
}

fn flip_count() -> usize {
    if cfg!(miri) {
        50
    } else {
        10_000
    }
}

/// Views each `Ok` exercise refines from.
fn exercise_views() -> usize {
    if cfg!(miri) {
        2
    } else {
        4
    }
}

/// A short name for an error's variant, for the tallies printed with `--nocapture`.
fn kind(e: &FormatError) -> &'static str {
    match e {
        FormatError::Truncated { .. } => "Truncated",
        FormatError::BadMagic => "BadMagic",
        FormatError::UnsupportedVersion { .. } => "UnsupportedVersion",
        FormatError::BadHeader { .. } => "BadHeader",
        FormatError::LengthMismatch { .. } => "LengthMismatch",
        FormatError::TrailingBytes { .. } => "TrailingBytes",
        FormatError::ChecksumMismatch { .. } => "ChecksumMismatch",
        FormatError::Misaligned { .. } => "Misaligned",
        FormatError::SectionTable { .. } => "SectionTable",
        FormatError::MissingSection { .. } => "MissingSection",
        FormatError::DuplicateSection { .. } => "DuplicateSection",
        FormatError::RecordSize { .. } => "RecordSize",
        FormatError::Count { .. } => "Count",
        FormatError::Invalid { .. } => "Invalid",
        FormatError::BlobRange { .. } => "BlobRange",
        FormatError::NotUtf8 { .. } => "NotUtf8",
        FormatError::BadPath { .. } => "BadPath",
        FormatError::Paged => "Paged",
    }
}

#[test]
fn the_golden_file_loads_and_runs() {
    let file = golden();
    let h = Hierarchy::from_bytes(file.bytes()).expect("the golden file is valid");
    assert!(!h.splits().is_empty(), "the golden hierarchy has splits");
    assert!(
        h.surface_count() >= 2,
        "the golden terrain has two surfaces"
    );
    assert_eq!(h.checksum(), header(file.bytes()).checksum);
    exercise(&h, exercise_views());
}

#[test]
fn every_truncation_is_refused() {
    let file = golden();
    let full = file.bytes();
    for len in truncation_lengths(full.len()) {
        let cut = AlignedBytes::from_slice(&full[..len]);
        let expected = if len < HEADER_LEN {
            FormatError::Truncated {
                needed: HEADER_LEN as u64,
                len: len as u64,
            }
        } else {
            FormatError::LengthMismatch {
                header: full.len() as u64,
                actual: len as u64,
            }
        };
        assert_eq!(
            Hierarchy::from_bytes(cut.bytes()).err(),
            Some(expected),
            "length {len}"
        );
    }
}

/// Truncations whose header is rewritten to agree (length and checksum): the section table
/// must catch every section that no longer fits.
#[test]
fn every_truncation_with_a_consistent_header_is_refused() {
    let file = golden();
    let full = file.bytes();
    for len in truncation_lengths(full.len()) {
        if len < HEADER_LEN {
            continue;
        }
        let mut cut = AlignedBytes::from_slice(&full[..len]);
        let mut h = header(cut.bytes());
        h.file_len = len as u64;
        set_header(cut.bytes_mut(), &h);
        fix_checksum(cut.bytes_mut());
        match Hierarchy::from_bytes(cut.bytes()) {
            Err(
                FormatError::Truncated { .. }
                | FormatError::SectionTable { .. }
                | FormatError::MissingSection { .. },
            ) => {}
            // Only trailing zero padding after the last section can go without harm.
            Ok(h) => {
                assert!(
                    full[len..].iter().all(|&b| b == 0),
                    "length {len}: a file missing data loaded"
                );
                exercise(&h, 1);
            }
            Err(e) => panic!("length {len}: unexpected error {e:?}"),
        }
    }
}

#[test]
fn seeded_byte_flips_never_panic() {
    let file = golden();
    let len = file.bytes().len();
    let mut rng = Rng::new(0x5eed_c1a0_d000_0001);
    let mut tally: BTreeMap<String, usize> = BTreeMap::new();
    for round in 0..flip_count() {
        let mut damaged = file.clone();
        let bytes = damaged.bytes_mut();
        // Rounds 0, 1 of every 5: no checksum fix (the checksum must catch body damage);
        // rounds 2, 3, 4: checksum rewritten, so the damage reaches the validator.
        let fix = round % 5 >= 2;
        let flips = if round % 2 == 0 { 1 } else { 2 + rng.below(7) };
        let mut body_touched = false;
        let mut header_touched = false;
        for _ in 0..flips {
            let at = rng.below(len);
            let xor = 1 + rng.below(255) as u8;
            bytes[at] ^= xor;
            if at >= HEADER_LEN {
                body_touched = true;
            } else {
                header_touched = true;
            }
        }
        if fix && len >= HEADER_LEN {
            fix_checksum(bytes);
        }
        let result = Hierarchy::from_bytes(damaged.bytes());
        let label = match &result {
            Ok(_) => "Ok".to_string(),
            Err(e) => kind(e).to_string(),
        };
        let key = format!("{}{label}", if fix { "fixed:" } else { "raw:" });
        *tally.entry(key).or_default() += 1;
        if !fix && body_touched && !header_touched {
            assert!(
                matches!(result, Err(FormatError::ChecksumMismatch { .. })),
                "round {round}: body damage without a checksum fix gave {result:?}"
            );
        }
        if let Ok(h) = result {
            exercise(&h, exercise_views());
        }
    }
    eprintln!("outcomes of {} flips: {tally:#?}", flip_count());
    // The sweep must reach the validator, not stop at the checksum every time.
    let reached_validator: usize = tally
        .iter()
        .filter(|(k, _)| k.starts_with("fixed:") && !k.ends_with("ChecksumMismatch"))
        .map(|(_, n)| n)
        .sum();
    assert!(reached_validator > 0, "{tally:?}");
}

/// Validation passes in pieces of `len` records, each piece's check run last to first (as
/// threads may finish in any order), the answers joined first to last.
struct Backwards {
    len: usize,
}

impl Pieces for Backwards {
    fn fold<T: Send>(
        &self,
        n: usize,
        map: &(dyn Fn(std::ops::Range<usize>) -> T + Sync),
        join: &dyn Fn(T, T) -> T,
    ) -> T {
        let starts: Vec<usize> = (0..n.max(1)).step_by(self.len).collect();
        let mut answers: Vec<T> = starts
            .iter()
            .rev()
            .map(|&s| map(s..(s + self.len).min(n)))
            .collect();
        answers.reverse();
        let mut answers = answers.into_iter();
        let first = answers.next().expect("at least one piece");
        answers.fold(first, join)
    }
}

/// A damaged file gets the same answer, the first error in record order, whatever the
/// pieces its validation passes run in.
#[test]
fn validation_in_pieces_gives_the_answer_of_one_piece() {
    let file = golden();
    let len = file.bytes().len();
    let mut rng = Rng::new(0x5eed_c1a0_d000_0002);
    let mut invalid = 0;
    for round in 0..flip_count() / 5 {
        let mut damaged = file.clone();
        let bytes = damaged.bytes_mut();
        for _ in 0..1 + round % 3 {
            let at = HEADER_LEN + rng.below(len - HEADER_LEN);
            bytes[at] ^= 1 + rng.below(255) as u8;
        }
        fix_checksum(bytes);
        let whole = Hierarchy::from_bytes(damaged.bytes());
        invalid += usize::from(matches!(whole, Err(FormatError::Invalid { .. })));
        for piece in [1, 3, 64] {
            let pieces = Backwards { len: piece };
            let parts = Hierarchy::from_bytes_in(damaged.bytes(), &pieces);
            assert_eq!(
                parts.as_ref().err(),
                whole.as_ref().err(),
                "round {round}, pieces of {piece}"
            );
            if let (Ok(a), Ok(b)) = (&parts, &whole) {
                assert_eq!(bytemuck::bytes_of(a.meta()), bytemuck::bytes_of(b.meta()));
            }
        }
    }
    assert!(invalid > 0, "the flips reached the record checks");
    let h = Hierarchy::from_parts_in(
        *Hierarchy::from_bytes(file.bytes()).expect("valid").parts(),
        &Backwards { len: 5 },
    )
    .expect("valid in pieces");
    assert!(!h.splits().is_empty());
}

// ---------------------------------------------------------------------------------------
// Targeted corruptions: each must be refused with its own typed error.

/// The section table of a valid file.
fn table(bytes: &[u8]) -> Vec<SectionEntry> {
    let count = header(bytes).section_count as usize;
    (0..count)
        .map(|i| {
            let at = HEADER_LEN + i * size_of::<SectionEntry>();
            bytemuck::pod_read_unaligned(&bytes[at..at + size_of::<SectionEntry>()])
        })
        .collect()
}

/// The byte range of section `tag`.
fn section_range(bytes: &[u8], tag: Tag) -> std::ops::Range<usize> {
    let e = table(bytes)
        .into_iter()
        .find(|e| e.tag == tag)
        .expect("section present");
    let start = e.offset as usize;
    start..start + e.record_size as usize * e.record_count as usize
}

/// Loads `bytes` and requires `FormatError::Invalid` naming `tag`, `record`, `field` and
/// `value`; returns the rule it names as broken.
fn refused_as(bytes: &[u8], tag: Tag, record: usize, field: &str, value: u64) -> &'static str {
    match Hierarchy::from_bytes(bytes) {
        Err(FormatError::Invalid {
            tag: t,
            record: r,
            field: f,
            problem,
            value: v,
        }) => {
            assert_eq!(
                (t, r, f, v),
                (tag, record as u64, field, value),
                "{problem}"
            );
            problem
        }
        other => panic!("expected Invalid {tag} record {record} {field}, got {other:?}"),
    }
}

#[test]
fn bad_magic_is_refused() {
    let mut f = golden();
    f.bytes_mut()[0] = b'X';
    assert_eq!(
        Hierarchy::from_bytes(f.bytes()).err(),
        Some(FormatError::BadMagic)
    );
}

#[test]
fn another_major_version_is_refused() {
    let mut f = golden();
    let mut h = header(f.bytes());
    h.version_major += 1;
    h.version_minor = 3;
    set_header(f.bytes_mut(), &h);
    assert_eq!(
        Hierarchy::from_bytes(f.bytes()).err(),
        Some(FormatError::UnsupportedVersion {
            major: h.version_major,
            minor: 3
        })
    );
}

#[test]
fn another_minor_version_is_accepted() {
    let mut f = golden();
    let mut h = header(f.bytes());
    h.version_minor += 1;
    set_header(f.bytes_mut(), &h);
    assert!(Hierarchy::from_bytes(f.bytes()).is_ok());
}

#[test]
fn a_wrong_length_is_refused() {
    let f = golden();
    let len = f.bytes().len() as u64;
    let mut longer = f.bytes().to_vec();
    longer.extend_from_slice(&[0; 16]);
    let longer = AlignedBytes::from_slice(&longer);
    let extended = Hierarchy::from_bytes(longer.bytes()).err();
    assert_eq!(
        extended,
        Some(FormatError::TrailingBytes {
            expected: len,
            len: len + 16
        })
    );
    let message = extended.map(|e| e.to_string()).unwrap_or_default();
    assert!(
        message.contains("16 more than its header records"),
        "{message}"
    );
    let mut lying = f.clone();
    let mut h = header(lying.bytes());
    h.file_len = len - 8;
    set_header(lying.bytes_mut(), &h);
    assert_eq!(
        Hierarchy::from_bytes(lying.bytes()).err(),
        Some(FormatError::TrailingBytes {
            expected: len - 8,
            len
        })
    );
    h.file_len = len + 8;
    set_header(lying.bytes_mut(), &h);
    assert_eq!(
        Hierarchy::from_bytes(lying.bytes()).err(),
        Some(FormatError::LengthMismatch {
            header: len + 8,
            actual: len
        })
    );
}

#[test]
fn a_wrong_checksum_is_refused() {
    let mut f = golden();
    let stored = header(f.bytes()).checksum;
    let last = f.bytes().len() - 1;
    f.bytes_mut()[last] ^= 0x40;
    match Hierarchy::from_bytes(f.bytes()) {
        Err(FormatError::ChecksumMismatch {
            stored: s,
            computed,
        }) => {
            assert_eq!(s, stored);
            assert_ne!(computed, stored);
        }
        other => panic!("expected ChecksumMismatch, got {other:?}"),
    }
}

#[test]
fn a_node_parent_out_of_range_is_refused() {
    let mut f = golden();
    let range = section_range(f.bytes(), tags::NODES);
    let nodes: &[Node] = bytemuck::cast_slice(&f.bytes()[range.clone()]);
    let i = nodes
        .iter()
        .position(|n| n.parent.is_some())
        .expect("a node with a parent");
    let bad = nodes.len() as u32 + 5;
    let at = range.start + i * size_of::<Node>();
    f.bytes_mut()[at..at + 4].copy_from_slice(&bad.to_le_bytes());
    // Without the checksum fixed, the checksum catches it first.
    assert!(matches!(
        Hierarchy::from_bytes(f.bytes()),
        Err(FormatError::ChecksumMismatch { .. })
    ));
    fix_checksum(f.bytes_mut());
    refused_as(f.bytes(), tags::NODES, i, "parent", u64::from(bad));
}

/// A split's neighbours are polygon keys, and each names a polygon: the key of a base
/// polygon, or of a split's `f_l` or `f_r`, and that polygon's key is the key again.
#[test]
fn split_neighbour_keys_name_polygons() {
    let f = golden();
    let h = Hierarchy::from_bytes(f.bytes()).expect("golden");
    let nb = h.base_polygon_count() as u32;
    let (mut base, mut created) = (0, 0);
    for s in h.splits() {
        for key in s.neighbours.into_iter().filter(|k| k.is_some()) {
            let poly = h.polygon_of(key).expect("a neighbour key names a polygon");
            assert_eq!(h.key_of(poly), Some(key));
            match key.creator(nb) {
                None => base += 1,
                Some((node, right)) => {
                    created += 1;
                    let own = h.split(node).expect("the creator has a split");
                    assert_eq!(Some(poly), if right { own.f_r } else { own.f_l }.get());
                }
            }
        }
    }
    assert!(
        base > 0 && created > 0,
        "{base} base and {created} created neighbours"
    );
    assert_eq!(h.polygon_of(PolyKey::NONE), None);
    assert_eq!(
        h.polygon_of(PolyKey(nb + 2 * h.splits().len() as u32)),
        None
    );
}

/// A split's neighbour key that names no polygon, or one of the split's own, is refused with
/// the split, the field and the key.
#[test]
fn bad_split_neighbour_keys_are_refused() {
    let f = golden();
    let h = Hierarchy::from_bytes(f.bytes()).expect("golden");
    let nb = h.base_polygon_count() as u32;
    let ns = h.splits().len() as u32;
    // A split without a right polygon (the golden terrain has borders).
    let without_fr = h
        .splits()
        .iter()
        .position(|s| s.f_r.is_none())
        .expect("a border split") as u32;
    let i = h
        .splits()
        .iter()
        .enumerate()
        .position(|(i, s)| i as u32 != without_fr && s.neighbours[1].is_some())
        .expect("a split");
    let cases = [
        (PolyKey(nb + 2 * ns), "polygon key out of range"),
        (PolyKey(u32::MAX - 1), "polygon key out of range"),
        (
            PolyKey::created(nb, caveclod_core::NodeId(i as u32), false),
            "one of the split's own polygons",
        ),
        (
            PolyKey::created(nb, caveclod_core::NodeId(without_fr), true),
            "names the f_r of a split that has none",
        ),
    ];
    let range = section_range(f.bytes(), tags::SPLITS);
    // `fl_clw` (index 1) is present in every split.
    let at = range.start + i * size_of::<Split>() + std::mem::offset_of!(Split, neighbours) + 4;
    for (bad, reason) in cases {
        let mut g = golden();
        g.bytes_mut()[at..at + 4].copy_from_slice(&bad.0.to_le_bytes());
        fix_checksum(g.bytes_mut());
        let problem = refused_as(g.bytes(), tags::SPLITS, i, "fl_clw", u64::from(bad.0));
        assert_eq!(problem, reason, "{bad:?}");
    }
}

#[test]
fn a_nan_position_is_refused() {
    let mut f = golden();
    let range = section_range(f.bytes(), tags::POSITIONS);
    let count = range.len() / size_of::<Position>();
    let i = count / 2;
    let at = range.start + i * size_of::<Position>() + 4; // the y coordinate
    f.bytes_mut()[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    fix_checksum(f.bytes_mut());
    refused_as(
        f.bytes(),
        tags::POSITIONS,
        i,
        "xyz",
        u64::from(f32::NAN.to_bits()),
    );
}

#[test]
fn a_misaligned_buffer_is_refused_not_copied() {
    let f = common::with_offset(common::GOLDEN, 1);
    let bytes = &f[1..];
    assert_eq!(bytes.as_ptr() as usize % 2, 1);
    assert!(matches!(
        Hierarchy::from_bytes(bytes),
        Err(FormatError::Misaligned { .. })
    ));
}

/// `Hierarchy::from_bytes` documents that a 4-byte aligned buffer is enough ("any
/// `Vec<u32>`-backed ... buffer is"). The section table holds `u64` fields; it used to be
/// cast in place, which needs 8-byte alignment, so a buffer 4 modulo 8 was refused with
/// `Misaligned { tag: "SECT" }` (found as a bug, fixed: the table is read unaligned).
#[test]
fn a_four_byte_aligned_buffer_is_accepted_as_documented() {
    let f = common::with_offset(common::GOLDEN, 4);
    let bytes = &f[4..];
    assert_eq!(bytes.as_ptr() as usize % 8, 4);
    let h = Hierarchy::from_bytes(bytes);
    assert!(h.is_ok(), "{:?}", h.err());
}

#[test]
fn a_section_past_the_end_is_refused() {
    let mut f = golden();
    let entries = table(f.bytes());
    let i = entries
        .iter()
        .position(|e| e.tag == tags::VERTICES)
        .expect("VERT section");
    let mut e = entries[i];
    e.record_count += 1_000;
    let at = HEADER_LEN + i * size_of::<SectionEntry>();
    f.bytes_mut()[at..at + size_of::<SectionEntry>()].copy_from_slice(bytemuck::bytes_of(&e));
    fix_checksum(f.bytes_mut());
    assert!(matches!(
        Hierarchy::from_bytes(f.bytes()),
        Err(FormatError::SectionTable { index, tag, .. }) if index == i as u32 && tag == tags::VERTICES
    ));
}
