//! Vector helpers, the point–triangle distance, triangle corners and normal cones.

pub(super) type V3 = [f64; 3];

pub(super) fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub(super) fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
pub(super) fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
pub(super) fn len(a: V3) -> f64 {
    dot(a, a).sqrt()
}
pub(super) fn norm(a: V3) -> V3 {
    let l = len(a);
    if l > 0.0 {
        [a[0] / l, a[1] / l, a[2] / l]
    } else {
        [0.0; 3]
    }
}

/// Squared distance from `x` to the triangle `a b c` ([`point_triangle_d2_from`] with
/// the edges and dot products computed here).
#[cfg(test)]
pub(super) fn point_triangle_d2(x: V3, a: V3, b: V3, c: V3) -> f64 {
    let (ab, ac, ax) = (sub(b, a), sub(c, a), sub(x, a));
    point_triangle_d2_from(x, [a, b, c], [ab, ac], [dot(ab, ax), dot(ac, ax)])
}

/// Squared distance from `x` to the triangle `a b c` (Ericson, "Real-Time Collision
/// Detection", 5.1.5: the closest point by the Voronoi region of `x`), from the triangle's
/// edges from `a`, `[ab, ac]`, and the dot products `[ab · ax, ac · ax]`, which a caller
/// has already.
#[inline]
pub(super) fn point_triangle_d2_from(
    x: V3,
    [a, b, c]: [V3; 3],
    [ab, ac]: [V3; 2],
    [d1, d2_]: [f64; 2],
) -> f64 {
    let d2 = |y: V3| dot(sub(x, y), sub(x, y));
    let along = |p: V3, s: f64, d: V3| [p[0] + s * d[0], p[1] + s * d[1], p[2] + s * d[2]];
    if d1 <= 0.0 && d2_ <= 0.0 {
        return d2(a);
    }
    let bx = sub(x, b);
    let (d3, d4) = (dot(ab, bx), dot(ac, bx));
    if d3 >= 0.0 && d4 <= d3 {
        return d2(b);
    }
    let vc = d1 * d4 - d3 * d2_;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return d2(along(a, d1 / (d1 - d3), ab));
    }
    let cx = sub(x, c);
    let (d5, d6) = (dot(ab, cx), dot(ac, cx));
    if d6 >= 0.0 && d5 <= d6 {
        return d2(c);
    }
    let vb = d5 * d2_ - d1 * d6;
    if vb <= 0.0 && d2_ >= 0.0 && d6 <= 0.0 {
        return d2(along(a, d2_ / (d2_ - d6), ac));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return d2(along(b, w, sub(c, b)));
    }
    let denom = va + vb + vc;
    if denom <= 0.0 {
        // Degenerate: the nearest corner.
        return d2(a).min(d2(b)).min(d2(c));
    }
    let (v, w) = (vb / denom, vc / denom);
    d2(along(along(a, v, ab), w, ac))
}

#[inline]
pub(super) fn next(k: usize) -> usize {
    if k == 2 {
        0
    } else {
        k + 1
    }
}

#[inline]
pub(super) fn prev(k: usize) -> usize {
    if k == 0 {
        2
    } else {
        k - 1
    }
}

/// The corner of `c` holding `v` (which it must hold).
#[inline]
pub(super) fn corner_of(c: [u32; 3], v: u32) -> usize {
    if c[0] == v {
        0
    } else if c[1] == v {
        1
    } else {
        debug_assert_eq!(c[2], v);
        2
    }
}

/// Smallest cone containing two cones `(axis, half angle)`.
pub(crate) fn merge_cones(a: ([f32; 3], f32), b: ([f32; 3], f32)) -> ([f32; 3], f32) {
    use std::f32::consts::PI;
    let d = (a.0[0] * b.0[0] + a.0[1] * b.0[1] + a.0[2] * b.0[2]).clamp(-1.0, 1.0);
    let phi = d.acos();
    if phi + b.1 <= a.1 {
        return a;
    }
    if phi + a.1 <= b.1 {
        return b;
    }
    let theta = (phi + a.1 + b.1) / 2.0;
    if theta >= PI || phi < 1e-6 {
        return (a.0, theta.min(PI));
    }
    let alpha = theta - a.1;
    let (wa, wb) = ((phi - alpha).sin() / phi.sin(), alpha.sin() / phi.sin());
    let axis = [
        a.0[0] * wa + b.0[0] * wb,
        a.0[1] * wa + b.0[1] * wb,
        a.0[2] * wa + b.0[2] * wb,
    ];
    let l = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    if l > 0.0 {
        ([axis[0] / l, axis[1] / l, axis[2] / l], theta)
    } else {
        (a.0, PI)
    }
}
