//! The page reader: the right bytes from files and memory, many reads at once, the simulated
//! disk's clock, failures that leave the other reads alone, refusals, buffer reuse and a
//! clean drop with reads outstanding.

use std::io;
use std::sync::Arc;
use std::time::{Duration, Instant};

use caveclod_io::pages::{
    DiskModel, FileSource, PageReader, PageSource, ReadDone, ReadRequest, ReaderConfig, SubmitError,
};

const MS: Duration = Duration::from_millis(1);

/// Bytes that differ from offset to offset and from file to file.
fn pattern(len: usize, seed: u32) -> Vec<u8> {
    (0..len as u32)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 13).wrapping_add(seed) as u8)
        .collect()
}

fn memory(bytes: Vec<u8>) -> Arc<dyn PageSource> {
    Arc::new(bytes)
}

fn config(threads: usize, max_in_flight: usize, max_read_len: u32) -> ReaderConfig {
    ReaderConfig {
        threads,
        max_in_flight,
        max_read_len,
        disk: None,
    }
}

fn req(file: u32, offset: u64, len: u32, tag: u64) -> ReadRequest {
    ReadRequest {
        file,
        offset,
        len,
        tag,
    }
}

/// A source whose reads each sleep `delay` (real time) before copying, or fail, or panic.
struct Slow {
    bytes: Vec<u8>,
    delay: Duration,
    /// Reads at this offset sleep `delay`; `None`: all of them do.
    only_at: Option<u64>,
}

impl PageSource for Slow {
    fn read_at(&self, offset: u64, buf: &mut [u8]) -> io::Result<()> {
        if self.only_at.is_none_or(|at| at == offset) {
            std::thread::sleep(self.delay);
        }
        self.bytes.read_at(offset, buf)
    }

    fn len(&self) -> u64 {
        self.bytes.len() as u64
    }
}

/// A source that fails every read at offset 0 with an OS-like error and panics at 1.
struct Broken;

impl PageSource for Broken {
    fn read_at(&self, offset: u64, buf: &mut [u8]) -> io::Result<()> {
        match offset {
            0 => Err(io::Error::new(io::ErrorKind::PermissionDenied, "no access")),
            1 => panic!("a broken source"),
            _ => {
                buf.fill(9);
                Ok(())
            }
        }
    }

    fn len(&self) -> u64 {
        1 << 20
    }
}

fn bytes(done: &ReadDone) -> &[u8] {
    match &done.result {
        Ok(b) => b,
        Err(e) => panic!("read {} failed: {e}", done.tag),
    }
}

#[test]
fn reads_return_the_bytes_of_a_file_and_of_memory() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("paged.clod");
    let on_disk = pattern(100_000, 1);
    std::fs::write(&path, &on_disk).unwrap();
    let in_memory = pattern(5000, 2);
    let files: Vec<Arc<dyn PageSource>> = vec![
        Arc::new(FileSource::open(&path).unwrap()),
        memory(in_memory.clone()),
    ];
    let mut reader = PageReader::new(files, config(2, 8, 65_536)).unwrap();
    let asks = [
        req(0, 0, 4096, 10),
        req(0, 99_000, 1000, 11),
        req(1, 4999, 1, 12),
        req(1, 64, 0, 13),
        req(0, 12_345, 65_536, 14),
    ];
    for r in asks {
        reader.submit(r, Duration::ZERO).unwrap();
    }
    assert_eq!(reader.in_flight(), asks.len());
    let mut done = Vec::new();
    reader.drain(&mut done);
    assert_eq!(reader.in_flight(), 0);
    assert_eq!(done.len(), asks.len());
    for d in &done {
        let r = asks.iter().find(|r| r.tag == d.tag).unwrap();
        assert_eq!(d.file, r.file);
        let src = if r.file == 0 { &on_disk } else { &in_memory };
        let at = r.offset as usize;
        assert_eq!(bytes(d), &src[at..at + r.len as usize], "tag {}", d.tag);
        assert_eq!(bytes(d).as_ptr() as usize % 64, 0);
    }
    let stats = reader.stats();
    assert_eq!(stats.reads, 5);
    assert_eq!(stats.bytes, 4096 + 1000 + 1 + 65_536);
    assert_eq!(stats.failures, 0);
}

#[test]
fn many_reads_at_once_on_many_threads() {
    let files: Vec<Vec<u8>> = (0..3)
        .map(|f| pattern(300_000 + f * 1000, f as u32))
        .collect();
    let sources = files.iter().cloned().map(memory).collect();
    let mut reader = PageReader::new(sources, config(4, 16, 8192)).unwrap();
    let ask = |tag: u64| {
        let file = (tag % 3) as u32;
        let len = 1 + (tag * 7919 % 8192) as u32;
        let offset = tag * 104_729 % (300_000 - u64::from(len));
        req(file, offset, len, tag)
    };
    let (mut next, mut seen, mut done) = (0u64, 0u64, Vec::new());
    while seen < 2000 {
        while next < 2000 && reader.submit(ask(next), Duration::ZERO).is_ok() {
            next += 1;
        }
        assert!(reader.in_flight() <= 16);
        reader.poll(Duration::ZERO, &mut done);
        for d in done.drain(..) {
            let r = ask(d.tag);
            let at = r.offset as usize;
            let want = &files[r.file as usize][at..at + r.len as usize];
            assert_eq!(bytes(&d), want, "tag {}", d.tag);
            seen += 1;
        }
        std::thread::yield_now();
    }
    let stats = reader.stats();
    assert_eq!((stats.reads, stats.failures), (2000, 0));
    assert!(stats.buffers_allocated <= 16, "{stats:?}");
}

#[test]
fn the_simulated_disk_delivers_on_its_own_clock_in_order_of_its_transfers() {
    // 200 KB at 200 MB/s after 8 ms: each read's latency is 8 ms, its transfer 1 ms.
    let disk = DiskModel::new(8 * MS, 200e6);
    // The first read takes 50 ms of real time and the second none, so the threads finish
    // them in the other order; the simulated device still hands the first back first.
    let source = Arc::new(Slow {
        bytes: pattern(1_000_000, 3),
        delay: 50 * MS,
        only_at: Some(0),
    });
    let config = ReaderConfig {
        disk: Some(disk),
        ..config(2, 4, 200_000)
    };
    let mut reader = PageReader::new(vec![source], config).unwrap();
    reader
        .submit(req(0, 0, 200_000, 1), Duration::ZERO)
        .unwrap();
    reader
        .submit(req(0, 200_000, 200_000, 2), Duration::ZERO)
        .unwrap();
    let mut done = Vec::new();
    reader.poll(8 * MS, &mut done);
    assert!(done.is_empty());
    reader.poll(9 * MS, &mut done);
    assert_eq!(done.iter().map(|d| d.tag).collect::<Vec<_>>(), [1]);
    // The second's latency overlapped the first's; its transfer waited for the first's: it
    // starts at 9 ms and finishes at 10 ms.
    reader.poll(10 * MS - Duration::from_nanos(1), &mut done);
    assert_eq!(done.len(), 1);
    reader.poll(10 * MS, &mut done);
    assert_eq!(done.iter().map(|d| d.tag).collect::<Vec<_>>(), [1, 2]);
    let stats = reader.stats();
    assert_eq!(stats.simulated_queue_delay, MS);
    assert_eq!(stats.simulated_max_queue_delay, MS);
    // An idle device: the empty read takes the latency alone (100 ms to 108 ms), the next
    // transfers after its own latency (108 ms to 109 ms).
    reader.submit(req(0, 0, 0, 3), 100 * MS).unwrap();
    reader.submit(req(0, 0, 200_000, 4), 100 * MS).unwrap();
    reader.poll(108 * MS - Duration::from_nanos(1), &mut done);
    assert_eq!(done.len(), 2);
    reader.poll(108 * MS, &mut done);
    assert_eq!(done.len(), 3);
    reader.poll(109 * MS - Duration::from_nanos(1), &mut done);
    assert_eq!(done.len(), 3);
    reader.poll(109 * MS, &mut done);
    assert_eq!(done.iter().map(|d| d.tag).collect::<Vec<_>>(), [1, 2, 3, 4]);
    assert_eq!(reader.in_flight(), 0);
}

#[test]
fn a_read_past_the_end_fails_clearly_and_the_others_succeed() {
    let src = pattern(10_000, 4);
    let sources = vec![memory(src.clone()), Arc::new(Broken) as Arc<dyn PageSource>];
    let mut reader = PageReader::new(sources, config(2, 8, 4096)).unwrap();
    let asks = [
        req(0, 0, 100, 1),
        req(0, 9_000, 1001, 2),
        req(0, u64::MAX, 1, 3),
        req(1, 0, 10, 4),
        req(1, 1, 10, 5),
        req(1, 2, 10, 6),
        req(0, 9_000, 1000, 7),
    ];
    for r in asks {
        reader.submit(r, Duration::ZERO).unwrap();
    }
    let mut done = Vec::new();
    reader.drain(&mut done);
    done.sort_by_key(|d| d.tag);
    assert_eq!(bytes(&done[0]), &src[..100]);
    let past = done[1].result.as_ref().unwrap_err();
    assert_eq!((past.file, past.offset, past.len), (0, 9_000, 1001));
    assert_eq!(past.source.kind(), io::ErrorKind::UnexpectedEof);
    let message = past.to_string();
    assert!(
        message.contains("file 0") && message.contains("offset 9000"),
        "{message}"
    );
    assert!(
        message.contains("past the end") && message.contains("10000"),
        "{message}"
    );
    assert!(done[2].result.is_err());
    let denied = done[3].result.as_ref().unwrap_err();
    assert_eq!(denied.source.kind(), io::ErrorKind::PermissionDenied);
    assert!(denied.to_string().contains("no access"), "{denied}");
    assert!(done[4]
        .result
        .as_ref()
        .unwrap_err()
        .to_string()
        .contains("panicked"));
    assert_eq!(bytes(&done[5]), &[9; 10]);
    assert_eq!(bytes(&done[6]), &src[9_000..]);
    let stats = reader.stats();
    assert_eq!((stats.reads, stats.failures), (3, 4));
}

#[test]
fn submissions_beyond_the_limits_are_refused_and_queue_nothing() {
    let source = Arc::new(Slow {
        bytes: pattern(1000, 5),
        delay: 20 * MS,
        only_at: None,
    });
    let mut reader = PageReader::new(vec![source], config(1, 2, 100)).unwrap();
    let now = Duration::ZERO;
    reader.submit(req(0, 0, 100, 1), now).unwrap();
    reader.submit(req(0, 100, 100, 2), now).unwrap();
    let full = reader.submit(req(0, 200, 100, 3), now).unwrap_err();
    assert_eq!(full, SubmitError::Full { max_in_flight: 2 });
    assert!(full.to_string().contains('2'), "{full}");
    assert_eq!(reader.in_flight(), 2);
    let mut held = Vec::new();
    reader.drain(&mut held);
    assert_eq!(held.len(), 2);
    // Both buffers are in the caller's hands: no room for a read until one is dropped.
    let no_buffer = reader.submit(req(0, 200, 100, 3), now).unwrap_err();
    assert_eq!(no_buffer, SubmitError::NoBuffer { buffers: 2 });
    assert_eq!(reader.in_flight(), 0);
    held.pop();
    reader.submit(req(0, 200, 100, 3), now).unwrap();
    assert_eq!(
        reader.submit(req(1, 0, 1, 4), now),
        Err(SubmitError::UnknownFile { file: 1, files: 1 })
    );
    assert_eq!(
        reader.submit(req(0, 0, 101, 5), now),
        Err(SubmitError::TooLong {
            len: 101,
            max_read_len: 100
        })
    );
    assert_eq!(reader.in_flight(), 1);
    let mut done = Vec::new();
    reader.drain(&mut done);
    assert_eq!(done.iter().map(|d| d.tag).collect::<Vec<_>>(), [3]);
    assert_eq!(reader.stats().refused, 4);
}

#[test]
fn buffers_are_reused_once_they_all_exist() {
    let src = pattern(1 << 20, 6);
    let mut reader = PageReader::new(vec![memory(src.clone())], config(2, 4, 4096)).unwrap();
    let mut done = Vec::new();
    for round in 0..250u64 {
        for k in 0..4 {
            let tag = round * 4 + k;
            reader
                .submit(req(0, tag * 1000, 4096, tag), Duration::ZERO)
                .unwrap();
        }
        reader.drain(&mut done);
        for d in done.drain(..) {
            let at = d.tag as usize * 1000;
            assert_eq!(bytes(&d), &src[at..at + 4096]);
        }
    }
    let stats = reader.stats();
    assert_eq!(stats.reads, 1000);
    assert_eq!(stats.buffers_allocated, 4);
    // A buffer may outlive the reader.
    reader.submit(req(0, 0, 8, 0), Duration::ZERO).unwrap();
    reader.drain(&mut done);
    drop(reader);
    assert_eq!(bytes(&done[0]), &src[..8]);
}

#[test]
fn dropping_the_reader_with_reads_outstanding_does_not_wait_for_them_all() {
    let source = Arc::new(Slow {
        bytes: pattern(1 << 16, 7),
        delay: 100 * MS,
        only_at: None,
    });
    let mut reader = PageReader::new(vec![source], config(2, 64, 1024)).unwrap();
    for tag in 0..64 {
        reader
            .submit(req(0, tag * 1024, 1024, tag), Duration::ZERO)
            .unwrap();
    }
    std::thread::sleep(10 * MS);
    let start = Instant::now();
    drop(reader);
    // The two reads under way finish; the 62 queued (3 s on two threads) are dropped.
    assert!(
        start.elapsed() < Duration::from_millis(1500),
        "{:?}",
        start.elapsed()
    );
}

#[test]
fn the_reader_moves_between_threads() {
    fn send<T: Send>(_: &T) {}
    let reader = PageReader::new(vec![memory(vec![1, 2, 3])], ReaderConfig::default()).unwrap();
    send(&reader);
    let mut reader = std::thread::spawn(move || reader).join().unwrap();
    reader.submit(req(0, 1, 2, 0), Duration::ZERO).unwrap();
    let mut done = Vec::new();
    reader.drain(&mut done);
    assert_eq!(bytes(&done[0]), &[2, 3]);
    assert!(format!("{reader:?}").contains("in_flight: 0"));
}

#[test]
fn with_a_disk_model_a_read_past_the_end_fails_at_once_and_drain_waits_for_the_rest() {
    let disk = DiskModel::new(5 * MS, f64::INFINITY);
    let config = ReaderConfig {
        disk: Some(disk),
        ..config(1, 4, 64)
    };
    let mut reader = PageReader::new(vec![memory(pattern(100, 8))], config).unwrap();
    reader.submit(req(0, 0, 64, 1), Duration::ZERO).unwrap();
    reader.submit(req(0, 64, 64, 2), MS).unwrap();
    reader.submit(req(0, 36, 64, 3), MS).unwrap();
    let mut done = Vec::new();
    reader.poll(MS, &mut done);
    assert_eq!(done.iter().map(|d| d.tag).collect::<Vec<_>>(), [2]);
    assert!(done[0].result.is_err());
    reader.drain(&mut done);
    assert_eq!(done.iter().map(|d| d.tag).collect::<Vec<_>>(), [2, 1, 3]);
    let stats = reader.stats();
    // The failed read took no device time, and with infinite bandwidth no transfer waits.
    assert_eq!(stats.simulated_queue_delay, Duration::ZERO);
    assert_eq!((stats.reads, stats.failures), (2, 1));
}
