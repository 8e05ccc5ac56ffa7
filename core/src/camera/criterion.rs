//! The refinement criterion (Hoppe's `qrefine`): whether a node's split is wanted from
//! where a view looks, its bounds against the frustum, the normal cone and the screen-space
//! tolerance; [`Criterion`] answers it for a pass (see `refine`) and for the morphs, in the
//! form of the call's [`ScreenTest`] that a pass asks fastest.

use glam::{Vec3, Vec4};

use crate::format::SplitBounds;
use crate::screen::ScreenTest;
#[cfg(doc)]
use crate::view::View;

/// `rhs` scaled just below itself: a squared error under `rhs · SHY` stays under any product
/// of `rhs` with a positive factor after both products round (see [`Criterion::wants_split`]).
const SHY: f32 = 1.0 - 1.0 / (1u32 << 20) as f32;

/// The refinement criterion: does a node with these bounds want its split?
///
/// Most visits ask about a node whose errors project below the tolerance (the front stays
/// where refinement left it), so that test comes first and reads only the point and the
/// errors; the frustum and the normal cone are looked at only when it passes. The frustum
/// planes are kept transposed, four to a vector, so a sphere meets four planes in one test.
/// The answers are those of the plain formulas, bit for bit: the same products and sums in
/// the same order, and an early "no" only where the full test cannot say "yes".
pub(super) struct Criterion {
    eye: Vec3,
    /// The view's pixels per radian (0 for a view without a screen).
    pub(super) pixels_per_radian: f32,
    /// The view direction (the near plane's normal), or zero for a view without one.
    forward: Vec3,
    tz2: f32,
    /// The square of the share of a node's bounding radius that counts as uniform error
    /// ([`ScreenTest::radius_share`]); 0 for none.
    radius2: f32,
    /// Whether `radius2` is positive: without the bound (the default), the split test takes
    /// the uniform error alone and never multiplies the radius in (a branch every visit
    /// takes the same way). The radius term is `radius² · 0 = 0` then, never above the
    /// squared error of a validated node (finite, non-negative), so the answers are the same.
    radius_bound: bool,
    /// Plane `k`'s `x`, `y`, `z`, `w` in lane `k % 4` of `planes[k / 4][0..4]`; the lanes of
    /// planes the view does not use always pass (`0 · p + ∞`).
    planes: [[Vec4; 4]; 2],
    frustum: bool,
    /// Whether the pass culls by the normal cone (the pass reads it for a parent's certificate).
    pub(super) backface: bool,
}

impl Criterion {
    pub(super) fn new(test: &ScreenTest) -> Self {
        let view = test.view();
        let radius_share = test.radius_share();
        let mut planes = [[Vec4::ZERO, Vec4::ZERO, Vec4::ZERO, Vec4::INFINITY]; 2];
        let used = (view.plane_count as usize).min(view.planes.len());
        for (k, p) in view.planes[..used].iter().enumerate() {
            for (component, value) in planes[k / 4].iter_mut().zip(p.to_array()) {
                component[k % 4] = value;
            }
        }
        Self {
            eye: view.eye,
            pixels_per_radian: view.pixels_per_radian,
            forward: match view.planes.get(4) {
                Some(near) if view.plane_count > 4 => near.truncate(),
                _ => Vec3::ZERO,
            },
            tz2: test.scale2(),
            radius2: radius_share * radius_share,
            radius_bound: radius_share * radius_share > 0.0,
            planes,
            frustum: test.frustum(),
            backface: test.backface(),
        }
    }

    /// [`View::sphere_visible`] with the transposed planes.
    #[inline(always)]
    fn sphere_visible(&self, c: Vec3, radius: f32) -> bool {
        let low = Vec4::splat(-radius);
        self.planes.iter().all(|[x, y, z, w]| {
            let s = *x * c.x + *y * c.y + *z * c.z + *w;
            s.cmpge(low).all()
        })
    }

    /// Most pixels a short move of a point at `p` covers per unit of its length: the
    /// perspective's magnification `pixels_per_radian · distance / depth²`, which grows
    /// towards the screen's edges (at the centre, `pixels_per_radian / distance`). Zero
    /// behind the eye; without a view direction, the centre's figure.
    #[inline]
    pub(super) fn magnification(&self, p: Vec3) -> f32 {
        let pe = p - self.eye;
        let distance = pe.length();
        if self.forward == Vec3::ZERO {
            return self.pixels_per_radian / distance;
        }
        let depth = pe.dot(self.forward);
        if depth > 0.0 {
            self.pixels_per_radian * distance / (depth * depth)
        } else {
            0.0
        }
    }

    /// Refinement's visibility of a node: its sphere inside the frustum and its normal cone
    /// not facing away (each where the pass culls by it), as Hoppe's `is_visible`.
    #[inline]
    pub(super) fn visible(&self, b: &SplitBounds) -> bool {
        let p = Vec3::from_array(b.point);
        if self.frustum && !self.sphere_visible(p, b.radius) {
            return false;
        }
        if !self.backface || b.cone_sin2 >= 1.0 {
            return true;
        }
        let pe = p - self.eye;
        let vdot = pe.dot(Vec3::from_array(b.cone_normal()));
        !(vdot > 0.0 && vdot * vdot > pe.length_squared() * b.cone_sin2)
    }

    #[inline(always)]
    pub(super) fn wants_split(&self, b: &SplitBounds) -> bool {
        let p = Vec3::from_array(b.point);
        let pe = p - self.eye;
        let pem2 = pe.length_squared();
        let rhs = self.tz2 * pem2;
        let uni2 = if self.radius_bound {
            (b.uni_error * b.uni_error).max(b.radius * b.radius * self.radius2)
        } else {
            b.uni_error * b.uni_error
        };
        let dir2 = b.dir_error * b.dir_error;
        // Neither error projects to the tolerance: every branch below answers no. The
        // directional test compares dir2 · (pem2 - vdot²) with rhs · pem2; the left side
        // rounds to at most dir2 · pem2, which stays under rhs · pem2 when dir2 is a relative
        // 2^-20 under rhs (each product rounds by at most 2^-24).
        if uni2 < rhs && dir2 < rhs * SHY {
            return false;
        }
        if self.frustum && !self.sphere_visible(p, b.radius) {
            return false;
        }
        let big_uniform = uni2 >= rhs;
        if b.cone_sin2 >= 1.0 {
            // No cone: no backface test, and the directional error counts in full.
            return big_uniform || dir2 >= rhs;
        }
        if !self.backface && b.dir_error <= 0.0 {
            return big_uniform;
        }
        let vdot = pe.dot(Vec3::from_array(b.cone_normal()));
        if self.backface && vdot > 0.0 && vdot * vdot > pem2 * b.cone_sin2 {
            return false;
        }
        big_uniform || dir2 * (pem2 - vdot * vdot) >= rhs * pem2
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::view::LookAt;

    /// The criterion as plainly written: the frustum through [`View::sphere_visible`], then the
    /// screen-space error and the cone, with no early answer.
    fn plain(t: &ScreenTest, b: &SplitBounds) -> bool {
        let (view, tz2, re) = (t.view(), t.scale2(), t.radius_share());
        let pt = Vec3::from_array(b.point);
        if t.frustum() && !view.sphere_visible(pt, b.radius) {
            return false;
        }
        let pe = pt - view.eye;
        let pem2 = pe.length_squared();
        let rhs = tz2 * pem2;
        let big_uniform = (b.uni_error * b.uni_error).max(b.radius * b.radius * (re * re)) >= rhs;
        if b.cone_sin2 >= 1.0 {
            return big_uniform || b.dir_error * b.dir_error >= rhs;
        }
        if !t.backface() && b.dir_error <= 0.0 {
            return big_uniform;
        }
        let vdot = pe.dot(Vec3::from_array(b.cone_normal()));
        if t.backface() && vdot > 0.0 && vdot * vdot > pem2 * b.cone_sin2 {
            return false;
        }
        big_uniform || b.dir_error * b.dir_error * (pem2 - vdot * vdot) >= rhs * pem2
    }

    /// xorshift64*: deterministic cases without a dependency (the test also runs under Miri).
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
        }
        fn unit(&mut self) -> f32 {
            (self.next() >> 40) as f32 / (1u64 << 24) as f32
        }
        fn range(&mut self, lo: f32, hi: f32) -> f32 {
            lo + (hi - lo) * self.unit()
        }
        fn vec(&mut self, r: f32) -> Vec3 {
            Vec3::new(self.range(-r, r), self.range(-r, r), self.range(-r, r))
        }
    }

    /// The fast criterion answers as the plain formulas do, bit for bit, also for errors a
    /// few ulps either side of the tolerance, where the early answer has to hold back.
    #[test]
    fn the_criterion_answers_as_the_plain_formulas() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let cases = if cfg!(miri) { 400 } else { 200_000 };
        let mut answers = [0u32; 2];
        for case in 0..cases {
            let eye = rng.vec(100.0);
            let look = LookAt {
                eye,
                target: eye + rng.vec(1.0) + Vec3::X * 1e-3,
                up: Vec3::Y,
                fov_y: rng.range(0.3, 2.0),
                near: rng.range(0.01, 1.0),
                far: rng.range(50.0, 400.0),
            };
            let aspect = rng.range(0.5, 2.5);
            let height = rng.range(100.0, 2000.0);
            let mut view = look.view((height * aspect) as u32, height as u32);
            view.plane_count = (rng.next() % 7) as u32;
            let cull = (rng.next() % 4 != 0, rng.next() % 3 != 0);
            let scale = if case % 97 == 0 {
                0.0
            } else {
                rng.range(1e-4, 1e-2)
            };
            let tz2 = scale * scale;
            let point = rng.vec(150.0);
            let pem2 = (point - eye).length_squared();
            let rhs = tz2 * pem2;
            // Errors at the tolerance, nudged a few ulps, or anywhere.
            let near = |rng: &mut Rng| {
                let e = libm::sqrtf(rhs);
                let ulps = (rng.next() % 9) as i32 - 4;
                f32::from_bits((e.to_bits() as i32 + ulps).max(0) as u32)
            };
            let error = |rng: &mut Rng| match rng.next() % 3 {
                0 => near(rng),
                1 => rng.range(0.0, 2.0) * libm::sqrtf(rhs),
                _ => rng.range(0.0, 5.0),
            };
            let (uni, dir) = (error(&mut rng), error(&mut rng));
            let cone_sin2 = match rng.next() % 4 {
                0 => 1.0,
                _ => rng.unit(),
            };
            // A cone axis across the view direction makes the directional test compare
            // dir² · pem2 with rhs · pem2, where rounding can make the two equal.
            let axis = match rng.next() % 3 {
                0 => (point - eye).cross(rng.vec(1.0)),
                _ => rng.vec(1.0),
            };
            let b = SplitBounds::new(
                point.to_array(),
                rng.range(0.0, 30.0),
                axis.normalize_or_zero().to_array(),
                cone_sin2,
                uni,
                dir,
            );
            // A share of the radius counting as uniform error in a third of the cases.
            let re = match rng.next() % 3 {
                0 => rng.range(0.0, 0.5),
                _ => 0.0,
            };
            let test = ScreenTest::from_parts(view, scale, re, cull);
            let fast = Criterion::new(&test).wants_split(&b);
            assert_eq!(fast, plain(&test, &b), "case {case}: {b:?}");
            answers[usize::from(fast)] += 1;
        }
        // Both answers were asked for often.
        assert!(answers.iter().all(|&n| n > cases / 20), "{answers:?}");
    }
}
