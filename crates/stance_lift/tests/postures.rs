//! The round trip's drawn postures, shared by `tests/round_trip.rs` and
//! `examples/lift_bench.rs` (which includes this file), so that the bench measures the lift on
//! the very postures the test holds to 2 px.

use glam::DVec3;
use stance_ik::{Frames, Posture, Skeleton, Solver, SolverSettings, Task};

/// A posture drawn from the default body: the feet pinned where `feet` put them (y at the
/// rest ankle height: on the floor), the wrists pulled to `hands` (world), the rest below.
pub fn drawn(s: &Skeleton, feet: [DVec3; 2], hands: [DVec3; 2]) -> Posture {
    // The drawn postures of these tests, as they were drawn before whole solves took the
    // falling damping (the lift's figures are measured on them).
    let settings = SolverSettings {
        damping: stance_ik::CONSTANT_DAMPING,
        ..SolverSettings::default()
    };
    drawn_with(s, feet, hands, None, settings)
}

/// A posture with the feet pinned at `feet` (level 1), the wrists pulled to `hands` (level
/// 2), the root to `pelvis` when given (level 3: a crouch or a seat) and the rest posture
/// below all, solved from rest with `settings` (up to 300 iterations).
pub fn drawn_with(
    s: &Skeleton,
    feet: [DVec3; 2],
    hands: [DVec3; 2],
    pelvis: Option<DVec3>,
    settings: SolverSettings,
) -> Posture {
    let at = |name: &str| s.joint_index(name).unwrap();
    let mut tasks = vec![
        Task::position(at("l_talocrural"), DVec3::ZERO, feet[0]),
        Task::position(at("r_talocrural"), DVec3::ZERO, feet[1]),
        Task::position(at("l_radiocarpal"), DVec3::ZERO, hands[0]).at_level(2),
        Task::position(at("r_radiocarpal"), DVec3::ZERO, hands[1]).at_level(2),
    ];
    let rest_level = if let Some(pelvis) = pelvis {
        tasks.push(Task::position(at("humanoid_root"), DVec3::ZERO, pelvis).at_level(3));
        4
    } else {
        3
    };
    tasks.push(Task::rest_posture(s).at_level(rest_level).with_weight(0.05));
    let mut posture = Posture::rest(s);
    let mut solver = Solver::new(SolverSettings {
        max_iterations: 300,
        ..settings
    })
    .unwrap();
    solver.solve(s, &tasks, &mut posture).unwrap();
    posture
}

/// The postures of the round trip: standing, reaching toward the camera with both hands, one
/// arm up and one across the body, a step with a hand forward.
pub fn postures(s: &Skeleton) -> Vec<(&'static str, Posture)> {
    let rest = Frames::new(s, &Posture::rest(s));
    let at = |name: &str| rest.joint_position[s.joint_index(name).unwrap()];
    let (lf, rf) = (at("l_talocrural"), at("r_talocrural"));
    vec![
        ("standing", Posture::rest(s)),
        (
            "hands toward the camera",
            drawn(
                s,
                [lf, rf],
                [DVec3::new(0.15, 1.25, 0.5), DVec3::new(-0.2, 1.1, 0.45)],
            ),
        ),
        (
            "arm up, arm across",
            drawn(
                s,
                [lf, rf],
                [DVec3::new(0.3, 1.85, 0.1), DVec3::new(0.1, 1.1, 0.3)],
            ),
        ),
        (
            "a step, a hand forward",
            drawn(
                s,
                [
                    lf + DVec3::new(0.0, 0.0, 0.3),
                    rf - DVec3::new(0.0, 0.0, 0.15),
                ],
                [DVec3::new(0.25, 1.0, 0.55), DVec3::new(-0.3, 0.85, -0.1)],
            ),
        ),
    ]
}
