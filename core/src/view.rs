//! What a camera sees: eye point, frustum planes and the pixel scale of the screen-space
//! error criterion.

use glam::{Mat4, Vec3, Vec4};

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
    /// A perspective camera at `eye` looking at `target`, with vertical field of view `fov_y`
    /// (radians), `aspect = width / height`, clip distances `near`/`far` and a viewport
    /// `viewport_height` pixels tall.
    #[allow(clippy::too_many_arguments)]
    pub fn perspective(
        eye: Vec3,
        target: Vec3,
        up: Vec3,
        fov_y: f32,
        aspect: f32,
        near: f32,
        far: f32,
        viewport_height: f32,
    ) -> Self {
        let f = (target - eye).normalize_or_zero();
        let r = f.cross(up).normalize_or_zero();
        let u = r.cross(f);
        let ty = libm::tanf(fov_y * 0.5);
        let tx = ty * aspect;
        let plane = |n: Vec3, through: Vec3| {
            let n = n.normalize_or_zero();
            n.extend(-n.dot(through))
        };
        let planes = [
            plane(r + f * tx, eye),
            plane(-r + f * tx, eye),
            plane(u + f * ty, eye),
            plane(-u + f * ty, eye),
            plane(f, eye + f * near),
            plane(-f, eye + f * far),
        ];
        Self {
            eye,
            planes,
            plane_count: 6,
            pixels_per_radian: viewport_height / (2.0 * ty),
        }
    }

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

    #[test]
    fn perspective_planes_agree_with_the_matrix() {
        let eye = Vec3::new(1.0, 2.0, 3.0);
        let target = Vec3::new(4.0, 1.0, -2.0);
        let a = View::perspective(eye, target, Vec3::Y, 1.0, 1.5, 0.1, 100.0, 600.0);
        let vp = glam::camera::rh::proj::vulkan::perspective(1.0, 1.5, 0.1, 100.0)
            * glam::camera::rh::view::look_at_mat4(eye, target, Vec3::Y);
        let b = View::from_view_projection(vp, eye, a.pixels_per_radian);
        for x in [-20.0f32, -3.0, 0.0, 2.5, 9.0] {
            for y in [-7.0f32, 0.0, 1.0, 4.0] {
                for z in [-30.0f32, -5.0, 0.0, 3.0] {
                    let p = Vec3::new(x, y, z);
                    assert_eq!(a.sphere_visible(p, 0.0), b.sphere_visible(p, 0.0), "{p}");
                }
            }
        }
        assert!(a.sphere_visible(target, 0.0));
        assert!(!a.sphere_visible(eye - (target - eye), 0.5));
    }
}
