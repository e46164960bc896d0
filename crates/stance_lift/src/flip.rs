//! The depth flip of a limb: what a single image cannot tell (a forearm toward the camera or
//! away from it projects the same), undone by hand. The editor can offer it as one click:
//! flip the posture, then solve the document's tasks from it again ([`crate::solve`]).

use glam::{DQuat, DVec3};
use stance_hanim::resolve_joint;
use stance_ik::{
    CONSTANT_DAMPING, Frames, Posture, Skeleton, Solver, SolverSettings, Task,
    nearest_rotation_vector,
};
use stance_render::OrbitCamera;

use crate::LiftError;
use crate::place::{LIMBS, PlacedLimb, Ray, other_depth, ray_sphere};
use crate::stages::descends_from;

/// `posture` with `joint`'s depth mirrored, every keypoint of the limb seen at the same place.
///
/// For the middle or end joint of an arm or a leg (`r_elbow`, `l_knee`, `r_radiocarpal`,
/// `l_talocrural`...) the flip is exact, in perspective too: the joint moves along the camera
/// ray through it to the other point at its bone's length from its parent joint (its mirror in
/// the plane through the parent perpendicular to that ray); for a middle joint the end joint
/// follows, along its own ray to the point at its bone's length from the flipped middle joint
/// on the other side in depth (as the whole limb mirrored would put it). The limb's closed form
/// turns the three joints there (`stance_ik::Limb`, within the joint limits where it can; the
/// hand or foot below turns with the end joint). For any other joint: the joint and the chain
/// below it mirrored in the plane through its parent joint perpendicular to the line of sight,
/// each joint turned by the shortest rotation that carries its segment there. Solve the tasks
/// again from the result ([`crate::solve`]) to put every keypoint (the hand's too) back on
/// its ray.
pub fn flip_depth(
    skeleton: &Skeleton,
    posture: &Posture,
    camera: &OrbitCamera,
    joint: &str,
) -> Result<Posture, LiftError> {
    let j =
        resolve_joint(skeleton, joint).ok_or_else(|| LiftError::UnknownJoint(joint.to_owned()))?;
    if let Some(flipped) = flip_limb(skeleton, posture, camera, j) {
        return flipped;
    }
    flip_chain(skeleton, posture, camera, joint, j)
}

/// A flipped limb whose middle or end joint the closed form cannot put within this of its
/// mirrored place (m; about 15 px at 3.4 m in a 768 px image) does not fit its keypoints
/// within the joints' ranges: refused. Nearer, the solve afterwards puts it on its rays.
const FLIP_FIT_M: f64 = 0.05;

/// The exact flip of a limb's middle or end joint `j` (see [`flip_depth`]); `None` when `j`
/// is neither.
fn flip_limb(
    skeleton: &Skeleton,
    posture: &Posture,
    camera: &OrbitCamera,
    j: usize,
) -> Option<Result<Posture, LiftError>> {
    let name = skeleton.joints().get(j)?.name.as_str();
    let (limb, middle) = LIMBS.iter().find_map(|limb| {
        let at = limb.joints.iter().position(|n| *n == name)?;
        (at > 0).then_some((limb, at == 1))
    })?;
    let placed = PlacedLimb::new(skeleton, limb.joints)?;
    let frames = Frames::new(skeleton, posture);
    let [upper, at_middle, at_end] = placed.positions(&frames);
    let ray = |p: DVec3| -> Ray { (p, sight(camera, p)) };
    let (middle_ray, end_ray) = (ray(at_middle), ray(at_end));
    let goal = if middle {
        let flipped = other_depth(middle_ray, upper, at_middle);
        // The end joint on the other side of the middle joint in depth, as it was of it.
        let was_far = (at_end - at_middle).dot(end_ray.1) > 0.0;
        let [near, far] = ray_sphere(end_ray, flipped, placed.lengths()[1]);
        [flipped, if was_far { near } else { far }]
    } else {
        [at_middle, other_depth(end_ray, at_middle, at_end)]
    };
    let mut flipped = posture.clone();
    placed.place(skeleton, &mut flipped, goal);
    let [_, middle_at, end_at] = placed.positions(&Frames::new(skeleton, &flipped));
    let off = middle_at.distance(goal[0]).max(end_at.distance(goal[1]));
    if off > FLIP_FIT_M {
        return Some(Err(LiftError::FlipOutOfRange {
            joint: name.to_owned(),
            off_mm: off * 1e3,
        }));
    }
    mirror_hand(skeleton, &frames, &mut flipped, camera, placed.joints());
    Some(Ok(flipped))
}

/// A ray's origin this far before the joint it passes through, back toward the camera (m):
/// any point of the line does for [`ray_sphere`].
const RAY_BACK_M: f64 = 10.0;
/// Iterations of the solve that brings a hand back onto its rays after its arm's flip.
const HAND_MIRROR_ITERATIONS: usize = 20;

/// After a limb's flip, what hangs below its end joint (a hand's finger joints) brought back
/// onto the camera rays through where its joints were `before` the flip: each joint, in order
/// down the hand, at the point of its ray at its distance (before) from the joint above it
/// (already placed) nearest to where the whole limb mirrored in depth would put it (its offset
/// from the joint above reflected in the plane perpendicular to the ray through the end
/// joint). Solved for on the forearm's and the hand's DOF, so that its
/// keypoints start on their rays whatever the flip did to the hand's turn (the tasks' solve
/// afterwards polishes what the joint limits leave).
fn mirror_hand(
    skeleton: &Skeleton,
    before: &Frames,
    posture: &mut Posture,
    camera: &OrbitCamera,
    [_, middle, end]: [usize; 3],
) {
    let below: Vec<usize> = (0..skeleton.joint_count())
        .filter(|&j| j != end && descends_from(skeleton, j, end))
        .collect();
    if below.is_empty() {
        return;
    }
    let after = Frames::new(skeleton, posture);
    let mut placed: Vec<(usize, DVec3)> = vec![(end, after.joint_position[end])];
    let sight_at_end = sight(camera, after.joint_position[end]);
    for &j in &below {
        let Some(&(above, at)) = skeleton.joints()[j]
            .parent
            .and_then(|p| placed.iter().find(|(k, _)| *k == p))
        else {
            continue;
        };
        let (was, was_above) = (before.joint_position[j], before.joint_position[above]);
        let u = sight(camera, was);
        let ray = (was - u * RAY_BACK_M, u);
        let offset = was - was_above;
        let mirrored = at + (offset - sight_at_end * (2.0 * offset.dot(sight_at_end)));
        let [near, far] = ray_sphere(ray, at, (was - was_above).length());
        let target = if near.distance(mirrored) <= far.distance(mirrored) {
            near
        } else {
            far
        };
        placed.push((j, target));
    }
    // The end joint where the flip put it first; the hand's joints below.
    let tasks: Vec<Task> = placed
        .iter()
        .map(|&(j, target)| {
            Task::position(j, DVec3::ZERO, target).at_level(if j == end { 1 } else { 2 })
        })
        .collect();
    let Ok(mut solver) = Solver::new(SolverSettings {
        max_iterations: HAND_MIRROR_ITERATIONS,
        restarts: false,
        damping: CONSTANT_DAMPING,
        ..SolverSettings::default()
    }) else {
        return;
    };
    let held: Vec<usize> = skeleton
        .joints()
        .iter()
        .enumerate()
        .filter(|&(j, _)| !descends_from(skeleton, j, middle))
        .flat_map(|(_, joint)| joint.dof_range())
        .collect();
    solver.set_locked_dofs(&held);
    let mut mirrored = posture.clone();
    if solver.solve(skeleton, &tasks, &mut mirrored).is_ok() {
        *posture = mirrored;
    }
}

/// The unit direction of the camera's ray through the world point `p`.
fn sight(camera: &OrbitCamera, p: DVec3) -> DVec3 {
    let eye = camera.eye_world().as_dvec3();
    if camera.orthographic {
        camera.target_world.as_dvec3() - eye
    } else {
        p - eye
    }
    .normalize_or(DVec3::NEG_Z)
}

/// The generic flip of [`flip_depth`]: `joint` and the chain below it mirrored about its
/// parent joint, perpendicular to the line of sight.
fn flip_chain(
    skeleton: &Skeleton,
    posture: &Posture,
    camera: &OrbitCamera,
    joint: &str,
    j: usize,
) -> Result<Posture, LiftError> {
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
    let sight = sight(camera, at_parent);
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
