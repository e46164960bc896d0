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

/// The JSON chunk of a GLB.
fn glb_json(bytes: &[u8]) -> Value {
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&bytes[20..20 + len]).unwrap()
}

/// A GLB with its JSON chunk replaced (the BIN chunk kept).
fn with_json(bytes: &[u8], json: &Value) -> Vec<u8> {
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let mut text = serde_json::to_vec(json).unwrap();
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    let rest = &bytes[20 + len..];
    let mut out = b"glTF".to_vec();
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&((20 + text.len() + rest.len()) as u32).to_le_bytes());
    out.extend_from_slice(&(text.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&text);
    out.extend_from_slice(rest);
    out
}

/// World positions of the named nodes of a GLB, from the node transforms in its JSON (this
/// test's own products, not the importer).
fn node_positions(bytes: &[u8]) -> std::collections::HashMap<String, glam::DVec3> {
    use glam::{DMat4, DQuat, DVec3};
    let json = glb_json(bytes);
    let nodes = json["nodes"].as_array().unwrap();
    let v = |n: &Value, key: &str, default: &[f64]| -> Vec<f64> {
        n.get(key)
            .and_then(Value::as_array)
            .map_or(default.to_vec(), |a| {
                a.iter().map(|x| x.as_f64().unwrap()).collect()
            })
    };
    let local = |n: &Value| {
        let t = v(n, "translation", &[0.0; 3]);
        let r = v(n, "rotation", &[0.0, 0.0, 0.0, 1.0]);
        let s = v(n, "scale", &[1.0; 3]);
        DMat4::from_scale_rotation_translation(
            DVec3::new(s[0], s[1], s[2]),
            DQuat::from_xyzw(r[0], r[1], r[2], r[3]),
            DVec3::new(t[0], t[1], t[2]),
        )
    };
    let mut out = std::collections::HashMap::new();
    let mut stack: Vec<(usize, DMat4)> = json["scenes"][0]["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| (i.as_u64().unwrap() as usize, DMat4::IDENTITY))
        .collect();
    while let Some((i, parent)) = stack.pop() {
        let world = parent * local(&nodes[i]);
        out.insert(
            nodes[i]["name"].as_str().unwrap_or_default().to_owned(),
            world.w_axis.truncate(),
        );
        for c in nodes[i]["children"].as_array().into_iter().flatten() {
            stack.push((c.as_u64().unwrap() as usize, world));
        }
    }
    out
}

/// `stance export-posed` poses the same document alike on the mannequin and on a T-pose avatar
/// (the shoulder nodes carrying the quarter turn), and a document made on that avatar before a
/// posture meant the same pose on every body (`"rest": "avatar"`) in the pose it was saved with.
#[test]
fn export_posed_poses_every_rest_alike_and_old_documents_as_they_were() {
    use glam::{DQuat, DVec3};
    let mannequin = temp("standard-mannequin.glb");
    let (ok, _, err) = stance(&["make-avatar", &mannequin]);
    assert!(ok, "{err}");
    let bytes = std::fs::read(&mannequin).unwrap();
    let mut json = glb_json(&bytes);
    for node in json["nodes"].as_array_mut().unwrap() {
        node.as_object_mut().unwrap().remove("extras");
        let turn = match node["name"].as_str().unwrap() {
            "l_shoulder" => 90f64,
            "r_shoulder" => -90.0,
            _ => continue,
        };
        let q = DQuat::from_rotation_z(turn.to_radians());
        node["rotation"] = serde_json::json!([q.x, q.y, q.z, q.w]);
    }
    let t_pose = temp("standard-t-pose.glb");
    std::fs::write(&t_pose, with_json(&bytes, &json)).unwrap();
    let document = temp("standard-reach.json");
    std::fs::write(
        &document,
        r#"{"rest": "standard", "posture": {"humanoid_root": {"ry": 0.4},
            "r_shoulder": {"rx": -1.3, "rz": -0.3}, "r_elbow": {"rx": -0.9},
            "l_shoulder": {"rz": 0.6}, "l_hip": {"rx": -0.6}, "l_knee": {"rx": 1.0}}}"#,
    )
    .unwrap();
    let bones = [
        ("r_shoulder", "r_elbow"),
        ("r_elbow", "r_radiocarpal"),
        ("l_shoulder", "l_elbow"),
        ("l_hip", "l_knee"),
        ("l_knee", "l_talocrural"),
    ];
    let posed = |avatar: &str, doc: &str, name: &str| {
        let out = temp(name);
        let (ok, _, err) = stance(&["export-posed", avatar, doc, &out]);
        assert!(ok, "{err}");
        (node_positions(&std::fs::read(&out).unwrap()), err)
    };
    let direction = |p: &std::collections::HashMap<String, DVec3>, (a, b): (&str, &str)| {
        (p[b] - p[a]).normalize()
    };
    let (on_mannequin, _) = posed(&mannequin, &document, "standard-1.glb");
    let (on_t_pose, _) = posed(&t_pose, &document, "standard-2.glb");
    for bone in bones {
        let angle = direction(&on_mannequin, bone)
            .angle_between(direction(&on_t_pose, bone))
            .to_degrees();
        assert!(angle < 2.0, "{bone:?}: {angle} degrees");
    }
    // Made on the T-pose avatar before: the left arm lowered by a quarter turn (back where
    // the mannequin's hangs), the right one left out to the side.
    let old = temp("standard-old.json");
    std::fs::write(
        &old,
        r#"{"avatar": {"url": "https://example.org/t-pose.glb"},
            "posture": {"l_shoulder": {"rz": -1.5707963267948966}}}"#,
    )
    .unwrap();
    let (then, note) = posed(&t_pose, &old, "standard-3.glb");
    assert!(note.contains("converted"), "{note}");
    let rest = node_positions(&bytes);
    let arm = |side: &str| {
        direction(
            &rest,
            (&format!("{side}_shoulder"), &format!("{side}_elbow")),
        )
    };
    let quarter = |d: f64| DQuat::from_rotation_z(d.to_radians());
    for (side, want) in [("l", arm("l")), ("r", quarter(-90.0) * arm("r"))] {
        let got = direction(
            &then,
            (&format!("{side}_shoulder"), &format!("{side}_elbow")),
        );
        let angle = got.angle_between(want).to_degrees();
        assert!(angle < 1.0, "{side} upper arm: {angle} degrees");
    }
}
