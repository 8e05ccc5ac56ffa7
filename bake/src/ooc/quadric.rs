//! Generalized quadrics (Garland & Heckbert 1998) over position and attributes.
//!
//! A corner is a point in R^n, n = [`DIM`] = 3 (position) + 3 (normal) + 2 (UV) + 4 (RGBA),
//! the attributes scaled by weights so that their distances compare with positions. A
//! triangle `p, q, r` spans a plane in R^n with the orthonormal frame
//! `e1 = (q - p) / |q - p|`, `e2 = (r - p - (e1·(r - p)) e1) / |...|`; the squared distance of
//! `v` to that plane is `vᵀAv + 2bᵀv + c` with `A = I - e1e1ᵀ - e2e2ᵀ`,
//! `b = (p·e1)e1 + (p·e2)e2 - p`, `c = p·p - (p·e1)² - (p·e2)²`. Each triangle's quadric is
//! weighted by its area, and a cluster's quadric is the sum over the triangles touching it.
//!
//! The representative is the minimiser, found by a regularised solve: `(A + εI)x = -b + εm`,
//! where `m` is the mean of the cluster's corners and `ε` a thousandth of `A`'s mean diagonal
//! entry (as Lindstrom truncates small singular values).
//! Along directions the quadric does not constrain (a flat region's tangent plane) this gives
//! the mean exactly; elsewhere it moves the optimum by a relative `ε / λ`. A solve that fails
//! (not positive definite in floating point) falls back to the mean. Attributes can be
//! solved with the position held fixed ([`Quadric::minimize_given`]), which is what lets the
//! sides of a seam share one position but keep their own attributes.
//!
//! `f64` throughout: sums over many triangles in file coordinates would lose the optimum to
//! cancellation in `f32`.

/// Dimension: position, normal, UV, RGBA.
pub const DIM: usize = 12;
/// Entries of the packed upper triangle.
const PACKED: usize = DIM * (DIM + 1) / 2;

/// Index of `(i, j)`, `i <= j`, in the packed upper triangle.
const fn packed(i: usize, j: usize) -> usize {
    i * DIM - i * i.saturating_sub(1) / 2 + (j - i)
}

/// Area-weighted sum of triangle quadrics, with the corner sum for the mean.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quadric {
    /// `A`, packed upper triangle.
    pub a: [f64; PACKED],
    /// `b`.
    pub b: [f64; DIM],
    /// `c`.
    pub c: f64,
}

impl Default for Quadric {
    fn default() -> Self {
        Self {
            a: [0.0; PACKED],
            b: [0.0; DIM],
            c: 0.0,
        }
    }
}

fn dot(a: &[f64; DIM], b: &[f64; DIM]) -> f64 {
    let mut s = 0.0;
    for k in 0..DIM {
        s += a[k] * b[k];
    }
    s
}

impl Quadric {
    /// The area-weighted quadric of triangle `p` (area taken from the positions), or `None`
    /// when the triangle is degenerate in R^n.
    pub fn triangle(p: &[[f64; DIM]; 3]) -> Option<Self> {
        let mut e1 = [0.0; DIM];
        let mut e2 = [0.0; DIM];
        for k in 0..DIM {
            e1[k] = p[1][k] - p[0][k];
            e2[k] = p[2][k] - p[0][k];
        }
        let d = [0, 1, 2].map(|k| e1[k]);
        let f = [0, 1, 2].map(|k| e2[k]);
        let cr = [
            d[1] * f[2] - d[2] * f[1],
            d[2] * f[0] - d[0] * f[2],
            d[0] * f[1] - d[1] * f[0],
        ];
        let area = 0.5 * (cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]).sqrt();
        let l1 = dot(&e1, &e1).sqrt();
        if l1.is_nan() || l1 <= 0.0 || area.is_nan() || area <= 0.0 {
            return None;
        }
        for v in &mut e1 {
            *v /= l1;
        }
        let t = dot(&e1, &e2);
        for k in 0..DIM {
            e2[k] -= t * e1[k];
        }
        let l2 = dot(&e2, &e2).sqrt();
        if l2.is_nan() || l2 <= 1e-12 * l1 {
            return None;
        }
        for v in &mut e2 {
            *v /= l2;
        }
        let mut q = Self::default();
        let mut idx = 0;
        for i in 0..DIM {
            for j in i..DIM {
                let id = if i == j { 1.0 } else { 0.0 };
                q.a[idx] = area * (id - e1[i] * e1[j] - e2[i] * e2[j]);
                idx += 1;
            }
        }
        let (pe1, pe2) = (dot(&p[0], &e1), dot(&p[0], &e2));
        for k in 0..DIM {
            q.b[k] = area * (pe1 * e1[k] + pe2 * e2[k] - p[0][k]);
        }
        q.c = area * (dot(&p[0], &p[0]) - pe1 * pe1 - pe2 * pe2);
        Some(q)
    }

    /// Adds `s * o`.
    pub fn add_scaled(&mut self, o: &Self, s: f64) {
        for k in 0..PACKED {
            self.a[k] += s * o.a[k];
        }
        for k in 0..DIM {
            self.b[k] += s * o.b[k];
        }
        self.c += s * o.c;
    }

    /// `A[i][j]`.
    pub fn at(&self, i: usize, j: usize) -> f64 {
        let (i, j) = if i <= j { (i, j) } else { (j, i) };
        self.a[packed(i, j)]
    }

    /// The quadric's value at `v`.
    pub fn eval(&self, v: &[f64; DIM]) -> f64 {
        let mut s = self.c;
        for i in 0..DIM {
            s += 2.0 * self.b[i] * v[i];
            for j in 0..DIM {
                s += v[i] * self.at(i, j) * v[j];
            }
        }
        s
    }

    /// The regularised minimiser over all coordinates; `mean` where the solve fails.
    pub fn minimize(&self, mean: &[f64; DIM]) -> [f64; DIM] {
        self.solve(mean, 0)
    }

    /// The regularised minimiser over the attributes with the position held at `position`.
    pub fn minimize_given(&self, position: [f64; 3], mean: &[f64; DIM]) -> [f64; DIM] {
        let mut m = *mean;
        m[..3].copy_from_slice(&position);
        self.solve(&m, 3)
    }

    /// `A` as a full symmetric matrix (the solve reads it row by row).
    fn unpacked(&self) -> [[f64; DIM]; DIM] {
        let mut full = [[0.0; DIM]; DIM];
        let mut idx = 0;
        for i in 0..DIM {
            for j in i..DIM {
                full[i][j] = self.a[idx];
                full[j][i] = self.a[idx];
                idx += 1;
            }
        }
        full
    }

    /// Solves for coordinates `fixed..DIM`, the others held at `start`'s.
    fn solve(&self, start: &[f64; DIM], fixed: usize) -> [f64; DIM] {
        let n = DIM - fixed;
        let full = self.unpacked();
        let mut trace = 0.0;
        for i in fixed..DIM {
            trace += full[i][i];
        }
        let eps = 1e-3 * (trace / n as f64).max(f64::MIN_POSITIVE);
        // M x = r with M = A_ff + εI, r = -(b_f + A_fx x_x) + ε m_f.
        let mut m = [[0.0; DIM]; DIM];
        let mut r = [0.0; DIM];
        for i in 0..n {
            let gi = i + fixed;
            m[i][..n].copy_from_slice(&full[gi][fixed..]);
            m[i][i] += eps;
            let mut s = -self.b[gi] + eps * start[gi];
            for k in 0..fixed {
                s -= full[gi][k] * start[k];
            }
            r[i] = s;
        }
        // Cholesky, in place (lower triangle).
        for j in 0..n {
            let mut d = m[j][j];
            for k in 0..j {
                d -= m[j][k] * m[j][k];
            }
            if d.is_nan() || d <= 0.0 {
                return *start;
            }
            let d = d.sqrt();
            m[j][j] = d;
            for i in j + 1..n {
                let mut s = m[i][j];
                for k in 0..j {
                    s -= m[i][k] * m[j][k];
                }
                m[i][j] = s / d;
            }
        }
        let mut y = [0.0; DIM];
        for i in 0..n {
            let mut s = r[i];
            for k in 0..i {
                s -= m[i][k] * y[k];
            }
            y[i] = s / m[i][i];
        }
        let mut x = *start;
        for i in (0..n).rev() {
            let mut s = y[i];
            for k in i + 1..n {
                s -= m[k][i] * x[k + fixed];
            }
            x[i + fixed] = s / m[i][i];
        }
        if x.iter().all(|v| v.is_finite()) {
            x
        } else {
            *start
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(p: [f64; 3], extra: f64) -> [f64; DIM] {
        let mut v = [0.0; DIM];
        v[..3].copy_from_slice(&p);
        v[6] = extra;
        v
    }

    #[test]
    fn packed_indices_cover_the_upper_triangle() {
        let mut seen = [false; PACKED];
        for i in 0..DIM {
            for j in i..DIM {
                assert!(!seen[packed(i, j)]);
                seen[packed(i, j)] = true;
            }
        }
        assert!(seen.iter().all(|&s| s));
    }

    #[test]
    fn a_triangle_quadric_is_zero_on_its_plane_and_the_squared_distance_off_it() {
        let t = [
            point([0.0, 0.0, 0.0], 0.0),
            point([2.0, 0.0, 0.0], 1.0),
            point([0.0, 2.0, 0.0], 0.0),
        ];
        let q = Quadric::triangle(&t).unwrap();
        let area = 2.0;
        // On the plane (affine combination), zero.
        assert!(q.eval(&point([0.5, 0.5, 0.0], 0.25)).abs() < 1e-12);
        // Off it by 3 along z: 9 per unit area.
        assert!((q.eval(&point([0.5, 0.5, 3.0], 0.25)) - 9.0 * area).abs() < 1e-9);
    }

    #[test]
    fn the_solve_reads_every_entry_of_a_as_the_packed_index_gives_it() {
        let mut q = Quadric::default();
        for (k, a) in q.a.iter_mut().enumerate() {
            *a = 1.0 + k as f64;
        }
        let full = q.unpacked();
        for i in 0..DIM {
            for j in 0..DIM {
                assert_eq!(full[i][j], q.at(i, j), "({i}, {j})");
            }
        }
    }

    #[test]
    fn the_minimiser_of_three_planes_is_their_corner() {
        // Faces of a cube corner at (1, 2, 3), each with an attribute linear in position.
        let c = [1.0, 2.0, 3.0];
        let attr = |p: [f64; 3]| 0.5 * p[0] - 0.25 * p[1] + p[2];
        let mut q = Quadric::default();
        for (u, v) in [(0, 1), (1, 2), (2, 0)] {
            let mut a = c;
            a[u] += 1.0;
            let mut b = c;
            b[v] += 1.0;
            q.add_scaled(
                &Quadric::triangle(&[point(c, attr(c)), point(a, attr(a)), point(b, attr(b))])
                    .unwrap(),
                1.0,
            );
        }
        // The solve is regularised towards the start point by a thousandth of the mean
        // diagonal, so the corner is reached within about 1% of the start's distance from it
        // (0.52 here), not exactly.
        let x = q.minimize(&point([1.3, 2.3, 3.3], 0.0));
        for k in 0..3 {
            assert!((x[k] - c[k]).abs() < 5e-3, "{x:?}");
        }
        assert!((x[6] - attr(c)).abs() < 1e-2, "{x:?}");
        // Held at the corner, the attribute alone.
        let y = q.minimize_given(c, &point([0.0; 3], 7.0));
        assert!((y[6] - attr(c)).abs() < 2e-2, "{y:?}"); // the start is 4 away
    }
}
