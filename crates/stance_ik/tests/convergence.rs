//! Strict priority through whole solves, against the plain recursion on the solver's own
//! linear systems (`common::plain_recursion`), on generated suites of the 50-DOF H-Anim body
//! whose levels cannot all be met:
//! (a) conflicting: every task's target from its own random posture;
//! (b) limits active: targets from a posture far outside the joint ranges.
//! The first level where the two differ must be no worse than the recursion's (by more than
//! 1e-3). The counts are printed (`cargo test -- --nocapture`). Convergence on problems whose
//! levels can all be met is measured against an oracle that shares no code with the solver:
//! `crates/stance_textbook/tests/families.rs` (docs/solver-families.md).

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use crate::common;

use common::*;
use glam::DVec3;
use rand::RngExt;
use rand::rngs::StdRng;
use stance_hanim::scenarios::{humanoid50, standing_posture};
use stance_ik::{Axes, Frames, Posture, Skeleton, Solver, SolverSettings, Task, TaskKind};

/// Cases per suite: the 1,000 natively (`STANCE_CASES` overrides); fewer in the
/// browser run (same code).
#[cfg(not(target_arch = "wasm32"))]
fn cases() -> u64 {
    std::env::var("STANCE_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1000)
}
#[cfg(target_arch = "wasm32")]
fn cases() -> u64 {
    60
}

/// Effectors: (joint, point in the joint frame).
const EFFECTORS: &[(&str, [f64; 3])] = &[
    ("l_radiocarpal", [0.0, -0.08, 0.0]),
    ("r_radiocarpal", [0.0, -0.08, 0.0]),
    ("l_talocrural", [0.0, -0.05, 0.0]),
    ("r_talocrural", [0.0, -0.05, 0.0]),
    ("l_metatarsophalangeal_2", [0.0, 0.0, 0.04]),
    ("skullbase", [0.0, 0.1, 0.05]),
    ("l_elbow", [0.0, 0.0, 0.0]),
    ("r_elbow", [0.0, 0.0, 0.0]),
    ("l_knee", [0.0, 0.0, 0.0]),
    ("r_knee", [0.0, 0.0, 0.0]),
    ("sacroiliac", [0.0, 0.0, 0.05]),
    ("vt1", [0.0, 0.0, 0.08]),
];
const ORIENTED: &[&str] = &[
    "l_radiocarpal",
    "r_radiocarpal",
    "skullbase",
    "sacroiliac",
    "vt6",
    "l_talocrural",
];

/// A random posture within the limits, around standing (`amplitude` rad per rotation DOF).
fn random_body_posture(
    r: &mut StdRng,
    skeleton: &Skeleton,
    amplitude: f64,
    respect_limits: bool,
) -> Posture {
    let mut p = standing_posture(skeleton);
    let (lo, hi) = (skeleton.lower_limits(), skeleton.upper_limits());
    let kinds = skeleton.dof_kinds();
    for (i, v) in p.values_mut().iter_mut().enumerate() {
        let scale = if kinds[i].is_rotation() {
            amplitude
        } else {
            0.2 * amplitude
        };
        *v += uniform(r, -scale, scale);
        if respect_limits {
            *v = v.clamp(lo[i], hi[i]);
        }
    }
    p
}

/// A random task whose target is taken from `goal`.
fn task_from(r: &mut StdRng, skeleton: &Skeleton, goal: &Posture, used_gaze: &mut bool) -> Task {
    let frames = Frames::new(skeleton, goal);
    let joint = |name: &str| skeleton.require_joint(name).unwrap();
    loop {
        match r.random_range(0..10) {
            0..=5 => {
                let (name, point) = EFFECTORS[r.random_range(0..EFFECTORS.len())];
                let j = joint(name);
                let point = DVec3::from_array(point);
                let axes = if r.random::<f64>() < 0.6 {
                    Axes::XYZ
                } else {
                    random_axes(r)
                };
                return Task::position(j, point, frames.point(j, point)).with_axes(axes);
            }
            6 | 7 => {
                let j = joint(ORIENTED[r.random_range(0..ORIENTED.len())]);
                return Task::orientation(j, frames.rotation(j));
            }
            8 if !*used_gaze => {
                *used_gaze = true;
                let j = joint("skullbase");
                let eye = DVec3::new(0.0, 0.08, 0.08);
                let forward = frames.world_from_joint_rotation[j] * DVec3::Z;
                let target = frames.point(j, eye) + forward * uniform(r, 0.5, 3.0);
                let mut t = Task::gaze(j, DVec3::Z, target);
                if let TaskKind::Gaze { effector, .. } = &mut t.kind {
                    effector.point = eye;
                }
                return t;
            }
            9 => {
                return Task::center_of_mass(Axes::new(true, false, true), frames.center_of_mass());
            }
            _ => {}
        }
    }
}

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Suite {
    Conflicting,
    Limits,
}

struct Case {
    tasks: Vec<Task>,
    start: Posture,
}

fn case(skeleton: &Skeleton, suite: Suite, seed: u64) -> Case {
    let mut r = rng(seed * 7919 + suite as u64);
    let levels = r.random_range(2..=6u32);
    let goal = match suite {
        Suite::Limits => random_body_posture(&mut r, skeleton, 2.5, false),
        _ => random_body_posture(&mut r, skeleton, 0.7, true),
    };
    let mut used_gaze = false;
    let mut tasks = Vec::new();
    for level in 1..=levels {
        for _ in 0..r.random_range(1..=2) {
            let from = if suite == Suite::Conflicting {
                random_body_posture(&mut r, skeleton, 0.7, true)
            } else {
                goal.clone()
            };
            tasks.push(task_from(&mut r, skeleton, &from, &mut used_gaze).at_level(level));
        }
    }
    let start = if r.random::<bool>() {
        standing_posture(skeleton)
    } else {
        random_body_posture(&mut r, skeleton, 0.5, true)
    };
    Case { tasks, start }
}

/// Level residuals of Stance's solve and of the oracle.
fn run(skeleton: &Skeleton, c: &Case) -> (Vec<f64>, Vec<f64>) {
    let mut posture = c.start.clone();
    let mut solver = Solver::new(SolverSettings::default()).unwrap();
    solver.solve(skeleton, &c.tasks, &mut posture).unwrap();
    let ours = level_residuals(skeleton, &c.tasks, &posture);
    let (oracle, _) = plain_recursion(skeleton, &c.tasks, &c.start, 100);
    (ours, level_residuals(skeleton, &c.tasks, &oracle))
}

/// At the first level where the two differ by more than `slack`, ours is the smaller.
fn no_worse(ours: &[f64], oracle: &[f64], slack: f64) -> bool {
    for (a, b) in ours.iter().zip(oracle) {
        if (a - b).abs() > slack {
            return a < b;
        }
    }
    true
}

fn no_worse_suite(suite: Suite) {
    let skeleton = humanoid50().unwrap();
    let n = cases();
    let mut ok = 0;
    let mut failures = Vec::new();
    for seed in 0..n {
        let c = case(&skeleton, suite, seed);
        let (ours, oracle) = run(&skeleton, &c);
        if no_worse(&ours, &oracle, 1e-3) {
            ok += 1;
        } else if failures.len() < 5 {
            failures.push((seed, ours, oracle));
        }
    }
    println!("{suite:?} suite: Stance no worse than the oracle in {ok}/{n}");
    assert!(
        ok as f64 >= 0.95 * n as f64,
        "{suite:?}: {ok}/{n}; first failures {failures:?}"
    );
}

#[test]
fn conflicting_suite_is_no_worse_than_the_oracle() {
    no_worse_suite(Suite::Conflicting);
}

#[test]
fn limits_suite_is_no_worse_than_the_oracle() {
    no_worse_suite(Suite::Limits);
}

/// A gaze task on the head of a standing body (facing +Z), whole body free.
fn gaze_solve(target_of: impl Fn(DVec3, DVec3) -> DVec3) -> (f64, f64) {
    let skeleton = humanoid50().unwrap();
    let head = skeleton.require_joint("skullbase").unwrap();
    let start = standing_posture(&skeleton);
    let frames = Frames::new(&skeleton, &start);
    let eye_local = DVec3::new(0.0, 0.08, 0.08);
    let eye = frames.point(head, eye_local);
    let forward = frames.world_from_joint_rotation[head] * DVec3::Z;
    let mut task = Task::gaze(head, DVec3::Z, target_of(eye, forward));
    if let TaskKind::Gaze { effector, .. } = &mut task.kind {
        effector.point = eye_local;
    }
    let tasks = [task];
    let mut posture = start.clone();
    let report = Solver::default()
        .solve(&skeleton, &tasks, &mut posture)
        .unwrap();
    let before = report.levels[0].residual_before;
    let after = level_residuals(&skeleton, &tasks, &posture)[0];
    assert!(
        (after - report.levels[0].residual_after).abs() < 1e-9,
        "the report tells the truth"
    );
    (before, after)
}

#[test]
fn gaze_turns_toward_a_target_straight_behind() {
    // The case: the target 2 m behind the head (body facing +Z).
    let (before, after) = gaze_solve(|_, _| DVec3::new(0.0, 1.6, -2.0));
    assert!(before > 2.8, "starts nearly opposite: {before}");
    assert!(after < 1e-6, "straight behind: {before} rad -> {after} rad");
    // Slightly to the side.
    let (before, after) = gaze_solve(|_, _| DVec3::new(0.3, 1.6, -2.0));
    assert!(before > 2.5);
    assert!(
        after < 1e-6,
        "behind, to the side: {before} rad -> {after} rad"
    );
}

#[test]
fn gaze_turns_toward_the_exact_antipode() {
    let (before, after) = gaze_solve(|eye, forward| eye - 2.0 * forward);
    assert!(
        (before - std::f64::consts::PI).abs() < 1e-9,
        "exact antipode: {before}"
    );
    assert!(after < 1e-6, "exact antipode: {before} rad -> {after} rad");
}
