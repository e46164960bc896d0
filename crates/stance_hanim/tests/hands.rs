//! Hand presets and finger curl, measured by forward kinematics on the default body, on a
//! left/right-symmetric body, on a T-pose avatar (other DOF axes) and on bodies without some
//! or all of their fingers.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;
#[cfg(target_arch = "wasm32")]
wasm_bindgen_test::wasm_bindgen_test_configure!(run_in_browser);

use glam::{DQuat, DVec3};
use stance_hanim::hands::{Finger, HandError, HandPreset, HandRig, has_fingers};
use stance_hanim::{
    HumanoidSkeleton, LevelOfArticulation, Mapping, Side, SkeletonOptions, SourceJoint,
    build_skeleton, default_skeleton, humanoid_joints, mirror_name,
};
use stance_ik::{Dof, Frames, JointDef, Posture, Skeleton};

fn body(loa: LevelOfArticulation) -> HumanoidSkeleton {
    default_skeleton(&SkeletonOptions {
        loa,
        ..SkeletonOptions::default()
    })
    .unwrap()
}

/// A body built from the H-Anim joint table with each joint's rest position changed by `place`
/// (name, centre, all centres by name), as an avatar would be. The centres are H-Anim's
/// defaults with the right side the mirror image of the left (some of the standard's default
/// right finger centres are astray: `r_carpal_distal_interphalangeal_5` above its PIP joint).
fn avatar(
    loa: LevelOfArticulation,
    keep: impl Fn(&str) -> bool,
    place: impl Fn(&str, DVec3, &dyn Fn(&str) -> DVec3) -> DVec3,
) -> HumanoidSkeleton {
    let table = humanoid_joints(loa);
    let default = |name: &str| {
        table
            .iter()
            .find(|j| j.definition.name == name)
            .map(|j| j.rest_centre)
            .unwrap()
    };
    let centre = |name: &str| match Side::of(name) {
        Side::Right => reflect(default(&mirror_name(name))),
        _ => default(name),
    };
    let mut joints: Vec<SourceJoint> = Vec::new();
    let mut new_index = vec![None; table.len()];
    for (k, j) in table.iter().enumerate() {
        let name = j.definition.name;
        if !keep(name) {
            continue;
        }
        // The nearest kept ancestor.
        let mut parent = j.parent;
        while let Some(p) = parent {
            if new_index[p].is_some() {
                break;
            }
            parent = table[p].parent;
        }
        new_index[k] = Some(joints.len());
        joints.push(SourceJoint {
            name: name.to_owned(),
            parent: parent.and_then(|p| new_index[p]),
            position: place(name, centre(name), &centre),
        });
    }
    let mapping = Mapping::auto(&joints, &[], false);
    let positions: Vec<DVec3> = joints.iter().map(|j| j.position).collect();
    build_skeleton(
        &mapping,
        &positions,
        &SkeletonOptions {
            loa,
            ..SkeletonOptions::default()
        },
    )
    .unwrap()
}

fn reflect(p: DVec3) -> DVec3 {
    DVec3::new(-p.x, p.y, p.z)
}

/// The default body with its right side the exact mirror image of its left side: offsets
/// reflected, limits mirrored (`ry` and `rz` change sign), central joints on x = 0.
fn symmetric_body(loa: LevelOfArticulation) -> Skeleton {
    let body = body(loa);
    let s = &body.skeleton;
    let defs = s
        .joints()
        .iter()
        .map(|j| {
            let side = Side::of(&j.name);
            let source = &s.joints()[if side == Side::Right {
                joint(s, &mirror_name(&j.name))
            } else {
                joint(s, &j.name)
            }];
            let offset = match side {
                Side::Right => reflect(source.offset),
                Side::Centre => DVec3::new(0.0, source.offset.y, source.offset.z),
                Side::Left => source.offset,
            };
            let parent = j.parent.map(|p| s.joints()[p].name.as_str());
            let mut def = JointDef::new(j.name.as_str(), parent, offset, &source.dofs);
            for (k, &dof) in source.dofs.iter().enumerate() {
                let (lo, hi) = (
                    s.lower_limits()[source.dof_start + k],
                    s.upper_limits()[source.dof_start + k],
                );
                let (lo, hi) = if side == Side::Right && matches!(dof, Dof::Ry | Dof::Rz) {
                    (-hi, -lo)
                } else {
                    (lo, hi)
                };
                if lo.is_finite() && hi.is_finite() {
                    def = def.with_limit(dof, lo, hi);
                }
            }
            def
        })
        .collect();
    Skeleton::new(defs).unwrap()
}

fn posed(skeleton: &Skeleton, values: &[(usize, f64)]) -> Posture {
    let mut posture = Posture::rest(skeleton);
    for &(dof, value) in values {
        posture.values_mut()[dof] = value;
    }
    posture
}

fn joint(skeleton: &Skeleton, name: &str) -> usize {
    skeleton
        .joint_index(name)
        .unwrap_or_else(|| panic!("{name}"))
}

/// The palm's centre, measured independently of the rig: the mean of the wrist and the
/// knuckles of fingers 2 to 5.
fn palm_centre(skeleton: &Skeleton, frames: &Frames, side: Side) -> DVec3 {
    let names = [
        "radiocarpal",
        "metacarpophalangeal_2",
        "metacarpophalangeal_3",
        "metacarpophalangeal_4",
        "metacarpophalangeal_5",
    ];
    names
        .iter()
        .map(|n| frames.joint_position[joint(skeleton, &format!("{}{n}", side.prefix()))])
        .sum::<DVec3>()
        / names.len() as f64
}

/// The tip of a digit, measured independently of the rig: 2 cm beyond its last joint along
/// the direction from its knuckle (its first joint for the thumb) to its last joint at rest,
/// turned with the last joint.
fn tip(skeleton: &Skeleton, frames: &Frames, side: Side, finger: Finger) -> DVec3 {
    let rest = Frames::new(skeleton, &Posture::rest(skeleton));
    let named = |k: usize| {
        let (_, bare) = finger.joints()[k];
        joint(skeleton, &format!("{}{bare}", side.prefix()))
    };
    let first = named(if finger == Finger::Thumb { 0 } else { 1 });
    let last = named(finger.joints().len() - 1);
    let along = (rest.joint_position[last] - rest.joint_position[first]).normalize();
    frames.point(last, along * 0.02)
}

fn both_sides() -> [Side; 2] {
    [Side::Left, Side::Right]
}

#[test]
fn a_fist_closes_every_finger_within_its_limits_and_brings_each_tip_to_the_palm() {
    for loa in [
        LevelOfArticulation::Loa2,
        LevelOfArticulation::Loa3,
        LevelOfArticulation::Loa4,
    ] {
        let body = body(loa);
        let s = &body.skeleton;
        for side in both_sides() {
            let rig = HandRig::new(s, side).unwrap();
            assert_eq!(rig.fingers.len(), 5, "{loa:?} {side:?}");
            let fist = rig.preset(s, HandPreset::Fist);
            let open = rig.preset(s, HandPreset::Open);
            for &(dof, value) in fist.iter().chain(&open) {
                assert!(
                    value >= s.lower_limits()[dof] - 1e-12
                        && value <= s.upper_limits()[dof] + 1e-12,
                    "{} = {value} outside its limits",
                    s.dof_name(dof)
                );
            }
            // Every knuckle and interphalangeal joint flexes, by most of its range.
            for rigged in &rig.fingers {
                for j in rigged.joints.iter().skip(1) {
                    let flexion = j.flexion.unwrap_or_else(|| {
                        panic!("{} has no flexion DOF", s.joints()[j.joint].name)
                    });
                    let value = fist.iter().find(|(d, _)| *d == flexion.dof).unwrap().1;
                    assert!(
                        value.abs() > 0.5,
                        "{} flexes {value} rad in a fist",
                        s.joints()[j.joint].name
                    );
                }
            }
            let fist = Frames::new(s, &posed(s, &fist));
            let open = Frames::new(s, &posed(s, &open));
            for finger in Finger::ALL {
                let closed = (tip(s, &fist, side, finger) - palm_centre(s, &fist, side)).length();
                let spread = (tip(s, &open, side, finger) - palm_centre(s, &open, side)).length();
                assert!(
                    closed < spread - 0.01,
                    "{loa:?} {side:?} {}: {closed:.3} m from the palm in a fist, {spread:.3} open",
                    finger.name()
                );
            }
            // The default body's palms face its thighs: a closed finger's tip is nearer the
            // body's midline than its knuckle (the left hand is on +x).
            for finger in &Finger::ALL[1..] {
                let knuckle = fist.joint_position[joint(
                    s,
                    &format!("{}metacarpophalangeal_{}", side.prefix(), finger.number()),
                )];
                let toward_midline = (knuckle.x - tip(s, &fist, side, *finger).x)
                    * if side == Side::Left { 1.0 } else { -1.0 };
                assert!(toward_midline > 0.01, "{side:?} {}", finger.name());
            }
        }
    }
}

#[test]
fn curl_closes_each_finger_monotonically_and_reads_back() {
    let symmetric = symmetric_body(LevelOfArticulation::Loa2);
    let s = &symmetric;
    for side in both_sides() {
        let rig = HandRig::new(s, side).unwrap();
        for finger in &Finger::ALL[1..] {
            let mut last = f64::INFINITY;
            for step in 0..=4 {
                let curl = f64::from(step) / 4.0;
                let values = rig.curl(s, Some(*finger), curl);
                let posture = posed(s, &values);
                let frames = Frames::new(s, &posture);
                let distance =
                    (tip(s, &frames, side, *finger) - palm_centre(s, &frames, side)).length();
                assert!(
                    distance < last - 1e-3,
                    "{side:?} {} curl {curl}: {distance} after {last}",
                    finger.name()
                );
                last = distance;
                let read = rig.curl_of(&posture, Some(*finger)).unwrap();
                assert!((read - curl).abs() < 1e-9, "{read} read for {curl}");
                // Only this finger moved.
                for other in Finger::ALL.into_iter().filter(|f| f != finger) {
                    assert_eq!(rig.curl_of(&posture, Some(other)), Some(0.0));
                }
            }
        }
        // The whole hand: every digit at once.
        let values = rig.curl(s, None, 0.5);
        let posture = posed(s, &values);
        for finger in Finger::ALL {
            let read = rig.curl_of(&posture, Some(finger)).unwrap();
            assert!((read - 0.5).abs() < 1e-9, "{}", finger.name());
        }
        // Out-of-range and non-finite curls stay within the limits.
        for curl in [-1.0, 2.0, f64::NAN] {
            for (dof, value) in rig.curl(s, None, curl) {
                assert!(value >= s.lower_limits()[dof] && value <= s.upper_limits()[dof]);
            }
        }
    }
}

#[test]
fn the_left_hand_is_the_mirror_image_of_the_right_in_every_preset() {
    for loa in [LevelOfArticulation::Loa2, LevelOfArticulation::Loa4] {
        let symmetric = symmetric_body(loa);
        let s = &symmetric;
        let left = HandRig::new(s, Side::Left).unwrap();
        let right = HandRig::new(s, Side::Right).unwrap();
        assert!((left.palm_normal - reflect(right.palm_normal)).length() < 1e-9);
        for preset in HandPreset::ALL {
            let mut values = left.preset(s, preset);
            values.extend(right.preset(s, preset));
            let frames = Frames::new(s, &posed(s, &values));
            let rest = Frames::new(s, &Posture::rest(s));
            let mut moved = 0.0_f64;
            for finger in Finger::ALL {
                let l = tip(s, &frames, Side::Left, finger);
                let r = tip(s, &frames, Side::Right, finger);
                assert!(
                    (l - reflect(r)).length() < 1e-9,
                    "{} {}: left {l} right {r}",
                    preset.name(),
                    finger.name()
                );
                moved = moved.max((l - tip(s, &rest, Side::Left, finger)).length());
                for (_, bare) in finger.joints() {
                    let l = frames.joint_position[joint(s, &format!("l_{bare}"))];
                    let r = frames.joint_position[joint(s, &format!("r_{bare}"))];
                    assert!((l - reflect(r)).length() < 1e-9, "{bare}");
                }
            }
            if preset != HandPreset::Open {
                assert!(moved > 0.01, "{} moves the fingers", preset.name());
            }
        }
    }
}

#[test]
fn presets_differ_where_they_should() {
    let body = body(LevelOfArticulation::Loa3);
    let s = &body.skeleton;
    let rig = HandRig::new(s, Side::Right).unwrap();
    let curl = |preset, finger| rig.curl_of(&posed(s, &rig.preset(s, preset)), Some(finger));
    // Pointing: the index straight, the others closed.
    assert_eq!(curl(HandPreset::Point, Finger::Index), Some(0.0));
    for finger in [Finger::Middle, Finger::Ring, Finger::Little] {
        assert!(curl(HandPreset::Point, finger).unwrap() > 0.8);
    }
    // Open: straight and spread apart; the index and the little finger further apart than
    // in the rest posture.
    let open = Frames::new(s, &posed(s, &rig.preset(s, HandPreset::Open)));
    let rest = Frames::new(s, &Posture::rest(s));
    let span = |f: &Frames| {
        (tip(s, f, Side::Right, Finger::Index) - tip(s, f, Side::Right, Finger::Little)).length()
    };
    assert!(
        span(&open) > span(&rest) + 0.01,
        "{} vs {}",
        span(&open),
        span(&rest)
    );
    // Pinch: the thumb and index tips come closer than in the open hand.
    let pinch = Frames::new(s, &posed(s, &rig.preset(s, HandPreset::Pinch)));
    let gap = |f: &Frames| {
        (tip(s, f, Side::Right, Finger::Thumb) - tip(s, f, Side::Right, Finger::Index)).length()
    };
    assert!(
        gap(&pinch) < gap(&open),
        "{} vs {}",
        gap(&pinch),
        gap(&open)
    );
    // The tips come together as far as the thumb's ranges allow: the H-Anim default thumb
    // rests 70 degrees from the index and the anatomical table gives its base 15 degrees of
    // flexion, so on this body they stop about 6 cm apart (the relaxed hand: about 14 cm).
    let relaxed = Frames::new(s, &posed(s, &rig.preset(s, HandPreset::Relaxed)));
    assert!(
        gap(&pinch) < 0.6 * gap(&relaxed),
        "the pinch leaves {} m, the relaxed hand {} m",
        gap(&pinch),
        gap(&relaxed)
    );
    // Relaxed sits between open and fist, finger by finger; grip too.
    for finger in &Finger::ALL[1..] {
        let relaxed = curl(HandPreset::Relaxed, *finger).unwrap();
        let grip = curl(HandPreset::Grip, *finger).unwrap();
        let fist = curl(HandPreset::Fist, *finger).unwrap();
        assert!(
            0.0 < relaxed && relaxed < grip && grip < fist,
            "{}",
            finger.name()
        );
    }
    for preset in HandPreset::ALL {
        assert_eq!(HandPreset::from_name(preset.name()), Some(preset));
    }
}

/// An avatar in a T-pose, palms down: its rest is matched onto the standard pose (the arms
/// lowered by the shortest turn, so the palms face the thighs), and flexion is found from its
/// own geometry.
#[test]
fn a_t_pose_avatar_curls_its_fingers_toward_its_palms() {
    let loa = LevelOfArticulation::Loa2;
    let table = humanoid_joints(loa);
    let in_arm = |name: &str, side: Side| {
        let mut at = table.iter().position(|j| j.definition.name == name);
        while let Some(k) = at {
            if table[k].definition.name == format!("{}shoulder", side.prefix()) {
                return table[k].definition.name != name;
            }
            at = table[k].parent;
        }
        false
    };
    let body = avatar(
        loa,
        |_| true,
        |name, p, centre| {
            for (side, angle) in [(Side::Left, 90.0_f64), (Side::Right, -90.0)] {
                if in_arm(name, side) {
                    let shoulder = centre(&format!("{}shoulder", side.prefix()));
                    let turn = DQuat::from_rotation_z(angle.to_radians());
                    return shoulder + turn * (p - shoulder);
                }
            }
            p
        },
    );
    let s = &body.skeleton;
    for side in both_sides() {
        let rig = HandRig::new(s, side).unwrap();
        // Palms down in the T-pose, towards the thighs once the arms are lowered.
        let outward = if side == Side::Left { 1.0 } else { -1.0 };
        assert!(
            rig.palm_normal.x * outward < -0.9,
            "{side:?} palm {}",
            rig.palm_normal
        );
        let fist = Frames::new(s, &posed(s, &rig.preset(s, HandPreset::Fist)));
        let open = Frames::new(s, &posed(s, &rig.preset(s, HandPreset::Open)));
        for finger in &Finger::ALL[1..] {
            let knuckle = fist.joint_position[joint(
                s,
                &format!("{}metacarpophalangeal_{}", side.prefix(), finger.number()),
            )];
            let closed = tip(s, &fist, side, *finger);
            assert!(
                closed.x * outward < knuckle.x * outward - 0.01,
                "{side:?} {} curls towards the thigh: tip {closed} knuckle {knuckle}",
                finger.name(),
            );
            let to_palm =
                |f: &Frames| (tip(s, f, side, *finger) - palm_centre(s, f, side)).length();
            assert!(to_palm(&fist) < to_palm(&open) - 0.01);
        }
    }
}

#[test]
fn missing_finger_joints_are_skipped_and_a_hand_without_fingers_says_so() {
    // LOA 1: no fingers at all.
    let loa1 = body(LevelOfArticulation::Loa1);
    assert!(!has_fingers(&loa1.skeleton));
    let error = HandRig::new(&loa1.skeleton, Side::Left).unwrap_err();
    assert_eq!(error, HandError::NoFingers { side: "left" });
    assert!(error.to_string().contains("no finger joints"), "{error}");
    assert!(has_fingers(&body(LevelOfArticulation::Loa2).skeleton));
    assert_eq!(
        HandRig::new(&body(LevelOfArticulation::Loa2).skeleton, Side::Centre),
        Err(HandError::NotASide)
    );
    // An avatar without little fingers and distal phalanges.
    let partial = avatar(
        LevelOfArticulation::Loa2,
        |name| !name.ends_with("_5") && !name.contains("distal"),
        |_, p, _| p,
    );
    let s = &partial.skeleton;
    let rig = HandRig::new(s, Side::Right).unwrap();
    assert!(rig.finger(Finger::Little).is_none());
    assert_eq!(rig.fingers.len(), 4);
    assert!(rig.fingers.iter().all(|f| f.joints.len() <= 3));
    let fist = posed(s, &rig.preset(s, HandPreset::Fist));
    assert!(rig.curl_of(&fist, Some(Finger::Index)).unwrap() > 0.9);
    // A hand with only its thumb: the palm cannot be told.
    let thumb_only = avatar(
        LevelOfArticulation::Loa2,
        |name| {
            !(Side::of(name) == Side::Left && name.contains("carp") && !name.ends_with("_1"))
                || name == "l_radiocarpal"
        },
        |_, p, _| p,
    );
    assert_eq!(
        HandRig::new(&thumb_only.skeleton, Side::Left),
        Err(HandError::NoPalm { side: "left" })
    );
}
