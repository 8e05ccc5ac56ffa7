//! The screen-space test of one call: the view a camera refines against and what a node's
//! error must project under, built once per call from the [`View`] and validated
//! [`RefineParams`].
//!
//! Refinement ([`CameraState::refine`](crate::CameraState::refine)), its certificates,
//! [`CameraState::lag`](crate::CameraState::lag) and the octree cut
//! ([`OctreeCut::select`](crate::OctreeCut::select)) all take their tolerance from here: a
//! node's error `e` at distance `d` projects to `e / d` radians, which is compared with the
//! tolerance in radians, `tolerance_px / pixels_per_radian` (formed in [`ScreenTest::new`],
//! the one place that quotient is computed).

use glam::Vec3;

use crate::format::SplitBounds;
use crate::params::{ParamsError, RefineParams};
use crate::view::View;

/// The screen-space test of one call (see the module docs).
#[derive(Clone, Copy, Debug)]
pub(crate) struct ScreenTest {
    /// The view refined against: the caller's, widened by the guard band for a camera that
    /// morphs ([`RefineParams::morph_guard_rad`]).
    view: View,
    tolerance_px: f32,
    /// The tolerance in radians; infinite for a view without a pixel scale (nothing then
    /// needs refining).
    scale: f32,
    /// The share of a node's bounding radius that counts as uniform error
    /// ([`RefineParams::morph_radius_tolerances`]); 0 for none.
    radius_share: f32,
    frustum: bool,
    backface: bool,
}

impl ScreenTest {
    /// The test of a call against `view` with `params`, for a camera that `morphs` (has
    /// morph memory): the parameters checked ([`RefineParams::validate`]), the view widened
    /// and the radius bound set where refine morphs are on.
    pub fn new(view: &View, params: &RefineParams, morphs: bool) -> Result<Self, ParamsError> {
        params.validate()?;
        let morphing = morphs && params.refine_morph_s > 0.0;
        let bound = params.morph_radius_tolerances;
        let radius_share = if morphing && bound > 0.0 && bound.is_finite() {
            1.0 / bound
        } else {
            0.0
        };
        Ok(Self {
            view: if morphing {
                view.widened(params.morph_guard_rad)
            } else {
                *view
            },
            tolerance_px: params.tolerance_px,
            scale: if view.pixels_per_radian > 0.0 {
                params.tolerance_px / view.pixels_per_radian
            } else {
                f32::INFINITY
            },
            radius_share,
            frustum: params.frustum_culling,
            backface: params.backface_culling,
        })
    }

    /// The test of `tolerance_px` alone (the octree cut's): the default parameters with that
    /// tolerance, for a view that does not morph.
    pub fn of_tolerance(view: &View, tolerance_px: f32) -> Result<Self, ParamsError> {
        let params = RefineParams {
            tolerance_px,
            ..RefineParams::default()
        };
        Self::new(view, &params, false)
    }

    /// A test from its parts, unchecked: for the criterion's comparison with the plain
    /// formulas, which draws scales no tolerance gives.
    #[cfg(test)]
    pub fn from_parts(view: View, scale: f32, radius_share: f32, cull: (bool, bool)) -> Self {
        Self {
            view,
            tolerance_px: scale * view.pixels_per_radian,
            scale,
            radius_share,
            frustum: cull.0,
            backface: cull.1,
        }
    }

    /// The view refined against.
    #[inline]
    pub fn view(&self) -> &View {
        &self.view
    }

    /// The square of the tolerance in radians: a node's squared error is compared with it
    /// times its squared distance.
    #[inline]
    pub fn scale2(&self) -> f32 {
        self.scale * self.scale
    }

    /// The share of a node's bounding radius that counts as uniform error; 0 for none.
    #[inline]
    pub fn radius_share(&self) -> f32 {
        self.radius_share
    }

    /// Whether the call coarsens outside the frustum.
    #[inline]
    pub fn frustum(&self) -> bool {
        self.frustum
    }

    /// Whether the call coarsens where the normal cone faces away.
    #[inline]
    pub fn backface(&self) -> bool {
        self.backface
    }

    /// Whether an error of `error` at `distance` from the eye projects to at most the
    /// tolerance (always, without a pixel scale).
    #[inline]
    pub fn error_fits(&self, error: f32, distance: f32) -> bool {
        self.scale == f32::INFINITY || error <= self.scale * distance
    }

    /// How far `b`'s projected error exceeds the tolerance, in pixels (0 within it).
    #[inline]
    pub fn excess_px(&self, b: &SplitBounds) -> f32 {
        (self.projected_px(b) - self.tolerance_px).max(0.0)
    }

    /// A node's error projected to the screen, in pixels: the larger of its uniform error and
    /// its directional error seen across the view direction, at its distance.
    pub fn projected_px(&self, b: &SplitBounds) -> f32 {
        let pe = Vec3::from_array(b.point) - self.view.eye;
        let d2 = pe.length_squared();
        if d2 <= 0.0 {
            return f32::INFINITY;
        }
        let d = libm::sqrtf(d2);
        let across = if b.cone_sin2 >= 1.0 {
            1.0
        } else {
            let vdot = pe.dot(Vec3::from_array(b.cone_normal())) / d;
            libm::sqrtf((1.0 - vdot * vdot).max(0.0))
        };
        b.uni_error.max(b.dir_error * across) / d * self.view.pixels_per_radian
    }
}
