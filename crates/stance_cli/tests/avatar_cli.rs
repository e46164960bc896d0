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
