//! Tasks (the paper's "contraintes"): what the solver is asked to achieve, each with a
//! priority level, a weight and an active flag. This module also computes each task's error
//! and Jacobian rows.

use glam::{DQuat, DVec3};

use crate::{Frames, IkError, Skeleton};

/// A subset of the world axes x, y, z.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Axes {
    mask: u8,
}

impl Axes {
    /// x, y and z.
    pub const XYZ: Axes = Axes { mask: 0b111 };
    /// The horizontal plane of the H-Anim frame (+Y up).
    pub const XZ: Axes = Axes { mask: 0b101 };

    /// From three flags.
    pub fn new(x: bool, y: bool, z: bool) -> Self {
        Self {
            mask: u8::from(x) | (u8::from(y) << 1) | (u8::from(z) << 2),
        }
    }

    /// Parses `"xyz"`, `"xz"`, `"y"`... (each letter at most once, at least one).
    pub fn parse(s: &str) -> Option<Self> {
        let mut mask = 0u8;
        for c in s.chars() {
            let bit = match c {
                'x' | 'X' => 1,
                'y' | 'Y' => 2,
                'z' | 'Z' => 4,
                _ => return None,
            };
            if mask & bit != 0 {
                return None;
            }
            mask |= bit;
        }
        (mask != 0).then_some(Self { mask })
    }

    /// Whether axis `i` (0 = x) is selected.
    pub fn has(self, i: usize) -> bool {
        i < 3 && self.mask & (1 << i) != 0
    }

    /// Number of selected axes.
    pub fn count(self) -> usize {
        self.mask.count_ones() as usize
    }

    /// The letters, e.g. `"xz"`.
    pub fn to_letters(self) -> String {
        ["x", "y", "z"]
            .iter()
            .enumerate()
            .filter(|(i, _)| self.has(*i))
            .map(|(_, s)| *s)
            .collect()
    }
}

/// A point fixed on a body segment: the frame of `joint`, at `point` in that frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Effector {
    /// The joint whose frame carries the point.
    pub joint: usize,
    /// The point in the joint frame (m).
    pub point: DVec3,
}

/// What a task controls.
#[derive(Debug, Clone, PartialEq)]
pub enum TaskKind {
    /// Position of an effector point along the selected world axes.
    Position {
        /// The controlled point.
        effector: Effector,
        /// Which world axes are controlled.
        axes: Axes,
        /// World target (all three components are stored; `axes` selects).
        target: DVec3,
    },
    /// World orientation of a segment (`world_from_joint`), 3 rows.
    Orientation {
        /// The joint.
        joint: usize,
        /// Target `world_from_joint` rotation.
        target: DQuat,
    },
    /// Gaze / direction: the segment axis `axis`, from the point `effector`, aims at `target`.
    /// 2 rows (the components of the unit direction to the target, in the joint frame,
    /// orthogonal to `axis`).
    Gaze {
        /// Eye point on the segment.
        effector: Effector,
        /// Aiming axis in the joint frame (unit).
        axis: DVec3,
        /// World point to look at.
        target: DVec3,
    },
    /// Whole-body centre of mass along the selected world axes (`Axes::XZ`: horizontal).
    CenterOfMass {
        /// Controlled axes.
        axes: Axes,
        /// World target.
        target: DVec3,
    },
    /// Attraction of the chosen DOF toward a reference posture (Jacobian = identity rows).
    PostureAttraction {
        /// Reference value for every DOF of the skeleton.
        reference: Vec<f64>,
        /// The attracted DOF (posture indices).
        dofs: Vec<usize>,
    },
}

/// One task with its priority level (1 = highest), weight inside its level and active flag.
#[derive(Debug, Clone, PartialEq)]
pub struct Task {
    /// What is controlled.
    pub kind: TaskKind,
    /// Priority level; smaller is more important. Levels need not be contiguous.
    pub level: u32,
    /// Weight inside the level (rows are scaled by `sqrt(weight)`); must be >= 0.
    pub weight: f64,
    /// Inactive tasks are ignored.
    pub active: bool,
}

impl Task {
    /// A task at level 1, weight 1, active.
    pub fn new(kind: TaskKind) -> Self {
        Self {
            kind,
            level: 1,
            weight: 1.0,
            active: true,
        }
    }

    /// Position of `point` (joint frame) of `joint`, all three axes.
    pub fn position(joint: usize, point: DVec3, target: DVec3) -> Self {
        Self::new(TaskKind::Position {
            effector: Effector { joint, point },
            axes: Axes::XYZ,
            target,
        })
    }

    /// Orientation of `joint`.
    pub fn orientation(joint: usize, target: DQuat) -> Self {
        Self::new(TaskKind::Orientation { joint, target })
    }

    /// Gaze of `joint` along its local `axis` toward `target`, from the joint centre.
    pub fn gaze(joint: usize, axis: DVec3, target: DVec3) -> Self {
        Self::new(TaskKind::Gaze {
            effector: Effector {
                joint,
                point: DVec3::ZERO,
            },
            axis,
            target,
        })
    }

    /// Centre of mass on `axes`.
    pub fn center_of_mass(axes: Axes, target: DVec3) -> Self {
        Self::new(TaskKind::CenterOfMass { axes, target })
    }

    /// Attraction of `dofs` toward `reference`.
    pub fn posture(reference: Vec<f64>, dofs: Vec<usize>) -> Self {
        Self::new(TaskKind::PostureAttraction { reference, dofs })
    }

    /// Attraction of every rotational DOF of every non-root joint toward the rest posture.
    pub fn rest_posture(skeleton: &Skeleton) -> Self {
        let dofs = (0..skeleton.dof_count())
            .filter(|&d| skeleton.dof_joint(d) != 0 && skeleton.dof_kinds()[d].is_rotation())
            .collect();
        Self::posture(vec![0.0; skeleton.dof_count()], dofs)
    }

    /// Sets the level (builder style).
    pub fn at_level(mut self, level: u32) -> Self {
        self.level = level;
        self
    }

    /// Sets the weight (builder style).
    pub fn with_weight(mut self, weight: f64) -> Self {
        self.weight = weight;
        self
    }

    /// Sets the axes of a position or centre-of-mass task (builder style).
    pub fn with_axes(mut self, new_axes: Axes) -> Self {
        match &mut self.kind {
            TaskKind::Position { axes, .. } | TaskKind::CenterOfMass { axes, .. } => {
                *axes = new_axes
            }
            _ => {}
        }
        self
    }

    /// Sets the active flag (builder style).
    pub fn with_active(mut self, active: bool) -> Self {
        self.active = active;
        self
    }

    /// Number of Jacobian rows.
    pub fn rows(&self) -> usize {
        match &self.kind {
            TaskKind::Position { axes, .. } | TaskKind::CenterOfMass { axes, .. } => axes.count(),
            TaskKind::Orientation { .. } => 3,
            TaskKind::Gaze { .. } => 2,
            TaskKind::PostureAttraction { dofs, .. } => dofs.len(),
        }
    }

    /// Whether the task is the (never "met") posture attraction.
    pub fn is_posture(&self) -> bool {
        matches!(self.kind, TaskKind::PostureAttraction { .. })
    }

    /// Checks the task against a skeleton. `index` is used in the error.
    pub fn validate(&self, skeleton: &Skeleton, index: usize) -> Result<(), IkError> {
        let bad = |reason: String| IkError::BadTask { index, reason };
        let joint_ok = |j: usize| {
            if j < skeleton.joint_count() {
                Ok(())
            } else {
                Err(bad(format!("joint index {j} out of range")))
            }
        };
        let finite = |v: DVec3, what: &str| {
            if v.is_finite() {
                Ok(())
            } else {
                Err(bad(format!("{what} is not finite")))
            }
        };
        if !(self.weight.is_finite() && self.weight >= 0.0) {
            return Err(bad("weight must be finite and >= 0".into()));
        }
        if self.level == 0 {
            return Err(bad("levels start at 1".into()));
        }
        match &self.kind {
            TaskKind::Position {
                effector, target, ..
            } => {
                joint_ok(effector.joint)?;
                finite(effector.point, "point")?;
                finite(*target, "target")?;
            }
            TaskKind::Orientation { joint, target } => {
                joint_ok(*joint)?;
                if !target.is_finite() || target.length() < 1e-9 {
                    return Err(bad("target quaternion must be finite and non-zero".into()));
                }
            }
            TaskKind::Gaze {
                effector,
                axis,
                target,
            } => {
                joint_ok(effector.joint)?;
                finite(effector.point, "point")?;
                finite(*target, "target")?;
                finite(*axis, "axis")?;
                if axis.length() < 1e-9 {
                    return Err(bad("gaze axis has zero length".into()));
                }
            }
            TaskKind::CenterOfMass { target, .. } => {
                finite(*target, "target")?;
                if skeleton.total_mass() <= 0.0 {
                    return Err(bad("centre-of-mass task on a skeleton without mass".into()));
                }
            }
            TaskKind::PostureAttraction { reference, dofs } => {
                if reference.len() != skeleton.dof_count() {
                    return Err(bad(format!(
                        "reference has {} values, the skeleton {} DOF",
                        reference.len(),
                        skeleton.dof_count()
                    )));
                }
                if reference.iter().any(|v| !v.is_finite()) {
                    return Err(bad("reference is not finite".into()));
                }
                if let Some(d) = dofs.iter().find(|&&d| d >= skeleton.dof_count()) {
                    return Err(bad(format!("DOF index {d} out of range")));
                }
            }
        }
        Ok(())
    }

    /// Posture indices of the possibly non-zero Jacobian columns.
    pub fn support(&self, skeleton: &Skeleton) -> Vec<usize> {
        match &self.kind {
            TaskKind::Position { effector, .. } | TaskKind::Gaze { effector, .. } => {
                skeleton.chain_dofs(effector.joint)
            }
            TaskKind::Orientation { joint, .. } => skeleton
                .chain_dofs(*joint)
                .into_iter()
                .filter(|&d| skeleton.dof_kinds()[d].is_rotation())
                .collect(),
            TaskKind::CenterOfMass { .. } => (0..skeleton.dof_count()).collect(),
            TaskKind::PostureAttraction { dofs, .. } => {
                let mut d = dofs.clone();
                d.sort_unstable();
                d.dedup();
                d
            }
        }
    }
}

/// What a task measures, for finite-difference checks: a vector whose derivative is the
/// Jacobian, or (orientation) a rotation whose angular velocity is the Jacobian.
#[derive(Debug, Clone, PartialEq)]
pub enum TaskFeature {
    /// Rows of the Jacobian are the derivatives of these values.
    Vector(Vec<f64>),
    /// Rows of the Jacobian are the world angular velocity of this rotation.
    Rotation(DQuat),
}

/// Step limits applied to a task's desired change.
#[derive(Debug, Clone, Copy)]
pub(crate) struct StepLimits {
    pub linear: f64,
    pub angular: f64,
}

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
struct GazeGeometry {
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
    fn new(frames: &Frames, effector: &Effector, axis: DVec3, target: DVec3) -> Option<Self> {
        let (a, l1, l2) = gaze_basis(axis);
        let v = gaze_local(frames, effector, target);
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
    fn log(&self) -> [f64; 2] {
        let x = self.u * self.angle;
        [self.l1.dot(x), self.l2.dot(x)]
    }

    /// The feature's change for a change `dv` of the (unnormalised) eye-to-target vector.
    fn log_derivative(&self, dv: DVec3) -> [f64; 2] {
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
        let _ = skeleton;
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
            TaskKind::CenterOfMass { axes, .. } => {
                let c = frames.center_of_mass();
                TaskFeature::Vector((0..3).filter(|&i| axes.has(i)).map(|i| c[i]).collect())
            }
            TaskKind::PostureAttraction { dofs, .. } => TaskFeature::Vector(
                dofs.iter()
                    .map(|&d| values.get(d).copied().unwrap_or(0.0))
                    .collect(),
            ),
        }
    }

    /// Error (unclamped residual norm, in metres or radians) of the task at `frames`.
    pub fn residual(&self, skeleton: &Skeleton, frames: &Frames, values: &[f64]) -> f64 {
        let mut err = vec![0.0; self.rows()];
        self.error(skeleton, frames, values, &mut err, None)
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
        let _ = skeleton;
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
            TaskKind::CenterOfMass { axes, target } => {
                let d = *target - frames.center_of_mass();
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
                let Some(g) = GazeGeometry::new(frames, effector, *axis, *target) else {
                    // Target at the eye: any direction is right.
                    err[0] = 0.0;
                    err[1] = 0.0;
                    return 0.0;
                };
                let [x1, x2] = g.log();
                err[0] = -x1;
                err[1] = -x2;
                clamp_vec(err, limits.map(|l| l.angular));
                g.angle
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
            TaskKind::CenterOfMass { axes, .. } => {
                let total = frames.subtree_mass.first().copied().unwrap_or(0.0);
                if total <= 0.0 {
                    return;
                }
                for &d in support {
                    let j = skeleton.dof_joint(d);
                    let axis = frames.dof_axis[d];
                    let v = if kinds[d].is_rotation() {
                        axis.cross(
                            frames.subtree_moment[j]
                                - frames.subtree_mass[j] * frames.joint_position[j],
                        ) / total
                    } else {
                        axis * (frames.subtree_mass[j] / total)
                    };
                    write_axes(jac_t, n, d, v, *axes);
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
            TaskKind::PostureAttraction { dofs, .. } => {
                for (row, &d) in dofs.iter().enumerate() {
                    jac_t[row * n + d] = 1.0;
                }
            }
        }
    }
}

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
