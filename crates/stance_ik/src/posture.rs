//! Postures: the DOF values of a skeleton, and forward kinematics.
//!
//! # Parameterisation (no Euler singularities inside the joint ranges)
//!
//! The rotational DOF `rx, ry, rz` of a joint are the components of a **rotation vector**
//! (exponential map) expressed in the joint's rest frame: the joint's local rotation is
//! `exp(rx*X + ry*Y + rz*Z)`, missing DOF being 0. A 1-DOF joint is therefore a plain hinge,
//! a 2-DOF joint a swing in the plane of its two axes, a 3-DOF joint a free rotation. The
//! exponential map has no singularity for rotation angles below 2*pi; the solver keeps free
//! joints below pi by re-wrapping (`r <- r * (1 - 2*pi/|r|)` gives the same rotation), so no
//! gimbal lock can appear. The order of the DOF in a joint does not matter. Limits are checked
//! per DOF on these components. Translational DOF (`tx, ty, tz`, used by the root) move the
//! joint along its parent's axes.
//!
//! Each joint frame is `world_from_joint = world_from_parent * T(offset + t) * R(exp(r))`.

use glam::{DMat3, DQuat, DVec3};

use crate::{IkError, Skeleton};

/// Values of all DOF of a skeleton (root translation and rotation, joint rotations).
#[derive(Debug, Clone, PartialEq)]
pub struct Posture {
    values: Vec<f64>,
}

impl Posture {
    /// The rest posture: all DOF zero.
    pub fn rest(skeleton: &Skeleton) -> Self {
        Self {
            values: vec![0.0; skeleton.dof_count()],
        }
    }

    /// `posture` of the skeleton `source` carried onto `target` by name: each DOF of `target`
    /// takes the value of the same DOF of the joint of the same name in `source`; joints and
    /// DOF that `source` lacks stay at rest (e.g. a mannequin's posture on an avatar's
    /// skeleton of the same standard, which may have fewer joints).
    pub fn carried_over(target: &Skeleton, source: &Skeleton, posture: &Posture) -> Self {
        let mut carried = Self::rest(target);
        for joint in target.joints() {
            let Some(there) = source.joint_index(&joint.name) else {
                continue;
            };
            let Some(other) = source.joints().get(there) else {
                continue;
            };
            for (k, dof) in joint.dofs.iter().enumerate() {
                if let Some(m) = other.dofs.iter().position(|d| d == dof)
                    && let Some(&v) = posture.values().get(other.dof_start + m)
                    && let Some(slot) = carried.values.get_mut(joint.dof_start + k)
                {
                    *slot = v;
                }
            }
        }
        carried
    }

    /// A posture from raw DOF values (checked against the skeleton; must be finite).
    pub fn from_values(skeleton: &Skeleton, values: Vec<f64>) -> Result<Self, IkError> {
        if values.len() != skeleton.dof_count() {
            return Err(IkError::PostureSize {
                expected: skeleton.dof_count(),
                got: values.len(),
            });
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(IkError::NotFinite {
                what: format!("posture value {i}"),
            });
        }
        Ok(Self { values })
    }

    /// A posture from raw DOF values checked only to be finite, for a skeleton not at hand
    /// (a posture handed over from another thread): whoever uses it checks its length
    /// against the skeleton first.
    pub fn from_finite_values(values: Vec<f64>) -> Result<Self, IkError> {
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(IkError::NotFinite {
                what: format!("posture value {i}"),
            });
        }
        Ok(Self { values })
    }

    /// A posture from a root translation and one local rotation per joint (the logarithm of
    /// each rotation is projected onto the joint's rotational DOF; DOF it lacks are dropped).
    pub fn from_rotations(
        skeleton: &Skeleton,
        root_translation: DVec3,
        local_rotations: &[DQuat],
    ) -> Result<Self, IkError> {
        if local_rotations.len() != skeleton.joint_count() {
            return Err(IkError::PostureSize {
                expected: skeleton.joint_count(),
                got: local_rotations.len(),
            });
        }
        let mut p = Self::rest(skeleton);
        for (j, (joint, q)) in skeleton.joints().iter().zip(local_rotations).enumerate() {
            let q = if q.w < 0.0 { -*q } else { *q };
            let r = q.normalize().to_scaled_axis();
            if !r.is_finite() {
                return Err(IkError::NotFinite {
                    what: format!("rotation of joint {j}"),
                });
            }
            for axis in 0..3 {
                if let Some(d) = joint.rotation_dof[axis] {
                    p.values[d] = r[axis];
                }
            }
            if joint.parent.is_none() {
                for axis in 0..3 {
                    if let Some(d) = joint.translation_dof[axis] {
                        p.values[d] = root_translation[axis];
                    }
                }
            }
        }
        Ok(p)
    }

    /// The DOF values, in skeleton order.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Mutable DOF values.
    pub fn values_mut(&mut self) -> &mut [f64] {
        &mut self.values
    }

    /// The rotation vector of a joint (zeros for missing DOF), radians.
    pub fn rotation_vector(&self, skeleton: &Skeleton, joint: usize) -> DVec3 {
        let j = &skeleton.joints()[joint];
        let mut r = DVec3::ZERO;
        for axis in 0..3 {
            if let Some(d) = j.rotation_dof[axis] {
                r[axis] = self.values[d];
            }
        }
        r
    }

    /// The joint's translation DOF (zeros for missing DOF), metres, parent frame.
    pub fn translation(&self, skeleton: &Skeleton, joint: usize) -> DVec3 {
        let j = &skeleton.joints()[joint];
        let mut t = DVec3::ZERO;
        for axis in 0..3 {
            if let Some(d) = j.translation_dof[axis] {
                t[axis] = self.values[d];
            }
        }
        t
    }

    /// `parent_from_joint` rotation of a joint.
    pub fn local_rotation(&self, skeleton: &Skeleton, joint: usize) -> DQuat {
        DQuat::from_scaled_axis(self.rotation_vector(skeleton, joint))
    }

    /// The root's world translation and rotation (`world_from_root`).
    pub fn root_transform(&self, skeleton: &Skeleton) -> (DVec3, DQuat) {
        match skeleton.joints().first() {
            Some(root) => (
                root.offset + self.translation(skeleton, 0),
                self.local_rotation(skeleton, 0),
            ),
            None => (DVec3::ZERO, DQuat::IDENTITY),
        }
    }

    /// Clamps every DOF into its limits and re-wraps free rotation vectors below pi.
    pub fn normalize(&mut self, skeleton: &Skeleton) {
        clamp_and_wrap(skeleton, &mut self.values);
    }
}

pub(crate) fn clamp_and_wrap(skeleton: &Skeleton, values: &mut [f64]) {
    let (lo, hi) = (skeleton.lower_limits(), skeleton.upper_limits());
    for joint in skeleton.joints() {
        let mut r = DVec3::ZERO;
        let mut free = true;
        for axis in 0..3 {
            if let Some(d) = joint.rotation_dof[axis] {
                r[axis] = values[d];
                free &= lo[d] == f64::NEG_INFINITY && hi[d] == f64::INFINITY;
            }
        }
        let angle = r.length();
        if free && angle > std::f64::consts::PI && angle.is_finite() {
            let r = r * (1.0 - std::f64::consts::TAU / angle);
            for axis in 0..3 {
                if let Some(d) = joint.rotation_dof[axis] {
                    values[d] = r[axis];
                }
            }
        }
    }
    for (i, v) in values.iter_mut().enumerate() {
        *v = v.clamp(lo[i], hi[i]);
    }
}

/// Derivative of the exponential map: `d exp(r) = [J_l(r) dr]x exp(r)` (left Jacobian of
/// SO(3)). Its columns are the angular velocities (in the parent frame) produced by each
/// rotation-vector component.
pub(crate) fn so3_left_jacobian(r: DVec3) -> DMat3 {
    let t2 = r.length_squared();
    let (a, b) = if t2 < 1e-8 {
        (0.5 - t2 / 24.0, 1.0 / 6.0 - t2 / 120.0)
    } else {
        let t = t2.sqrt();
        ((1.0 - t.cos()) / t2, (t - t.sin()) / (t2 * t))
    };
    let k = skew(r);
    DMat3::IDENTITY + k * a + (k * k) * b
}

pub(crate) fn skew(v: DVec3) -> DMat3 {
    DMat3::from_cols(
        DVec3::new(0.0, v.z, -v.y),
        DVec3::new(-v.z, 0.0, v.x),
        DVec3::new(v.y, -v.x, 0.0),
    )
}

/// World frames of all joints for one posture (forward kinematics), plus what the Jacobians
/// need: per-DOF world axes and the subtree mass sums for the centre of mass.
#[derive(Debug, Clone, Default)]
pub struct Frames {
    /// `world_from_joint` rotation per joint.
    pub world_from_joint_rotation: Vec<DMat3>,
    /// World position of each joint centre (m).
    pub joint_position: Vec<DVec3>,
    /// Per DOF: world angular velocity axis (rotations) or world translation direction.
    pub dof_axis: Vec<DVec3>,
    /// Per joint: mass of the subtree rooted there (kg).
    pub subtree_mass: Vec<f64>,
    /// Per joint: sum over the subtree of `mass * world centre of mass` (kg m).
    pub subtree_moment: Vec<DVec3>,
}

impl Frames {
    /// Forward kinematics of `posture`.
    pub fn new(skeleton: &Skeleton, posture: &Posture) -> Self {
        let mut f = Self::default();
        f.update(skeleton, posture.values());
        f
    }

    /// Recomputes the frames in place (no allocation after the first call).
    pub fn update(&mut self, skeleton: &Skeleton, values: &[f64]) {
        let n = skeleton.joint_count();
        self.world_from_joint_rotation.resize(n, DMat3::IDENTITY);
        self.joint_position.resize(n, DVec3::ZERO);
        self.dof_axis.resize(skeleton.dof_count(), DVec3::ZERO);
        self.subtree_mass.resize(n, 0.0);
        self.subtree_moment.resize(n, DVec3::ZERO);
        for (j, joint) in skeleton.joints().iter().enumerate() {
            let (parent_rot, parent_pos) = match joint.parent {
                Some(p) => (self.world_from_joint_rotation[p], self.joint_position[p]),
                None => (DMat3::IDENTITY, DVec3::ZERO),
            };
            let mut t = DVec3::ZERO;
            let mut r = DVec3::ZERO;
            for axis in 0..3 {
                if let Some(d) = joint.translation_dof[axis] {
                    t[axis] = values.get(d).copied().unwrap_or(0.0);
                    self.dof_axis[d] = parent_rot.col(axis);
                }
                if let Some(d) = joint.rotation_dof[axis] {
                    r[axis] = values.get(d).copied().unwrap_or(0.0);
                }
            }
            let position = parent_pos + parent_rot * (joint.offset + t);
            let rot = if r == DVec3::ZERO {
                parent_rot
            } else {
                parent_rot * DMat3::from_quat(DQuat::from_scaled_axis(r))
            };
            if joint.has_rotation() {
                let jl = parent_rot * so3_left_jacobian(r);
                for axis in 0..3 {
                    if let Some(d) = joint.rotation_dof[axis] {
                        self.dof_axis[d] = jl.col(axis);
                    }
                }
            }
            self.world_from_joint_rotation[j] = rot;
            self.joint_position[j] = position;
            self.subtree_mass[j] = joint.mass;
            self.subtree_moment[j] = joint.mass * (position + rot * joint.com);
        }
        for j in (1..n).rev() {
            if let Some(p) = skeleton.joints()[j].parent {
                self.subtree_mass[p] += self.subtree_mass[j];
                let m = self.subtree_moment[j];
                self.subtree_moment[p] += m;
            }
        }
    }

    /// World position of a point given in a joint's frame.
    pub fn point(&self, joint: usize, local_point: DVec3) -> DVec3 {
        self.joint_position[joint] + self.world_from_joint_rotation[joint] * local_point
    }

    /// `world_from_joint` rotation as a quaternion.
    pub fn rotation(&self, joint: usize) -> DQuat {
        DQuat::from_mat3(&self.world_from_joint_rotation[joint])
    }

    /// Centre of mass of the body rooted at joint `root` (the subtree from it; the whole
    /// body for joint 0), or that joint's position when the body has no mass.
    pub fn body_center_of_mass(&self, root: usize) -> DVec3 {
        match (self.subtree_mass.get(root), self.subtree_moment.get(root)) {
            (Some(&m), Some(&s)) if m > 0.0 => s / m,
            _ => self
                .joint_position
                .get(root)
                .copied()
                .unwrap_or(DVec3::ZERO),
        }
    }

    /// Whole-body centre of mass (the root position when the body has no mass).
    pub fn center_of_mass(&self) -> DVec3 {
        match (self.subtree_mass.first(), self.subtree_moment.first()) {
            (Some(&m), Some(&s)) if m > 0.0 => s / m,
            _ => self.joint_position.first().copied().unwrap_or(DVec3::ZERO),
        }
    }
}
