//! Collision avoidance as an inequality: capsules fixed in the joints' frames keep at least
//! `margin` between their surfaces, and above the floor (`y = 0`). Each row is one
//! constraint along its line of closest approach: the distance between the surfaces, with an
//! error where it is under the margin, a zero error within [`COLLISION_BAND`] over it (the
//! surfaces may slide along each other but not come closer), nothing further out. A task has a
//! fixed number of rows: the nearest constraints fill them, nearest first; the rest are empty
//! (zero rows).

use std::sync::Arc;

use glam::DVec3;

use super::point_column;
use crate::{Frames, Skeleton};

/// How far past the margin a constraint still holds (with a zero error): the lower levels may
/// not pull the surfaces back together (m).
pub const COLLISION_BAND: f64 = 0.002;

/// A collision task's data: the surfaces of the `pairs` of `capsules` (and of the `floor`
/// capsules and the floor `y = 0`) keep at least `margin` apart, `rows` constraints at once.
/// One row per constraint along its line of closest approach, the nearest first: an error
/// where two surfaces are closer than the margin, a zero error within [`COLLISION_BAND`]
/// beyond it (they may slide along each other but not come closer), empty rows for the rest.
/// Pairs far apart cost the distance of two bounding spheres.
#[derive(Debug, Clone, PartialEq)]
pub struct Collision {
    /// The body's capsules.
    pub capsules: Arc<[Capsule]>,
    /// Indices into `capsules` of the pairs tested ([`collision_pairs`]).
    pub pairs: Arc<[(usize, usize)]>,
    /// Indices into `capsules` of those kept above the floor ([`floor_capsules`]).
    pub floor: Arc<[usize]>,
    /// Distance kept between surfaces (m), >= 0.
    pub margin: f64,
    /// Constraints held at once (>= 1).
    pub rows: usize,
}

impl Collision {
    /// Checks the data against a skeleton; the reason names the offending part.
    pub fn validate(&self, skeleton: &Skeleton) -> Result<(), String> {
        for (i, c) in self.capsules.iter().enumerate() {
            if c.joint >= skeleton.joint_count() {
                return Err(format!("capsule {i}: joint index {} out of range", c.joint));
            }
            if !(c.start.is_finite() && c.end.is_finite()) {
                return Err(format!("capsule {i}: its ends are not finite"));
            }
            if !(c.radius.is_finite() && c.radius > 0.0) {
                return Err(format!("capsule {i}: radius must be finite and > 0"));
            }
        }
        let n = self.capsules.len();
        if let Some(&(a, b)) = self
            .pairs
            .iter()
            .find(|&&(a, b)| a == b || a >= n || b >= n)
        {
            return Err(format!("pair ({a}, {b}) is not two of the capsules"));
        }
        if let Some(i) = self.floor.iter().find(|&&i| i >= n) {
            return Err(format!("floor capsule {i} is not one of the capsules"));
        }
        if !(self.margin.is_finite() && self.margin >= 0.0) {
            return Err("margin must be finite and >= 0".into());
        }
        if self.rows == 0 {
            return Err("a collision task needs at least one row".into());
        }
        Ok(())
    }

    /// The constraints at `frames`: every pair and every floor capsule within the margin plus
    /// the band, nearest first, at most `rows`.
    pub(super) fn constraints(&self, frames: &Frames) -> Vec<Constraint> {
        constraints(
            frames,
            &self.capsules,
            &self.pairs,
            self.margin,
            &self.floor,
            self.rows,
        )
    }
}

/// A capsule of the body: a segment fixed in a joint's frame, swept by a sphere.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Capsule {
    /// The joint whose frame carries it.
    pub joint: usize,
    /// Centre of the start cap, joint frame (m).
    pub start: DVec3,
    /// Centre of the end cap, joint frame (m).
    pub end: DVec3,
    /// Radius of the swept sphere (m).
    pub radius: f64,
}

impl Capsule {
    /// Its two cap centres in the world, the body posed as `frames` say.
    pub fn world(&self, frames: &Frames) -> (DVec3, DVec3) {
        (
            frames.point(self.joint, self.start),
            frames.point(self.joint, self.end),
        )
    }
}

/// The closest points of the segments `p0 p1` and `q0 q1` (one on each; either may be a
/// point): the pair minimising the distance, the first segment's parameter clamped first
/// where the segments are parallel.
pub fn closest_points(p0: DVec3, p1: DVec3, q0: DVec3, q1: DVec3) -> (DVec3, DVec3) {
    let (u, v, w) = (p1 - p0, q1 - q0, p0 - q0);
    let (a, b, c) = (u.dot(u), u.dot(v), v.dot(v));
    let (d, e) = (u.dot(w), v.dot(w));
    const TINY: f64 = 1e-18;
    // t for a given s: the projection of the point at s onto the second segment.
    let t_of = |s: f64| {
        if c <= TINY {
            0.0
        } else {
            ((b * s + e) / c).clamp(0.0, 1.0)
        }
    };
    // s for a given t: the projection of the point at t onto the first segment.
    let s_of = |t: f64| {
        if a <= TINY {
            0.0
        } else {
            ((b * t - d) / a).clamp(0.0, 1.0)
        }
    };
    let denominator = a * c - b * b;
    let s = if a <= TINY {
        0.0
    } else if denominator <= TINY * a.max(1.0) * c.max(1.0) {
        // Parallel (or the second a point): any s; the start of the first.
        0.0
    } else {
        ((b * e - c * d) / denominator).clamp(0.0, 1.0)
    };
    let t = t_of(s);
    // Clamping t may move the best s: project back once.
    let s = s_of(t);
    let t = t_of(s);
    (p0 + u * s, q0 + v * t)
}

/// The pairs of `capsules` a collision task tests: capsules on joints at least three steps
/// apart in the tree (a bone and its neighbours, which share a joint, always touch), and more
/// than `clearance` apart at the rest posture `rest` (capsules that touch standing at rest,
/// such as the chest and the upper arms' roots, are one body; pass the task's margin and
/// [`COLLISION_BAND`], so that no pair starts held).
pub fn collision_pairs(
    skeleton: &Skeleton,
    capsules: &[Capsule],
    rest: &Frames,
    clearance: f64,
) -> Vec<(usize, usize)> {
    let parents: Vec<Option<usize>> = skeleton.joints().iter().map(|j| j.parent).collect();
    let depth = |mut j: usize| {
        let mut k = 0;
        while let Some(p) = parents.get(j).copied().flatten() {
            j = p;
            k += 1;
        }
        k
    };
    // Steps between two joints through their lowest common ancestor.
    let steps = |mut a: usize, mut b: usize| {
        let (mut da, mut db) = (depth(a), depth(b));
        let mut k = 0;
        while a != b {
            if da >= db {
                let Some(p) = parents[a] else { break };
                a = p;
                da -= 1;
            } else {
                let Some(p) = parents[b] else { break };
                b = p;
                db -= 1;
            }
            k += 1;
        }
        k
    };
    let mut pairs = Vec::new();
    for i in 0..capsules.len() {
        for j in i + 1..capsules.len() {
            let (a, b) = (&capsules[i], &capsules[j]);
            if a.joint >= parents.len() || b.joint >= parents.len() || steps(a.joint, b.joint) < 3 {
                continue;
            }
            if surface_distance(a, a.world(rest), b, b.world(rest)).0 > clearance {
                pairs.push((i, j));
            }
        }
    }
    pairs
}

/// The capsules a collision task keeps above the floor `y = 0`: those clear of it at the rest
/// posture (`rest`). The feet's capsules, which stand on it (their axes run through the bones,
/// so their bottoms dip under the sole), are left to the tasks that hold the feet.
pub fn floor_capsules(capsules: &[Capsule], rest: &Frames) -> Vec<usize> {
    capsules
        .iter()
        .enumerate()
        .filter(|(_, c)| {
            let (a, b) = c.world(rest);
            a.y.min(b.y) - c.radius > 0.0
        })
        .map(|(i, _)| i)
        .collect()
}

/// The distance between the surfaces of `a` and `b` whose axes' ends are given (in the
/// world; negative where they overlap) and the closest points of their axes, on each.
fn surface_distance(
    a: &Capsule,
    (a0, a1): (DVec3, DVec3),
    b: &Capsule,
    (b0, b1): (DVec3, DVec3),
) -> (f64, DVec3, DVec3) {
    let (pa, pb) = closest_points(a0, a1, b0, b1);
    ((pa - pb).length() - a.radius - b.radius, pa, pb)
}

/// One constraint: the distance between two surfaces (or a surface and the floor) and how it
/// changes.
#[derive(Debug, Clone, Copy)]
pub(super) struct Constraint {
    /// Distance between the surfaces (m).
    pub distance: f64,
    /// Closest point of the first capsule's axis, and its joint.
    a: (usize, DVec3),
    /// The second capsule's, or `None` for the floor.
    b: Option<(usize, DVec3)>,
    /// Unit direction from the second to the first (up for the floor).
    normal: DVec3,
}

/// The task's errors at `found` (`margin` less each distance where it is under it, 0 for the
/// rows held in the band and the empty ones); returns their norm.
pub(super) fn errors(found: &[Constraint], margin: f64, err: &mut [f64]) -> f64 {
    err.fill(0.0);
    for (e, c) in err.iter_mut().zip(found) {
        *e = (margin - c.distance).max(0.0);
    }
    err.iter().map(|e| e * e).sum::<f64>().sqrt()
}

/// The task's rows at `found` into `jac_t` (`n x rows`, column-major, zero on entry): each
/// the distance's change for unit velocities of the DOF of the two points' chains.
pub(super) fn write_rows(
    skeleton: &Skeleton,
    frames: &Frames,
    found: &[Constraint],
    jac_t: &mut [f64],
    n: usize,
) {
    for (row, c) in found.iter().enumerate() {
        let Some(column) = jac_t.get_mut(row * n..(row + 1) * n) else {
            return;
        };
        let ends = [(c.a.0, c.a.1, 1.0)]
            .into_iter()
            .chain(c.b.map(|(j, p)| (j, p, -1.0)));
        for (joint, point, sign) in ends {
            for d in skeleton.chain_dofs(joint) {
                column[d] += sign
                    * c.normal
                        .dot(point_column(skeleton, frames, d, joint, point));
            }
        }
    }
}

/// The task's constraints at `frames`: every pair and every capsule of `floor` within
/// `margin` plus the band, nearest first, at most `rows`. Pairs whose capsules' bounding
/// spheres are further apart cost a distance of centres only.
fn constraints(
    frames: &Frames,
    capsules: &[Capsule],
    pairs: &[(usize, usize)],
    margin: f64,
    floor: &[usize],
    rows: usize,
) -> Vec<Constraint> {
    let reach = margin + COLLISION_BAND;
    // Each capsule's ends in the world and its bounding sphere, once.
    let ends: Vec<(DVec3, DVec3)> = capsules.iter().map(|c| c.world(frames)).collect();
    let spheres: Vec<(DVec3, f64)> = capsules
        .iter()
        .zip(&ends)
        .map(|(c, &(a, b))| ((a + b) * 0.5, (b - a).length() * 0.5 + c.radius))
        .collect();
    let mut found = Vec::new();
    for &(i, j) in pairs {
        let (Some(a), Some(b)) = (capsules.get(i), capsules.get(j)) else {
            continue;
        };
        let ((ca, ra), (cb, rb)) = (spheres[i], spheres[j]);
        let apart = ra + rb + reach;
        if (ca - cb).length_squared() > apart * apart {
            continue;
        }
        let (distance, pa, pb) = surface_distance(a, ends[i], b, ends[j]);
        let gap = pa - pb;
        if distance < reach && gap.length() > 1e-9 {
            found.push(Constraint {
                distance,
                a: (a.joint, pa),
                b: Some((b.joint, pb)),
                normal: gap.normalize(),
            });
        }
    }
    for (c, &(p0, p1)) in floor
        .iter()
        .filter_map(|&i| Some((capsules.get(i)?, ends.get(i)?)))
    {
        {
            let low = if p0.y <= p1.y { p0 } else { p1 };
            let distance = low.y - c.radius;
            if distance < reach {
                found.push(Constraint {
                    distance,
                    a: (c.joint, low),
                    b: None,
                    normal: DVec3::Y,
                });
            }
        }
    }
    found.sort_by(|x, y| x.distance.total_cmp(&y.distance));
    found.truncate(rows);
    found
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    use super::*;

    /// The distance of two segments by another route: `f(s) = min_t |p(s) - q(t)|` is convex
    /// in `s` (the distance of a point on a line to a convex set, along a line), its inner
    /// minimum the clamped projection; a golden-section search over `s`.
    fn searched(p0: DVec3, p1: DVec3, q0: DVec3, q1: DVec3) -> f64 {
        let v = q1 - q0;
        let inner = |s: f64| {
            let p = p0 + (p1 - p0) * s;
            let t = if v.length_squared() > 0.0 {
                ((p - q0).dot(v) / v.length_squared()).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (p - (q0 + v * t)).length()
        };
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        let g = (5f64.sqrt() - 1.0) / 2.0;
        for _ in 0..200 {
            let (m1, m2) = (hi - g * (hi - lo), lo + g * (hi - lo));
            if inner(m1) <= inner(m2) {
                hi = m2;
            } else {
                lo = m1;
            }
        }
        inner((lo + hi) / 2.0).min(inner(0.0)).min(inner(1.0))
    }

    /// Catches a closest-point routine that clamps wrongly (end against end, a point against
    /// a segment, parallel segments): on random segments, some degenerate, some parallel, the
    /// distance equals the searched one and both points lie on their segments.
    #[test]
    fn closest_points_match_a_search_along_the_segments() {
        let mut r = StdRng::seed_from_u64(3);
        let point = |r: &mut StdRng| {
            DVec3::new(
                r.random_range(-1.0..1.0),
                r.random_range(-1.0..1.0),
                r.random_range(-1.0..1.0),
            )
        };
        for case in 0..2000 {
            let p0 = point(&mut r);
            let mut p1 = point(&mut r);
            let q0 = point(&mut r);
            let mut q1 = point(&mut r);
            match case % 5 {
                0 => p1 = p0,
                1 => q1 = q0,
                2 => q1 = q0 + (p1 - p0) * 0.7,
                _ => {}
            }
            let (pa, pb) = closest_points(p0, p1, q0, q1);
            let on = |x: DVec3, a: DVec3, b: DVec3| {
                let ab = b - a;
                let t = if ab.length_squared() > 0.0 {
                    ((x - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                (a + ab * t - x).length() < 1e-9
            };
            assert!(on(pa, p0, p1) && on(pb, q0, q1), "case {case}");
            let expected = searched(p0, p1, q0, q1);
            let got = (pa - pb).length();
            assert!(
                (got - expected).abs() < 1e-9,
                "case {case}: {got} vs {expected}"
            );
        }
    }
}
