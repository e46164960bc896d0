//! How each task of a problem fares in a posture: its residual, and when it is not met, why
//! it gave way (the higher-priority tasks it conflicts with, the joint limits, or a goal out of
//! reach). One status for the editor's task list, `stance solve` and the `stance-ik` package.

use serde::Serialize;
use serde_json::{Value, json};
use stance_hanim::HumanoidSkeleton;
use stance_ik::conflict::{Unmet, diagnose};
use stance_ik::{Frames, Posture, Skeleton, Task};

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
