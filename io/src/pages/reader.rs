//! [`PageReader`]: reads submitted by the caller, done by the worker threads, handed back in
//! completion order or, with a [`DiskModel`](super::DiskModel), in simulated finish order.

use std::collections::VecDeque;
use std::io;
use std::sync::Arc;
use std::time::Duration;

use super::buffer::{BufferPool, PageBuffer};
use super::disk::Timeline;
use super::error::{ReadError, SubmitError};
use super::source::PageSource;
use super::worker::{Finished, Job, Workers};
use super::{ReadDone, ReadRequest, ReaderConfig, ReaderStats};

/// A read waiting for its simulated finish time, with its result once the thread is done.
struct Scheduled {
    tag: u64,
    file: u32,
    result: Option<Result<PageBuffer, ReadError>>,
}

/// Serves byte-range reads of a set of [`PageSource`]s on worker threads (see the
/// [module docs](super)).
///
/// A read whose range runs past the end of its source is not refused: it is queued and
/// handed back as a failed [`ReadDone`], as a read that fails on the device is, so that the
/// caller deals with every failure of the data in one place and a refusal always means "not
/// now" or "not valid". It takes no buffer and, with a [`DiskModel`](super::DiskModel), no
/// device time.
///
/// Dropping the reader lets each thread finish the read it is doing, drops the reads not
/// started, and joins the threads.
///
/// ```
/// # fn demo() -> std::io::Result<()> {
/// use std::sync::Arc;
/// use std::time::Duration;
/// use caveclod_io::pages::{PageReader, PageSource, ReadRequest, ReaderConfig};
///
/// let file: Arc<dyn PageSource> = Arc::new((0..=255u8).collect::<Vec<u8>>());
/// let mut reader = PageReader::new(vec![file], ReaderConfig::default())?;
/// let req = ReadRequest { file: 0, offset: 16, len: 4, tag: 7 };
/// reader.submit(req, Duration::ZERO).expect("room for a read");
/// let mut done = Vec::new();
/// reader.drain(&mut done);
/// assert_eq!(done[0].tag, 7);
/// assert_eq!(&done[0].result.as_ref().expect("read")[..], &[16, 17, 18, 19]);
/// # Ok(())
/// # }
/// # demo().unwrap();
/// ```
pub struct PageReader {
    files: Vec<Arc<dyn PageSource>>,
    config: ReaderConfig,
    buffers: BufferPool,
    workers: Workers,
    /// The next read's submission number.
    next_seq: u64,
    /// Reads submitted and not handed back.
    in_flight: usize,
    /// Without a model: reads failed at submission, handed back at the next poll.
    failed: VecDeque<ReadDone>,
    /// With a model: the device's timeline, and the reads in flight sorted by (simulated
    /// finish, submission).
    timeline: Timeline,
    scheduled: VecDeque<((Duration, u64), Scheduled)>,
    stats: ReaderStats,
}

impl PageReader {
    /// A reader of `files` (a request's `file` indexes them) with `config`'s threads and
    /// buffers; buffers are allocated as reads first need them. Fails only if a thread
    /// cannot be started.
    pub fn new(files: Vec<Arc<dyn PageSource>>, config: ReaderConfig) -> io::Result<Self> {
        let config = ReaderConfig {
            threads: config.threads.max(1),
            max_in_flight: config.max_in_flight.max(1),
            ..config
        };
        let most = config.max_in_flight;
        Ok(Self {
            files,
            buffers: BufferPool::new(most, config.max_read_len as usize),
            workers: Workers::start(config.threads, most)?,
            config,
            next_seq: 0,
            in_flight: 0,
            failed: VecDeque::with_capacity(most),
            timeline: Timeline::default(),
            scheduled: VecDeque::with_capacity(most),
            stats: ReaderStats::default(),
        })
    }

    /// The configuration in use (thread and buffer counts raised to at least one).
    pub fn config(&self) -> &ReaderConfig {
        &self.config
    }

    /// Queues a read at time `now` (the caller's clock; used only with a
    /// [`DiskModel`](super::DiskModel)).
    ///
    /// Refused, with nothing queued, when [`ReaderConfig::max_in_flight`] reads are in
    /// flight, every buffer is in use, the file index is unknown or the read is longer than
    /// [`ReaderConfig::max_read_len`]. A range past the end of the source is accepted and
    /// handed back as failed (see the type's docs).
    pub fn submit(&mut self, req: ReadRequest, now: Duration) -> Result<(), SubmitError> {
        let result = self.try_submit(req, now);
        if result.is_err() {
            self.stats.refused += 1;
        }
        result
    }

    fn try_submit(&mut self, req: ReadRequest, now: Duration) -> Result<(), SubmitError> {
        let Some(source) = self.files.get(req.file as usize) else {
            return Err(SubmitError::UnknownFile {
                file: req.file,
                files: self.files.len(),
            });
        };
        let max_read_len = self.config.max_read_len;
        if req.len > max_read_len {
            return Err(SubmitError::TooLong {
                len: req.len,
                max_read_len,
            });
        }
        let max_in_flight = self.config.max_in_flight;
        if self.in_flight >= max_in_flight {
            return Err(SubmitError::Full { max_in_flight });
        }
        let file_len = source.len();
        let past_end = req
            .offset
            .checked_add(u64::from(req.len))
            .is_none_or(|end| end > file_len);
        let buf = if past_end {
            None
        } else {
            let buffers = max_in_flight;
            Some(
                self.buffers
                    .take()
                    .ok_or(SubmitError::NoBuffer { buffers })?,
            )
        };
        let source = Arc::clone(source);
        let seq = self.next_seq;
        self.next_seq += 1;
        self.in_flight += 1;
        let key = match (&self.config.disk, &buf) {
            (Some(model), Some(_)) => {
                let slot = self.timeline.schedule(model, u64::from(req.len), now);
                self.stats.simulated_queue_delay += slot.queued;
                let max = &mut self.stats.simulated_max_queue_delay;
                *max = (*max).max(slot.queued);
                (slot.finish, seq)
            }
            // A failure found here takes no device time.
            (Some(_), None) => (now, seq),
            (None, _) => (Duration::ZERO, seq),
        };
        let Some(buf) = buf else {
            let failed = ReadDone {
                tag: req.tag,
                file: req.file,
                result: Err(ReadError::past_end(req.file, req.offset, req.len, file_len)),
            };
            self.hold(key, failed);
            return Ok(());
        };
        if self.config.disk.is_some() {
            let waiting = Scheduled {
                tag: req.tag,
                file: req.file,
                result: None,
            };
            self.schedule(key, waiting);
        }
        self.workers.push(Job {
            key,
            req,
            source,
            buf,
        });
        Ok(())
    }

    /// Keeps a finished read until it is handed back: by simulated finish with a model, else
    /// in the order finished.
    fn hold(&mut self, key: (Duration, u64), done: ReadDone) {
        if self.config.disk.is_none() {
            self.failed.push_back(done);
            return;
        }
        match self.scheduled.binary_search_by_key(&key, |(k, _)| *k) {
            Ok(at) => self.scheduled[at].1.result = Some(done.result),
            // A read failed at submission is scheduled here.
            Err(_) => self.schedule(
                key,
                Scheduled {
                    tag: done.tag,
                    file: done.file,
                    result: Some(done.result),
                },
            ),
        }
    }

    /// Adds a read to those waiting for their simulated finish, in key order (after all of
    /// them but for failures found at submission, which take no device time).
    fn schedule(&mut self, key: (Duration, u64), waiting: Scheduled) {
        let at = self.scheduled.partition_point(|(k, _)| *k < key);
        self.scheduled.insert(at, (key, waiting));
    }

    /// Appends to `out` the reads finished by `now`, without waiting for reads still to
    /// finish.
    ///
    /// Without a [`DiskModel`](super::DiskModel), those are the reads the threads have
    /// finished, in the order they finished. With one, they are the reads whose simulated
    /// finish is at or before `now`, in that order, whenever the threads finished them: if a
    /// thread has not yet finished such a read (this machine is slower than the model),
    /// `poll` waits for that read, so that what is handed back depends on the simulated clock
    /// alone.
    pub fn poll(&mut self, now: Duration, out: &mut Vec<ReadDone>) {
        if self.config.disk.is_some() {
            while let Some(f) = self.workers.try_finished() {
                self.receive(f);
            }
            self.hand_back_until(now, out);
            return;
        }
        while let Some(done) = self.failed.pop_front() {
            self.hand_back(done, out);
        }
        while let Some(f) = self.workers.try_finished() {
            let done = self.complete(f);
            self.hand_back(done, out);
        }
    }

    /// Waits for every read in flight and appends them to `out` (in simulated finish order
    /// with a [`DiskModel`](super::DiskModel), else as they finish): for tests and for
    /// shutting down.
    pub fn drain(&mut self, out: &mut Vec<ReadDone>) {
        if self.config.disk.is_some() {
            self.hand_back_until(Duration::MAX, out);
            return;
        }
        while let Some(done) = self.failed.pop_front() {
            self.hand_back(done, out);
        }
        while self.in_flight > 0 {
            // Every read in flight not handed back yet is with the threads.
            let f = self.workers.wait_finished();
            let done = self.complete(f);
            self.hand_back(done, out);
        }
    }

    /// Reads submitted and not yet handed back.
    pub fn in_flight(&self) -> usize {
        self.in_flight
    }

    /// What the reader has done so far.
    pub fn stats(&self) -> ReaderStats {
        ReaderStats {
            buffers_allocated: self.buffers.allocated(),
            ..self.stats
        }
    }

    /// With a model: hands back, in key order, the reads whose simulated finish is at or
    /// before `now`, waiting for the threads where they lag behind.
    fn hand_back_until(&mut self, now: Duration, out: &mut Vec<ReadDone>) {
        while let Some(((finish, _), first)) = self.scheduled.front() {
            if *finish > now {
                return;
            }
            if first.result.is_none() {
                // Every read scheduled without a result is with the threads.
                let f = self.workers.wait_finished();
                self.receive(f);
                continue;
            }
            let Some((_, s)) = self.scheduled.pop_front() else {
                return;
            };
            if let Some(result) = s.result {
                let done = ReadDone {
                    tag: s.tag,
                    file: s.file,
                    result,
                };
                self.hand_back(done, out);
            }
        }
    }

    /// With a model: a thread's finished read, kept until its simulated finish.
    fn receive(&mut self, f: Finished) {
        let key = f.key;
        let done = self.complete(f);
        self.hold(key, done);
    }

    /// A thread's finished read as the caller sees it; a failed read's buffer goes back.
    fn complete(&mut self, f: Finished) -> ReadDone {
        let req = f.req;
        let result = match f.result {
            Ok(()) => Ok(self.buffers.wrap(f.buf, req.len as usize)),
            Err(source) => {
                self.buffers.give_back(f.buf);
                Err(ReadError {
                    file: req.file,
                    offset: req.offset,
                    len: req.len,
                    source,
                })
            }
        };
        ReadDone {
            tag: req.tag,
            file: req.file,
            result,
        }
    }

    /// Counts a read handed back and appends it to `out`.
    fn hand_back(&mut self, done: ReadDone, out: &mut Vec<ReadDone>) {
        self.in_flight -= 1;
        match &done.result {
            Ok(bytes) => {
                self.stats.reads += 1;
                self.stats.bytes += bytes.len() as u64;
            }
            Err(_) => self.stats.failures += 1,
        }
        out.push(done);
    }
}

impl std::fmt::Debug for PageReader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PageReader")
            .field("files", &self.files.len())
            .field("config", &self.config)
            .field("in_flight", &self.in_flight)
            .field("stats", &self.stats())
            .finish_non_exhaustive()
    }
}
