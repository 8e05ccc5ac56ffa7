//! Certificates: answers of the refinement criterion that stay true while the view moves a
//! little, so a pass need not read the bounds that gave them.
//!
//! A settled pass asks two questions per active node and almost always gets the same
//! answers: is the node's own split wanted (no: its error projects under the tolerance, or
//! it lies outside the frustum, or it faces away), and, for a stationary child, is its
//! parent's split still wanted (yes: no collapse; or no, and the collapse was refused
//! before). Each answer costs a read of a 32-byte bounds record wherever the hierarchy
//! keeps it, one cache line per question; several cameras' worth of those lines do not fit
//! the caches that one camera's fit, so cameras sharing a hierarchy slow each other down
//! through them. Yet each answer can only change once the view has moved by some distance the
//! visit can compute, so the visit writes into the node's active record the odometer
//! reading up to which its answer holds, and later visits skip the bounds until the
//! odometer gets there.
//!
//! Each camera keeps two odometers, summed in `f64` and rounded up:
//! - **path**: the eye's path length. A node of error `m` at distance `d` from the eye stays
//!   too fine to split while the eye stays farther than `m / t` from its point (`t` the
//!   tolerance in radians): for `d - m / t` of path, by the triangle inequality.
//! - **sweep**: the path plus, per pass, how far any frustum plane moved anywhere in the
//!   hierarchy's bounding box (`|Δn · o + Δw| + Σ |Δn_i| h_i` for a plane `n · x + w`, `o`
//!   and `h` the box's centre and half extents), plus that pass's rounding allowance. A parent
//!   whose split is wanted keeps wanting it while its error still projects over the
//!   tolerance (`m / t - d` of path), its sphere stays inside every plane (the smallest
//!   plane distance plus the radius, of sweep) and, with backface culling, the eye stays
//!   outside the cone's back region (the cone test's margin over its Lipschitz constant
//!   2, of path); the certificate is the least of the three on the sweep odometer, which
//!   grows at least as fast as the path.
//! - A split **not wanted** stays so while any of three reasons stands: the error projects
//!   under the tolerance (path, as above), the sphere lies outside a frustum plane (that
//!   plane's distance past the radius, of sweep), or the cone faces away from the eye (the
//!   test's margin over the Lipschitz constant, of path). (A fourth, a directional error
//!   seen too edge-on, is left uncertified: the three above need only distances to the eye
//!   and to the planes, while this one would need a bound on how fast the angle between
//!   the cone's axis and the line of sight turns as the eye moves; such a visit reads its
//!   bounds.)
//!
//! Each record holds two `f32` certificates, the sign saying which answer and odometer:
//! the own one is positive for "not wanted" until a path reading, negative for "not
//! wanted" until a sweep reading (frustum reasons); the parent's is positive for "wanted"
//! and negative for "not wanted", both until a sweep reading (a slack in path is one in
//! sweep, too). Readings are never negative, so 0 ([`UNKNOWN`]) holds at none, either sign.
//!
//! The margins cover every rounding of the `f32` tests: the errors and the cone compare
//! products of differences from the eye, each rounding by at most 2⁻²⁴ relative, and the
//! margins keep 2⁻¹⁶; the frustum test sums products of coordinates, rounding by at most
//! 2⁻²¹ of the terms' magnitude, and every pass adds 2⁻¹⁹ of that bound to the sweep. So
//! refinement takes exactly the decisions it takes without certificates; a test compares
//! the two frame by frame on a flight that closes in, pulls away and turns.
//!
//! Certificates hold for one tolerance, one set of culling switches and one number of
//! frustum planes; a pass with others forgets them all (one sweep of the active records),
//! as does an eye or a plane that is not finite. Writing a record (a split, a collapse, a
//! reset) forgets its certificates.

use glam::{BVec4A, Vec3, Vec4};

use super::records::{ActiveVertex, UNKNOWN};
use crate::format::SplitBounds;
use crate::hierarchy::HierarchyRecords;
use crate::screen::ScreenTest;

/// Relative margin kept between a distance and the distance at which a test's answer
/// would change; it dwarfs the `f32` tests' rounding (under 2⁻²⁰).
const MARGIN: f64 = 1.0 / (1u32 << 16) as f64;

/// Per pass, the sweep odometer's allowance for the frustum test's rounding, relative to
/// the largest magnitude of its terms (the test rounds by less than 2⁻²¹ of it).
const FRUSTUM_ROUNDING: f64 = 1.0 / (1u32 << 19) as f64;

/// The allowance for `f32` rounding in [`Odometer::plane_slacks`], relative to the terms'
/// magnitude.
const PLANE_ROUNDING: f32 = 1.0 / (1u32 << 19) as f32;

/// Bounds on the cone test's change per unit of eye movement: `|n| + sin α <= 2` for the
/// decoded unit normal (a few ulps over 1).
const CONE_LIPSCHITZ: f64 = 2.01;

/// What the certificates were given under; another key forgets them.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Key {
    tz2_bits: u32,
    radius_error_bits: u32,
    planes: u32,
    frustum: bool,
    backface: bool,
}

/// The odometers of one camera, and the view of its last pass.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Odometer {
    /// Eye path length (rounded up), world units.
    path: f64,
    /// Path plus frustum-plane movement plus rounding allowances (rounded up).
    sweep: f64,
    /// The last pass's eye and planes; `None` before the first pass.
    last: Option<(Vec3, [Vec4; 6])>,
    key: Key,
    /// The reciprocal of the tolerance in radians (`1 / sqrt(tz2)`).
    inv_tolerance: f64,
    /// The last pass's frustum planes transposed, four to a vector (`x`, `y`, `z`, `w`),
    /// and which lanes hold a plane the pass used.
    planes_t: [[Vec4; 4]; 2],
    used: [BVec4A; 2],
}

/// The readings a pass compares certificates with, rounded up to `f32`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Readings {
    pub path: f32,
    pub sweep: f32,
}

/// Whether an own certificate still says the node's split is not wanted: a positive one
/// until the path reads it, a negative one until the sweep reads its magnitude.
#[inline(always)]
pub(crate) fn own_holds(cert: f32, at: Readings) -> bool {
    cert > at.path || -cert > at.sweep
}

/// What a parent certificate still says of the parent's split (both signs count on the
/// sweep): wanted (`Some(true)`, positive), not wanted (`Some(false)`, negative), or
/// nothing (`None`, lapsed).
#[inline(always)]
pub(crate) fn parent_says(cert: f32, at: Readings) -> Option<bool> {
    if cert > at.sweep {
        Some(true)
    } else if -cert > at.sweep {
        Some(false)
    } else {
        None
    }
}

/// The hierarchy's bounding box in `f64` (exact): centre and half extents.
fn box_of(h: &impl HierarchyRecords) -> ([f64; 3], [f64; 3]) {
    let m = h.meta();
    let mut centre = [0.0; 3];
    let mut half = [0.0; 3];
    for k in 0..3 {
        let (lo, hi) = (f64::from(m.bounds_min[k]), f64::from(m.bounds_max[k]));
        centre[k] = (lo + hi) * 0.5;
        half[k] = (hi - lo) * 0.5;
    }
    (centre, half)
}

impl Odometer {
    /// An odometer that has seen no pass.
    pub const fn new() -> Self {
        Self {
            path: 0.0,
            sweep: 0.0,
            last: None,
            key: Key {
                tz2_bits: 0,
                radius_error_bits: 0,
                planes: 0,
                frustum: false,
                backface: false,
            },
            inv_tolerance: 0.0,
            planes_t: [[Vec4::ZERO; 4]; 2],
            used: [BVec4A::FALSE; 2],
        }
    }

    /// Moves to the view of `test` for a pass with its squared tolerance, its share of a
    /// node's radius that counts as uniform error and its culling switches, forgetting every
    /// certificate in `records` when they no longer apply.
    pub fn advance(
        &mut self,
        h: &impl HierarchyRecords,
        test: &ScreenTest,
        records: &mut [ActiveVertex],
    ) -> Readings {
        let view = test.view();
        let (tz2, frustum) = (test.scale2(), test.frustum());
        let planes = (view.plane_count as usize).min(view.planes.len());
        let key = Key {
            tz2_bits: tz2.to_bits(),
            radius_error_bits: test.radius_share().to_bits(),
            planes: planes as u32,
            frustum,
            backface: test.backface(),
        };
        let finite = view.eye.is_finite()
            && view.planes[..planes].iter().all(|p| p.is_finite())
            && tz2.is_finite()
            && tz2 > 0.0;
        let moved = match self.last {
            Some((eye, last_planes)) if finite && key == self.key => {
                let step = distance(view.eye, eye) * (1.0 + 1e-12);
                let swept = if frustum {
                    sweep_of_planes(h, &last_planes[..planes], &view.planes[..planes])
                } else {
                    0.0
                };
                Some((step, step + swept))
            }
            _ => None,
        };
        match moved {
            Some((step, sweep)) => {
                self.path = (self.path + step) * (1.0 + 1e-15);
                self.sweep = (self.sweep + sweep) * (1.0 + 1e-15);
            }
            None => {
                for r in records.iter_mut() {
                    r.own_cert = UNKNOWN;
                    r.parent_cert = UNKNOWN;
                }
                self.path = 0.0;
                self.sweep = 0.0;
                self.key = key;
                self.inv_tolerance = 1.0 / libm::sqrt(f64::from(tz2));
            }
        }
        self.last = finite.then_some((view.eye, view.planes));
        let lane = Vec4::new(0.0, 1.0, 2.0, 3.0);
        for (k, (group, used)) in self.planes_t.iter_mut().zip(&mut self.used).enumerate() {
            *used = (lane + Vec4::splat(4.0 * k as f32)).cmplt(Vec4::splat(planes as f32));
            for (component, c) in group.iter_mut().zip(0..) {
                *component = Vec4::from_array(core::array::from_fn(|l| {
                    view.planes.get(4 * k + l).map_or(0.0, |p| p.to_array()[c])
                }));
            }
        }
        Readings {
            path: round_up(self.path),
            sweep: round_up(self.sweep),
        }
    }

    /// A node's uniform error as the criterion counts it: at least the share of its radius
    /// the key says (see `Criterion::wants_split`, whose product this rounds the same way).
    #[inline(always)]
    fn uniform(&self, b: &SplitBounds) -> f32 {
        b.uni_error
            .max(b.radius * f32::from_bits(self.key.radius_error_bits))
    }

    /// The own certificate of a node whose split the criterion just did not want
    /// ([`own_holds`]); [`UNKNOWN`] when there is no slack.
    pub fn unwanted_own(&self, b: &SplitBounds) -> f32 {
        let slack = self.unwanted_slack(b);
        if slack.path > 0.0 && slack.path >= slack.sweep {
            until(self.path, slack.path)
        } else {
            -until(self.sweep, slack.sweep)
        }
    }

    /// The parent certificate of a parent whose split the criterion just did not want
    /// ([`parent_says`]); [`UNKNOWN`] when there is no slack. Parent certificates count on
    /// the sweep, which grows at least as fast as the path.
    pub fn unwanted_parent(&self, b: &SplitBounds) -> f32 {
        let slack = self.unwanted_slack(b);
        -until(self.sweep, slack.path.max(slack.sweep))
    }

    /// How far the view may move while a node with these bounds certainly does not want its
    /// split, for any of three reasons:
    /// - its errors project under the tolerance (`d - m / t` of path);
    /// - its sphere lies outside a frustum plane (that plane's distance past the radius, of
    ///   sweep);
    /// - its normal cone faces away from the eye (the cone test's margin over its Lipschitz
    ///   constant, of path).
    ///
    /// The first is the common case and needs no more work; the others are looked at only
    /// without it.
    fn unwanted_slack(&self, b: &SplitBounds) -> Slack {
        let Some((eye, _)) = self.last else {
            return Slack::NONE;
        };
        let point = Vec3::from_array(b.point);
        let d = distance(point, eye);
        let m = f64::from(self.uniform(b).max(b.dir_error));
        let too_fine = d * (1.0 - 1e-12) - m * self.inv_tolerance * (1.0 + MARGIN);
        if too_fine > 0.0 {
            return Slack {
                path: too_fine,
                sweep: 0.0,
            };
        }
        let mut slack = Slack {
            path: too_fine,
            sweep: 0.0,
        };
        if self.key.frustum {
            slack.sweep = self.plane_slacks(point, b.radius).outside;
        }
        // Outside a plane already gives a certificate; the cone test costs a decode.
        if self.key.backface && b.cone_sin2 < 1.0 && slack.sweep <= 0.0 {
            let g = self.cone_gap(point, d, b.cone_sin2, b.cone_normal(), MARGIN);
            // Facing away while `vdot > (sin + MARGIN) · d`.
            slack.path = slack.path.max(g / CONE_LIPSCHITZ - MARGIN * d);
        }
        slack
    }

    /// The parent certificate of a parent whose split the criterion just wanted
    /// ([`parent_says`]); [`UNKNOWN`] when there is no slack. `cone_normal` is the decoded
    /// cone axis when the backface test applies.
    pub fn wanted_parent(&self, b: &SplitBounds, cone_normal: Option<[f32; 3]>) -> f32 {
        let Some((eye, _)) = self.last else {
            return UNKNOWN;
        };
        let point = Vec3::from_array(b.point);
        let d = distance(point, eye);
        let has_cone = b.cone_sin2 < 1.0;
        // Which errors decide "wanted" without the cone: both when there is no cone; else
        // only the uniform one (the directional one then depends on the view direction).
        let m = if has_cone {
            self.uniform(b)
        } else {
            self.uniform(b).max(b.dir_error)
        };
        let mut slack = f64::from(m) * self.inv_tolerance * (1.0 - MARGIN) - d * (1.0 + 1e-12);
        if self.key.frustum {
            slack = slack.min(self.plane_slacks(point, b.radius).inside);
        }
        if self.key.backface && has_cone {
            let Some(n) = cone_normal else {
                return UNKNOWN;
            };
            // Not facing away while `vdot <= (sin - MARGIN) · d`.
            let g = self.cone_gap(point, d, b.cone_sin2, n, -MARGIN);
            slack = slack.min(-g / CONE_LIPSCHITZ - MARGIN * d);
        }
        until(self.sweep, slack)
    }

    /// How far a sphere at `p` of radius `r` is inside every plane of the last pass (the
    /// least `n · p + w + r`) and outside one (the largest `-(n · p + w + r)`), rounded
    /// down: computed in `f32` four planes at a time, less `2⁻¹⁹` of the terms' magnitude,
    /// which bounds the evaluation's rounding (under `2⁻²¹` of it) with room to spare.
    fn plane_slacks(&self, p: Vec3, r: f32) -> Planes {
        let mut inside = f32::INFINITY;
        let mut outside = f32::NEG_INFINITY;
        for ([x, y, z, w], used) in self.planes_t.iter().zip(self.used) {
            let rr = Vec4::splat(r);
            let sr = *x * p.x + *y * p.y + *z * p.z + *w + rr;
            let magnitude =
                x.abs() * p.x.abs() + y.abs() * p.y.abs() + z.abs() * p.z.abs() + w.abs() + rr;
            if !magnitude.is_finite() {
                return Planes::NONE;
            }
            let err = magnitude * PLANE_ROUNDING;
            inside = inside.min(Vec4::select(used, sr - err, Vec4::INFINITY).min_element());
            outside = outside.max(Vec4::select(used, -sr - err, Vec4::NEG_INFINITY).max_element());
        }
        Planes {
            inside: f64::from(inside),
            outside: f64::from(outside),
        }
    }

    /// `vdot - (sin + margin) · d` for the cone of axis `n` and `sin² = sin2` at `point`,
    /// `d` away from the last eye, in `f64`: the backface test's answer with a margin. It
    /// changes by at most [`CONE_LIPSCHITZ`] per unit of eye movement.
    fn cone_gap(&self, point: Vec3, d: f64, sin2: f32, n: [f32; 3], margin: f64) -> f64 {
        let eye = self.last.map_or(Vec3::ZERO, |(eye, _)| eye);
        let pe = [
            f64::from(point.x) - f64::from(eye.x),
            f64::from(point.y) - f64::from(eye.y),
            f64::from(point.z) - f64::from(eye.z),
        ];
        let vdot = pe[0] * f64::from(n[0]) + pe[1] * f64::from(n[1]) + pe[2] * f64::from(n[2]);
        vdot - (libm::sqrt(f64::from(sin2)) + margin) * d
    }
}

/// [`Odometer::plane_slacks`]: how far inside every plane, and outside one.
#[derive(Clone, Copy, Debug)]
struct Planes {
    inside: f64,
    outside: f64,
}

impl Planes {
    const NONE: Self = Self {
        inside: f64::NEG_INFINITY,
        outside: f64::NEG_INFINITY,
    };
}

/// Slack of an answer, in eye path and in sweep; not positive where it has none that way.
#[derive(Clone, Copy, Debug)]
struct Slack {
    path: f64,
    sweep: f64,
}

impl Slack {
    const NONE: Self = Self {
        path: 0.0,
        sweep: 0.0,
    };
}

/// How far any of `planes` moved, anywhere in the hierarchy's box, from `last`, plus the
/// pass's rounding allowance for the frustum test (rounded up). Over a box, the largest
/// `|Δn · x + Δw|` is `|Δn · centre + Δw| + Σ |Δn_i| half_i`.
fn sweep_of_planes(h: &impl HierarchyRecords, last: &[Vec4], planes: &[Vec4]) -> f64 {
    let (centre, half) = box_of(h);
    // The largest `|x| + |y| + |z|` of a point in the box.
    let l1: f64 = (0..3).map(|k| centre[k].abs() + half[k]).sum();
    let mut most = 0.0f64;
    let (mut n_max, mut w_max) = (0.0f64, 0.0f64);
    for (a, b) in last.iter().zip(planes) {
        let (a, b) = (a.to_array(), b.to_array());
        let d: [f64; 4] = core::array::from_fn(|k| f64::from(b[k]) - f64::from(a[k]));
        let at_centre = d[0] * centre[0] + d[1] * centre[1] + d[2] * centre[2] + d[3];
        let spread = d[0].abs() * half[0] + d[1].abs() * half[1] + d[2].abs() * half[2];
        most = most.max(at_centre.abs() + spread);
        n_max = n_max.max(b[..3].iter().fold(0.0f64, |m, x| m.max(f64::from(x.abs()))));
        w_max = w_max.max(f64::from(b[3]).abs());
    }
    (most + (n_max * l1 + w_max) * FRUSTUM_ROUNDING) * (1.0 + 1e-12)
}

/// `reading + slack`, rounded down to `f32`; [`UNKNOWN`] when `slack` is not positive (or
/// NaN). Never negative, so that either sign of it encodes a certificate.
fn until(reading: f64, slack: f64) -> f32 {
    if slack > 0.0 {
        round_down(reading + slack * (1.0 - 1e-12))
    } else {
        UNKNOWN
    }
}

/// `|a - b|` in `f64` (the differences of `f32`s are exact there but for far exponents).
fn distance(a: Vec3, b: Vec3) -> f64 {
    let (x, y, z) = (
        f64::from(a.x) - f64::from(b.x),
        f64::from(a.y) - f64::from(b.y),
        f64::from(a.z) - f64::from(b.z),
    );
    libm::sqrt(x * x + y * y + z * z)
}

/// The smallest `f32` not below `x` (`x` non-negative; `∞` past the largest).
fn round_up(x: f64) -> f32 {
    let r = x as f32;
    if f64::from(r) < x {
        f32::from_bits(r.to_bits() + 1)
    } else {
        r
    }
}

/// The largest `f32` not above `x` (`x` positive); [`UNKNOWN`] (0) for a non-finite `x`.
fn round_down(x: f64) -> f32 {
    if !x.is_finite() {
        return UNKNOWN;
    }
    let r = x as f32;
    if f64::from(r) > x {
        f32::from_bits(r.to_bits() - 1)
    } else {
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roundings_go_the_safe_way() {
        for x in [0.0, 1e-30, 0.1, 1.0 / 3.0, 7.0, 1e7 + 0.3, 3.4e38] {
            assert!(f64::from(round_up(x)) >= x, "{x}");
            if x > 0.0 {
                assert!(f64::from(round_down(x)) <= x, "{x}");
            }
        }
        assert_eq!(round_down(f64::INFINITY), UNKNOWN);
        assert_eq!(until(5.0, 0.0), UNKNOWN);
        assert_eq!(until(5.0, f64::NAN), UNKNOWN);
        // UNKNOWN holds at no reading, read as either sign.
        let at = Readings {
            path: 0.0,
            sweep: 0.0,
        };
        assert!(!own_holds(UNKNOWN, at) && !own_holds(-UNKNOWN, at));
        assert_eq!(parent_says(UNKNOWN, at), None);
        assert_eq!(parent_says(-UNKNOWN, at), None);
        assert!(until(5.0, 1.0) < 6.0 && until(5.0, 1.0) > 5.99);
    }
}
