//! The worker threads: a queue of reads under a lock, taken in order by whichever thread is
//! free, and a queue of finished reads the reader takes them back from. Both queues hold at
//! most the reads in flight and are made that large up front, so passing reads to the
//! threads and back allocates nothing.

use std::collections::VecDeque;
use std::io;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::{Arc, Condvar, Mutex, MutexGuard, PoisonError};
use std::thread::JoinHandle;
use std::time::Duration;

use super::source::PageSource;
use super::ReadRequest;
use crate::aligned::AlignedBytes;

/// A read for a worker: the request, where to read it from and into.
pub(super) struct Job {
    /// The reader's key for the read: its simulated finish (zero without a model) and its
    /// submission number.
    pub(super) key: (Duration, u64),
    pub(super) req: ReadRequest,
    pub(super) source: Arc<dyn PageSource>,
    pub(super) buf: AlignedBytes,
}

/// A read a worker has done: the job's key, request and buffer, and whether it worked.
pub(super) struct Finished {
    pub(super) key: (Duration, u64),
    pub(super) req: ReadRequest,
    pub(super) buf: AlignedBytes,
    pub(super) result: io::Result<()>,
}

/// The reads not yet started, and whether to stop.
struct Queue {
    jobs: VecDeque<Job>,
    stop: bool,
}

/// What the threads and the reader share.
struct Shared {
    queue: Mutex<Queue>,
    /// Signalled when a job is queued or the threads are to stop.
    wake: Condvar,
    done: Mutex<VecDeque<Finished>>,
    /// Signalled when a read is finished.
    finished: Condvar,
}

/// `mutex`'s value, whole even after a panic elsewhere: a push or pop leaves a queue valid,
/// and the threads catch a source's panic outside the locks anyway.
fn lock<T>(mutex: &Mutex<T>) -> MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(PoisonError::into_inner)
}

/// The worker threads. Dropping them lets each finish the read it is doing, drops the reads
/// not started, and joins the threads.
pub(super) struct Workers {
    shared: Arc<Shared>,
    threads: Vec<JoinHandle<()>>,
}

impl Workers {
    /// Starts `count` threads (at least one), with room for `capacity` reads in flight.
    pub(super) fn start(count: usize, capacity: usize) -> io::Result<Self> {
        let shared = Shared {
            queue: Mutex::new(Queue {
                jobs: VecDeque::with_capacity(capacity),
                stop: false,
            }),
            wake: Condvar::new(),
            done: Mutex::new(VecDeque::with_capacity(capacity)),
            finished: Condvar::new(),
        };
        let mut workers = Self {
            shared: Arc::new(shared),
            threads: Vec::with_capacity(count.max(1)),
        };
        // Every thread is running before `start` returns: a thread's start-up allocates,
        // and must not do so during a later frame.
        let running = Arc::new((Mutex::new(0usize), Condvar::new()));
        let mut failed = None;
        for i in 0..count.max(1) {
            let shared = Arc::clone(&workers.shared);
            let up = Arc::clone(&running);
            let thread = std::thread::Builder::new()
                .name(format!("caveclod-pages-{i}"))
                .spawn(move || {
                    *lock(&up.0) += 1;
                    up.1.notify_all();
                    work(&shared)
                });
            match thread {
                Ok(t) => workers.threads.push(t),
                Err(e) => {
                    failed = Some(e);
                    break;
                }
            }
        }
        let mut n = lock(&running.0);
        while *n < workers.threads.len() {
            n = running.1.wait(n).unwrap_or_else(PoisonError::into_inner);
        }
        drop(n);
        // On failure `workers` drops, stopping the threads already started.
        match failed {
            Some(e) => Err(e),
            None => Ok(workers),
        }
    }

    /// Queues a read for the next free thread.
    pub(super) fn push(&self, job: Job) {
        lock(&self.shared.queue).jobs.push_back(job);
        self.shared.wake.notify_one();
    }

    /// The next finished read, if there is one.
    pub(super) fn try_finished(&self) -> Option<Finished> {
        lock(&self.shared.done).pop_front()
    }

    /// The next finished read, waiting for one. Only for a caller with a read pushed and
    /// not yet taken back: every pushed read comes back (a source's panic fails it).
    pub(super) fn wait_finished(&self) -> Finished {
        let mut done = lock(&self.shared.done);
        loop {
            if let Some(f) = done.pop_front() {
                return f;
            }
            done = self
                .shared
                .finished
                .wait(done)
                .unwrap_or_else(PoisonError::into_inner);
        }
    }
}

impl Drop for Workers {
    fn drop(&mut self) {
        {
            let mut queue = lock(&self.shared.queue);
            queue.stop = true;
            queue.jobs.clear();
        }
        self.shared.wake.notify_all();
        for thread in self.threads.drain(..) {
            // A thread's own panics are caught in `work`; nothing is left to report.
            let _ = thread.join();
        }
    }
}

/// A worker thread: takes jobs until told to stop.
fn work(shared: &Shared) {
    loop {
        let job = {
            let mut queue = lock(&shared.queue);
            loop {
                if queue.stop {
                    return;
                }
                if let Some(job) = queue.jobs.pop_front() {
                    break job;
                }
                queue = shared
                    .wake
                    .wait(queue)
                    .unwrap_or_else(PoisonError::into_inner);
            }
        };
        let Job {
            key,
            req,
            source,
            mut buf,
        } = job;
        let into = &mut buf[..req.len as usize];
        // A source that panics fails its read instead of taking the thread (and every read
        // queued behind it) down.
        let result = catch_unwind(AssertUnwindSafe(|| source.read_at(req.offset, into)))
            .unwrap_or_else(|_| Err(io::Error::other("the page source panicked")));
        let finished = Finished {
            key,
            req,
            buf,
            result,
        };
        lock(&shared.done).push_back(finished);
        shared.finished.notify_one();
    }
}
