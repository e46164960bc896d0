//! The prioritized step: recursive projector == naive oracle, strict priority, joint limits,
//! robustness in degenerate cases, solver statuses.

// A test crate: on wasm32 `#[test]` becomes `wasm_bindgen_test`, which clippy does not treat
// as a test, and fixture helpers panic on broken fixtures on purpose.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use crate::common;

use std::cell::Cell;

use common::*;
use glam::DVec3;
use nalgebra::DVector;
use rand::RngExt;
use rand::rngs::StdRng;
use stance_ik::{
    Damping, Dof, Iteration, JointDef, LevelSystem, Posture, Skeleton, SolveStatus, Solver,
    SolverSettings, StepParams, StepWorkspace, Task, prioritized_step,
};

fn random_problem(seed: u64, limits: bool) -> (Skeleton, Posture, Vec<Task>) {
    let mut r = rng(seed);
    let joints = r.random_range(3..14);
    let s = random_skeleton(&mut r, joints, limits);
    let p = random_posture(&mut r, &s, 1.0);
    let levels = r.random_range(1..6);
    let count = r.random_range(1..9);
    let tasks = (0..count)
        .map(|_| {
            let level = r.random_range(1..=levels);
            random_task(&mut r, &s, level)
        })
        .collect();
    (s, p, tasks)
}

fn linearized_residual(level: &LevelSystem, dtheta: &DVector<f64>) -> f64 {
    (&level.dx - level.jacobian_t.tr_mul(dtheta)).norm()
}

#[test]
fn recursive_projector_equals_naive() {
    let mut compared = 0;
    for seed in 0..150 {
        let (s, p, tasks) = random_problem(seed, false);
        let systems = Solver::default().linear_systems(&s, &tasks, &p).unwrap();
        let n = s.dof_count();
        for lambda in [0.0, 0.05] {
            let params = exact_params(lambda);
            let mut projectors = Vec::new();
            let step = prioritized_step(
                &systems,
                n,
                &params,
                None,
                None,
                &mut StepWorkspace::default(),
                Some(&mut projectors),
            );
            let (naive, naive_p) = naive_step(&systems, n, lambda, params.rank_tolerance);
            for (k, (a, b)) in projectors.iter().zip(&naive_p).enumerate() {
                assert!(
                    (a - b).amax() < 1e-8,
                    "seed {seed}: projector {k} differs by {}",
                    (a - b).amax()
                );
                // Symmetric and idempotent.
                assert!((a - a.transpose()).amax() < 1e-12);
                assert!((a * a - a).amax() < 1e-9);
            }
            if lambda > 0.0 {
                let scale = 1.0 + naive.amax();
                assert!(
                    (&step - &naive).amax() < 1e-7 * scale,
                    "seed {seed}: steps differ\n{step}\n{naive}"
                );
            }
            compared += 1;
        }
    }
    assert_eq!(compared, 300);
}

#[test]
fn exactly_dependent_levels_give_the_naive_projector() {
    // The same task at levels 1 and 2: level 2 must get nothing and the projector must not grow.
    let (s, p, _) = random_problem(7, false);
    let j = s.joint_count() - 1;
    let t = Task::position(j, DVec3::X * 0.1, DVec3::new(0.3, 0.2, 0.1));
    let tasks = vec![t.clone(), t.at_level(2)];
    let systems = Solver::default().linear_systems(&s, &tasks, &p).unwrap();
    let mut projectors = Vec::new();
    let params = exact_params(0.01);
    prioritized_step(
        &systems,
        s.dof_count(),
        &params,
        None,
        None,
        &mut StepWorkspace::default(),
        Some(&mut projectors),
    );
    let (_, naive_p) = naive_step(&systems, s.dof_count(), 0.01, params.rank_tolerance);
    assert!((&projectors[0] - &projectors[1]).amax() < 1e-9);
    assert!((&projectors[1] - &naive_p[1]).amax() < 1e-9);
}

#[test]
fn lower_levels_never_change_a_higher_levels_achieved_residual() {
    let mut checked = 0;
    for seed in 1000..1200 {
        let (s, p, tasks) = random_problem(seed, false);
        let systems = Solver::default().linear_systems(&s, &tasks, &p).unwrap();
        let n = s.dof_count();
        for params in [
            StepParams::default(),
            StepParams {
                damping: Damping::Adaptive {
                    lambda_max: 0.1,
                    epsilon: 0.1,
                },
                ..StepParams::default()
            },
        ] {
            let mut ws = StepWorkspace::default();
            let full = prioritized_step(&systems, n, &params, None, None, &mut ws, None);
            for k in 1..systems.len() {
                let partial =
                    prioritized_step(&systems[..k], n, &params, None, None, &mut ws, None);
                for level in &systems[..k] {
                    let a = linearized_residual(level, &partial);
                    let b = linearized_residual(level, &full);
                    assert!(
                        (a - b).abs() < 1e-9,
                        "seed {seed}: level {} {a} vs {b}",
                        level.level
                    );
                    checked += 1;
                }
            }
        }
    }
    assert!(checked > 200, "{checked}");
}

#[test]
fn strict_priority_holds_through_solver_iterations() {
    // Over several iterations, with and without the lower levels: the top level's linearised
    // residual of each step is identical, whatever lower levels are added.
    for seed in 2000..2040 {
        let (s, p, mut tasks) = random_problem(seed, false);
        for t in &mut tasks {
            t.level += 1;
        }
        let mut r = rng(seed);
        let top = Task::position(s.joint_count() - 1, DVec3::ZERO, vec3(&mut r, 1.0));
        let with: Vec<Task> = std::iter::once(top.clone()).chain(tasks).collect();
        let mut solver = Solver::default();
        let mut posture = p.clone();
        for _ in 0..5 {
            let systems = solver.linear_systems(&s, &with, &posture).unwrap();
            let n = s.dof_count();
            let mut ws = StepWorkspace::default();
            let params = StepParams::default();
            let alone = prioritized_step(&systems[..1], n, &params, None, None, &mut ws, None);
            let all = prioritized_step(&systems, n, &params, None, None, &mut ws, None);
            let (a, b) = (
                linearized_residual(&systems[0], &alone),
                linearized_residual(&systems[0], &all),
            );
            assert!((a - b).abs() < 1e-9, "seed {seed}: {a} vs {b}");
            solver.iterate(&s, &with, &mut posture).unwrap();
        }
    }
}

/// Strict priority over whole solves, per residual vector: at every iteration of a solve
/// (the textbook iteration: each level's share within what the levels above left of the
/// priority budget, the whole in its trust region), the move the solver takes changes no row
/// of a higher level's linearised error compared with the step of the higher levels alone
/// (scaled by the same factor). On problems where every
/// level has work left all along (three points of one chain pulled out of reach in different
/// directions) and not vacuously: the lower levels do change the move.
#[test]
fn strict_priority_holds_per_residual_vector_over_whole_solves() {
    let mut checked = 0;
    let mut lower_levels_moved = 0;
    for seed in 2100..2130 {
        let mut r = rng(seed);
        // Two-DOF joints only: no rotation vector to re-wrap, so that the move taken is the
        // step's.
        let s = limited_chain(9, 0.2, 100.0);
        let mut posture = random_posture(&mut r, &s, 0.8);
        let far = |r: &mut StdRng| vec3(r, 1.0).normalize_or(DVec3::X) * 4.0;
        let tasks = vec![
            Task::position(9, DVec3::ZERO, far(&mut r)),
            Task::position(6, DVec3::ZERO, far(&mut r)).at_level(2),
            Task::position(3, DVec3::ZERO, far(&mut r)).at_level(3),
        ];
        let settings = SolverSettings {
            iteration: Iteration::Textbook,
            restarts: false,
            ..SolverSettings::default()
        };
        let params = StepParams {
            damping: settings.damping,
            rank_tolerance: settings.rank_tolerance,
            max_dof_step: settings.priority_budget,
        };
        let mut solver = Solver::new(settings).unwrap();
        let n = s.dof_count();
        let mut ws = StepWorkspace::default();
        for _ in 0..20 {
            let systems = solver.linear_systems(&s, &tasks, &posture).unwrap();
            assert!(systems.iter().all(|l| l.dx.norm() > 0.05), "work left");
            let before = DVector::from_column_slice(posture.values());
            solver.iterate(&s, &tasks, &mut posture).unwrap();
            let taken = DVector::from_column_slice(posture.values()) - before;
            // The trust region scales the whole step by one factor, its direction kept.
            let full = prioritized_step(&systems, n, &params, None, None, &mut ws, None);
            let scale = taken.amax() / full.amax();
            assert!(
                scale > 0.0 && scale <= 1.0 + 1e-12,
                "seed {seed}: scale {scale}"
            );
            assert!(
                (&taken - &full * scale).amax() < 1e-9,
                "seed {seed}: the move is the prioritized step, scaled"
            );
            for k in 1..systems.len() {
                let higher =
                    prioritized_step(&systems[..k], n, &params, None, None, &mut ws, None) * scale;
                for level in &systems[..k] {
                    let a = level.jacobian_t.tr_mul(&taken);
                    let b = level.jacobian_t.tr_mul(&higher);
                    let off = (&a - &b).amax();
                    assert!(
                        off < 1e-9,
                        "seed {seed}: level {} row moved by {off}",
                        level.level
                    );
                    checked += 1;
                }
                if (&taken - &higher).norm() > 1e-4 {
                    lower_levels_moved += 1;
                }
            }
        }
    }
    assert_eq!(checked, 30 * 20 * 3);
    // Not vacuous: the lower levels change the move in a good share of the 1,200 (iteration,
    // level) pairs (566 with the default priority budget; where the levels above spend all of
    // it, the lower ones wait their turn; all 1,200 with the plain recursion's unlimited budget).
    assert!(lower_levels_moved > 30 * 20 / 2, "{lower_levels_moved}");
}

#[test]
fn joint_limits_are_never_exceeded() {
    for seed in 3000..3060 {
        let (s, p, tasks) = random_problem(seed, true);
        let mut solver = Solver::new(SolverSettings {
            max_iterations: 1,
            ..Default::default()
        })
        .unwrap();
        let mut posture = p;
        let (lo, hi) = (s.lower_limits().to_vec(), s.upper_limits().to_vec());
        for _ in 0..25 {
            solver.solve(&s, &tasks, &mut posture).unwrap();
            for (i, v) in posture.values().iter().enumerate() {
                assert!(v.is_finite());
                assert!(
                    *v >= lo[i] && *v <= hi[i],
                    "seed {seed}: DOF {i} = {v} outside [{}, {}]",
                    lo[i],
                    hi[i]
                );
            }
        }
    }
}

/// A planar-ish chain of `links` links with `rx`, `rz` in `[-limit, limit]`.
fn limited_chain(links: usize, length: f64, limit: f64) -> Skeleton {
    let mut defs = vec![JointDef::new("j0", None, DVec3::ZERO, &[])];
    for i in 1..=links {
        defs.push(
            JointDef::new(
                format!("j{i}"),
                Some(&format!("j{}", i - 1)),
                if i == 1 {
                    DVec3::ZERO
                } else {
                    DVec3::Y * length
                },
                &[Dof::Rx, Dof::Rz],
            )
            .with_limit(Dof::Rx, -limit, limit)
            .with_limit(Dof::Rz, -limit, limit),
        );
    }
    defs.push(JointDef::new(
        "tip",
        Some(&format!("j{links}")),
        DVec3::Y * length,
        &[],
    ));
    Skeleton::new(defs).unwrap()
}

/// The clamping loop of [BAE 98]: a DOF that would leave its range is put on its bound, its
/// column taken out and its move subtracted from every level's error, and the step solved
/// again, so that the free DOF make up for it. One iteration from a posture near the bounds,
/// where the lower level pulls four DOF past their range: the DOF that hit their bounds sit
/// exactly on them and the top level's linearised error is still met exactly by the step
/// taken. Clamping the values after an unchanged step instead (the loop removed) leaves the
/// top level off by what the clamped DOF did not do.
#[test]
fn higher_levels_stay_exact_while_dof_sit_on_their_limits() {
    let s = limited_chain(8, 0.2, 0.35);
    let tip = s.joint_count() - 1;
    let (lo, hi) = (s.lower_limits().to_vec(), s.upper_limits().to_vec());
    let mut solver = Solver::new(SolverSettings {
        iteration: Iteration::Textbook,
        restarts: false,
        max_iterations: 1,
        damping: Damping::Constant { lambda: 0.0 },
        // The textbook's task clamps: the posture level asks 0.3 rad, so no DOF moves past
        // the trust region (whose scaling would shorten level 1's step too).
        max_linear_step: stance_ik::TEXTBOOK_LINEAR_STEP,
        max_angular_step: stance_ik::TEXTBOOK_ANGULAR_STEP,
        ..SolverSettings::default()
    })
    .unwrap();
    let mut on_bounds = 0;
    for seed in 7100..7160 {
        let mut r = rng(seed);
        // A curled chain (every DOF 0.2-0.3 rad), away from the straight singular posture.
        let curl: Vec<f64> = (0..s.dof_count())
            .map(|_| uniform(&mut r, 0.2, 0.3))
            .collect();
        let start = Posture::from_values(&s, curl).unwrap();
        let tip_now = stance_ik::Frames::new(&s, &start).point(tip, DVec3::ZERO);
        let pulled: Vec<usize> = (0..4).map(|_| r.random_range(0..s.dof_count())).collect();
        let tasks = vec![
            Task::position(tip, DVec3::ZERO, tip_now + vec3(&mut r, 0.02)),
            Task::posture(vec![0.8; s.dof_count()], pulled).at_level(2),
        ];
        let systems = solver.linear_systems(&s, &tasks, &start).unwrap();
        let mut posture = start.clone();
        solver.iterate(&s, &tasks, &mut posture).unwrap();
        let step = DVector::from_iterator(
            s.dof_count(),
            posture
                .values()
                .iter()
                .zip(start.values())
                .map(|(a, b)| a - b),
        );
        let residual = linearized_residual(&systems[0], &step);
        assert!(residual < 1e-9, "seed {seed}: level 1 off by {residual}");
        let here = posture
            .values()
            .iter()
            .enumerate()
            .filter(|&(i, v)| *v == lo[i] || *v == hi[i])
            .count();
        assert!(here > 0, "seed {seed}: no DOF reached its bound");
        on_bounds += here;
    }
    assert!(
        on_bounds >= 60,
        "{on_bounds} DOF on their bounds in 60 cases"
    );
}

fn all_finite(p: &Posture) -> bool {
    p.values().iter().all(|v| v.is_finite())
}

fn straight_chain(links: usize, length: f64) -> Skeleton {
    let mut defs = vec![JointDef::new(
        "j0",
        None,
        DVec3::ZERO,
        &[Dof::Rx, Dof::Ry, Dof::Rz],
    )];
    for i in 1..links {
        defs.push(JointDef::new(
            format!("j{i}"),
            Some(&format!("j{}", i - 1)),
            DVec3::Y * length,
            &[Dof::Rx, Dof::Rz],
        ));
    }
    Skeleton::new(defs).unwrap()
}

#[test]
fn no_nan_in_singular_unreachable_coincident_and_zero_length_cases() {
    let chain = straight_chain(4, 0.5);
    let tip = chain.joint_count() - 1;
    let zero = straight_chain(4, 0.0);
    let cases: Vec<(&str, Skeleton, Vec<Task>)> = vec![
        // Straight chain pulled along its own axis: singular Jacobian.
        (
            "singular",
            chain.clone(),
            vec![Task::position(tip, DVec3::ZERO, DVec3::Y * 1.2)],
        ),
        (
            "unreachable",
            chain.clone(),
            vec![Task::position(tip, DVec3::ZERO, DVec3::new(5.0, 9.0, -3.0))],
        ),
        // Same effector, contradictory goals at two levels, and the same goal twice.
        (
            "conflict",
            chain.clone(),
            vec![
                Task::position(tip, DVec3::ZERO, DVec3::X),
                Task::position(tip, DVec3::ZERO, -DVec3::X).at_level(2),
                Task::position(tip, DVec3::ZERO, -DVec3::X).at_level(2),
            ],
        ),
        // Goal already reached; gaze target on the eye; gaze target straight behind.
        (
            "coincident",
            chain.clone(),
            vec![
                Task::position(tip, DVec3::ZERO, DVec3::Y * 1.5),
                Task::gaze(tip, DVec3::Z, DVec3::Y * 1.5).at_level(2),
                Task::gaze(1, DVec3::Z, DVec3::new(0.0, 0.5, -3.0)).at_level(3),
            ],
        ),
        // Every segment has zero length: all Jacobian columns vanish.
        (
            "zero-length",
            zero.clone(),
            vec![
                Task::position(tip, DVec3::ZERO, DVec3::ONE),
                Task::gaze(tip, DVec3::Z, DVec3::ZERO).at_level(2),
                Task::orientation(tip, glam::DQuat::from_rotation_x(3.1)).at_level(3),
            ],
        ),
    ];
    for damping in [
        Damping::Constant { lambda: 0.0 },
        Damping::Constant { lambda: 0.01 },
        Damping::Adaptive {
            lambda_max: 0.05,
            epsilon: 0.05,
        },
    ] {
        for (name, s, tasks) in &cases {
            let mut solver = Solver::new(SolverSettings {
                damping,
                max_iterations: 60,
                ..Default::default()
            })
            .unwrap();
            let mut p = Posture::rest(s);
            let report = solver.solve(s, tasks, &mut p).unwrap();
            assert!(all_finite(&p), "{name} {damping:?}: {:?}", p.values());
            for l in &report.levels {
                assert!(l.residual_after.is_finite(), "{name}: {report:?}");
            }
        }
    }
}

#[test]
fn unreachable_goal_stops_with_the_level_that_gave_way() {
    let chain = straight_chain(4, 0.5);
    let tip = chain.joint_count() - 1;
    let tasks = vec![Task::position(tip, DVec3::ZERO, DVec3::new(3.0, 0.5, 0.0))];
    let mut p = Posture::rest(&chain);
    let settings = SolverSettings {
        max_iterations: 2000,
        ..Default::default()
    };
    let report = Solver::new(settings)
        .unwrap()
        .solve(&chain, &tasks, &mut p)
        .unwrap();
    assert_ne!(report.status, SolveStatus::Converged);
    assert_eq!(report.gave_way, Some(1));
    // Reached as close as possible: the chain is stretched toward the goal (1.5 m long).
    let residual = report.levels[0].residual_after;

    let best = DVec3::new(3.0, 0.5, 0.0).length() - 1.5;
    assert!((residual - best).abs() < 1e-2, "{residual} vs {best}");
}

#[test]
fn reachable_goal_converges_and_reports() {
    let chain = straight_chain(4, 0.5);
    let tip = chain.joint_count() - 1;
    let tasks = vec![Task::position(tip, DVec3::ZERO, DVec3::new(0.4, 0.9, 0.3))];
    let mut p = Posture::rest(&chain);
    let report = Solver::default().solve(&chain, &tasks, &mut p).unwrap();
    assert_eq!(report.status, SolveStatus::Converged, "{report:?}");
    assert!(report.levels[0].residual_after <= 1e-6);
    assert!(report.levels[0].residual_before > 0.5);
    assert_eq!(report.gave_way, None);
    // Inactive tasks are ignored.
    let inactive = vec![tasks[0].clone().with_active(false)];
    let report = Solver::default()
        .solve(&chain, &inactive, &mut Posture::rest(&chain))
        .unwrap();
    assert_eq!(
        (report.status, report.iterations, report.levels.len()),
        (SolveStatus::Converged, 0, 0)
    );
}

#[test]
fn budgets_stop_the_solver() {
    let chain = straight_chain(4, 0.5);
    let tip = chain.joint_count() - 1;
    let tasks = vec![Task::position(tip, DVec3::ZERO, DVec3::new(0.4, 0.9, 0.3))];
    let settings = SolverSettings {
        max_iterations: 2,
        ..Default::default()
    };
    let report = Solver::new(settings)
        .unwrap()
        .solve(&chain, &tasks, &mut Posture::rest(&chain))
        .unwrap();
    assert_eq!(
        (report.status, report.iterations),
        (SolveStatus::IterationBudget, 2)
    );
    // A fake clock advancing 1 ms per reading, budget 3.5 ms.
    let ticks = Cell::new(0.0);
    let clock = || {
        ticks.set(ticks.get() + 1e-3);
        ticks.get()
    };
    let settings = SolverSettings {
        time_budget_secs: Some(3.5e-3),
        ..Default::default()
    };
    let report = Solver::new(settings)
        .unwrap()
        .solve_with_clock(&chain, &tasks, &mut Posture::rest(&chain), Some(&clock))
        .unwrap();
    assert_eq!(report.status, SolveStatus::TimeBudget);
    assert!(report.iterations <= 4, "{report:?}");
}

#[test]
fn bad_inputs_are_errors_not_panics() {
    let chain = straight_chain(3, 0.5);
    let mut p = Posture::rest(&chain);
    let mut solver = Solver::default();
    let nan = Task::position(1, DVec3::ZERO, DVec3::new(f64::NAN, 0.0, 0.0));
    assert!(solver.solve(&chain, &[nan], &mut p).is_err());
    assert!(
        solver
            .solve(
                &chain,
                &[Task::position(99, DVec3::ZERO, DVec3::ZERO)],
                &mut p
            )
            .is_err()
    );
    assert!(
        solver
            .solve(&chain, &[Task::gaze(1, DVec3::ZERO, DVec3::ONE)], &mut p)
            .is_err()
    );
    assert!(
        solver
            .solve(
                &chain,
                &[Task::position(1, DVec3::ZERO, DVec3::ONE).at_level(0)],
                &mut p
            )
            .is_err()
    );
    assert!(
        solver
            .solve(
                &chain,
                &[Task::center_of_mass(stance_ik::Axes::XZ, DVec3::ZERO)],
                &mut p
            )
            .is_err()
    );
    assert!(
        Solver::new(SolverSettings {
            tolerance: f64::NAN,
            ..Default::default()
        })
        .is_err()
    );
    assert!(Posture::from_values(&chain, vec![0.0]).is_err());
}

#[test]
fn kernel_and_nalgebra_steps_agree() {
    for seed in 4000..4100 {
        let (s, p, tasks) = random_problem(seed, false);
        let systems = Solver::default().linear_systems(&s, &tasks, &p).unwrap();
        let n = s.dof_count();
        let mut clamped = vec![false; n];
        clamped[n / 2] = true;
        let fixed = DVector::from_fn(n, |i, _| if i == n / 2 { 0.01 } else { 0.0 });
        for params in [
            StepParams::default(),
            StepParams {
                damping: Damping::Adaptive {
                    lambda_max: 0.1,
                    epsilon: 0.1,
                },
                ..StepParams::default()
            },
        ] {
            let (mut pa, mut pb) = (Vec::new(), Vec::new());
            let a = prioritized_step(
                &systems,
                n,
                &params,
                Some(&clamped),
                Some(&fixed),
                &mut StepWorkspace::default(),
                Some(&mut pa),
            );
            let b = stance_ik::prioritized_step_nalgebra(
                &systems,
                n,
                &params,
                Some(&clamped),
                Some(&fixed),
                &mut StepWorkspace::default(),
                Some(&mut pb),
            );
            assert!(
                (&a - &b).amax() < 1e-9 * (1.0 + b.amax()),
                "seed {seed}\n{a}\n{b}"
            );
            for (x, y) in pa.iter().zip(&pb) {
                assert!((x - y).amax() < 1e-9);
            }
        }
    }
}

/// A DOF clamped onto its limit moves by `fixed`; every level must see that move and
/// compensate it with the free DOF. A feasible, exactly solvable level 1 (one 3-D position
/// task on a long chain) therefore still reaches its linearized target, in both backends.
#[test]
fn clamped_moves_are_compensated_by_the_free_dof() {
    let mut checked = 0;
    for seed in 7000..7060 {
        let mut r = rng(seed);
        let s = straight_chain(8, 0.2);
        let p = random_posture(&mut r, &s, 0.6);
        let tip = s.joint_count() - 1;
        let frames = stance_ik::Frames::new(&s, &p);
        let target = frames.point(tip, DVec3::ZERO) + vec3(&mut r, 0.05);
        let tasks = vec![
            Task::position(tip, DVec3::ZERO, target).at_level(1),
            Task::position(tip / 2, DVec3::ZERO, vec3(&mut r, 0.5)).at_level(2),
        ];
        let systems = Solver::default().linear_systems(&s, &tasks, &p).unwrap();
        let n = s.dof_count();
        let clamped_dof = r.random_range(0..n);
        let mut clamped = vec![false; n];
        clamped[clamped_dof] = true;
        let fixed = DVector::from_fn(n, |i, _| if i == clamped_dof { 0.05 } else { 0.0 });
        let params = exact_params(0.0);
        for nalgebra in [false, true] {
            let step = if nalgebra {
                stance_ik::prioritized_step_nalgebra
            } else {
                prioritized_step
            };
            let free_step = step(
                &systems,
                n,
                &params,
                Some(&clamped),
                Some(&fixed),
                &mut StepWorkspace::default(),
                None,
            );
            assert_eq!(free_step[clamped_dof], 0.0, "seed {seed}");
            let total = &free_step + &fixed;
            let residual = linearized_residual(&systems[0], &total);
            assert!(
                residual < 1e-9,
                "seed {seed} nalgebra {nalgebra}: level 1 off by {residual}"
            );
            checked += 1;
        }
    }
    assert_eq!(checked, 120);
}

#[test]
fn per_level_damping_acts_on_its_level_only() {
    // Two levels on a 3-link planar chain: the tip's x at level 1, its y at level 2.
    let chain = straight_chain(3, 0.5);
    let tip = chain.joint_count() - 1;
    let mut p = Posture::rest(&chain);
    p.values_mut().iter_mut().for_each(|v| *v = 0.3);
    let tasks = vec![
        Task::position(tip, DVec3::ZERO, DVec3::new(0.2, 0.0, 0.0))
            .with_axes(stance_ik::Axes::new(true, false, false))
            .at_level(1),
        Task::position(tip, DVec3::ZERO, DVec3::new(0.0, 0.9, 0.0))
            .with_axes(stance_ik::Axes::new(false, true, false))
            .at_level(2),
    ];
    let n = chain.dof_count();
    // Level 2 asked 0.1 m (the textbook clamp) of the tip's 0.11 m error.
    let short = SolverSettings {
        max_linear_step: stance_ik::TEXTBOOK_LINEAR_STEP,
        ..SolverSettings::default()
    };
    let plain = Solver::new(short)
        .unwrap()
        .linear_systems(&chain, &tasks, &p)
        .unwrap();
    let mut damped = plain.clone();
    damped[1].damping = Some(Damping::Constant { lambda: 1.0 });
    let params = exact_params(0.0);
    let mut ws = StepWorkspace::default();
    let a = prioritized_step(&plain, n, &params, None, None, &mut ws, None);
    let b = prioritized_step(&damped, n, &params, None, None, &mut ws, None);
    // Level 1 gets the same linearised result; level 2 asks for the same change but gets
    // less of it (damped), not nothing.
    let (r1a, r1b) = (
        linearized_residual(&plain[0], &a),
        linearized_residual(&plain[0], &b),
    );
    assert!((r1a - r1b).abs() < 1e-9, "level 1: {r1a} vs {r1b}");
    let (r2a, r2b) = (
        linearized_residual(&plain[1], &a),
        linearized_residual(&plain[1], &b),
    );
    let asked = plain[1].dx.norm();
    assert!(r2a < 1e-9 * asked.max(1.0), "undamped level 2 met: {r2a}");
    assert!(
        r2b > 0.2 * asked && r2b < 0.99 * asked,
        "damped: {r2b} of {asked}"
    );
    // The same through the solver's per-level setting.
    let mut solver = Solver::default();
    solver
        .level_damping
        .insert(2, Damping::Constant { lambda: 1.0 });
    let systems = solver.linear_systems(&chain, &tasks, &p).unwrap();
    assert_eq!(systems[1].damping, Some(Damping::Constant { lambda: 1.0 }));
    assert_eq!(systems[0].damping, None);
}
