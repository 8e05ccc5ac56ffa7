//! Writing a file section by section through a `FilePlan` and a `SectionWriter` gives the
//! bytes `write_into` gives, whatever pieces the sections arrive in; the plan's table is the
//! file's; bytes that do not match the plan are refused.

mod common;

use caveclod_core::format::{
    tags, write_into, ExtraSection, FileHeader, FilePlan, SectionEntry, SectionSpec, SectionWriter,
    Sink, StreamError, Tag, WriteError, MAX_SECTIONS,
};
use caveclod_core::Hierarchy;
use common::{golden, header, AlignedBytes};

struct VecSink(Vec<u8>);

impl Sink for VecSink {
    type Error = ();
    fn put(&mut self, bytes: &[u8]) -> Result<(), ()> {
        self.0.extend_from_slice(bytes);
        Ok(())
    }
}

/// The golden hierarchy written by `write_into` with two extra sections, one empty and one of
/// 3-byte records whose length is not a multiple of the alignment.
fn reference() -> Vec<u8> {
    let file = golden();
    let h = Hierarchy::from_bytes(file.bytes()).expect("golden");
    let odd: Vec<u8> = (0..21).collect();
    let extra = [
        ExtraSection {
            tag: Tag(*b"EMPT"),
            record_size: 4,
            bytes: &[],
        },
        ExtraSection {
            tag: Tag(*b"ODD3"),
            record_size: 3,
            bytes: &odd,
        },
    ];
    let mut out = vec![0u8; caveclod_core::format::serialized_len(h.parts(), &extra)];
    let n = write_into(h.parts(), &extra, &mut out).expect("write_into");
    assert_eq!(n, out.len());
    out
}

/// The section table of `bytes`, and each section's bytes.
fn table(bytes: &[u8]) -> Vec<(SectionEntry, &[u8])> {
    let count = header(bytes).section_count as usize;
    (0..count)
        .map(|i| {
            let at = size_of::<FileHeader>() + i * size_of::<SectionEntry>();
            let e: SectionEntry =
                bytemuck::pod_read_unaligned(&bytes[at..at + size_of::<SectionEntry>()]);
            let len = (e.record_count * u64::from(e.record_size)) as usize;
            (e, &bytes[e.offset as usize..e.offset as usize + len])
        })
        .collect()
}

fn specs(t: &[(SectionEntry, &[u8])]) -> Vec<SectionSpec> {
    t.iter()
        .map(|(e, b)| SectionSpec {
            tag: e.tag,
            record_size: e.record_size,
            byte_len: b.len() as u64,
        })
        .collect()
}

#[test]
fn sections_in_any_pieces_give_the_write_into_bytes() {
    let want = reference();
    let t = table(&want);
    let specs = specs(&t);
    let plan = FilePlan::new(specs.as_slice()).expect("plan");
    assert_eq!(plan.file_len(), want.len() as u64);
    let entries: Vec<SectionEntry> = plan.entries().collect();
    assert_eq!(entries, t.iter().map(|(e, _)| *e).collect::<Vec<_>>());
    assert_eq!(plan.data_start(), entries[0].offset);
    let steps: &[usize] = if cfg!(miri) {
        &[7]
    } else {
        &[1, 7, 64, 1000, usize::MAX]
    };
    for &step in steps {
        let mut w = SectionWriter::new(plan, VecSink(Vec::new())).expect("table");
        for (e, bytes) in &t {
            if !bytes.is_empty() {
                assert_eq!(
                    w.current().map(|(s, left)| (s.tag, left)),
                    Some((e.tag, bytes.len() as u64))
                );
            }
            for piece in bytes.chunks(step.min(bytes.len().max(1))) {
                w.put(piece).expect("put");
            }
        }
        assert_eq!(w.current(), None);
        let (head, VecSink(mut out)) = w.finish().expect("finish");
        out[..size_of::<FileHeader>()].copy_from_slice(bytemuck::bytes_of(&head));
        assert!(out == want, "pieces of {step}: bytes differ");
    }
    Hierarchy::from_bytes(AlignedBytes::from_slice(&want).bytes())
        .expect("the written file reads back");
}

#[test]
fn bytes_off_the_plan_are_refused() {
    let specs = [
        SectionSpec {
            tag: Tag(*b"AAAA"),
            record_size: 2,
            byte_len: 4,
        },
        SectionSpec {
            tag: Tag(*b"BBBB"),
            record_size: 1,
            byte_len: 3,
        },
    ];
    let plan = FilePlan::new(specs.as_slice()).expect("plan");
    // Header, two entries, padding to 128; 4 bytes padded to 64; 3 bytes padded to 64.
    assert_eq!(plan.file_len(), 128 + 64 + 64);

    let mut w = SectionWriter::new(plan, VecSink(Vec::new())).expect("table");
    let before = plan.data_start() as usize;
    let too_long = w.put(&[1; 5]);
    assert_eq!(
        too_long,
        Err(StreamError::Plan(WriteError::NotAsPlanned {
            tag: Some(Tag(*b"AAAA")),
            planned: 4,
            given: 5
        }))
    );
    w.put(&[1; 3]).expect("within the section");
    let short = w.finish();
    assert!(matches!(
        short,
        Err(StreamError::Plan(WriteError::NotAsPlanned { tag: Some(t), planned: 4, given: 3 })) if t == Tag(*b"AAAA")
    ));

    let mut w = SectionWriter::new(plan, VecSink(Vec::new())).expect("table");
    w.put(&[1; 4]).expect("first");
    w.put(&[2; 3]).expect("second");
    assert_eq!(
        w.put(&[3]),
        Err(StreamError::Plan(WriteError::NotAsPlanned {
            tag: None,
            planned: 0,
            given: 1
        }))
    );
    let (head, VecSink(out)) = w.finish().expect("complete");
    assert_eq!(out.len() as u64, plan.file_len());
    assert_eq!(head.file_len, plan.file_len());
    assert_eq!(head.section_count, 2);
    assert_eq!(&out[before..before + 4], &[1; 4]);
    assert_eq!(&out[before + 64..before + 67], &[2; 3]);
    assert!(out[before + 4..before + 64].iter().all(|&b| b == 0));
    assert_eq!(
        head.checksum,
        caveclod_core::format::checksum64(&out[size_of::<FileHeader>()..])
    );
}

#[test]
fn unplannable_sections_are_refused() {
    let spec = |record_size, byte_len| SectionSpec {
        tag: tags::NODES,
        record_size,
        byte_len,
    };
    for bad in [spec(0, 0), spec(8, 12)] {
        assert_eq!(
            FilePlan::new([bad].as_slice()).map(|p| p.file_len()),
            Err(WriteError::BadExtraSection { tag: tags::NODES })
        );
    }
    assert_eq!(
        FilePlan::new([spec(1, u64::MAX - 10)].as_slice()).map(|p| p.file_len()),
        Err(WriteError::TooLarge)
    );
    let many = vec![spec(1, 0); MAX_SECTIONS as usize + 1];
    assert_eq!(
        FilePlan::new(many.as_slice()).map(|p| p.file_len()),
        Err(WriteError::TooManySections {
            count: MAX_SECTIONS as usize + 1
        })
    );
}
