//! [`Streamer`]: a page pool's loads served by a [`PageReader`], one call a frame.

use std::sync::Arc;
use std::time::Duration;

use caveclod_core::format::paged::PagedRoot;
use caveclod_core::stream::{
    InstallError, LoadRequest, PageFault, PageKey, Residency, ScheduleStats,
};

use crate::pages::{PageReader, PageSource, ReadDone, ReadRequest, ReaderConfig};

/// What one [`Streamer::frame`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrameStreaming {
    /// The pool's choice of loads and evictions.
    pub schedule: ScheduleStats,
    /// Pages installed.
    pub installs: u32,
    /// Pages that failed (each reported once, in the caller's list).
    pub faults: u32,
    /// Bytes of the pages read.
    pub bytes_read: u64,
    /// Reads in flight after the frame.
    pub in_flight: u32,
}

/// Serves a [`Residency`]'s loads from files through a [`PageReader`]: each frame it
/// installs the pages that arrived (checked by their file's root), then schedules and
/// submits new loads, at most a cap a frame. Its buffers are made once, so a frame
/// allocates nothing but a failed page's message.
pub struct Streamer {
    reader: PageReader,
    loads: Vec<LoadRequest>,
    evicted: Vec<PageKey>,
    done: Vec<ReadDone>,
    max_in_flight: usize,
}

impl Streamer {
    /// A streamer over `files` (indexed as the pool's files are), at most
    /// `loads_per_frame` loads started a frame.
    pub fn new(
        files: Vec<Arc<dyn PageSource>>,
        config: ReaderConfig,
        loads_per_frame: usize,
    ) -> std::io::Result<Self> {
        let max_in_flight = config.max_in_flight.max(1);
        Ok(Self {
            reader: PageReader::new(files, config)?,
            loads: vec![LoadRequest::default(); loads_per_frame.min(max_in_flight)],
            evicted: vec![PageKey::default(); loads_per_frame.min(max_in_flight)],
            done: Vec::with_capacity(max_in_flight),
            max_in_flight,
        })
    }

    /// After the cameras have said what they want this frame: installs what arrived by
    /// `now` (on the reader's clock), then schedules and submits loads. `roots[f]` is file
    /// `f`'s root. Failed pages are appended to `faults`, each once.
    pub fn frame(
        &mut self,
        pool: &mut Residency<'_, '_>,
        roots: &[PagedRoot<'_>],
        now: Duration,
        faults: &mut Vec<PageFault>,
    ) -> FrameStreaming {
        let mut f = FrameStreaming::default();
        self.install_arrived(pool, roots, now, faults, &mut f);
        let room = self.max_in_flight - self.reader.in_flight();
        let room = room.min(self.loads.len());
        f.schedule = pool.schedule(&mut self.loads[..room], &mut self.evicted);
        for l in &self.loads[..f.schedule.loads as usize] {
            let read = ReadRequest {
                file: l.key.file,
                offset: l.offset,
                len: l.size,
                tag: u64::from(l.slot),
            };
            if self.reader.submit(read, now).is_err() {
                // The reader refused (its sources or limits changed under it): the page fails
                // like a read that failed.
                if let Ok(fault) = pool.fail(l.slot) {
                    faults.push(fault);
                    f.faults += 1;
                }
            }
        }
        f.in_flight = self.reader.in_flight() as u32;
        f
    }

    /// The pages the last frame evicted.
    pub fn evicted(&self, last: &FrameStreaming) -> &[PageKey] {
        &self.evicted[..last.schedule.evictions as usize]
    }

    /// The reader, for its statistics.
    pub fn reader(&self) -> &PageReader {
        &self.reader
    }

    fn install_arrived(
        &mut self,
        pool: &mut Residency<'_, '_>,
        roots: &[PagedRoot<'_>],
        now: Duration,
        faults: &mut Vec<PageFault>,
        f: &mut FrameStreaming,
    ) {
        self.done.clear();
        self.reader.poll(now, &mut self.done);
        for d in self.done.drain(..) {
            let slot = d.tag as u32;
            let arrived = match (&d.result, roots.get(d.file as usize)) {
                (Ok(bytes), Some(root)) => Some((bytes, root)),
                _ => None,
            };
            let installed = match arrived {
                Some((bytes, root)) => {
                    let filled = match pool.loading_slot_mut(slot) {
                        Ok(dst) if dst.len() == bytes.len() => {
                            dst.copy_from_slice(bytes);
                            true
                        }
                        _ => false,
                    };
                    if filled {
                        f.bytes_read += bytes.len() as u64;
                        pool.install(slot, root)
                    } else {
                        failed(pool, slot)
                    }
                }
                None => failed(pool, slot),
            };
            match installed {
                Ok(_) => f.installs += 1,
                Err(InstallError::Fault(fault)) => {
                    faults.push(fault);
                    f.faults += 1;
                }
                Err(InstallError::Misuse(_)) => {}
            }
        }
    }
}

/// Fails the page loading into `slot`: its fault, to report.
fn failed(pool: &mut Residency<'_, '_>, slot: u32) -> Result<PageKey, InstallError> {
    match pool.fail(slot) {
        Ok(fault) => Err(InstallError::Fault(fault)),
        Err(e) => Err(InstallError::Misuse(e)),
    }
}
