//! Shared helpers of the stance_ik tests: random trees and tasks (seeded), finite
//! differences, and the naive augmented-projector oracle of [SIC 91].

#![allow(dead_code)]
// Test-support code (not itself a #[test]): panicking on broken fixtures is what we want.
#![allow(clippy::expect_used, clippy::unwrap_used, clippy::panic)]

use glam::{DQuat, DVec3};
use nalgebra::{DMatrix, DVector};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use stance_ik::{
    Axes, Damping, Dof, Frames, JointDef, LevelSystem, Posture, Skeleton, StepParams, Task,
    TaskFeature,
};

pub fn rng(seed: u64) -> StdRng {
    StdRng::seed_from_u64(seed)
}

pub fn uniform(rng: &mut StdRng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.random::<f64>()
}

pub fn vec3(rng: &mut StdRng, r: f64) -> DVec3 {
    DVec3::new(
        uniform(rng, -r, r),
        uniform(rng, -r, r),
        uniform(rng, -r, r),
    )
}

/// A random tree: a root with 6 DOF (or fewer), `joints - 1` more joints with 0..3 rotational
/// DOF, random offsets (some zero-length), optional limits and masses.
pub fn random_skeleton(rng: &mut StdRng, joints: usize, limits: bool) -> Skeleton {
    let mut defs = Vec::new();
    let root_dofs: Vec<Dof> = if rng.random::<f64>() < 0.7 {
        Dof::ALL.to_vec()
    } else {
        vec![Dof::Rx, Dof::Ry, Dof::Rz]
    };
    defs.push(JointDef::new("j0", None, vec3(rng, 1.0), &root_dofs).with_mass(1.0, vec3(rng, 0.1)));
    for i in 1..joints {
        let parent = rng.random_range(0..i);
        let offset = if rng.random::<f64>() < 0.1 {
            DVec3::ZERO
        } else {
            vec3(rng, 0.4)
        };
        let mut dofs = Vec::new();
        for d in [Dof::Rx, Dof::Ry, Dof::Rz] {
            if rng.random::<f64>() < 0.6 {
                dofs.push(d);
            }
        }
        let mut def = JointDef::new(format!("j{i}"), Some(&format!("j{parent}")), offset, &dofs)
            .with_mass(uniform(rng, 0.0, 3.0), vec3(rng, 0.2));
        if limits {
            for &d in &dofs {
                if rng.random::<f64>() < 0.7 {
                    let lo = uniform(rng, -1.5, -0.05);
                    let hi = uniform(rng, 0.05, 1.5);
                    def = def.with_limit(d, lo, hi);
                }
            }
        }
        defs.push(def);
    }
    Skeleton::new(defs).expect("random skeleton is valid")
}

/// A random posture inside the limits.
pub fn random_posture(rng: &mut StdRng, skeleton: &Skeleton, amplitude: f64) -> Posture {
    let (lo, hi) = (skeleton.lower_limits(), skeleton.upper_limits());
    let values = (0..skeleton.dof_count())
        .map(|i| uniform(rng, -amplitude, amplitude).clamp(lo[i], hi[i]))
        .collect();
    Posture::from_values(skeleton, values).expect("posture fits")
}

pub fn random_axes(rng: &mut StdRng) -> Axes {
    loop {
        let a = Axes::new(rng.random(), rng.random(), rng.random());
        if a.count() > 0 {
            return a;
        }
    }
}

/// One random task of any kind.
pub fn random_task(rng: &mut StdRng, skeleton: &Skeleton, level: u32) -> Task {
    let j = rng.random_range(0..skeleton.joint_count());
    let task = match rng.random_range(0..13) {
        0..=4 => Task::position(j, vec3(rng, 0.2), vec3(rng, 1.5)).with_axes(random_axes(rng)),
        5 => {
            let axis = vec3(rng, 1.0).normalize_or(DVec3::Z);
            Task::orientation(j, DQuat::from_axis_angle(axis, uniform(rng, -2.0, 2.0)))
        }
        6 | 7 => {
            let mut t = Task::gaze(j, vec3(rng, 1.0).normalize_or(DVec3::Z), vec3(rng, 3.0));
            if let stance_ik::TaskKind::Gaze { effector, .. } = &mut t.kind {
                effector.point = vec3(rng, 0.1);
            }
            t
        }
        8 => Task::center_of_mass(random_axes(rng), vec3(rng, 1.0)),
        9 | 10 => Task::direction(
            j,
            vec3(rng, 1.0).normalize_or(DVec3::Y),
            vec3(rng, 1.0).normalize_or(DVec3::Y),
        ),
        11 => {
            // 1 to 5 contact points on random segments; a margin up to 5 cm.
            let count = rng.random_range(1..6);
            let support = (0..count)
                .map(|_| stance_ik::Effector {
                    joint: rng.random_range(0..skeleton.joint_count()),
                    point: vec3(rng, 0.3),
                })
                .collect();
            Task::balance(support, uniform(rng, 0.0, 0.05))
        }
        _ => {
            let n = skeleton.dof_count();
            let dofs: Vec<usize> = (0..n).filter(|_| rng.random::<f64>() < 0.5).collect();
            let reference = (0..n).map(|_| uniform(rng, -0.5, 0.5)).collect();
            Task::posture(reference, dofs)
        }
    };
    task.at_level(level).with_weight(uniform(rng, 0.2, 2.0))
}

/// Jacobian of one task by central finite differences (columns per DOF), `rows x N`.
pub fn finite_difference_jacobian(
    skeleton: &Skeleton,
    posture: &Posture,
    task: &Task,
) -> DMatrix<f64> {
    let n = skeleton.dof_count();
    let h = 1e-6;
    let rows = task.rows();
    let mut jac = DMatrix::zeros(rows, n);
    for d in 0..n {
        let mut plus = posture.clone();
        plus.values_mut()[d] += h;
        let mut minus = posture.clone();
        minus.values_mut()[d] -= h;
        let fp = Frames::new(skeleton, &plus);
        let fm = Frames::new(skeleton, &minus);
        match (
            task.feature(skeleton, &fp, plus.values()),
            task.feature(skeleton, &fm, minus.values()),
        ) {
            (TaskFeature::Vector(a), TaskFeature::Vector(b)) => {
                for r in 0..rows {
                    jac[(r, d)] = (a[r] - b[r]) / (2.0 * h);
                }
            }
            (TaskFeature::Rotation(a), TaskFeature::Rotation(b)) => {
                let q = a * b.inverse();
                let q = if q.w < 0.0 { -q } else { q };
                let w = q.to_scaled_axis() / (2.0 * h);
                for r in 0..3 {
                    jac[(r, d)] = w[r];
                }
            }
            _ => panic!("feature kind changed"),
        }
    }
    jac
}

/// One-sided Jacobi SVD (Hestenes) of a tall matrix: `a = U diag(s) V^T`. Slow and very
/// accurate, which is what an oracle needs (nalgebra's SVD was seen to lose accuracy on
/// rank-deficient matrices).
pub fn jacobi_svd(a: &DMatrix<f64>) -> (DMatrix<f64>, Vec<f64>, DMatrix<f64>) {
    let n = a.ncols();
    let mut u = a.clone();
    let mut v = DMatrix::<f64>::identity(n, n);
    for _sweep in 0..100 {
        let mut rotated = false;
        for p in 0..n {
            for q in p + 1..n {
                let (mut alpha, mut beta, mut gamma) = (0.0, 0.0, 0.0);
                for (x, y) in u.column(p).iter().zip(u.column(q).iter()) {
                    alpha += x * x;
                    beta += y * y;
                    gamma += x * y;
                }
                if gamma.abs() <= 1e-300 || gamma.abs() <= f64::EPSILON * (alpha * beta).sqrt() {
                    continue;
                }
                rotated = true;
                let zeta = (beta - alpha) / (2.0 * gamma);
                let t = zeta.signum() / (zeta.abs() + (1.0 + zeta * zeta).sqrt());
                let t = if zeta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (1.0 + t * t).sqrt();
                let s = c * t;
                for m in [&mut u, &mut v] {
                    for r in 0..m.nrows() {
                        let (x, y) = (m[(r, p)], m[(r, q)]);
                        m[(r, p)] = c * x - s * y;
                        m[(r, q)] = s * x + c * y;
                    }
                }
            }
        }
        if !rotated {
            break;
        }
    }
    let s: Vec<f64> = (0..n).map(|i| u.column(i).norm()).collect();
    for (i, &si) in s.iter().enumerate() {
        if si > 0.0 {
            let mut col = u.column_mut(i);
            col /= si;
        }
    }
    (u, s, v)
}

/// `sum f(sigma_i) v_i u_i^T` over the singular values above `rel_tol * scale`.
fn filtered_pinv(
    a: &DMatrix<f64>,
    rel_tol: f64,
    scale: f64,
    f: impl Fn(f64) -> f64,
) -> DMatrix<f64> {
    let wide = a.nrows() < a.ncols();
    let tall = if wide { a.transpose() } else { a.clone() };
    let (u, s, v) = jacobi_svd(&tall);
    // tall = U S V^T; pinv(tall) = V f(S) U^T; pinv(a) = pinv(tall)^T when wide.
    let mut out = DMatrix::zeros(tall.ncols(), tall.nrows());
    for (i, &si) in s.iter().enumerate() {
        if si > rel_tol * scale {
            out += v.column(i) * u.column(i).transpose() * f(si);
        }
    }
    if wide { out.transpose() } else { out }
}

/// Moore-Penrose pseudo-inverse with a relative rank threshold.
pub fn pinv(a: &DMatrix<f64>, rel_tol: f64, scale: f64) -> DMatrix<f64> {
    filtered_pinv(a, rel_tol, scale, |s| 1.0 / s)
}

/// Damped pseudo-inverse (Annex I) with the same rank threshold.
pub fn damped_pinv(a: &DMatrix<f64>, lambda: f64, rel_tol: f64, scale: f64) -> DMatrix<f64> {
    filtered_pinv(a, rel_tol, scale, |s| s / (s * s + lambda * lambda))
}

/// The naive [SIC 91] form: `P_k = I - (J_k^A)^+ J_k^A` from the stacked Jacobian, O(p^2).
/// Returns the step and the projectors after each level.
pub fn naive_step(
    levels: &[LevelSystem],
    n: usize,
    lambda: f64,
    rel_tol: f64,
) -> (DVector<f64>, Vec<DMatrix<f64>>) {
    let mut dtheta = DVector::zeros(n);
    let mut p = DMatrix::identity(n, n);
    let mut stacked: Vec<DMatrix<f64>> = Vec::new();
    let mut projectors = Vec::new();
    for level in levels {
        let j = level.jacobian_t.transpose();
        let scale = (0..j.nrows()).map(|r| j.row(r).norm()).fold(0.0, f64::max);
        let jh = &j * &p;
        let e = &level.dx - &j * &dtheta;
        dtheta += damped_pinv(&jh, lambda, rel_tol, scale) * e;
        stacked.push(j);
        let rows: usize = stacked.iter().map(|m| m.nrows()).sum();
        let mut ja = DMatrix::zeros(rows, n);
        let mut r0 = 0;
        for m in &stacked {
            ja.rows_mut(r0, m.nrows()).copy_from(m);
            r0 += m.nrows();
        }
        let scale_a = (0..ja.nrows())
            .map(|r| ja.row(r).norm())
            .fold(0.0, f64::max);
        p = DMatrix::identity(n, n) - pinv(&ja, rel_tol, scale_a) * &ja;
        projectors.push(p.clone());
    }
    (dtheta, projectors)
}

/// Step parameters without the per-level step scaling (for exact comparisons).
pub fn exact_params(lambda: f64) -> StepParams {
    StepParams {
        damping: Damping::Constant { lambda },
        rank_tolerance: 1e-9,
        max_dof_step: f64::INFINITY,
    }
}

/// The active tasks with rows, grouped by priority level, highest first.
pub fn tasks_by_level(tasks: &[Task]) -> Vec<Vec<&Task>> {
    let active = || tasks.iter().filter(|t| t.active && t.rows() > 0);
    let mut levels: Vec<u32> = active().map(|t| t.level).collect();
    levels.sort_unstable();
    levels.dedup();
    levels
        .iter()
        .map(|&l| active().filter(|t| t.level == l).collect())
        .collect()
}

/// Residual norm per priority level (posture attraction included), in level order.
pub fn level_residuals(skeleton: &Skeleton, tasks: &[Task], posture: &Posture) -> Vec<f64> {
    let frames = Frames::new(skeleton, posture);
    tasks_by_level(tasks)
        .iter()
        .map(|level| {
            level
                .iter()
                .map(|t| t.residual(skeleton, &frames, posture.values()).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .collect()
}

/// The textbook recursion as a whole solver (the oracle of the convergence suites): per
/// iteration each level's error clamped per task (0.1 m / 0.3 rad, through the solver's
/// `linear_systems`, whatever the solver's default step limits), `dtheta_k = dtheta_{k-1} + (J_k P_{k-1})^{+lambda} (dx_k - J_k
/// dtheta_{k-1})`, `P_k = P_{k-1} - Jh_k^+ Jh_k` (undamped, rank-decided), all with explicit
/// `N x N` matrices and a Jacobi SVD; joint limits by the textbook clamping loop (a DOF that
/// would leave its range is put on the bound, its column removed, its move subtracted from
/// every level's error, and the step recomputed); `theta += dtheta`. No line search, no
/// cascade, no budget. Stops when every level is met (1e-6), at a fixed point (no DOF moves by
/// 1e-12) or after `iterations`. Returns the
/// final posture and the iterations taken.
pub fn plain_recursion(
    skeleton: &Skeleton,
    tasks: &[Task],
    start: &Posture,
    iterations: usize,
) -> (Posture, usize) {
    let n = skeleton.dof_count();
    let (lo, hi) = (skeleton.lower_limits(), skeleton.upper_limits());
    let mut posture = start.clone();
    // The oracle's own clamp (the textbook's 0.1 m / 0.3 rad), whatever the solver's defaults.
    let mut solver = stance_ik::Solver::new(stance_ik::SolverSettings {
        max_linear_step: stance_ik::TEXTBOOK_LINEAR_STEP,
        max_angular_step: stance_ik::TEXTBOOK_ANGULAR_STEP,
        ..Default::default()
    })
    .expect("valid settings");
    let posture_only: Vec<bool> = tasks_by_level(tasks)
        .iter()
        .map(|level| level.iter().all(|t| t.is_posture()))
        .collect();
    for it in 0..iterations {
        let res = level_residuals(skeleton, tasks, &posture);
        if res.iter().zip(&posture_only).all(|(&r, &p)| p || r <= 1e-6) {
            return (posture, it);
        }
        let systems = solver
            .linear_systems(skeleton, tasks, &posture)
            .expect("valid problem");
        let values = posture.values().to_vec();
        let mut clamped = vec![false; n];
        let mut fixed = DVector::<f64>::zeros(n);
        let mut total;
        loop {
            let mut dtheta = DVector::<f64>::zeros(n);
            let mut p = DMatrix::<f64>::identity(n, n);
            for c in 0..n {
                if clamped[c] {
                    p[(c, c)] = 0.0;
                }
            }
            for level in &systems {
                let j = level.jacobian_t.transpose();
                let scale = (0..j.nrows()).map(|r| j.row(r).norm()).fold(0.0, f64::max);
                if scale <= 0.0 {
                    continue;
                }
                // One SVD of Jh^T = U S V^T (N x m): Jh^{+lambda} = U f(S) V^T, and the
                // row space of Jh is spanned by the columns of U with s above the threshold.
                let jht = &p * &level.jacobian_t;
                let e = &level.dx - &j * (&dtheta + &fixed);
                let (u, s, v) = jacobi_svd(&jht);
                let ve = v.transpose() * e;
                for (i, &si) in s.iter().enumerate() {
                    if si > 1e-9 * scale {
                        let ui = u.column(i);
                        dtheta.axpy(ve[i] * si / (si * si + 0.002 * 0.002), &ui, 1.0);
                        // P -= u_i u_i^T, in place.
                        p.ger(-1.0, &ui, &ui, 1.0);
                    }
                }
            }
            total = dtheta + &fixed;
            let mut new_clamp = false;
            for i in 0..n {
                if clamped[i] {
                    continue;
                }
                let next = values[i] + total[i];
                if next > hi[i] || next < lo[i] {
                    clamped[i] = true;
                    fixed[i] = next.clamp(lo[i], hi[i]) - values[i];
                    new_clamp = true;
                }
            }
            if !new_clamp {
                break;
            }
        }
        let mut moved: f64 = 0.0;
        for i in 0..n {
            let next = (values[i] + total[i]).clamp(lo[i], hi[i]);
            moved = moved.max((next - values[i]).abs());
            posture.values_mut()[i] = next;
        }
        if moved < 1e-12 {
            // A fixed point: every further iteration would leave the posture as it is.
            return (posture, it + 1);
        }
    }
    (posture, iterations)
}
