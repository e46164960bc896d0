//! Several bodies in one problem ([`Bodies`]): the meet task and a body's own centre of mass
//! and balance against central differences and a hand-summed centre of mass; the joined
//! skeleton against each body placed by hand; two bodies hand in hand, each keeping its own
//! priorities.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use crate::common;

use common::*;
use glam::{DQuat, DVec3};
use rand::RngExt as _;
use stance_ik::{
    Axes, BALANCE_BAND, Bodies, BodyPlacement, Dof, Effector, Frames, JointDef, Posture, Skeleton,
    Solver, Task, TaskFeature, TaskKind,
};

/// A small humanoid: a free pelvis (six DOF), legs, a chest and arms hanging down, with
/// masses. Written here, apart from any library body.
fn little_body() -> Skeleton {
    use Dof::*;
    let ball = [Rx, Ry, Rz];
    let j = |name: &str, parent: &str, offset: [f64; 3], dofs: &[Dof], mass: f64| {
        JointDef::new(name, Some(parent), DVec3::from(offset), dofs)
            .with_mass(mass, DVec3::new(0.0, -0.1, 0.0))
    };
    Skeleton::new(vec![
        JointDef::new("pelvis", None, DVec3::new(0.0, 0.95, 0.0), &Dof::ALL)
            .with_mass(12.0, DVec3::ZERO),
        j("l_hip", "pelvis", [0.1, -0.05, 0.0], &ball, 8.0),
        j("l_knee", "l_hip", [0.0, -0.42, 0.0], &[Rx], 4.0),
        j("l_ankle", "l_knee", [0.0, -0.42, 0.0], &[Rx, Rz], 1.0),
        j("r_hip", "pelvis", [-0.1, -0.05, 0.0], &ball, 8.0),
        j("r_knee", "r_hip", [0.0, -0.42, 0.0], &[Rx], 4.0),
        j("r_ankle", "r_knee", [0.0, -0.42, 0.0], &[Rx, Rz], 1.0),
        j("chest", "pelvis", [0.0, 0.25, 0.0], &ball, 20.0),
        j("l_shoulder", "chest", [0.18, 0.22, 0.0], &ball, 2.0),
        j("l_elbow", "l_shoulder", [0.0, -0.3, 0.0], &[Rx, Ry], 1.5),
        j("l_wrist", "l_elbow", [0.0, -0.27, 0.0], &[Rx, Rz], 0.5),
        j("r_shoulder", "chest", [-0.18, 0.22, 0.0], &ball, 2.0),
        j("r_elbow", "r_shoulder", [0.0, -0.3, 0.0], &[Rx, Ry], 1.5),
        j("r_wrist", "r_elbow", [0.0, -0.27, 0.0], &[Rx, Rz], 0.5),
    ])
    .unwrap()
}

fn placed(x: f64, turn_degrees: f64) -> BodyPlacement {
    BodyPlacement {
        rotation: DQuat::from_rotation_y(turn_degrees.to_radians()),
        translation: DVec3::new(x, 0.0, 0.0),
    }
}

/// The centre of mass of the subtree from `root`, summed by hand from the segments' places.
fn summed_center_of_mass(s: &Skeleton, frames: &Frames, root: usize) -> DVec3 {
    let (mut moment, mut mass) = (DVec3::ZERO, 0.0);
    for (j, joint) in s.joints().iter().enumerate() {
        if s.is_ancestor_or_self(root, j) {
            moment += joint.mass * frames.point(j, joint.com);
            mass += joint.mass;
        }
    }
    moment / mass
}

/// The meet task and a body's centre of mass and balance: their Jacobians against central
/// differences of their features, their errors' derivatives against minus the Jacobian, and
/// the body's centre of mass against a sum by hand (the balance cases outside the polygon
/// counted, so that the check cannot pass on empty rows alone).
#[test]
fn meet_and_a_bodys_centre_of_mass_match_central_differences() {
    let mut r = rng(31);
    let mut solver = Solver::default();
    let mut balance_outside = 0;
    for case in 0..60 {
        let s = random_skeleton(&mut r, 9, false);
        let p = random_posture(&mut r, &s, 1.2);
        let frames = Frames::new(&s, &p);
        let joint = |r: &mut rand::rngs::StdRng| r.random_range(0..s.joint_count());
        let root = (0..20)
            .map(|_| joint(&mut r))
            .find(|&j| j != 0 && s.body_mass(j) > 0.0)
            .unwrap_or(0);
        let body = Some(root);
        let task = match case % 3 {
            0 => {
                let (a, b) = (joint(&mut r), joint(&mut r));
                let mut t = Task::meet(a, vec3(&mut r, 0.2), b, vec3(&mut r, 0.2));
                t = t.with_axes(random_axes(&mut r));
                t
            }
            1 => Task::new(TaskKind::CenterOfMass {
                axes: random_axes(&mut r),
                target: vec3(&mut r, 1.0),
                body,
            }),
            _ => Task::new(TaskKind::Balance {
                support: (0..3)
                    .map(|_| Effector {
                        joint: joint(&mut r),
                        point: vec3(&mut r, 0.3),
                    })
                    .collect(),
                margin: 0.01,
                body,
            }),
        };
        if let TaskKind::CenterOfMass { .. } = task.kind {
            let TaskFeature::Vector(c) = task.feature(&s, &frames, p.values()) else {
                panic!("a vector")
            };
            let want = summed_center_of_mass(&s, &frames, root);
            let picked: Vec<f64> = (0..3)
                .filter(|&i| task.rows() == 3 || axes_of(&task).has(i))
                .map(|i| want[i])
                .collect();
            for (got, want) in c.iter().zip(&picked) {
                assert!((got - want).abs() < 1e-12, "{got} against {want}");
            }
        }
        if let TaskKind::Balance { .. } = task.kind
            && let TaskFeature::Vector(v) = task.feature(&s, &frames, p.values())
            && (-BALANCE_BAND..=0.0).contains(&v[0])
        {
            continue;
        }
        let analytic = solver
            .linear_systems(&s, std::slice::from_ref(&task), &p)
            .unwrap()[0]
            .jacobian_t
            .transpose();
        let numeric = finite_difference_jacobian(&s, &p, &task);
        assert!(
            (&analytic - &numeric).amax() < 1e-6,
            "{:?}\n{analytic}\n{numeric}",
            task.kind
        );
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
        if matches!(task.kind, TaskKind::Balance { .. }) && analytic.amax() > 0.0 {
            balance_outside += 1;
        }
    }
    assert!(balance_outside >= 4, "{balance_outside} balance cases");
}

fn axes_of(task: &Task) -> Axes {
    match &task.kind {
        TaskKind::CenterOfMass { axes, .. } | TaskKind::Meet { axes, .. } => *axes,
        _ => Axes::XYZ,
    }
}

/// Every joint of the joined skeleton stands where its body, posed alone and then placed by
/// hand (turned and moved), puts it; splitting the joined posture gives each body's back.
#[test]
fn joined_bodies_stand_where_each_body_placed_by_hand_stands() {
    let body = little_body();
    let mut r = rng(5);
    let places = [placed(-0.6, 90.0), placed(0.7, -135.0), placed(0.0, 0.0)];
    let postures: Vec<Posture> = (0..3).map(|_| random_posture(&mut r, &body, 0.8)).collect();
    let bodies = Bodies::new(&places.map(|p| (&body, p))).unwrap();
    let joined = bodies
        .posture(&postures.iter().collect::<Vec<_>>())
        .unwrap();
    let frames = Frames::new(bodies.skeleton(), &joined);
    for (b, (posture, place)) in postures.iter().zip(&places).enumerate() {
        let alone = Frames::new(&body, posture);
        for j in 0..body.joint_count() {
            let want = place.point(alone.joint_position[j]);
            let got = frames.joint_position[bodies.joint(b, j).unwrap()];
            assert!((got - want).length() < 1e-12, "body {b} joint {j}");
            let turn = place.rotation * alone.rotation(j);
            let there = frames.rotation(bodies.joint(b, j).unwrap());
            assert!(turn.angle_between(there) < 1e-6);
        }
    }
    for (back, posture) in bodies.split(&joined).unwrap().iter().zip(&postures) {
        let alone = Frames::new(&body, posture);
        let again = Frames::new(&body, back);
        for j in 0..body.joint_count() {
            assert!((alone.joint_position[j] - again.joint_position[j]).length() < 1e-12);
        }
    }
    // A turned body needs a free root.
    let fixed = Skeleton::new(vec![JointDef::new("a", None, DVec3::ZERO, &[Dof::Ry])]).unwrap();
    assert!(Bodies::new(&[(&fixed, placed(1.0, 0.0))]).is_err());
    assert!(Bodies::new(&[(&fixed, BodyPlacement::default())]).is_ok());
}

/// Each body's own tasks, in its own frame: both feet pinned where they stand (level 1), its
/// balance over its own feet (level 2).
fn own_tasks(s: &Skeleton, posture: &Posture) -> Vec<Task> {
    let frames = Frames::new(s, posture);
    let mut tasks = Vec::new();
    let mut support = Vec::new();
    for foot in ["l_ankle", "r_ankle"] {
        let j = s.joint_index(foot).unwrap();
        tasks.push(Task::position(j, DVec3::ZERO, frames.joint_position[j]).at_level(1));
        for corner in [
            [-0.05, -0.08, -0.06],
            [0.05, -0.08, -0.06],
            [0.0, -0.08, 0.16],
        ] {
            support.push(Effector {
                joint: j,
                point: DVec3::from(corner),
            });
        }
    }
    tasks.push(Task::balance(support, 0.02).at_level(2));
    tasks
}

/// Two bodies facing each other 0.9 m apart, each with its feet pinned and its balance, the
/// first's right wrist in the second's left at level 3: solved as one problem, the wrists
/// meet within 1 mm, every foot holds, and each body's centre of mass (summed by hand from
/// its own posture, placed) stays over its own feet. Put 4 m apart the hands cannot meet:
/// the meet gives way and the feet and balance still hold.
#[test]
fn two_bodies_hand_in_hand_keep_their_own_priorities() {
    let body = little_body();
    for (gap, reachable) in [(0.9, true), (4.0, false)] {
        let places = [placed(-gap / 2.0, 90.0), placed(gap / 2.0, -90.0)];
        let rest = Posture::rest(&body);
        let bodies = Bodies::new(&places.map(|p| (&body, p))).unwrap();
        let mut tasks = Vec::new();
        for b in 0..2 {
            for task in own_tasks(&body, &rest) {
                tasks.push(bodies.task(b, &task).unwrap());
            }
        }
        let (rw, lw) = (
            body.joint_index("r_wrist").unwrap(),
            body.joint_index("l_wrist").unwrap(),
        );
        tasks.push(
            Task::meet(
                bodies.joint(0, rw).unwrap(),
                DVec3::ZERO,
                bodies.joint(1, lw).unwrap(),
                DVec3::ZERO,
            )
            .at_level(3),
        );
        let mut joined = bodies.posture(&[&rest, &rest]).unwrap();
        let report = Solver::default()
            .solve(bodies.skeleton(), &tasks, &mut joined)
            .unwrap();
        let postures = bodies.split(&joined).unwrap();
        let frames: Vec<Frames> = postures.iter().map(|p| Frames::new(&body, p)).collect();
        let rest_frames = Frames::new(&body, &rest);
        for (b, f) in frames.iter().enumerate() {
            for foot in ["l_ankle", "r_ankle"] {
                let j = body.joint_index(foot).unwrap();
                let moved = (f.joint_position[j] - rest_frames.joint_position[j]).length();
                assert!(
                    moved < 1e-4,
                    "body {b}'s {foot} moved {moved} m (gap {gap})"
                );
            }
            // Over its own feet: between the ankles' x, within the soles' z.
            let c = summed_center_of_mass(&body, f, 0);
            assert!(
                c.x.abs() < 0.1 && (-0.06..0.16).contains(&c.z),
                "body {b}: {c}"
            );
        }
        let hands = (places[0].point(frames[0].joint_position[rw])
            - places[1].point(frames[1].joint_position[lw]))
        .length();
        if reachable {
            assert!(hands < 1e-3, "hands {hands} m apart: {report:?}");
            assert_eq!(report.gave_way, None);
        } else {
            assert!(hands > 1.0, "hands {hands} m apart");
            assert_eq!(report.gave_way, Some(3), "{report:?}");
        }
    }
}
