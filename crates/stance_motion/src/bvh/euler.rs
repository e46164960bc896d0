//! Euler angle orders as BVH writes them: the rotation is the product of the per-axis
//! rotations in channel order (intrinsic), e.g. `Zrotation Xrotation Yrotation` is
//! `Rz * Rx * Ry`.

use glam::{DMat3, DQuat, DVec3};

/// The order of a joint's three rotation channels. The rotation is the product of the
/// axis rotations in this order: [`EulerOrder::Zxy`] is `Rz(a0) * Rx(a1) * Ry(a2)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum EulerOrder {
    /// `Xrotation Yrotation Zrotation`: `Rx * Ry * Rz`.
    Xyz,
    /// `Xrotation Zrotation Yrotation`: `Rx * Rz * Ry`.
    Xzy,
    /// `Yrotation Xrotation Zrotation`: `Ry * Rx * Rz`.
    Yxz,
    /// `Yrotation Zrotation Xrotation`: `Ry * Rz * Rx`.
    Yzx,
    /// `Zrotation Xrotation Yrotation`: `Rz * Rx * Ry` (the most common BVH order).
    #[default]
    Zxy,
    /// `Zrotation Yrotation Xrotation`: `Rz * Ry * Rx` (CMU's conversions).
    Zyx,
}

impl EulerOrder {
    /// All six orders.
    pub const ALL: [Self; 6] = [
        Self::Xyz,
        Self::Xzy,
        Self::Yxz,
        Self::Yzx,
        Self::Zxy,
        Self::Zyx,
    ];

    /// The axes in order (0 = X, 1 = Y, 2 = Z).
    pub fn axes(self) -> [usize; 3] {
        match self {
            Self::Xyz => [0, 1, 2],
            Self::Xzy => [0, 2, 1],
            Self::Yxz => [1, 0, 2],
            Self::Yzx => [1, 2, 0],
            Self::Zxy => [2, 0, 1],
            Self::Zyx => [2, 1, 0],
        }
    }

    /// The order whose axes are `axes` (a permutation of 0, 1, 2).
    pub fn from_axes(axes: [usize; 3]) -> Option<Self> {
        Self::ALL.into_iter().find(|o| o.axes() == axes)
    }

    /// The BVH channel names of the rotation channels, in order.
    pub fn channel_names(self) -> [&'static str; 3] {
        self.axes()
            .map(|a| ["Xrotation", "Yrotation", "Zrotation"][a])
    }

    /// The rotation of the angles (radians), `angles[i]` about the `i`-th axis of the order.
    pub fn to_quat(self, angles: [f64; 3]) -> DQuat {
        let [a, b, c] = self.axes();
        axis_rotation(a, angles[0]) * axis_rotation(b, angles[1]) * axis_rotation(c, angles[2])
    }

    /// Angles (radians) of a rotation, in the order's sequence, such that
    /// `to_quat(from_quat(q))` is `q` (up to sign). The middle angle is in
    /// `[-pi/2, pi/2]`; at gimbal lock the first is 0.
    pub fn from_quat(self, q: DQuat) -> [f64; 3] {
        let q = q.normalize();
        if !q.is_finite() {
            return [0.0; 3];
        }
        let [i, j, k] = self.axes();
        let m = DMat3::from_quat(q);
        let r = |row: usize, col: usize| m.col(col)[row];
        // +1 for the cyclic orders (xyz, yzx, zxy), -1 for the others.
        let s = if (j + 3 - i) % 3 == 1 { 1.0 } else { -1.0 };
        let cos_b = r(i, i).hypot(r(i, j));
        let b = (s * r(i, k)).atan2(cos_b);
        let a = if cos_b > 1e-12 {
            (-s * r(j, k)).atan2(r(k, k))
        } else {
            0.0
        };
        // The last angle from what remains, exact even near gimbal lock.
        let rest = (axis_rotation(i, a) * axis_rotation(j, b)).inverse() * q;
        let v = DVec3::new(rest.x, rest.y, rest.z);
        let c = 2.0 * v[k].atan2(rest.w);
        let c = wrap(c);
        [wrap(a), b, c]
    }
}

/// Rotation about axis `axis` (0 = X, 1 = Y, 2 = Z) by `angle` radians.
pub(crate) fn axis_rotation(axis: usize, angle: f64) -> DQuat {
    match axis {
        0 => DQuat::from_rotation_x(angle),
        1 => DQuat::from_rotation_y(angle),
        _ => DQuat::from_rotation_z(angle),
    }
}

/// Angle wrapped into (-pi, pi].
fn wrap(a: f64) -> f64 {
    let tau = std::f64::consts::TAU;
    let w = a.rem_euclid(tau);
    if w > std::f64::consts::PI { w - tau } else { w }
}
