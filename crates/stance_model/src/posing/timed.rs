//! Tasks over time: on a timeline each task with an active interval acts with its ease
//! weight at the shown time. A goal in the middle of a ramp is blended between where the
//! frame's own posture has the effector and the task's goal (nothing pops at the interval's
//! ends); a task of weight 0 is left out.

use glam::{DQuat, DVec3};
use stance_document::{TaskKindSpec, TaskSpec};
use stance_hanim::resolve_joint;
use stance_ik::{Frames, Skeleton};

/// A timeline frame being shown: its time and the forward kinematics of the frame's own
/// posture (before the tasks act on it).
#[derive(Debug, Clone)]
pub struct TimedFrame {
    /// The timeline's time (s).
    pub time: f64,
    /// Forward kinematics of the frame's posture.
    pub frames: Frames,
}

/// `tasks` as the solver takes them at `timed`'s time: each task with an interval weighted
/// (see the module documentation); without a timed frame, the tasks as they are.
pub fn timed_tasks(
    tasks: &[TaskSpec],
    skeleton: &Skeleton,
    timed: Option<&TimedFrame>,
) -> Vec<TaskSpec> {
    let Some(timed) = timed else {
        return tasks.to_vec();
    };
    tasks
        .iter()
        .filter_map(|spec| {
            let weight = spec
                .interval
                .map_or(1.0, |interval| interval.weight(timed.time));
            if weight <= 0.0 {
                None
            } else if weight >= 1.0 {
                Some(spec.clone())
            } else {
                Some(blended(spec, weight, skeleton, &timed.frames))
            }
        })
        .collect()
}

/// `tasks` as the solver takes them at `time` seconds of a timeline whose frame there has
/// `posture` (see [`timed_tasks`]).
pub fn timed_tasks_at(
    tasks: &[TaskSpec],
    skeleton: &Skeleton,
    posture: &stance_ik::Posture,
    time: f64,
) -> Vec<TaskSpec> {
    let timed = TimedFrame {
        time,
        frames: Frames::new(skeleton, posture),
    };
    timed_tasks(tasks, skeleton, Some(&timed))
}

/// `spec` at `weight` in (0, 1): its goal that fraction of the way from where `frames` has
/// the effector to the task's goal; a balance or posture task has its weight scaled.
pub fn blended(spec: &TaskSpec, weight: f64, skeleton: &Skeleton, frames: &Frames) -> TaskSpec {
    let mut out = spec.clone();
    let joint =
        |name: &str| resolve_joint(skeleton, name).filter(|&j| j < frames.joint_position.len());
    let lerp = |own: DVec3, goal: &mut [f64; 3]| {
        *goal = own.lerp(DVec3::from_array(*goal), weight).to_array();
    };
    match &mut out.kind {
        TaskKindSpec::Position {
            joint: name,
            point,
            target,
            ..
        } => {
            if let Some(j) = joint(name) {
                lerp(frames.point(j, DVec3::from_array(*point)), target);
            }
        }
        TaskKindSpec::Limb {
            limb,
            joints,
            target,
            orientation,
            ..
        } => {
            let end = match (limb, joints) {
                (Some(limb), _) => joint(limb.joints()[2]),
                (None, names) => names.as_ref().and_then(|names| joint(&names[2])),
            };
            if let Some(j) = end {
                lerp(frames.joint_position[j], target);
                if let Some(q) = orientation {
                    *q = slerp_to(frames.rotation(j), *q, weight);
                }
            }
        }
        TaskKindSpec::Gaze {
            joint: name,
            axis,
            point,
            target,
        } => {
            if let Some(j) = joint(name) {
                lerp(gazed_at(frames, j, *point, *axis, *target), target);
            }
        }
        TaskKindSpec::Orientation {
            joint: name,
            target,
        } => {
            if let Some(j) = joint(name) {
                *target = slerp_to(frames.rotation(j), *target, weight);
            }
        }
        TaskKindSpec::Direction {
            joint: name,
            axis,
            target,
        } => {
            if let Some(j) = joint(name) {
                let own = (frames.rotation(j) * DVec3::from_array(*axis)).normalize_or_zero();
                let goal = DVec3::from_array(*target).normalize_or_zero();
                let between = own.lerp(goal, weight);
                if between.length() > 1e-6 {
                    *target = between.to_array();
                }
            }
        }
        TaskKindSpec::Com { target, .. } => lerp(frames.center_of_mass(), target),
        TaskKindSpec::Balance { .. }
        | TaskKindSpec::Posture { .. }
        | TaskKindSpec::Comfort { .. }
        | TaskKindSpec::Line { .. }
        | TaskKindSpec::Plane { .. }
        | TaskKindSpec::Collision { .. } => out.weight *= weight,
    }
    out
}

/// Where the joint `j`'s eye at `point` looks now (along `axis`, joint frame), as far off as
/// the gaze's `target`.
fn gazed_at(frames: &Frames, j: usize, point: [f64; 3], axis: [f64; 3], target: [f64; 3]) -> DVec3 {
    let eye = frames.point(j, DVec3::from_array(point));
    let aim = (frames.rotation(j) * DVec3::from_array(axis)).normalize_or_zero();
    eye + aim * (DVec3::from_array(target) - eye).length()
}

/// The rotation `weight` of the way from `own` to the quaternion `[x, y, z, w]`.
fn slerp_to(own: DQuat, target: [f64; 4], weight: f64) -> [f64; 4] {
    let goal = DQuat::from_array(target).normalize();
    own.slerp(goal, weight).normalize().to_array()
}
