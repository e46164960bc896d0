//! The rotation a joint can take that is nearest to a wanted rotation: a rotation vector with
//! components only on the joint's rotational DOF axes, each within its limits, minimising the
//! geodesic angle on SO(3) to the wanted rotation. Used for the end joint (wrist, ankle) of a
//! [`crate::Limb`] with a goal orientation.
//!
//! # Without limits: a closed form
//! With `q = (w, v)` the wanted rotation and `m` the joint's DOF axes, the rotations `exp(r)`
//! with `r` on those axes are exactly the unit quaternions `p` in the subspace
//! `span(1, m)` (a rotation about an axis in `span(m)`). The angle between `p` and `q` is
//! `2 acos |p . q|`, and over unit `p` of that subspace `|p . q|` is largest for the
//! normalised projection of `q` onto it: **zero the missing quaternion components and
//! renormalise**. Zeroing the missing components of the rotation *vector* instead (keeping the
//! full angle on the remaining axes) is not the nearest rotation for a 2-DOF wrist, nor for a
//! hinge. When the projection vanishes (`q` a half turn about a missing axis) every rotation of
//! the DOF is a half turn away; the result is then the one nearest to zero within the limits.
//!
//! # With limits
//! The rotation vector of the projection, `r*` (`|r*| <= pi`), and its images
//! `r* (1 + 2 pi m / |r*|)` are the only interior minima; the first of them inside the box of
//! limits is the answer. Otherwise the minimum lies on the box's boundary: the two ends for one
//! DOF (exact: the angle is unimodal on each period), the four edges for two DOF (each a 1-D
//! problem: dense samples, every sampled local minimum refined by golden-section search), the
//! six faces for three DOF (a sampled grid with Gauss-Newton refinement, plus the edges). A DOF
//! without a limit is searched within `[-UNLIMITED_RANGE, UNLIMITED_RANGE]`.

use std::f64::consts::TAU;

use glam::{DQuat, DVec3};

/// Search range of a rotational DOF without a limit (rad): a joint without limits reaches
/// every rotation of its DOF with `|r| <= pi`; `2 pi` leaves room for the other DOF of a joint
/// whose DOF are only partly limited.
pub const UNLIMITED_RANGE: f64 = TAU;

/// Sample spacing along a boundary edge (rad; the angle is 1-Lipschitz in the rotation vector).
const EDGE_STEP: f64 = 0.02;
/// Grid spacing on a boundary face of a 3-DOF box (rad).
const FACE_STEP: f64 = 0.2;

/// Rotation vector (log map, angle in [0, pi]) of a unit quaternion, accurate for small angles.
pub(crate) fn rotation_vector(q: DQuat) -> DVec3 {
    let q = if q.w < 0.0 { -q } else { q };
    let xyz = DVec3::new(q.x, q.y, q.z);
    let s = xyz.length();
    if s < 1e-300 {
        return DVec3::ZERO;
    }
    let angle = 2.0 * s.atan2(q.w);
    xyz * (angle / s)
}

/// Geodesic angle (rad, in [0, pi]) between two unit quaternions' rotations.
pub fn rotation_angle(a: DQuat, b: DQuat) -> f64 {
    let d = a.inverse() * b;
    2.0 * DVec3::new(d.x, d.y, d.z).length().atan2(d.w.abs())
}

/// The rotation vector nearest (geodesic angle) to `target` among those with components only
/// on the axes where `dofs` is true (x, y, z of the joint frame), each component `i` within
/// `[lower[i], upper[i]]` (an infinite or NaN bound: `UNLIMITED_RANGE`). Components off the
/// DOF axes are 0. Without limits the result has `|r| <= pi`. A non-finite or zero `target`
/// counts as the identity. Never NaN.
pub fn nearest_rotation_vector(
    target: DQuat,
    dofs: [bool; 3],
    lower: DVec3,
    upper: DVec3,
) -> DVec3 {
    let q = if target.is_finite() && target.length_squared() > 1e-300 {
        target.normalize()
    } else {
        DQuat::IDENTITY
    };
    let q = if q.w < 0.0 { -q } else { q };
    let mut lo = DVec3::ZERO;
    let mut hi = DVec3::ZERO;
    let mut axes = [0usize; 3];
    let mut k = 0;
    for a in 0..3 {
        if dofs[a] {
            let l = if lower[a].is_finite() {
                lower[a]
            } else {
                -UNLIMITED_RANGE
            };
            let h = if upper[a].is_finite() {
                upper[a]
            } else {
                UNLIMITED_RANGE
            };
            lo[a] = l;
            hi[a] = h.max(l);
            axes[k] = a;
            k += 1;
        }
    }
    let problem = Problem {
        q,
        lo,
        hi,
        axes: &axes[..k],
    };
    if k == 0 {
        return DVec3::ZERO;
    }
    let mut v = DVec3::new(q.x, q.y, q.z);
    for a in 0..3 {
        if !dofs[a] {
            v[a] = 0.0;
        }
    }
    let norm = (q.w * q.w + v.length_squared()).sqrt();
    if norm < 1e-12 {
        // Every rotation of the DOF is equally far (a half turn, to 1e-11 rad): the one
        // nearest to zero.
        return DVec3::ZERO.clamp(lo, hi);
    }
    // The projection; its rotation vector is exactly 0 off the DOF axes.
    let r_star = rotation_vector(DQuat::from_xyzw(
        v.x / norm,
        v.y / norm,
        v.z / norm,
        q.w / norm,
    ));
    let len = r_star.length();
    if len == 0.0 {
        if problem.inside(DVec3::ZERO) {
            return DVec3::ZERO;
        }
    } else {
        // The images of r*, nearest to zero first.
        for m in [0.0, -1.0, 1.0, -2.0, 2.0] {
            let r = r_star * ((len + TAU * m) / len);
            if problem.inside(r) {
                return r;
            }
        }
    }
    problem.boundary_minimum().0
}

/// One box-constrained nearest-rotation problem.
struct Problem<'a> {
    q: DQuat,
    lo: DVec3,
    hi: DVec3,
    axes: &'a [usize],
}

impl Problem<'_> {
    fn angle(&self, r: DVec3) -> f64 {
        rotation_angle(DQuat::from_scaled_axis(r), self.q)
    }

    fn inside(&self, r: DVec3) -> bool {
        self.axes
            .iter()
            .all(|&a| r[a] >= self.lo[a] && r[a] <= self.hi[a])
    }

    /// The minimum over the box's boundary (each active axis in turn at either bound).
    fn boundary_minimum(&self) -> (DVec3, f64) {
        let mut best = (DVec3::ZERO.clamp(self.lo, self.hi), f64::INFINITY);
        let mut consider = |c: (DVec3, f64)| {
            if c.1 < best.1 {
                best = c;
            }
        };
        for (i, &a) in self.axes.iter().enumerate() {
            let free: Vec<usize> = self
                .axes
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, &b)| b)
                .collect();
            for bound in [self.lo[a], self.hi[a]] {
                let mut start = DVec3::ZERO;
                start[a] = bound;
                consider(self.minimize_on(start, &free));
            }
        }
        if !best.1.is_finite() {
            let r = DVec3::ZERO.clamp(self.lo, self.hi);
            return (r, self.angle(r));
        }
        best
    }

    /// Minimum over the free axes (within their bounds), the others as in `fixed`.
    fn minimize_on(&self, fixed: DVec3, free: &[usize]) -> (DVec3, f64) {
        match free {
            [] => (fixed, self.angle(fixed)),
            [a] => self.minimize_edge(fixed, *a),
            [a, b] => self.minimize_face(fixed, *a, *b),
            _ => (fixed, self.angle(fixed)),
        }
    }

    /// 1-D: samples every `EDGE_STEP`, each sampled local minimum refined by golden section.
    fn minimize_edge(&self, fixed: DVec3, axis: usize) -> (DVec3, f64) {
        let (a, b) = (self.lo[axis], self.hi[axis]);
        let at = |t: f64| {
            let mut r = fixed;
            r[axis] = t;
            r
        };
        let f = |t: f64| self.angle(at(t));
        let n = (((b - a) / EDGE_STEP).ceil() as usize).clamp(1, 4096);
        let t = |i: usize| grid(a, b, i, n);
        let values: Vec<f64> = (0..=n).map(|i| f(t(i))).collect();
        let mut best = (a, values[0]);
        for i in 0..=n {
            let left = i == 0 || values[i] < values[i - 1];
            let right = i == n || values[i] <= values[i + 1];
            if !(left && right) {
                continue;
            }
            let lo = if i == 0 { a } else { t(i - 1) };
            let hi = if i == n { b } else { t(i + 1) };
            let (x, fx) = golden(&f, lo, hi);
            for (x, fx) in [(t(i), values[i]), (x, fx)] {
                if fx < best.1 {
                    best = (x, fx);
                }
            }
        }
        (at(best.0), best.1)
    }

    /// 2-D: a grid every `FACE_STEP`, each grid local minimum refined by Gauss-Newton, and
    /// the face's four edges.
    fn minimize_face(&self, fixed: DVec3, a: usize, b: usize) -> (DVec3, f64) {
        let na = (((self.hi[a] - self.lo[a]) / FACE_STEP).ceil() as usize).clamp(1, 256);
        let nb = (((self.hi[b] - self.lo[b]) / FACE_STEP).ceil() as usize).clamp(1, 256);
        let at = |i: usize, j: usize| {
            let mut r = fixed;
            r[a] = grid(self.lo[a], self.hi[a], i, na);
            r[b] = grid(self.lo[b], self.hi[b], j, nb);
            r
        };
        let values: Vec<f64> = (0..=na)
            .flat_map(|i| (0..=nb).map(move |j| (i, j)))
            .map(|(i, j)| self.angle(at(i, j)))
            .collect();
        let value = |i: usize, j: usize| values[i * (nb + 1) + j];
        let mut best = (at(0, 0), value(0, 0));
        for i in 0..=na {
            for j in 0..=nb {
                let v = value(i, j);
                let lower_than_neighbours = (i == 0 || v <= value(i - 1, j))
                    && (i == na || v <= value(i + 1, j))
                    && (j == 0 || v <= value(i, j - 1))
                    && (j == nb || v <= value(i, j + 1));
                if !lower_than_neighbours {
                    continue;
                }
                let refined = self.gauss_newton(at(i, j), [a, b]);
                for c in [(at(i, j), v), refined] {
                    if c.1 < best.1 {
                        best = c;
                    }
                }
            }
        }
        for (axis, other) in [(a, b), (b, a)] {
            for bound in [self.lo[other], self.hi[other]] {
                let mut edge = fixed;
                edge[other] = bound;
                let c = self.minimize_edge(edge, axis);
                if c.1 < best.1 {
                    best = c;
                }
            }
        }
        best
    }

    /// Projected Levenberg-Marquardt on the residual `log(exp(r)^-1 q)` over two free axes.
    fn gauss_newton(&self, start: DVec3, free: [usize; 2]) -> (DVec3, f64) {
        let residual = |r: DVec3| rotation_vector(DQuat::from_scaled_axis(r).inverse() * self.q);
        let mut r = start;
        let mut e = residual(r);
        let mut f = self.angle(r);
        let mut mu = 1e-9;
        for _ in 0..60 {
            let h = 1e-7;
            let mut cols = [DVec3::ZERO; 2];
            for (c, &axis) in cols.iter_mut().zip(&free) {
                let (mut plus, mut minus) = (r, r);
                plus[axis] += h;
                minus[axis] -= h;
                *c = (residual(plus) - residual(minus)) / (2.0 * h);
            }
            // A DOF on a bound whose descent direction points outward stays there.
            let g = [cols[0].dot(e), cols[1].dot(e)];
            let mut active = [true; 2];
            for (k, &axis) in free.iter().enumerate() {
                let at_lo = r[axis] <= self.lo[axis] && g[k] > 0.0;
                let at_hi = r[axis] >= self.hi[axis] && g[k] < 0.0;
                active[k] = !(at_lo || at_hi);
            }
            let (m00, m01, m11) = (
                cols[0].dot(cols[0]),
                cols[0].dot(cols[1]),
                cols[1].dot(cols[1]),
            );
            let mut improved = false;
            while mu < 1e6 {
                let (a00, a11) = (m00 + mu, m11 + mu);
                let step = match active {
                    [true, true] => {
                        let det = a00 * a11 - m01 * m01;
                        [
                            -(a11 * g[0] - m01 * g[1]) / det,
                            -(a00 * g[1] - m01 * g[0]) / det,
                        ]
                    }
                    [true, false] => [-g[0] / a00, 0.0],
                    [false, true] => [0.0, -g[1] / a11],
                    [false, false] => [0.0, 0.0],
                };
                if step.iter().all(|s| s.abs() < 1e-15) || !step.iter().all(|s| s.is_finite()) {
                    break;
                }
                let mut candidate = r;
                for (k, &axis) in free.iter().enumerate() {
                    candidate[axis] =
                        (candidate[axis] + step[k]).clamp(self.lo[axis], self.hi[axis]);
                }
                let fc = self.angle(candidate);
                if fc < f {
                    r = candidate;
                    f = fc;
                    e = residual(r);
                    mu = (mu * 0.1).max(1e-12);
                    improved = true;
                    break;
                }
                mu *= 10.0;
            }
            if !improved {
                break;
            }
        }
        (r, f)
    }
}

/// Point `i` of `n` equal steps from `a` to `b` (`b` exactly at `i = n`).
fn grid(a: f64, b: f64, i: usize, n: usize) -> f64 {
    if i >= n {
        b
    } else {
        a + (b - a) * i as f64 / n as f64
    }
}

/// Golden-section search for a minimum of `f` on `[a, b]`; returns (argument, value).
pub(crate) fn golden(f: &impl Fn(f64) -> f64, mut a: f64, mut b: f64) -> (f64, f64) {
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let mut x1 = b - g * (b - a);
    let mut x2 = a + g * (b - a);
    let mut f1 = f(x1);
    let mut f2 = f(x2);
    for _ in 0..90 {
        if b - a < 1e-14 {
            break;
        }
        if f1 <= f2 {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - g * (b - a);
            f1 = f(x1);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + g * (b - a);
            f2 = f(x2);
        }
    }
    if f1 <= f2 { (x1, f1) } else { (x2, f2) }
}
