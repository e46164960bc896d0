//! Load shares, the 15 % flag and the order of the highest loads against hand computations
//! on a body whose torques are `m g d`.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use glam::DVec3;
use stance_ik::{Dof, JointDef, Posture, Skeleton};

use super::*;
use crate::strength::aligned_axes;

/// Two arms on a trunk of 59.5 kg: 70 kg in all, so the strengths are the 70 kg values of
/// `crate::strength` unscaled. Each arm hangs along -y from its shoulder: upper arm 0.3 m
/// (2 kg at 0.15 m), forearm 0.25 m (1.5 kg at 0.125 m past the elbow), hand 0.08 m past
/// the wrist: 0.5 kg on the left, 3 kg on the right (a hand holding a load).
fn two_arms() -> Skeleton {
    let arm = |side: &str, x: f64, hand: f64| {
        let name = |joint: &str| format!("{side}_{joint}");
        vec![
            JointDef::new(
                name("shoulder"),
                Some("humanoid_root"),
                DVec3::new(x, 0.4, 0.0),
                &[Dof::Rx, Dof::Ry, Dof::Rz],
            )
            .with_mass(2.0, DVec3::new(0.0, -0.15, 0.0)),
            JointDef::new(
                name("elbow"),
                Some(&name("shoulder")),
                DVec3::new(0.0, -0.3, 0.0),
                &[Dof::Rx, Dof::Ry],
            )
            .with_mass(1.5, DVec3::new(0.0, -0.125, 0.0)),
            JointDef::new(
                name("radiocarpal"),
                Some(&name("elbow")),
                DVec3::new(0.0, -0.25, 0.0),
                &[Dof::Rx, Dof::Rz],
            )
            .with_mass(hand, DVec3::new(0.0, -0.08, 0.0)),
        ]
    };
    let mut joints = vec![
        JointDef::new("humanoid_root", None, DVec3::new(0.0, 1.0, 0.0), &[])
            .with_mass(59.5, DVec3::ZERO),
    ];
    joints.extend(arm("l", 0.2, 0.5));
    joints.extend(arm("r", -0.2, 3.0));
    Skeleton::new(joints).unwrap()
}

/// The posture with each shoulder flexed (`-rx`) by the given angles (degrees): the arm
/// swings forward, each centre of mass `d sin(angle)` in front of its joint.
fn flexed(s: &Skeleton, left_deg: f64, right_deg: f64) -> Posture {
    let mut p = Posture::rest(s);
    for (joint, deg) in [("l_shoulder", left_deg), ("r_shoulder", right_deg)] {
        let j = s.joint_index(joint).unwrap();
        p.values_mut()[s.joints()[j].rotation_dof[0].unwrap()] = -deg.to_radians();
    }
    p
}

fn report(s: &Skeleton, p: &Posture) -> ComfortReport {
    comfort_report(s, &aligned_axes(s), p, &ComfortSettings::default())
}

fn load<'a>(r: &'a ComfortReport, joint: &str) -> &'a JointLoad {
    r.loads.iter().find(|l| l.joint == joint).unwrap()
}

#[test]
fn arms_held_out_horizontally_load_each_joint_by_m_g_d() {
    // Catches a share taken against the wrong curve (the extensors for a flexing load), a
    // strength not scaled to the body mass, a torque not reduced to the DOF axes, and loads
    // sorted by torque or the wrong way round.
    //
    // Hand computation, both arms straight forward (90 deg of flexion), every lever arm the
    // horizontal distance along +z; gravity pulls each arm down in front, so the torque is
    // about +x and the flexors (-rx) hold it. The body weighs 70 kg: strengths unscaled.
    // Right (hand 3 kg):
    //   shoulder 9.81 * (2 * 0.15 + 1.5 * 0.425 + 3 * 0.63) = 9.81 * 2.8275 = 27.7378 N m,
    //     / 89.9 (shoulder flexion) = 0.30854;
    //   elbow 9.81 * (1.5 * 0.125 + 3 * 0.33) = 9.81 * 1.1775 = 11.5513 N m,
    //     / 54.6 (elbow flexion, 0.78 * 70) = 0.21156;
    //   wrist 9.81 * 3 * 0.08 = 2.3544 N m, / 11.0 (radial deviation, -rx) = 0.21404.
    // Left (hand 0.5 kg):
    //   shoulder 9.81 * (0.3 + 0.6375 + 0.315) = 9.81 * 1.2525 = 12.2870 N m, / 89.9 =
    //     0.13667;
    //   elbow 9.81 * (0.1875 + 0.165) = 3.4580 N m, / 54.6 = 0.06333;
    //   wrist 9.81 * 0.5 * 0.08 = 0.3924 N m, / 11.0 = 0.03567.
    // Highest share first: r_shoulder, r_radiocarpal, r_elbow, l_shoulder, l_elbow (the
    // right wrist before the right elbow although its torque is a fifth); l_radiocarpal is
    // sixth. Flagged above 0.15: the three right joints.
    let s = two_arms();
    assert!((s.total_mass() - 70.0).abs() < 1e-12);
    let r = report(&s, &flexed(&s, 90.0, 90.0));
    let expected = [
        ("r_shoulder", 27.7378, 0.30854),
        ("r_radiocarpal", 2.3544, 0.21404),
        ("r_elbow", 11.5513, 0.21156),
        ("l_shoulder", 12.2870, 0.13667),
        ("l_elbow", 3.4580, 0.06333),
        ("l_radiocarpal", 0.3924, 0.03567),
    ];
    for (joint, torque, share) in expected {
        let l = load(&r, joint);
        assert!((l.torque_nm - torque).abs() < 1e-4, "{joint}: {l:?}");
        let got = l.share.unwrap();
        assert!(
            (got - share).abs() < 1e-5,
            "{joint}: share {got}, by hand {share}"
        );
        assert_eq!(l.flagged, share > 0.15, "{joint}: {l:?}");
    }
    let top: Vec<&str> = r.highest(5).iter().map(|l| l.joint.as_str()).collect();
    assert_eq!(
        top,
        [
            "r_shoulder",
            "r_radiocarpal",
            "r_elbow",
            "l_shoulder",
            "l_elbow"
        ],
        "{:#?}",
        r.loads
    );
    assert_eq!(r.loads.len(), 6, "the root has no rotation DOF");
    // The effort is the sum of the squared shares of the DOF with a strength (only the rx
    // DOF are loaded): 0.30854^2 + 0.21404^2 + 0.21156^2 + 0.13667^2 + 0.06333^2 +
    // 0.03567^2 = 0.09520 + 0.04581 + 0.04476 + 0.01868 + 0.00401 + 0.00127 = 0.20973.
    assert!(
        (r.terms.effort - 0.20973).abs() < 1e-4,
        "{}",
        r.terms.effort
    );
}

#[test]
fn a_load_is_flagged_just_above_fifteen_percent_and_not_just_below() {
    // Catches a flag at another threshold, at or above rather than above, or on the torque
    // instead of the share.
    //
    // Hand computation: the right shoulder flexed by a, the left arm hanging (no load). The
    // right shoulder's share is 0.30854 sin(a) (every lever arm times sin a):
    //   a = 28.9 deg: sin = 0.48328, share 0.14911 (not flagged);
    //   a = 29.2 deg: sin = 0.48786, share 0.15052 (flagged).
    // The elbow (0.21156 sin a = 0.1022 / 0.1032) and wrist (0.21404 sin a = 0.1034 /
    // 0.1044) stay below.
    let s = two_arms();
    for (degrees, share, flagged) in [(28.9, 0.14911, false), (29.2, 0.15052, true)] {
        let r = report(&s, &flexed(&s, 0.0, degrees));
        let shoulder = load(&r, "r_shoulder");
        let got = shoulder.share.unwrap();
        assert!(
            (got - share).abs() < 1e-5,
            "{degrees} deg: share {got}, by hand {share}"
        );
        assert_eq!(shoulder.flagged, flagged, "{degrees} deg: {shoulder:?}");
        let others: Vec<&str> = r
            .loads
            .iter()
            .filter(|l| l.flagged && l.joint != "r_shoulder")
            .map(|l| l.joint.as_str())
            .collect();
        assert!(others.is_empty(), "{degrees} deg: {others:?}");
        assert_eq!(r.loads[0].joint, "r_shoulder");
        // The hanging left arm carries nothing.
        assert!(load(&r, "l_shoulder").torque_nm < 1e-12);
    }
}
