//! Fault injection: the two seams through which a test (this crate's, or a host's testing
//! its own recovery) makes a context run out of device memory or lose its device on
//! purpose, with the errors the real faults give (the design decisions are on [`Faults`]).

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use crate::error::{from_allocation, Error, Result};

/// No fault planned.
const NEVER: u64 = u64::MAX;

/// A context's fault plan ([`Context::faults`](crate::Context::faults)), and counters of
/// the points where faults can be injected.
///
/// Design decisions:
/// - **Two seams, where the faults arise.** Every device allocation this crate makes
///   (buffers, images) goes through the context's allocation step, which consults the plan
///   before asking gpu-allocator; every call this crate makes that the Vulkan specification
///   lets return `VK_ERROR_DEVICE_LOST` (`vkQueueSubmit2`, `vkWaitForFences`,
///   `vkDeviceWaitIdle`) passes a device checkpoint first. Acquire and present are the
///   host's calls, on the host's swapchain, and so are its own allocations from a shared
///   allocator: this plan does not reach them.
/// - **Faults fail before the call**, as a call that fails does nothing: an injected fault
///   creates no object that the injection itself would leak, so any leak a fault test
///   finds is the code's.
/// - **Exhausted memory stays exhausted** until [`restore_memory`](Self::restore_memory)
///   (memory being freed elsewhere): every allocation from the planned one on fails, so
///   clean-up paths that allocate are caught too. The error is the one gpu-allocator's own
///   out-of-memory gives, [`Error::OutOfMemory`] with `device: true`.
/// - **A lost device stays lost** until [`restore_device`](Self::restore_device): every
///   checkpoint from the planned one on reports [`Error::DeviceLost`], as a real lost
///   device does, so nothing waits for work that was never submitted. Tear-down
///   (`destroy` of the renderer and of the context) waits without a checkpoint and accepts
///   a lost device, since the specification lets a lost device's objects be destroyed.
/// - **Always compiled and public**: integration tests are another crate (a `cfg(test)`
///   seam would not reach them), hosts can test their own recovery with it, and an unplanned
///   check is a relaxed atomic increment and a load or two per allocation or submission.
#[derive(Debug)]
pub struct Faults {
    allocations: AtomicU64,
    exhaust_at: AtomicU64,
    checkpoints: AtomicU64,
    lose_at: AtomicU64,
    lost: AtomicBool,
}

impl Default for Faults {
    fn default() -> Self {
        Self {
            allocations: AtomicU64::new(0),
            exhaust_at: AtomicU64::new(NEVER),
            checkpoints: AtomicU64::new(0),
            lose_at: AtomicU64::new(NEVER),
            lost: AtomicBool::new(false),
        }
    }
}

impl Faults {
    /// Device allocations attempted through the context so far (failed ones included).
    pub fn allocations(&self) -> u64 {
        self.allocations.load(Ordering::Relaxed)
    }

    /// Device checkpoints passed so far (submissions and waits; failed ones included).
    pub fn checkpoints(&self) -> u64 {
        self.checkpoints.load(Ordering::Relaxed)
    }

    /// Device memory runs out at the `n`-th allocation from now (0: the next one): it and
    /// every later one fail with [`Error::OutOfMemory`] until
    /// [`restore_memory`](Self::restore_memory).
    pub fn exhaust_memory_after(&self, n: u64) {
        let at = self.allocations().saturating_add(n);
        self.exhaust_at.store(at, Ordering::Relaxed);
    }

    /// Memory is back: allocations succeed again (as far as the device allows).
    pub fn restore_memory(&self) {
        self.exhaust_at.store(NEVER, Ordering::Relaxed);
    }

    /// The device is lost at the `n`-th checkpoint from now (0: the next one): it and every
    /// later one fail with [`Error::DeviceLost`] until
    /// [`restore_device`](Self::restore_device).
    pub fn lose_device_after(&self, n: u64) {
        let at = self.checkpoints().saturating_add(n);
        self.lose_at.store(at, Ordering::Relaxed);
    }

    /// Ends an injected device loss: checkpoints pass again.
    pub fn restore_device(&self) {
        self.lose_at.store(NEVER, Ordering::Relaxed);
        self.lost.store(false, Ordering::Relaxed);
    }

    /// `true` once an injected device loss has happened (until
    /// [`restore_device`](Self::restore_device)).
    pub fn device_lost(&self) -> bool {
        self.lost.load(Ordering::Relaxed)
    }

    /// Counts an allocation of `name`; the out-of-memory error if memory is exhausted.
    pub(crate) fn allocation(&self, name: &str) -> Result<()> {
        let n = self.allocations.fetch_add(1, Ordering::Relaxed);
        if n >= self.exhaust_at.load(Ordering::Relaxed) {
            return Err(from_allocation(
                name,
                gpu_allocator::AllocationError::OutOfMemory,
            ));
        }
        Ok(())
    }

    /// Counts a checkpoint before `call`; [`Error::DeviceLost`] if the device is lost.
    pub(crate) fn checkpoint(&self, call: &'static str) -> Result<()> {
        let n = self.checkpoints.fetch_add(1, Ordering::Relaxed);
        if n >= self.lose_at.load(Ordering::Relaxed) {
            self.lost.store(true, Ordering::Relaxed);
        }
        if self.device_lost() {
            return Err(Error::DeviceLost { call });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn memory_stays_exhausted_until_restored() {
        let f = Faults::default();
        assert!(f.allocation("a").is_ok());
        f.exhaust_memory_after(1);
        assert!(f.allocation("b").is_ok());
        for _ in 0..3 {
            let e = f.allocation("c").err();
            assert!(
                matches!(e, Some(Error::OutOfMemory { device: true, .. })),
                "{e:?}"
            );
        }
        f.restore_memory();
        assert!(f.allocation("d").is_ok());
        assert_eq!(f.allocations(), 6);
    }

    #[test]
    fn a_lost_device_stays_lost_until_restored() {
        let f = Faults::default();
        f.lose_device_after(2);
        assert!(f.checkpoint("vkQueueSubmit2").is_ok());
        assert!(f.checkpoint("vkWaitForFences").is_ok());
        assert!(!f.device_lost());
        assert!(matches!(
            f.checkpoint("vkQueueSubmit2"),
            Err(Error::DeviceLost {
                call: "vkQueueSubmit2"
            })
        ));
        assert!(f.device_lost());
        assert!(matches!(
            f.checkpoint("vkDeviceWaitIdle"),
            Err(Error::DeviceLost {
                call: "vkDeviceWaitIdle"
            })
        ));
        f.restore_device();
        assert!(f.checkpoint("vkQueueSubmit2").is_ok());
        assert_eq!(f.checkpoints(), 5);
    }
}
