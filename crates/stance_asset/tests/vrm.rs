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
            "meta": {"title": "test", "licenseName": "CC_BY"},
            "blendShapeMaster": {"blendShapeGroups": [{"name": "Joy", "presetName": "joy",
                "binds": [{"mesh": 0, "index": 0, "weight": 100}]}]},
            "materialProperties": [{"name": "skin", "shader": "VRM/MToon", "textureProperties": {},
                "vectorProperties": {"_Color": [0.5, 0.4, 0.3, 1.0]}}]}});
        j["extensionsUsed"] = json!(["VRM"]);
    } else {
        let mut bones = serde_json::Map::new();
        for (b1, _, h) in BONES {
            bones.insert((*b1).into(), json!({"node": index[*h]}));
        }
        j["extensions"] = json!({"VRMC_vrm": {"specVersion": "1.0",
            "meta": {"name": "test", "licenseUrl": "https://vrm.dev/licenses/1.0/"},
            "humanoid": {"humanBones": bones},
            "expressions": {"preset": {"happy": {"morphTargetBinds": [{"node": 0, "index": 0, "weight": 1.0}]}}}}});
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

/// Exported (posed, as `stance export-posed` and the editor write it), a VRM is still a VRM:
/// the same version, its meta (licence) kept, and a re-import maps the scrambled joints through
/// the humanoid extension alone; expressions lose their morph-target binds (morph targets are
/// not kept).
fn exported_stays_vrm(version: u8) {
    let mut avatar = load_avatar(&vrm_file(version), &LoadOptions::default()).unwrap();
    let body = avatar.skeleton(&Default::default()).unwrap();
    let mut posture = stance_ik::Posture::rest(&body.skeleton);
    let elbow = body.skeleton.joint_index("l_elbow").unwrap();
    posture.values_mut()[body.skeleton.joints()[elbow].dof_start] = -1.0;
    avatar.apply_posture(&body, &posture).unwrap();
    let bytes = stance_asset::export_glb(&avatar).unwrap();
    let (json, _) = common::split(&bytes);
    let (name, meta_key) = if version == 0 {
        ("VRM", "title")
    } else {
        ("VRMC_vrm", "name")
    };
    assert!(
        json["extensionsUsed"]
            .as_array()
            .unwrap()
            .contains(&json!(name))
    );
    assert_eq!(json["extensions"][name]["meta"][meta_key], json!("test"));
    if version == 0 {
        assert_eq!(
            json["extensions"]["VRM"]["meta"]["licenseName"],
            json!("CC_BY")
        );
        let group = &json["extensions"]["VRM"]["blendShapeMaster"]["blendShapeGroups"][0];
        assert_eq!(group["name"], json!("Joy"));
        assert_eq!(group["binds"], json!([]));
    } else {
        let happy = &json["extensions"]["VRMC_vrm"]["expressions"]["preset"]["happy"];
        assert_eq!(happy["morphTargetBinds"], json!([]));
    }
    let again = load_avatar(&bytes, &LoadOptions::default()).unwrap();
    assert_eq!(again.format, avatar.format);
    for (_, _, h) in BONES {
        let m = again
            .mapping
            .get(h)
            .unwrap_or_else(|| panic!("{h} not mapped"));
        assert_eq!(m.method, MatchMethod::Vrm, "{h}");
        assert_eq!(Some(m.source), avatar.mapping.source_of(h), "{h}");
    }
    // The posture is in the file: the elbow's node turned away from its rest rotation (kept
    // in the node's extras for Stance).
    let node = &json["nodes"][avatar.mapping.source_of("l_elbow").unwrap()];
    let turned: Vec<f64> = serde_json::from_value(node["rotation"].clone()).unwrap();
    let rest: Vec<f64> =
        serde_json::from_value(node["extras"]["stance_rest"]["rotation"].clone()).unwrap();
    let dot: f64 = turned.iter().zip(&rest).map(|(a, b)| a * b).sum();
    assert!(
        dot.abs() < 0.95,
        "the elbow is bent in the file: {turned:?} vs {rest:?}"
    );
}

#[test]
fn vrm1_exported_is_still_vrm1() {
    exported_stays_vrm(1);
}

#[test]
fn vrm0_exported_is_still_vrm0() {
    exported_stays_vrm(0);
}
