//! The point-on-a-line and point-on-a-plane tasks: their Jacobians and errors against central
//! differences on random trees and postures (the oracle: the distances measured from the
//! world point, by a formula of the test's own), and solves that put a hand on a bar and a
//! foot on a plane, judged by those distances.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use glam::DVec3;
use stance_hanim::{LevelOfArticulation, SkeletonOptions, default_skeleton};
use stance_ik::{Frames, PLANE_BAND, Posture, Skeleton, Solver, SolverSettings, Task};

use crate::common::{finite_difference_jacobian, random_posture, random_skeleton, rng, vec3};

/// The distance of `p` from the line through `o` along `u` (the test's own formula).
fn line_distance(p: DVec3, o: DVec3, u: DVec3) -> f64 {
    (p - o).cross(u.normalize()).length()
}

/// The signed distance of `p` from the plane through `o` with normal `n`.
fn plane_distance(p: DVec3, o: DVec3, n: DVec3) -> f64 {
    (p - o).dot(n.normalize())
}

fn jacobian(solver: &mut Solver, s: &Skeleton, p: &Posture, task: &Task) -> nalgebra::DMatrix<f64> {
    solver
        .linear_systems(s, std::slice::from_ref(task), p)
        .unwrap()[0]
        .jacobian_t
        .transpose()
}

/// Catches a row that is not the derivative of the offset it measures (a basis vector of
/// the line's rows not orthogonal to it, the plane's normal not normalised, a DOF's column
/// taken at the wrong joint), and an error whose derivative is not `-J`.
#[test]
fn line_and_plane_jacobians_match_central_differences() {
    let mut r = rng(41);
    let mut solver = Solver::default();
    let mut checked = [0; 3];
    for _ in 0..40 {
        let s = random_skeleton(&mut r, 8, false);
        let p = random_posture(&mut r, &s, 1.2);
        let frames = Frames::new(&s, &p);
        let joint = r.random_range(0..s.joint_count());
        let point = vec3(&mut r, 0.2);
        let effector = frames.point(joint, point);
        let line = Task::point_on_line(joint, point, vec3(&mut r, 1.5), vec3(&mut r, 1.0) + 0.1);
        let normal = vec3(&mut r, 1.0) + DVec3::Y * 0.1;
        // An equality, and an inequality whose point lies below the plane (its row acts).
        let plane = Task::point_on_plane(joint, point, vec3(&mut r, 1.5), normal * 2.0, false);
        let below = Task::point_on_plane(joint, point, effector + normal * 0.1, normal, true);
        for (k, task) in [line, plane, below].iter().enumerate() {
            let analytic = jacobian(&mut solver, &s, &p, task);
            let numeric = finite_difference_jacobian(&s, &p, task);
            let err = (&analytic - &numeric).amax();
            assert!(err < 1e-6, "{:?}: |J - FD| = {err}", task.kind);
            let h = 1e-6;
            for d in 0..s.dof_count() {
                let at = |delta: f64| {
                    let mut q = p.clone();
                    q.values_mut()[d] += delta;
                    task.error_vector(&s, &Frames::new(&s, &q), q.values())
                };
                let (plus, minus) = (at(h), at(-h));
                for row in 0..task.rows() {
                    let numeric = (plus[row] - minus[row]) / (2.0 * h);
                    assert!(
                        (numeric + analytic[(row, d)]).abs() < 2e-6,
                        "{:?}",
                        task.kind
                    );
                }
            }
            checked[k] += 1;
        }
        // The error's norm is the distance the test measures.
        let Task { kind, .. } = Task::point_on_line(joint, point, DVec3::ONE, DVec3::X);
        let residual = Task::new(kind).residual(&s, &frames, p.values());
        let want = line_distance(effector, DVec3::ONE, DVec3::X);
        assert!((residual - want).abs() < 1e-12, "{residual} {want}");
    }
    assert_eq!(checked, [40; 3]);
}

use rand::RngExt;

/// Catches an inequality that holds a point above the plane (its row not empty there) or lets
/// it below (no error there): the row is empty more than [`PLANE_BAND`] above, zero-error
/// inside the band, and pushes back from below.
#[test]
fn on_or_above_a_plane_acts_only_below_it() {
    let s = random_skeleton(&mut rng(5), 5, false);
    let p = Posture::rest(&s);
    let frames = Frames::new(&s, &p);
    let mut solver = Solver::default();
    let joint = s.joint_count() - 1;
    let at = frames.joint_position[joint];
    let task = |height: f64| {
        Task::point_on_plane(joint, DVec3::ZERO, at - DVec3::Y * height, DVec3::Y, true)
    };
    // 5 cm above the plane: empty row, no error.
    let high = task(0.05);
    assert_eq!(high.error_vector(&s, &frames, p.values()), vec![0.0]);
    assert_eq!(jacobian(&mut solver, &s, &p, &high).amax(), 0.0);
    // 1 mm above: held with a zero error.
    let held = task(PLANE_BAND / 2.0);
    assert_eq!(held.error_vector(&s, &frames, p.values()), vec![0.0]);
    // 3 cm below: the error lifts it by 3 cm.
    let low = task(-0.03);
    let e = low.error_vector(&s, &frames, p.values());
    assert!((e[0] - 0.03).abs() < 1e-12, "{e:?}");
    // The equality pulls down from above.
    let equal = Task::point_on_plane(joint, DVec3::ZERO, at - DVec3::Y * 0.05, DVec3::Y, false);
    let e = equal.error_vector(&s, &frames, p.values());
    assert!((e[0] + 0.05).abs() < 1e-12, "{e:?}");
}

fn loa2() -> Skeleton {
    default_skeleton(&SkeletonOptions {
        loa: LevelOfArticulation::Loa2,
        ..SkeletonOptions::default()
    })
    .map(|body| body.skeleton)
    .unwrap_or_else(|e| panic!("{e}"))
}

/// Catches a line task that does not put the hand on the bar or holds it at one point of it
/// (a position task in disguise): the left wrist on a horizontal bar in front of the body at
/// level 1, pulled along the bar at level 2 toward a point beyond its end; the wrist ends on
/// the bar (the test's distance) and has moved along it toward the pull. A foot on a tilted
/// plane (equality) and the other on or above the floor, with a goal under it: both judged by
/// the signed distances.
#[test]
fn a_hand_on_a_bar_slides_along_it_and_a_foot_stays_on_a_plane() {
    let s = loa2();
    let rest = Posture::rest(&s);
    let frames = Frames::new(&s, &rest);
    let at = |name: &str| s.joint_index(name).unwrap();
    let (wrist, left_foot, right_foot) =
        (at("l_radiocarpal"), at("l_talocrural"), at("r_talocrural"));
    let bar_origin = DVec3::new(0.3, 1.2, 0.35);
    let bar = DVec3::X;
    let tilted = DVec3::new(0.0, 1.0, 0.3);
    let plane_origin = frames.joint_position[left_foot] + DVec3::Z * 0.05;
    let floor = DVec3::new(0.0, frames.joint_position[right_foot].y, 0.0);
    let tasks = vec![
        Task::point_on_line(wrist, DVec3::ZERO, bar_origin, bar),
        Task::point_on_plane(left_foot, DVec3::ZERO, plane_origin, tilted, false),
        Task::point_on_plane(right_foot, DVec3::ZERO, floor, DVec3::Y, true),
        Task::position(wrist, DVec3::ZERO, bar_origin + DVec3::new(0.4, 0.3, 0.2)).at_level(2),
        Task::position(
            right_foot,
            DVec3::ZERO,
            frames.joint_position[right_foot] - DVec3::Y * 0.1,
        )
        .at_level(2),
        Task::rest_posture(&s).at_level(3).with_weight(0.01),
    ];
    let mut posture = rest.clone();
    let mut solver = Solver::new(SolverSettings {
        max_iterations: 300,
        ..SolverSettings::default()
    })
    .unwrap();
    let report = solver.solve(&s, &tasks, &mut posture).unwrap();
    let f = Frames::new(&s, &posture);
    let hand = f.joint_position[wrist];
    let off_bar = line_distance(hand, bar_origin, bar);
    assert!(
        off_bar < 1e-4,
        "the wrist is {off_bar} m off the bar; {report:?}"
    );
    assert!(
        (hand - bar_origin).dot(bar) > 0.1,
        "the wrist stayed at {hand}"
    );
    let off_plane = plane_distance(f.joint_position[left_foot], plane_origin, tilted);
    assert!(
        off_plane.abs() < 1e-4,
        "the left foot is {off_plane} m off its plane"
    );
    let under = plane_distance(f.joint_position[right_foot], floor, DVec3::Y);
    assert!(
        under > -1e-4,
        "the right foot went {under} m under the floor"
    );
    assert!(
        under < 0.01,
        "the right foot was pulled down to the floor: {under} m"
    );
}
