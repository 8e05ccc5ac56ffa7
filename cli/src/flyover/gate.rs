//! How far apart the camera threads of a flight may run: frames in flight.
//!
//! A renderer with `k` frames in flight keeps `k` index lists per camera and view, so a
//! camera may refine and emit frame `n` into one while frame `n - 1` is still being drawn
//! from another; it must wait only before it would overwrite the lists of a frame not yet
//! complete: frame `n` needs every camera done with frame `n - k`. With one frame in flight
//! that is a barrier per frame (every camera waits for the slowest, every frame); with two, a
//! camera that finished early starts its next frame while another camera finishes this one,
//! and a frame in which one camera has much to do no longer idles the other core.
//!
//! The shorter a camera's frame (with the index cache, emission is a copy), the more waiting
//! for the slowest camera weighs against the work itself, and the more slack a camera needs
//! to absorb a frame in which another has much to do. The fly-over keeps three frames in
//! flight, as a triple-buffered renderer does: a camera may run two frames ahead of the
//! slowest before it waits.

use std::sync::{Condvar, Mutex, PoisonError};

/// Frames in flight unless a flight says otherwise: a camera may run two frames ahead of
/// the slowest camera.
pub const FRAMES_IN_FLIGHT: usize = 3;

/// Counts each camera's finished frames and holds a camera back from frame `n` until every
/// camera has finished frame `n - in_flight`.
pub struct FrameGate {
    done: Mutex<Vec<usize>>,
    changed: Condvar,
    lead: usize,
}

impl FrameGate {
    /// A gate for `cameras` threads and `in_flight` frames in flight (at least one).
    pub fn new(cameras: usize, in_flight: usize) -> Self {
        Self {
            done: Mutex::new(vec![0; cameras]),
            changed: Condvar::new(),
            lead: in_flight.max(1) - 1,
        }
    }

    /// Waits until the camera may start its `n`-th frame (counted from 0): every camera has
    /// finished `n - (in_flight - 1)` frames.
    pub fn enter(&self, n: usize) {
        let need = n.saturating_sub(self.lead);
        let mut done = self.done.lock().unwrap_or_else(PoisonError::into_inner);
        while done.iter().any(|&d| d < need) {
            done = self
                .changed
                .wait(done)
                .unwrap_or_else(PoisonError::into_inner);
        }
    }

    /// Camera `c` finished a frame. Waiters wait for the slowest camera, so only the
    /// slowest finishing a frame can let one go: the others wake nobody.
    pub fn leave(&self, c: usize) {
        let mut done = self.done.lock().unwrap_or_else(PoisonError::into_inner);
        let slowest = done.iter().copied().min();
        let Some(d) = done.get_mut(c) else {
            return;
        };
        let was_slowest = Some(*d) == slowest;
        *d += 1;
        drop(done);
        if was_slowest {
            self.changed.notify_all();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// No camera ever starts a frame more than `in_flight - 1` frames ahead of a camera that
    /// has not finished, and with one frame in flight the gate is a barrier.
    #[test]
    fn cameras_stay_within_the_frames_in_flight() {
        const CAMERAS: usize = 4;
        const FRAMES: usize = 400;
        for in_flight in 1..=3 {
            let gate = FrameGate::new(CAMERAS, in_flight);
            let finished: Vec<AtomicUsize> = (0..CAMERAS).map(|_| AtomicUsize::new(0)).collect();
            std::thread::scope(|s| {
                for c in 0..CAMERAS {
                    let (gate, finished) = (&gate, &finished);
                    s.spawn(move || {
                        for n in 0..FRAMES {
                            gate.enter(n);
                            let slowest = finished.iter().map(|f| f.load(Ordering::Acquire)).min();
                            assert!(
                                slowest.unwrap_or(0) + in_flight > n,
                                "camera {c} began frame {n} with a camera at {slowest:?} \
                                 ({in_flight} in flight)"
                            );
                            if (n * 7 + c * 13) % 31 == 0 {
                                // Now and then one camera is slow, so the others must wait.
                                std::thread::sleep(std::time::Duration::from_micros(300));
                            }
                            finished[c].fetch_add(1, Ordering::AcqRel);
                            gate.leave(c);
                        }
                    });
                }
            });
            assert!(finished.iter().all(|f| f.load(Ordering::Acquire) == FRAMES));
        }
    }
}
