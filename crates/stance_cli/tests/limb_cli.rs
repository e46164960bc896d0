//! `stance solve` with `{"kind": "limb"}` tasks and `stance bench` S7, through the built binary.

// Helpers outside #[test] functions panic on broken fixtures on purpose.
#![allow(clippy::expect_used, clippy::unwrap_used, clippy::panic)]

use std::io::Write;
use std::process::Command;

use serde_json::Value;

const SKELETON: &str = r#"{"joints":[
 {"name":"humanoid_root","parent":null,"offset":[0,0.824,0.0277],"dofs":["tx","ty","tz","rx","ry","rz"]},
 {"name":"vl5","parent":"humanoid_root","offset":[0.0028,0.2328,-0.1053],"dofs":["rx","ry","rz"],"mass":30.0},
 {"name":"l_hip","parent":"humanoid_root","offset":[0.0961,0.0884,-0.0278],"dofs":["rx","ry","rz"],"limits":{"rx":[-2.0,0.6]}},
 {"name":"l_knee","parent":"l_hip","offset":[0.0079,-0.4257,0.0309],"dofs":["rx"],"limits":{"rx":[0,2.4]}},
 {"name":"l_talocrural","parent":"l_knee","offset":[0.0061,-0.4211,-0.1044],"dofs":["rx","rz"]},
 {"name":"l_shoulder","parent":"vl5","offset":[0.2001,0.3808,0.0389],"dofs":["rx","ry","rz"]},
 {"name":"l_elbow","parent":"l_shoulder","offset":[-0.0015,-0.3019,-0.0295],"dofs":["rx"],"limits":{"rx":[-2.5,0]}},
 {"name":"l_wrist","parent":"l_elbow","offset":[-0.003,-0.2694,0.0099],"dofs":["rx","rz"]}
]}"#;

/// The skeleton with the root and the spine fixed (only the limbs move).
fn fixed_torso() -> String {
    SKELETON
        .replace(r#""dofs":["tx","ty","tz","rx","ry","rz"]"#, r#""dofs":[]"#)
        .replace(
            r#""dofs":["rx","ry","rz"],"mass":30.0"#,
            r#""dofs":[],"mass":30.0"#,
        )
}

fn problem(tasks: &str, settings: &str) -> String {
    format!(r#"{{"skeleton":{SKELETON},"tasks":[{tasks}],"settings":{{{settings}}}}}"#)
}

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

fn write_temp(name: &str, text: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("stance-limb-cli-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join(name);
    let mut f = std::fs::File::create(&path).expect("create");
    f.write_all(text.as_bytes()).expect("write");
    path
}

fn solve(name: &str, text: &str) -> Value {
    let path = write_temp(name, text);
    let (ok, stdout, stderr) = stance(&["solve", path.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    serde_json::from_str(&stdout).expect("one JSON object")
}

fn close(v: &Value, target: [f64; 3], tol: f64) -> bool {
    let a = v.as_array().expect("a point");
    a.iter()
        .zip(target)
        .all(|(x, t)| (x.as_f64().unwrap() - t).abs() < tol)
}

#[test]
fn limb_task_with_named_joints_meets_target_and_swivel() {
    let target = [0.35, 1.05, 0.2];
    let v = solve(
        "limb.json",
        &problem(
            r#"{"level":1,"kind":"limb","joints":["l_shoulder","l_elbow","l_wrist"],"target":[0.35,1.05,0.2],"swivel":0.3}"#,
            "",
        ),
    );
    assert!(close(&v["joints"]["l_wrist"], target, 1e-9), "{v}");
    assert_eq!(v["report"]["status"], "converged");
    let limb = &v["limbs"][0];
    assert_eq!(limb["joints"][2], "l_wrist");
    assert!((limb["start_swivel"].as_f64().unwrap() - 0.3).abs() < 1e-12);
    assert!((limb["swivel"].as_f64().unwrap() - 0.3).abs() < 1e-9);
    assert_eq!(limb["reached"], true);
    assert_eq!(limb["within_limits"], true);
    assert!(
        v["report"]["analytic_restarts"]
            .as_array()
            .unwrap()
            .is_empty()
    );
    // The elbow stays inside its limits.
    let elbow = v["posture"]["l_elbow"]["rx"].as_f64().unwrap();
    assert!((-2.5..=0.0).contains(&elbow));
}

#[test]
fn limb_shorthand_resolves_hanim_names_and_aliases() {
    // `l_arm` ends at l_radiocarpal, here present under its alias l_wrist; `l_leg` at
    // l_talocrural. An orientation goal for the ankle comes with it.
    let v = solve(
        "shorthand.json",
        &problem(
            r#"{"level":1,"kind":"limb","limb":"l_arm","target":[0.3,1.0,0.15]},
               {"level":1,"kind":"limb","limb":"l_leg","target":[0.12,0.2,0.1],"swivel":-0.2,
                "orientation":[0,0,0,1]},
               {"level":2,"kind":"posture","weight":0.1}"#,
            "",
        ),
    );
    assert!(
        close(&v["joints"]["l_wrist"], [0.3, 1.0, 0.15], 1e-6),
        "{v}"
    );
    assert!(
        close(&v["joints"]["l_talocrural"], [0.12, 0.2, 0.1], 1e-6),
        "{v}"
    );
    let limbs = v["limbs"].as_array().unwrap();
    assert_eq!(limbs.len(), 2);
    assert_eq!(limbs[1]["joints"][0], "l_hip");
    assert_eq!(limbs[1]["joints"][2], "l_talocrural");
}

#[test]
fn unreachable_limb_goal_extends_toward_it() {
    let text = format!(
        r#"{{"skeleton":{},"tasks":[{{"kind":"limb","limb":"l_arm","target":[1.5,1.4,0.0],"swivel":0.0}}]}}"#,
        fixed_torso()
    );
    let v = solve("far.json", &text);
    assert_eq!(v["limbs"][0]["reached"], false);
    assert_eq!(v["report"]["status"], "stalled");
    let wrist = v["joints"]["l_wrist"].as_array().unwrap();
    assert!(wrist.iter().all(|x| x.as_f64().unwrap().is_finite()));
}

#[test]
fn hybrid_setting_restarts_a_stalled_arm() {
    // The straight arm hangs down; the target lies on it, closer to the shoulder: the
    // variational solver alone cannot move the wrist along the arm.
    let shoulder = [0.2029, 1.4376, -0.0387];
    let target = format!("[{},{},{}]", shoulder[0], shoulder[1] - 0.4, shoulder[2]);
    let straight = fixed_torso()
        .replace("[-0.0015,-0.3019,-0.0295]", "[0,-0.3019,0]")
        .replace("[-0.003,-0.2694,0.0099]", "[0,-0.2694,0]");
    let tasks = format!(r#"[{{"level":1,"kind":"position","joint":"l_wrist","target":{target}}}]"#);
    let text = |settings: &str| {
        format!(r#"{{"skeleton":{straight},"tasks":{tasks},"settings":{{{settings}}}}}"#)
    };
    let alone = solve("alone.json", &text(r#""hybrid":false"#));
    assert_eq!(alone["report"]["status"], "stalled");
    let hybrid = solve("hybrid.json", &text(r#""hybrid":true"#));
    assert_eq!(hybrid["report"]["status"], "converged", "{hybrid}");
    let restarts = hybrid["report"]["analytic_restarts"].as_array().unwrap();
    assert_eq!(restarts.len(), 1);
    assert_eq!(restarts[0]["joints"][1], "l_elbow");
}

fn expect_error(name: &str, text: &str, needles: &[&str]) {
    let path = write_temp(name, text);
    let (ok, _, stderr) = stance(&["solve", path.to_str().unwrap()]);
    assert!(!ok, "{name} should fail");
    for n in needles {
        assert!(stderr.contains(n), "{name}: `{n}` not in: {stderr}");
    }
}

#[test]
fn malformed_limb_tasks_are_rejected_with_the_field_named() {
    expect_error(
        "unknown_limb.json",
        &problem(r#"{"kind":"limb","limb":"l_tail","target":[0,1,0]}"#, ""),
        &["tasks[0].limb", "l_tail"],
    );
    expect_error(
        "two_joints.json",
        &problem(
            r#"{"kind":"limb","joints":["l_shoulder","l_elbow"],"target":[0,1,0]}"#,
            "",
        ),
        &["tasks[0].joints", "3 joint names"],
    );
    expect_error(
        "not_chain.json",
        &problem(
            r#"{"kind":"limb","joints":["l_shoulder","l_knee","l_wrist"],"target":[0,1,0]}"#,
            "",
        ),
        &["tasks[0]", "not a solvable limb"],
    );
    expect_error(
        "both.json",
        &problem(
            r#"{"kind":"limb","limb":"l_arm","joints":["l_shoulder","l_elbow","l_wrist"],"target":[0,1,0]}"#,
            "",
        ),
        &["tasks[0]", "not both"],
    );
    expect_error(
        "swivel.json",
        &problem(
            r#"{"kind":"limb","limb":"l_arm","target":[0,1,0],"swivel":"x"}"#,
            "",
        ),
        &["tasks[0].swivel", "number"],
    );
    expect_error(
        "no_arm.json",
        &problem(r#"{"kind":"limb","limb":"r_arm","target":[0,1,0]}"#, ""),
        &["tasks[0].limb", "lacks"],
    );
}

#[test]
fn bench_reports_s7() {
    let (ok, stdout, stderr) = stance(&["bench", "--json", "--millis", "5", "--scenario", "S7"]);
    assert!(ok, "{stderr}");
    let v: Value = serde_json::from_str(&stdout).unwrap();
    assert!(v["S7"]["us_per_solve"].as_f64().unwrap() > 0.0, "{v}");
    assert_eq!(v["S7"]["status"], "converged");
    assert!(v.get("S1").is_none());
}
