//! Why a task is not met: which higher-priority tasks really stand in its way.
//!
//! At the settled posture, each task is linearised on its own with stance_ik's
//! `Solver::linear_systems` (`J`, desired change `e`). The unmet task's progress is the part
//! of `e` that a damped least-squares motion of the body's own joints makes (the free-floating
//! root only for tasks nothing else moves; DOF at a limit that the motion pushes against are
//! left out). A higher task is in the way when the motions that leave it unchanged
//! (`J_low (I - J_high^+ J_high)`) make clearly less progress: it takes away a good part of
//! what the unmet task could do. Higher tasks that only block together (both feet holding the
//! pelvis up) are named when releasing one of them gives progress back. When no progress is
//! possible to begin with, or nothing above takes it away, the goal is out of reach (or the
//! joint limits stop the task). A collision task above holds the contacts it keeps at the
//! posture (a hand stopped against the chest gives way to it).

use nalgebra::{DMatrix, DVector};

use crate::{Frames, Posture, Skeleton, Solver, Task, TaskKind};

/// A higher task is named when holding it takes away at least this fraction of the progress
/// the unmet task could make.
const LOSS_RATIO: f64 = 0.3;
/// Below this fraction of its desired change, a task cannot even start toward its goal.
const MIN_PROGRESS: f64 = 0.1;
/// Damping of the least-squares motion (m or rad): directions the joints barely move the
/// task along do not count as motion.
const DAMPING: f64 = 0.05;
/// A DOF this close to a limit sits at it (rad or m).
const AT_LIMIT: f64 = 1e-6;
/// The limits stop the task when they take away at least this fraction of what it could do.
const LIMITS_TAKE: f64 = 0.5;

/// Why an unmet task is not met.
#[derive(Debug, Clone, PartialEq)]
pub enum Unmet {
    /// It gave way to these higher tasks (indices into the list given to [`diagnose`]).
    Conflicts(Vec<usize>),
    /// DOF of its chain sit at their limits, in the way.
    JointLimits,
    /// Nothing above is in the way: the goal cannot be reached from where the body stands.
    OutOfReach,
}

/// One task linearised on its own: its Jacobian (`m x N`) and its desired change.
struct Linear {
    rows: DMatrix<f64>,
    desired: DVector<f64>,
    support: Vec<usize>,
}

fn linearise(skeleton: &Skeleton, posture: &Posture, task: &Task) -> Option<Linear> {
    if let TaskKind::Collision(c) = &task.kind {
        // The contacts it holds at the posture (within the margin and the band), a row each:
        // the solver's level stops their surfaces meeting, which holding them here stands for
        // (at a settled posture the level itself has rows only for the pairs inside the
        // margin). What a higher task asks for is not used.
        let frames = Frames::new(skeleton, posture);
        let held = c.contacts(&frames).len();
        let n = skeleton.dof_count();
        let mut jt = vec![0.0; n * task.rows()];
        let support = task.support(skeleton);
        task.jacobian_t(skeleton, &frames, posture.values(), &support, &mut jt, n);
        jt.truncate(held * n);
        return Some(Linear {
            rows: DMatrix::from_vec(n, held, jt).transpose(),
            desired: DVector::zeros(held),
            support,
        });
    }
    let mut single = task.clone();
    single.level = 1;
    single.weight = 1.0;
    single.active = true;
    let support = single.support(skeleton);
    let systems = Solver::default()
        .linear_systems(skeleton, std::slice::from_ref(&single), posture)
        .ok()?;
    let system = systems.into_iter().next()?;
    Some(Linear {
        rows: system.jacobian_t.transpose(),
        desired: system.dx,
        support,
    })
}

/// `gram x = b` for a symmetric positive definite `gram` (Cholesky; LU when rounding makes it
/// indefinite). `None` when singular or not finite.
fn solve_gram(gram: DMatrix<f64>, b: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let x = match gram.clone().cholesky() {
        Some(cholesky) => cholesky.solve(b),
        None => gram.lu().solve(b)?,
    };
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// `rows rows^T + damping^2 I`.
fn damped_gram(rows: &DMatrix<f64>) -> DMatrix<f64> {
    let mut gram = rows * rows.transpose();
    for i in 0..gram.nrows() {
        gram[(i, i)] += DAMPING * DAMPING;
    }
    gram
}

/// Damped least-squares motion `dq = S^2 J^T (J S^2 J^T + damping^2 I)^-1 e` over the DOF with
/// a non-zero `scale` (S = diag(scale)).
fn motion(linear: &Linear, scale: &[f64]) -> Option<DVector<f64>> {
    let scaled_rows = scaled(&linear.rows, scale);
    let y = solve_gram(
        damped_gram(&scaled_rows),
        &DMatrix::from_column_slice(linear.desired.len(), 1, linear.desired.as_slice()),
    )?;
    let mut dq = scaled_rows.transpose() * y.column(0);
    for (value, s) in dq.iter_mut().zip(scale) {
        *value *= s;
    }
    Some(dq)
}

/// The rows with each column `j` multiplied by `scale[j]`.
fn scaled(rows: &DMatrix<f64>, scale: &[f64]) -> DMatrix<f64> {
    let mut out = rows.clone();
    for (mut column, s) in out.column_iter_mut().zip(scale) {
        column *= *s;
    }
    out
}

/// The fraction of `desired` that the damped least-squares motion along `rows` makes.
fn achieved(rows: &DMatrix<f64>, desired: &DVector<f64>, wanted: f64) -> f64 {
    let b = DMatrix::from_column_slice(desired.len(), 1, desired.as_slice());
    let Some(y) = solve_gram(damped_gram(rows), &b) else {
        return 0.0;
    };
    // J J^T y = desired - damping^2 y.
    let made = desired - y.column(0) * (DAMPING * DAMPING);
    made.norm() / wanted
}

/// The rows restricted to motions that leave `constraint` unchanged:
/// `A - A B^T (B B^T)^-1 B` (slightly regularised for rank-deficient `B`).
fn without_moving(rows: &DMatrix<f64>, constraint: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let mut gram = constraint * constraint.transpose();
    let size = gram.trace();
    for i in 0..gram.nrows() {
        gram[(i, i)] += 1e-9 * size.max(1e-12);
    }
    // C^T = (B B^T)^-1 B A^T.
    let coefficients_t = solve_gram(gram, &(constraint * rows.transpose()))?;
    Some(rows - coefficients_t.transpose() * constraint)
}

/// The rows of several linearised tasks, stacked.
fn stacked<'a>(parts: impl Iterator<Item = &'a DMatrix<f64>>, columns: usize) -> DMatrix<f64> {
    let parts: Vec<&DMatrix<f64>> = parts.collect();
    let total = parts.iter().map(|part| part.nrows()).sum();
    let mut out = DMatrix::zeros(total, columns);
    let mut row = 0;
    for part in parts {
        out.rows_mut(row, part.nrows()).copy_from(part);
        row += part.nrows();
    }
    out
}

/// Why `low` (unmet at `posture`) is not met, given the active higher-priority tasks.
///
/// Each higher task is tried on its own as a constraint: it is in the way when holding it
/// takes away a good part of the progress the unmet task could make (`LOSS_RATIO`). Tasks that
/// only block together (the feet and the balance holding the body where it stands) are not
/// named: the goal is then out of reach from there.
pub fn diagnose(skeleton: &Skeleton, posture: &Posture, low: &Task, higher: &[Task]) -> Unmet {
    let Some(linear) = linearise(skeleton, posture, low) else {
        return Unmet::OutOfReach;
    };
    let wanted = linear.desired.norm();
    if wanted <= 0.0 || !wanted.is_finite() {
        return Unmet::OutOfReach;
    }
    let n = skeleton.dof_count();
    let root: Vec<bool> = (0..n)
        .map(|dof| {
            skeleton
                .joints()
                .get(skeleton.dof_joint(dof))
                .is_some_and(|joint| joint.parent.is_none())
        })
        .collect();
    // The body's own joints move the task; the free-floating root only when nothing else does
    // (a task on the pelvis itself).
    let body_moves_it = linear
        .support
        .iter()
        .any(|&dof| !root[dof] && linear.rows.column(dof).iter().any(|value| *value != 0.0));
    let mut scale: Vec<f64> = (0..n)
        .map(|dof| if root[dof] && body_moves_it { 0.0 } else { 1.0 })
        .collect();
    let could = achieved(&scaled(&linear.rows, &scale), &linear.desired, wanted);
    if could < MIN_PROGRESS {
        // Not even the first step toward the goal is possible: the limb is stretched out.
        return Unmet::OutOfReach;
    }
    // DOF at a limit that the motion pushes further are out. Those at a limit that the motion
    // does not move away from cannot help to hold a higher task either (which way they would
    // have to go is not known): they are out of that test.
    let free = motion(&linear, &scale).unwrap_or_else(|| DVector::zeros(n));
    let largest = free.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
    let values = posture.values();
    let (lower, upper) = (skeleton.lower_limits(), skeleton.upper_limits());
    let mut blocked = false;
    let mut holding_scale = scale.clone();
    for dof in 0..n {
        let (Some(&value), Some(&low_limit), Some(&high_limit), Some(&push)) = (
            values.get(dof),
            lower.get(dof),
            upper.get(dof),
            free.get(dof),
        ) else {
            continue;
        };
        if low_limit > high_limit {
            continue;
        }
        let at_low = value <= low_limit + AT_LIMIT;
        let at_high = value >= high_limit - AT_LIMIT;
        let pushes = push.abs() > 1e-3 * largest;
        let outward = pushes && ((push < 0.0 && at_low) || (push > 0.0 && at_high));
        let inward = pushes && ((push > 0.0 && at_low) || (push < 0.0 && at_high));
        if outward && scale[dof] != 0.0 {
            scale[dof] = 0.0;
            blocked = true;
        }
        if (at_low || at_high) && !inward {
            holding_scale[dof] = 0.0;
        }
    }
    let rows = scaled(&linear.rows, &scale);
    let can = achieved(&rows, &linear.desired, wanted);
    let mut conflicts = Vec::new();
    if can >= MIN_PROGRESS {
        let own = scaled(&linear.rows, &holding_scale);
        let others: Vec<(usize, DMatrix<f64>)> = higher
            .iter()
            .enumerate()
            .filter(|(_, task)| !task.is_posture())
            .filter_map(|(index, task)| {
                let other = linearise(skeleton, posture, task)?;
                Some((index, scaled(&other.rows, &holding_scale)))
            })
            .collect();
        // What is left of the progress while these higher tasks hold.
        let left_holding = |held: &mut dyn Iterator<Item = &DMatrix<f64>>| {
            let constraint = stacked(held, n);
            if constraint.nrows() == 0 {
                return can;
            }
            without_moving(&own, &constraint)
                .map_or(can, |rows| achieved(&rows, &linear.desired, wanted))
        };
        // A higher task that on its own takes away a good part of the progress.
        for (index, rows) in &others {
            let left = left_holding(&mut std::iter::once(rows));
            if left < (1.0 - LOSS_RATIO) * can {
                conflicts.push(*index);
            }
        }
        // Tasks that only block together (both feet holding the pelvis): those whose release
        // gives a good part of the progress back.
        if conflicts.is_empty() {
            let all = left_holding(&mut others.iter().map(|(_, rows)| rows));
            if all < (1.0 - LOSS_RATIO) * can {
                for (index, _) in &others {
                    let mut rest = others
                        .iter()
                        .filter(|(other, _)| other != index)
                        .map(|(_, rows)| rows);
                    if left_holding(&mut rest) >= all + LOSS_RATIO * can {
                        conflicts.push(*index);
                    }
                }
            }
        }
    }
    if !conflicts.is_empty() {
        Unmet::Conflicts(conflicts)
    } else if blocked && can < (1.0 - LIMITS_TAKE) * could {
        Unmet::JointLimits
    } else {
        Unmet::OutOfReach
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::{Axes, Dof, Effector, JointDef, TaskKind};

    /// A planar three-link arm on a fixed base: three hinges about Z, links of 0.3 m along X.
    fn arm() -> Skeleton {
        let hinge = |name: &str, parent: Option<&str>, x: f64| {
            JointDef::new(name, parent, DVec3::new(x, 0.0, 0.0), &[Dof::Rz])
        };
        let defs = vec![
            hinge("shoulder", None, 0.0),
            hinge("elbow", Some("shoulder"), 0.3),
            hinge("wrist", Some("elbow"), 0.3),
            JointDef::new("tip", Some("wrist"), DVec3::new(0.3, 0.0, 0.0), &[]),
        ];
        let Ok(skeleton) = Skeleton::new(defs) else {
            panic!("the arm builds");
        };
        skeleton
    }

    fn position(skeleton: &Skeleton, joint: &str, target: DVec3) -> Task {
        let joint = skeleton.joint_index(joint).unwrap_or(0);
        Task::new(TaskKind::Position {
            effector: Effector {
                joint,
                point: DVec3::ZERO,
            },
            axes: Axes::XYZ,
            target,
        })
    }

    /// The arm bent at every hinge (no two links in line).
    fn bent(skeleton: &Skeleton) -> Posture {
        let mut posture = Posture::rest(skeleton);
        posture.values_mut().copy_from_slice(&[0.5, 0.5, 0.6]);
        posture
    }

    #[test]
    fn a_higher_task_holding_the_same_chain_is_named() {
        let skeleton = arm();
        let posture = bent(&skeleton);
        let frames = crate::Frames::new(&skeleton, &posture);
        let at = |name: &str| frames.joint_position[skeleton.joint_index(name).unwrap_or(0)];
        // The tip pulled toward the wrist: with the wrist held where it is, only the wrist
        // hinge moves the tip, across that direction; the higher task is in the way.
        let (wrist, tip) = (at("wrist"), at("tip"));
        let inward = position(&skeleton, "tip", tip + (wrist - tip).normalize() * 0.1);
        let hold_wrist = position(&skeleton, "wrist", wrist);
        let unmet = diagnose(
            &skeleton,
            &posture,
            &inward,
            std::slice::from_ref(&hold_wrist),
        );
        assert_eq!(unmet, Unmet::Conflicts(vec![0]));
        // Holding the elbow leaves two bent hinges to move the tip anywhere in the plane:
        // nothing above is in the way.
        let hold_elbow = position(&skeleton, "elbow", at("elbow"));
        let unmet = diagnose(&skeleton, &posture, &inward, &[hold_elbow]);
        assert!(!matches!(unmet, Unmet::Conflicts(_)), "{unmet:?}");
    }

    #[test]
    fn a_stretched_arm_cannot_reach_further_out() {
        let skeleton = arm();
        let posture = Posture::rest(&skeleton);
        let far = position(&skeleton, "tip", DVec3::new(1.5, 0.0, 0.0));
        assert_eq!(diagnose(&skeleton, &posture, &far, &[]), Unmet::OutOfReach);
    }

    #[test]
    fn a_hinge_at_its_limit_is_the_reason() {
        let defs = vec![
            JointDef::new("shoulder", None, DVec3::ZERO, &[Dof::Rz]).with_limit(Dof::Rz, 0.0, 0.0),
            JointDef::new(
                "elbow",
                Some("shoulder"),
                DVec3::new(0.3, 0.0, 0.0),
                &[Dof::Rz],
            )
            .with_limit(Dof::Rz, 0.0, 0.0),
            JointDef::new("tip", Some("elbow"), DVec3::new(0.3, 0.0, 0.0), &[]),
        ];
        let Ok(skeleton) = Skeleton::new(defs) else {
            panic!("the arm builds");
        };
        let posture = Posture::rest(&skeleton);
        let up = position(&skeleton, "tip", DVec3::new(0.5, 0.3, 0.0));
        assert_eq!(diagnose(&skeleton, &posture, &up, &[]), Unmet::JointLimits);
    }
}
