//! Obstacles of a collision task: fixed convex solids (a box, a ball, a capped cylinder) that
//! the body's capsules keep a margin from. A box of no height is a flat rectangle, but an axis
//! through it measures 0 however deep it goes: give a surface stood on some depth (a scene's
//! plane prop is a slab under its surface). The
//! distance from a capsule is found exactly: the solid's signed distance is convex, so along
//! the capsule's axis it has one minimum, found by a golden-section search to the last bits
//! of a double; its change with the posture is the solid's unit normal at the nearest point
//! of the axis dotted with that point's velocity (the point's place along the axis does not
//! change it to first order, since it minimises the distance there).

use glam::{DMat3, DVec3};

/// A solid's shape, in its own frame (centred on its origin).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ObstacleShape {
    /// A box of these half extents along X, Y and Z (m; a zero one makes a flat rectangle).
    Box {
        /// Half extents (m), each >= 0.
        half: DVec3,
    },
    /// A ball.
    Sphere {
        /// Radius (m), > 0.
        radius: f64,
    },
    /// A cylinder along Y with flat caps.
    Cylinder {
        /// Radius (m), > 0.
        radius: f64,
        /// Half its length along Y (m), > 0.
        half_height: f64,
    },
}

/// A fixed solid in the world the body's capsules keep the collision task's margin from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Obstacle {
    /// Its shape in its own frame.
    pub shape: ObstacleShape,
    /// The rotation from its frame to the world (orthonormal).
    pub world_from_obstacle_rotation: DMat3,
    /// Its centre in the world (m).
    pub position: DVec3,
}

impl Obstacle {
    /// Checks its numbers; the reason names what is wrong.
    pub fn validate(&self) -> Result<(), String> {
        let fine = match self.shape {
            ObstacleShape::Box { half } => half.is_finite() && half.min_element() >= 0.0,
            ObstacleShape::Sphere { radius } => radius.is_finite() && radius > 0.0,
            ObstacleShape::Cylinder {
                radius,
                half_height,
            } => radius.is_finite() && radius > 0.0 && half_height.is_finite() && half_height > 0.0,
        };
        if !fine {
            return Err("its size must be finite and above 0".into());
        }
        if !(self.position.is_finite() && self.world_from_obstacle_rotation.is_finite()) {
            return Err("its place is not finite".into());
        }
        Ok(())
    }

    /// The radius of a ball around its centre that holds it (m).
    pub fn bounding_radius(&self) -> f64 {
        match self.shape {
            ObstacleShape::Box { half } => half.length(),
            ObstacleShape::Sphere { radius } => radius,
            ObstacleShape::Cylinder {
                radius,
                half_height,
            } => (radius * radius + half_height * half_height).sqrt(),
        }
    }

    /// The signed distance of the world point `p` from the solid's surface (negative inside)
    /// and its gradient, the outward unit normal (world).
    pub fn signed_distance(&self, p: DVec3) -> (f64, DVec3) {
        let rotation = self.world_from_obstacle_rotation;
        let local = rotation.transpose() * (p - self.position);
        let (distance, normal) = local_signed_distance(self.shape, local);
        (distance, rotation * normal)
    }

    /// The point of the segment `a b` nearest the solid (by signed distance), its signed
    /// distance and how that distance changes as the point moves: the outward unit normal
    /// there, or at a kink inside the solid the mix of the normals either side (see
    /// [`Obstacle::gradient_at`]).
    pub fn nearest_on_segment(&self, a: DVec3, b: DVec3) -> (DVec3, f64, DVec3) {
        let at = |t: f64| a.lerp(b, t);
        let f = |t: f64| self.signed_distance(at(t)).0;
        let inside = if (b - a).length_squared() > 0.0 {
            crate::joint_rotation::golden(&f, 0.0, 1.0).0
        } else {
            0.5
        };
        // The ends too: the minimum of a convex function on [0, 1] may sit on one.
        let best = [0.0, inside, 1.0]
            .into_iter()
            .min_by(|x, y| f(*x).total_cmp(&f(*y)))
            .unwrap_or(0.0);
        let p = at(best);
        let (distance, normal) = self.signed_distance(p);
        // Outside, the distance is smooth: its normal is its gradient.
        let gradient = if distance < 0.0 {
            self.gradient_at(a, b, best, normal)
        } else {
            normal
        };
        (p, distance, gradient)
    }

    /// How the least signed distance along the segment `a b` (reached at `t`, where the
    /// normal is `normal`) changes as the point at `t` moves: the normal, except where the
    /// minimum sits on a kink of the distance along the segment (inside a box, between two
    /// faces; inside a cylinder, between its side and a cap): there the mix of the normals on
    /// either side whose change along the segment is zero (the minimum of the larger of two
    /// planes' distances moves as that mix says).
    fn gradient_at(&self, a: DVec3, b: DVec3, t: f64, normal: DVec3) -> DVec3 {
        const SIDE: f64 = 1e-7;
        let along = b - a;
        if t <= SIDE || t >= 1.0 - SIDE || along.length_squared() == 0.0 {
            return normal;
        }
        let (_, before) = self.signed_distance(a.lerp(b, t - SIDE));
        let (_, after) = self.signed_distance(a.lerp(b, t + SIDE));
        let (down, up) = (before.dot(along), after.dot(along));
        if (before - after).length() < 1e-9 || down >= 0.0 || up <= 0.0 {
            return normal;
        }
        let share = up / (up - down);
        before * share + after * (1.0 - share)
    }
}

/// The signed distance and outward unit normal of `p` in the solid's own frame.
fn local_signed_distance(shape: ObstacleShape, p: DVec3) -> (f64, DVec3) {
    match shape {
        ObstacleShape::Sphere { radius } => {
            let length = p.length();
            let normal = if length > 0.0 { p / length } else { DVec3::Y };
            (length - radius, normal)
        }
        ObstacleShape::Box { half } => {
            let q = p.abs() - half;
            let sign = DVec3::new(sign(p.x), sign(p.y), sign(p.z));
            let outside = q.max(DVec3::ZERO);
            let out_length = outside.length();
            if out_length > 0.0 {
                (out_length, (outside * sign) / out_length)
            } else {
                // Inside (or on the surface): the nearest face, along its axis.
                let axis = if q.x >= q.y && q.x >= q.z {
                    DVec3::X
                } else if q.y >= q.z {
                    DVec3::Y
                } else {
                    DVec3::Z
                };
                (q.max_element(), axis * sign)
            }
        }
        ObstacleShape::Cylinder {
            radius,
            half_height,
        } => {
            let radial = DVec3::new(p.x, 0.0, p.z);
            let r = radial.length();
            let out = if r > 0.0 { radial / r } else { DVec3::X };
            let up = DVec3::Y * sign(p.y);
            let (dr, dy) = (r - radius, p.y.abs() - half_height);
            if dr > 0.0 && dy > 0.0 {
                let length = (dr * dr + dy * dy).sqrt();
                (length, (out * dr + up * dy) / length)
            } else if dr > 0.0 || dy > 0.0 {
                if dr > dy { (dr, out) } else { (dy, up) }
            } else if dr >= dy {
                (dr, out)
            } else {
                (dy, up)
            }
        }
    }
}

/// The sign of `x`, +1 at 0.
fn sign(x: f64) -> f64 {
    if x < 0.0 { -1.0 } else { 1.0 }
}
