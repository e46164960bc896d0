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
    // The T-pose elbow flexes about world y.
    let flexion = s.joints()[elbow].rotation_dof[Dof::Ry.axis_index()].unwrap();
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
    let as_rest_frame = spec.to_task(s, &[]).unwrap();
    assert!(
        peak(&as_rest_frame.kind) < 20.0,
        "the skeleton alone cannot know its axes"
    );
}
