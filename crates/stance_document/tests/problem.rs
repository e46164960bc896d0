//! `Problem`: the one way from tasks to a solver problem, from a problem file and from a
//! document, with the same tasks, limb starts and results.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use glam::{DQuat, DVec3};
use stance_document::{Document, Problem};
use stance_hanim::scenarios::loa2_body40;
use stance_ik::{Frames, Skeleton, TaskKind};

/// The LOA2 body as a problem file's `skeleton` (names, parents, offsets, DOF, limits).
fn skeleton_json(s: &Skeleton) -> String {
    stance_document::skeleton_json(s).to_string()
}

const TASKS: &str = r#"[
 {"kind":"position","joint":"l_talocrural","target":[0.09,0.08,0.0]},
 {"kind":"limb","limb":"r_arm","target":[-0.25,1.15,0.3],"orientation":[0,0,0.3826834,0.9238795],"level":2},
 {"kind":"balance","level":3}
]"#;

#[test]
fn a_limb_task_with_an_orientation_is_the_same_problem_from_a_file_and_a_document() {
    let s = loa2_body40().unwrap();
    let file = Problem::from_json(&format!(
        r#"{{"skeleton":{},"tasks":{TASKS},"settings":{{"max_iterations":300}}}}"#,
        skeleton_json(&s)
    ))
    .unwrap();
    let document = Document::from_json(&format!(
        r#"{{"avatar":"default","posture":{{}},"tasks":{TASKS}}}"#
    ))
    .unwrap();
    let doc = Problem::from_document(&document, s.clone()).unwrap();
    // 4 solver tasks: the pin, the wrist's orientation and position, the balance.
    assert_eq!(file.tasks.len(), 4);
    assert_eq!(file.tasks, doc.tasks);
    assert_eq!(file.limb_starts.len(), 1);
    assert_eq!(doc.limb_starts.len(), 1);
    let wrist = s.joint_index("r_radiocarpal").unwrap();
    assert!(matches!(
        file.tasks[1].kind,
        TaskKind::Orientation { joint, .. } if joint == wrist
    ));
    // Solved, the hand holds the orientation as well as the position.
    let (posture, report) = file.solve().unwrap();
    let frames = Frames::new(&s, &posture);
    let want = DQuat::from_xyzw(0.0, 0.0, 0.3826834, 0.9238795).normalize();
    assert!(report.levels[1].met, "{report:?}");
    assert!(frames.rotation(wrist).angle_between(want) < 1e-5);
    assert!((frames.joint_position[wrist] - DVec3::new(-0.25, 1.15, 0.3)).length() < 1e-5);
    let (same, _) = doc.solve().unwrap();
    assert_eq!(posture, same, "the document's problem solves the same");
}

#[test]
fn problem_file_errors_name_the_field() {
    let s = loa2_body40().unwrap();
    let skeleton = skeleton_json(&s);
    for (tail, want) in [
        (
            r#""tasks":[{"kind":"limb","limb":"l_tail","target":[0,1,0]}]"#,
            "tasks[0].limb",
        ),
        (
            r#""settings":{"levels":{"0":{"lambda":0.1}}}"#,
            "settings.levels.0",
        ),
        (
            r#""settings":{"levels":{"2":{"lambda":-1}}}"#,
            "settings.levels.2.lambda",
        ),
        (r#""settings":{"hybrid":1}"#, "settings.hybrid"),
        (
            r#""settings":{"levenberg":{"lambda":0.002,"error_scale":0}}"#,
            "settings.levenberg",
        ),
        (
            r#""settings":{"levenberg":{"lambda":0.002}}"#,
            "error_scale",
        ),
        (r#""settings":{"tolerance":-1}"#, "settings"),
        (r#""settings":{"priority_budget":0}"#, "priority_budget"),
        (r#""posture":{"l_knee":{"rq":1}}"#, "posture.l_knee"),
    ] {
        let text = format!(r#"{{"skeleton":{skeleton},{tail}}}"#);
        let e = Problem::from_json(&text).unwrap_err().to_string();
        assert!(e.contains(want), "{e} (wanted {want})");
    }
    let read = Problem::from_json(&format!(
        r#"{{"skeleton":{skeleton},"settings":{{"priority_budget":2.5}}}}"#
    ))
    .unwrap();
    assert_eq!(read.settings.priority_budget, 2.5);
    let e = Problem::from_json(r#"{"skeleton":{"joints":[{"name":"a","dofs":["rq"]}]}}"#)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("skeleton.joints[0] (`a`).dofs[0]") && e.contains("rq"),
        "{e}"
    );
    assert!(
        Problem::from_json("{")
            .unwrap_err()
            .to_string()
            .contains("not valid JSON")
    );
}

/// A problem written by `problem_json` reads back as the same skeleton, tasks and start
/// posture, for every family's kinds.
#[test]
fn a_written_problem_reads_back_the_same() {
    use stance_hanim::families::families;
    for family in families() {
        let skeleton = family.body.skeleton().unwrap();
        for index in 0..3 {
            let p = family.problem(&skeleton, 7, index).unwrap();
            let json = stance_document::problem_json(&skeleton, &p.tasks, &p.start).unwrap();
            let back = Problem::from_json(&json.to_string()).unwrap();
            assert_eq!(back.skeleton, skeleton, "{}", p.name);
            assert_eq!(back.tasks.len(), p.tasks.len(), "{}", p.name);
            for (read, written) in back.tasks.iter().zip(&p.tasks) {
                // Quaternions and directions are normalised on reading (an ulp or so).
                let as_json = |t: &stance_ik::Task| {
                    serde_json::to_value(stance_document::TaskSpec::from_task(&skeleton, t))
                        .unwrap()
                };
                let (r, w) = (as_json(read), as_json(written));
                assert!(close(&r, &w), "{}: {r} read back as {w}", p.name);
            }
            assert_eq!(back.start_posture().0, p.start, "{}", p.name);
        }
    }
}

/// `settings.levenberg` is the damping that falls with the error; `lambda` a constant one.
#[test]
fn the_damping_settings_read_as_written() {
    let skeleton = skeleton_json(&loa2_body40().unwrap());
    let damping = |settings: &str| {
        Problem::from_json(&format!(
            r#"{{"skeleton":{skeleton},"settings":{settings}}}"#
        ))
        .unwrap()
        .settings
        .damping
    };
    assert_eq!(damping("{}"), stance_ik::Damping::default());
    assert_eq!(
        damping(r#"{"levenberg":{"lambda":0.01,"error_scale":0.05}}"#),
        stance_ik::Damping::Levenberg {
            lambda: 0.01,
            error_scale: 0.05
        }
    );
    assert_eq!(
        damping(r#"{"lambda":0.01}"#),
        stance_ik::Damping::Constant { lambda: 0.01 }
    );
}

/// The same JSON, numbers within 1e-12.
fn close(a: &serde_json::Value, b: &serde_json::Value) -> bool {
    use serde_json::Value;
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            (x.as_f64().unwrap() - y.as_f64().unwrap()).abs() <= 1e-12
        }
        (Value::Array(x), Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(p, q)| close(p, q))
        }
        (Value::Object(x), Value::Object(y)) => {
            x.len() == y.len() && x.iter().all(|(k, v)| y.get(k).is_some_and(|w| close(v, w)))
        }
        _ => a == b,
    }
}
