//! Skeleton validation, forward kinematics, task Jacobians against finite differences.

// A test crate: on wasm32 `#[test]` becomes `wasm_bindgen_test`, which clippy does not treat
// as a test, and fixture helpers panic on broken fixtures on purpose.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use crate::common;

use common::*;
use glam::{DQuat, DVec3};
use stance_ik::{
    BALANCE_BAND, Dof, Frames, IkError, JointDef, Posture, Skeleton, Solver, Task, TaskFeature,
    TaskKind,
};

fn j(name: &str, parent: Option<&str>) -> JointDef {
    JointDef::new(name, parent, DVec3::Y, &[Dof::Rx])
}

#[test]
fn skeleton_rejects_bad_trees() {
    assert_eq!(
        Skeleton::new(vec![j("a", None), j("a", Some("a"))]),
        Err(IkError::DuplicateJoint("a".into()))
    );
    assert!(matches!(
        Skeleton::new(vec![j("a", None), j("b", Some("zz"))]),
        Err(IkError::UnknownParent { .. })
    ));
    assert!(matches!(
        Skeleton::new(vec![j("a", None), j("b", Some("c")), j("c", Some("b"))]),
        Err(IkError::Cycle(_))
    ));
    assert!(matches!(
        Skeleton::new(vec![j("b", Some("c")), j("c", Some("b"))]),
        Err(IkError::Cycle(_))
    ));
    assert!(matches!(
        Skeleton::new(vec![j("a", None), j("b", None)]),
        Err(IkError::RootCount(2))
    ));
    assert_eq!(Skeleton::new(vec![]), Err(IkError::Empty));
    let dup = JointDef::new("a", None, DVec3::ZERO, &[Dof::Rx, Dof::Rx]);
    assert!(matches!(
        Skeleton::new(vec![dup]),
        Err(IkError::DuplicateDof { .. })
    ));
    let bad_limit = j("a", None).with_limit(Dof::Rx, 1.0, -1.0);
    assert!(matches!(
        Skeleton::new(vec![bad_limit]),
        Err(IkError::BadLimit { .. })
    ));
    let nan = JointDef::new("a", None, DVec3::new(f64::NAN, 0.0, 0.0), &[]);
    assert!(matches!(
        Skeleton::new(vec![nan]),
        Err(IkError::NotFinite { .. })
    ));
}

#[test]
fn skeleton_sorts_parents_first() {
    let s = Skeleton::new(vec![j("c", Some("b")), j("b", Some("a")), j("a", None)]).unwrap();
    let names: Vec<_> = s.joints().iter().map(|j| j.name.as_str()).collect();
    assert_eq!(names, ["a", "b", "c"]);
    assert_eq!(s.joints()[2].parent, Some(1));
    assert_eq!(s.chain_dofs(2), vec![0, 1, 2]);
}

#[test]
fn forward_kinematics_of_a_hinge_chain() {
    let s = Skeleton::new(vec![
        JointDef::new("a", None, DVec3::ZERO, &[Dof::Rz]),
        JointDef::new("b", Some("a"), DVec3::X, &[Dof::Rz]),
        JointDef::new("c", Some("b"), DVec3::X, &[]),
    ])
    .unwrap();
    let p = Posture::from_values(
        &s,
        vec![std::f64::consts::FRAC_PI_2, -std::f64::consts::FRAC_PI_2],
    )
    .unwrap();
    let f = Frames::new(&s, &p);
    assert!((f.joint_position[1] - DVec3::Y).length() < 1e-12);
    assert!((f.joint_position[2] - DVec3::new(1.0, 1.0, 0.0)).length() < 1e-12);
}

#[test]
fn rotations_round_trip_and_wrap() {
    let mut r = rng(1);
    let s = random_skeleton(&mut r, 6, false);
    let q: Vec<DQuat> = (0..s.joint_count())
        .map(|_| DQuat::from_scaled_axis(vec3(&mut r, 1.5)))
        .collect();
    let p = Posture::from_rotations(&s, DVec3::new(0.1, 0.2, 0.3), &q).unwrap();
    for (i, joint) in s.joints().iter().enumerate() {
        if joint.rotation_dof.iter().all(Option::is_some) {
            assert!(p.local_rotation(&s, i).angle_between(q[i]) < 1e-9);
        }
    }
    // A free ball joint past pi is re-wrapped to the same rotation.
    let ball = Skeleton::new(vec![JointDef::new(
        "a",
        None,
        DVec3::ZERO,
        &[Dof::Rx, Dof::Ry, Dof::Rz],
    )])
    .unwrap();
    let mut p = Posture::from_values(&ball, vec![4.0, 0.0, 0.0]).unwrap();
    let before = p.local_rotation(&ball, 0);
    p.normalize(&ball);
    assert!(p.values()[0].abs() <= std::f64::consts::PI);
    assert!(p.local_rotation(&ball, 0).angle_between(before) < 1e-12);
}

#[test]
fn every_task_jacobian_matches_finite_differences() {
    let mut r = rng(2);
    let mut solver = Solver::default();
    let mut checked = 0;
    for _ in 0..40 {
        let s = random_skeleton(&mut r, 8, false);
        let p = random_posture(&mut r, &s, 1.2);
        for _ in 0..6 {
            let task = random_task(&mut r, &s, 1).with_weight(1.0);
            let systems = solver
                .linear_systems(&s, std::slice::from_ref(&task), &p)
                .unwrap();
            let analytic = systems[0].jacobian_t.transpose();
            let numeric = finite_difference_jacobian(&s, &p, &task);
            let err = (&analytic - &numeric).amax();
            assert!(
                err < 1e-6,
                "{:?}: |J - FD| = {err}\n{analytic}\n{numeric}",
                task.kind
            );
            checked += 1;
        }
    }
    assert_eq!(checked, 240);
}

/// Every task's error `e` (the desired change the solver drives to zero) has the derivative
/// `-J`: checked by central differences on every kind. The orientation error is the log of
/// the remaining rotation, whose derivative is `-J` only to first order in the error, so its
/// target is put within 1e-6 rad of the current orientation; every other kind is exact at any
/// error.
#[test]
fn every_task_error_matches_finite_differences() {
    let mut r = rng(12);
    let mut solver = Solver::default();
    let mut kinds = std::collections::HashSet::new();
    let mut balance_outside = 0;
    for _ in 0..60 {
        let s = random_skeleton(&mut r, 8, false);
        let p = random_posture(&mut r, &s, 1.2);
        let frames = Frames::new(&s, &p);
        for _ in 0..6 {
            let mut task = random_task(&mut r, &s, 1).with_weight(1.0);
            if let TaskKind::Orientation { joint, target } = &mut task.kind {
                let near = DQuat::from_scaled_axis(vec3(&mut r, 1e-6));
                *target = near * frames.rotation(*joint);
            }
            if let TaskKind::Balance { .. } = task.kind
                && let TaskFeature::Vector(v) = task.feature(&s, &frames, p.values())
                && (-BALANCE_BAND..=0.0).contains(&v[0])
            {
                // Inside the activation band the row holds with a zero error.
                continue;
            }
            let analytic = solver
                .linear_systems(&s, std::slice::from_ref(&task), &p)
                .unwrap()[0]
                .jacobian_t
                .transpose();
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
                    let want = -analytic[(row, d)];
                    assert!(
                        (numeric - want).abs() < 2e-6,
                        "{:?}: de/dq[{row},{d}] = {numeric}, -J = {want}",
                        task.kind
                    );
                }
            }
            kinds.insert(std::mem::discriminant(&task.kind));
            if matches!(task.kind, TaskKind::Balance { .. }) && analytic.amax() > 0.0 {
                balance_outside += 1;
            }
        }
    }
    assert!(
        balance_outside >= 5,
        "{balance_outside} balance cases outside the polygon"
    );
    // position, orientation, gaze, centre of mass, direction, balance, posture
    assert_eq!(kinds.len(), 7, "every task kind was checked");
}

#[test]
fn jacobian_is_zero_outside_the_chain() {
    let mut r = rng(3);
    let s = random_skeleton(&mut r, 12, false);
    let p = random_posture(&mut r, &s, 1.0);
    let mut solver = Solver::default();
    for joint in 0..s.joint_count() {
        let task = Task::position(joint, DVec3::X, DVec3::ONE);
        let jt = &solver.linear_systems(&s, &[task], &p).unwrap()[0].jacobian_t;
        for d in 0..s.dof_count() {
            if !s.is_ancestor_or_self(s.dof_joint(d), joint) {
                assert_eq!(jt.row(d).amax(), 0.0);
            }
        }
    }
}

#[test]
fn center_of_mass_is_mass_weighted() {
    let s = Skeleton::new(vec![
        JointDef::new("a", None, DVec3::ZERO, &[Dof::Rz]).with_mass(1.0, DVec3::ZERO),
        JointDef::new("b", Some("a"), DVec3::X * 2.0, &[]).with_mass(3.0, DVec3::Y),
    ])
    .unwrap();
    let f = Frames::new(&s, &Posture::rest(&s));
    assert!((f.center_of_mass() - DVec3::new(1.5, 0.75, 0.0)).length() < 1e-12);
}

/// A posture carried onto another skeleton goes joint by joint and DOF by DOF by name: the
/// same joint's same DOF gets the value wherever it sits in either skeleton's DOF order;
/// what the source lacks stays at rest, and what the target lacks is dropped.
#[test]
fn a_posture_is_carried_over_by_joint_and_dof_name() {
    let source = Skeleton::new(vec![
        JointDef::new("root", None, DVec3::ZERO, &[Dof::Ry]),
        JointDef::new("a", Some("root"), DVec3::Y, &[Dof::Rx, Dof::Rz]),
        JointDef::new("only_here", Some("a"), DVec3::Y, &[Dof::Rx]),
    ])
    .unwrap();
    // Other joint order, other DOF order, a joint the source lacks, a DOF it lacks.
    let target = Skeleton::new(vec![
        JointDef::new("root", None, DVec3::ZERO, &[Dof::Ry]),
        JointDef::new("new", Some("root"), DVec3::X, &[Dof::Ry]),
        JointDef::new("a", Some("new"), DVec3::Y, &[Dof::Rz, Dof::Ry, Dof::Rx]),
    ])
    .unwrap();
    let posture = Posture::from_values(&source, vec![0.3, 0.5, -0.7, 1.1]).unwrap();
    let carried = Posture::carried_over(&target, &source, &posture);
    let a = &target.joints()[target.joint_index("a").unwrap()];
    let value = |dof: Dof| {
        let k = a.dofs.iter().position(|d| *d == dof).unwrap();
        carried.values()[a.dof_start + k]
    };
    assert_eq!(carried.values()[0], 0.3, "root ry");
    assert_eq!(value(Dof::Rx), 0.5);
    assert_eq!(value(Dof::Rz), -0.7);
    assert_eq!(value(Dof::Ry), 0.0, "a DOF the source lacks stays at rest");
    let new = &target.joints()[target.joint_index("new").unwrap()];
    assert_eq!(carried.values()[new.dof_start], 0.0);
    assert_eq!(carried.values().len(), target.dof_count());
}
