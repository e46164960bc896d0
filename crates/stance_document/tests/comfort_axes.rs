//! A comfort task on an avatar reads the body's own anatomical axes: on a T-pose body the
//! elbow flexes about world y, and its strength there must be the elbow flexors', not the
//! forearm's pronators' (what a skeleton taken as the H-Anim rest frame would give).

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use glam::DVec3;
use stance_document::TaskSpec;
use stance_hanim::{
    LevelOfArticulation, Mapping, SkeletonOptions, SourceJoint, build_skeleton, humanoid_joints,
};
use stance_ik::{Dof, TaskKind};

/// The LOA1 default joints with both arms stretched out sideways (a T-pose).
fn t_pose_joints() -> Vec<SourceJoint> {
    let loa1 = humanoid_joints(LevelOfArticulation::Loa1);
    let centre = |name: &str| {
        loa1.iter()
            .find(|j| j.definition.name == name)
            .map(|j| j.rest_centre)
            .unwrap()
    };
    loa1.iter()
        .map(|j| {
            let name = j.definition.name;
            let mut position = j.rest_centre;
            for (side, sign) in [("l_", 1.0), ("r_", -1.0)] {
                if name == format!("{side}elbow") || name == format!("{side}radiocarpal") {
                    let shoulder = centre(&format!("{side}shoulder"));
                    let reach = (shoulder - position).length();
                    position = shoulder + DVec3::new(sign * reach, 0.0, 0.0);
                }
            }
            SourceJoint {
                name: name.into(),
                parent: j.parent,
                position,
            }
        })
        .collect()
}

#[test]
fn a_comfort_task_on_a_t_pose_body_gives_the_elbow_its_flexors() {
    let joints = t_pose_joints();
    let positions: Vec<DVec3> = joints.iter().map(|j| j.position).collect();
    let body = build_skeleton(
        &Mapping::auto(&joints, &[], false),
        &positions,
        &SkeletonOptions {
            loa: LevelOfArticulation::Loa1,
            ..Default::default()
        },
    )
    .unwrap();
    let s = &body.skeleton;
    let elbow = s.joint_index("l_elbow").unwrap();
    // The T-pose body is built in the standard pose: its elbow flexes about world x.
    let flexion = s.joints()[elbow].rotation_dof[Dof::Rx.axis_index()].unwrap();
    let peak = |kind: &TaskKind| match kind {
        TaskKind::Comfort { model } => {
            let strength = model.strength[flexion].unwrap();
            strength.positive.at(0.0).0.max(strength.negative.at(0.0).0)
        }
        other => panic!("not a comfort task: {other:?}"),
    };
    let spec = TaskSpec::comfort();
    let on_body = spec.to_task_on(&body, &[]).unwrap();
    // Elbow flexors hold about 0.78 N m per kg of a 70 kg body (55 N m); pronators 13 N m.
    let flexors = peak(&on_body.kind);
    assert!(flexors > 40.0, "{flexors} N m");
    // Its joint frames are the standard pose's: the skeleton alone gives the same axes.
    let as_rest_frame = spec.to_task(s, &[]).unwrap();
    assert!(peak(&as_rest_frame.kind) > 40.0);
}

/// A document written before `rest` (values relative to the avatar's own rest) made on a
/// T-pose avatar, its arm lowered by a quarter turn about the body's front axis and the
/// forearm bent about world y: converted, the standard pose's arm points where the T-pose arm
/// did (straight down), and so does the forearm.
#[test]
fn an_old_document_made_on_a_t_pose_avatar_keeps_its_pose() {
    let joints = t_pose_joints();
    let positions: Vec<DVec3> = joints.iter().map(|j| j.position).collect();
    let body = build_skeleton(
        &Mapping::auto(&joints, &[], false),
        &positions,
        &SkeletonOptions::default(),
    )
    .unwrap();
    let old = stance_document::Document::from_json(
        r#"{"avatar": {"url": "https://example.org/t.glb"},
            "posture": {"l_shoulder": {"rz": -1.5707963267948966}, "l_elbow": {"ry": 0.5}}}"#,
    )
    .unwrap();
    assert_eq!(old.rest, stance_document::PostureRest::Avatar);
    let new = old.in_standard_rest(&body);
    assert_eq!(new.rest, stance_document::PostureRest::Standard);
    let rotation = |joint: &str| {
        let v = new.posture.joints.get(joint).copied().unwrap_or_default();
        let r = |dof: Dof| v.get(dof).unwrap_or(0.0);
        glam::DQuat::from_scaled_axis(DVec3::new(r(Dof::Rx), r(Dof::Ry), r(Dof::Rz)))
    };
    // The old meaning, by hand: the T-pose arm (+x) turned by the old values.
    let lowered = glam::DQuat::from_rotation_z(-std::f64::consts::FRAC_PI_2);
    let old_upper = lowered * DVec3::X;
    let old_fore = lowered * glam::DQuat::from_rotation_y(0.5) * DVec3::X;
    // The new meaning: the standard pose's bones (the default centres) turned by the values.
    let centre = |name: &str| stance_hanim::scenarios::hanim_centre(name).unwrap();
    let upper = (centre("l_elbow") - centre("l_shoulder")).normalize();
    let fore = (centre("l_radiocarpal") - centre("l_elbow")).normalize();
    let shoulder = rotation("l_shoulder");
    let elbow = shoulder * rotation("l_elbow");
    assert!((shoulder * upper).angle_between(old_upper) < 1e-6);
    // The elbow has no twist DOF: the projection onto its two leaves a small error.
    let off = (elbow * fore).angle_between(old_fore).to_degrees();
    assert!(off < 2.0, "{off} degrees");
    // A document that says `"rest": "standard"` is kept as it is.
    let text = new.to_json(false);
    assert!(text.contains(r#""rest":"standard""#), "{text}");
    let again = stance_document::Document::from_json(&text).unwrap();
    assert_eq!(again.in_standard_rest(&body), again);
}
