#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
//! BVH import: dialect quirks, units, axes and rig namings, each against hand computations.

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use crate::common;

use common::{MIXAMO, Names, humanoid};
use glam::{DQuat, DVec3};
use stance_hanim::LevelOfArticulation;
use stance_motion::{BvhLimits, Clip, EulerOrder, read_bvh};

fn read(text: &str) -> Clip {
    read_bvh(text.as_bytes(), "t", &BvhLimits::default()).unwrap()
}

/// The angle between two rotations, precise near zero.
fn angle(a: DQuat, b: DQuat) -> f64 {
    let d = a.conjugate() * b;
    2.0 * DVec3::new(d.x, d.y, d.z).length().atan2(d.w.abs())
}

fn close(a: DVec3, b: DVec3, eps: f64) {
    assert!((a - b).length() < eps, "{a} != {b}");
}

/// A chain root > a > b > end with no human names (kept as is: no axes or unit change).
fn chain(a_channels: &str, b_channels: &str, row: &str) -> String {
    format!(
        "HIERARCHY\nROOT r\n{{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n \
         JOINT a\n {{\n  OFFSET 0 1 0\n  CHANNELS {} {a_channels}\n  JOINT b\n  {{\n   OFFSET 1 0 0\n   CHANNELS {} {b_channels}\n   \
         End Site\n   {{\n    OFFSET 1 0 0\n   }}\n  }}\n }}\n}}\nMOTION\nFrames: 1\nFrame Time: 0.5\n{row}\n",
        a_channels.split_whitespace().count(),
        b_channels.split_whitespace().count(),
    )
}

#[test]
fn rotation_order_is_per_joint_from_the_channel_order() {
    // a: Rz(90); b: Rx(90) Ry(90). b at (0,2,0); the end at b + Rz90 Rx90 Ry90 (1,0,0):
    // Ry90 (1,0,0) = (0,0,-1); Rx90 (0,0,-1) = (0,1,0); Rz90 (0,1,0) = (-1,0,0).
    let c = read(&chain(
        "Zrotation Xrotation Yrotation",
        "Xrotation Yrotation Zrotation",
        "0 0 0 0 0 0 90 0 0 90 90 0",
    ));
    assert_eq!(c.joints.len(), 4);
    assert_eq!(c.joints[3].name, "b_End");
    let w = c.world(&c.frames[0]);
    close(w[2].1, DVec3::new(0.0, 2.0, 0.0), 1e-12);
    close(w[3].1, DVec3::new(-1.0, 2.0, 0.0), 1e-12);
    // The same values in Y-X-Z order: Ry90 Rx90 (1,0,0) = Ry90 (1,0,0) = (0,0,-1), and Rz90
    // keeps it: the end at (0,2,-1).
    let c = read(&chain(
        "Zrotation Xrotation Yrotation",
        "Yrotation Xrotation Zrotation",
        "0 0 0 0 0 0 90 0 0 90 90 0",
    ));
    close(
        c.world(&c.frames[0])[3].1,
        DVec3::new(0.0, 2.0, -1.0),
        1e-12,
    );
}

#[test]
fn zrotation_90_xrotation_90_is_the_hand_computed_quaternion() {
    // Rz(90) Rx(90) = (cos45 + k sin45)(cos45 + i sin45) = 0.5 (1 + i + j + k).
    let expected = DQuat::from_xyzw(0.5, 0.5, 0.5, 0.5);
    let h = std::f64::consts::FRAC_PI_2;
    let q = EulerOrder::Zxy.to_quat([h, h, 0.0]);
    assert!(q.abs_diff_eq(expected, 1e-12), "{q}");
    let c = read(&chain(
        "Zrotation Xrotation Yrotation",
        "Zrotation Xrotation Yrotation",
        "0 0 0 0 0 0 90 90 0 0 0 0",
    ));
    assert!(c.frames[0].rotations[1].abs_diff_eq(expected, 1e-12));
    // And back.
    // At gimbal lock the first angle is 0 and the last takes the rest.
    let a = EulerOrder::Zxy.from_quat(expected);
    assert!(
        a[0].abs() < 1e-12 && (a[1] - h).abs() < 1e-12 && (a[2] - h).abs() < 1e-12,
        "{a:?}"
    );
    assert!(angle(EulerOrder::Zxy.to_quat(a), expected) < 1e-12);
}

#[test]
fn all_six_orders_round_trip_through_quaternions() {
    for order in EulerOrder::ALL {
        for angles in [
            [0.3, -1.2, 2.5],
            [-2.9, 0.7, 0.1],
            [1.0, std::f64::consts::FRAC_PI_2 - 1e-7, -0.4],
            [0.0, -std::f64::consts::FRAC_PI_2, 0.8],
        ] {
            let q = order.to_quat(angles);
            let back = order.to_quat(order.from_quat(q));
            assert!(angle(q, back) < 1e-12, "{order:?} {angles:?}");
        }
        let names = order.channel_names();
        assert_eq!(EulerOrder::from_axes(order.axes()), Some(order));
        assert_eq!(names.len(), 3);
    }
}

#[test]
fn mixed_three_and_six_channel_joints_and_position_channels() {
    // b has 6 channels. Frame 1: its positions equal its OFFSET (MotionBuilder's absolute
    // translations); frame 2 moves it to (1, 0.5, 0).
    let text = chain(
        "Zrotation Xrotation Yrotation",
        "Xposition Yposition Zposition Zrotation Xrotation Yrotation",
        "0 0 0 0 0 0 0 0 0 1 0 0 0 0 0",
    )
    .replace("Frames: 1", "Frames: 2")
        + "0 0 0 0 0 0 0 0 0 1 0.5 0 0 0 0\n";
    let c = read(&text);
    assert_eq!(c.frames[1].translations[2], DVec3::new(1.0, 0.5, 0.0));
    assert!(
        c.notes.iter().any(|n| n.contains("'b' read as absolute")),
        "{:?}",
        c.notes
    );
    // Frame 1 differs from the OFFSET: the values are added (three.js's reading).
    let text = chain(
        "Zrotation Xrotation Yrotation",
        "Xposition Yposition Zposition Zrotation Xrotation Yrotation",
        "0 0 0 0 0 0 0 0 0 0 0.25 0 0 0 0",
    );
    let c = read(&text);
    assert_eq!(c.frames[0].translations[2], DVec3::new(1.0, 0.25, 0.0));
    assert!(
        c.notes
            .iter()
            .any(|n| n.contains("'b' added to its OFFSET"))
    );
}

#[test]
fn root_translation_is_offset_plus_channels_unless_absolute() {
    let base = chain(
        "Zrotation Xrotation Yrotation",
        "Zrotation Xrotation Yrotation",
        "ROW",
    )
    .replace("OFFSET 0 0 0", "OFFSET 0 1 0");
    let c = read(&base.replace("ROW", "0 0.5 0 0 0 0 0 0 0 0 0 0"));
    assert_eq!(c.frames[0].translations[0], DVec3::new(0.0, 1.5, 0.0));
    // Within 1 % of the OFFSET on frame 1: absolute.
    let c = read(&base.replace("ROW", "0 1.005 0 0 0 0 0 0 0 0 0 0"));
    assert_eq!(c.frames[0].translations[0], DVec3::new(0.0, 1.005, 0.0));
    assert!(c.notes.iter().any(|n| n.contains("'r' read as absolute")));
}

#[test]
fn a_frame_count_one_off_uses_the_rows() {
    let one = chain(
        "Zrotation Xrotation Yrotation",
        "Zrotation Xrotation Yrotation",
        "0 0 0 0 0 0 0 0 0 0 0 0",
    );
    let c = read(&one.replace("Frames: 1", "Frames: 2"));
    assert_eq!(c.frame_count(), 1);
    assert!(
        c.notes
            .iter()
            .any(|n| n.contains("'Frames: 2' (line 22) but 1 rows")),
        "{:?}",
        c.notes
    );
    let c = read(&format!("{}1 2 3 0 0 0 0 0 0 0 0 0\n", one));
    assert_eq!(c.frame_count(), 2);
    assert_eq!(c.frames[1].translations[0], DVec3::new(1.0, 2.0, 3.0));
    let e = read_bvh(
        one.replace("Frames: 1", "Frames: 5000").as_bytes(),
        "t",
        &BvhLimits::default(),
    )
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        "line 22, Frames:: 5000 frames declared, the file has 1"
    );
}

#[test]
fn scientific_notation_and_numbers_without_spaces() {
    let text = chain(
        "Zrotation Xrotation Yrotation",
        "Zrotation Xrotation Yrotation",
        "0.0-7.5 1E+2 0 0 0 0 0 0 0 0 0",
    )
    .replace("OFFSET 0 1 0", "OFFSET 1.5e-3-2 1E+2");
    let c = read(&text);
    assert_eq!(c.joints[1].offset, DVec3::new(1.5e-3, -2.0, 100.0));
    assert_eq!(c.frames[0].translations[0], DVec3::new(0.0, -7.5, 100.0));
}

#[test]
fn tabs_spaces_crlf_lone_cr_and_blank_lines_read_alike() {
    let text = chain(
        "Zrotation Xrotation Yrotation",
        "Zrotation Xrotation Yrotation",
        "1 2 3 10 20 30 40 50 60 70 80 90",
    );
    let reference = read(&text);
    let variants = [
        text.replace(' ', "\t"),
        text.replace(' ', "   \t "),
        text.replace('\n', "\r\n"),
        text.replace('\n', "\r"),
        text.replace('\n', "\n\n  \n"),
    ];
    for v in variants {
        let c = read(&v);
        assert_eq!(c.joints, reference.joints);
        assert_eq!(c.frames, reference.frames);
    }
}

#[test]
fn end_sites_become_leaf_joints_named_after_their_parent() {
    let c = read(&chain(
        "Zrotation Xrotation Yrotation",
        "Zrotation Xrotation Yrotation",
        "0 0 0 0 0 0 0 0 0 0 0 0",
    ));
    assert_eq!(c.joints[3].name, "b_End");
    assert_eq!(c.joints[3].parent, Some(2));
    assert_eq!(c.joints[3].offset, DVec3::new(1.0, 0.0, 0.0));
}

#[test]
fn keywords_are_case_insensitive_and_frame_time_spacing_varies() {
    let text = chain(
        "zROTATION xrotation YRotation",
        "Zrotation Xrotation Yrotation",
        "0 0 0 0 0 0 0 0 0 0 0 0",
    )
    .replace("HIERARCHY", "hierarchy")
    .replace("ROOT", "Root")
    .replace("JOINT", "Joint")
    .replace("End Site", "END SITE")
    .replace("OFFSET", "Offset")
    .replace("CHANNELS", "channels")
    .replace("MOTION", "Motion");
    for (frames, time) in [
        ("Frames: 1", "Frame Time: 0.5"),
        ("FRAMES:1", "FRAME TIME:0.5"),
        ("Frames :  1", "Frame Time :\t0.5"),
        ("frames 1", "frame time 0.5"),
        ("Frames:\t1", "Frame   Time:   5e-1"),
    ] {
        let c = read(
            &text
                .replace("Frames: 1", frames)
                .replace("Frame Time: 0.5", time),
        );
        assert_eq!(c.frame_time, 0.5);
        assert_eq!(c.frame_count(), 1);
        assert_eq!(c.joints.len(), 4);
    }
}

#[test]
fn trailing_garbage_after_the_last_frame_names_its_line() {
    let text = chain(
        "Zrotation Xrotation Yrotation",
        "Zrotation Xrotation Yrotation",
        "0 0 0 0 0 0 0 0 0 0 0 0",
    );
    let e = read_bvh(
        format!("{text}\nthe end\n").as_bytes(),
        "t",
        &BvhLimits::default(),
    )
    .unwrap_err();
    assert_eq!(e.line(), 26);
    assert!(
        e.to_string()
            .starts_with("line 26, after the last frame: unexpected \"the end\""),
        "{e}"
    );
}

#[test]
fn centimetres_and_metres_give_the_same_clip() {
    let m = read(&humanoid(&MIXAMO, 1.0, false, 3));
    let cm = read(&humanoid(&MIXAMO, 0.01, false, 3));
    assert!(
        m.notes[0].starts_with("units: metres (skull base 1.5 units"),
        "{:?}",
        m.notes
    );
    assert!(
        cm.notes[0].starts_with("units: centimetres (skull base 153.0 units"),
        "{:?}",
        cm.notes
    );
    for (a, b) in m.joints.iter().zip(&cm.joints) {
        close(a.offset, b.offset, 1e-9);
    }
    for (fa, fb) in m.frames.iter().zip(&cm.frames) {
        for (a, b) in fa.translations.iter().zip(&fb.translations) {
            close(*a, *b, 1e-9);
        }
        for (a, b) in fa.rotations.iter().zip(&fb.rotations) {
            assert!(angle(*a, *b) < 1e-9);
        }
    }
    // The hips at 0.95 m, the origin kept.
    close(
        m.frames[2].translations[0],
        DVec3::new(0.0, 0.95, 0.02),
        1e-12,
    );
}

#[test]
fn a_z_up_file_is_turned_into_the_h_anim_frame() {
    let y = read(&humanoid(&MIXAMO, 1.0, false, 1));
    let z = read(&humanoid(&MIXAMO, 0.01, true, 1));
    assert!(
        z.notes
            .iter()
            .any(|n| n.starts_with("axes: the body's up is file +Z, its front -Y, its left +X")),
        "{:?}",
        z.notes
    );
    assert!(!y.notes.iter().any(|n| n.starts_with("axes")));
    for (a, b) in y.rest_positions().iter().zip(z.rest_positions()) {
        close(*a, b, 1e-9);
    }
    close(
        z.frames[0].translations[0],
        DVec3::new(0.0, 0.95, 0.0),
        1e-9,
    );
    let l_hand = z.joint_of("l_radiocarpal").unwrap();
    assert!(z.rest_positions()[l_hand].x > 0.6);
}

fn assert_maps(names: &Names, expect: &[(&str, &str)]) {
    let c = read(&humanoid(names, 0.01, false, 2));
    let missing = c.mapping.missing(LevelOfArticulation::Loa1);
    assert!(missing.is_empty(), "missing {missing:?}");
    for (hanim, source) in expect {
        let i = c
            .joint_of(hanim)
            .unwrap_or_else(|| panic!("{hanim} unmapped"));
        assert_eq!(c.joints[i].name, *source, "{hanim}");
    }
}

#[test]
fn cmu_names_map_onto_h_anim() {
    let cmu = Names {
        hips: "Hips",
        spine: "LowerBack",
        chest: "Spine1",
        neck: "Neck",
        head: "Head",
        up_leg: "{}UpLeg",
        leg: "{}Leg",
        foot: "{}Foot",
        toe: "{}ToeBase",
        collar: "{}Shoulder",
        arm: "{}Arm",
        fore_arm: "{}ForeArm",
        hand: "{}Hand",
        sides: ["Left", "Right"],
        biped: false,
    };
    assert_maps(
        &cmu,
        &[
            ("humanoid_root", "Hips"),
            ("l_hip", "LeftUpLeg"),
            ("l_knee", "LeftLeg"),
            ("l_talocrural", "LeftFoot"),
            ("r_metatarsophalangeal_2", "RightToeBase"),
            ("l_sternoclavicular", "LeftShoulder"),
            ("l_shoulder", "LeftArm"),
            ("l_elbow", "LeftForeArm"),
            ("r_radiocarpal", "RightHand"),
            ("skullbase", "Head"),
            ("vl5", "LowerBack"),
        ],
    );
}

#[test]
fn motionbuilder_names_map_onto_h_anim() {
    let mb = Names {
        hips: "Character1_Hips",
        spine: "Character1_Spine",
        chest: "Character1_Spine1",
        neck: "Character1_Neck",
        head: "Character1_Head",
        up_leg: "Character1_{}UpLeg",
        leg: "Character1_{}Leg",
        foot: "Character1_{}Foot",
        toe: "Character1_{}ToeBase",
        collar: "Character1_{}Shoulder",
        arm: "Character1_{}Arm",
        fore_arm: "Character1_{}ForeArm",
        hand: "Character1_{}Hand",
        sides: ["Left", "Right"],
        biped: false,
    };
    assert_maps(
        &mb,
        &[
            ("humanoid_root", "Character1_Hips"),
            ("l_hip", "Character1_LeftUpLeg"),
            ("r_knee", "Character1_RightLeg"),
            ("l_talocrural", "Character1_LeftFoot"),
            ("l_shoulder", "Character1_LeftArm"),
            ("l_elbow", "Character1_LeftForeArm"),
            ("l_radiocarpal", "Character1_LeftHand"),
            ("skullbase", "Character1_Head"),
            ("l_sternoclavicular", "Character1_LeftShoulder"),
        ],
    );
}

#[test]
fn daz_names_map_onto_h_anim() {
    let daz = Names {
        hips: "hip",
        spine: "abdomen",
        chest: "chest",
        neck: "neck",
        head: "head",
        up_leg: "{}Thigh",
        leg: "{}Shin",
        foot: "{}Foot",
        toe: "{}Toe",
        collar: "{}Collar",
        arm: "{}Shldr",
        fore_arm: "{}ForeArm",
        hand: "{}Hand",
        sides: ["l", "r"],
        biped: false,
    };
    assert_maps(
        &daz,
        &[
            ("humanoid_root", "hip"),
            ("l_hip", "lThigh"),
            ("l_knee", "lShin"),
            ("r_talocrural", "rFoot"),
            ("l_sternoclavicular", "lCollar"),
            ("l_shoulder", "lShldr"),
            ("r_elbow", "rForeArm"),
            ("l_radiocarpal", "lHand"),
            ("skullbase", "head"),
            ("vl5", "abdomen"),
        ],
    );
    let genesis = Names {
        up_leg: "{}ThighBend",
        arm: "{}ShldrBend",
        fore_arm: "{}ForearmBend",
        ..daz
    };
    assert_maps(
        &genesis,
        &[
            ("l_hip", "lThighBend"),
            ("l_shoulder", "lShldrBend"),
            ("r_elbow", "rForearmBend"),
        ],
    );
}

#[test]
fn mixamo_names_map_onto_h_anim() {
    assert_maps(
        &MIXAMO,
        &[
            ("humanoid_root", "mixamorig:Hips"),
            ("l_hip", "mixamorig:LeftUpLeg"),
            ("l_shoulder", "mixamorig:LeftArm"),
            ("r_radiocarpal", "mixamorig:RightHand"),
            ("skullbase", "mixamorig:Head"),
            ("l_metatarsophalangeal_2", "mixamorig:LeftToeBase"),
        ],
    );
}

#[test]
fn biped_names_map_onto_h_anim() {
    let biped = Names {
        hips: "Bip01 Pelvis",
        spine: "Bip01 Spine",
        chest: "Bip01 Spine1",
        neck: "Bip01 Neck",
        head: "Bip01 Head",
        up_leg: "Bip01 {} Thigh",
        leg: "Bip01 {} Calf",
        foot: "Bip01 {} Foot",
        toe: "Bip01 {} Toe0",
        collar: "Bip01 {} Clavicle",
        arm: "Bip01 {} UpperArm",
        fore_arm: "Bip01 {} Forearm",
        hand: "Bip01 {} Hand",
        sides: ["L", "R"],
        biped: true,
    };
    assert_maps(
        &biped,
        &[
            ("humanoid_root", "Bip01 Pelvis"),
            ("l_hip", "Bip01 L Thigh"),
            ("l_knee", "Bip01 L Calf"),
            ("r_talocrural", "Bip01 R Foot"),
            ("l_sternoclavicular", "Bip01 L Clavicle"),
            ("l_shoulder", "Bip01 L UpperArm"),
            ("l_elbow", "Bip01 L Forearm"),
            ("r_radiocarpal", "Bip01 R Hand"),
            ("skullbase", "Bip01 Head"),
            ("vc4", "Bip01 Neck"),
            ("vl5", "Bip01 Spine"),
        ],
    );
}
