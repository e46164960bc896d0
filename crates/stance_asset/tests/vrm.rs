//! VRM 0.x and 1.0 files built by the test from the default avatar (joint names scrambled,
//! so only the VRM humanoid extension can map them).

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;
#[cfg(target_arch = "wasm32")]
wasm_bindgen_test::wasm_bindgen_test_configure!(run_in_browser);

mod common;

use serde_json::{Value, json};
use stance_asset::{LoadOptions, SourceFormat, load_avatar};
use stance_hanim::{LevelOfArticulation, MatchMethod};

/// (VRM 1.0 bone, VRM 0.x bone, H-Anim joint).
const BONES: &[(&str, &str, &str)] = &[
    ("hips", "hips", "humanoid_root"),
    ("spine", "spine", "vl5"),
    ("chest", "chest", "vt10"),
    ("upperChest", "upperChest", "vt1"),
    ("neck", "neck", "vc4"),
    ("head", "head", "skullbase"),
    ("leftUpperLeg", "leftUpperLeg", "l_hip"),
    ("leftLowerLeg", "leftLowerLeg", "l_knee"),
    ("leftFoot", "leftFoot", "l_talocrural"),
    ("leftToes", "leftToes", "l_metatarsophalangeal_2"),
    ("rightUpperLeg", "rightUpperLeg", "r_hip"),
    ("rightLowerLeg", "rightLowerLeg", "r_knee"),
    ("rightFoot", "rightFoot", "r_talocrural"),
    ("rightToes", "rightToes", "r_metatarsophalangeal_2"),
    ("leftShoulder", "leftShoulder", "l_sternoclavicular"),
    ("leftUpperArm", "leftUpperArm", "l_shoulder"),
    ("leftLowerArm", "leftLowerArm", "l_elbow"),
    ("leftHand", "leftHand", "l_radiocarpal"),
    ("rightShoulder", "rightShoulder", "r_sternoclavicular"),
    ("rightUpperArm", "rightUpperArm", "r_shoulder"),
    ("rightLowerArm", "rightLowerArm", "r_elbow"),
    ("rightHand", "rightHand", "r_radiocarpal"),
    (
        "leftThumbMetacarpal",
        "leftThumbProximal",
        "l_carpometacarpal_1",
    ),
    (
        "leftThumbProximal",
        "leftThumbIntermediate",
        "l_metacarpophalangeal_1",
    ),
    (
        "leftThumbDistal",
        "leftThumbDistal",
        "l_carpal_interphalangeal_1",
    ),
    (
        "leftIndexProximal",
        "leftIndexProximal",
        "l_metacarpophalangeal_2",
    ),
    (
        "rightLittleDistal",
        "rightLittleDistal",
        "r_carpal_distal_interphalangeal_5",
    ),
];

/// The default avatar with scrambled node names, VRM-extended.
fn vrm_file(version: u8) -> Vec<u8> {
    let (mut j, bin) = common::split(&common::default_glb());
    let nodes = j["nodes"].as_array_mut().unwrap();
    let mut index = std::collections::HashMap::new();
    for (i, n) in nodes.iter_mut().enumerate() {
        index.insert(n["name"].as_str().unwrap().to_owned(), i);
        n["name"] = json!(format!("J{i:03}"));
    }
    let root = index["humanoid_root"];
    if version == 0 {
        // VRM 0.x models face -Z: turn the body around.
        j["nodes"][root]["rotation"] = json!([0.0, 1.0, 0.0, 0.0]);
        let bones: Vec<Value> = BONES
            .iter()
            .map(|(_, b0, h)| json!({"bone": b0, "node": index[*h], "useDefaultValues": true}))
            .collect();
        j["extensions"] = json!({"VRM": {"exporterVersion": "test", "humanoid": {"humanBones": bones},
            "materialProperties": [{"name": "skin", "shader": "VRM/MToon", "textureProperties": {},
                "vectorProperties": {"_Color": [0.5, 0.4, 0.3, 1.0]}}]}});
        j["extensionsUsed"] = json!(["VRM"]);
    } else {
        let mut bones = serde_json::Map::new();
        for (b1, _, h) in BONES {
            bones.insert((*b1).into(), json!({"node": index[*h]}));
        }
        j["extensions"] = json!({"VRMC_vrm": {"specVersion": "1.0", "meta": {"name": "test"},
            "humanoid": {"humanBones": bones}}});
        j["materials"][0]["extensions"] = json!({"VRMC_materials_mtoon": {"specVersion": "1.0"}});
        j["extensionsUsed"] = json!(["VRMC_vrm", "VRMC_materials_mtoon"]);
    }
    common::join(&j, &bin)
}

fn check(version: u8) {
    let avatar = load_avatar(&vrm_file(version), &LoadOptions::default()).unwrap();
    assert_eq!(
        avatar.format,
        if version == 0 {
            SourceFormat::Vrm0
        } else {
            SourceFormat::Vrm1
        }
    );
    for (_, _, h) in BONES {
        let m = avatar
            .mapping
            .get(h)
            .unwrap_or_else(|| panic!("{h} not mapped"));
        assert_eq!(m.method, MatchMethod::Vrm, "{h}");
        assert_eq!(avatar.nodes[m.source].name, format!("J{:03}", m.source));
    }
    assert!(avatar.mapping.missing(LevelOfArticulation::Loa1).is_empty());
    assert!(avatar.materials[0].mtoon);
    // Normalised to H-Anim: the left shoulder on +X and the toes forward, whatever the facing.
    let p = avatar.hanim_rest_positions();
    let at = |h: &str| p[avatar.mapping.source_of(h).unwrap()];
    assert!(at("l_shoulder").x > 0.1, "{}", at("l_shoulder"));
    assert!(at("l_metatarsophalangeal_2").z > at("l_talocrural").z);
    let body = avatar.skeleton(&Default::default()).unwrap();
    assert!(body.skeleton.joint_count() >= 27);
}

#[test]
fn vrm1_maps_through_the_extension() {
    check(1);
}

#[test]
fn vrm0_maps_through_the_extension_and_faces_forward() {
    check(0);
}
