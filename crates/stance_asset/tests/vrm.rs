//! VRM 0.x and 1.0 files built by the test from the default avatar (joint names scrambled,
//! so only the VRM humanoid extension can map them).

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use crate::common;

use serde_json::json;
use stance_asset::{LoadOptions, SourceFormat, load_avatar};
use stance_hanim::{LevelOfArticulation, MatchMethod};

/// The default avatar with scrambled node names, VRM-extended.
fn vrm_file(version: u8) -> Vec<u8> {
    common::vrm_from(&common::default_glb(), version)
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
    for (_, _, h) in common::VRM_BONES {
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
    for (_, _, h) in common::VRM_BONES {
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
