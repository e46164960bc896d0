//! The damping that falls with the error (`Damping::Levenberg`): near a singularity, where a
//! constant damping makes every iteration shave off only a share of the error (linear
//! convergence at the rate `lambda^2 / (sigma^2 + lambda^2)`), it converges quadratically. Checked on an arm reaching nearly straight, by the errors of successive
//! iterations (independent of the solver's own convergence test).

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use glam::DVec3;
use stance_hanim::scenarios::arm7;
use stance_ik::{Damping, Frames, Posture, Solver, SolverSettings, Task};

/// Errors (m) of the hand after each of `count` iterations from the rest (straight) arm,
/// toward a target 1 µm short of full reach, off to the side.
fn errors(damping: Damping, count: usize) -> Vec<f64> {
    let skeleton = arm7().unwrap();
    let hand = skeleton.require_joint("l_radiocarpal").unwrap();
    let shoulder = skeleton.require_joint("l_shoulder").unwrap();
    let rest = Posture::rest(&skeleton);
    let frames = Frames::new(&skeleton, &rest);
    let reach = (frames.joint_position[hand] - frames.joint_position[shoulder]).length();
    let direction = DVec3::new(0.3, -0.8, 0.5).normalize();
    let target = frames.joint_position[shoulder] + direction * (reach - 1e-6);
    let tasks = vec![Task::position(hand, DVec3::ZERO, target)];
    let mut solver = Solver::new(SolverSettings {
        damping,
        ..SolverSettings::default()
    })
    .unwrap();
    let mut posture = rest;
    // Bent a little first, so that the elbow is off the exact singularity.
    posture.values_mut()[3] = -0.3;
    (0..count)
        .map(|_| {
            solver.iterate(&skeleton, &tasks, &mut posture).unwrap();
            (Frames::new(&skeleton, &posture).joint_position[hand] - target).length()
        })
        .collect()
}

#[test]
fn near_full_reach_levenberg_damping_converges_quadratically_and_a_constant_one_does_not() {
    let default = errors(
        Damping::Levenberg {
            lambda: 0.002,
            error_scale: 0.01,
        },
        40,
    );
    let constant = errors(Damping::Constant { lambda: 0.002 }, 40);
    let to = |e: &[f64], tol: f64| e.iter().position(|&x| x <= tol);
    let ours = to(&default, 1e-12).expect("the Levenberg damping reaches 1e-12 m");
    // Quadratic: once below 1 mm, each error at most a modest multiple of the last squared.
    let tail: Vec<f64> = default[..=ours]
        .iter()
        .copied()
        .skip_while(|&e| e > 1e-3)
        .collect();
    for pair in tail.windows(2) {
        assert!(
            pair[1] <= 1e3 * pair[0] * pair[0] + 1e-12,
            "not quadratic: {} after {} ({default:?})",
            pair[1],
            pair[0]
        );
    }
    // Never there within the 40 iterations counts as later.
    let theirs = to(&constant, 1e-12).unwrap_or(usize::MAX);
    assert!(
        ours + 2 <= theirs,
        "Levenberg {ours} iterations, constant {theirs}: {default:?} {constant:?}"
    );
    println!("to 1e-12 m: Levenberg {ours} iterations, constant {theirs}");
}
