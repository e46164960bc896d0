//! The point-on-a-line and point-on-a-plane tasks: an effector point kept on a world line (a
//! hand on a bar, a keypoint on the camera ray through its pixel) or on a world plane (a
//! hand or foot on a surface; optionally on or above it, an inequality).
//!
//! Both errors are linear in the effector point `p`, so their Jacobians are exact: the line's
//! two rows are `p`'s offset from the line along two unit vectors orthogonal to its
//! direction, the plane's row is the signed distance `n · (p - origin)`.

use glam::DVec3;

/// The band over the plane (m) inside which an "on or above" plane task holds its row with a
/// zero error (the point may slide along the plane but not go below it); further above, the
/// row is empty. As the balance and collision inequalities do.
pub const PLANE_BAND: f64 = 0.002;

/// Two unit vectors orthogonal to the unit `direction` and to each other, the same for the
/// same direction (the rows of a line task).
pub(crate) fn line_basis(direction: DVec3) -> [DVec3; 2] {
    let u = direction.normalize_or(DVec3::Z);
    let first = u.any_orthonormal_vector();
    [first, u.cross(first)]
}

/// The offset of `point` from the line through `origin` along `direction`, on the line's
/// two row vectors: what a line task drives to zero.
pub(crate) fn line_offset(point: DVec3, origin: DVec3, direction: DVec3) -> [f64; 2] {
    let [e1, e2] = line_basis(direction);
    let d = point - origin;
    [d.dot(e1), d.dot(e2)]
}

/// The signed distance of `point` from the plane through `origin` with normal `normal`
/// (positive on the side the normal points to).
pub(crate) fn plane_distance(point: DVec3, origin: DVec3, normal: DVec3) -> f64 {
    normal.normalize_or(DVec3::Y).dot(point - origin)
}

/// Whether a plane task's row acts at the signed distance `distance`: always for an equality,
/// for "on or above" only below [`PLANE_BAND`].
pub(crate) fn plane_active(distance: f64, above: bool) -> bool {
    !above || distance <= PLANE_BAND
}

/// A plane task's error at the signed distance `distance`: minus the distance for an
/// equality; for "on or above", minus the distance below the plane and zero over it.
pub(crate) fn plane_error(distance: f64, above: bool) -> f64 {
    if above {
        (-distance).max(0.0)
    } else {
        -distance
    }
}
