//! The lift's solve in stages, each on the DOF that move its keypoints.
//!
//! A lifted document holds a camera-ray task per keypoint: 18 on the body and 21 on each hand
//! (59 tasks, 118 rows on the 132 DOF of the LOA 2 body). Solved as one problem, every
//! iteration factors a 118-row level on 132 DOF (2 to 3 ms; `stance_ik`'s kernel spends its
//! time in the level's QR and Gram matrix, which grow with rows squared times DOF). But a hand's
//! keypoints move only with the forearm and the hand (the elbow and the joints below it), and
//! the body's keypoints not at all with the fingers. So:
//!
//! 1. **The body**: every task but the hands' keypoints (the body's keypoints, the feet, balance,
//!    comfort when asked), the DOF that move none of those tasks' points held: the hands (the
//!    wrist joint and below) and the toes. About 38 rows on 68 DOF.
//! 2. **Each hand**: its keypoints and those on its forearm (the wrist's), on the elbow's twist
//!    and the DOF below it, everything else held (the elbow's hinge too: the body stage placed
//!    the wrist). 42 rows on 29 DOF.
//!
//! The report is the whole problem's at the result (every level's residual as one solve
//! reports it), its iterations the stages' sum.

use stance_document::{Document, PostureValues, Problem};
use stance_ik::{
    CONSTANT_DAMPING, Limb, Posture, Skeleton, SolveReport, SolveStatus, SolverSettings, Task,
    TaskKind,
};

use crate::LiftError;

/// A stage stops when this many iterations in a row bring no meaningful improvement: from the
/// placed start a stage that will meet its levels does so in a few iterations, and one that
/// cannot (a fitted camera, balance against the feet, a hand whose arm is at the wrong depth)
/// no longer spends the default 40 finding that out. Every stalled stage spends the window
/// (three stages a solve, a solve per flip candidate): 5 against 10 cut the lift's time on
/// the CPU by a fifth on the tuned postures and by a third on the random family
/// (`examples/lift_bench`), the keypoints left over 2 px as many. No restarts either: the
/// lift's own start is the better start (module docs of `lift`).
const STALL_WINDOW: usize = 5;

/// The joints whose subtree is a hand: the wrists (`*_radiocarpal`) where fingers hang below.
fn hand_roots(skeleton: &Skeleton) -> Vec<usize> {
    ["l_radiocarpal", "r_radiocarpal"]
        .into_iter()
        .filter_map(|name| skeleton.joint_index(name))
        .filter(|&wrist| {
            skeleton
                .joints()
                .iter()
                .any(|joint| joint.parent == Some(wrist))
        })
        .collect()
}

/// The hinge DOF of the elbow above the wrist `hand` (its flexion; its other DOF turns the
/// forearm about itself).
fn elbow_hinge(skeleton: &Skeleton, hand: usize) -> Option<usize> {
    let wrist = &skeleton.joints().get(hand)?.name;
    let limb = crate::place::LIMBS
        .iter()
        .find(|limb| limb.joints[2] == wrist.as_str())?;
    Some(Limb::from_names(skeleton, limb.joints).ok()?.hinge_dof())
}

/// Whether `joint` is `ancestor` or below it.
pub(crate) fn descends_from(skeleton: &Skeleton, joint: usize, ancestor: usize) -> bool {
    let mut at = Some(joint);
    while let Some(index) = at {
        if index == ancestor {
            return true;
        }
        at = skeleton.joints().get(index).and_then(|j| j.parent);
    }
    false
}

/// The joint a task holds: a keypoint on its ray, an ankle on the floor, and what a user may
/// add to a lifted document (a point, a turn, a gaze, a direction); `None` for the tasks of
/// the whole body (balance, comfort, ...), which go to the body stage.
fn task_joint(task: &Task) -> Option<usize> {
    match &task.kind {
        TaskKind::PointOnLine { effector, .. }
        | TaskKind::PointOnPlane { effector, .. }
        | TaskKind::Position { effector, .. }
        | TaskKind::Gaze { effector, .. } => Some(effector.joint),
        TaskKind::Orientation { joint, .. } | TaskKind::Direction { joint, .. } => Some(*joint),
        _ => None,
    }
}

fn is_comfort(task: &Task) -> bool {
    matches!(task.kind, TaskKind::Comfort { .. })
}

/// The DOF of the joints for which `keep` is false.
fn dofs_where(skeleton: &Skeleton, keep: impl Fn(usize) -> bool) -> Vec<usize> {
    skeleton
        .joints()
        .iter()
        .enumerate()
        .filter(|&(j, _)| !keep(j))
        .flat_map(|(_, joint)| joint.dof_range())
        .collect()
}

/// `document`'s problem on `skeleton`, solved from `start`.
fn problem_from(
    skeleton: &Skeleton,
    document: &Document,
    start: &Posture,
) -> Result<Problem, LiftError> {
    let with_start = Document {
        posture: PostureValues::from_posture(skeleton, start),
        ..document.clone()
    };
    let mut problem = Problem::from_document(&with_start, skeleton.clone())
        .map_err(|e| LiftError::Problem(e.to_string()))?;
    // A fit: some keypoints are never met exactly, and the falling damping's undamped steps
    // near a singular level throw it off.
    problem.settings.damping = CONSTANT_DAMPING;
    Ok(problem)
}

/// The problem's tasks but its comfort task.
fn without_comfort(problem: &Problem) -> Vec<Task> {
    problem
        .tasks
        .iter()
        .filter(|t| !is_comfort(t))
        .cloned()
        .collect()
}

/// The settings of one stage's solve: no restarts, the stages' stall window.
fn stage_settings(problem: &Problem, max_iterations: usize, tolerance: f64) -> SolverSettings {
    SolverSettings {
        max_iterations,
        tolerance,
        restarts: false,
        stall_window: STALL_WINDOW,
        ..problem.settings
    }
}

/// Solves `document`'s tasks from `start` in the stages of the module's docs (the comfort
/// task only with `comfort`), at most `max_iterations` each, a level met within `tolerance`.
pub(crate) fn solve_staged(
    skeleton: &Skeleton,
    document: &Document,
    start: &Posture,
    max_iterations: usize,
    tolerance: f64,
    comfort: bool,
) -> Result<(Posture, SolveReport), LiftError> {
    let problem = problem_from(skeleton, document, start)?;
    let body = &problem.skeleton;
    let settings = stage_settings(&problem, max_iterations, tolerance);
    let solver = |locked: &[usize], iterations: usize| {
        let mut solver = problem
            .solver(SolverSettings {
                max_iterations: iterations,
                ..settings
            })
            .map_err(|e| LiftError::Problem(e.to_string()))?;
        solver.set_locked_dofs(locked);
        Ok::<_, LiftError>(solver)
    };
    let tasks: Vec<Task> = problem
        .tasks
        .iter()
        .filter(|t| comfort || !is_comfort(t))
        .cloned()
        .collect();
    let hands = hand_roots(body);
    let in_hand = |j: usize| hands.iter().any(|&h| j != h && descends_from(body, j, h));
    let body_tasks: Vec<Task> = tasks
        .iter()
        .filter(|t| !task_joint(t).is_some_and(in_hand))
        .cloned()
        .collect();
    // Held in the body stage: the joints that carry none of its tasks' points, nor have one
    // below them (the hands, the toes).
    let held_points: Vec<usize> = body_tasks.iter().filter_map(task_joint).collect();
    let moves_a_point = |j: usize| {
        held_points
            .iter()
            .any(|&point| descends_from(body, point, j))
    };
    let mut posture = start.clone();
    let mut stage = solver(&dofs_where(body, moves_a_point), max_iterations)?;
    let body_report = stage
        .solve(body, &body_tasks, &mut posture)
        .map_err(|e| LiftError::Problem(e.to_string()))?;
    let mut iterations = body_report.iterations;
    let mut status = body_report.status;
    for &hand in &hands {
        let Some((hand_tasks, held)) = hand_stage(body, &tasks, hand) else {
            continue;
        };
        let mut stage = solver(&held, max_iterations)?;
        let report = stage
            .solve(body, &hand_tasks, &mut posture)
            .map_err(|e| LiftError::Problem(e.to_string()))?;
        iterations += report.iterations;
        if status == SolveStatus::Converged {
            status = report.status;
        }
    }
    let report = report_at(solver(&[], 0)?, body, &tasks, &posture, iterations, status)?;
    Ok((posture, report))
}

/// The stage of the hand below the wrist `hand` (module docs): the tasks on its forearm and
/// below (comfort aside), and the DOF held (all but the forearm's and below, and the elbow's
/// hinge: it would move the wrist, which the body stage placed); `None` when no keypoint of
/// the hand is among `tasks`.
fn hand_stage(body: &Skeleton, tasks: &[Task], hand: usize) -> Option<(Vec<Task>, Vec<usize>)> {
    let forearm = body.joints().get(hand)?.parent?;
    let on_forearm = |j: usize| descends_from(body, j, forearm);
    let hand_tasks: Vec<Task> = tasks
        .iter()
        .filter(|t| !is_comfort(t) && task_joint(t).is_some_and(on_forearm))
        .cloned()
        .collect();
    let has_hand_point = hand_tasks
        .iter()
        .filter_map(task_joint)
        .any(|j| j != hand && descends_from(body, j, hand));
    if !has_hand_point {
        return None;
    }
    let mut held = dofs_where(body, on_forearm);
    held.extend(elbow_hinge(body, hand));
    Some((hand_tasks, held))
}

/// The whole problem's levels at `posture`, without a step (`whole`: a solver of no
/// iterations), as one solve of `iterations` ending with `status` would report them.
fn report_at(
    mut whole: stance_ik::Solver,
    body: &Skeleton,
    tasks: &[Task],
    posture: &Posture,
    iterations: usize,
    status: SolveStatus,
) -> Result<SolveReport, LiftError> {
    let mut at_end = posture.clone();
    let mut report = whole
        .solve(body, tasks, &mut at_end)
        .map_err(|e| LiftError::Problem(e.to_string()))?;
    report.iterations = iterations;
    if report.status != SolveStatus::Converged {
        report.status = status;
    }
    Ok(report)
}

/// Each limb of `limbs` (arms and legs, [`crate::place::LIMBS`]) solved alone from `start`:
/// the tasks from its upper joint down (an arm's elbow, wrist and hand keypoints; a leg's
/// knee and ankle keypoints and its ankle on the floor) on the DOF from its upper joint down,
/// everything else held, at most `max_iterations` each. What the stages leave off where a
/// hand needs its elbow moved (the hand stage holds its hinge), and where a nearly straight
/// knee stalls the body stage (its 38 rows, the torso's among them, move the leg no further
/// while the leg alone, 5 rows on about 10 DOF, meets its rays within a few iterations), at
/// a fraction of the whole problem's cost (an arm: about 45 rows on 30 DOF against 118 on
/// 132).
pub(crate) fn solve_limbs(
    skeleton: &Skeleton,
    document: &Document,
    start: &Posture,
    limbs: &[&crate::place::LimbKeypoints],
    max_iterations: usize,
    tolerance: f64,
) -> Result<(Posture, SolveReport), LiftError> {
    let problem = problem_from(skeleton, document, start)?;
    let body = &problem.skeleton;
    let settings = stage_settings(&problem, max_iterations, tolerance);
    let tasks = without_comfort(&problem);
    let mut posture = start.clone();
    let (mut iterations, mut status) = (0, SolveStatus::Converged);
    let uppers = limbs
        .iter()
        .filter_map(|limb| body.joint_index(limb.joints[0]));
    for upper in uppers {
        let on_limb = |j: usize| descends_from(body, j, upper);
        let limb_tasks: Vec<Task> = tasks
            .iter()
            .filter(|t| task_joint(t).is_some_and(on_limb))
            .cloned()
            .collect();
        let mut solver = problem
            .solver(settings)
            .map_err(|e| LiftError::Problem(e.to_string()))?;
        solver.set_locked_dofs(&dofs_where(body, on_limb));
        let report = solver
            .solve(body, &limb_tasks, &mut posture)
            .map_err(|e| LiftError::Problem(e.to_string()))?;
        iterations += report.iterations;
        if status == SolveStatus::Converged {
            status = report.status;
        }
    }
    let whole = problem
        .solver(SolverSettings {
            max_iterations: 0,
            ..settings
        })
        .map_err(|e| LiftError::Problem(e.to_string()))?;
    let report = report_at(whole, body, &tasks, &posture, iterations, status)?;
    Ok((posture, report))
}

/// `document`'s tasks but comfort solved from `start` as one problem (every DOF, every
/// keypoint together) for at most `max_iterations`, as the solver's defaults have it: its
/// restarts of a stalled solve and its longer stall window (the lift before the stages; slow,
/// the last resort for a start that led astray).
pub(crate) fn solve_whole(
    skeleton: &Skeleton,
    document: &Document,
    start: &Posture,
    max_iterations: usize,
    tolerance: f64,
) -> Result<(Posture, SolveReport), LiftError> {
    let problem = problem_from(skeleton, document, start)?;
    let mut solver = problem
        .solver(SolverSettings {
            max_iterations,
            tolerance,
            ..problem.settings
        })
        .map_err(|e| LiftError::Problem(e.to_string()))?;
    let tasks = without_comfort(&problem);
    let mut posture = start.clone();
    let report = solver
        .solve(&problem.skeleton, &tasks, &mut posture)
        .map_err(|e| LiftError::Problem(e.to_string()))?;
    Ok((posture, report))
}
