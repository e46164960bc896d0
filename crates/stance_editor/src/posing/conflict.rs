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
//! joint limits stop the task).

use stance_ik::{Posture, Skeleton, Solver, Task};

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
pub(crate) enum Unmet {
    /// It gave way to these higher tasks (indices into the list given to [`diagnose`]).
    Conflicts(Vec<usize>),
    /// DOF of its chain sit at their limits, in the way.
    JointLimits,
    /// Nothing above is in the way: the goal cannot be reached from where the body stands.
    OutOfReach,
}

/// One task linearised on its own: the rows of its Jacobian and its desired change.
struct Linear {
    rows: Vec<Vec<f64>>,
    desired: Vec<f64>,
    support: Vec<usize>,
}

fn linearise(skeleton: &Skeleton, posture: &Posture, task: &Task) -> Option<Linear> {
    let mut single = task.clone();
    single.level = 1;
    single.weight = 1.0;
    single.active = true;
    let support = single.support(skeleton);
    let systems = Solver::default()
        .linear_systems(skeleton, std::slice::from_ref(&single), posture)
        .ok()?;
    let system = systems.into_iter().next()?;
    let rows = (0..system.jacobian_t.ncols())
        .map(|row| system.jacobian_t.column(row).iter().copied().collect())
        .collect();
    Some(Linear {
        rows,
        desired: system.dx.iter().copied().collect(),
        support,
    })
}

fn norm(values: &[f64]) -> f64 {
    values.iter().map(|v| v * v).sum::<f64>().sqrt()
}

/// Solves the small dense system `a x = b` (Gaussian elimination with partial pivoting).
fn solve_small(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Option<Vec<f64>> {
    let n = b.len();
    for column in 0..n {
        let pivot =
            (column..n).max_by(|&i, &j| a[i][column].abs().total_cmp(&a[j][column].abs()))?;
        if a[pivot][column].abs() < 1e-300 {
            return None;
        }
        a.swap(column, pivot);
        b.swap(column, pivot);
        for row in column + 1..n {
            let factor = a[row][column] / a[column][column];
            for k in column..n {
                a[row][k] -= factor * a[column][k];
            }
            b[row] -= factor * b[column];
        }
    }
    let mut x = vec![0.0; n];
    for row in (0..n).rev() {
        let tail: f64 = (row + 1..n).map(|k| a[row][k] * x[k]).sum();
        x[row] = (b[row] - tail) / a[row][row];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Damped least-squares motion `dq = S^2 J^T (J S^2 J^T + damping^2 I)^-1 e` over the DOF with
/// a non-zero `scale` (S = diag(scale)).
fn motion(linear: &Linear, scale: &[f64]) -> Option<Vec<f64>> {
    let m = linear.rows.len();
    let gram: Vec<Vec<f64>> = (0..m)
        .map(|i| {
            (0..m)
                .map(|j| {
                    let dot: f64 = linear.rows[i]
                        .iter()
                        .zip(&linear.rows[j])
                        .zip(scale)
                        .map(|((a, b), s)| a * b * s * s)
                        .sum();
                    if i == j { dot + DAMPING * DAMPING } else { dot }
                })
                .collect()
        })
        .collect();
    let y = solve_small(gram, linear.desired.clone())?;
    Some(
        (0..scale.len())
            .map(|dof| {
                let s2 = scale[dof] * scale[dof];
                if s2 == 0.0 {
                    return 0.0;
                }
                s2 * (0..m).map(|i| linear.rows[i][dof] * y[i]).sum::<f64>()
            })
            .collect(),
    )
}

/// The rows with each column `j` multiplied by `scale[j]`.
fn scaled(rows: &[Vec<f64>], scale: &[f64]) -> Vec<Vec<f64>> {
    rows.iter()
        .map(|row| row.iter().zip(scale).map(|(a, s)| a * s).collect())
        .collect()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// `a b^T` for row lists.
fn outer(a: &[Vec<f64>], b: &[Vec<f64>]) -> Vec<Vec<f64>> {
    a.iter()
        .map(|row_a| b.iter().map(|row_b| dot(row_a, row_b)).collect())
        .collect()
}

/// The fraction of `desired` that the damped least-squares motion along `rows` makes.
fn achieved(rows: &[Vec<f64>], desired: &[f64], wanted: f64) -> f64 {
    let mut gram = outer(rows, rows);
    for (i, row) in gram.iter_mut().enumerate() {
        row[i] += DAMPING * DAMPING;
    }
    let Some(y) = solve_small(gram, desired.to_vec()) else {
        return 0.0;
    };
    // J J^T y = desired - damping^2 y.
    let made: Vec<f64> = desired
        .iter()
        .zip(&y)
        .map(|(d, y)| d - DAMPING * DAMPING * y)
        .collect();
    norm(&made) / wanted
}

/// The rows restricted to motions that leave `constraint` unchanged:
/// `A - A B^T (B B^T)^-1 B` (slightly regularised for rank-deficient `B`).
fn without_moving(rows: &[Vec<f64>], constraint: &[Vec<f64>]) -> Option<Vec<Vec<f64>>> {
    let mut gram = outer(constraint, constraint);
    let size = gram.iter().enumerate().map(|(i, row)| row[i]).sum::<f64>();
    for (i, row) in gram.iter_mut().enumerate() {
        row[i] += 1e-9 * size.max(1e-12);
    }
    let cross = outer(rows, constraint);
    rows.iter()
        .zip(&cross)
        .map(|(row, cross_row)| {
            // Coefficients c = (B B^T)^-1 B a for this row a.
            let c = solve_small(gram.clone(), cross_row.clone())?;
            Some(
                (0..row.len())
                    .map(|j| {
                        row[j]
                            - c.iter()
                                .zip(constraint)
                                .map(|(ci, b)| ci * b[j])
                                .sum::<f64>()
                    })
                    .collect(),
            )
        })
        .collect()
}

/// Why `low` (unmet at `posture`) is not met, given the active higher-priority tasks.
///
/// Each higher task is tried on its own as a constraint: it is in the way when holding it
/// takes away a good part of the progress the unmet task could make (`LOSS_RATIO`). Tasks that
/// only block together (the feet and the balance holding the body where it stands) are not
/// named: the goal is then out of reach from there.
pub(crate) fn diagnose(
    skeleton: &Skeleton,
    posture: &Posture,
    low: &Task,
    higher: &[Task],
) -> Unmet {
    let Some(linear) = linearise(skeleton, posture, low) else {
        return Unmet::OutOfReach;
    };
    let wanted = norm(&linear.desired);
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
        .any(|&dof| !root[dof] && linear.rows.iter().any(|row| row[dof] != 0.0));
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
    let free = motion(&linear, &scale).unwrap_or_else(|| vec![0.0; n]);
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
        let others: Vec<(usize, Vec<Vec<f64>>)> = higher
            .iter()
            .enumerate()
            .filter(|(_, task)| !task.is_posture())
            .filter_map(|(index, task)| {
                let other = linearise(skeleton, posture, task)?;
                Some((index, scaled(&other.rows, &holding_scale)))
            })
            .collect();
        // What is left of the progress while these higher tasks hold.
        let left_holding = |held: &mut dyn Iterator<Item = &Vec<Vec<f64>>>| {
            let constraint: Vec<Vec<f64>> = held.flatten().cloned().collect();
            if constraint.is_empty() {
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
