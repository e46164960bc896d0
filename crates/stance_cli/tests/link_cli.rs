//! `stance link encode` / `stance link decode` end to end, through the built binary.

#![allow(clippy::expect_used, clippy::unwrap_used, clippy::panic)]

use std::io::Write;
use std::process::{Command, Stdio};

use serde_json::Value;

const DOC: &str = r#"{
  "version": 1,
  "avatar": {"url": "https://example.org/avatars/jin.glb"},
  "posture": {"humanoid_root": {"tx": 0.1, "ty": -0.02, "tz": 0, "rx": 0, "ry": 0.5, "rz": 0},
              "l_knee": {"rx": 0.3}, "l_shoulder": {"rx": -0.4, "ry": 0.1, "rz": 1.2}},
  "tasks": [
    {"level": 1, "kind": "position", "joint": "l_radiocarpal", "point": [0, 0, 0], "axes": "xyz",
     "target": [0.25, 1.1, 0.3], "weight": 1.0},
    {"level": 1, "kind": "orientation", "joint": "skullbase", "target": [0, 0, 0, 1]},
    {"level": 1, "kind": "gaze", "joint": "skullbase", "axis": [0, 0, 1], "target": [0, 1.6, 2]},
    {"level": 2, "kind": "com", "axes": "xz", "target": [0.02, 0, 0.03]},
    {"level": 3, "kind": "limb", "limb": "r_arm", "target": [-0.3, 1.2, 0.3], "swivel": 0.5},
    {"level": 4, "kind": "posture", "weight": 0.1}
  ]
}"#;

fn stance(args: &[&str], stdin: Option<&str>) -> (bool, String, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_stance"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("runs");
    if let Some(text) = stdin {
        child
            .stdin
            .take()
            .unwrap()
            .write_all(text.as_bytes())
            .unwrap();
    } else {
        drop(child.stdin.take());
    }
    let out = child.wait_with_output().expect("waits");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn write_temp(name: &str, text: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("stance-link-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join(name);
    std::fs::write(&path, text).expect("write");
    path
}

fn encode(doc: &str) -> String {
    let path = write_temp("doc.json", doc);
    let (ok, stdout, stderr) = stance(&["link", "encode", path.to_str().unwrap()], None);
    assert!(ok, "{stderr}");
    let fragment = stdout.trim().to_owned();
    assert!(!fragment.is_empty() && !fragment.contains('#'));
    assert!(
        fragment
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_'),
        "{fragment}"
    );
    fragment
}

#[test]
fn encode_then_decode_gives_the_document_back() {
    let fragment = encode(DOC);
    let url = format!("https://stance.example/#{fragment}");
    for input in [fragment.as_str(), url.as_str()] {
        let (ok, stdout, stderr) = stance(&["link", "decode", input], None);
        assert!(ok, "{stderr}");
        let v: Value = serde_json::from_str(&stdout).expect("JSON document");
        assert_eq!(
            v["avatar"]["url"].as_str(),
            Some("https://example.org/avatars/jin.glb")
        );
        // Within the quantisation: 0.005 degrees for angles.
        let knee = v["posture"]["l_knee"]["rx"].as_f64().unwrap();
        assert!((knee - 0.3).abs() <= 0.0025f64.to_radians(), "{knee}");
        let shoulder = v["posture"]["l_shoulder"]["rz"].as_f64().unwrap();
        assert!((shoulder - 1.2).abs() < 1e-4, "{shoulder}");
        let tasks = v["tasks"].as_array().unwrap();
        let kinds: Vec<&str> = tasks.iter().map(|t| t["kind"].as_str().unwrap()).collect();
        assert_eq!(
            kinds,
            ["position", "orientation", "gaze", "com", "limb", "posture"]
        );
        assert_eq!(tasks[4]["limb"].as_str(), Some("r_arm"));
        assert_eq!(tasks[5]["weight"].as_f64(), Some(0.1));
        // The decoded document is itself a valid document: encoding it gives the same link.
        let again = encode(&stdout);
        assert_eq!(again, fragment);
    }
}

#[test]
fn encode_reads_standard_input() {
    let (ok, stdout, stderr) = stance(&["link", "encode", "-"], Some(DOC));
    assert!(ok, "{stderr}");
    assert_eq!(stdout.trim(), encode(DOC));
}

#[test]
fn damaged_links_fail_with_the_reason() {
    let fragment = encode(DOC);
    let cut = &fragment[..fragment.len() - 10];
    let (ok, stdout, stderr) = stance(&["link", "decode", cut], None);
    assert!(!ok);
    assert!(stdout.is_empty());
    assert!(stderr.contains("incomplete"), "{stderr}");

    let mut chars: Vec<char> = fragment.chars().collect();
    chars[10] = if chars[10] == 'x' { 'y' } else { 'x' };
    let changed: String = chars.into_iter().collect();
    let (ok, _, stderr) = stance(&["link", "decode", &changed], None);
    assert!(!ok);
    assert!(stderr.contains("checksum"), "{stderr}");

    let (ok, _, stderr) = stance(&["link", "decode", "https://stance.example/#"], None);
    assert!(!ok);
    assert!(stderr.contains("nothing after"), "{stderr}");

    let (ok, _, stderr) = stance(&["link", "decode", "abc$def"], None);
    assert!(!ok);
    assert!(stderr.contains("`$`"), "{stderr}");
}

#[test]
fn invalid_documents_are_rejected_with_the_field_named() {
    let path = write_temp(
        "bad.json",
        &DOC.replace("[0.25, 1.1, 0.3]", "[0.25, \"x\", 0.3]"),
    );
    let (ok, _, stderr) = stance(&["link", "encode", path.to_str().unwrap()], None);
    assert!(!ok);
    assert!(stderr.contains("tasks[0].target[1]"), "{stderr}");
    let (ok, _, stderr) = stance(&["link", "encode", "/no/such/file.json"], None);
    assert!(!ok);
    assert!(stderr.contains("cannot read"), "{stderr}");
}
