//! Once its buffers exist, the page reader reads without allocating: counted by a global
//! allocator, in a test binary of its own so that no other test allocates meanwhile.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Duration;

use caveclod_io::pages::{DiskModel, PageReader, PageSource, ReadRequest, ReaderConfig};

/// The system allocator, counting allocations on every thread.
struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: every call is passed to the system allocator unchanged; the count is a side effect.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: the caller's guarantees for `layout` are the system allocator's.
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: as for `alloc`.
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: `ptr` was allocated by this allocator, so by the system one, with `layout`.
        unsafe { System.realloc(ptr, layout, new_size) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: as for `realloc`.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Reads `rounds` times 8 pages, polling as a frame loop does, and checks the bytes.
fn read_rounds(
    reader: &mut PageReader,
    src: &[u8],
    rounds: u64,
    done: &mut Vec<caveclod_io::ReadDone>,
) {
    let mut now = Duration::ZERO;
    for round in 0..rounds {
        for k in 0..8u64 {
            let tag = round * 8 + k;
            let req = ReadRequest {
                file: 0,
                offset: tag % 500 * 1000,
                len: 4096,
                tag,
            };
            reader.submit(req, now).expect("room for the round's reads");
        }
        while reader.in_flight() > 0 {
            now += Duration::from_micros(500);
            reader.poll(now, done);
            for d in done.drain(..) {
                let at = (d.tag % 500 * 1000) as usize;
                let bytes = d.result.as_ref().expect("read");
                assert!(bytes[..] == src[at..at + 4096], "tag {}", d.tag);
            }
        }
    }
}

#[test]
fn steady_state_reading_allocates_nothing() {
    let src: Vec<u8> = (0..600_000u32).map(|i| (i % 251) as u8).collect();
    for disk in [None, Some(DiskModel::new(Duration::from_millis(1), 100e6))] {
        let source: Arc<dyn PageSource> = Arc::new(src.clone());
        let config = ReaderConfig {
            threads: 3,
            max_in_flight: 8,
            max_read_len: 4096,
            disk,
        };
        let mut reader = PageReader::new(vec![source], config).unwrap();
        let mut done = Vec::with_capacity(8);
        read_rounds(&mut reader, &src, 4, &mut done);
        let before = ALLOCATIONS.load(Ordering::Relaxed);
        read_rounds(&mut reader, &src, 200, &mut done);
        let after = ALLOCATIONS.load(Ordering::Relaxed);
        assert_eq!(after - before, 0, "allocations while reading ({disk:?})");
        let stats = reader.stats();
        assert_eq!((stats.reads, stats.buffers_allocated), (204 * 8, 8));
    }
}
