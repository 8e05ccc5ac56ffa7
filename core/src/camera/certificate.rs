//! Certificates: answers of the refinement criterion that stay true while the view moves a
//! little, so a pass need not read the bounds that gave them.
//!
//! A settled pass asks two questions per active node and almost always gets the same
//! answers: the node's own split is not wanted (its error projects under the tolerance),
//! and, for a stationary child, its parent's split still is (so no collapse). Each answer
//! costs a read of a 32-byte bounds record wherever the hierarchy keeps it, one cache line
//! per question; four cameras' worth of those lines no longer fit the caches that one
//! camera's fit, which is what made four cameras cost more than four times one. Yet each
//! answer can only change once the view has moved by some distance the visit can compute,
//! so the visit writes into the node's active record the odometer reading up to which its
//! answer holds, and later visits skip the bounds until the odometer gets there.
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

use glam::{Vec3, Vec4};

use super::ActiveVertex;
use crate::hierarchy::Hierarchy;
use crate::records::SplitBounds;
use crate::view::View;

/// Relative margin kept between a distance and the distance at which a test's answer
/// would change; it dwarfs the `f32` tests' rounding (under 2⁻²⁰).
const MARGIN: f64 = 1.0 / (1u32 << 16) as f64;

/// Per pass, the sweep odometer's allowance for the frustum test's rounding, relative to
/// the largest magnitude of its terms (the test rounds by less than 2⁻²¹ of it).
const FRUSTUM_ROUNDING: f64 = 1.0 / (1u32 << 19) as f64;

/// Bounds on the cone test's change per unit of eye movement: `|n| + sin α <= 2` for the
/// decoded unit normal (a few ulps over 1).
const CONE_LIPSCHITZ: f64 = 2.01;

/// What the certificates were given under; another key forgets them.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Key {
    tz2_bits: u32,
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
    /// Tolerance in radians (`sqrt(tz2)`).
    tolerance: f64,
}

/// The readings a pass compares certificates with, rounded up to `f32`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Readings {
    pub path: f32,
    pub sweep: f32,
}

/// The hierarchy's bounding box in `f64` (exact): centre and half extents.
fn box_of(h: &Hierarchy<'_>) -> ([f64; 3], [f64; 3]) {
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
                planes: 0,
                frustum: false,
                backface: false,
            },
            tolerance: 0.0,
        }
    }

    /// Moves to `view` for a pass with squared tolerance `tz2` and the given culling
    /// switches, forgetting every certificate in `records` when they no longer apply.
    pub fn advance(
        &mut self,
        h: &Hierarchy<'_>,
        view: &View,
        tz2: f32,
        frustum: bool,
        backface: bool,
        records: &mut [ActiveVertex],
    ) -> Readings {
        let planes = (view.plane_count as usize).min(view.planes.len());
        let key = Key {
            tz2_bits: tz2.to_bits(),
            planes: planes as u32,
            frustum,
            backface,
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
                    r.sure_until = f32::NEG_INFINITY;
                    r.kept_until = f32::NEG_INFINITY;
                }
                self.path = 0.0;
                self.sweep = 0.0;
                self.key = key;
                self.tolerance = libm::sqrt(f64::from(tz2));
            }
        }
        self.last = finite.then_some((view.eye, view.planes));
        Readings {
            path: round_up(self.path),
            sweep: round_up(self.sweep),
        }
    }

    /// The path reading up to which a node with these bounds certainly does not want its
    /// split (its errors project under the tolerance); `-∞` when there is no slack.
    pub fn sure_until(&self, b: &SplitBounds) -> f32 {
        let Some((eye, _)) = self.last else {
            return f32::NEG_INFINITY;
        };
        let d = distance(Vec3::from_array(b.point), eye);
        let m = f64::from(b.uni_error.max(b.dir_error));
        let slack = d * (1.0 - 1e-12) - m / self.tolerance * (1.0 + MARGIN);
        until(self.path, slack)
    }

    /// The sweep reading up to which a node with these bounds, whose split the criterion
    /// just wanted, certainly keeps wanting it; `-∞` when there is no slack.
    pub fn kept_until(&self, b: &SplitBounds, cone_normal: Option<[f32; 3]>) -> f32 {
        let Some((eye, planes)) = self.last else {
            return f32::NEG_INFINITY;
        };
        let point = Vec3::from_array(b.point);
        let d = distance(point, eye);
        let has_cone = b.cone_sin2 < 1.0;
        // Which errors decide "wanted" without the cone: both when there is no cone; else
        // only the uniform one (the directional one then depends on the view direction).
        let m = if has_cone {
            b.uni_error
        } else {
            b.uni_error.max(b.dir_error)
        };
        let mut slack = f64::from(m) / self.tolerance * (1.0 - MARGIN) - d * (1.0 + 1e-12);
        if self.key.frustum {
            let r = f64::from(b.radius);
            for p in &planes[..self.key.planes as usize] {
                let (n, w) = (p.truncate(), f64::from(p.w));
                let s = f64::from(n.x) * f64::from(point.x)
                    + f64::from(n.y) * f64::from(point.y)
                    + f64::from(n.z) * f64::from(point.z)
                    + w;
                let magnitude = f64::from(n.abs().dot(point.abs())) + w.abs() + r;
                slack = slack.min(s + r - magnitude * 1e-12);
            }
        }
        if self.key.backface && has_cone {
            let Some(n) = cone_normal else {
                return f32::NEG_INFINITY;
            };
            let pe = [
                f64::from(point.x) - f64::from(eye.x),
                f64::from(point.y) - f64::from(eye.y),
                f64::from(point.z) - f64::from(eye.z),
            ];
            let vdot = pe[0] * f64::from(n[0]) + pe[1] * f64::from(n[1]) + pe[2] * f64::from(n[2]);
            let sin = libm::sqrt(f64::from(b.cone_sin2));
            // Not facing away while vdot <= (sin - MARGIN) · d.
            let g = vdot - (sin - MARGIN) * d;
            slack = slack.min(-g / CONE_LIPSCHITZ - MARGIN * d);
        }
        until(self.sweep, slack)
    }
}

/// How far any of `planes` moved, anywhere in the hierarchy's box, from `last`, plus the
/// pass's rounding allowance for the frustum test (rounded up). Over a box, the largest
/// `|Δn · x + Δw|` is `|Δn · centre + Δw| + Σ |Δn_i| half_i`.
fn sweep_of_planes(h: &Hierarchy<'_>, last: &[Vec4], planes: &[Vec4]) -> f64 {
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

/// `reading + slack`, rounded down to `f32`; `-∞` when `slack` is not positive (or NaN).
fn until(reading: f64, slack: f64) -> f32 {
    if slack > 0.0 {
        round_down(reading + slack * (1.0 - 1e-12))
    } else {
        f32::NEG_INFINITY
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

/// The largest `f32` not above `x` (`x` positive); `-∞` for a non-finite `x`.
fn round_down(x: f64) -> f32 {
    if !x.is_finite() {
        return f32::NEG_INFINITY;
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
        assert_eq!(round_down(f64::INFINITY), f32::NEG_INFINITY);
        assert_eq!(until(5.0, 0.0), f32::NEG_INFINITY);
        assert_eq!(until(5.0, f64::NAN), f32::NEG_INFINITY);
        assert!(until(5.0, 1.0) < 6.0 && until(5.0, 1.0) > 5.99);
    }
}
