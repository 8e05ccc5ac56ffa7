use super::runs::chunk_bytes_per_triangle;
use super::*;
use crate::base::temp::TempSpace;
use crate::ooc::soup::RECORD_BYTES;
use crate::ooc::stream::SoupSink;

#[test]
fn runs_merge_sorted_from_anywhere_and_cells_are_counted() {
    let temp = TempSpace::new(None, None).unwrap();
    let mut progress = |_, _, _| {};
    // Chunks of 10 triangles: 100 triangles make 10 runs.
    let mut b = RunBuilder::<SoupTriangle>::new(
        &temp,
        20 * chunk_bytes_per_triangle::<SoupTriangle>(),
        &mut progress,
    );
    let cube = Cube::around([0.0; 3], [1.0; 3]);
    b.start(&cube, 100).unwrap();
    let mut keys = Vec::new();
    for i in 0..100u64 {
        // Repeated positions (so keys: i % 37), across runs and inside them.
        let j = (i % 37) as f32;
        let position = [(j * 0.618).fract(), (j * 0.37).fract(), j / 37.0];
        let corner = super::super::soup::Corner {
            position,
            // The input position, to check the order among equal keys.
            uv: [i as f32, 0.0],
            ..Default::default()
        };
        let key = cube.key(&[position; 3]);
        keys.push((key, i));
        b.push(&SoupTriangle {
            key,
            corners: [corner; 3],
            ..Default::default()
        })
        .unwrap();
    }
    let sorted = b.finish(1 << 16).unwrap();
    assert_eq!(sorted.runs.len(), 10);
    assert_eq!(sorted.triangles, 100);
    // By key, then by run (runs are consecutive inputs), then by position in the run.
    keys.sort_unstable();
    let bytes = std::fs::read(&sorted.keys).unwrap();
    let got: Vec<u64> = bytes
        .chunks(8)
        .map(bytemuck::pod_read_unaligned::<u64>)
        .collect();
    assert_eq!(got, keys.iter().map(|k| k.0).collect::<Vec<_>>());
    for first in [0, 1, 13, 50, 99, 100] {
        let mut m = sorted.merge_from(first, 1 << 12).unwrap();
        let mut got = Vec::new();
        m.take(100 - first, &mut |t| {
            got.push((t.key, t.corners[0].uv[0] as u64))
        })
        .unwrap();
        assert_eq!(got, keys[first as usize..], "from {first}");
        assert!(m.take(1, &mut |_| {}).is_err());
    }
    // Depth 0: one cell; at full depth, every distinct key.
    assert_eq!(sorted.occupied[0], 1);
    let at = |d: u32| {
        let mut p: Vec<u64> = keys
            .iter()
            .map(|&(k, _)| super::super::soup::key_prefix(k, d))
            .collect();
        p.dedup();
        p.len() as u64
    };
    assert_eq!(sorted.occupied[KEY_LEVELS as usize], at(KEY_LEVELS));
    for d in 0..=KEY_LEVELS {
        assert_eq!(sorted.occupied[d as usize], at(d), "depth {d}");
    }
    // Records and keys of every run, and the merged keys.
    assert_eq!(std::fs::read_dir(temp.path()).unwrap().count(), 21);
}

#[test]
fn a_builder_of_keys_sorts_and_counts_like_one_of_records() {
    let temp = TempSpace::new(None, None).unwrap();
    let cube = Cube::around([0.0; 3], [1.0; 3]);
    let triangles: Vec<SoupTriangle> = (0..100u64)
        .map(|i| {
            let j = (i % 37) as f32;
            let position = [(j * 0.618).fract(), (j * 0.37).fract(), j / 37.0];
            SoupTriangle {
                key: cube.key(&[position; 3]),
                ..Default::default()
            }
        })
        .collect();
    let mut p1 = |_, _, _| {};
    let mut records = RunBuilder::<SoupTriangle>::new(
        &temp,
        20 * chunk_bytes_per_triangle::<SoupTriangle>(),
        &mut p1,
    );
    let mut p2 = |_, _, _| {};
    let mut keys = RunBuilder::<u64>::new(&temp, 20 * chunk_bytes_per_triangle::<u64>(), &mut p2);
    records.start(&cube, 100).unwrap();
    keys.start(&cube, 100).unwrap();
    for (i, t) in triangles.iter().enumerate() {
        records.push(t).unwrap();
        // Half pushed, half filled in place as the readers do.
        if i % 2 == 0 {
            keys.push(t).unwrap();
        } else {
            *keys.slot().unwrap() = *t;
        }
    }
    let (a, b) = (
        records.finish(1 << 16).unwrap(),
        keys.finish(1 << 16).unwrap(),
    );
    assert_eq!(b.runs.len(), 10);
    assert_eq!(b.triangles, 100);
    assert_eq!(a.occupied, b.occupied);
    assert_eq!(
        std::fs::read(&a.keys).unwrap(),
        std::fs::read(&b.keys).unwrap()
    );
    assert!(b.runs.iter().all(|r| r.records.is_none()));
    let e = b.merge_from(0, 1 << 12).err().unwrap();
    assert!(e.to_string().contains("without their records"), "{e}");
}

#[test]
fn a_writer_error_comes_back_and_nothing_is_left_writing() {
    let parent = tempfile::tempdir().unwrap();
    let temp = TempSpace::new(Some(parent.path()), Some(50 * RECORD_BYTES as u64)).unwrap();
    let mut progress = |_, _, _| {};
    let mut b = RunBuilder::<SoupTriangle>::new(
        &temp,
        20 * chunk_bytes_per_triangle::<SoupTriangle>(),
        &mut progress,
    );
    b.start(&Cube::around([0.0; 3], [1.0; 3]), 0).unwrap();
    let mut result = Ok(());
    for _ in 0..200 {
        result = b.push(&SoupTriangle::default());
        if result.is_err() {
            break;
        }
    }
    let e = result.err().or_else(|| b.finish(1 << 16).err()).unwrap();
    assert!(e.to_string().contains("temporary space full"), "{e}");
    drop(temp);
    assert_eq!(std::fs::read_dir(parent.path()).unwrap().count(), 0);
}
