//! The depth flip of a limb: what a single image cannot tell (a forearm toward the camera or
//! away from it projects the same), undone by hand. The editor can offer it as one click:
//! flip the posture, then solve the document's tasks from it again ([`crate::solve`]).

use glam::{DQuat, DVec3};
use stance_hanim::resolve_joint;
use stance_ik::{Frames, Posture, Skeleton, nearest_rotation_vector};
use stance_render::OrbitCamera;

use crate::LiftError;

/// `posture` with `joint`'s depth mirrored: `joint` and the limb below it (each joint's only
/// child in turn, to where the hand or foot branches) reflected in the plane through the
/// centre of its parent joint (the nearest ancestor that turns) perpendicular to the line of
/// sight to it (in orthographic projection, the plane parallel to the image), so that each
/// lands where the camera sees it at the same place (exactly in orthographic projection, to
/// first order in perspective), the other side of the parent in depth. Each joint of the chain
/// turns by the shortest rotation that carries its segment there, as far as its DOF and limits
/// allow. Solve the tasks again from the result ([`crate::solve`]) to put every keypoint back
/// on its ray.
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
    let at_parent = frames.joint_position[p];
    let eye = camera.eye_world().as_dvec3();
    let sight = if camera.orthographic {
        camera.target_world.as_dvec3() - eye
    } else {
        at_parent - eye
    }
    .normalize_or(DVec3::NEG_Z);
    let mirror = |x: DVec3| x - sight * (2.0 * (x - at_parent).dot(sight));
    // The limb from the parent down: `joint`, then each joint's only child (the wrist or
    // ankle ends it where the hand or foot branches).
    let mut chain = vec![p, j];
    while chain.len() < 5 {
        let last = chain[chain.len() - 1];
        let children: Vec<usize> = (0..skeleton.joint_count())
            .filter(|&c| skeleton.joints()[c].parent == Some(last))
            .collect();
        match children.as_slice() {
            [only] => chain.push(*only),
            _ => break,
        }
    }
    let goals: Vec<DVec3> = chain
        .iter()
        .map(|&c| mirror(frames.joint_position[c]))
        .collect();
    let mut flipped = posture.clone();
    for (k, pair) in chain.windows(2).enumerate() {
        let (a, b) = (pair[0], pair[1]);
        let now = Frames::new(skeleton, &flipped);
        let (at_a, at_b) = (now.joint_position[a], now.joint_position[b]);
        let (from, to) = (at_b - at_a, goals[k + 1] - at_a);
        if from.length() < 1e-9 || to.length() < 1e-9 {
            continue;
        }
        let turn = DQuat::from_rotation_arc(from.normalize(), to.normalize());
        turn_joint(skeleton, &now, &mut flipped, a, turn);
    }
    Ok(flipped)
}

/// Turns joint `a` by the world rotation `turn` (its children with it), as far as its DOF
/// and limits allow.
fn turn_joint(skeleton: &Skeleton, frames: &Frames, posture: &mut Posture, a: usize, turn: DQuat) {
    let definition = &skeleton.joints()[a];
    let above = definition
        .parent
        .map_or(DQuat::IDENTITY, |g| frames.rotation(g));
    let local = above.inverse() * turn * frames.rotation(a);
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
    for (axis, dof) in definition.rotation_dof.iter().enumerate() {
        if let Some(d) = *dof {
            posture.values_mut()[d] = r[axis];
        }
    }
}
