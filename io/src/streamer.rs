//! [`Streamer`]: a page pool's loads served by a [`PageReader`], one call a frame.

use std::sync::Arc;
use std::time::Duration;

use caveclod_core::format::paged::PagedRoot;
use caveclod_core::stream::{
    InstallError, LoadRequest, PageFault, PageKey, PageState, Residency, ScheduleStats,
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
/// installs the pages that arrived (checked by their file's root; at most
/// [`with_max_installs`](Self::with_max_installs) a frame, the rest wait), then schedules
/// and submits new loads, at most a cap a frame. Its buffers are made once, so a frame
/// allocates nothing but a failed page's message.
pub struct Streamer {
    reader: PageReader,
    loads: Vec<LoadRequest>,
    evicted: Vec<PageKey>,
    done: Vec<ReadDone>,
    /// Reads that arrived and wait for a parent page to install, or for the next frame.
    pending: Vec<ReadDone>,
    max_in_flight: usize,
    max_installs: usize,
    /// The pages the last frame installed.
    installed: Vec<PageKey>,
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
            pending: Vec::with_capacity(max_in_flight),
            max_in_flight,
            max_installs: usize::MAX,
            installed: Vec::with_capacity(max_in_flight),
        })
    }

    /// This streamer installing at most `max_installs` pages a frame (at least one): what a
    /// device vertex pool copies in a frame (`VertexPool`'s own cap in caveclod-vulkan).
    pub fn with_max_installs(self, max_installs: usize) -> Self {
        Self {
            max_installs: max_installs.max(1),
            ..self
        }
    }

    /// The pages the last [`frame`](Self::frame) installed and left resident, in install
    /// order: their vertices go to a device vertex pool before a frame's fronts may use them.
    pub fn installed(&self) -> &[PageKey] {
        &self.installed
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
        let held = self.reader.in_flight() + self.pending.len();
        let room = self.max_in_flight.saturating_sub(held);
        let room = room.min(self.loads.len());
        f.schedule = pool.schedule(&mut self.loads[..room], &mut self.evicted);
        // A page installed now and evicted by the same schedule (nothing wanted it since it
        // was asked for) has nothing to copy.
        self.installed
            .retain(|&k| pool.state(k) == Some(PageState::Resident));
        for l in &self.loads[..f.schedule.loads as usize] {
            let read = ReadRequest {
                file: l.key.file,
                offset: l.offset,
                len: l.size,
                // The page orders installs (parents first); the slot names the load.
                tag: (u64::from(l.key.page) << 32) | u64::from(l.slot),
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
        f.in_flight = (self.reader.in_flight() + self.pending.len()) as u32;
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

    /// Installs the reads that arrived by `now` and those that waited for a parent, in
    /// page order (parents first); a page whose parent is still loading waits again.
    fn install_arrived(
        &mut self,
        pool: &mut Residency<'_, '_>,
        roots: &[PagedRoot<'_>],
        now: Duration,
        faults: &mut Vec<PageFault>,
        f: &mut FrameStreaming,
    ) {
        self.reader.poll(now, &mut self.done);
        self.pending.append(&mut self.done);
        self.pending.sort_unstable_by_key(|d| (d.file, d.tag >> 32));
        self.installed.clear();
        let (installed, cap) = (&mut self.installed, self.max_installs);
        self.pending.retain(|d| {
            if installed.len() >= cap {
                return true;
            }
            let slot = d.tag as u32;
            let outcome = match (&d.result, roots.get(d.file as usize)) {
                (Ok(bytes), Some(root)) => match pool.loading_slot_mut(slot) {
                    Ok(dst) if dst.len() == bytes.len() => {
                        dst.copy_from_slice(bytes);
                        pool.install(slot, root)
                    }
                    _ => failed(pool, slot),
                },
                _ => failed(pool, slot),
            };
            match outcome {
                Ok(key) => {
                    installed.push(key);
                    f.installs += 1;
                    f.bytes_read += d.result.as_ref().map_or(0, |b| b.len() as u64);
                }
                Err(InstallError::Wait) => return true,
                Err(InstallError::Fault(fault)) => {
                    faults.push(fault);
                    f.faults += 1;
                }
                Err(InstallError::Abandoned(_) | InstallError::Misuse(_)) => {}
            }
            false
        });
    }
}

/// Fails the page loading into `slot`: its fault, to report.
fn failed(pool: &mut Residency<'_, '_>, slot: u32) -> Result<PageKey, InstallError> {
    match pool.fail(slot) {
        Ok(fault) => Err(InstallError::Fault(fault)),
        Err(e) => Err(InstallError::Misuse(e)),
    }
}
