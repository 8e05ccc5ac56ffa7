//! What a camera sees: eye point, frustum planes and the pixel scale of the screen-space
//! error criterion. A [`LookAt`] describes a perspective camera; it owns the checks of such
//! a description ([`LookAt::validate`], refusing with a [`ViewError`]) and the pixel scale
//! of a viewport ([`LookAt::pixels_per_radian`]).

use glam::camera::rh::{proj, view::look_at_mat4};
use glam::{Mat4, Vec3, Vec4};

/// A perspective camera looking from `eye` at `target`: what the GPU needs (a
/// view-projection matrix) and what refinement needs (a [`View`] with the same frustum and
/// the viewport's pixel scale) from one description, so the two never disagree.
///
/// ```
/// use caveclod_core::glam::Vec3;
/// use caveclod_core::LookAt;
/// let look = LookAt {
///     eye: Vec3::new(0.0, 2.0, 10.0),
///     target: Vec3::ZERO,
///     up: Vec3::Y,
///     fov_y: 1.0,
///     near: 0.1,
///     far: 100.0,
/// };
/// let view = look.view(1280, 720);
/// assert!(view.sphere_visible(Vec3::ZERO, 0.0));
/// assert!(!view.sphere_visible(Vec3::new(0.0, 2.0, 20.0), 1.0)); // behind the eye
/// let _draw = look.view_projection(1280.0 / 720.0);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LookAt {
    /// Eye point.
    pub eye: Vec3,
    /// Point looked at.
    pub target: Vec3,
    /// Up direction.
    pub up: Vec3,
    /// Vertical field of view, radians.
    pub fov_y: f32,
    /// Near clip distance.
    pub near: f32,
    /// Far clip distance.
    pub far: f32,
}

impl LookAt {
    /// The view-projection matrix for a viewport of `aspect = width / height`: right-handed
    /// y-up view space, Vulkan clip space (y down, depth 0..1).
    pub fn view_projection(&self, aspect: f32) -> Mat4 {
        proj::vulkan::perspective(self.fov_y, aspect, self.near, self.far)
            * look_at_mat4(self.eye, self.target, self.up)
    }

    /// Pixels per radian at the centre of a viewport `viewport_height` pixels high:
    /// `viewport_height / (2 tan(fov_y / 2))`, the scale that turns the pixel tolerance into
    /// an angle.
    pub fn pixels_per_radian(&self, viewport_height: u32) -> f32 {
        viewport_height as f32 / (2.0 * libm::tanf(self.fov_y * 0.5))
    }

    /// The refinement view: the frustum of [`view_projection`](Self::view_projection) and
    /// the pixels per radian of a viewport `viewport_width` × `viewport_height` pixels
    /// ([`pixels_per_radian`](Self::pixels_per_radian)). Unchecked: see
    /// [`checked_view`](Self::checked_view).
    pub fn view(&self, viewport_width: u32, viewport_height: u32) -> View {
        let aspect = viewport_width as f32 / viewport_height.max(1) as f32;
        self.view_for_aspect(aspect, viewport_height)
    }

    /// [`view`](Self::view) for a viewport given by its `aspect` (width / height) and its
    /// height in pixels.
    pub fn view_for_aspect(&self, aspect: f32, viewport_height: u32) -> View {
        View::from_view_projection(
            self.view_projection(aspect),
            self.eye,
            self.pixels_per_radian(viewport_height),
        )
    }

    /// `Ok` for a camera that looks somewhere: every field finite, `fov_y` in (0, π),
    /// `near` above 0, `far` beyond `near`, `target` away from `eye`, and `up` not parallel
    /// to the view direction; else the first rule broken.
    pub fn validate(&self) -> Result<(), ViewError> {
        let points = [("eye", self.eye), ("target", self.target), ("up", self.up)];
        if let Some((field, _)) = points.iter().find(|(_, p)| !p.is_finite()) {
            return Err(ViewError::NotFinite { field });
        }
        let scalars = [
            ("fov_y", self.fov_y),
            ("near", self.near),
            ("far", self.far),
        ];
        if let Some((field, _)) = scalars.iter().find(|(_, x)| !x.is_finite()) {
            return Err(ViewError::NotFinite { field });
        }
        if !(self.fov_y > 0.0 && self.fov_y < core::f32::consts::PI) {
            return Err(ViewError::FieldOfView { fov_y: self.fov_y });
        }
        if self.near <= 0.0 {
            return Err(ViewError::Near { near: self.near });
        }
        if self.far <= self.near {
            return Err(ViewError::Far {
                near: self.near,
                far: self.far,
            });
        }
        let forward = self.target - self.eye;
        if forward.length_squared() <= 0.0 {
            return Err(ViewError::EyeAtTarget);
        }
        if forward.cross(self.up).length_squared() <= 0.0 {
            return Err(ViewError::UpAlongView);
        }
        Ok(())
    }

    /// [`view_for_aspect`](Self::view_for_aspect) for a checked camera
    /// ([`validate`](Self::validate)) and viewport: `aspect` a finite number above 0,
    /// `viewport_height` at least 1.
    pub fn checked_view(&self, aspect: f32, viewport_height: u32) -> Result<View, ViewError> {
        self.validate()?;
        if !(aspect.is_finite() && aspect > 0.0) {
            return Err(ViewError::Aspect { aspect });
        }
        if viewport_height == 0 {
            return Err(ViewError::ViewportHeight);
        }
        Ok(self.view_for_aspect(aspect, viewport_height))
    }
}

/// Why a [`LookAt`] (with its viewport) describes no view: the rule it breaks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ViewError {
    /// A point (`eye`, `target`, `up`) has a coordinate, or a scalar (`fov_y`, `near`,
    /// `far`) a value, that is not a finite number.
    NotFinite {
        /// The field.
        field: &'static str,
    },
    /// The vertical field of view is not in (0, π).
    FieldOfView {
        /// Its value, radians.
        fov_y: f32,
    },
    /// The near distance is not above 0.
    Near {
        /// Its value.
        near: f32,
    },
    /// The far distance is not beyond the near one.
    Far {
        /// The near distance.
        near: f32,
        /// The far distance.
        far: f32,
    },
    /// `target` is `eye`: the view has no direction.
    EyeAtTarget,
    /// `up` is zero or parallel to the view direction: the view's roll is undefined.
    UpAlongView,
    /// The viewport's width / height is not a finite number above 0.
    Aspect {
        /// Its value.
        aspect: f32,
    },
    /// The viewport is 0 pixels high.
    ViewportHeight,
}

impl core::fmt::Display for ViewError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::NotFinite { field } => {
                write!(f, "{field} is not finite: expected finite numbers")
            }
            Self::FieldOfView { fov_y } => {
                write!(f, "fov_y is {fov_y}: expected radians above 0 and below pi")
            }
            Self::Near { near } => write!(f, "near is {near}: expected a distance above 0"),
            Self::Far { near, far } => {
                write!(f, "far is {far}: expected a distance beyond near ({near})")
            }
            Self::EyeAtTarget => write!(f, "eye and target are one point: no view direction"),
            Self::UpAlongView => {
                write!(
                    f,
                    "up is zero or parallel to the view direction (target - eye)"
                )
            }
            Self::Aspect { aspect } => {
                write!(
                    f,
                    "aspect is {aspect}: expected a finite width / height above 0"
                )
            }
            Self::ViewportHeight => write!(f, "viewport_height is 0: expected at least 1 pixel"),
        }
    }
}

impl core::error::Error for ViewError {}

/// A camera's view for refinement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// Eye point, world space.
    pub eye: Vec3,
    /// Frustum planes `(n, d)` with `n` unit length pointing inside: a point `p` is inside
    /// when `n · p + d >= 0`.
    pub planes: [Vec4; 6],
    /// How many of `planes` are used.
    pub plane_count: u32,
    /// Pixels per radian at the screen centre: `viewport_height / (2 tan(fov_y / 2))`.
    pub pixels_per_radian: f32,
}

impl View {
    /// From a view-projection matrix with Vulkan's clip space (depth 0..1), as
    /// `glam::camera::rh::proj::vulkan::perspective(..) * view` builds it; planes by Gribb & Hartmann.
    pub fn from_view_projection(view_projection: Mat4, eye: Vec3, pixels_per_radian: f32) -> Self {
        let m = view_projection.transpose();
        let (r0, r1, r2, r3) = (m.x_axis, m.y_axis, m.z_axis, m.w_axis);
        let norm = |p: Vec4| {
            let l = p.truncate().length();
            if l > 0.0 {
                p / l
            } else {
                p
            }
        };
        let planes = [
            norm(r3 + r0),
            norm(r3 - r0),
            norm(r3 + r1),
            norm(r3 - r1),
            norm(r2),
            norm(r3 - r2),
        ];
        Self {
            eye,
            planes,
            plane_count: 6,
            pixels_per_radian,
        }
    }

    /// No culling planes: refinement by screen-space error alone.
    pub fn without_frustum(eye: Vec3, pixels_per_radian: f32) -> Self {
        Self {
            eye,
            planes: [Vec4::ZERO; 6],
            plane_count: 0,
            pixels_per_radian,
        }
    }

    /// This view with each side plane through the eye turned outwards by `angle` radians
    /// about the eye, so the frustum reaches `angle` further on every side (a guard band:
    /// what turns into view was refined before it shows). Planes that do not pass through
    /// the eye (an orthographic view's), the near and far planes, a view without a near
    /// plane, and an angle that is not positive and finite are left as they are.
    pub fn widened(&self, angle: f32) -> Self {
        let mut out = *self;
        let used = (self.plane_count as usize).min(6);
        if !(angle > 0.0 && angle.is_finite()) || used < 5 {
            return out;
        }
        let forward = self.planes[4].truncate();
        let (sin, cos) = (libm::sinf(angle), libm::cosf(angle));
        let reach = 1e-4 * (1.0 + self.eye.abs().max_element());
        for p in &mut out.planes[..4] {
            let n = p.truncate();
            if (n.dot(self.eye) + p.w).abs() > reach {
                continue;
            }
            // The plane's edge direction towards the view direction, in the plane.
            let edge = (forward - n * n.dot(forward)).normalize_or_zero();
            if edge == Vec3::ZERO {
                continue;
            }
            let turned = (n * cos + edge * sin).normalize_or_zero();
            *p = turned.extend(-turned.dot(self.eye));
        }
        out
    }

    /// `true` if the sphere lies at least partly inside every plane.
    #[inline]
    pub fn sphere_visible(&self, centre: Vec3, radius: f32) -> bool {
        let n = (self.plane_count as usize).min(6);
        self.planes[..n]
            .iter()
            .all(|p| p.truncate().dot(centre) + p.w >= -radius)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tests' look: off every axis, 1 radian high.
    fn look() -> LookAt {
        LookAt {
            eye: Vec3::new(1.0, 2.0, 3.0),
            target: Vec3::new(4.0, 1.0, -2.0),
            up: Vec3::Y,
            fov_y: 1.0,
            near: 0.1,
            far: 100.0,
        }
    }

    /// A point just past a side of the view is inside the widened view when it is less than
    /// the angle past it, and outside when it is more; the near and far planes stay, and
    /// a view whose planes do not pass through the eye is left as it is.
    #[test]
    fn a_widened_view_reaches_the_angle_further_on_every_side() {
        let look = look();
        let view = look.view(900, 600);
        let angle = 0.1;
        let wide = view.widened(angle);
        assert_eq!(wide.planes[4..], view.planes[4..]);
        let forward = (look.target - look.eye).normalize();
        let right = forward.cross(Vec3::Y).normalize();
        let up = right.cross(forward);
        let half_y = look.fov_y / 2.0;
        let half_x = libm::atanf(libm::tanf(half_y) * 1.5);
        for (axis, half) in [
            (right, half_x),
            (-right, half_x),
            (up, half_y),
            (-up, half_y),
        ] {
            let at = |a: f32| look.eye + (forward * libm::cosf(a) + axis * libm::sinf(a)) * 10.0;
            assert!(view.sphere_visible(at(half - 0.01), 0.0));
            assert!(!view.sphere_visible(at(half + 0.05), 0.0));
            assert!(wide.sphere_visible(at(half + 0.05), 0.0));
            assert!(wide.sphere_visible(at(half + angle - 0.01), 0.0));
            assert!(!wide.sphere_visible(at(half + angle + 0.01), 0.0));
        }
        let unchanged = View::without_frustum(look.eye, 100.0);
        assert_eq!(unchanged.widened(angle), unchanged);
        assert_eq!(view.widened(0.0), view);
        assert_eq!(view.widened(f32::NAN), view);
        // Planes away from the eye (an orthographic view's) stay.
        let mut ortho = view;
        for p in &mut ortho.planes[..4] {
            p.w += 1.0;
        }
        assert_eq!(ortho.widened(angle), ortho);
    }

    /// Every rule of a camera description is checked, the first broken one named; a sound
    /// description gives the unchecked view bit for bit.
    #[test]
    fn a_look_at_is_checked_rule_by_rule() {
        let ok = look();
        assert_eq!(ok.validate(), Ok(()));
        assert_eq!(ok.checked_view(1.5, 600), Ok(ok.view(900, 600)));
        let nan = f32::NAN;
        let cases = [
            (
                LookAt {
                    eye: Vec3::new(nan, 0.0, 0.0),
                    ..ok
                },
                ViewError::NotFinite { field: "eye" },
            ),
            (
                LookAt {
                    target: Vec3::INFINITY,
                    ..ok
                },
                ViewError::NotFinite { field: "target" },
            ),
            (
                LookAt {
                    up: Vec3::NAN,
                    ..ok
                },
                ViewError::NotFinite { field: "up" },
            ),
            (
                LookAt {
                    far: f32::INFINITY,
                    ..ok
                },
                ViewError::NotFinite { field: "far" },
            ),
            (
                LookAt { fov_y: 0.0, ..ok },
                ViewError::FieldOfView { fov_y: 0.0 },
            ),
            (
                LookAt { fov_y: 3.2, ..ok },
                ViewError::FieldOfView { fov_y: 3.2 },
            ),
            (LookAt { near: 0.0, ..ok }, ViewError::Near { near: 0.0 }),
            (
                LookAt { far: 0.1, ..ok },
                ViewError::Far {
                    near: 0.1,
                    far: 0.1,
                },
            ),
            (
                LookAt {
                    target: ok.eye,
                    ..ok
                },
                ViewError::EyeAtTarget,
            ),
            (
                LookAt {
                    up: ok.target - ok.eye,
                    ..ok
                },
                ViewError::UpAlongView,
            ),
            (
                LookAt {
                    up: Vec3::ZERO,
                    ..ok
                },
                ViewError::UpAlongView,
            ),
        ];
        for (look, error) in cases {
            assert_eq!(look.validate(), Err(error), "{look:?}");
            assert_eq!(look.checked_view(1.0, 100), Err(error));
        }
        assert_eq!(
            ok.checked_view(0.0, 100),
            Err(ViewError::Aspect { aspect: 0.0 })
        );
        assert!(matches!(
            ok.checked_view(nan, 100),
            Err(ViewError::Aspect { .. })
        ));
        assert_eq!(ok.checked_view(1.0, 0), Err(ViewError::ViewportHeight));
    }

    #[test]
    fn look_at_frustum_matches_its_matrix() {
        let look = look();
        let view = look.view(900, 600);
        assert!((view.pixels_per_radian - 600.0 / (2.0 * libm::tanf(0.5))).abs() < 1e-3);
        let m = look.view_projection(1.5);
        // A point is inside the planes exactly when its clip coordinates are inside the
        // Vulkan clip volume (away from the boundary, where rounding could differ).
        for x in [-20.0f32, -3.0, 0.0, 2.5, 9.0] {
            for y in [-7.0f32, 0.0, 1.0, 4.0] {
                for z in [-30.0f32, -5.0, 0.0, 3.0] {
                    let p = Vec3::new(x, y, z);
                    let c = m * p.extend(1.0);
                    let inside = c.w > 0.0
                        && c.x.abs() <= c.w
                        && c.y.abs() <= c.w
                        && c.z >= 0.0
                        && c.z <= c.w;
                    assert_eq!(view.sphere_visible(p, 0.0), inside, "{p}");
                }
            }
        }
        assert!(view.sphere_visible(look.target, 0.0));
        assert!(!view.sphere_visible(look.eye - (look.target - look.eye), 0.5));
    }
}
