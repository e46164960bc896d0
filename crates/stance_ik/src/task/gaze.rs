//! Gaze and direction geometry: the log map of the target direction on the sphere around a
//! joint's axis, its derivative, and the desired change of gaze and direction tasks.

use glam::DVec3;

use super::{Effector, StepLimits};
use crate::Frames;

/// Local orthonormal pair orthogonal to a gaze axis (fixed in the joint frame).
fn gaze_basis(axis: DVec3) -> (DVec3, DVec3, DVec3) {
    let a = axis.normalize_or(DVec3::Z);
    let (l1, l2) = a.any_orthonormal_pair();
    (a, l1, l2)
}

/// A gaze task's geometry in the joint frame: the axis `a`, the pair `l1`, `l2` orthogonal
/// to it, and the unit direction `q` from the eye to the target at angle `angle` from `a`.
///
/// The task's feature is the logarithm of `q` on the sphere around `a`, written in
/// (`l1`, `l2`): `angle * u` with `u` the unit direction of `q`'s part orthogonal to `a`
/// (the azimuthal equidistant map). Driving it to zero turns `a` along the great circle
/// toward the target from any side: from behind, the error still points toward the target,
/// never toward its antipode, and the map's only singular point is the exact antipode,
/// where any perpendicular is as good as another (`l1` is taken).
pub(super) struct GazeGeometry {
    a: DVec3,
    l1: DVec3,
    l2: DVec3,
    /// Unit direction to the target, joint frame.
    q: DVec3,
    /// Distance from the eye to the target.
    len: f64,
    /// Unit direction of `q`'s part orthogonal to `a` (`l1` at the poles).
    u: DVec3,
    /// `sin(angle)`, `cos(angle)`.
    sin: f64,
    cos: f64,
    angle: f64,
}

/// Below this `sin(angle)` the gaze geometry uses its pole limits.
const GAZE_POLE: f64 = 1e-9;
/// Largest gain of the azimuthal row near the antipode (`angle / sin(angle)`).
const GAZE_MAX_GAIN: f64 = 1e3;

impl GazeGeometry {
    pub(super) fn new(
        frames: &Frames,
        effector: &Effector,
        axis: DVec3,
        target: DVec3,
    ) -> Option<Self> {
        Self::from_local(axis, gaze_local(frames, effector, target))
    }

    /// A direction task's geometry: the world direction `target` seen from the joint frame
    /// (a gaze at a point infinitely far along `target`).
    pub(super) fn direction(
        frames: &Frames,
        joint: usize,
        axis: DVec3,
        target: DVec3,
    ) -> Option<Self> {
        let rot = frames.world_from_joint_rotation[joint];
        Self::from_local(axis, rot.transpose() * target.normalize_or_zero())
    }

    /// From the vector `v` toward the target in the joint frame.
    fn from_local(axis: DVec3, v: DVec3) -> Option<Self> {
        let (a, l1, l2) = gaze_basis(axis);
        let len = v.length();
        if len < 1e-12 {
            return None;
        }
        let q = v / len;
        let (x1, x2) = (l1.dot(q), l2.dot(q));
        let sin = (x1 * x1 + x2 * x2).sqrt();
        let cos = a.dot(q);
        let u = if sin > GAZE_POLE {
            (l1 * x1 + l2 * x2) / sin
        } else {
            l1
        };
        Some(Self {
            a,
            l1,
            l2,
            q,
            len,
            u,
            sin,
            cos,
            angle: sin.atan2(cos),
        })
    }

    /// The feature: `angle * u` in (`l1`, `l2`).
    pub(super) fn log(&self) -> [f64; 2] {
        let x = self.u * self.angle;
        [self.l1.dot(x), self.l2.dot(x)]
    }

    /// The feature's change for a change `dv` of the (unnormalised) eye-to-target vector.
    pub(super) fn log_derivative(&self, dv: DVec3) -> [f64; 2] {
        let dq = (dv - self.q * self.q.dot(dv)) / self.len;
        let d = if self.sin <= GAZE_POLE && self.cos > 0.0 {
            // At the axis the map is the identity on the tangent plane.
            dq
        } else {
            // Meridian (toward larger angles) and azimuth directions at q.
            let m = self.u * self.cos - self.a * self.sin;
            let w = self.a.cross(self.u);
            let gain = if self.sin > GAZE_POLE {
                (self.angle / self.sin).min(GAZE_MAX_GAIN)
            } else {
                GAZE_MAX_GAIN
            };
            self.u * m.dot(dq) + w * (gain * w.dot(dq))
        };
        [self.l1.dot(d), self.l2.dot(d)]
    }
}

/// Vector from the eye to the target in the joint frame.
fn gaze_local(frames: &Frames, effector: &Effector, target: DVec3) -> DVec3 {
    let rot = frames.world_from_joint_rotation[effector.joint];
    rot.transpose() * (target - frames.point(effector.joint, effector.point))
}

/// A gaze or direction task's desired change (minus the log map, clamped to the angular
/// step limit) and its unclamped error (the angle to the target direction).
pub(super) fn direction_error(
    geometry: Option<GazeGeometry>,
    err: &mut [f64],
    limits: Option<StepLimits>,
) -> f64 {
    let Some(g) = geometry else {
        // Target at the eye (or a zero direction): any direction is right.
        err[0] = 0.0;
        err[1] = 0.0;
        return 0.0;
    };
    let [x1, x2] = g.log();
    err[0] = -x1;
    err[1] = -x2;
    if let Some(l) = limits {
        let norm = x1.hypot(x2);
        if norm > l.angular {
            let s = l.angular / norm;
            err[0] *= s;
            err[1] *= s;
        }
    }
    g.angle
}
