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
//!
//! A mesh's quadrics are kept in a [`Quadrics`] table holding only the attributes its
//! [`Layout`] names: those that vary over the mesh. An attribute with one value at every
//! vertex (white where the mesh has no colours, zero where it has no UVs, a normal given no
//! weight) has that value wherever a cost is evaluated, and its interpolant over every
//! triangle is that value, so its term of every cost is zero: the triangles' quadrics are
//! made with it zero ([`Layout::only`]) and the table leaves it out, which saves 32 bytes a
//! quadric. The costs are then, to the bit, those of the mesh with that attribute zero;
//! where the value is not zero, the full quadric's terms for it would cancel only up to
//! their rounding.

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

/// Numbers of a [`Quadrics`] row besides its attributes': the position block of `A` (6),
/// the attribute block (1), the position part of `b` (3) and the constant (1).
const FIXED: usize = 11;

/// Which of the [`M`] attributes a table of quadrics holds, in order.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Layout {
    /// The attributes held, `kept[..count]`.
    kept: [u8; M],
    count: u8,
}

impl Layout {
    /// The attributes that differ between some of `values`.
    pub fn of(values: impl IntoIterator<Item = [f64; M]>) -> Self {
        let mut values = values.into_iter();
        let first = values.next().unwrap_or([0.0; M]);
        let mut any = [false; M];
        for s in values {
            for ((a, x), f) in any.iter_mut().zip(s).zip(first) {
                *a |= x != f;
            }
        }
        let mut layout = Self {
            kept: [0; M],
            count: 0,
        };
        for (j, _) in any.iter().enumerate().filter(|(_, &a)| a) {
            layout.kept[usize::from(layout.count)] = j as u8;
            layout.count += 1;
        }
        layout
    }

    /// `s` with the attributes the layout leaves out zero.
    pub fn only(&self, s: [f64; M]) -> [f64; M] {
        let mut out = [0.0; M];
        for &j in self.attributes() {
            out[usize::from(j)] = s[usize::from(j)];
        }
        out
    }

    /// The attributes held, in order.
    pub fn attributes(&self) -> &[u8] {
        &self.kept[..usize::from(self.count)]
    }

    /// The `k`-th attribute held (below [`M`] without a bounds check in the cost's loop).
    #[inline]
    fn attribute(&self, k: usize) -> usize {
        const { assert!(M.is_power_of_two()) };
        usize::from(self.kept[k]) & (M - 1)
    }

    /// Numbers per quadric: `11 + 4m` for `m` attributes.
    fn stride(&self) -> usize {
        FIXED + 4 * usize::from(self.count)
    }
}

/// Quadrics over the attributes of a [`Layout`], one row of `11 + 4m` numbers each: the
/// position block of `A`, the attribute block, the position part of `b`, the constant,
/// then per attribute its coupling with the position (3) and its part of `b`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Quadrics {
    layout: Layout,
    data: Vec<f64>,
}

/// Rows of a [`Quadrics`] to add to: a table's, or a part of them ([`QuadricsMut::split_at`]).
#[derive(Debug)]
pub struct QuadricsMut<'a> {
    layout: Layout,
    data: &'a mut [f64],
}

impl Quadrics {
    /// `n` zero quadrics over the attributes of `layout`.
    pub fn zeros(layout: Layout, n: usize) -> Self {
        Self {
            layout,
            data: vec![0.0; n * layout.stride()],
        }
    }

    /// All rows, to add to.
    pub fn as_mut(&mut self) -> QuadricsMut<'_> {
        QuadricsMut {
            layout: self.layout,
            data: &mut self.data,
        }
    }

    /// Copies rows `from` to the rows from `to` on.
    pub fn move_rows(&mut self, from: std::ops::Range<usize>, to: usize) {
        let n = self.layout.stride();
        self.data.copy_within(from.start * n..from.end * n, to * n);
    }

    /// Keeps the first `rows` rows and gives the rest of the memory back.
    pub fn truncate(&mut self, rows: usize) {
        self.data.truncate(rows * self.layout.stride());
        self.data.shrink_to_fit();
    }

    /// Row `i`'s numbers.
    #[inline]
    pub fn row(&self, i: usize) -> &[f64] {
        let n = self.layout.stride();
        &self.data[i * n..][..n]
    }

    /// Row `i`'s `Q(p, s)` ([`Quadric::eval`]: the same number), never negative.
    #[inline]
    pub fn eval(&self, i: usize, p: [f64; 3], s: &[f64; M]) -> f64 {
        // One loop per attribute count, so that each is unrolled.
        match self.layout.count {
            0 => self.eval_with::<0>(i, p, s),
            1 => self.eval_with::<1>(i, p, s),
            2 => self.eval_with::<2>(i, p, s),
            3 => self.eval_with::<3>(i, p, s),
            4 => self.eval_with::<4>(i, p, s),
            5 => self.eval_with::<5>(i, p, s),
            6 => self.eval_with::<6>(i, p, s),
            7 => self.eval_with::<7>(i, p, s),
            _ => self.eval_with::<M>(i, p, s),
        }
    }

    /// [`Self::eval`] of a layout of `K` attributes.
    #[inline]
    fn eval_with<const K: usize>(&self, i: usize, p: [f64; 3], s: &[f64; M]) -> f64 {
        let n = FIXED + 4 * K;
        let r = &self.data[i * n..][..n];
        let pap = r[0] * p[0] * p[0]
            + r[3] * p[1] * p[1]
            + r[5] * p[2] * p[2]
            + 2.0 * (r[1] * p[0] * p[1] + r[2] * p[0] * p[2] + r[4] * p[1] * p[2]);
        let (ass, c) = (r[6], r[10]);
        let mut v = pap + 2.0 * dot([r[7], r[8], r[9]], p) + c;
        for k in 0..K {
            let sj = s[self.layout.attribute(k)];
            let g = [r[FIXED + 3 * k], r[FIXED + 3 * k + 1], r[FIXED + 3 * k + 2]];
            let b = r[FIXED + 3 * K + k];
            v += 2.0 * sj * dot(g, p) + ass * sj * sj + 2.0 * b * sj;
        }
        v.max(0.0)
    }
}

impl<'a> QuadricsMut<'a> {
    /// The same rows, for a shorter borrow.
    pub fn reborrow(&mut self) -> QuadricsMut<'_> {
        QuadricsMut {
            layout: self.layout,
            data: self.data,
        }
    }

    /// Adds row `src` to row `dst`.
    #[inline]
    pub fn merge(&mut self, dst: usize, src: usize) {
        let n = self.layout.stride();
        let mut from = [0.0; FIXED + 4 * M];
        from[..n].copy_from_slice(&self.data[src * n..][..n]);
        for (t, f) in self.data[dst * n..][..n].iter_mut().zip(&from) {
            *t += f;
        }
    }

    /// The first `rows` rows and the others.
    pub fn split_at(self, rows: usize) -> (Self, Self) {
        let (a, b) = self.data.split_at_mut(rows * self.layout.stride());
        let layout = self.layout;
        (Self { layout, data: a }, Self { layout, data: b })
    }

    /// Adds `q` to row `i`: its attributes the layout holds (the others must be zero:
    /// [`Layout::only`]).
    #[inline]
    pub fn add(&mut self, i: usize, q: &Quadric) {
        let mut row = [0.0; FIXED + 4 * M];
        let n = self.layout.stride();
        q.write_row(self.layout, &mut row[..n]);
        self.add_row(i, &row[..n]);
    }

    /// Adds a row of numbers of this layout ([`Quadric::write_row`]) to row `i`.
    #[inline]
    pub fn add_row(&mut self, i: usize, row: &[f64]) {
        let n = self.layout.stride();
        for (t, f) in self.data[i * n..][..n].iter_mut().zip(row) {
            *t += f;
        }
    }

    /// The rows one after the other, to fill.
    pub fn rows(self) -> std::slice::ChunksExactMut<'a, f64> {
        self.data.chunks_exact_mut(self.layout.stride())
    }

    /// The rows, to fill on the rayon pool.
    pub fn par_rows(self) -> rayon::slice::ChunksExactMut<'a, f64> {
        use rayon::slice::ParallelSliceMut;
        self.data.par_chunks_exact_mut(self.layout.stride())
    }
}

impl Quadric {
    /// Writes the numbers of `layout`'s row for the quadric into `row` (the attributes the
    /// layout holds; the others must be zero: [`Layout::only`]).
    #[inline]
    pub fn write_row(&self, layout: Layout, row: &mut [f64]) {
        let (fixed, attrs) = row.split_at_mut(FIXED);
        fixed.copy_from_slice(&[
            self.app[0],
            self.app[1],
            self.app[2],
            self.app[3],
            self.app[4],
            self.app[5],
            self.ass,
            self.bp[0],
            self.bp[1],
            self.bp[2],
            self.c,
        ]);
        let kept = layout.attributes();
        let (aps, bs) = attrs.split_at_mut(3 * kept.len());
        for ((g, b), &j) in aps.chunks_exact_mut(3).zip(bs).zip(kept) {
            let j = usize::from(j);
            g.copy_from_slice(&self.aps[j]);
            *b = self.bs[j];
        }
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

    #[test]
    fn a_table_holds_only_the_attributes_that_vary() {
        // UVs (3, 4) and the third colour channel (7), the others zero everywhere.
        let at = |u: f64, v: f64, b: f64| {
            let mut s = [0.0; M];
            (s[3], s[4], s[7]) = (u, v, b);
            s
        };
        let values = [at(0.0, 0.5, 0.25), at(1.0, 0.0, 0.0), at(0.5, 1.0, 1.0)];
        let layout = Layout::of(values);
        assert_eq!(layout.attributes(), [3, 4, 7]);
        let p = [[0.1, 0.0, 0.3], [2.0, 0.4, 0.0], [0.0, 1.7, 0.2]];
        let a = Quadric::triangle(p, values);
        let b = Quadric::plane([0.0, 0.6, 0.8], -0.3, 2.5);
        let mut table = Quadrics::zeros(layout, 3);
        let mut rows = table.as_mut();
        rows.add(0, &a);
        rows.add(1, &b);
        let (_, mut last) = rows.split_at(2);
        last.add(0, &a);
        table.as_mut().merge(0, 1);
        let mut sum = a;
        sum.add(&b);
        for (x, s) in [
            ([0.2, 0.7, -0.4], at(0.9, 0.1, 0.3)),
            ([1.0, 1.0, 0.0], values[1]),
        ] {
            // The same number to the bit: what the table leaves out adds exact zeros.
            assert_eq!(table.eval(0, x, &s).to_bits(), sum.eval(x, &s).to_bits());
            assert_eq!(table.eval(1, x, &s).to_bits(), b.eval(x, &s).to_bits());
            assert_eq!(table.eval(2, x, &s).to_bits(), a.eval(x, &s).to_bits());
        }
    }

    #[test]
    fn an_attribute_with_one_value_everywhere_is_left_out_and_costs_nothing() {
        // UV u (3) varies; the colour's red (5) is 0.7 at every vertex.
        let at = |u: f64| {
            let mut s = [0.0; M];
            (s[3], s[5]) = (u, 0.7);
            s
        };
        let values = [at(0.0), at(1.0), at(0.5)];
        let layout = Layout::of(values);
        assert_eq!(layout.attributes(), [3]);
        let p = [[0.1, 0.0, 0.3], [2.0, 0.4, 0.0], [0.0, 1.7, 0.2]];
        let mut table = Quadrics::zeros(layout, 1);
        table
            .as_mut()
            .add(0, &Quadric::triangle(p, values.map(|s| layout.only(s))));
        let (full, plain) = (
            Quadric::triangle(p, values),
            Quadric::triangle(
                p,
                values.map(|s| [s[0], s[1], s[2], s[3], 0.0, 0.0, 0.0, 0.0]),
            ),
        );
        for (x, u) in [([0.2, 0.7, -0.4], 0.9), ([1.0, 1.0, 0.0], 0.25)] {
            // The cost of the mesh with red zero, to the bit; the full quadric's red terms
            // are zero but for their rounding.
            let cost = table.eval(0, x, &at(u));
            let mut zero_red = at(u);
            zero_red[5] = 0.0;
            assert_eq!(cost.to_bits(), plain.eval(x, &zero_red).to_bits());
            assert!((cost - full.eval(x, &at(u))).abs() <= 1e-12 * (1.0 + cost));
        }
    }
}
