//! The mapping's unit tests.

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use super::*;

fn m(name: &str) -> Option<&'static str> {
    match_name(name).map(|(h, _)| h)
}

#[test]
fn names_of_common_rigs() {
    assert_eq!(m("mixamorig:LeftArm"), Some("l_shoulder"));
    assert_eq!(m("LeftArm"), Some("l_shoulder"));
    assert_eq!(m("mixamorig:LeftShoulder"), Some("l_sternoclavicular"));
    assert_eq!(m("mixamorig:RightForeArm"), Some("r_elbow"));
    assert_eq!(m("mixamorig:Hips"), Some("humanoid_root"));
    assert_eq!(m("Hips"), Some("humanoid_root"));
    assert_eq!(m("UpperArm_L"), Some("l_shoulder"));
    assert_eq!(m("upper_arm.R"), Some("r_shoulder"));
    assert_eq!(m("arm_joint_L_1"), Some("l_shoulder"));
    assert_eq!(m("arm_joint_L_2"), Some("l_elbow"));
    assert_eq!(m("arm_joint_R_3"), Some("r_radiocarpal"));
    assert_eq!(m("thigh_l"), Some("l_hip"));
    assert_eq!(m("calf_r"), Some("r_knee"));
    assert_eq!(m("Bip01 L Thigh"), Some("l_hip"));
    assert_eq!(m("LeftHandIndex1"), Some("l_metacarpophalangeal_2"));
    assert_eq!(m("mixamorig:RightHandThumb1"), Some("r_carpometacarpal_1"));
    assert_eq!(m("LeftUpLeg"), Some("l_hip"));
    assert_eq!(m("LeftToeBase"), Some("l_metatarsophalangeal_2"));
    assert_eq!(m("l_talocrural"), Some("l_talocrural"));
    assert_eq!(m("l_ankle"), Some("l_talocrural"));
    assert_eq!(m("LeftHandIndex4"), None);
    assert_eq!(m("Camera"), None);
}

#[test]
fn names_of_motion_capture_rigs() {
    // CMU's ASF names (one word, side glued on).
    assert_eq!(m("lfemur"), Some("l_hip"));
    assert_eq!(m("rtibia"), Some("r_knee"));
    assert_eq!(m("lfoot"), Some("l_talocrural"));
    assert_eq!(m("ltoes"), Some("l_metatarsophalangeal_2"));
    assert_eq!(m("lclavicle"), Some("l_sternoclavicular"));
    assert_eq!(m("rhumerus"), Some("r_shoulder"));
    assert_eq!(m("lradius"), Some("l_elbow"));
    assert_eq!(m("lwrist"), Some("l_radiocarpal"));
    assert_eq!(m("lowerback"), Some("vl5"));
    assert_eq!(m("upperback"), Some("vt10"));
    assert_eq!(m("thorax"), Some("vt1"));
    assert_eq!(m("lowerneck"), Some("vc7"));
    assert_eq!(m("upperneck"), Some("vc4"));
    assert_eq!(m("lhipjoint"), None);
    assert_eq!(m("LHipJoint"), None);
    assert_eq!(m("root"), None);
    // MotionBuilder's Character1_ prefix.
    assert_eq!(m("Character1_LeftUpLeg"), Some("l_hip"));
    assert_eq!(m("Character1_Hips"), Some("humanoid_root"));
    assert_eq!(m("Character1_Spine1"), Some("vt10"));
    assert_eq!(m("Character1_RightForeArm"), Some("r_elbow"));
    // Daz (Poser-style and Genesis).
    assert_eq!(m("lShldr"), Some("l_shoulder"));
    assert_eq!(m("lShldrBend"), Some("l_shoulder"));
    assert_eq!(m("lShldrTwist"), None);
    assert_eq!(m("rForearmBend"), Some("r_elbow"));
    assert_eq!(m("lThighBend"), Some("l_hip"));
    assert_eq!(m("lShin"), Some("l_knee"));
    assert_eq!(m("lCollar"), Some("l_sternoclavicular"));
    // 3ds Max Biped.
    assert_eq!(m("Bip01 Pelvis"), Some("humanoid_root"));
    assert_eq!(m("Bip01 L Calf"), Some("l_knee"));
    assert_eq!(m("Bip01 R UpperArm"), Some("r_shoulder"));
    assert_eq!(m("Bip01 L Toe0"), Some("l_metatarsophalangeal_2"));
    assert_eq!(m("Bip01"), None);
}

/// A shoulder under a collar is the upper arm; a pelvis under the hip root the
/// sacroiliac.
#[test]
fn shoulder_under_collar_and_pelvis_under_hip() {
    let names = [
        ("hip", None),
        ("pelvis", Some(0)),
        ("LeftCollar", Some(0)),
        ("LeftShoulder", Some(2)),
    ];
    let joints: Vec<SourceJoint> = names
        .iter()
        .map(|(n, p)| SourceJoint {
            name: (*n).into(),
            parent: *p,
            position: DVec3::ZERO,
        })
        .collect();
    let mapping = Mapping::auto(&joints, &[], false);
    assert_eq!(mapping.source_of("humanoid_root"), Some(0));
    assert_eq!(mapping.source_of("sacroiliac"), Some(1));
    assert_eq!(mapping.source_of("l_sternoclavicular"), Some(2));
    assert_eq!(mapping.source_of("l_shoulder"), Some(3));
}

#[test]
fn vrm_bones() {
    assert_eq!(vrm_bone_to_hanim("leftUpperArm", false), Some("l_shoulder"));
    assert_eq!(
        vrm_bone_to_hanim("leftThumbMetacarpal", false),
        Some("l_carpometacarpal_1")
    );
    assert_eq!(
        vrm_bone_to_hanim("leftThumbProximal", true),
        Some("l_carpometacarpal_1")
    );
    assert_eq!(
        vrm_bone_to_hanim("rightLittleDistal", false),
        Some("r_carpal_distal_interphalangeal_5")
    );
}

/// A rig with meaningless names: found by geometry.
#[test]
fn geometry_fallback_finds_limbs() {
    let mut joints = Vec::new();
    let mut add = |name: &str, parent: Option<usize>, p: [f64; 3]| {
        joints.push(SourceJoint {
            name: name.into(),
            parent,
            position: DVec3::from_array(p),
        });
        joints.len() - 1
    };
    let root = add("b0", None, [0.0, 1.0, 0.0]);
    let s = add("b1", Some(root), [0.0, 1.2, 0.0]);
    let chest = add("b2", Some(s), [0.0, 1.4, 0.0]);
    let n = add("b3", Some(chest), [0.0, 1.5, 0.0]);
    add("b4", Some(n), [0.0, 1.6, 0.0]);
    for x in [1.0, -1.0] {
        let c = add("c", Some(chest), [0.05 * x, 1.45, 0.0]);
        let sh = add("c", Some(c), [0.18 * x, 1.45, 0.0]);
        let e = add("c", Some(sh), [0.18 * x, 1.15, 0.0]);
        let w = add("c", Some(e), [0.18 * x, 0.9, 0.0]);
        add("c", Some(w), [0.18 * x, 0.8, 0.0]);
        let h = add("d", Some(root), [0.1 * x, 0.95, 0.0]);
        let k = add("d", Some(h), [0.1 * x, 0.5, 0.0]);
        let a = add("d", Some(k), [0.1 * x, 0.08, 0.0]);
        add("d", Some(a), [0.1 * x, 0.0, 0.1]);
    }
    let mapping = Mapping::auto(&joints, &[], false);
    assert!(
        mapping.missing(LevelOfArticulation::Loa1).is_empty(),
        "{:?}",
        mapping.missing(LevelOfArticulation::Loa1)
    );
    assert_eq!(mapping.source_of("l_elbow"), Some(7));
    assert_eq!(mapping.source_of("r_knee"), Some(20));
}

#[test]
fn user_corrections() {
    let joints: Vec<SourceJoint> = ["Hips", "Foo"]
        .iter()
        .enumerate()
        .map(|(i, n)| SourceJoint {
            name: (*n).into(),
            parent: i.checked_sub(1),
            position: DVec3::ZERO,
        })
        .collect();
    let mut mapping = Mapping::auto(&joints, &[], false);
    assert_eq!(mapping.source_of("humanoid_root"), Some(0));
    assert_eq!(
        mapping.get("sacroiliac").map(|m| m.method),
        Some(MatchMethod::Implied)
    );
    mapping.set("vl5", 1).unwrap();
    assert_eq!(mapping.hanim_of(1), Some("vl5"));
    assert_eq!(
        mapping.get("vl5").map(|m| m.method),
        Some(MatchMethod::User)
    );
    assert!(mapping.set("nope", 0).is_err());
    assert!(mapping.set("vl5", 9).is_err());
    assert!(mapping.remove("vl5"));
    assert_eq!(mapping.hanim_of(1), None);
}
#[test]
fn remapped_renumbers_and_drops() {
    let joints: Vec<SourceJoint> = ["Armature", "Hips", "Spine", "Foo"]
        .iter()
        .enumerate()
        .map(|(i, n)| SourceJoint {
            name: (*n).into(),
            parent: i.checked_sub(1),
            position: DVec3::new(0.0, i as f64, 0.0),
        })
        .collect();
    let mut mapping = Mapping::auto(&joints, &[], false);
    mapping.set("vl1", 3).unwrap();
    assert_eq!(mapping.source_of("humanoid_root"), Some(1));
    // Armature dropped, the others reversed.
    let r = mapping.remapped(&[None, Some(2), Some(1), Some(0)], 3);
    assert_eq!(r.source_count(), 3);
    assert_eq!(r.source_of("humanoid_root"), Some(2));
    assert_eq!(r.source_of("vl1"), Some(0));
    for m in r.matches() {
        let old = mapping.get(m.hanim).unwrap();
        assert_eq!((m.method, m.confidence), (old.method, old.confidence));
    }
    assert_eq!(r.matches().len(), mapping.matches().len());
    // Dropping a mapped joint (or a short table, or an index past the count) unmaps it.
    let r = mapping.remapped(&[None, Some(0), Some(1)], 2);
    assert_eq!(r.source_of("vl1"), None);
    assert_eq!(r.source_of("humanoid_root"), Some(0));
    let r = mapping.remapped(&[None, Some(5), Some(1), Some(0)], 2);
    assert_eq!(r.source_of("humanoid_root"), None);
    assert!(r.matches().iter().all(|m| m.source < 2));
}
