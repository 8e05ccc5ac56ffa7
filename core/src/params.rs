//! The parameters of a refinement pass ([`RefineParams`]) and their one check
//! ([`RefineParams::validate`], refusing with a [`ParamsError`]).
//!
//! Every entry point that takes parameters ([`CameraState::refine`](crate::CameraState),
//! [`CameraState::lag`](crate::CameraState::lag), [`OctreeCut::select`](crate::OctreeCut))
//! checks them here, through the screen-space test it builds (see `screen`), so the C ABI and
//! the applications pass values through and report core's error.

/// Knobs of [`CameraState::refine`](crate::CameraState::refine).
///
/// Values out of range are refused by every call that takes them, with a [`ParamsError`]
/// naming the field ([`validate`](Self::validate) says which ranges hold).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefineParams {
    /// Screen-space tolerance in pixels: split while a node's error projects larger. A
    /// finite number above 0.
    pub tolerance_px: f32,
    /// Most splits + collapses in one call (amortisation over frames); `u32::MAX` for none.
    pub max_ops: u32,
    /// Share of the active list one call visits (Hoppe's amortised `adapt_refinement`, whose
    /// demos visit a third per frame), above 0 and at most 1. At 1, the default, a call
    /// walks the whole list from its start, so one call settles refinement. Below 1, a call
    /// looks at that share of the list's records (at least one) from where the camera's
    /// previous amortised call stopped, wrapping round at the end; the camera remembers the
    /// place in its own state. A camera visited so converges, while the view holds still,
    /// to the front full passes settle at; a moving view is followed a share per call, so
    /// parts of the front lag by up to `1 / visit_fraction` calls. A camera at its base mesh
    /// (new, reset, or coarsened all the way) visits its whole list whatever this share says
    /// (within [`max_visits`](Self::max_visits)): a new camera settles in one call.
    pub visit_fraction: f32,
    /// Most records of the active list one call looks at, at least 1 (a record looked at
    /// again after an operation counts again, and a call looks at no record twice but so),
    /// however large the share: a work budget per call; any cap makes calls resume where the
    /// last stopped. `u32::MAX`, the default, sets none. A time budget can be built on it by
    /// the caller: measure a call's time per
    /// [`RefineStats::nodes_visited`](crate::RefineStats::nodes_visited) and set this to the
    /// budget over that cost (the cost per visit is steady for a given hierarchy and
    /// machine). Operations are bounded separately by `max_ops`.
    pub max_visits: u32,
    /// Coarsen outside the view frustum.
    pub frustum_culling: bool,
    /// Coarsen where the normal cone faces away from the eye.
    pub backface_culling: bool,
    /// Seconds of the caller's clock since this camera's previous pass: how far its morphs
    /// move in this one (finite, 0 or more). The default is one frame at 60 Hz, so a caller
    /// that does not set it gets morphs that count frames; pass the frame's real time for
    /// morphs that last the same at any frame rate (and 0 for a repeated pass within one
    /// frame).
    pub dt_s: f32,
    /// Seconds a refine morph takes (a split's floating child gliding out of its parent's
    /// position), finite; 0 splits at once. Only a camera with morph memory
    /// ([`CameraConfig::max_morphs`](crate::CameraConfig::max_morphs)) morphs, and not in
    /// its first pass since it was made or [reset](crate::CameraState::reset): nothing was
    /// drawn before it to morph from.
    pub refine_morph_s: f32,
    /// Seconds a coarsen morph takes (the floating child gliding back before its collapse),
    /// finite; 0 collapses at once.
    pub coarsen_morph_s: f32,
    /// Fastest a morphing vertex may glide across the screen, in pixels per second of the
    /// caller's clock (the view's pixels): a morph whose path is long on the screen then
    /// takes longer than its duration, so no vertex slides further per frame than this speed
    /// allows, however far its floating child lies from its parent. The path's screen length
    /// is taken at the larger magnification of its ends each pass, so a morph slows as the
    /// eye comes closer. Infinity (the default) or 0 set no limit: the durations alone, as
    /// Hoppe's morphs (a morph held to no speed at all would never end, so 0 cannot mean
    /// that); a negative value or NaN is refused. A limit trades popping for lag: near the
    /// eye, slow morphs leave the surface coarser for longer, and neighbouring morphs at
    /// different phases can fold triangles over, so the lower the limit, the more the folds
    /// show.
    pub morph_speed_px_s: f32,
    /// How large on the screen a node of a morphing camera may stay, in tolerances: a
    /// visible node also wants its split while its bounding sphere's radius, at the
    /// sphere's distance, projects to more than this many times
    /// [`tolerance_px`](Self::tolerance_px) (its uniform error counts as at least its radius
    /// over this). A split's floating child and its parent both lie within the node's
    /// sphere, so a morph's path on the screen starts at about twice this many tolerances
    /// at most, and each frame of a morph moves a vertex a duration's share of that.
    /// Hoppe's criterion alone leaves large flat nodes near the eye unsplit until their
    /// small error projects to the tolerance, and their floating children then slide
    /// hundreds of pixels in one morph; the bound splits them sooner, at the cost of more
    /// polygons: a lower bound shortens every morph's path on the screen and keeps more
    /// polygons. Applies only to a camera with morph memory and a refine duration, and
    /// scales with the tolerance, so a regulator that moves the tolerance moves it too.
    /// Infinity (the default) or 0 set no bound: Hoppe's criterion alone (a bound of no
    /// tolerances would split every visible node, so 0 cannot mean that); a negative value
    /// or NaN is refused.
    pub morph_radius_tolerances: f32,
    /// How far beyond the view's sides a morphing camera refines, in radians, at least 0
    /// and below π/2: the frustum's side planes turn outwards by this angle
    /// ([`View::widened`](crate::View::widened)), so what turns into view was refined, and
    /// its morphs started, before it shows, instead of splitting from a coarse node at the
    /// screen's edge, where a turning view would otherwise see it pop or glide fast. A view
    /// that turns by less than this angle between two passes shows only ground that the
    /// previous pass refined; the band costs the polygons of the area it adds. Applies as
    /// [`morph_radius_tolerances`](Self::morph_radius_tolerances) does; 0 for none. The
    /// default is 0.15 (about 9 degrees).
    pub morph_guard_rad: f32,
}

/// Hoppe's viewer defaults at 60 frames per second: 32 frames to refine, 16 to coarsen.
const REFINE_MORPH_S: f32 = 32.0 / 60.0;
const COARSEN_MORPH_S: f32 = 16.0 / 60.0;
/// The default screen speed limit of a morphing vertex: none.
const MORPH_SPEED_PX_S: f32 = f32::INFINITY;
/// The default bound on a morphing camera's nodes' screen radius, in tolerances: none.
const MORPH_RADIUS_TOLERANCES: f32 = f32::INFINITY;
/// The default guard band of a morphing camera, in radians.
const MORPH_GUARD_RAD: f32 = 0.15;

impl Default for RefineParams {
    fn default() -> Self {
        Self {
            tolerance_px: 1.0,
            max_ops: u32::MAX,
            visit_fraction: 1.0,
            max_visits: u32::MAX,
            frustum_culling: true,
            backface_culling: true,
            dt_s: 1.0 / 60.0,
            refine_morph_s: REFINE_MORPH_S,
            coarsen_morph_s: COARSEN_MORPH_S,
            morph_speed_px_s: MORPH_SPEED_PX_S,
            morph_radius_tolerances: MORPH_RADIUS_TOLERANCES,
            morph_guard_rad: MORPH_GUARD_RAD,
        }
    }
}

impl RefineParams {
    /// These parameters visiting `fraction` of the active list per call (see
    /// [`visit_fraction`](Self::visit_fraction)).
    pub fn amortised(self, fraction: f32) -> Self {
        Self {
            visit_fraction: fraction,
            ..self
        }
    }

    /// These parameters with morphs off: every split and collapse at once (what a camera
    /// without morph memory always does).
    pub fn without_morphs(self) -> Self {
        Self {
            refine_morph_s: 0.0,
            coarsen_morph_s: 0.0,
            ..self
        }
    }

    /// `Ok` when every field is in range, else the first field that is not, with its value:
    /// - `tolerance_px` finite and above 0;
    /// - `visit_fraction` above 0 and at most 1;
    /// - `max_visits` at least 1;
    /// - `dt_s`, `refine_morph_s`, `coarsen_morph_s` finite and 0 or more;
    /// - `morph_speed_px_s`, `morph_radius_tolerances` 0 or more (infinity allowed: 0 and
    ///   infinity both mean none);
    /// - `morph_guard_rad` 0 or more and below π/2.
    ///
    /// `max_ops` and the culling switches take any value.
    pub fn validate(&self) -> Result<(), ParamsError> {
        let fields = [
            (ParamField::TolerancePx, self.tolerance_px),
            (ParamField::VisitFraction, self.visit_fraction),
            (ParamField::MaxVisits, self.max_visits as f32),
            (ParamField::DtS, self.dt_s),
            (ParamField::RefineMorphS, self.refine_morph_s),
            (ParamField::CoarsenMorphS, self.coarsen_morph_s),
            (ParamField::MorphSpeedPxS, self.morph_speed_px_s),
            (
                ParamField::MorphRadiusTolerances,
                self.morph_radius_tolerances,
            ),
            (ParamField::MorphGuardRad, self.morph_guard_rad),
        ];
        match fields
            .into_iter()
            .find(|&(field, value)| !field.allows(value))
        {
            Some((field, value)) => Err(ParamsError { field, value }),
            None => Ok(()),
        }
    }

    /// Records of an active list of `len` records one call may look at, or `None` for a full
    /// pass from the list's start (a share of 1 and no visit cap). For validated parameters.
    pub(crate) fn visit_cap(&self, len: u32) -> Option<u32> {
        if self.visit_fraction >= 1.0 && self.max_visits == u32::MAX {
            return None;
        }
        let by_share = libm::ceilf(self.visit_fraction * len as f32) as u32;
        Some(by_share.min(self.max_visits).max(1))
    }
}

/// A field of [`RefineParams`] that has a range, as a [`ParamsError`] names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ParamField {
    /// [`RefineParams::tolerance_px`].
    TolerancePx,
    /// [`RefineParams::visit_fraction`].
    VisitFraction,
    /// [`RefineParams::max_visits`].
    MaxVisits,
    /// [`RefineParams::dt_s`].
    DtS,
    /// [`RefineParams::refine_morph_s`].
    RefineMorphS,
    /// [`RefineParams::coarsen_morph_s`].
    CoarsenMorphS,
    /// [`RefineParams::morph_speed_px_s`].
    MorphSpeedPxS,
    /// [`RefineParams::morph_radius_tolerances`].
    MorphRadiusTolerances,
    /// [`RefineParams::morph_guard_rad`].
    MorphGuardRad,
}

impl ParamField {
    /// The field's name in [`RefineParams`] (and in the C ABI's parameters).
    pub const fn name(self) -> &'static str {
        match self {
            Self::TolerancePx => "tolerance_px",
            Self::VisitFraction => "visit_fraction",
            Self::MaxVisits => "max_visits",
            Self::DtS => "dt_s",
            Self::RefineMorphS => "refine_morph_s",
            Self::CoarsenMorphS => "coarsen_morph_s",
            Self::MorphSpeedPxS => "morph_speed_px_s",
            Self::MorphRadiusTolerances => "morph_radius_tolerances",
            Self::MorphGuardRad => "morph_guard_rad",
        }
    }

    /// What the field must hold, in words.
    pub const fn expected(self) -> &'static str {
        match self {
            Self::TolerancePx => "a finite number of pixels above 0",
            Self::VisitFraction => "a share of the active list above 0 and at most 1",
            Self::MaxVisits => "at least 1 record (u32::MAX for no cap)",
            Self::DtS => "a finite number of seconds, 0 or more",
            Self::RefineMorphS | Self::CoarsenMorphS => {
                "a finite number of seconds, 0 or more (0 for no morph)"
            }
            Self::MorphSpeedPxS => {
                "pixels per second, 0 or more (0 or infinity for no limit), not NaN"
            }
            Self::MorphRadiusTolerances => {
                "a number of tolerances, 0 or more (0 or infinity for no bound), not NaN"
            }
            Self::MorphGuardRad => "radians, 0 or more and below pi/2",
        }
    }

    /// Whether `value` is in the field's range ([`RefineParams::validate`]).
    fn allows(self, value: f32) -> bool {
        match self {
            Self::TolerancePx => value.is_finite() && value > 0.0,
            Self::VisitFraction => value > 0.0 && value <= 1.0,
            Self::MaxVisits => value >= 1.0,
            Self::DtS | Self::RefineMorphS | Self::CoarsenMorphS => {
                value.is_finite() && value >= 0.0
            }
            Self::MorphSpeedPxS | Self::MorphRadiusTolerances => value >= 0.0,
            Self::MorphGuardRad => (0.0..core::f32::consts::FRAC_PI_2).contains(&value),
        }
    }
}

/// Why [`RefineParams`] were refused: a field out of its range, and its value (a count
/// such as `max_visits` as a float).
///
/// Two errors are equal when they name the same field and the same value bit for bit, so a
/// NaN equals itself here.
#[derive(Clone, Copy, Debug)]
pub struct ParamsError {
    /// The field out of range.
    pub field: ParamField,
    /// Its value.
    pub value: f32,
}

impl PartialEq for ParamsError {
    fn eq(&self, other: &Self) -> bool {
        self.field == other.field && self.value.to_bits() == other.value.to_bits()
    }
}

impl Eq for ParamsError {}

impl core::fmt::Display for ParamsError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "{} is {}: expected {}",
            self.field.name(),
            self.value,
            self.field.expected()
        )
    }
}

impl core::error::Error for ParamsError {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_the_field_the_value_and_the_range() {
        let e = RefineParams {
            tolerance_px: -1.0,
            ..RefineParams::default()
        }
        .validate();
        let expected = ParamsError {
            field: ParamField::TolerancePx,
            value: -1.0,
        };
        assert_eq!(e, Err(expected));
        let mut text = [0u8; 96];
        let mut w = Writer(&mut text, 0);
        assert_eq!(core::fmt::write(&mut w, format_args!("{expected}")), Ok(()));
        let len = w.1;
        assert_eq!(
            &text[..len],
            b"tolerance_px is -1: expected a finite number of pixels above 0"
        );
    }

    /// A `fmt::Write` into a byte array (the crate has no `String` without `alloc`).
    struct Writer<'a>(&'a mut [u8], usize);
    impl core::fmt::Write for Writer<'_> {
        fn write_str(&mut self, s: &str) -> core::fmt::Result {
            let end = self.1 + s.len();
            let dst = self.0.get_mut(self.1..end).ok_or(core::fmt::Error)?;
            dst.copy_from_slice(s.as_bytes());
            self.1 = end;
            Ok(())
        }
    }
}
