//! Regulation of a camera's pixel tolerance to hold a number of active polygons: Hoppe's
//! regulator (`screen_thresh *= pow(current_faces / goal_faces, gain)`, with a floor; see
//! `libHh/SrMesh.cpp`), made to predict the count it regulates, so that it follows a moving
//! view without lagging behind it and settles instead of oscillating.
//!
//! A budgeted camera ([`CameraConfig::with_polygon_budget`](crate::CameraConfig)) that meets
//! its budget refuses splits: the front it draws is fine where it was refined first and
//! coarse elsewhere. A regulated camera instead raises its tolerance everywhere until the
//! front it wants fits, so its screen-space error stays uniform over the view; sized a little
//! above the regulator's target, it never refuses a split.
//!
//! # The count it predicts
//!
//! In logarithms, a frame's count is `ln N = c - a · ln t`: `c` is what the view offers (the
//! count at 1 px), `a` the front's **response** to its tolerance `t`. A terrain seen from
//! afar responds with `a` near 2 (each polygon's screen area grows with the square of the
//! error it may have); a front near full resolution barely responds (`a` of 0.2 and below),
//! since a finer tolerance finds few nodes left to split. Hoppe's rule
//! `t *= (N / target)^g` shrinks the count's error by `1 - a · g` per frame, so one gain is
//! either slow where the response is weak or overshoots where it is strong; and as the view
//! moves, `c` drifts by a few percent a frame, which a rule that only integrates the error
//! trails by `drift / (a · g)`, far outside a tolerance of 5%.
//!
//! The regulator therefore estimates both from the frames it sees, by recursive least squares
//! with forgetting over `Δ ln N = drift - a · Δ ln t` (a few floats, no history), and picks the
//! next tolerance so that the predicted count corrects a share `gain` of the error, drift
//! included: `Δ ln t = (gain · ln(N / target) + drift) / a`. With the drift known, a steadily
//! moving view is followed without a standing error; with the response known, one gain fits
//! both the coarse and the saturated front. Until the estimates have seen frames, `a` is
//! [`Regulator::PRIOR_RESPONSE`] and the drift zero, which is Hoppe's rule with exponent
//! `gain / PRIOR_RESPONSE`.
//!
//! # The camera's own lags
//!
//! An amortised camera ([`RefineParams::visit_fraction`]) visits its front once in
//! `1 / visit_fraction` frames, so its count follows the mean tolerance of that many frames;
//! told so ([`Regulator::with_response_frames`]), the regulator regresses on that mean and
//! regulates the count the current tolerance will settle at. A camera with geomorphs shows a
//! split at once but a collapse only when its coarsen morph ends; it gives the settled count
//! too ([`Regulator::update_settling`]).
//!
//! # Damping
//!
//! Three guards, each against one way such a loop oscillates:
//! - a **gain** below one ([`Regulator::DEFAULT_GAIN`]): each step corrects part of the
//!   predicted error, so an estimate somewhat off still approaches from one side;
//! - a **dead band** ([`Regulator::DEFAULT_DEAD_BAND`]): while the count the next frame is
//!   predicted to have (the drift included) stays within it, the tolerance holds, so the
//!   small changes of a moving view do not make it chatter;
//! - a **clamped step** ([`Regulator::DEFAULT_MAX_STEP`]): one frame changes the tolerance by
//!   at most this ratio, so a frame with a wild count (the first, from the base mesh; a cut
//!   to the view) cannot throw it far. The estimated response stays within
//!   [`Regulator::MIN_RESPONSE`]` ..= `[`Regulator::MAX_RESPONSE`] and the drift within the
//!   clamped step's logarithm, so no estimate runs away.
//!
//! Give [`Regulator::update`] the camera's active polygons
//! ([`RefineStats::active_polygons`](crate::RefineStats)) after each frame refined with
//! [`Regulator::tolerance`]. A camera at its budget refuses splits
//! ([`RefineStats::capacity_refusals`](crate::RefineStats)); adding two polygons per refusal
//! tells the regulator how far beyond its budget the front wants to grow. A camera with
//! geomorphs calls [`Regulator::update_settling`] instead, with the refused splits' polygons
//! added to both of its counts.
//!
//! The tolerance stays within a floor and a ceiling ([`Regulator::with_limits`]); every input
//! (zero polygons included) gives a finite positive tolerance. A view that holds fewer
//! polygons than the target even at full resolution keeps the tolerance at the floor: no
//! tolerance reaches that target.

use crate::params::RefineParams;

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
    model: Model,
    /// Frames a change of tolerance takes to show in full in the count (1: the next frame).
    response_frames: u8,
    /// `ln t` of the last `response_frames` frames, the newest at `recent_at`.
    recent: [f32; Regulator::MAX_RESPONSE_FRAMES as usize],
    recent_at: u8,
    recent_len: u8,
    /// The smoothed share of the count that waits for coarsen morphs, in logarithms.
    waiting: f32,
}

/// The regulator's estimate of how the count moves (see the module docs), in logarithms.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Model {
    /// `a`: the count's fall per unit of `ln t`.
    response: f32,
    /// The count's change per frame at a fixed tolerance.
    drift: f32,
    /// The least-squares covariance of (`response`, `drift`): `[p00, p01, p11]`.
    p: [f32; 3],
    /// `ln N` and `ln t` of the previous frame, once there was one.
    last: Option<(f32, f32)>,
}

impl Model {
    /// Covariance of a fresh estimate: the response uncertain by about its own size, the
    /// drift by a few percent a frame.
    const P0: [f32; 3] = [1.0, 0.0, 0.001];
    /// How far the response may move from one frame to the next, as a variance: the front's
    /// response changes as the view moves over other ground.
    const Q_RESPONSE: f32 = 0.05 * 0.05;
    /// How far the drift may move from one frame to the next, as a variance (0.5% a frame):
    /// a view that turns changes what it offers within a few frames.
    const Q_DRIFT: f32 = 0.005 * 0.005;
    /// The variance of a frame's count about the model (0.5%): what one frame's splits and
    /// collapses add besides the view and the tolerance.
    const R: f32 = 0.005 * 0.005;
    /// Largest variance of the response estimate: while the tolerance holds still nothing
    /// is learnt about the response, and the variance must not grow without bound.
    const P_RESPONSE_MAX: f32 = 1.0;

    fn new() -> Self {
        Self {
            response: Regulator::PRIOR_RESPONSE,
            drift: 0.0,
            p: Self::P0,
            last: None,
        }
    }

    /// Takes a frame's `ln N` at `ln t` and updates the estimates from its change since the
    /// previous frame: a Kalman filter over `Δ ln N = response · (-Δ ln t) + drift`, both
    /// estimates random walks; the drift is kept within `max_drift`.
    fn observe(&mut self, y: f32, u: f32, max_drift: f32) {
        let Some((y0, u0)) = self.last.replace((y, u)) else {
            return;
        };
        let (dy, du) = (y - y0, u - u0);
        if !(dy.is_finite() && du.is_finite()) {
            return;
        }
        // The estimates may have moved since the last frame.
        let [p00, p01, p11] = [
            self.p[0] + Self::Q_RESPONSE,
            self.p[1],
            self.p[2] + Self::Q_DRIFT,
        ];
        let phi = [-du, 1.0];
        let pp = [p00 * phi[0] + p01 * phi[1], p01 * phi[0] + p11 * phi[1]];
        let denom = Self::R + phi[0] * pp[0] + phi[1] * pp[1];
        if !(denom.is_finite() && denom > 0.0) {
            return;
        }
        let k = [pp[0] / denom, pp[1] / denom];
        let residual = dy - (self.response * phi[0] + self.drift);
        let response = self.response + k[0] * residual;
        let drift = self.drift + k[1] * residual;
        let p = [p00 - k[0] * pp[0], p01 - k[0] * pp[1], p11 - k[1] * pp[1]];
        if !(response.is_finite() && drift.is_finite() && p.iter().all(|x| x.is_finite())) {
            *self = Self {
                last: self.last,
                ..Self::new()
            };
            return;
        }
        self.response = response.clamp(Regulator::MIN_RESPONSE, Regulator::MAX_RESPONSE);
        self.drift = drift.clamp(-max_drift, max_drift);
        // Bounded variances, and a covariance that stays positive semi-definite.
        let p00 = p[0].clamp(0.0, Self::P_RESPONSE_MAX);
        let p11 = p[2].clamp(0.0, Self::P0[2].max(Self::Q_DRIFT));
        let p01 = if p[1] * p[1] <= p00 * p11 { p[1] } else { 0.0 };
        self.p = [p00, p01, p11];
    }
}

impl Regulator {
    /// Share of the count's predicted error, in logarithms, that one frame corrects: 0.4
    /// leaves 60% of it, so an estimate of the response off by a factor of two still
    /// approaches from one side.
    pub const DEFAULT_GAIN: f32 = 0.4;
    /// Relative error of the predicted count within which the tolerance holds: 1%.
    pub const DEFAULT_DEAD_BAND: f32 = 0.01;
    /// Largest change of the tolerance in one frame, as a ratio: 15%.
    pub const DEFAULT_MAX_STEP: f32 = 1.15;
    /// How far the smoothed share of collapses waiting for their coarsen morphs moves towards
    /// this frame's in one frame ([`update_settling`](Self::update_settling)): a quarter, so
    /// the waiting collapses a raise of tolerance starts count at first only a little.
    pub const WAITING_SMOOTHING: f32 = 0.25;
    /// Most frames [`with_response_frames`](Self::with_response_frames) takes.
    pub const MAX_RESPONSE_FRAMES: u8 = 8;
    /// The default floor of the tolerance, in pixels.
    pub const DEFAULT_MIN_TOLERANCE: f32 = 0.1;
    /// The default ceiling of the tolerance, in pixels.
    pub const DEFAULT_MAX_TOLERANCE: f32 = 1000.0;
    /// The response assumed before any frame: the count falling as `tolerance^-1`, between a
    /// coarse terrain's 2 and a front near full resolution's fraction.
    pub const PRIOR_RESPONSE: f32 = 1.0;
    /// Least response the regulator estimates: a weaker front's steps are as large as this
    /// one's (and clamped).
    pub const MIN_RESPONSE: f32 = 0.2;
    /// Largest response the regulator estimates.
    pub const MAX_RESPONSE: f32 = 3.0;

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
            model: Model::new(),
            response_frames: 1,
            recent: [0.0; Self::MAX_RESPONSE_FRAMES as usize],
            recent_at: 0,
            recent_len: 0,
            waiting: 0.0,
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

    /// With gain `gain`, the share of the predicted error one frame corrects, clamped to
    /// `0..=1` (not a number keeps the current one). At 1 a step aims at the target itself,
    /// which an estimate that is off overshoots.
    pub fn with_gain(mut self, gain: f32) -> Self {
        if !gain.is_nan() {
            self.gain = gain.clamp(0.0, 1.0);
        }
        self
    }

    /// With a dead band of `relative` error (0.01: while the predicted count stays within 1%
    /// of the target the tolerance holds), clamped to `0..=0.5` (not a number keeps the
    /// current one).
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

    /// For a camera whose count shows a change of tolerance over `frames` frames (at least
    /// 1, at most [`MAX_RESPONSE_FRAMES`](Self::MAX_RESPONSE_FRAMES)): an amortised camera
    /// ([`RefineParams::visit_fraction`]) visits its front once in `1 / visit_fraction`
    /// frames, so the count follows the mean tolerance of that many frames. The regulator
    /// then predicts the count the current tolerance will settle at and regulates that.
    pub fn with_response_frames(mut self, frames: u8) -> Self {
        self.response_frames = frames.clamp(1, Self::MAX_RESPONSE_FRAMES);
        self
    }

    /// The frames a change of tolerance takes to show ([`with_response_frames`](Self::with_response_frames)).
    pub fn response_frames(&self) -> u8 {
        self.response_frames
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

    /// The estimated response of the count to the tolerance: `-d ln N / d ln t`, within
    /// [`MIN_RESPONSE`](Self::MIN_RESPONSE)` ..= `[`MAX_RESPONSE`](Self::MAX_RESPONSE).
    pub fn response(&self) -> f32 {
        self.model.response
    }

    /// The estimated change of the count per frame at a fixed tolerance, as a ratio (1.02:
    /// the view offers 2% more polygons each frame).
    pub fn drift(&self) -> f32 {
        libm::expf(self.model.drift)
    }

    /// Takes the count of active polygons of the frame refined with
    /// [`tolerance`](Self::tolerance) and returns the tolerance for the next frame. For a
    /// camera that refuses splits at its capacity, pass the polygons the front wants:
    /// `stats.active_polygons + 2 * stats.capacity_refusals` (each refused split would have
    /// added up to two).
    pub fn update(&mut self, active_polygons: u32) -> f32 {
        self.update_settling(active_polygons, active_polygons)
    }

    /// [`update`](Self::update) for a camera with geomorphs: `active_polygons` on the screen,
    /// of which `settled_polygons` remain once the collapses waiting for their coarsen
    /// morphs are applied ([`CameraState::settled_polygon_count`](crate::CameraState)).
    ///
    /// Capacity refusals count as in [`update`](Self::update), and in both counts: add
    /// `2 * stats.capacity_refusals` to `active_polygons` and to `settled_polygons` alike.
    /// A refused split is polygons the front wants to keep, not a collapse waiting for its
    /// morph, and the difference of the two counts is read as waiting collapses: added to
    /// `active_polygons` alone, refusals would count only through the waiting share's
    /// smoothing, frames late.
    ///
    /// A raise of tolerance shows in the settled count at once but on the screen only when
    /// the coarsen morphs end (16 frames by default); regulated on the screen's count, the
    /// regulator would keep raising meanwhile and overshoot. It regulates the settled count
    /// plus a smoothed share of the waiting collapses ([`WAITING_SMOOTHING`](
    /// Self::WAITING_SMOOTHING)): a raise shows at once, and a view that keeps collapses
    /// waiting all the time (a forward flight leaves ground behind) still holds the screen's
    /// count at the target.
    pub fn update_settling(&mut self, active_polygons: u32, settled_polygons: u32) -> f32 {
        let before = self.tolerance;
        // One polygon at least: the logarithm of zero would be a step of infinite size.
        let settled = libm::logf(settled_polygons.min(active_polygons).max(1) as f32);
        let waiting = libm::logf(active_polygons.max(1) as f32) - settled;
        if waiting.is_finite() {
            self.waiting += Self::WAITING_SMOOTHING * (waiting - self.waiting);
        }
        let y = settled + self.waiting;
        let u = libm::logf(before);
        let shown = self.remember(u);
        let max_log_step = libm::logf(self.max_step).max(0.0);
        self.model.observe(y, shown, max_log_step);
        // The count once the current tolerance shows in full.
        let expected = y - self.model.response * (u - shown);
        let error = expected - libm::logf(self.target as f32);
        let predicted = error + self.model.drift;
        if libm::fabsf(predicted) > libm::log1pf(self.dead_band) {
            let log_step = (self.gain * error + self.model.drift) / self.model.response;
            let log_step = log_step.clamp(-max_log_step, max_log_step);
            let step = libm::expf(log_step);
            if step.is_finite() && step > 0.0 {
                self.tolerance = self.clamp(self.tolerance * step);
            }
        }
        self.last_step = self.tolerance / before;
        self.tolerance
    }

    /// Keeps `ln t` of this frame and returns the mean over the last
    /// [`response_frames`](Self::response_frames) frames: the tolerance the count shows.
    fn remember(&mut self, u: f32) -> f32 {
        let n = Self::MAX_RESPONSE_FRAMES;
        self.recent_at = (self.recent_at + 1) % n;
        if let Some(slot) = self.recent.get_mut(self.recent_at as usize) {
            *slot = u;
        }
        self.recent_len = (self.recent_len + 1).min(n);
        let frames = self.response_frames.min(self.recent_len).max(1);
        let mut sum = 0.0;
        for k in 0..frames {
            let at = (self.recent_at + n - k) % n;
            sum += self.recent.get(at as usize).copied().unwrap_or(u);
        }
        sum / f32::from(frames)
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
mod tests;
