//! The inequality balance task (centre of mass inside the support polygon) and the partial
//! orientation (`TaskKind::Direction`), solved on the 50-DOF H-Anim body and checked against
//! hand computations: a rectangle for the polygon of two flat, parallel feet, angles between
//! world axes.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use glam::{DQuat, DVec3};
use stance_hanim::scenarios::{humanoid50, standing_posture};
use stance_ik::{Effector, Frames, Posture, Skeleton, Solver, SolverSettings, Task};

/// Sole corners of a foot, relative to its ankle (world axes at the standing posture): 4 cm
/// to each side, 5 cm behind and 15 cm ahead of the ankle, on the floor.
const HALF_WIDTH: f64 = 0.04;
const HEEL: f64 = -0.05;
const TOE: f64 = 0.15;

struct Stand {
    skeleton: Skeleton,
    start: Posture,
    /// Feet pinned (position and orientation) at level 1.
    pins: Vec<Task>,
    /// The 8 sole corners as effectors.
    support: Vec<Effector>,
    /// The hand-computed support rectangle: (min x, max x, min z, max z).
    rectangle: (f64, f64, f64, f64),
}

fn stand() -> Stand {
    let skeleton = humanoid50().unwrap();
    let start = standing_posture(&skeleton);
    let frames = Frames::new(&skeleton, &start);
    let mut pins = Vec::new();
    let mut support = Vec::new();
    let (mut min_x, mut max_x) = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut min_z, mut max_z) = (f64::INFINITY, f64::NEG_INFINITY);
    for name in ["l_talocrural", "r_talocrural"] {
        let j = skeleton.require_joint(name).unwrap();
        let ankle = frames.joint_position[j];
        pins.push(Task::position(j, DVec3::ZERO, ankle));
        pins.push(Task::orientation(j, frames.rotation(j)));
        let rotation = frames.world_from_joint_rotation[j];
        for (dx, dz) in [
            (-HALF_WIDTH, HEEL),
            (HALF_WIDTH, HEEL),
            (-HALF_WIDTH, TOE),
            (HALF_WIDTH, TOE),
        ] {
            let world = DVec3::new(ankle.x + dx, 0.0, ankle.z + dz);
            support.push(Effector {
                joint: j,
                point: rotation.transpose() * (world - ankle),
            });
            min_x = min_x.min(world.x);
            max_x = max_x.max(world.x);
            min_z = min_z.min(world.z);
            max_z = max_z.max(world.z);
        }
    }
    Stand {
        skeleton,
        start,
        pins,
        support,
        rectangle: (min_x, max_x, min_z, max_z),
    }
}

/// How far the centre of mass's projection is inside the rectangle (negative: outside).
fn depth_inside(rectangle: (f64, f64, f64, f64), com: DVec3) -> f64 {
    let (x0, x1, z0, z1) = rectangle;
    (com.x - x0).min(x1 - com.x).min(com.z - z0).min(z1 - com.z)
}

fn reach(stand: &Stand, forward: f64, balance: Option<f64>) -> (Posture, Frames, f64) {
    reach_with(stand, forward, balance, SolverSettings::default())
}

fn reach_with(
    stand: &Stand,
    forward: f64,
    balance: Option<f64>,
    settings: SolverSettings,
) -> (Posture, Frames, f64) {
    let s = &stand.skeleton;
    let wrist = s.require_joint("r_radiocarpal").unwrap();
    let start_frames = Frames::new(s, &stand.start);
    let goal = start_frames.joint_position[wrist] + DVec3::new(0.0, 0.3, forward);
    let mut tasks = stand.pins.clone();
    if let Some(margin) = balance {
        tasks.push(Task::balance(stand.support.clone(), margin).at_level(2));
    }
    tasks.push(Task::position(wrist, DVec3::ZERO, goal).at_level(3));
    let mut posture = stand.start.clone();
    let report = Solver::new(settings)
        .expect("valid settings")
        .solve(s, &tasks, &mut posture)
        .expect("valid problem");
    assert!(
        report.levels[0].residual_after < 1e-6,
        "the pinned feet hold: {report:?}"
    );
    let frames = Frames::new(s, &posture);
    let hand = (frames.joint_position[wrist] - goal).length();
    (posture, frames, hand)
}

#[test]
fn balance_keeps_the_centre_of_mass_inside_the_feet_while_the_hand_reaches_far() {
    let stand = stand();
    let margin = 0.02;
    // Without balance the reach carries the centre of mass past the toes.
    let (_, free, free_hand) = reach(&stand, 1.5, None);
    let free_depth = depth_inside(stand.rectangle, free.center_of_mass());
    assert!(
        free_depth < -0.02,
        "the unbalanced reach leaves the feet (depth {free_depth})"
    );
    // With it, the projection stays `margin` inside the rectangle, on the boundary of the
    // shrunk rectangle (the inequality is tight: the hand uses the whole polygon, no more).
    let (_, held, hand) = reach(&stand, 1.5, Some(margin));
    let com = held.center_of_mass();
    let depth = depth_inside(stand.rectangle, com);
    assert!(
        depth >= margin - 1e-6,
        "centre of mass {com} is {depth} m inside, wanted >= {margin}"
    );
    assert!(
        depth <= margin + 5e-3,
        "the balance is tight at the boundary (depth {depth})"
    );
    assert!(
        hand > free_hand,
        "balance costs reach ({hand} vs {free_hand})"
    );
}

#[test]
fn balance_does_not_constrain_a_reach_that_stays_inside() {
    let stand = stand();
    // A small reach: the centre of mass stays well inside, so the inequality stays empty and
    // the lower level is solved exactly as without it. With the textbook's short steps
    // (0.1 m a task per iteration) no iterate comes near the margin; the default 0.3 m steps
    // overshoot on the way (an iterate's projection crosses the margin, the inequality holds
    // it there), which the second half checks: still met, still inside.
    let short = SolverSettings {
        max_linear_step: stance_ik::TEXTBOOK_LINEAR_STEP,
        max_angular_step: stance_ik::TEXTBOOK_ANGULAR_STEP,
        ..SolverSettings::default()
    };
    let (free_posture, free, free_hand) = reach_with(&stand, 0.3, None, short);
    assert!(depth_inside(stand.rectangle, free.center_of_mass()) > 0.03);
    let (posture, _, hand) = reach_with(&stand, 0.3, Some(0.02), short);
    assert!(free_hand < 1e-6 && hand < 1e-6, "{free_hand} {hand}");
    let moved = posture
        .values()
        .iter()
        .zip(free_posture.values())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(
        moved < 1e-9,
        "same posture with and without balance: {moved}"
    );
    let (_, held, hand) = reach(&stand, 0.3, Some(0.02));
    let depth = depth_inside(stand.rectangle, held.center_of_mass());
    assert!(hand < 1e-6 && depth >= 0.02 - 1e-6, "{hand} {depth}");
}

#[test]
fn balance_brings_an_unbalanced_start_back_over_the_feet() {
    let stand = stand();
    let s = &stand.skeleton;
    // Start from the unbalanced far reach (feet pinned where they stood, the centre of mass
    // far ahead of the toes) and ask for balance alone.
    let (lean, _, _) = reach(&stand, 1.5, None);
    let start_depth = depth_inside(stand.rectangle, Frames::new(s, &lean).center_of_mass());
    let mut tasks = stand.pins.clone();
    tasks.push(Task::balance(stand.support.clone(), 0.03).at_level(2));
    let mut posture = lean;
    let report = Solver::default().solve(s, &tasks, &mut posture).unwrap();
    let depth = depth_inside(stand.rectangle, Frames::new(s, &posture).center_of_mass());
    assert!(start_depth < -0.1, "{start_depth}");
    assert!(report.levels[0].residual_after < 1e-6 && report.levels[1].residual_after < 1e-6);
    assert!(depth >= 0.03 - 1e-6, "depth {depth}");
}

fn angle(a: DVec3, b: DVec3) -> f64 {
    a.normalize().dot(b.normalize()).clamp(-1.0, 1.0).acos()
}

#[test]
fn direction_keeps_the_pelvis_upright_and_leaves_its_heading_free() {
    let s = humanoid50().unwrap();
    let start = standing_posture(&s);
    let pelvis = s.require_joint("sacroiliac").unwrap();
    let upright = Task::direction(pelvis, DVec3::Y, DVec3::Y);
    assert_eq!(upright.rows(), 2);
    // Level 2 asks the pelvis to pitch 30 degrees forward and turn 40 degrees: only the turn,
    // the rotation about the kept axis, can be granted.
    let wanted = DQuat::from_rotation_y(40f64.to_radians()) * DQuat::from_rotation_x(0.5);
    let tasks = vec![upright, Task::orientation(pelvis, wanted).at_level(2)];
    let mut posture = start.clone();
    Solver::default().solve(&s, &tasks, &mut posture).unwrap();
    let frames = Frames::new(&s, &posture);
    let rotation = frames.world_from_joint_rotation[pelvis];
    assert!(angle(rotation * DVec3::Y, DVec3::Y) < 1e-6, "upright");
    let forward = rotation * DVec3::Z;
    let heading = forward.x.atan2(forward.z).to_degrees();
    assert!((heading - 40.0).abs() < 1e-3, "heading {heading}");
}

#[test]
fn direction_turns_the_palm_down_with_the_feet_pinned() {
    let stand = stand();
    let s = &stand.skeleton;
    let wrist = s.require_joint("r_radiocarpal").unwrap();
    // The right palm faces the thigh (+X) at rest; turn it to face the floor.
    let palm = Frames::new(s, &stand.start).world_from_joint_rotation[wrist].transpose() * DVec3::X;
    let start_angle = angle(
        Frames::new(s, &stand.start).world_from_joint_rotation[wrist] * palm,
        -DVec3::Y,
    );
    let mut tasks = stand.pins.clone();
    tasks.push(Task::direction(wrist, palm, -DVec3::Y).at_level(2));
    let mut posture = stand.start.clone();
    let report = Solver::default().solve(s, &tasks, &mut posture).unwrap();
    let frames = Frames::new(s, &posture);
    let end_angle = angle(frames.world_from_joint_rotation[wrist] * palm, -DVec3::Y);
    assert!(start_angle > 1.0, "{start_angle}");
    assert!(end_angle < 1e-6, "palm down: {end_angle} rad ({report:?})");
    assert!(report.levels[0].residual_after < 1e-6);
}
