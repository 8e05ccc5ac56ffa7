//! Regulation of a camera's pixel tolerance to hold a number of active polygons (Hoppe's
//! `screen_thresh *= pow(current_faces / goal_faces, gain)`, with a floor; see
//! `libHh/SrMesh.cpp`), damped so that it settles instead of oscillating.
//!
//! A budgeted camera ([`CameraConfig::with_polygon_budget`](crate::CameraConfig)) that meets
//! its budget refuses splits: the front it draws is fine where it was refined first and
//! coarse elsewhere. A regulated camera instead raises its tolerance everywhere until the
//! front it wants fits, so its screen-space error stays uniform over the view; sized a little
//! above the regulator's target, it never refuses a split.
//!
//! # Damping
//!
//! A front's polygon count falls roughly as `tolerance^-2` (the area each polygon covers on
//! the screen grows with the square of the error it may have), so Hoppe's rule with gain `g`
//! shrinks the count's error, in logarithms, by the factor `1 - 2g` per frame (a real front
//! often responds less: near full resolution a finer tolerance adds few polygons). The
//! regulator takes that step with three guards, each against one way such a loop oscillates:
//! - a **gain** below one half ([`Regulator::DEFAULT_GAIN`]): every step undershoots, so
//!   the count approaches the target from one side instead of jumping across it;
//! - a **dead band** ([`Regulator::DEFAULT_DEAD_BAND`]): within it the tolerance stays as it
//!   is, so the small changes of a moving view do not make it chatter;
//! - a **clamped step** ([`Regulator::DEFAULT_MAX_STEP`]): one frame changes the tolerance by
//!   at most this ratio, so a frame with a wild count (the first, from the base mesh; a cut
//!   to the view) cannot throw it far.
//!
//! Give [`Regulator::update`] the camera's active polygons
//! ([`RefineStats::active_polygons`](crate::RefineStats)). A camera at its budget refuses
//! splits ([`RefineStats::capacity_refusals`](crate::RefineStats)); adding two polygons per
//! refusal tells the regulator how far beyond its budget the front wants to grow.
//!
//! The tolerance stays within a floor and a ceiling ([`Regulator::with_limits`]); every input
//! (zero polygons included) gives a finite positive tolerance.

use crate::camera::RefineParams;

/// Holds a camera's active polygons near a target by adapting its pixel tolerance each frame.
///
/// ```
/// use caveclod_core::{RefineParams, Regulator};
/// let mut r = Regulator::new(20_000);
/// let mut params = RefineParams::default();
/// for _frame in 0..3 {
///     params.tolerance_px = r.tolerance();
///     // cam.refine(&h, &view, &params)?; then:
///     let active = 30_000; // stats.active_polygons + 2 * stats.capacity_refusals
///     r.update(active);
/// }
/// assert!(r.tolerance() > 1.0); // too many polygons: coarser
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Regulator {
    target: u32,
    tolerance: f32,
    gain: f32,
    dead_band: f32,
    max_step: f32,
    min_tolerance: f32,
    max_tolerance: f32,
    last_step: f32,
}

impl Regulator {
    /// The exponent of Hoppe's rule: with a count falling as `tolerance^-2` the count's error
    /// shrinks by `1 - 2 * 0.4 = 0.2` per frame, without overshoot (tuned on the fly-over's
    /// flights over St. Helens, whose fronts respond more weakly).
    pub const DEFAULT_GAIN: f32 = 0.4;
    /// Relative error of the count within which the tolerance holds: 1%.
    pub const DEFAULT_DEAD_BAND: f32 = 0.01;
    /// Largest change of the tolerance in one frame, as a ratio: 15%.
    pub const DEFAULT_MAX_STEP: f32 = 1.15;
    /// The default floor of the tolerance, in pixels.
    pub const DEFAULT_MIN_TOLERANCE: f32 = 0.1;
    /// The default ceiling of the tolerance, in pixels.
    pub const DEFAULT_MAX_TOLERANCE: f32 = 1000.0;

    /// A regulator for `target_polygons` (0 counts as 1), starting at 1 pixel with the
    /// default gain, dead band, step and limits.
    pub fn new(target_polygons: u32) -> Self {
        Self {
            target: target_polygons.max(1),
            tolerance: 1.0,
            gain: Self::DEFAULT_GAIN,
            dead_band: Self::DEFAULT_DEAD_BAND,
            max_step: Self::DEFAULT_MAX_STEP,
            min_tolerance: Self::DEFAULT_MIN_TOLERANCE,
            max_tolerance: Self::DEFAULT_MAX_TOLERANCE,
            last_step: 1.0,
        }
    }

    /// Starting at `tolerance_px` (within the limits; a value that is not a positive number
    /// keeps the current one).
    pub fn with_tolerance(mut self, tolerance_px: f32) -> Self {
        if positive(tolerance_px) {
            self.tolerance = tolerance_px;
        }
        self.tolerance = self.clamp(self.tolerance);
        self
    }

    /// With gain `gain`, clamped to `0..=1` (not a number keeps the current one). Above one
    /// half a step overshoots the target of a count falling as `tolerance^-2`.
    pub fn with_gain(mut self, gain: f32) -> Self {
        if !gain.is_nan() {
            self.gain = gain.clamp(0.0, 1.0);
        }
        self
    }

    /// With a dead band of `relative` error (0.01: within 1% of the target the tolerance
    /// holds), clamped to `0..=0.5` (not a number keeps the current one).
    pub fn with_dead_band(mut self, relative: f32) -> Self {
        if !relative.is_nan() {
            self.dead_band = relative.clamp(0.0, 0.5);
        }
        self
    }

    /// With at most a ratio of `ratio` between two frames' tolerances, at least 1 (1: the
    /// tolerance never moves; not a number or infinity keeps the current one).
    pub fn with_max_step(mut self, ratio: f32) -> Self {
        if ratio.is_finite() {
            self.max_step = ratio.max(1.0);
        }
        self
    }

    /// With the tolerance kept within `min_px..=max_px` (the floor of Hoppe's rule and a
    /// ceiling). A bound that is not a positive number keeps the current one, and a ceiling
    /// below the floor is raised to it.
    pub fn with_limits(mut self, min_px: f32, max_px: f32) -> Self {
        if positive(min_px) {
            self.min_tolerance = min_px;
        }
        if positive(max_px) {
            self.max_tolerance = max_px;
        }
        self.max_tolerance = self.max_tolerance.max(self.min_tolerance);
        self.tolerance = self.clamp(self.tolerance);
        self
    }

    /// The polygons it holds the camera to.
    pub fn target(&self) -> u32 {
        self.target
    }

    /// The tolerance to refine the next frame with, in pixels.
    pub fn tolerance(&self) -> f32 {
        self.tolerance
    }

    /// `params` with the regulated tolerance.
    pub fn params(&self, params: RefineParams) -> RefineParams {
        RefineParams {
            tolerance_px: self.tolerance,
            ..params
        }
    }

    /// The ratio of the last update's tolerance to the one before (1 before any update, in
    /// the dead band, or held at a limit).
    pub fn last_step(&self) -> f32 {
        self.last_step
    }

    /// Takes the frame's count of active polygons (see the module docs) and returns the
    /// tolerance for the next frame.
    pub fn update(&mut self, active_polygons: u32) -> f32 {
        let before = self.tolerance;
        // One polygon at least: the logarithm of zero would be a step of infinite size.
        let ratio = active_polygons.max(1) as f32 / self.target as f32;
        if (ratio - 1.0).abs() > self.dead_band {
            let step = libm::powf(ratio, self.gain);
            let step = step.clamp(1.0 / self.max_step, self.max_step);
            if step.is_finite() {
                self.tolerance = self.clamp(self.tolerance * step);
            }
        }
        self.last_step = self.tolerance / before;
        self.tolerance
    }

    fn clamp(&self, tolerance: f32) -> f32 {
        tolerance.clamp(self.min_tolerance, self.max_tolerance)
    }
}

/// `true` for a finite number above zero.
fn positive(x: f32) -> bool {
    x.is_finite() && x > 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A front of `c / tolerance^2` polygons, as a terrain's is roughly.
    fn polygons(c: f32, tolerance: f32) -> u32 {
        (c / (tolerance * tolerance)).min(u32::MAX as f32) as u32
    }

    #[test]
    fn converges_on_a_front_falling_with_the_square_of_the_tolerance() {
        for (c, target) in [(80_000.0f32, 20_000u32), (5_000.0, 20_000), (1e6, 1_000)] {
            let mut r = Regulator::new(target);
            let mut last = 0.0f32;
            for _ in 0..200 {
                last = r.update(polygons(c, r.tolerance()));
            }
            let p = polygons(c, last) as f32;
            assert!(
                (p / target as f32 - 1.0).abs() <= 0.011,
                "{c}: {p} for {target}"
            );
            // `last` is about `sqrt(c / target)`.
            let want = c / target as f32;
            assert!(
                (last * last / want - 1.0).abs() < 0.02,
                "{last}² for {want}"
            );
        }
    }

    #[test]
    fn approaches_from_one_side_without_overshoot() {
        let mut r = Regulator::new(20_000);
        let c = 20_000.0 * 9.0; // settles at 3 px
        let mut signs = 0;
        let mut last_sign = 0.0f32;
        for _ in 0..300 {
            let p = polygons(c, r.tolerance());
            r.update(p);
            let s = r.last_step() - 1.0;
            if s != 0.0 {
                if last_sign != 0.0 && s.signum() != last_sign {
                    signs += 1;
                }
                last_sign = s.signum();
            }
        }
        assert_eq!(signs, 0, "the step never changes direction on a still view");
        assert!(
            (r.tolerance() / 3.0 - 1.0).abs() < 0.01,
            "{}",
            r.tolerance()
        );
    }

    #[test]
    fn holds_in_the_dead_band_and_clamps_each_step() {
        let mut r = Regulator::new(10_000);
        assert_eq!(r.update(10_050), 1.0);
        assert_eq!(r.last_step(), 1.0);
        let t = r.update(u32::MAX);
        assert!((t - Regulator::DEFAULT_MAX_STEP).abs() < 1e-6, "{t}");
        let mut r = Regulator::new(10_000);
        let t = r.update(0);
        assert!((t - 1.0 / Regulator::DEFAULT_MAX_STEP).abs() < 1e-6, "{t}");
    }

    #[test]
    fn respects_floor_and_ceiling() {
        let mut r = Regulator::new(1_000).with_limits(0.5, 4.0);
        for _ in 0..100 {
            r.update(0);
        }
        assert_eq!(r.tolerance(), 0.5);
        for _ in 0..100 {
            r.update(u32::MAX);
        }
        assert_eq!(r.tolerance(), 4.0);
        let r = Regulator::new(1).with_limits(8.0, 2.0);
        assert_eq!(
            r.tolerance(),
            8.0,
            "a ceiling below the floor is raised to it"
        );
    }

    #[test]
    fn never_gives_a_tolerance_that_is_not_a_positive_number() {
        let odd = [
            0.0f32,
            -1.0,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            1e-30,
            1e30,
        ];
        let counts = [0u32, 1, 7, 20_000, u32::MAX];
        for &a in &odd {
            for &b in &odd {
                let mut r = Regulator::new(0)
                    .with_tolerance(a)
                    .with_gain(b)
                    .with_dead_band(a)
                    .with_max_step(b)
                    .with_limits(a, b);
                for &n in counts.iter().chain(counts.iter().rev()) {
                    let t = r.update(n);
                    assert!(t.is_finite() && t > 0.0, "{a} {b} {n}: {t}");
                    assert_eq!(t, r.tolerance());
                    assert!(r.last_step().is_finite() && r.last_step() > 0.0);
                }
            }
        }
    }
}
