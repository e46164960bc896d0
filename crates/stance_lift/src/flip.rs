//! The depth flip of a limb: what a single image cannot tell (a forearm toward the camera or
//! away from it projects the same), undone by hand. The editor can offer it as one click:
//! flip the posture, then solve the document's tasks from it again ([`crate::solve`]).

use glam::{DQuat, DVec3};
use stance_hanim::resolve_joint;
use stance_ik::{Frames, Posture, Skeleton, nearest_rotation_vector};
use stance_render::OrbitCamera;

use crate::LiftError;

/// `posture` with `joint`'s depth mirrored: the segment from its parent joint (the nearest
/// ancestor that turns) to `joint` reflected in the plane through the parent's centre
/// perpendicular to the line of sight to it (in orthographic projection, the plane parallel
/// to the image), so that `joint` lands where the camera sees it at the same place (exactly
/// in orthographic projection, to first order in perspective), the other side of its parent
/// in depth. The parent turns by the shortest rotation that carries the segment there, as far
/// as its DOF and limits allow; the limbs below turn with it. Solve the tasks again from the
/// result to put every keypoint back on its ray.
pub fn flip_depth(
    skeleton: &Skeleton,
    posture: &Posture,
    camera: &OrbitCamera,
    joint: &str,
) -> Result<Posture, LiftError> {
    let j =
        resolve_joint(skeleton, joint).ok_or_else(|| LiftError::UnknownJoint(joint.to_owned()))?;
    let turns = |p: usize| {
        skeleton.joints()[p]
            .rotation_dof
            .iter()
            .any(Option::is_some)
    };
    let mut parent = skeleton.joints()[j].parent;
    while let Some(p) = parent
        && !turns(p)
    {
        parent = skeleton.joints()[p].parent;
    }
    let p = parent.ok_or_else(|| LiftError::CannotFlip(joint.to_owned()))?;
    let frames = Frames::new(skeleton, posture);
    let (at_parent, at_joint) = (frames.joint_position[p], frames.joint_position[j]);
    let eye = camera.eye_world().as_dvec3();
    let sight = if camera.orthographic {
        camera.target_world.as_dvec3() - eye
    } else {
        at_parent - eye
    }
    .normalize_or(DVec3::NEG_Z);
    let segment = at_joint - at_parent;
    let mirrored = segment - sight * (2.0 * segment.dot(sight));
    if segment.length() < 1e-9 || (mirrored - segment).length() < 1e-9 {
        return Ok(posture.clone());
    }
    let turn = DQuat::from_rotation_arc(segment.normalize(), mirrored.normalize());
    let grandparent = skeleton.joints()[p]
        .parent
        .map_or(DQuat::IDENTITY, |g| frames.rotation(g));
    let local = grandparent.inverse() * turn * frames.rotation(p);
    let definition = &skeleton.joints()[p];
    let (lower, upper) = (skeleton.lower_limits(), skeleton.upper_limits());
    let mut dofs = [false; 3];
    let (mut lo, mut hi) = (DVec3::splat(f64::NEG_INFINITY), DVec3::splat(f64::INFINITY));
    for (axis, dof) in definition.rotation_dof.iter().enumerate() {
        if let Some(d) = *dof {
            dofs[axis] = true;
            lo[axis] = lower[d];
            hi[axis] = upper[d];
        }
    }
    let r = nearest_rotation_vector(local, dofs, lo, hi);
    let mut flipped = posture.clone();
    for (axis, dof) in definition.rotation_dof.iter().enumerate() {
        if let Some(d) = *dof {
            flipped.values_mut()[d] = r[axis];
        }
    }
    Ok(flipped)
}
