//! The simulated device: how long each read takes on the caller's clock.

use std::time::Duration;

/// A simulated storage device or network: a read's bytes start to arrive `latency` after it
/// is submitted, and arrive at `bytes_per_second`, which all reads share: latencies overlap
/// (many reads may be in flight, as on an SSD's queue or a network), transfers do not, and
/// they run in the order submitted.
///
/// Times are on the clock the caller passes to the reader (a [`Duration`] since any start it
/// likes), not the machine's, so a fly-over advanced by a fixed step per frame meets the same
/// slow disk on a fast machine and a slow one. The device is shared by all of a reader's
/// files, as files on one disk are.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiskModel {
    /// The time before a read's first byte arrives.
    pub latency: Duration,
    /// How fast bytes arrive after that; infinite, zero, negative or NaN means they take no
    /// time.
    pub bytes_per_second: f64,
}

impl DiskModel {
    /// A device whose reads take no time: reads are handed back, in order, at the time they
    /// were submitted.
    pub fn none() -> Self {
        Self {
            latency: Duration::ZERO,
            bytes_per_second: f64::INFINITY,
        }
    }

    /// A device with this latency and bandwidth.
    pub fn new(latency: Duration, bytes_per_second: f64) -> Self {
        Self {
            latency,
            bytes_per_second,
        }
    }

    /// How long a read of `len` bytes takes on an idle device: its latency and its transfer,
    /// to the nearest nanosecond.
    pub fn read_time(&self, len: u64) -> Duration {
        self.latency + self.transfer_time(len)
    }

    /// How long `len` bytes keep the shared bandwidth busy.
    pub fn transfer_time(&self, len: u64) -> Duration {
        let bps = self.bytes_per_second;
        if !(bps > 0.0 && bps.is_finite()) {
            return Duration::ZERO;
        }
        let nanos = (len as f64 * 1e9 / bps).round();
        // A float too large for u64 nanoseconds (centuries) saturates.
        Duration::from_nanos(nanos as u64)
    }
}

/// The device's timeline: when its bandwidth finishes the last transfer queued on it.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Timeline {
    busy_until: Duration,
}

/// When a read runs on the simulated device.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Slot {
    /// How long its transfer waited for earlier ones, after its latency.
    pub(super) queued: Duration,
    /// When its bytes are all there.
    pub(super) finish: Duration,
}

impl Timeline {
    /// Queues a read of `len` bytes submitted at `now`: after its latency, its transfer
    /// starts once the earlier transfers are done.
    pub(super) fn schedule(&mut self, model: &DiskModel, len: u64, now: Duration) -> Slot {
        let arrives = now.saturating_add(model.latency);
        let start = arrives.max(self.busy_until);
        let finish = start.saturating_add(model.transfer_time(len));
        self.busy_until = finish;
        Slot {
            queued: start - arrives,
            finish,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: Duration = Duration::from_millis(1);

    #[test]
    fn latencies_overlap_and_transfers_share_the_bandwidth() {
        let disk = DiskModel::new(8 * MS, 200e6);
        assert_eq!(disk.read_time(200_000), 9 * MS);
        assert_eq!(DiskModel::none().read_time(1 << 30), Duration::ZERO);
        assert_eq!(DiskModel::new(MS, 0.0).read_time(10), MS);
        let mut t = Timeline::default();
        let a = t.schedule(&disk, 200_000, 10 * MS);
        let b = t.schedule(&disk, 200_000, 10 * MS);
        let c = t.schedule(&disk, 200_000, 30 * MS);
        let slot = |queued, finish| Slot { queued, finish };
        assert_eq!(a, slot(Duration::ZERO, 19 * MS));
        // Submitted with `a`: its latency overlaps `a`'s, its transfer follows `a`'s.
        assert_eq!(b, slot(MS, 20 * MS));
        // An idle device starts a late read's transfer after its latency.
        assert_eq!(c, slot(Duration::ZERO, 39 * MS));
    }
}
