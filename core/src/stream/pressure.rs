//! Quality under streaming pressure: when the pool or the reads cannot keep up with what
//! the cameras want, every camera over the pool coarsens together, as Nanite lowers its
//! quality when its pool is nearly full.
//!
//! One scale multiplies the tolerance of every camera refining over the pool. Each frame it
//! looks at three signals: the room the pool has for loads (free slots and pages nothing
//! holds), whether the reads fall behind (loadable pages the schedule had to leave for a
//! later frame), and the splits deferred for pages against the fronts' nodes. Too little
//! room, or many deferrals while the reads fall behind, raise the scale by a step; room with
//! the reads keeping up lowers it, more slowly, back towards 1. Deferrals while the reads
//! keep up are the latency of a page on its way, which a coarser tolerance would not
//! shorten. A coarser tolerance collapses the fronts out of the deepest pages (they
//! become evictable) and stops wanting pages the reads could not bring in time, so the
//! splits that still wait are few and recent. The lag a camera keeps against its own
//! tolerance is the price, and the scale says how much was paid.

use super::{PoolStats, ScheduleStats};
use crate::RefineParams;

/// One scale on the tolerance of every camera over a pool (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pressure {
    scale: f32,
    max_scale: f32,
    rise: f32,
    fall: f32,
}

/// The signals [`Pressure::update`] reads, for one frame of every camera over the pool.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PressureSignal {
    /// The pool's slots.
    pub slots: u32,
    /// Slots a load may take this frame without touching a front: free, or holding a page
    /// nothing holds ([`PoolStats::free_slots`] + [`PoolStats::evictable`]).
    pub room: u32,
    /// Loadable pages the schedule left for a later frame: the reads fall behind, or no slot
    /// was free ([`ScheduleStats::waiting`]).
    pub waiting: u32,
    /// Splits deferred for absent pages this frame, over every camera.
    pub deferred: u32,
    /// The nodes of every front after this frame's refinement.
    pub active_nodes: u32,
}

impl PressureSignal {
    /// The signals from the pool's stats after this frame's loads were scheduled, what the
    /// schedule did, and the cameras' refinement counts.
    pub fn new(
        slots: u32,
        pool: &PoolStats,
        schedule: &ScheduleStats,
        deferred: u32,
        active_nodes: u32,
    ) -> Self {
        Self {
            slots,
            room: pool.free_slots.saturating_add(pool.evictable),
            waiting: schedule.waiting,
            deferred,
            active_nodes,
        }
    }
}

/// Room below this share of the slots raises the scale: the pool is nearly full.
const ROOM_LOW: f32 = 1.0 / 32.0;
/// Room above this share lets the scale fall.
const ROOM_HIGH: f32 = 1.0 / 8.0;
/// Deferred splits above this share of the fronts' nodes, while the reads fall behind,
/// raise the scale.
const DEFERRED_HIGH: f32 = 0.004;

impl Pressure {
    /// No pressure yet (scale 1), rising by 4% a frame under pressure and falling by 2% a
    /// frame without, to at most 16.
    pub const fn new() -> Self {
        Self {
            scale: 1.0,
            max_scale: 16.0,
            rise: 1.04,
            fall: 1.02,
        }
    }

    /// With the scale held at most `max_scale` (at least 1): how coarse streaming may make
    /// the cameras.
    pub fn with_max_scale(mut self, max_scale: f32) -> Self {
        self.max_scale = if max_scale.is_finite() {
            max_scale.max(1.0)
        } else {
            1.0
        };
        self.scale = self.scale.min(self.max_scale);
        self
    }

    /// With the ratios the scale moves by in a frame: `rise` under pressure, `fall`
    /// without (each at least 1; 1 holds the scale).
    pub fn with_steps(mut self, rise: f32, fall: f32) -> Self {
        let at_least_one = |r: f32| if r.is_finite() { r.max(1.0) } else { 1.0 };
        self.rise = at_least_one(rise);
        self.fall = at_least_one(fall);
        self
    }

    /// The scale on the tolerance now (1: none).
    pub fn scale(&self) -> f32 {
        self.scale
    }

    /// `params` with the tolerance scaled.
    pub fn params(&self, params: RefineParams) -> RefineParams {
        RefineParams {
            tolerance_px: params.tolerance_px * self.scale,
            ..params
        }
    }

    /// Reads one frame's signals and moves the scale: up a step when the pool is nearly full
    /// or many splits waited while the reads fell behind, down a step when the pool has room
    /// and the reads keep up. Returns the scale for the next frame.
    pub fn update(&mut self, s: &PressureSignal) -> f32 {
        let slots = s.slots.max(1) as f32;
        let room = s.room as f32 / slots;
        let behind = s.waiting > 0;
        let deferred = s.deferred as f32 / s.active_nodes.max(1) as f32;
        if room < ROOM_LOW || (behind && deferred > DEFERRED_HIGH) {
            self.scale = (self.scale * self.rise).min(self.max_scale);
        } else if room > ROOM_HIGH && !behind {
            self.scale = (self.scale / self.fall).max(1.0);
        }
        self.scale
    }
}

impl Default for Pressure {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn signal(room: u32, waiting: u32, deferred: u32) -> PressureSignal {
        PressureSignal {
            slots: 1000,
            room,
            waiting,
            deferred,
            active_nodes: 10_000,
        }
    }

    #[test]
    fn pressure_raises_the_scale_and_its_end_lowers_it_to_one() {
        let mut p = Pressure::new().with_max_scale(4.0);
        assert_eq!(p.update(&signal(500, 0, 0)), 1.0, "no pressure, no scale");
        let full = p.update(&signal(10, 0, 0));
        assert!(full > 1.0, "a nearly full pool raises it");
        let behind = p.update(&signal(500, 5, 100));
        assert!(
            behind > full,
            "1% of the front waiting on slow reads raises it"
        );
        let latency = p.update(&signal(100, 0, 100));
        assert_eq!(latency, behind, "waits while the reads keep up hold it");
        for _ in 0..200 {
            p.update(&signal(10, 5, 100));
        }
        assert_eq!(p.scale(), 4.0, "held at the largest scale");
        let held = p.update(&signal(500, 5, 20));
        assert_eq!(held, 4.0, "room while the reads fall behind holds it");
        for _ in 0..1000 {
            p.update(&signal(500, 0, 0));
        }
        assert_eq!(p.scale(), 1.0, "never below 1");
        let params = p.params(RefineParams::default());
        assert_eq!(params.tolerance_px, RefineParams::default().tolerance_px);
    }

    #[test]
    fn bad_settings_hold_the_scale_at_one() {
        let mut p = Pressure::new()
            .with_max_scale(f32::NAN)
            .with_steps(f32::INFINITY, 0.5);
        assert_eq!(p.update(&signal(0, 10, 10_000)), 1.0);
    }
}
