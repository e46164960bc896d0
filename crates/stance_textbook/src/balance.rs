//! The `balance` task as the problem format defines it, written here from that definition: the
//! centre of mass's projection on the floor (XZ) kept inside the convex hull of the support
//! points shrunk by `margin` (no margin with one point or points on one line), a foot standing
//! for its sole (four corners sized from the foot's toe joints, else from the leg's length in
//! anthropometric proportions, Drillis & Contini).
//!
//! The polygon is never built as a hull: with a handful of support points, the edges are the
//! pairs of points with every other point on one side of their line, and the distance from
//! outside is the least distance to any segment between two points (every chord lies inside
//! the hull, so the nearest is on its boundary).

use nalgebra::Vector3;

use crate::{Frames, Problem};

/// Foot length, breadth and hip-to-ankle height as fractions of stature (Drillis & Contini
/// 1966), the heel's share of the foot behind the ankle and the ball's share ahead of it.
const FOOT_LENGTH: f64 = 0.152;
const FOOT_BREADTH: f64 = 0.055;
const HIP_TO_ANKLE: f64 = 0.491;
const HEEL_SHARE: f64 = 0.2;
const BALL_SHARE: f64 = 0.55;
/// Stature without a leg to measure (m).
const STATURE: f64 = 1.7;
/// Inside the polygon by less than this, the row already holds the centre of mass (m).
pub(crate) const BAND: f64 = 0.002;

/// The name without its side (`l_`, `r_`).
fn bare(name: &str) -> &str {
    name.strip_prefix("l_")
        .or_else(|| name.strip_prefix("r_"))
        .unwrap_or(name)
}

/// A foot joint: the ankle, a mid-foot joint or a toe joint.
fn is_foot(name: &str) -> bool {
    let b = bare(name);
    b == "talocrural"
        || [
            "metatarsophalangeal",
            "tarsal_",
            "tarso",
            "talo",
            "cuneo",
            "calcaneo",
            "transverse",
        ]
        .iter()
        .any(|p| b.starts_with(p))
}

/// Where the centre of mass stands with respect to the support polygon.
pub(crate) struct Standing {
    /// Signed distance past the shrunk polygon (m): > 0 outside.
    pub(crate) violation: f64,
    /// The nearest boundary point is `(1 - t) p_a + t p_b` of support points `a` and `b`, and
    /// the violation grows along `normal` (horizontal, unit) as the centre of mass moves
    /// relative to it.
    pub(crate) a: usize,
    pub(crate) b: usize,
    pub(crate) t: f64,
    pub(crate) normal: [f64; 2],
}

fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

/// The nearest point of segment `a b` to `c`: its parameter and distance.
fn nearest_on_segment(c: [f64; 2], a: [f64; 2], b: [f64; 2]) -> (f64, f64) {
    let e = sub(b, a);
    let len2 = dot(e, e);
    let t = if len2 > 0.0 {
        (dot(sub(c, a), e) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let p = [a[0] + t * e[0], a[1] + t * e[1]];
    let d = sub(c, p);
    (t, dot(d, d).sqrt())
}

/// Where `c` stands with respect to the convex hull of `points` shrunk by `margin`.
pub(crate) fn standing(c: [f64; 2], points: &[[f64; 2]], margin: f64) -> Option<Standing> {
    let n = points.len();
    if n == 0 {
        return None;
    }
    let scale = points
        .iter()
        .map(|p| p[0].abs().max(p[1].abs()))
        .fold(1.0, f64::max);
    let eps = 1e-12 * scale * scale;
    // Edges: pairs with every point on their left or on their line (counter-clockwise).
    let mut edges = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let e = sub(points[j], points[i]);
            if i == j || dot(e, e) <= eps {
                continue;
            }
            if points.iter().all(|&p| cross(e, sub(p, points[i])) >= -eps) {
                edges.push((i, j));
            }
        }
    }
    let flat = points.iter().all(|&p| {
        points.iter().all(|&q| {
            points
                .iter()
                .all(|&r| cross(sub(q, p), sub(r, p)).abs() <= eps)
        })
    });
    let outside = flat
        || edges
            .iter()
            .any(|&(i, j)| cross(sub(points[j], points[i]), sub(c, points[i])) < 0.0);
    if outside {
        let mut best: Option<(f64, usize, usize, f64)> = None;
        for i in 0..n {
            for j in i..n {
                let (t, d) = nearest_on_segment(c, points[i], points[j]);
                if best.is_none_or(|b| d < b.0) {
                    best = Some((d, i, j, t));
                }
            }
        }
        let (d, a, b, t) = best?;
        let p = [
            points[a][0] + t * (points[b][0] - points[a][0]),
            points[a][1] + t * (points[b][1] - points[a][1]),
        ];
        let away = sub(c, p);
        let normal = if d > 1e-12 {
            [away[0] / d, away[1] / d]
        } else {
            [1.0, 0.0]
        };
        let margin = if flat { 0.0 } else { margin };
        return Some(Standing {
            violation: d + margin,
            a,
            b,
            t,
            normal,
        });
    }
    // Inside: minus the distance to the nearest edge's line.
    let mut best: Option<Standing> = None;
    for &(i, j) in &edges {
        let e = sub(points[j], points[i]);
        let len = dot(e, e).sqrt();
        // Outward: to the right of a counter-clockwise edge.
        let normal = [e[1] / len, -e[0] / len];
        let signed = dot(normal, sub(c, points[i]));
        if best.as_ref().is_none_or(|b| signed + margin > b.violation) {
            best = Some(Standing {
                violation: signed + margin,
                a: i,
                b: j,
                t: dot(sub(c, points[i]), e) / (len * len),
                normal,
            });
        }
    }
    best
}

impl Problem {
    /// The support points of a `balance` task's `support` names: a foot joint gives its
    /// ankle's sole (once per foot), any other joint its centre. (joint, point in its frame).
    pub(crate) fn support_points(&self, names: &[&str]) -> Option<Vec<(usize, Vector3<f64>)>> {
        let mut feet = Vec::new();
        let mut points = Vec::new();
        for name in names {
            let j = self.joints.iter().position(|joint| joint.name == *name)?;
            if !is_foot(name) {
                points.push((j, Vector3::zeros()));
                continue;
            }
            let mut at = Some(j);
            let ankle = loop {
                let k = at?;
                if bare(&self.joints[k].name) == "talocrural" {
                    break k;
                }
                at = self.joints[k].parent;
            };
            if !feet.contains(&ankle) {
                feet.push(ankle);
                points.extend(self.sole(ankle).into_iter().map(|p| (ankle, p)));
            }
        }
        Some(points)
    }

    /// The four corners of the sole of `ankle`'s foot, in its frame (at rest, joint frames are
    /// the body's: +Z ahead, +Y up).
    fn sole(&self, ankle: usize) -> [Vector3<f64>; 4] {
        let f = self.frames(&vec![0.0; self.dof_count()]);
        let toes: Vec<f64> = (0..self.joints.len())
            .filter(|&j| {
                self.ancestor[j][ankle]
                    && bare(&self.joints[j].name).starts_with("metatarsophalangeal")
            })
            .map(|j| f.position[j].z - f.position[ankle].z)
            .collect();
        let ahead = toes.iter().sum::<f64>() / toes.len().max(1) as f64;
        let hip = self.joints[ankle]
            .parent
            .and_then(|knee| self.joints[knee].parent);
        let stature = hip
            .map(|h| (f.position[h] - f.position[ankle]).norm() / HIP_TO_ANKLE)
            .filter(|s| s.is_finite() && *s > 0.0)
            .unwrap_or(STATURE);
        let length = if ahead > 0.02 {
            ahead / BALL_SHARE
        } else {
            FOOT_LENGTH * stature
        };
        let half = 0.5 * FOOT_BREADTH * stature;
        let (heel, toe) = (-HEEL_SHARE * length, (1.0 - HEEL_SHARE) * length);
        [
            Vector3::new(-half, 0.0, heel),
            Vector3::new(half, 0.0, heel),
            Vector3::new(half, 0.0, toe),
            Vector3::new(-half, 0.0, toe),
        ]
    }

    /// Where the centre of mass stands over these support points at frames `f`.
    pub(crate) fn standing(
        &self,
        f: &Frames,
        support: &[(usize, Vector3<f64>)],
        margin: f64,
    ) -> Option<Standing> {
        let floor: Vec<[f64; 2]> = support
            .iter()
            .map(|(j, p)| {
                let w = f.position[*j] + f.rotation[*j] * p;
                [w.x, w.z]
            })
            .collect();
        let c = self.com(f);
        standing([c.x, c.z], &floor, margin)
    }
}

#[cfg(test)]
mod tests {
    use super::standing;

    /// Hand-computed distances to a unit square shrunk by 0.1, a segment and a point.
    #[test]
    fn distances_to_a_square_a_segment_and_a_point() {
        let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.5]];
        let at = |c: [f64; 2]| standing(c, &square, 0.1).unwrap().violation;
        assert!((at([0.5, 0.5]) - (-0.4)).abs() < 1e-12);
        assert!((at([0.95, 0.5]) - 0.05).abs() < 1e-12);
        assert!((at([2.0, 0.5]) - 1.1).abs() < 1e-12);
        // Past a corner: the distance to the corner.
        assert!((at([2.0, 2.0]) - (2f64.sqrt() + 0.1)).abs() < 1e-12);
        let segment = [[0.0, 0.0], [2.0, 0.0]];
        let s = standing([1.0, 0.5], &segment, 0.1).unwrap();
        assert!((s.violation - 0.5).abs() < 1e-12 && (s.t - 0.5).abs() < 1e-12);
        let point = standing([3.0, 4.0], &[[0.0, 0.0]], 0.1).unwrap();
        assert!((point.violation - 5.0).abs() < 1e-12);
    }
}
