//! How each task of a problem fares in a posture: its residual, and when it is not met, why
//! it gave way (the higher-priority tasks it conflicts with, the joint limits, or a goal out of
//! reach). One status for the editor's task list, `stance solve` and the `stance-ik` package.

use serde::Serialize;
use serde_json::{Value, json};
use stance_hanim::HumanoidSkeleton;
use stance_hanim::anatomy::{JointClass, segment_of};
use stance_hanim::{Side, readable_name};
use stance_ik::conflict::{Unmet, diagnose};
use stance_ik::{Frames, Posture, Skeleton, Task, TaskKind};

use crate::TaskSpec;

/// Residual below which a task counts as met (m or rad).
pub const MET_TOLERANCE: f64 = 1e-3;

/// How one task fares in a posture.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TaskStatus {
    /// Norm of the task's error (m or rad); `None` when the task cannot be evaluated.
    pub residual: Option<f64>,
    /// Why the task is not met, in words; `None` when it is met, inactive or soft.
    pub gave_way: Option<String>,
    /// The task cannot be turned into a solver task (e.g. an unknown joint).
    pub problem: Option<String>,
}

/// The statuses of `specs` in `posture` (`frames` its forward kinematics) on `skeleton`, or on
/// a built `body` (whose comfort tasks read its own anatomical axes). `settled`: the solve has
/// ended; while it runs an unmet task is "still moving".
pub fn task_statuses(
    skeleton: &Skeleton,
    body: Option<&HumanoidSkeleton>,
    posture: &Posture,
    frames: &Frames,
    specs: &[TaskSpec],
    settled: bool,
) -> Vec<TaskStatus> {
    let values = posture.values();
    let evaluated: Vec<Result<f64, String>> = specs
        .iter()
        .map(|spec| match spec.solver_tasks_with(skeleton, body, specs) {
            Ok(converted) => Ok(converted
                .iter()
                .map(|task| task.residual(skeleton, frames, values).powi(2))
                .sum::<f64>()
                .sqrt()),
            Err(error) => Err(error.to_string()),
        })
        .collect();
    specs
        .iter()
        .zip(&evaluated)
        .map(|(spec, own)| {
            let residual = own.as_ref().ok().copied();
            let unmet =
                spec.active && !spec.kind.is_soft() && residual.is_some_and(|r| r > MET_TOLERANCE);
            let gave_way = unmet.then(|| {
                if settled {
                    why_unmet(skeleton, body, posture, spec, specs, &evaluated)
                } else {
                    "still moving".to_owned()
                }
            });
            TaskStatus {
                residual,
                gave_way,
                problem: own.as_ref().err().cloned(),
            }
        })
        .collect()
}

/// The statuses of `specs` as `stance solve` and the package print them: per task its level,
/// description, residual, whether it is met ([`MET_TOLERANCE`]), why it gave way and what
/// keeps it from the solver.
pub fn statuses_json(specs: &[TaskSpec], statuses: &[TaskStatus]) -> Value {
    specs
        .iter()
        .zip(statuses)
        .map(|(spec, status)| {
            json!({
                "level": spec.level,
                "description": spec.description(),
                "residual": status.residual,
                "met": status.residual.is_some_and(|r| r <= MET_TOLERANCE),
                "gave_way": status.gave_way,
                "problem": status.problem,
            })
        })
        .collect()
}

/// Names the higher-priority tasks a task really gave way to (those that, held, take away
/// its progress; see `stance_ik::conflict`), or says the goal is out of reach or stopped by
/// the joint limits.
fn why_unmet(
    skeleton: &Skeleton,
    body: Option<&HumanoidSkeleton>,
    posture: &Posture,
    spec: &TaskSpec,
    specs: &[TaskSpec],
    evaluated: &[Result<f64, String>],
) -> String {
    let Ok(task) = spec.task_with(skeleton, body, specs) else {
        return "out of reach".to_owned();
    };
    let higher: Vec<(&TaskSpec, Task)> = specs
        .iter()
        .zip(evaluated)
        .filter(|(other, evaluated)| {
            other.active && other.level < spec.level && !other.kind.is_soft() && evaluated.is_ok()
        })
        .filter_map(|(other, _)| Some((other, other.task_with(skeleton, body, specs).ok()?)))
        .collect();
    let solver_tasks: Vec<Task> = higher.iter().map(|(_, task)| task.clone()).collect();
    match diagnose(skeleton, posture, &task, &solver_tasks) {
        Unmet::Conflicts(indices) => {
            // A collision task in the way: the contact that stops the task's part.
            if let Some(words) = indices
                .iter()
                .filter_map(|&index| higher.get(index))
                .find_map(|(_, other)| stopped_by(skeleton, posture, &task, other))
            {
                return format!("gives way to collision: {words}");
            }
            let names: Vec<String> = indices
                .iter()
                .filter_map(|&index| higher.get(index))
                .map(|(other, _)| format!("level {}: {}", other.level, other.description()))
                .collect();
            format!("conflicts with {}", names.join(", "))
        }
        Unmet::JointLimits => "limited by joint limits".to_owned(),
        Unmet::OutOfReach => "out of reach".to_owned(),
    }
}

/// The contact of the collision task `collision` (none for another kind) that stops `task`'s
/// part at `posture`, in words ("right forearm against middle trunk"): the nearest one whose
/// parts `task` moves, the part it moves named first.
fn stopped_by(
    skeleton: &Skeleton,
    posture: &Posture,
    task: &Task,
    collision: &Task,
) -> Option<String> {
    let TaskKind::Collision(c) = &collision.kind else {
        return None;
    };
    let moved = task.support(skeleton);
    let joints = skeleton.joints();
    let moves = |joint: usize| {
        joints
            .get(joint)
            .is_some_and(|j| j.dof_range().any(|d| moved.contains(&d)))
    };
    let contact = c
        .contacts(&Frames::new(skeleton, posture))
        .into_iter()
        .find(|contact| moves(contact.joints.0) || contact.joints.1.is_some_and(moves))?;
    let part = |joint: usize| {
        let Some(name) = joints.get(joint).map(|j| j.name.as_str()) else {
            return "a part".to_owned();
        };
        let side = match Side::split(name).0 {
            Side::Left => "left ",
            Side::Right => "right ",
            Side::Centre => "",
        };
        segment_of(JointClass::of(name)).map_or_else(
            || readable_name(name),
            |segment| format!("{side}{}", segment.name),
        )
    };
    let first = part(contact.joints.0);
    let other = match contact.joints.1 {
        Some(joint) => part(joint),
        // The floor holds its point at height 0.
        None if contact.points.1.y.abs() < 1e-9 => "the floor".to_owned(),
        None => "a prop".to_owned(),
    };
    // The part the task moves first; of two, the one further down the tree (joints come
    // parents first): the limb, not the trunk that carries it too.
    let first_moved = match contact.joints.1 {
        Some(second) if moves(second) => moves(contact.joints.0) && contact.joints.0 > second,
        _ => true,
    };
    Some(if first_moved {
        format!("{first} against {other}")
    } else {
        format!("{other} against {first}")
    })
}
