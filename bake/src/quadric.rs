//! Attribute-aware quadrics (Hoppe, "New quadric metric for simplifying meshes with
//! appearance attributes", 1999).
//!
//! A vertex is `x = (p, s)`: its position and `M` attributes (normal, UV, colour), scaled by
//! per-kind weights so that attribute error is measured in the same units as distance. Each
//! triangle contributes, weighted by its area, the squared distance of `p` to its plane and,
//! per attribute, the squared difference between `s_j` and the attribute's linear
//! interpolant over the triangle, `g_j · p + d_j`. The sum is a quadratic form
//! `Q(x) = xᵀAx + 2bᵀx + c` stored in `11 + 4M` numbers (not `(3 + M)²`), because the
//! attribute block of `A` is a multiple of the identity and each attribute's coupling with
//! the position is one vector.

/// Attributes per vertex: normal (3), UV (2), colour RGB (3).
pub const M: usize = 8;

/// A quadric over position and [`M`] attributes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quadric {
    /// Position block of `A` (symmetric: xx, xy, xz, yy, yz, zz).
    app: [f64; 6],
    /// Position–attribute coupling: column `j` is `-Σ area · g_j`.
    aps: [[f64; 3]; M],
    /// Attribute block of `A`: `Σ area` times the identity.
    ass: f64,
    /// Position part of `b`.
    bp: [f64; 3],
    /// Attribute part of `b`: `-Σ area · d_j`.
    bs: [f64; M],
    /// Constant.
    c: f64,
}

impl Default for Quadric {
    fn default() -> Self {
        Self {
            app: [0.0; 6],
            aps: [[0.0; 3]; M],
            ass: 0.0,
            bp: [0.0; 3],
            bs: [0.0; M],
            c: 0.0,
        }
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

impl Quadric {
    /// The quadric of one triangle with corner positions `p` and attributes `s`, weighted by
    /// its area. A degenerate triangle gives the zero quadric.
    pub fn triangle(p: [[f64; 3]; 3], s: [[f64; M]; 3]) -> Self {
        let (e1, e2) = (sub(p[1], p[0]), sub(p[2], p[0]));
        let n = cross(e1, e2);
        let len = dot(n, n).sqrt();
        if len <= 0.0 || !len.is_finite() {
            return Self::default();
        }
        let area = 0.5 * len;
        let n = [n[0] / len, n[1] / len, n[2] / len];
        let d0 = -dot(n, p[0]);
        let mut q = Self::plane(n, d0, area);
        // Gradient of each attribute in the triangle's plane: g · e1 = Δ1, g · e2 = Δ2,
        // g = x e1 + y e2.
        let (a11, a12, a22) = (dot(e1, e1), dot(e1, e2), dot(e2, e2));
        let det = a11 * a22 - a12 * a12;
        if det.abs() <= 1e-30 {
            return q;
        }
        for j in 0..M {
            let (d1, d2) = (s[1][j] - s[0][j], s[2][j] - s[0][j]);
            let x = (d1 * a22 - d2 * a12) / det;
            let y = (d2 * a11 - d1 * a12) / det;
            let g = [
                x * e1[0] + y * e2[0],
                x * e1[1] + y * e2[1],
                x * e1[2] + y * e2[2],
            ];
            let d = s[0][j] - dot(g, p[0]);
            // (g·p + d - s)²: A_pp += g gᵀ, A_ps = -g, A_ss = 1, b_p += d g, b_s = -d, c += d².
            q.app[0] += area * g[0] * g[0];
            q.app[1] += area * g[0] * g[1];
            q.app[2] += area * g[0] * g[2];
            q.app[3] += area * g[1] * g[1];
            q.app[4] += area * g[1] * g[2];
            q.app[5] += area * g[2] * g[2];
            q.aps[j] = [-area * g[0], -area * g[1], -area * g[2]];
            for k in 0..3 {
                q.bp[k] += area * d * g[k];
            }
            q.bs[j] = -area * d;
            q.c += area * d * d;
        }
        q.ass = area;
        q
    }

    /// `weight · (n · p + d)²`: a plane with no attribute terms.
    pub fn plane(n: [f64; 3], d: f64, weight: f64) -> Self {
        Self {
            app: [
                weight * n[0] * n[0],
                weight * n[0] * n[1],
                weight * n[0] * n[2],
                weight * n[1] * n[1],
                weight * n[1] * n[2],
                weight * n[2] * n[2],
            ],
            bp: [weight * d * n[0], weight * d * n[1], weight * d * n[2]],
            c: weight * d * d,
            ..Self::default()
        }
    }

    /// Adds `other`.
    pub fn add(&mut self, other: &Self) {
        for k in 0..6 {
            self.app[k] += other.app[k];
        }
        for j in 0..M {
            for k in 0..3 {
                self.aps[j][k] += other.aps[j][k];
            }
            self.bs[j] += other.bs[j];
        }
        self.ass += other.ass;
        for k in 0..3 {
            self.bp[k] += other.bp[k];
        }
        self.c += other.c;
    }

    /// `Q(p, s)`, never negative.
    pub fn eval(&self, p: [f64; 3], s: &[f64; M]) -> f64 {
        let a = &self.app;
        let pap = a[0] * p[0] * p[0]
            + a[3] * p[1] * p[1]
            + a[5] * p[2] * p[2]
            + 2.0 * (a[1] * p[0] * p[1] + a[2] * p[0] * p[2] + a[4] * p[1] * p[2]);
        let mut v = pap + 2.0 * dot(self.bp, p) + self.c;
        for j in 0..M {
            v +=
                2.0 * s[j] * dot(self.aps[j], p) + self.ass * s[j] * s[j] + 2.0 * self.bs[j] * s[j];
        }
        v.max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn attrs(v: f64) -> [f64; M] {
        let mut s = [0.0; M];
        s[3] = v;
        s
    }

    #[test]
    fn plane_distance_squared_times_area() {
        let p = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]];
        let q = Quadric::triangle(p, [attrs(0.0); 3]);
        // Area 2; point 3 above the plane: 2 · 9.
        assert!((q.eval([5.0, -1.0, 3.0], &attrs(0.0)) - 18.0).abs() < 1e-9);
        assert!(q.eval([0.3, 0.4, 0.0], &attrs(0.0)).abs() < 1e-12);
    }

    #[test]
    fn attribute_error_is_the_difference_from_the_interpolant() {
        // u = x / 2 over the triangle.
        let p = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]];
        let q = Quadric::triangle(p, [attrs(0.0), attrs(1.0), attrs(0.0)]);
        assert!(q.eval([1.0, 1.0, 0.0], &attrs(0.5)).abs() < 1e-12);
        // 0.25 off: area 2 · 0.0625.
        assert!((q.eval([1.0, 1.0, 0.0], &attrs(0.75)) - 0.125).abs() < 1e-9);
        // Off the plane and off the attribute: both terms add.
        assert!((q.eval([1.0, 1.0, 1.0], &attrs(0.75)) - (2.0 + 0.125)).abs() < 1e-9);
    }

    #[test]
    fn sums_add() {
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let a = Quadric::triangle(p, [attrs(0.0), attrs(1.0), attrs(2.0)]);
        let b = Quadric::plane([0.0, 1.0, 0.0], -3.0, 0.5);
        let mut s = a;
        s.add(&b);
        let (x, v) = ([0.2, 0.7, -0.4], attrs(0.9));
        assert!((s.eval(x, &v) - a.eval(x, &v) - b.eval(x, &v)).abs() < 1e-9);
    }
}
