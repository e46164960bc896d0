//! Comfort: gravity torques against a hand computation and an independent static
//! Newton-Euler recursion, the cost's analytic gradient against finite differences, and the
//! comfort task: it lowers the effort of a solved posture while the levels above stay exact.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use crate::common;

use common::*;
use glam::DVec3;
use stance_hanim::scenarios::{humanoid50, standing_posture};
use stance_ik::comfort::{
    AngleBand, AngleReference, ComfortModel, DofStrength, GRAVITY, StrengthCurve, dof_torques,
    gravity_torques,
};
use stance_ik::{Dof, Frames, JointDef, Posture, Skeleton, Solver, SolverSettings, Task};

/// A horizontal two-segment arm along +X: shoulder (3 DOF) at the origin, upper arm 0.30 m
/// (2.0 kg at 0.15 m), elbow (1 DOF), forearm and hand (1.5 kg at 0.12 m past the elbow).
fn two_segment_arm() -> Skeleton {
    Skeleton::new(vec![
        JointDef::new("shoulder", None, DVec3::ZERO, &[Dof::Rx, Dof::Ry, Dof::Rz])
            .with_mass(2.0, DVec3::new(0.15, 0.0, 0.0)),
        JointDef::new(
            "elbow",
            Some("shoulder"),
            DVec3::new(0.3, 0.0, 0.0),
            &[Dof::Ry],
        )
        .with_mass(1.5, DVec3::new(0.12, 0.0, 0.0)),
    ])
    .unwrap()
}

#[test]
fn gravity_torques_of_a_horizontal_arm_match_a_hand_computation() {
    let s = two_segment_arm();
    let frames = Frames::new(&s, &Posture::rest(&s));
    let torques = gravity_torques(&frames);
    // Weights pull down (-Y) at +X: the torque of gravity about the joint is along -Z,
    // |tau| = sum of m g x.
    let g = 9.81;
    let shoulder = g * (2.0 * 0.15 + 1.5 * 0.42);
    let elbow = g * 1.5 * 0.12;
    assert!((torques[0] - DVec3::new(0.0, 0.0, -shoulder)).length() < 1e-12);
    assert!((torques[1] - DVec3::new(0.0, 0.0, -elbow)).length() < 1e-12);
    // About the DOF axes: the shoulder's z carries it all, the elbow's y (a vertical hinge)
    // nothing.
    let per_dof = dof_torques(&s, &frames);
    assert!((per_dof[2] + shoulder).abs() < 1e-12, "{per_dof:?}");
    assert!(per_dof[0].abs() < 1e-12 && per_dof[1].abs() < 1e-12);
    assert!(per_dof[3].abs() < 1e-12);
    // The forearm swung about the elbow's vertical hinge to point along -Z: its centre of
    // mass at (0.3, 0, -0.12), the elbow torque `(0, 0, -0.12) x m g`.
    let mut p = Posture::rest(&s);
    p.values_mut()[3] = std::f64::consts::FRAC_PI_2;
    let frames = Frames::new(&s, &p);
    let t = gravity_torques(&frames);
    let expected = DVec3::new(0.0, 0.0, -0.12).cross(1.5 * GRAVITY);
    assert!(
        (t[1] - expected).length() < 1e-12,
        "{:?} vs {expected:?}",
        t[1]
    );
}

/// The static Newton-Euler recursion, written independently: from the leaves up, the force
/// a joint transmits is the weight of its segment plus its children's forces, and its moment
/// about the joint centre is its segment's weight moment plus, per child, the child's moment
/// and the moment of the child's force applied at the child's joint centre.
fn newton_euler_torques(s: &Skeleton, p: &Posture) -> Vec<DVec3> {
    let frames = Frames::new(s, p);
    let joints = s.joints();
    let mut force = vec![DVec3::ZERO; joints.len()];
    let mut moment = vec![DVec3::ZERO; joints.len()];
    for j in (0..joints.len()).rev() {
        let centre = frames.point(j, joints[j].com);
        let weight = joints[j].mass * GRAVITY;
        force[j] += weight;
        moment[j] += (centre - frames.joint_position[j]).cross(weight);
        if let Some(parent) = joints[j].parent {
            let lever = frames.joint_position[j] - frames.joint_position[parent];
            let (f, m) = (force[j], moment[j]);
            force[parent] += f;
            moment[parent] += m + lever.cross(f);
        }
    }
    moment
}

#[test]
fn gravity_torques_match_newton_euler_on_random_postures() {
    let s = humanoid50().unwrap();
    let mut worst: f64 = 0.0;
    for seed in 0..20 {
        let mut r = rng(seed);
        let p = random_posture(&mut r, &s, 0.8);
        let ours = gravity_torques(&Frames::new(&s, &p));
        let theirs = newton_euler_torques(&s, &p);
        for (a, b) in ours.iter().zip(&theirs) {
            if b.length() > 1e-3 {
                worst = worst.max((*a - *b).length() / b.length());
            }
        }
    }
    assert!(worst < 0.005, "worst relative difference {worst}");
    assert!(worst < 1e-9, "the same physics: {worst}");
}

/// A model with every term on: every rotation DOF's strength, the range walls and two
/// angle bands (a segment against the world, a segment against another segment).
fn full_model(s: &Skeleton) -> ComfortModel {
    let strength = s
        .dof_kinds()
        .iter()
        .enumerate()
        .map(|(d, k)| {
            k.is_rotation().then_some(DofStrength {
                positive: StrengthCurve::constant(40.0 + d as f64),
                // An angle curve on the negative side (Anderson's form), to check its term.
                negative: StrengthCurve {
                    peak: 60.0 + 0.5 * d as f64,
                    width: 0.9,
                    centre: 0.3,
                    sign: if d % 2 == 0 { 1.0 } else { -1.0 },
                    floor: 0.1,
                },
            })
        })
        .collect();
    let j = |n: &str| s.require_joint(n).unwrap();
    ComfortModel {
        effort_weight: 1.0,
        strength,
        range_weight: 0.5,
        band_weight: 0.3,
        bands: vec![
            AngleBand {
                name: "r_upper_arm".into(),
                joint: j("r_shoulder"),
                axis: DVec3::NEG_Y,
                reference: AngleReference::Segment {
                    joint: j("vt1"),
                    axis: DVec3::NEG_Y,
                },
                edges: vec![(0.35, 1.0), (0.79, 1.0), (1.57, 1.0)],
                width: 0.05,
                ramp: 0.2,
            },
            AngleBand {
                name: "neck".into(),
                joint: j("skullbase"),
                axis: DVec3::Y,
                reference: AngleReference::World(DVec3::Y),
                edges: vec![(0.17, 1.0), (0.35, -1.0)],
                width: 0.05,
                ramp: 0.2,
            },
        ],
    }
}

#[test]
fn comfort_gradient_matches_finite_differences() {
    let s = humanoid50().unwrap();
    let model = full_model(&s);
    let n = s.dof_count();
    let mut checked = 0;
    for seed in 100..110 {
        let mut r = rng(seed);
        let p = random_posture(&mut r, &s, 0.7);
        let frames = Frames::new(&s, &p);
        let mut analytic = vec![0.0; n];
        let terms = model.gradient(&s, &frames, p.values(), &mut analytic);
        assert!(terms.effort > 0.0 && terms.bands > 0.0, "{terms:?}");
        let cost = |values: &[f64]| {
            let q = Posture::from_values(&s, values.to_vec()).unwrap();
            model.terms(&s, &Frames::new(&s, &q), values).total
        };
        for d in 0..n {
            let h = 1e-6;
            let mut plus = p.values().to_vec();
            let mut minus = p.values().to_vec();
            plus[d] += h;
            minus[d] -= h;
            let numeric = (cost(&plus) - cost(&minus)) / (2.0 * h);
            let scale = numeric.abs().max(analytic[d].abs()).max(1.0);
            assert!(
                (numeric - analytic[d]).abs() < 1e-5 * scale,
                "seed {seed}, DOF {d} ({}): analytic {} numeric {numeric}",
                s.dof_name(d),
                analytic[d]
            );
            checked += 1;
        }
    }
    assert_eq!(checked, 10 * n);
}

#[test]
fn the_range_term_grows_near_the_limits_only() {
    let s = humanoid50().unwrap();
    let model = ComfortModel {
        range_weight: 1.0,
        ..ComfortModel::default()
    };
    let knee = s.require_joint("l_knee").unwrap();
    let d = s.joints()[knee].dof_start;
    let (lo, hi) = (s.lower_limits()[d], s.upper_limits()[d]);
    let at = |q: f64| {
        let mut p = standing_posture(&s);
        // Keep every other DOF mid-range: only this one's walls count.
        for (i, v) in p.values_mut().iter_mut().enumerate() {
            let (l, h) = (s.lower_limits()[i], s.upper_limits()[i]);
            if l.is_finite() && h.is_finite() {
                *v = 0.5 * (l + h);
            }
        }
        p.values_mut()[d] = q;
        model.terms(&s, &Frames::new(&s, &p), p.values()).range
    };
    let mid = at(0.5 * (lo + hi));
    assert!(mid < 1e-6, "mid-range {mid}");
    assert!((at(hi) - 1.0).abs() < 1e-3, "at the upper limit {}", at(hi));
    assert!((at(lo) - 1.0).abs() < 1e-3, "at the lower limit {}", at(lo));
    assert!(at(hi - 0.03 * (hi - lo)) > 0.1 && at(hi - 0.15 * (hi - lo)) < 1e-3);
}

/// Feet pinned (level 1), the right wrist on a point in front (level 2); the rest free.
fn reach_problem(s: &Skeleton, start: &Posture, goal: DVec3) -> Vec<Task> {
    let frames = Frames::new(s, start);
    let j = |n: &str| s.require_joint(n).unwrap();
    let mut tasks = Vec::new();
    for foot in ["l_talocrural", "r_talocrural"] {
        tasks.push(Task::position(
            j(foot),
            DVec3::ZERO,
            frames.joint_position[j(foot)],
        ));
        tasks.push(Task::orientation(j(foot), frames.rotation(j(foot))));
    }
    tasks.push(Task::position(j("r_radiocarpal"), DVec3::ZERO, goal).at_level(2));
    tasks
}

#[test]
fn a_comfort_level_lowers_the_effort_while_the_levels_above_stay_exact() {
    let s = humanoid50().unwrap();
    let start = standing_posture(&s);
    let model = ComfortModel {
        effort_weight: 1.0,
        strength: full_model(&s).strength,
        ..ComfortModel::default()
    };
    let shoulder = Frames::new(&s, &start).joint_position[s.require_joint("r_shoulder").unwrap()];
    let mut lowered = 0;
    for (i, offset) in [
        DVec3::new(-0.1, -0.05, 0.35),
        DVec3::new(-0.2, 0.1, 0.3),
        DVec3::new(0.0, -0.2, 0.3),
        DVec3::new(-0.15, 0.2, 0.25),
    ]
    .into_iter()
    .enumerate()
    {
        let tasks = reach_problem(&s, &start, shoulder + offset);
        let mut plain = start.clone();
        Solver::default().solve(&s, &tasks, &mut plain).unwrap();
        let mut with = tasks.clone();
        with.push(Task::comfort(model.clone()).at_level(3));
        let mut comfy = start.clone();
        let report = Solver::new(SolverSettings::default())
            .unwrap()
            .solve(&s, &with, &mut comfy)
            .unwrap();
        let levels = level_residuals(&s, &with, &comfy);
        assert!(
            levels[0] < 1e-6 && levels[1] < 1e-6,
            "case {i}: levels 1-2 stay met: {levels:?} ({report:?})"
        );
        let effort = |p: &Posture| model.terms(&s, &Frames::new(&s, p), p.values()).effort;
        let (before, after) = (effort(&plain), effort(&comfy));
        assert!(
            after <= before + 1e-9,
            "case {i}: effort {before} -> {after}"
        );
        if after < 0.9 * before {
            lowered += 1;
        }
    }
    assert!(
        lowered >= 3,
        "the comfort level lowers the effort clearly: {lowered}/4"
    );
}

#[test]
fn the_report_gives_the_comfort_cost_of_the_posture_left() {
    // A comfort level waits while the levels above are unmet and keeps the cost it last had;
    // whichever iteration a solve stops at, its report weighs the posture it leaves.
    let s = humanoid50().unwrap();
    let start = standing_posture(&s);
    let model = full_model(&s);
    let wrist = s.require_joint("r_radiocarpal").unwrap();
    let goal = Frames::new(&s, &start).joint_position[wrist] + DVec3::new(0.0, 0.3, 0.3);
    let tasks = [
        Task::position(wrist, DVec3::ZERO, goal),
        Task::comfort(model.clone()).at_level(2),
    ];
    let mut waiting = 0;
    for max_iterations in 1..=30 {
        let mut p = start.clone();
        // Short task steps: the reach takes many iterations, the comfort level waiting.
        let report = Solver::new(SolverSettings {
            max_iterations,
            max_linear_step: 0.02,
            ..SolverSettings::default()
        })
        .unwrap()
        .solve(&s, &tasks, &mut p)
        .unwrap();
        let reported = report.levels[1].residual_after;
        let cost = model.terms(&s, &Frames::new(&s, &p), p.values()).total;
        assert!(
            (reported - cost).abs() <= 1e-12 * cost.max(1.0),
            "{max_iterations} iterations: reported {reported} for a posture of cost {cost}"
        );
        if !report.levels[0].met && p.values() != start.values() {
            waiting += 1;
        }
    }
    assert!(
        waiting >= 5,
        "solves stop on the way, the comfort level waiting: {waiting}"
    );
}

#[test]
fn a_comfort_task_cannot_share_its_level() {
    let s = humanoid50().unwrap();
    let start = standing_posture(&s);
    let mut tasks = reach_problem(&s, &start, DVec3::new(0.0, 1.2, 0.4));
    tasks.push(Task::comfort(ComfortModel::default()).at_level(2));
    let error = Solver::default()
        .solve(&s, &tasks, &mut start.clone())
        .unwrap_err();
    assert!(error.to_string().contains("comfort"), "{error}");
}

#[test]
fn stiffness_weights_the_pseudo_inverse() {
    use nalgebra::{DMatrix, DVector};
    let mut s = humanoid50().unwrap();
    // A stiff spine: every vertebra and the pelvis at 0.8.
    for name in ["sacroiliac", "vl5", "vt6", "vt1"] {
        if let Some(j) = s.joint_index(name) {
            for d in s.joints()[j].dof_range() {
                s.set_stiffness(d, 0.8).unwrap();
            }
        }
    }
    assert!(
        s.set_stiffness(0, 0.5).is_err(),
        "a translation has no stiffness"
    );
    assert!(
        s.set_stiffness(4, 1.0).is_err(),
        "1 would be rigid: out of range"
    );
    let start = standing_posture(&s);
    let wrist = s.require_joint("r_radiocarpal").unwrap();
    let goal = Frames::new(&s, &start).joint_position[wrist] + DVec3::new(0.05, 0.05, 0.08);
    let tasks = [Task::position(wrist, DVec3::ZERO, goal)];
    let settings = SolverSettings {
        iteration: stance_ik::Iteration::Textbook,
        trust_region: f64::INFINITY,
        enforce_limits: false,
        restarts: false,
        ..SolverSettings::default()
    };
    let mut solver = Solver::new(settings).unwrap();
    let system = solver.linear_systems(&s, &tasks, &start).unwrap().remove(0);
    let mut posture = start.clone();
    solver.iterate(&s, &tasks, &mut posture).unwrap();
    let taken =
        DVector::from_column_slice(posture.values()) - DVector::from_column_slice(start.values());
    // The textbook weighted, damped pseudo-inverse: W^-1 J^T (J W^-1 J^T + lambda^2 I)^-1 e.
    let j = system.jacobian_t.transpose();
    let w_inv = DMatrix::from_diagonal(&DVector::from_iterator(
        s.dof_count(),
        s.stiffness().iter().map(|k| 1.0 - k),
    ));
    let g = &j * &w_inv * j.transpose() + DMatrix::identity(3, 3) * (0.002 * 0.002);
    let expected = &w_inv * j.transpose() * g.try_inverse().unwrap() * &system.dx;
    assert!(
        (&taken - &expected).amax() < 1e-9,
        "weighted step off by {}",
        (&taken - &expected).amax()
    );
    // And the stiff DOF move less than with no stiffness.
    let plain = humanoid50().unwrap();
    let mut free = start.clone();
    Solver::new(settings)
        .unwrap()
        .iterate(&plain, &tasks, &mut free)
        .unwrap();
    let spine = |p: &Posture| -> f64 {
        ["vl5", "vt6", "vt1"]
            .iter()
            .filter_map(|n| s.joint_index(n))
            .flat_map(|j| s.joints()[j].dof_range())
            .map(|d| (p.values()[d] - start.values()[d]).abs())
            .sum()
    };
    assert!(
        spine(&posture) < 0.5 * spine(&free),
        "{} vs {}",
        spine(&posture),
        spine(&free)
    );
}
