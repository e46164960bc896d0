//! The collision task on the H-Anim body's capsules (`stance_hanim::capsules`): its rows'
//! Jacobian against central differences of the surfaces' distances, and a reach whose goal
//! lies inside the torso: with the task the forearm and hand stay outside every other
//! capsule they may touch, without it they go through.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::sync::Arc;

use glam::DVec3;
use stance_hanim::capsules::body_capsules;
use stance_hanim::{LevelOfArticulation, SkeletonOptions, default_skeleton};
use stance_ik::{
    Capsule, Collision, Frames, Posture, Skeleton, Solver, SolverSettings, Task, TaskKind,
    closest_points, collision_pairs, floor_capsules,
};

use crate::common::{finite_difference_jacobian, random_posture, rng};

fn loa2() -> Skeleton {
    default_skeleton(&SkeletonOptions {
        loa: LevelOfArticulation::Loa2,
        ..SkeletonOptions::default()
    })
    .map(|body| body.skeleton)
    .unwrap_or_else(|e| panic!("{e}"))
}

fn collision(skeleton: &Skeleton, margin: f64) -> (Task, Vec<Capsule>, Vec<(usize, usize)>) {
    let capsules = body_capsules(skeleton);
    let rest = Frames::new(skeleton, &Posture::rest(skeleton));
    let pairs = collision_pairs(
        skeleton,
        &capsules,
        &rest,
        margin + stance_ik::COLLISION_BAND,
    );
    let task = Task::new(TaskKind::Collision(Collision {
        capsules: Arc::from(capsules.clone()),
        pairs: Arc::from(pairs.clone()),
        margin,
        floor: Arc::from(floor_capsules(&capsules, &rest)),
        rows: 8,
    }));
    (task, capsules, pairs)
}

/// The deepest overlap of the tested pairs at `posture` (m; negative: a gap), from the
/// capsules' world segments.
fn deepest(
    skeleton: &Skeleton,
    capsules: &[Capsule],
    pairs: &[(usize, usize)],
    posture: &Posture,
) -> f64 {
    let frames = Frames::new(skeleton, posture);
    pairs
        .iter()
        .map(|&(i, j)| {
            let (a0, a1) = capsules[i].world(&frames);
            let (b0, b1) = capsules[j].world(&frames);
            let (pa, pb) = closest_points(a0, a1, b0, b1);
            capsules[i].radius + capsules[j].radius - (pa - pb).length()
        })
        .fold(f64::NEG_INFINITY, f64::max)
}

/// Catches a row whose Jacobian is not the distance's derivative (the normal's sign, a closest
/// point moved with the wrong joint, the floor's row along another axis): random postures of
/// the LOA 2 body, a margin wide enough that several constraints hold, each against central
/// differences of the distances the task measures.
#[test]
fn collision_rows_are_the_derivatives_of_the_distances() {
    let s = loa2();
    let (task, _, _) = collision(&s, 0.08);
    let mut solver = Solver::default();
    let mut r = rng(21);
    let mut rows_checked = 0;
    for _ in 0..12 {
        let p = random_posture(&mut r, &s, 0.8);
        let analytic = solver
            .linear_systems(&s, std::slice::from_ref(&task), &p)
            .unwrap_or_else(|e| panic!("{e}"))[0]
            .jacobian_t
            .transpose();
        let numeric = finite_difference_jacobian(&s, &p, &task);
        for row in 0..task.rows() {
            if analytic.row(row).amax() == 0.0 {
                continue;
            }
            let err = (analytic.row(row) - numeric.row(row)).amax();
            assert!(err < 1e-5, "row {row}: |J - FD| = {err}");
            rows_checked += 1;
        }
    }
    println!("collision: {rows_checked} rows checked against central differences");
    assert!(rows_checked >= 12, "{rows_checked} rows held");
}

/// Catches a collision task that does not hold the body apart, or that takes the step from
/// the levels above it: the right wrist pulled to a point inside the chest, the feet and the
/// chest pinned above it. With the collision task at level 2 no tested pair overlaps by more than a
/// millimetre and the feet hold; without it the hand goes into the torso.
#[test]
fn a_hand_pulled_into_the_chest_stays_outside_it() {
    let s = loa2();
    let (task, capsules, pairs) = collision(&s, 0.01);
    let rest = Posture::rest(&s);
    let frames = Frames::new(&s, &rest);
    let at = |name: &str| s.joint_index(name).unwrap_or_else(|| panic!("{name}"));
    // The middle of the bar between the collarbones: on the chest capsule's axis.
    let chest = frames.joint_position[at("l_sternoclavicular")]
        .lerp(frames.joint_position[at("r_sternoclavicular")], 0.5);
    // The feet and the chest held where they stand (the chest cannot lean away from the hand).
    let chest_joint = s.joints()[at("l_sternoclavicular")].parent.unwrap_or(0);
    let feet = [at("l_talocrural"), at("r_talocrural"), chest_joint]
        .map(|j| Task::position(j, DVec3::ZERO, frames.joint_position[j]).at_level(1));
    let reach = Task::position(at("r_radiocarpal"), DVec3::ZERO, chest).at_level(3);
    let solve = |with_collision: bool| {
        let mut tasks = feet.to_vec();
        if with_collision {
            tasks.push(task.clone().at_level(2));
        }
        tasks.push(reach.clone());
        let mut posture = rest.clone();
        let mut solver = Solver::new(SolverSettings {
            max_iterations: 300,
            ..SolverSettings::default()
        })
        .unwrap_or_else(|e| panic!("{e}"));
        let report = solver
            .solve(&s, &tasks, &mut posture)
            .unwrap_or_else(|e| panic!("{e}"));
        (posture, report)
    };
    let (free, _) = solve(false);
    assert!(
        deepest(&s, &capsules, &pairs, &free) > 0.02,
        "without the task the hand goes in: {}",
        deepest(&s, &capsules, &pairs, &free)
    );
    let (held, report) = solve(true);
    let overlap = deepest(&s, &capsules, &pairs, &held);
    println!(
        "collision: deepest overlap {:.1} mm without the task, {:.2} mm with it ({} iterations, {} pairs tested)",
        deepest(&s, &capsules, &pairs, &free) * 1e3,
        overlap * 1e3,
        report.iterations,
        pairs.len()
    );
    assert!(overlap < 0.001, "overlap {overlap} m");
    let f = Frames::new(&s, &held);
    for j in [at("l_talocrural"), at("r_talocrural"), chest_joint] {
        assert!((f.joint_position[j] - frames.joint_position[j]).length() < 1e-4);
    }
    // The hand still reaches toward the chest, nearer than it started (the arm hanging at
    // rest slides up the body until it stops on it), and never inside the chest's capsule.
    let start = (frames.joint_position[at("r_radiocarpal")] - chest).length();
    let end = (f.joint_position[at("r_radiocarpal")] - chest).length();
    let bar = capsules
        .iter()
        .filter(|c| c.joint == chest_joint)
        .map(|c| c.radius)
        .fold(0.0, f64::max);
    assert!(
        end > bar,
        "the wrist {end} m from the chest bar's axis, radius {bar}"
    );
    println!(
        "collision: the wrist {:.3} m from the goal inside the chest (started {:.3})",
        end, start
    );
    assert!(end < start - 0.03, "{end} of {start} m left; {report:?}");
}
