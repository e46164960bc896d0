//! `stance inspect`, `stance export-posed`, `stance make-avatar` end to end.

#![allow(clippy::expect_used, clippy::unwrap_used, clippy::panic)]

use std::process::Command;

use serde_json::Value;

fn stance(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_stance"))
        .args(args)
        .output()
        .expect("runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn temp(name: &str) -> String {
    let dir = std::env::temp_dir().join(format!("stance-avatar-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name).to_string_lossy().into_owned()
}

#[test]
fn make_inspect_pose_and_reimport() {
    let glb = temp("default.glb");
    let (ok, _, err) = stance(&["make-avatar", &glb]);
    assert!(ok, "{err}");
    let (ok, out, err) = stance(&["inspect", &glb]);
    assert!(ok, "{err}");
    let v: Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(v["joints"], 71);
    assert_eq!(v["meshes"], 1);
    assert!(v["vertices"].as_u64().unwrap() > 1000);
    assert_eq!(v["mapping"]["l_knee"], "l_knee");
    assert!(v["unmapped"].as_array().unwrap().is_empty());
    // The summary keeps its keys and adds per-joint confidence.
    let keys: Vec<&str> = v.as_object().unwrap().keys().map(String::as_str).collect();
    assert_eq!(
        keys,
        [
            "confidence",
            "extensions",
            "joints",
            "mapping",
            "meshes",
            "unmapped",
            "vertices",
            "warnings"
        ]
    );
    let confidence = v["confidence"].as_object().unwrap();
    assert_eq!(
        confidence.len(),
        v["mapping"].as_object().unwrap().len(),
        "one entry per mapped joint"
    );
    assert_eq!(
        v["confidence"]["l_knee"],
        serde_json::json!({"hanim": "l_knee", "method": "hanim_name", "confidence": 1.0})
    );

    let posture = temp("posture.json");
    std::fs::write(
        &posture,
        r#"{"loa": 1, "posture": {"l_knee": {"rx": 0.8}, "l_hip": {"rx": -0.5},
            "l_carpal_distal_interphalangeal_3": {"rz": 0.1}, "vl5": {"rq": 1.0}}}"#,
    )
    .unwrap();
    let posed = temp("posed.glb");
    let (ok, _, err) = stance(&["export-posed", &glb, &posture, &posed]);
    assert!(!ok, "an unknown DOF is an error");
    assert!(err.contains("unknown DOF `rq`"), "{err}");
    std::fs::write(
        &posture,
        r#"{"loa": 1, "posture": {"l_knee": {"rx": 0.8}, "l_hip": {"rx": -0.5},
            "l_carpal_distal_interphalangeal_3": {"rz": 0.1}}}"#,
    )
    .unwrap();
    let (ok, _, err) = stance(&["export-posed", &glb, &posture, &posed]);
    assert!(ok, "{err}");
    assert!(
        err.contains("not in this avatar's skeleton"),
        "LOA1 skips fingers: {err}"
    );
    let bytes = std::fs::read(&posed).unwrap();
    let avatar = stance_asset::load_avatar(&bytes, &Default::default()).unwrap();
    let body = avatar
        .skeleton(&stance_hanim::SkeletonOptions {
            loa: stance_hanim::LevelOfArticulation::Loa1,
            ..Default::default()
        })
        .unwrap();
    let p = avatar.current_posture(&body).unwrap();
    let s = &body.skeleton;
    let knee = &s.joints()[s.joint_index("l_knee").unwrap()];
    let rx = p.values()[knee.rotation_dof[0].unwrap()];
    assert!((rx - 0.8).abs() < 1e-5, "{rx}");
}

#[test]
fn inspect_fails_with_a_reason() {
    let bad = temp("bad.gltf");
    std::fs::write(&bad, r#"{"asset":{"version":"2.0"},"nodes":[{"mesh":3}]}"#).unwrap();
    let (ok, _, err) = stance(&["inspect", &bad]);
    assert!(!ok);
    assert!(err.contains("node 0 refers to mesh 3"), "{err}");
    let (ok, _, err) = stance(&["inspect", "/no/such/file.glb"]);
    assert!(!ok);
    assert!(err.contains("reading /no/such/file.glb"), "{err}");
}

/// `confidence` reports how each joint was matched: Mixamo, other known rig names, name
/// patterns and H-Anim names, with the mapper's confidence.
#[test]
fn inspect_reports_match_methods_and_confidence() {
    let file = temp("rig.gltf");
    std::fs::write(
        &file,
        r#"{"asset":{"version":"2.0"},"nodes":[
            {"name":"mixamorig:Hips","translation":[0,1,0],"children":[1,3]},
            {"name":"leg_L_1","translation":[0.1,0,0],"children":[2]},
            {"name":"l_knee","translation":[0,-0.45,0]},
            {"name":"Spine","translation":[0,0.2,0],"children":[4]},
            {"name":"UpperArm_R","translation":[-0.2,0.3,0]}],
            "scenes":[{"nodes":[0]}]}"#,
    )
    .unwrap();
    let (ok, out, err) = stance(&["inspect", &file]);
    assert!(ok, "{err}");
    let v: Value = serde_json::from_str(out.trim()).unwrap();
    let c = &v["confidence"];
    let entry = |hanim: &str, method: &str, confidence: f64| serde_json::json!({"hanim": hanim, "method": method, "confidence": confidence});
    assert_eq!(c["mixamorig:Hips"], entry("humanoid_root", "mixamo", 0.95));
    assert_eq!(c["leg_L_1"], entry("l_hip", "name_pattern", 0.75));
    assert_eq!(c["l_knee"], entry("l_knee", "hanim_name", 1.0));
    assert_eq!(c["UpperArm_R"], entry("r_shoulder", "known_rig_name", 0.95));
    assert_eq!(v["mapping"]["leg_L_1"], "l_hip");
    assert!(
        v["warnings"][0]
            .as_str()
            .unwrap()
            .contains("not a complete humanoid"),
        "{v}"
    );
}
