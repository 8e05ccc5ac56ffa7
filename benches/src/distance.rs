//! Sampled symmetric distances between triangle soups, shared by the bake and out-of-core
//! benchmarks: points uniform by area on each surface (SplitMix64, fixed seeds) plus each
//! surface's distinct corners, each point's exact distance to the nearest point of the other
//! surface through a bounding-volume hierarchy. Hausdorff: the largest distance either way,
//! corners included; RMS: over the area samples of both directions; both relative to the
//! input's bounding-box diagonal.

pub type P3 = [f64; 3];

pub fn sub(a: P3, b: P3) -> P3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub fn dot(a: P3, b: P3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
pub fn cross(a: P3, b: P3) -> P3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
pub fn axpy(a: P3, s: f64, d: P3) -> P3 {
    [a[0] + s * d[0], a[1] + s * d[1], a[2] + s * d[2]]
}
pub fn d2(a: P3, b: P3) -> f64 {
    let d = sub(a, b);
    dot(d, d)
}
pub fn wide(p: [f32; 3]) -> P3 {
    p.map(f64::from)
}

/// SplitMix64 (the tests' generator): deterministic samples, so runs compare.
pub use caveclod_bake::generate::SplitMix64 as Rng;

/// A triangle soup: three corners per triangle.
pub type Soup = Vec<[[f32; 3]; 3]>;

/// Squared distance from `p` to the segment `a`–`b`.
pub fn segment_d2(p: P3, a: P3, b: P3) -> f64 {
    let ab = sub(b, a);
    let l = dot(ab, ab);
    let t = if l > 0.0 {
        (dot(sub(p, a), ab) / l).clamp(0.0, 1.0)
    } else {
        0.0
    };
    d2(p, axpy(a, t, ab))
}

/// Squared distance from `p` to the triangle `t` (Ericson, Real-Time Collision Detection,
/// 5.1.5), falling back to the edges for a degenerate triangle.
pub fn triangle_d2(p: P3, t: &[[f32; 3]; 3]) -> f64 {
    let (a, b, c) = (wide(t[0]), wide(t[1]), wide(t[2]));
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(p, a));
    let (d1, d2_) = (dot(ab, ap), dot(ac, ap));
    if d1 <= 0.0 && d2_ <= 0.0 {
        return dot(ap, ap);
    }
    let bp = sub(p, b);
    let (d3, d4) = (dot(ab, bp), dot(ac, bp));
    if d3 >= 0.0 && d4 <= d3 {
        return dot(bp, bp);
    }
    let vc = d1 * d4 - d3 * d2_;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return d2(p, axpy(a, d1 / (d1 - d3), ab));
    }
    let cp = sub(p, c);
    let (d5, d6) = (dot(ab, cp), dot(ac, cp));
    if d6 >= 0.0 && d5 <= d6 {
        return dot(cp, cp);
    }
    let vb = d5 * d2_ - d1 * d6;
    if vb <= 0.0 && d2_ >= 0.0 && d6 <= 0.0 {
        return d2(p, axpy(a, d2_ / (d2_ - d6), ac));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return d2(p, axpy(b, w, sub(c, b)));
    }
    let denom = va + vb + vc;
    let r = if denom != 0.0 {
        let (v, w) = (vb / denom, vc / denom);
        d2(p, axpy(axpy(a, v, ab), w, ac))
    } else {
        f64::NAN
    };
    if r.is_finite() {
        r
    } else {
        segment_d2(p, a, b)
            .min(segment_d2(p, b, c))
            .min(segment_d2(p, c, a))
    }
}

/// A bounding-volume hierarchy over a triangle soup, for nearest-point queries.
pub struct Bvh {
    /// `(lo, hi, first, count)`: a leaf if `count > 0`, else the right child is node
    /// `first` and the left child follows its parent.
    nodes: Vec<([f32; 3], [f32; 3], u32, u32)>,
    tris: Soup,
}

const LEAF: usize = 4;

impl Bvh {
    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Builds the hierarchy over `tris`.
    pub fn new(tris: &[[[f32; 3]; 3]]) -> Self {
        let boxes: Vec<([f32; 3], [f32; 3])> = tris
            .iter()
            .map(|t| {
                let mut lo = t[0];
                let mut hi = t[0];
                for p in &t[1..] {
                    for k in 0..3 {
                        lo[k] = lo[k].min(p[k]);
                        hi[k] = hi[k].max(p[k]);
                    }
                }
                (lo, hi)
            })
            .collect();
        let mut order: Vec<u32> = (0..tris.len() as u32).collect();
        let mut bvh = Self {
            nodes: Vec::with_capacity(2 * tris.len() / LEAF + 1),
            tris: Vec::new(),
        };
        bvh.build(&mut order, &boxes, 0);
        bvh.tris = order.iter().map(|&i| tris[i as usize]).collect();
        bvh
    }

    fn build(&mut self, order: &mut [u32], boxes: &[([f32; 3], [f32; 3])], first: usize) {
        let id = self.nodes.len();
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        let (mut clo, mut chi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for &i in order.iter() {
            let (a, b) = boxes[i as usize];
            for k in 0..3 {
                lo[k] = lo[k].min(a[k]);
                hi[k] = hi[k].max(b[k]);
                let c = 0.5 * (a[k] + b[k]);
                clo[k] = clo[k].min(c);
                chi[k] = chi[k].max(c);
            }
        }
        if order.len() <= LEAF {
            self.nodes.push((lo, hi, first as u32, order.len() as u32));
            return;
        }
        self.nodes.push((lo, hi, 0, 0));
        let axis = (0..3)
            .max_by(|&a, &b| (chi[a] - clo[a]).total_cmp(&(chi[b] - clo[b])))
            .unwrap_or(0);
        let mid = order.len() / 2;
        let centre = |i: &u32| {
            let (a, b) = boxes[*i as usize];
            a[axis] + b[axis]
        };
        order.select_nth_unstable_by(mid, |x, y| centre(x).total_cmp(&centre(y)));
        let (left, right) = order.split_at_mut(mid);
        self.build(left, boxes, first);
        self.nodes[id].2 = self.nodes.len() as u32;
        self.build(right, boxes, first + mid);
    }

    fn box_d2(&self, n: usize, p: P3) -> f64 {
        let (lo, hi, _, _) = &self.nodes[n];
        let mut s = 0.0;
        for k in 0..3 {
            let d = (lo[k] as f64 - p[k]).max(p[k] - hi[k] as f64).max(0.0);
            s += d * d;
        }
        s
    }

    /// Squared distance from `p` to the nearest point of the soup.
    fn nearest_d2(&self, p: P3, stack: &mut Vec<u32>) -> f64 {
        let mut best = f64::INFINITY;
        stack.clear();
        stack.push(0);
        while let Some(n) = stack.pop() {
            let n = n as usize;
            if self.box_d2(n, p) >= best {
                continue;
            }
            let (_, _, first, count) = self.nodes[n];
            if count > 0 {
                for t in &self.tris[first as usize..(first + count) as usize] {
                    best = best.min(triangle_d2(p, t));
                }
                continue;
            }
            let (l, r) = (n + 1, first as usize);
            let (dl, dr) = (self.box_d2(l, p), self.box_d2(r, p));
            let (near, far, dfar) = if dl <= dr { (l, r, dr) } else { (r, l, dl) };
            if dfar < best {
                stack.push(far as u32);
            }
            stack.push(near as u32);
        }
        best
    }
}

/// Points of a soup: `count` uniform by area (seeded), then its distinct corners.
pub struct Samples {
    /// Uniform by area.
    pub area: Vec<P3>,
    /// Distinct corners.
    pub corners: Vec<P3>,
}

pub fn sample(tris: &[[[f32; 3]; 3]], count: usize, seed: u64) -> Samples {
    let mut cumulative = Vec::with_capacity(tris.len());
    let mut total = 0.0;
    for t in tris {
        let (a, b, c) = (wide(t[0]), wide(t[1]), wide(t[2]));
        let n = cross(sub(b, a), sub(c, a));
        total += 0.5 * dot(n, n).sqrt();
        cumulative.push(total);
    }
    let mut rng = Rng(seed);
    let area = (0..count)
        .map(|_| {
            let x = rng.unit_f64() * total;
            let i = cumulative.partition_point(|&c| c <= x).min(tris.len() - 1);
            let t = &tris[i];
            let (a, b, c) = (wide(t[0]), wide(t[1]), wide(t[2]));
            let s = rng.unit_f64().sqrt();
            let r = rng.unit_f64();
            axpy(axpy(a, s * (1.0 - r), sub(b, a)), s * r, sub(c, a))
        })
        .collect();
    let mut corners: Vec<[u32; 3]> = tris
        .iter()
        .flat_map(|t| t.iter().map(|p| p.map(f32::to_bits)))
        .collect();
    corners.sort_unstable();
    corners.dedup();
    Samples {
        area,
        corners: corners
            .iter()
            .map(|p| p.map(f32::from_bits))
            .map(wide)
            .collect(),
    }
}

/// One direction: `(largest distance over all samples, sum of squares over the area samples)`.
pub fn one_way(samples: &Samples, target: &Bvh) -> (f64, f64) {
    let mut stack = Vec::with_capacity(64);
    let (mut max, mut sum) = (0.0f64, 0.0f64);
    for &p in &samples.area {
        let d = target.nearest_d2(p, &mut stack);
        max = max.max(d);
        sum += d;
    }
    for &p in &samples.corners {
        max = max.max(target.nearest_d2(p, &mut stack));
    }
    (max.sqrt(), sum)
}

/// The input, ready for comparisons.
pub struct Reference {
    /// Nearest-point queries on the input.
    pub bvh: Bvh,
    /// Points on the input.
    pub samples: Samples,
    /// The input's bounding-box diagonal.
    pub diagonal: f64,
}

/// `(Hausdorff, RMS)` of `result` against the reference, both over the diagonal.
pub fn distances(r: &Reference, result: &[[[f32; 3]; 3]], count: usize, seed: u64) -> (f64, f64) {
    let s = sample(result, count, seed);
    let bvh = Bvh::new(result);
    let (h1, s1) = one_way(&s, &r.bvh);
    let (h2, s2) = one_way(&r.samples, &bvh);
    let n = (s.area.len() + r.samples.area.len()) as f64;
    (h1.max(h2) / r.diagonal, ((s1 + s2) / n).sqrt() / r.diagonal)
}

impl Reference {
    /// The input soup with `count` area samples (seed `seed`) and its diagonal.
    pub fn new(input: &[[[f32; 3]; 3]], count: usize, seed: u64) -> Self {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in input.iter().flatten() {
            for k in 0..3 {
                lo[k] = lo[k].min(f64::from(p[k]));
                hi[k] = hi[k].max(f64::from(p[k]));
            }
        }
        Self {
            bvh: Bvh::new(input),
            samples: sample(input, count, seed),
            diagonal: d2(lo, hi).sqrt(),
        }
    }
}
