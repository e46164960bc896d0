//! Each task's measured feature, error and Jacobian rows (the solver's linearisation), and
//! the comfort task's gradient step: split from `task.rs`, which defines the tasks.

use glam::{DQuat, DVec3};

use super::balance::{BalanceGeometry, convex_hull, floor_points};
use super::collision::{self, NearList};
use super::gaze::{GazeGeometry, direction_error};
use super::locus::{line_basis, line_offset, plane_active, plane_distance, plane_error};
use super::{
    Axes, BALANCE_BAND, COLLISION_AIM, COLLISION_BAND, COLLISION_LOOKAHEAD, PLANE_BAND, StepLimits,
    Task, TaskFeature, TaskKind,
};
use crate::comfort::ComfortModel;
use crate::{Frames, Skeleton};

/// The velocity of the world point `p` carried by `joint` for a unit velocity of DOF `d`.
fn point_column(skeleton: &Skeleton, frames: &Frames, d: usize, joint: usize, p: DVec3) -> DVec3 {
    let owner = skeleton.dof_joint(d);
    if !skeleton.is_ancestor_or_self(owner, joint) {
        DVec3::ZERO
    } else if skeleton.dof_kinds()[d].is_rotation() {
        frames.dof_axis[d].cross(p - frames.joint_position[owner])
    } else {
        frames.dof_axis[d]
    }
}

/// The velocity of the centre of mass of the body rooted at `root` (of mass `total`) for a
/// unit velocity of DOF `d`.
fn com_column(skeleton: &Skeleton, frames: &Frames, d: usize, root: usize, total: f64) -> DVec3 {
    let j = skeleton.dof_joint(d);
    let axis = frames.dof_axis[d];
    if root != 0 && !skeleton.is_ancestor_or_self(root, j) {
        // A DOF above the body moves it as a whole (one of another body: not at all).
        return point_column(skeleton, frames, d, root, frames.body_center_of_mass(root));
    }
    if skeleton.dof_kinds()[d].is_rotation() {
        axis.cross(frames.subtree_moment[j] - frames.subtree_mass[j] * frames.joint_position[j])
            / total
    } else {
        axis * (frames.subtree_mass[j] / total)
    }
}

/// Shortest rotation vector of `q`.
pub(crate) fn log_rotation(q: DQuat) -> DVec3 {
    let q = if q.w < 0.0 { -q } else { q };
    let v = q.xyz();
    let s = v.length();
    if s < 1e-12 {
        return 2.0 * v;
    }
    let angle = 2.0 * s.atan2(q.w);
    v * (angle / s)
}

impl Task {
    /// The measured feature (see [`TaskFeature`]).
    pub fn feature(&self, skeleton: &Skeleton, frames: &Frames, values: &[f64]) -> TaskFeature {
        match &self.kind {
            TaskKind::Position { effector, axes, .. } => {
                let p = frames.point(effector.joint, effector.point);
                TaskFeature::Vector((0..3).filter(|&i| axes.has(i)).map(|i| p[i]).collect())
            }
            TaskKind::Orientation { joint, .. } => TaskFeature::Rotation(frames.rotation(*joint)),
            TaskKind::Gaze {
                effector,
                axis,
                target,
            } => {
                let x = GazeGeometry::new(frames, effector, *axis, *target)
                    .map_or([0.0, 0.0], |g| g.log());
                TaskFeature::Vector(x.to_vec())
            }
            TaskKind::Direction {
                joint,
                axis,
                target,
            } => {
                let x = GazeGeometry::direction(frames, *joint, *axis, *target)
                    .map_or([0.0, 0.0], |g| g.log());
                TaskFeature::Vector(x.to_vec())
            }
            TaskKind::CenterOfMass { axes, body, .. } => {
                let c = frames.body_center_of_mass(body.unwrap_or(0));
                TaskFeature::Vector((0..3).filter(|&i| axes.has(i)).map(|i| c[i]).collect())
            }
            TaskKind::Meet { a, b, axes } => {
                let d = frames.point(b.joint, b.point) - frames.point(a.joint, a.point);
                TaskFeature::Vector((0..3).filter(|&i| axes.has(i)).map(|i| -d[i]).collect())
            }
            TaskKind::Balance {
                support,
                margin,
                body,
            } => {
                // The signed distance past the shrunk polygon; constant where the row is empty.
                let x = BalanceGeometry::new(frames, support, *margin, body.unwrap_or(0))
                    .filter(BalanceGeometry::active)
                    .map_or(-BALANCE_BAND, |g| g.violation);
                TaskFeature::Vector(vec![x])
            }
            TaskKind::Comfort { model } => {
                TaskFeature::Vector(vec![model.terms(skeleton, frames, values).total])
            }
            TaskKind::PointOnLine {
                effector,
                origin,
                direction,
            } => {
                let p = frames.point(effector.joint, effector.point);
                TaskFeature::Vector(line_offset(p, *origin, *direction).to_vec())
            }
            TaskKind::PointOnPlane {
                effector,
                origin,
                normal,
                above,
            } => {
                // The signed distance; constant where an inequality's row is empty.
                let s = plane_distance(
                    frames.point(effector.joint, effector.point),
                    *origin,
                    *normal,
                );
                TaskFeature::Vector(vec![if plane_active(s, *above) {
                    s
                } else {
                    PLANE_BAND
                }])
            }
            TaskKind::Collision(c) => {
                // The distances of the rows held; constant where a row is empty.
                let found = c.constraints(frames);
                TaskFeature::Vector(
                    (0..c.rows())
                        .map(|i| {
                            found
                                .get(i)
                                .map_or(c.margin() + COLLISION_BAND, |f| f.distance)
                        })
                        .collect(),
                )
            }
            TaskKind::PostureAttraction { dofs, .. } => TaskFeature::Vector(
                dofs.iter()
                    .map(|&d| values.get(d).copied().unwrap_or(0.0))
                    .collect(),
            ),
        }
    }

    /// Error (unclamped residual norm, in metres or radians; a comfort task's cost) of the
    /// task at `frames`.
    pub fn residual(&self, skeleton: &Skeleton, frames: &Frames, values: &[f64]) -> f64 {
        self.residual_with(skeleton, frames, values, &mut Vec::new())
    }

    /// [`Task::residual`] with a scratch buffer for the error rows. A comfort task weighs its
    /// cost alone: its gradient is only needed to step.
    pub(crate) fn residual_with(
        &self,
        skeleton: &Skeleton,
        frames: &Frames,
        values: &[f64],
        scratch: &mut Vec<f64>,
    ) -> f64 {
        if let Some(cost) = self.comfort_cost(skeleton, frames, values) {
            return cost;
        }
        scratch.resize(self.rows(), 0.0);
        self.error(skeleton, frames, values, scratch, None)
    }

    /// The support polygon of a balance task at `frames`, as the solver sees it: the corners
    /// of the convex hull of the support points, counter-clockwise seen from below (x, z), on
    /// the floor plane y = 0. Empty for other kinds.
    pub fn support_polygon(&self, frames: &Frames) -> Vec<DVec3> {
        let TaskKind::Balance { support, .. } = &self.kind else {
            return Vec::new();
        };
        convex_hull(floor_points(frames, support))
            .into_iter()
            .map(|([x, z], _)| DVec3::new(x, 0.0, z))
            .collect()
    }

    /// The desired change of the task's feature (unclamped, one value per row): the error
    /// the solver drives to zero, whose derivative is minus the Jacobian.
    pub fn error_vector(&self, skeleton: &Skeleton, frames: &Frames, values: &[f64]) -> Vec<f64> {
        let mut err = vec![0.0; self.rows()];
        self.error(skeleton, frames, values, &mut err, None);
        err
    }

    /// Writes the desired change (clamped by `limits` when given) into `err` and returns the
    /// unclamped residual norm.
    pub(crate) fn error(
        &self,
        skeleton: &Skeleton,
        frames: &Frames,
        values: &[f64],
        err: &mut [f64],
        limits: Option<StepLimits>,
    ) -> f64 {
        let clamp_vec = |e: &mut [f64], max: Option<f64>| {
            let norm = e.iter().map(|v| v * v).sum::<f64>().sqrt();
            if let Some(max) = max
                && norm > max
            {
                let s = max / norm;
                e.iter_mut().for_each(|v| *v *= s);
            }
            norm
        };
        match &self.kind {
            TaskKind::Position {
                effector,
                axes,
                target,
            } => {
                let d = *target - frames.point(effector.joint, effector.point);
                fill_axes(err, d, *axes);
                clamp_vec(err, limits.map(|l| l.linear))
            }
            TaskKind::CenterOfMass { axes, target, body } => {
                let d = *target - frames.body_center_of_mass(body.unwrap_or(0));
                fill_axes(err, d, *axes);
                clamp_vec(err, limits.map(|l| l.linear))
            }
            TaskKind::Meet { a, b, axes } => {
                let d = frames.point(b.joint, b.point) - frames.point(a.joint, a.point);
                fill_axes(err, d, *axes);
                clamp_vec(err, limits.map(|l| l.linear))
            }
            TaskKind::Orientation { joint, target } => {
                let e = log_rotation(target.normalize() * frames.rotation(*joint).inverse());
                err[..3].copy_from_slice(&e.to_array());
                clamp_vec(err, limits.map(|l| l.angular))
            }
            TaskKind::Gaze {
                effector,
                axis,
                target,
            } => {
                let geometry = GazeGeometry::new(frames, effector, *axis, *target);
                direction_error(geometry, err, limits)
            }
            TaskKind::Direction {
                joint,
                axis,
                target,
            } => {
                let geometry = GazeGeometry::direction(frames, *joint, *axis, *target);
                direction_error(geometry, err, limits)
            }
            TaskKind::Balance {
                support,
                margin,
                body,
            } => {
                let violation = BalanceGeometry::new(frames, support, *margin, body.unwrap_or(0))
                    .map_or(0.0, |g| g.violation.max(0.0));
                err[0] = -violation;
                clamp_vec(err, limits.map(|l| l.linear))
            }
            TaskKind::Comfort { model } => {
                let (cost, gradient) = comfort_gradient(model, skeleton, frames, values);
                err[0] = comfort_step(&gradient, limits);
                cost
            }
            TaskKind::Collision(c) => {
                let found = c.constraints(frames);
                collision::errors(&found, c.margin(), err);
                clamp_vec(err, limits.map(|l| l.linear))
            }
            TaskKind::PointOnLine {
                effector,
                origin,
                direction,
            } => {
                let p = frames.point(effector.joint, effector.point);
                let [a, b] = line_offset(p, *origin, *direction);
                err[0] = -a;
                err[1] = -b;
                clamp_vec(err, limits.map(|l| l.linear))
            }
            TaskKind::PointOnPlane {
                effector,
                origin,
                normal,
                above,
            } => {
                let s = plane_distance(
                    frames.point(effector.joint, effector.point),
                    *origin,
                    *normal,
                );
                err[0] = plane_error(s, *above);
                clamp_vec(err, limits.map(|l| l.linear))
            }
            TaskKind::PostureAttraction { reference, dofs } => {
                for (e, &d) in err.iter_mut().zip(dofs) {
                    let v = values.get(d).copied().unwrap_or(0.0);
                    *e = reference.get(d).copied().unwrap_or(0.0) - v;
                }
                let norm = err.iter().map(|v| v * v).sum::<f64>().sqrt();
                if let Some(l) = limits {
                    err.iter_mut()
                        .for_each(|v| *v = v.clamp(-l.angular, l.angular));
                }
                norm
            }
        }
    }

    /// Writes the Jacobian rows: `jac_t` is column-major `N x rows` (one column per row of
    /// J, i.e. J transposed), already zero outside this task's support.
    pub(crate) fn jacobian_t(
        &self,
        skeleton: &Skeleton,
        frames: &Frames,
        values: &[f64],
        support: &[usize],
        jac_t: &mut [f64],
        n: usize,
    ) {
        let kinds = skeleton.dof_kinds();
        match &self.kind {
            TaskKind::Position { effector, axes, .. } => {
                let p = frames.point(effector.joint, effector.point);
                for &d in support {
                    let axis = frames.dof_axis[d];
                    let v = if kinds[d].is_rotation() {
                        axis.cross(p - frames.joint_position[skeleton.dof_joint(d)])
                    } else {
                        axis
                    };
                    write_axes(jac_t, n, d, v, *axes);
                }
            }
            TaskKind::CenterOfMass { axes, body, .. } => {
                let root = body.unwrap_or(0);
                let total = frames.subtree_mass.get(root).copied().unwrap_or(0.0);
                if total <= 0.0 {
                    return;
                }
                for &d in support {
                    let column = com_column(skeleton, frames, d, root, total);
                    write_axes(jac_t, n, d, column, *axes);
                }
            }
            TaskKind::Meet { a, b, axes } => {
                let (pa, pb) = (
                    frames.point(a.joint, a.point),
                    frames.point(b.joint, b.point),
                );
                for &d in support {
                    let v = point_column(skeleton, frames, d, a.joint, pa)
                        - point_column(skeleton, frames, d, b.joint, pb);
                    write_axes(jac_t, n, d, v, *axes);
                }
            }
            TaskKind::Balance {
                support: contacts,
                margin,
                body,
            } => {
                let root = body.unwrap_or(0);
                let total = frames.subtree_mass.get(root).copied().unwrap_or(0.0);
                let Some(g) = BalanceGeometry::new(frames, contacts, *margin, root) else {
                    return;
                };
                if total <= 0.0 || !g.active() {
                    return;
                }
                let (a, b) = (&contacts[g.a], &contacts[g.b]);
                let (pa, pb) = (
                    frames.point(a.joint, a.point),
                    frames.point(b.joint, b.point),
                );
                for &d in support {
                    let moved = point_column(skeleton, frames, d, a.joint, pa) * (1.0 - g.t)
                        + point_column(skeleton, frames, d, b.joint, pb) * g.t;
                    jac_t[d] = g
                        .normal
                        .dot(com_column(skeleton, frames, d, root, total) - moved);
                }
            }
            TaskKind::Collision(c) => {
                let found = c.constraints(frames);
                collision::write_rows(skeleton, frames, &found, jac_t, n);
            }
            TaskKind::PointOnLine {
                effector,
                direction,
                ..
            } => {
                let p = frames.point(effector.joint, effector.point);
                let [e1, e2] = line_basis(*direction);
                for &d in support {
                    let v = point_column(skeleton, frames, d, effector.joint, p);
                    jac_t[d] = e1.dot(v);
                    jac_t[n + d] = e2.dot(v);
                }
            }
            TaskKind::PointOnPlane {
                effector,
                origin,
                normal,
                above,
            } => {
                let p = frames.point(effector.joint, effector.point);
                if !plane_active(plane_distance(p, *origin, *normal), *above) {
                    return;
                }
                let unit = normal.normalize_or(DVec3::Y);
                for &d in support {
                    jac_t[d] = unit.dot(point_column(skeleton, frames, d, effector.joint, p));
                }
            }
            TaskKind::Orientation { .. } => {
                for &d in support {
                    if kinds[d].is_rotation() {
                        write_axes(jac_t, n, d, frames.dof_axis[d], Axes::XYZ);
                    }
                }
            }
            TaskKind::Gaze {
                effector,
                axis,
                target,
            } => {
                let Some(g) = GazeGeometry::new(frames, effector, *axis, *target) else {
                    return;
                };
                let rot_t = frames.world_from_joint_rotation[effector.joint].transpose();
                for &d in support {
                    let axis_w = frames.dof_axis[d];
                    let dq = if kinds[d].is_rotation() {
                        -(rot_t
                            * axis_w.cross(*target - frames.joint_position[skeleton.dof_joint(d)]))
                    } else {
                        -(rot_t * axis_w)
                    };
                    let [r1, r2] = g.log_derivative(dq);
                    jac_t[d] = r1;
                    jac_t[n + d] = r2;
                }
            }
            TaskKind::Direction {
                joint,
                axis,
                target,
            } => {
                let Some(g) = GazeGeometry::direction(frames, *joint, *axis, *target) else {
                    return;
                };
                let rot_t = frames.world_from_joint_rotation[*joint].transpose();
                let world = target.normalize_or_zero();
                for &d in support {
                    if kinds[d].is_rotation() {
                        let dq = -(rot_t * frames.dof_axis[d].cross(world));
                        let [r1, r2] = g.log_derivative(dq);
                        jac_t[d] = r1;
                        jac_t[n + d] = r2;
                    }
                }
            }
            TaskKind::PostureAttraction { dofs, .. } => {
                for (row, &d) in dofs.iter().enumerate() {
                    jac_t[row * n + d] = 1.0;
                }
            }
            TaskKind::Comfort { model } => {
                let (_, gradient) = comfort_gradient(model, skeleton, frames, values);
                unit_gradient_row(&gradient, support, jac_t);
            }
        }
    }

    /// A comfort task's cost alone (no gradient: a level waiting for the levels above it, or
    /// a candidate posture weighed); `None` for other kinds.
    pub(crate) fn comfort_cost(
        &self,
        skeleton: &Skeleton,
        frames: &Frames,
        values: &[f64],
    ) -> Option<f64> {
        let TaskKind::Comfort { model } = &self.kind else {
            return None;
        };
        Some(model.terms(skeleton, frames, values).total)
    }

    /// The rows and errors at once for the kinds that find both together (`jac_t` zero on
    /// entry, `n` DOF), how many rows are written and how many of them are held: comfort (one
    /// gradient, as [`Task::error`] and [`Task::jacobian_t`] write it; returns the cost, one
    /// row, held) and collision (one search for its constraints within
    /// [`COLLISION_LOOKAHEAD`] of the margin, nearest first; returns the error's norm, one row
    /// per constraint found and how many of them are under the margin: those rows hold their
    /// error, the margin less the distance; the others, the candidates of the solver's active
    /// set, hold the margin less the distance, negative: the change that brings them to the
    /// margin; the rows past those found stay empty and the solver leaves them out of the
    /// level; the search goes by `near`, which the caller keeps from one linearisation to the
    /// next, see [`NearList`]). `None` for other kinds.
    pub(crate) fn system_at_once(
        &self,
        skeleton: &Skeleton,
        frames: &Frames,
        values: &[f64],
        support: &[usize],
        (err, jac_t, n): (&mut [f64], &mut [f64], usize),
        limits: Option<StepLimits>,
        near: &mut NearList,
    ) -> Option<(f64, usize, usize)> {
        match &self.kind {
            TaskKind::Comfort { model } => {
                let (cost, gradient) = comfort_gradient(model, skeleton, frames, values);
                err[0] = comfort_step(&gradient, limits);
                unit_gradient_row(&gradient, support, jac_t);
                Some((cost, 1, 1))
            }
            TaskKind::Collision(c) => {
                let found = c.constraints_listed(frames, c.margin() + COLLISION_LOOKAHEAD, near);
                let held = found.partition_point(|f| f.distance < c.margin());
                let norm = collision::errors(&found[..held], c.margin(), err);
                // Each row aims a little past the margin (the steps' second-order motion).
                let aim = c.margin() + COLLISION_AIM;
                for (e, f) in err.iter_mut().zip(&found) {
                    *e = aim - f.distance;
                }
                let aimed = err[..held].iter().map(|e| e * e).sum::<f64>().sqrt();
                if let Some(l) = limits
                    && aimed > l.linear
                {
                    let s = l.linear / aimed;
                    err[..held].iter_mut().for_each(|v| *v *= s);
                }
                collision::write_rows(skeleton, frames, &found, jac_t, n);
                Some((norm, found.len(), held))
            }
            _ => None,
        }
    }
}

/// The comfort cost and its gradient, projected onto the joint ranges: a DOF on a limit that
/// the descent would push further out stays out of the row (else every step would clamp it
/// again, a whole prioritized step per clamping pass).
fn comfort_gradient(
    model: &ComfortModel,
    skeleton: &Skeleton,
    frames: &Frames,
    values: &[f64],
) -> (f64, Vec<f64>) {
    let mut gradient = vec![0.0; skeleton.dof_count()];
    let terms = model.gradient(skeleton, frames, values, &mut gradient);
    let (lo, hi) = (skeleton.lower_limits(), skeleton.upper_limits());
    for (d, g) in gradient.iter_mut().enumerate() {
        let q = values.get(d).copied().unwrap_or(0.0);
        if (q >= hi[d] && *g < 0.0) || (q <= lo[d] && *g > 0.0) {
            *g = 0.0;
        }
    }
    (terms.total, gradient)
}

/// The comfort row's error: a gradient step of `gain * |grad|` radians, at most
/// [`COMFORT_MAX_STEP`] (and the angular step limit).
fn comfort_step(gradient: &[f64], limits: Option<StepLimits>) -> f64 {
    let slope = gradient.iter().map(|g| g * g).sum::<f64>().sqrt();
    let most = limits.map_or(COMFORT_MAX_STEP, |l| l.angular.min(COMFORT_MAX_STEP));
    -(COMFORT_STEP_GAIN * slope).min(most)
}

/// The comfort row: the unit gradient (the step is the projected gradient times the error).
fn unit_gradient_row(gradient: &[f64], support: &[usize], jac_t: &mut [f64]) {
    let slope = gradient.iter().map(|g| g * g).sum::<f64>().sqrt();
    if slope > 0.0 && slope.is_finite() {
        for &d in support {
            jac_t[d] = gradient[d] / slope;
        }
    }
}

/// The comfort task's gradient step: `gain * |grad|` radians (a plain gradient descent with
/// this rate where the levels above leave the gradient free) ...
const COMFORT_STEP_GAIN: f64 = 0.05;
/// ... as far as this (rad) per iteration.
const COMFORT_MAX_STEP: f64 = 0.1;

fn fill_axes(err: &mut [f64], d: DVec3, axes: Axes) {
    let mut k = 0;
    for i in 0..3 {
        if axes.has(i) {
            err[k] = d[i];
            k += 1;
        }
    }
}

fn write_axes(jac_t: &mut [f64], n: usize, dof: usize, v: DVec3, axes: Axes) {
    let mut k = 0;
    for i in 0..3 {
        if axes.has(i) {
            jac_t[k * n + dof] = v[i];
            k += 1;
        }
    }
}
