//! Balance geometry: the support points on the floor, their convex hull (the support
//! polygon), and where the centre of mass stands with respect to it.

use glam::DVec3;

use super::Effector;
use crate::Frames;

/// Width of the band inside the support polygon where the balance row is already active
/// (with a zero error), so that the lower levels slide the centre of mass along the boundary
/// instead of pushing it out every other iteration (m).
pub const BALANCE_BAND: f64 = 0.002;

/// Where the centre of mass stands with respect to the shrunk support polygon.
#[derive(Debug, Clone, Copy)]
pub(super) struct BalanceGeometry {
    /// Outward unit normal of the nearest boundary, horizontal.
    pub(super) normal: DVec3,
    /// Signed distance of the centre of mass's projection past the shrunk polygon (m):
    /// > 0 outside, <= 0 inside.
    pub(super) violation: f64,
    /// The nearest boundary point is `(1 - t) a + t b` of the support points `a`, `b` (a
    /// vertex: `a == b`); inside, the foot of the perpendicular on the nearest edge's line.
    /// The violation's derivative is `normal . (dc - (1 - t) da - t db)`: the support moves
    /// with the body unless something holds it.
    pub(super) a: usize,
    pub(super) b: usize,
    pub(super) t: f64,
}

/// A support point in the floor plane with its index in the task's list.
type FloorPoint = ([f64; 2], usize);

/// The support points' floor-plane positions (x, z) at `frames`, with their indices.
pub(super) fn floor_points(frames: &Frames, support: &[Effector]) -> Vec<FloorPoint> {
    support
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let p = frames.point(s.joint, s.point);
            ([p.x, p.z], i)
        })
        .collect()
}

impl BalanceGeometry {
    /// `body`: the balanced body's root joint (0: the whole skeleton).
    pub(super) fn new(
        frames: &Frames,
        support: &[Effector],
        margin: f64,
        body: usize,
    ) -> Option<Self> {
        let points = floor_points(frames, support);
        let c = frames.body_center_of_mass(body);
        let c = [c.x, c.z];
        let hull = convex_hull(points);
        let (nearest, margin) = match hull.as_slice() {
            [] => return None,
            [a] => (Nearest::vertex(c, *a), 0.0),
            [a, b] => (Nearest::on_segment(c, *a, *b), 0.0),
            _ => (Nearest::on_polygon(c, &hull), margin),
        };
        Some(Self {
            normal: DVec3::new(nearest.normal[0], 0.0, nearest.normal[1]),
            violation: nearest.signed_distance + margin,
            a: nearest.a,
            b: nearest.b,
            t: nearest.t,
        })
    }

    /// Whether the row constrains the lower levels.
    pub(super) fn active(&self) -> bool {
        self.violation > -BALANCE_BAND
    }
}

/// The boundary feature of a support polygon nearest to a point.
struct Nearest {
    normal: [f64; 2],
    signed_distance: f64,
    a: usize,
    b: usize,
    t: f64,
}

impl Nearest {
    fn vertex(c: [f64; 2], (p, i): FloorPoint) -> Self {
        let d = [c[0] - p[0], c[1] - p[1]];
        let len = d[0].hypot(d[1]);
        let normal = if len < 1e-12 {
            [1.0, 0.0]
        } else {
            [d[0] / len, d[1] / len]
        };
        Self {
            normal,
            signed_distance: len,
            a: i,
            b: i,
            t: 0.0,
        }
    }

    /// Outside distance to the segment `a b`.
    fn on_segment(c: [f64; 2], (a, ia): FloorPoint, (b, ib): FloorPoint) -> Self {
        let e = [b[0] - a[0], b[1] - a[1]];
        let len2 = e[0] * e[0] + e[1] * e[1];
        let t = if len2 > 0.0 {
            (((c[0] - a[0]) * e[0] + (c[1] - a[1]) * e[1]) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let p = [a[0] + t * e[0], a[1] + t * e[1]];
        Self {
            a: ia,
            b: ib,
            t,
            ..Self::vertex(c, (p, ia))
        }
    }

    /// Signed distance to a counter-clockwise convex polygon: outside, the distance to the
    /// nearest edge; inside, minus the distance to the nearest edge's line.
    fn on_polygon(c: [f64; 2], hull: &[FloorPoint]) -> Self {
        let edges = || (0..hull.len()).map(|i| (hull[i], hull[(i + 1) % hull.len()]));
        let outside = edges().any(|((a, _), (b, _))| {
            let e = [b[0] - a[0], b[1] - a[1]];
            e[1] * (c[0] - a[0]) - e[0] * (c[1] - a[1]) > 0.0
        });
        if outside {
            return edges()
                .map(|(a, b)| Self::on_segment(c, a, b))
                .min_by(|x, y| x.signed_distance.total_cmp(&y.signed_distance))
                .unwrap_or_else(|| Self::vertex(c, hull[0]));
        }
        edges()
            .map(|((a, ia), (b, ib))| {
                let e = [b[0] - a[0], b[1] - a[1]];
                let len = e[0].hypot(e[1]);
                let normal = [e[1] / len, -e[0] / len];
                let d = [c[0] - a[0], c[1] - a[1]];
                Self {
                    normal,
                    signed_distance: normal[0] * d[0] + normal[1] * d[1],
                    a: ia,
                    b: ib,
                    t: (d[0] * e[0] + d[1] * e[1]) / (len * len),
                }
            })
            .max_by(|x, y| x.signed_distance.total_cmp(&y.signed_distance))
            .unwrap_or_else(|| Self::vertex(c, hull[0]))
    }
}

/// Convex hull in counter-clockwise order (Andrew's monotone chain), without collinear or
/// repeated points.
pub(super) fn convex_hull(mut points: Vec<FloorPoint>) -> Vec<FloorPoint> {
    points.sort_by(|(a, _), (b, _)| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    points.dedup_by(|(a, _), (b, _)| (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-9);
    if points.len() < 3 {
        return points;
    }
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut hull: Vec<FloorPoint> = Vec::with_capacity(2 * points.len());
    for pass in 0..2 {
        let start = hull.len();
        let mut push = |p: FloorPoint| {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2].0, hull[hull.len() - 1].0, p.0) <= 1e-12
            {
                hull.pop();
            }
            hull.push(p);
        };
        if pass == 0 {
            points.iter().for_each(|&p| push(p));
        } else {
            points.iter().rev().for_each(|&p| push(p));
        }
        hull.pop();
    }
    hull
}
