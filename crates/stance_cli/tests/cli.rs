//! `stance solve` and `stance bench` end to end, through the built binary.

// Helpers outside #[test] functions panic on broken fixtures on purpose.
#![allow(clippy::expect_used, clippy::unwrap_used, clippy::panic)]

use std::io::Write;
use std::process::Command;

use serde_json::Value;

const EXAMPLE: &str = r#"{"skeleton":{"joints":[
 {"name":"humanoid_root","parent":null,"offset":[0,0.824,0.0277],"dofs":["tx","ty","tz","rx","ry","rz"]},
 {"name":"sacroiliac","parent":"humanoid_root","offset":[0,0.0909,-0.0261],"dofs":["rx","ry","rz"],"mass":10.0,"com":[0,0.05,0]},
 {"name":"l_hip","parent":"sacroiliac","offset":[0.0961,-0.0025,-0.0017],"dofs":["rx","ry","rz"],"limits":{"rx":[-2.0,0.6]},"mass":9.8,"com":[0,-0.2,0]},
 {"name":"l_knee","parent":"l_hip","offset":[0.0079,-0.4257,0.0309],"dofs":["rx"],"limits":{"rx":[0,2.4]},"mass":4.0,"com":[0,-0.2,0]},
 {"name":"vl5","parent":"humanoid_root","offset":[0.0028,0.2328,-0.1053],"dofs":["rx","ry","rz"],"mass":30.0,"com":[0,0.2,0]},
 {"name":"skullbase","parent":"vl5","offset":[0.0016,0.5641,0.1012],"dofs":["rx","ry","rz"],"mass":5.0,"com":[0,0.1,0]},
 {"name":"l_shoulder","parent":"vl5","offset":[0.2001,0.3808,0.0389],"dofs":["rx","ry","rz"],"mass":2.0},
 {"name":"l_elbow","parent":"l_shoulder","offset":[-0.0015,-0.3019,-0.0295],"dofs":["rx"],"limits":{"rx":[-2.5,0]},"mass":1.2},
 {"name":"l_wrist","parent":"l_elbow","offset":[-0.003,-0.2694,0.0099],"dofs":["rx","rz"]}
]},
"tasks":[
 {"level":1,"kind":"position","joint":"l_wrist","point":[0,0,0],"axes":"xyz","target":[0.25,1.1,0.3],"weight":1.0},
 {"level":1,"kind":"orientation","joint":"skullbase","target":[0,0,0,1]},
 {"level":1,"kind":"gaze","joint":"skullbase","axis":[0,0,1],"target":[0.0,1.6,2.0]},
 {"level":2,"kind":"com","axes":"xz","target":[0.02,0,0.03]},
 {"level":4,"kind":"posture","weight":0.1}
],
"settings":{"max_iterations":200,"tolerance":1e-6}}"#;

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

/// `stance solve PATH --out OUT`: its report (stdout) as JSON; fails the test on an error.
fn solve_into(path: &std::path::Path, out: &std::path::Path) -> Value {
    let (ok, stdout, stderr) = stance(&[
        "solve",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    serde_json::from_str(&stdout).expect("one JSON object")
}

fn write_temp(name: &str, text: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("stance-cli-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join(name);
    let mut f = std::fs::File::create(&path).expect("create");
    f.write_all(text.as_bytes()).expect("write");
    path
}

#[test]
fn solve_prints_joints_posture_and_report() {
    let path = write_temp("example.json", EXAMPLE);
    let (ok, stdout, stderr) = stance(&["solve", path.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    let v: Value = serde_json::from_str(&stdout).expect("one JSON object");
    let wrist = v["joints"]["l_wrist"].as_array().expect("l_wrist position");
    let target = [0.25, 1.1, 0.3];
    for (a, b) in wrist.iter().zip(target) {
        assert!((a.as_f64().unwrap() - b).abs() < 1e-4, "{wrist:?}");
    }
    assert!(v["posture"]["humanoid_root"]["tx"].is_number());
    assert!(v["posture"]["l_knee"]["rx"].as_f64().unwrap() >= 0.0);
    let report = &v["report"];
    assert!(report["status"].is_string());
    assert!(report["iterations"].as_u64().unwrap() > 0);
    let levels = report["levels"].as_array().unwrap();
    assert_eq!(levels.len(), 3);
    assert!(
        levels[0]["residual_before"].as_f64().unwrap()
            > levels[0]["residual_after"].as_f64().unwrap()
    );
}

#[test]
fn solve_starts_from_a_given_posture() {
    let with_posture = EXAMPLE.replacen(
        "\"settings\":",
        "\"posture\":{\"l_knee\":{\"rx\":0.5}},\"tasks_unused\":[],\"settings\":",
        1,
    );
    let no_tasks = with_posture.replace("\"tasks\":[", "\"ignored\":[");
    let path = write_temp("posture.json", &no_tasks);
    let (ok, stdout, stderr) = stance(&["solve", path.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    let v: Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(v["posture"]["l_knee"]["rx"].as_f64(), Some(0.5));
    assert_eq!(v["report"]["iterations"].as_u64(), Some(0));
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
fn malformed_problems_are_rejected_with_the_field_named() {
    expect_error(
        "unknown.json",
        &EXAMPLE.replace("\"joint\":\"l_wrist\"", "\"joint\":\"l_wirst\""),
        &["tasks[0].joint", "unknown joint `l_wirst`"],
    );
    expect_error(
        "dup.json",
        &EXAMPLE.replace("{\"name\":\"l_knee\"", "{\"name\":\"l_hip\""),
        &["duplicate joint name `l_hip`"],
    );
    expect_error(
        "cycle.json",
        &EXAMPLE.replace(
            "\"name\":\"vl5\",\"parent\":\"humanoid_root\"",
            "\"name\":\"vl5\",\"parent\":\"l_wrist\"",
        ),
        &["cycle"],
    );
    expect_error(
        "nan.json",
        &EXAMPLE.replace("[0.25,1.1,0.3]", "[\"NaN\",1.1,0.3]"),
        &["tasks[0].target[0]", "number"],
    );
    expect_error(
        "inf.json",
        &EXAMPLE.replace("[0.25,1.1,0.3]", "[1e999,1.1,0.3]"),
        &["not valid JSON"],
    );
    expect_error(
        "short.json",
        &EXAMPLE.replace("[0.25,1.1,0.3]", "[0.25,1.1]"),
        &["tasks[0].target", "3 numbers"],
    );
    expect_error(
        "kind.json",
        &EXAMPLE.replace("\"kind\":\"gaze\"", "\"kind\":\"stare\""),
        &["tasks[2].kind", "stare"],
    );
    expect_error(
        "axes.json",
        &EXAMPLE.replace("\"axes\":\"xz\"", "\"axes\":\"xw\""),
        &["tasks[3].axes"],
    );
    expect_error(
        "dof.json",
        &EXAMPLE.replace("\"dofs\":[\"rx\",\"rz\"]", "\"dofs\":[\"rx\",\"rq\"]"),
        &["dofs[1]", "rq"],
    );
    expect_error(
        "parent.json",
        &EXAMPLE.replace("\"parent\":\"l_hip\"", "\"parent\":\"l_hop\""),
        &["unknown parent `l_hop`"],
    );
    expect_error(
        "missing.json",
        &EXAMPLE.replace("\"target\":[0.02,0,0.03]", "\"targt\":[0.02,0,0.03]"),
        &["tasks[3].target: missing"],
    );
    expect_error(
        "settings.json",
        &EXAMPLE.replace("\"tolerance\":1e-6", "\"tolerance\":-1"),
        &["settings", "tolerance"],
    );
    expect_error("json.json", "{", &["not valid JSON"]);
}

#[test]
fn bench_times_a_problem_file() {
    let path = write_temp("bench.json", EXAMPLE);
    let (ok, stdout, stderr) = stance(&[
        "bench",
        "--problem",
        path.to_str().unwrap(),
        "--json",
        "--millis",
        "20",
    ]);
    assert!(ok, "{stderr}");
    let v: Value = serde_json::from_str(&stdout).unwrap();
    assert!(v["us_per_iteration"].as_f64().unwrap() > 0.0);
    assert!(v["us_per_solve"].as_f64().unwrap() > 0.0);
    assert!(v["iterations"].as_u64().is_some());
    // The final residual of every level and the status, as `stance solve` reports them.
    let (ok, solved, _) = stance(&["solve", path.to_str().unwrap()]);
    assert!(ok);
    let solved: Value = serde_json::from_str(&solved).unwrap();
    let levels = solved["report"]["levels"].as_array().unwrap();
    let residuals = v["residuals"].as_array().unwrap();
    assert_eq!(residuals.len(), levels.len(), "{v}");
    for (r, l) in residuals.iter().zip(levels) {
        let (r, l) = (r.as_f64().unwrap(), l["residual_after"].as_f64().unwrap());
        assert!((r - l).abs() < 1e-9, "bench {r} vs solve {l}");
    }
    assert_eq!(v["status"], solved["report"]["status"]);
}

#[test]
fn bench_suite_counts_per_family_and_beside_a_peer() {
    let dir = std::env::temp_dir().join(format!("stance-cli-suite-{}", std::process::id()));
    let (one, two) = (dir.join("one"), dir.join("two"));
    std::fs::create_dir_all(&one).unwrap();
    std::fs::create_dir_all(&two).unwrap();
    // Family "one": a reachable problem and the same body asked to reach 10 m away (never
    // met); family "two": the reachable one alone.
    std::fs::write(one.join("a-reachable.json"), EXAMPLE).unwrap();
    let far = EXAMPLE.replace("[0.25,1.1,0.3]", "[10.0,1.1,0.3]");
    std::fs::write(one.join("b-unreachable.json"), far).unwrap();
    std::fs::write(one.join("notes.txt"), "not a problem").unwrap();
    std::fs::write(two.join("a-reachable.json"), EXAMPLE).unwrap();
    // A peer that met both of family one's problems in 20 iterations, 1 ms each.
    let peer = dir.join("peer.jsonl");
    std::fs::write(
        &peer,
        "{\"family\":\"one\",\"problem\":\"a-reachable.json\",\"met_every_level\":true,\"iterations\":20,\"us_per_solve\":1000.0}\n\
         {\"family\":\"one\",\"problem\":\"b-unreachable.json\",\"met_every_level\":true,\"iterations\":20,\"us_per_solve\":1000.0}\n",
    )
    .unwrap();
    let (ok, stdout, stderr) = stance(&[
        "bench",
        "--suite",
        dir.to_str().unwrap(),
        "--peer",
        peer.to_str().unwrap(),
        "--json",
    ]);
    assert!(ok, "{stderr}");
    let v: Value = serde_json::from_str(&stdout).unwrap();
    let families = v["families"].as_array().unwrap();
    assert_eq!(families.len(), 2, "{v}");
    let (f1, f2) = (&families[0], &families[1]);
    assert_eq!(
        (f1["family"].as_str(), f1["cases"].as_u64()),
        (Some("one"), Some(2))
    );
    assert_eq!(f1["met_every_level"], 1, "{v}");
    assert_eq!(f1["peer"]["met_every_level"], 2, "{v}");
    assert_eq!(f1["peer"]["stance_meets_where_peer_meets"], 1, "{v}");
    assert_eq!(f1["peer"]["median_iterations_both"]["peer"], 20.0, "{v}");
    let ratio = f1["peer"]["per_solve_ratio"].as_f64().unwrap();
    let ours = f1["peer"]["median_us_per_solve_both"]["stance"]
        .as_f64()
        .unwrap();
    assert!((ratio - 1000.0 / ours).abs() < 1e-9 * ratio, "{v}");
    assert_eq!(
        (f2["family"].as_str(), f2["met_every_level"].as_u64()),
        (Some("two"), Some(1))
    );
    assert_eq!(f2["peer"]["cases"], 0, "no peer line for family two: {v}");
    let results = v["results"].as_array().unwrap();
    assert_eq!(results.len(), 3);
    assert_eq!(results[1]["met_every_level"], false);
    // What bench/placo/compare.py reads of each result.
    assert_ne!(results[1]["status"], "converged", "{v}");
    assert_eq!(results[0]["status"], "converged", "{v}");
    assert!(
        results[0]["residuals"]
            .as_array()
            .is_some_and(|r| !r.is_empty())
    );
    // Without --json: a table with a line per family.
    let (ok, stdout, _) = stance(&["bench", "--suite", dir.to_str().unwrap()]);
    assert!(ok);
    assert!(stdout.lines().any(|l| l.starts_with("one ")), "{stdout}");
    assert!(stdout.lines().any(|l| l.starts_with("two ")), "{stdout}");
}

/// `stance families` writes problem files that `stance solve` reads, one folder per family.
#[test]
fn families_are_written_as_problem_files_that_solve() {
    let dir = std::env::temp_dir().join(format!("stance-cli-families-{}", std::process::id()));
    let (ok, stdout, stderr) = stance(&[
        "families",
        "--out",
        dir.to_str().unwrap(),
        "--cases",
        "2",
        "--family",
        "reach",
        "--family",
        "mixed",
    ]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("reach: 2 problems"), "{stdout}");
    let file = dir.join("mixed").join("mixed-0001.json");
    let (ok, stdout, stderr) = stance(&["solve", file.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    let v: Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(v["report"]["status"], "converged", "{v}");
    let (ok, _, stderr) = stance(&["families", "--out", "/tmp/x", "--family", "nope"]);
    assert!(!ok && stderr.contains("no family `nope`"), "{stderr}");
}

#[test]
fn per_level_damping_in_problem_files() {
    let with = |levels: &str| {
        EXAMPLE.replace(
            r#""settings":{"max_iterations":200,"tolerance":1e-6}"#,
            &format!(r#""settings":{{"max_iterations":200,"tolerance":1e-6,"levels":{levels}}}"#),
        )
    };
    let path = write_temp("levels.json", &with(r#"{"2":{"lambda":0.05}}"#));
    let (ok, stdout, stderr) = stance(&["solve", path.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    let v: Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(v["report"]["levels"][0]["met"], true, "{v}");
    for (levels, named) in [
        (r#"{"0":{"lambda":0.05}}"#, "settings.levels.0"),
        (r#"{"x":{"lambda":0.05}}"#, "settings.levels.x"),
        (r#"{"2":{}}"#, "settings.levels.2"),
        (r#"{"2":{"lambda":-1}}"#, "settings.levels.2.lambda"),
    ] {
        let path = write_temp("bad-levels.json", &with(levels));
        let (ok, _, stderr) = stance(&["solve", path.to_str().unwrap()]);
        assert!(!ok, "{levels} accepted");
        assert!(stderr.contains(named), "{levels}: {stderr}");
    }
}

#[test]
fn bench_runs_every_scenario() {
    let (ok, stdout, stderr) = stance(&["bench", "--json", "--millis", "5"]);
    assert!(ok, "{stderr}");
    let v: Value = serde_json::from_str(&stdout).unwrap();
    for s in ["S1", "S2", "S3", "S4", "S5", "S6"] {
        assert!(v[s]["us_per_iteration"].as_f64().unwrap() > 0.0, "{s}: {v}");
        assert!(v[s]["us_per_solve"].as_f64().is_some());
        assert!(v[s]["iterations"].as_u64().is_some());
    }
}

#[test]
fn direction_and_balance_in_problem_files() {
    // The forearm (its elbow-to-wrist offset as the axis) points straight ahead; the rotation
    // about it stays free. The centre of mass stays over the left foot's sole.
    let axis = "[-0.003,-0.2694,0.0099]";
    let tasks = format!(
        r#""tasks":[
 {{"level":1,"kind":"direction","joint":"l_elbow","axis":{axis},"target":[0,0,1]}},
 {{"level":1,"kind":"position","joint":"l_knee","target":[0.1,0.45,0.05]}},
 {{"level":2,"kind":"balance","support":["l_knee"],"margin":0.0}}
],"#
    );
    let problem = EXAMPLE.replacen(
        &EXAMPLE[EXAMPLE.find("\"tasks\"").unwrap()..EXAMPLE.find("\"settings\"").unwrap()],
        &tasks,
        1,
    );
    let path = write_temp("direction.json", &problem);
    let (ok, stdout, stderr) = stance(&["solve", path.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    let v: Value = serde_json::from_str(&stdout).unwrap();
    let at = |joint: &str| -> Vec<f64> {
        v["joints"][joint]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    let (elbow, wrist) = (at("l_elbow"), at("l_wrist"));
    let d: Vec<f64> = (0..3).map(|i| wrist[i] - elbow[i]).collect();
    let len = d.iter().map(|x| x * x).sum::<f64>().sqrt();
    assert!(
        (d[2] / len - 1.0).abs() < 1e-6,
        "the forearm points ahead: {d:?}"
    );
    let levels = v["report"]["levels"].as_array().unwrap();
    assert!(
        levels.iter().all(|l| l["met"].as_bool() == Some(true)),
        "{levels:?}"
    );

    let bad = problem.replace("\"support\":[\"l_knee\"]", "\"support\":[\"tail\"]");
    expect_error("balance-bad.json", &bad, &["tasks[2].support[0]", "tail"]);
    let bad = problem.replace("\"target\":[0,0,1]", "\"target\":[0,0,0]");
    expect_error(
        "direction-bad.json",
        &bad,
        &["tasks[0].target", "zero-length"],
    );
}

/// `stance solve` says which task gave way and why, in the words of the editor's task list:
/// the wrist pinned at level 1 and pulled elsewhere at level 2 holds its pin, and the pull
/// names the pin it conflicts with. Its residual is the distance, computed here from the
/// printed wrist position, between the wrist and the pull's target. Catches a report that only
/// gives the level (`gave_way: 2`) without the task and the reason, a residual that is not the
/// task's error, or statuses out of the file's task order.
#[test]
fn solve_says_which_task_gave_way_and_why() {
    let problem = EXAMPLE.replacen(
        r#""tasks":["#,
        r#""tasks":[
 {"level":2,"kind":"position","joint":"l_wrist","point":[0,0,0],"axes":"xyz","target":[0.1,1.4,0.4]},"#,
        1,
    );
    let path = write_temp("gave_way.json", &problem);
    let (ok, stdout, stderr) = stance(&["solve", path.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    let v: Value = serde_json::from_str(&stdout).expect("one JSON object");
    let tasks = v["tasks"].as_array().expect("tasks");
    assert_eq!(tasks.len(), 6, "one status per task of the file");
    let pull = &tasks[0];
    let pin = &tasks[1];
    assert_eq!(pin["level"], 1);
    assert_eq!(pin["met"], true, "{pin}");
    assert!(pin["gave_way"].is_null(), "{pin}");
    assert_eq!(pull["level"], 2);
    assert_eq!(pull["met"], false, "{pull}");
    let reason = pull["gave_way"].as_str().expect("a reason");
    let pin_words = pin["description"].as_str().unwrap();
    assert_eq!(pin_words, "left wrist position");
    assert_eq!(reason, format!("conflicts with level 1: {pin_words}"));
    let wrist: Vec<f64> = v["joints"]["l_wrist"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    let distance =
        ((wrist[0] - 0.1).powi(2) + (wrist[1] - 1.4).powi(2) + (wrist[2] - 0.4).powi(2)).sqrt();
    let residual = pull["residual"].as_f64().unwrap();
    assert!(
        (residual - distance).abs() < 1e-6,
        "{residual} vs {distance}"
    );
    // The comfort (posture) task is minimised, never "given way".
    assert!(tasks[5]["gave_way"].is_null(), "{}", tasks[5]);
}

/// Two characters, each with its feet pinned where they stand and a wrist goal in its own
/// frame; the second placed and turned.
const SCENE: &str = r#"{"characters": [
  {"name": "Ann", "tasks": [
    {"level": 1, "kind": "position", "joint": "l_talocrural", "target": [0.1, 0.07, 0.0]},
    {"level": 2, "kind": "position", "joint": "r_radiocarpal", "target": [-0.3, 1.3, 0.3]}]},
  {"name": "Bo", "placement": {"position": [0.8, 0, -0.2], "yaw": 90}, "tasks": [
    {"level": 1, "kind": "position", "joint": "l_radiocarpal", "target": [0.35, 1.2, 0.25]}]}
]}"#;

#[test]
fn solve_reads_a_scene_and_solves_every_character_in_its_own_frame() {
    // Catches: a scene refused or only its selected character solved, a goal read in the
    // scene's frame instead of the character's, a solved scene not written back.
    let path = write_temp("scene.json", SCENE);
    let out = path.with_file_name("scene-solved.json");
    let v = solve_into(&path, &out);
    let characters = v["characters"].as_array().expect("one entry per character");
    assert_eq!(characters.len(), 2);
    let near = |c: &Value, joint: &str, target: [f64; 3]| {
        let p = c["joints"][joint].as_array().expect("the joint's position");
        p.iter()
            .zip(target)
            .all(|(a, b)| (a.as_f64().unwrap() - b).abs() < 1e-3)
    };
    assert_eq!(characters[0]["name"], "Ann");
    assert!(near(&characters[0], "r_radiocarpal", [-0.3, 1.3, 0.3]));
    assert!(near(&characters[0], "l_talocrural", [0.1, 0.07, 0.0]));
    assert_eq!(characters[1]["name"], "Bo");
    assert_eq!(characters[1]["placement"]["yaw"], 90.0);
    assert!(near(&characters[1], "l_radiocarpal", [0.35, 1.2, 0.25]));
    assert!(characters.iter().all(|c| c["report"]["gave_way"].is_null()));
    // The scene written back solves again where it stands (its postures are the solved ones).
    let (ok, again, stderr) = stance(&["solve", out.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    let again: Value = serde_json::from_str(&again).unwrap();
    for c in again["characters"].as_array().unwrap() {
        assert!(
            c["report"]["iterations"].as_u64().unwrap() <= 1,
            "{}",
            c["report"]
        );
    }
    // A plain document is a scene of one.
    let document = write_temp(
        "document.json",
        r#"{"tasks": [{"level": 1, "kind": "position", "joint": "l_radiocarpal", "target": [0.3, 1.0, 0.3]}]}"#,
    );
    let (ok, stdout, stderr) = stance(&["solve", document.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    let v: Value = serde_json::from_str(&stdout).unwrap();
    assert!(near(&v["characters"][0], "l_radiocarpal", [0.3, 1.0, 0.3]));
    // A bad character is named; a problem file with --out is refused.
    let bad = write_temp(
        "bad-scene.json",
        r#"{"characters": [{"name": "Ann"}, {"name": "Bo", "tasks": [{"level": 1, "kind": "position", "joint": "no_such_joint", "target": [0, 1, 0]}]}]}"#,
    );
    let (ok, _, stderr) = stance(&["solve", bad.to_str().unwrap()]);
    assert!(!ok);
    assert!(
        stderr.contains("Bo") || stderr.contains("no_such_joint"),
        "{stderr}"
    );
    let problem = write_temp("problem.json", EXAMPLE);
    let (ok, _, stderr) = stance(&["solve", problem.to_str().unwrap(), "--out", "x.json"]);
    assert!(!ok);
    assert!(stderr.contains("problem file"), "{stderr}");
}

#[test]
fn solve_reads_a_scene_that_carries_its_prop_files_and_writes_them_back() {
    // Catches: a scene with `files` refused, or written back by --out without its mesh props'
    // files (a solved scene would reopen with its props as boxes).
    const BOX_GLTF: &[u8] = include_bytes!("../../stance_asset/tests/fixtures/Box.gltf");
    let carried = stance_document::FileReference::embed("Box.gltf", BOX_GLTF);
    let files = serde_json::to_value([&carried]).unwrap();
    let scene = serde_json::json!({
        "characters": [{"name": "Ann", "tasks": [
            {"level": 1, "kind": "position", "joint": "l_radiocarpal", "target": [0.3, 1.0, 0.3]}]}],
        "props": [{"name": "Box", "shape": "mesh", "file": "Box.gltf", "size": [0.3, 0.3, 0.3],
            "position": [2.0, 0.15, 0.0]}],
        "files": files,
    });
    let path = write_temp("scene-files.json", &scene.to_string());
    let out = path.with_file_name("scene-files-solved.json");
    let v = solve_into(&path, &out);
    let wrist = v["characters"][0]["joints"]["l_radiocarpal"]
        .as_array()
        .unwrap();
    let wrist: Vec<f64> = wrist.iter().map(|x| x.as_f64().unwrap()).collect();
    assert!(
        wrist
            .iter()
            .zip([0.3, 1.0, 0.3])
            .all(|(a, b)| (a - b).abs() < 1e-3),
        "solved: {wrist:?}"
    );
    let text = std::fs::read_to_string(&out).unwrap();
    let written: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(
        written["files"], scene["files"],
        "the props' files, as they came"
    );
    assert_ne!(
        written["characters"][0]["posture"],
        Value::Null,
        "the solved posture"
    );
    let solved = stance_document::Scene::from_json(&text).unwrap();
    assert_eq!(solved.files.len(), 1);
    assert!(solved.files[0].is_file(BOX_GLTF));
}

/// Two characters facing each other 0.7 m apart with their feet pinned, the first's right
/// wrist in the second's left (a task between characters, level 3).
const HAND_IN_HAND: &str = r#"{"characters": [
  {"name": "Ann", "placement": {"position": [-0.35, 0, 0], "yaw": 90}, "tasks": [
    {"level": 1, "kind": "position", "joint": "l_talocrural", "target": [0.1, 0.08, 0.0]},
    {"level": 1, "kind": "position", "joint": "r_talocrural", "target": [-0.1, 0.08, 0.0]},
    {"level": 2, "kind": "balance"}]},
  {"name": "Bo", "placement": {"position": [0.35, 0, 0], "yaw": -90}, "tasks": [
    {"level": 1, "kind": "position", "joint": "l_talocrural", "target": [0.1, 0.08, 0.0]},
    {"level": 1, "kind": "position", "joint": "r_talocrural", "target": [-0.1, 0.08, 0.0]},
    {"level": 2, "kind": "balance"}, {"level": 9, "kind": "comfort"}]},
  {"name": "Cy", "placement": {"position": [3, 0, 0]}}
], "between": [{"kind": "meet", "level": 3,
  "a": {"character": 0, "joint": "r_radiocarpal"}, "b": {"character": 1, "joint": "l_radiocarpal"}}]}"#;

#[test]
fn solve_joins_the_characters_a_task_between_them_joins() {
    // Catches: the task between characters ignored (each solved alone), a placement applied
    // twice or not at all (hands apart in the scene), a character's own pins given up for the
    // hands, the solved scene written without the task.
    let path = write_temp("hand-in-hand.json", HAND_IN_HAND);
    let out = path.with_file_name("hand-in-hand-solved.json");
    let v = solve_into(&path, &out);
    let c = v["characters"].as_array().unwrap();
    let joint = |c: &Value, name: &str| -> [f64; 3] {
        let p = c["joints"][name].as_array().expect("the joint's position");
        [0, 1, 2].map(|i| p[i].as_f64().unwrap())
    };
    // Placed by hand: turned about +Y by `yaw` degrees, then moved.
    let placed = |p: [f64; 3], x: f64, yaw: f64| {
        let (s, co) = yaw.to_radians().sin_cos();
        [co * p[0] + s * p[2] + x, p[1], -s * p[0] + co * p[2]]
    };
    let a = placed(joint(&c[0], "r_radiocarpal"), -0.35, 90.0);
    let b = placed(joint(&c[1], "l_radiocarpal"), 0.35, -90.0);
    let apart = (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt();
    assert!(apart < 1e-3, "the hands are {apart} m apart: {a:?} {b:?}");
    let reported = v["between"][0]["distance"].as_f64().unwrap();
    assert!(
        (reported - apart).abs() < 1e-6,
        "{reported} against {apart}"
    );
    for (i, character) in c[..2].iter().enumerate() {
        for (ankle, target) in [("l_talocrural", 0.1), ("r_talocrural", -0.1)] {
            let p = joint(character, ankle);
            let off = ((p[0] - target).powi(2) + (p[1] - 0.08).powi(2) + p[2].powi(2)).sqrt();
            assert!(off < 1e-3, "character {i}'s {ankle} is {off} m off");
        }
        assert_eq!(character["solved_with"], serde_json::json!([1 - i]));
    }
    // The comfort task could not join; the third character was solved alone.
    let left = c[1]["left_out"].as_array().unwrap();
    assert!(left.len() == 1 && left[0].as_str().unwrap().contains("comfort"));
    assert!(c[2].get("solved_with").is_none());
    // Written back with the task; solving it again moves nothing.
    let written = std::fs::read_to_string(&out).unwrap();
    assert!(written.contains("\"between\""), "{written}");
    let (ok, again, stderr) = stance(&["solve", out.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    let again: Value = serde_json::from_str(&again).unwrap();
    assert!(again["between"][0]["distance"].as_f64().unwrap() < 1e-3);
    assert!(
        again["characters"][0]["report"]["iterations"]
            .as_u64()
            .unwrap()
            <= 2
    );
}

/// The complete scene example of docs/document-format.md (Table 1 with its sphere and bar, a
/// second character's hand on the first's shoulder), as the document shows it: every level
/// of both characters met, the hand on the shoulder.
#[test]
fn the_documented_scene_example_solves_as_it_says() {
    let doc = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../docs/document-format.md"
    ))
    .unwrap();
    let heading = doc
        .find("### Example: Table 1 with its sphere and bar")
        .expect("the example's heading");
    let start = heading + doc[heading..].find("```json\n").unwrap() + "```json\n".len();
    let end = start + doc[start..].find("```").unwrap();
    let path = write_temp("documented-scene.json", &doc[start..end]);
    let (ok, stdout, stderr) = stance(&["solve", path.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    let v: Value = serde_json::from_str(&stdout).unwrap();
    for character in v["characters"].as_array().unwrap() {
        assert!(
            character["report"]["gave_way"].is_null(),
            "{}",
            character["report"]
        );
        for task in character["tasks"].as_array().unwrap() {
            assert_eq!(task["met"], true, "{} {task}", character["name"]);
        }
        assert_eq!(character["left_out"], serde_json::json!([]));
    }
    assert!(v["between"][0]["distance"].as_f64().unwrap() < 1e-3);
}
/// Catches a scene's props left out of its characters' collision tasks, or taken in the
/// scene's frame instead of the character's: one character placed 1 m along X and turned a
/// quarter, a 30 cm box 35 cm before it (in the scene) at chest height, its right
/// wrist pulled to the box's middle (in its own frame) with the collision task at level 2.
/// Solved, the wrist is outside the box (more than its capsule's 2.2 cm from it, in the
/// scene); without the box the same problem puts the wrist at the middle.
#[test]
fn solve_holds_a_scene_s_characters_off_its_props() {
    // The character's frame: its +Z (front) is the scene's +X after a quarter turn.
    let scene = |props: &str| {
        format!(
            r#"{{"characters": [{{"name": "Ann", "placement": {{"position": [1.0, 0, 0], "yaw": 90}},
              "tasks": [
                {{"level": 1, "kind": "position", "joint": "l_talocrural", "target": [0.1101, 0.0656, -0.0736]}},
                {{"level": 1, "kind": "position", "joint": "r_talocrural", "target": [-0.0801, 0.0712, -0.0766]}},
                {{"level": 2, "kind": "collision"}},
                {{"level": 3, "kind": "position", "joint": "r_radiocarpal", "target": [-0.2, 1.0, 0.35]}}]}}],
              "props": [{props}]}}"#
        )
    };
    // The goal in the scene: the character's (-0.2, 1.0, 0.35) turned a quarter about Y and
    // moved 1 m along X: (1.35, 1.0, 0.2).
    let with_box = write_temp(
        "scene-box.json",
        &scene(r#"{"shape": "box", "size": [0.3, 0.3, 0.3], "position": [1.35, 1.0, 0.2]}"#),
    );
    let without = write_temp("scene-no-box.json", &scene(""));
    let wrist_in_scene = |path: &std::path::Path| {
        let (ok, stdout, stderr) = stance(&["solve", path.to_str().unwrap()]);
        assert!(ok, "{stderr}");
        let v: Value = serde_json::from_str(&stdout).unwrap();
        let p = v["characters"][0]["joints"]["r_radiocarpal"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect::<Vec<_>>();
        // Character frame to scene: a quarter turn about Y (x' = z, z' = -x), then +1 m in X.
        [p[2] + 1.0, p[1], -p[0]]
    };
    let outside = |p: [f64; 3]| {
        let q = [p[0] - 1.35, p[1] - 1.0, p[2] - 0.2];
        let d: Vec<f64> = q.iter().map(|v| (v.abs() - 0.15).max(0.0)).collect();
        (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
    };
    let free = wrist_in_scene(&without);
    assert!(
        outside(free) < 1e-3,
        "without the box the wrist reaches {free:?}"
    );
    let held = wrist_in_scene(&with_box);
    assert!(
        outside(held) > 0.022,
        "the wrist at {held:?}, {} m from the box",
        outside(held)
    );
}
