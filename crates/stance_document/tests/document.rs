//! The document's JSON form and its conversion into solver tasks and postures.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use crate::common;

use common::*;
use stance_document::{
    AvatarReference, Document, DocumentError, PostureValues, TaskKindSpec, TaskSpec,
};
use stance_hanim::scenarios::loa2_body40;
use stance_ik::{Dof, Posture, TaskKind};

/// The `tasks` array of the example in docs/problem-format.md.
const PROBLEM_TASKS: &str = r#"[
    {"level": 1, "kind": "position", "joint": "l_radiocarpal", "point": [0, 0, 0], "axes": "xyz",
     "target": [0.25, 1.1, 0.3], "weight": 1.0},
    {"level": 1, "kind": "orientation", "joint": "skullbase", "target": [0, 0, 0, 1]},
    {"level": 1, "kind": "gaze", "joint": "skullbase", "axis": [0, 0, 1], "target": [0, 1.6, 2]},
    {"level": 2, "kind": "com", "axes": "xz", "target": [0.02, 0, 0.03]},
    {"level": 4, "kind": "posture", "weight": 0.1}
  ]"#;

fn doc_with_tasks(tasks: &str) -> String {
    format!(r#"{{"avatar": "default", "posture": {{"l_knee": {{"rx": 0.3}}}}, "tasks": {tasks}}}"#)
}

fn err(text: &str) -> String {
    Document::from_json(text).unwrap_err().to_string()
}

#[test]
fn a_problem_files_tasks_are_document_tasks() {
    let d = Document::from_json(&doc_with_tasks(PROBLEM_TASKS)).unwrap();
    assert_eq!(d.tasks.len(), 5);
    assert_eq!(d.avatar, AvatarReference::Default);
    assert_eq!(d.posture.get("l_knee", Dof::Rx), Some(0.3));
    assert_eq!(d.tasks[4].weight, 0.1);
    assert_eq!(d.tasks[4].level, 4);
    let s = loa2_body40().unwrap();
    let tasks = d.to_tasks(&s).unwrap();
    assert!(matches!(tasks[0].kind, TaskKind::Position { .. }));
    assert!(matches!(tasks[3].kind, TaskKind::CenterOfMass { .. }));
    assert!(tasks[4].is_posture());
    let p = d.to_posture(&s).unwrap();
    let knee = s.joint_index("l_knee").unwrap();
    assert_eq!(p.values()[s.joints()[knee].dof_start], 0.3);
}

/// Catches a reader that takes any JSON object for a document: an OpenPose keypoints file
/// (what `stance render --keypoints-out` writes) opened by mistake read as an empty document,
/// and opening it replaced the user's posture and tasks with nothing. The empty document `{}`
/// and unknown fields beside a document's still read.
#[test]
fn a_json_file_that_is_no_document_is_refused_by_name() {
    let openpose = r#"{"people": [{"pose_keypoints_2d": [1, 2, 1]}], "canvas_width": 512, "canvas_height": 512}"#;
    let e = err(openpose);
    assert!(
        e.contains("none of a document's fields") && e.contains("people"),
        "{e}"
    );
    assert!(e.contains("posture"), "{e}");
    assert_eq!(
        Document::from_json("{}").unwrap(),
        Document::from_json("{}").unwrap()
    );
    let d = Document::from_json(r#"{"posture": {"l_knee": {"rx": 0.3}}, "note": "mine"}"#).unwrap();
    assert_eq!(d.posture.get("l_knee", Dof::Rx), Some(0.3));
}

#[test]
fn json_round_trips_exactly() {
    let mut r = rng(5);
    for _ in 0..100 {
        let d = random_document(&mut r);
        let text = d.to_json(false);
        assert_eq!(Document::from_json(&text).unwrap(), d, "{text}");
        let v: Document = serde_json::from_str(&d.to_json(true)).unwrap();
        assert_eq!(v, d);
    }
}

#[test]
fn errors_name_the_field() {
    let e = err(&doc_with_tasks(
        r#"[{"kind":"position","joint":"l_wrist","target":["NaN",1,2]}]"#,
    ));
    assert!(
        e.starts_with("tasks[0].target[0]: expected a number"),
        "{e}"
    );
    let e = err(&doc_with_tasks(
        r#"[{"kind":"position","joint":"l_wrist","target":[1e999,1,2]}]"#,
    ));
    assert!(e.contains("not valid JSON"), "{e}");
    let e = err(&doc_with_tasks(r#"[{"kind":"com","target":[1,2]}]"#));
    assert!(
        e.starts_with("tasks[0].target: expected 3 numbers, found 2"),
        "{e}"
    );
    let e = err(&doc_with_tasks(
        r#"[{"kind":"com"},{"kind":"stare","target":[1,2,3]}]"#,
    ));
    assert!(e.starts_with("tasks[0].target: missing"), "{e}");
    let e = err(&doc_with_tasks(r#"[{"kind":"stare","target":[1,2,3]}]"#));
    assert!(e.starts_with("tasks[0].kind: unknown kind `stare`"), "{e}");
    let e = err(&doc_with_tasks(
        r#"[{"kind":"com","axes":"xw","target":[1,2,3]}]"#,
    ));
    assert!(e.starts_with("tasks[0].axes"), "{e}");
    let e = err(&doc_with_tasks(
        r#"[{"kind":"com","level":0,"target":[1,2,3]}]"#,
    ));
    assert!(e.starts_with("tasks[0].level"), "{e}");
    let e = err(&doc_with_tasks(
        r#"[{"kind":"orientation","joint":"a","target":[0,0,0,0]}]"#,
    ));
    assert!(
        e.contains("tasks[0].target: the quaternion has zero length"),
        "{e}"
    );
    let e = err(&doc_with_tasks(r#"[{"kind":"limb","target":[0,0,0]}]"#));
    assert!(
        e.starts_with("tasks[0].joints: missing (or give `limb`)"),
        "{e}"
    );
    let e = err(&doc_with_tasks(
        r#"[{"kind":"limb","limb":"l_arm","joints":["a","b","c"],"target":[0,0,0]}]"#,
    ));
    assert!(
        e.starts_with("tasks[0]: give either `joints` or `limb`"),
        "{e}"
    );
    let e = err(&doc_with_tasks(
        r#"[{"kind":"limb","limb":"l_arm","target":[0,0,0],"orientation":[0,0,0]}]"#,
    ));
    assert!(
        e.starts_with("tasks[0].orientation: expected 4 numbers"),
        "{e}"
    );
    let e = err(&doc_with_tasks(
        r#"[{"kind":"limb","limb":"l_tail","target":[0,0,0]}]"#,
    ));
    assert!(e.contains("unknown limb `l_tail`"), "{e}");
    let e = err(r#"{"posture": {"l_knee": {"rq": 1}}}"#);
    assert!(e.starts_with("posture.l_knee.rq: unknown DOF"), "{e}");
    let e = err(r#"{"avatar": 3}"#);
    assert!(e.starts_with("avatar: "), "{e}");
    let e = err(r#"{"version": 7}"#);
    assert!(e.contains("newer version of Stance (format 7)"), "{e}");
    assert!(err("{").contains("not valid JSON"));

    // Against a skeleton.
    let s = loa2_body40().unwrap();
    let d = Document::from_json(&doc_with_tasks(
        r#"[{"kind":"com","target":[0,0,0]},{"kind":"com","target":[0,0,0]},
            {"kind":"position","joint":"l_wirst","target":[0,0,0]}]"#,
    ))
    .unwrap();
    let e = d.to_tasks(&s).unwrap_err();
    assert_eq!(e.to_string(), "tasks[2].joint: unknown joint `l_wirst`");
    assert_eq!(e.path(), "tasks[2].joint");
    let mut p = PostureValues::default();
    p.set("l_knee", Dof::Ry, 0.1);
    let e = p.to_posture(&s).unwrap_err().to_string();
    assert_eq!(e, "posture.l_knee.ry: joint `l_knee` has no DOF `ry`");
    let mut p = PostureValues::default();
    p.set("l_knee", Dof::Rx, f64::NAN);
    assert!(p.to_posture(&s).unwrap_err().to_string().contains("finite"));
    let doc = Document {
        posture: p,
        ..Document::default()
    };
    assert!(
        doc.validate()
            .unwrap_err()
            .to_string()
            .starts_with("posture.l_knee.rx")
    );
}

#[test]
fn limb_tasks_give_a_closed_form_limb_and_an_end_joint_task() {
    let s = loa2_body40().unwrap();
    let d = Document::from_json(&doc_with_tasks(
        r#"[{"kind":"limb","limb":"l_arm","target":[0.3,1.0,0.2],"swivel":0.3,"level":2},
            {"kind":"limb","joints":["r_hip","r_knee","r_ankle"],"target":[-0.1,0.1,0.0],
             "orientation":[0,0,0,1]}]"#,
    ))
    .unwrap();
    let tasks = d.to_tasks(&s).unwrap();
    // l_arm: a position task; r_leg with an orientation: orientation + position.
    assert_eq!(tasks.len(), 3);
    let wrist = s.joint_index("l_radiocarpal").unwrap();
    let ankle = s.joint_index("r_talocrural").unwrap();
    assert!(
        matches!(tasks[0].kind, TaskKind::Position { effector, .. } if effector.joint == wrist)
    );
    assert_eq!(tasks[0].level, 2);
    assert!(matches!(tasks[1].kind, TaskKind::Orientation { joint, .. } if joint == ankle));
    assert!(
        matches!(tasks[2].kind, TaskKind::Position { effector, .. } if effector.joint == ankle)
    );
    let limbs = d.to_limbs(&s).unwrap();
    assert_eq!(limbs.len(), 2);
    assert_eq!(limbs[0].0, 0);
    assert_eq!(limbs[0].1.swivel, Some(0.3));
    assert_eq!(limbs[0].1.limb.joints()[2], wrist);
    assert!(limbs[1].1.goal.orientation.is_some());
    // A limb the skeleton lacks.
    let d = Document::from_json(&doc_with_tasks(
        r#"[{"kind":"limb","joints":["l_hip","l_knee","l_toe"],"target":[0,0,0]}]"#,
    ))
    .unwrap();
    let e = d.to_tasks(&s).unwrap_err();
    assert_eq!(e.to_string(), "tasks[0].joints[2]: unknown joint `l_toe`");
    assert!(matches!(e, DocumentError::Field { .. }));
}

#[test]
fn postures_convert_both_ways_and_aliases_resolve() {
    let s = loa2_body40().unwrap();
    let mut r = rng(3);
    let values: Vec<f64> = (0..s.dof_count())
        .map(|_| uniform(&mut r, -1.0, 1.0))
        .collect();
    let p = Posture::from_values(&s, values).unwrap();
    let pv = PostureValues::from_posture(&s, &p);
    assert_eq!(pv.to_posture(&s).unwrap(), p);
    // The root has 6 DOF, the knee 1.
    assert!(pv.joints["humanoid_root"].iter().count() == 6);
    assert!(pv.joints["l_knee"].iter().count() == 1);
    // `l_ankle` is the H-Anim 1.1 name of `l_talocrural`.
    let mut a = PostureValues::default();
    a.set("l_ankle", Dof::Rx, 0.2);
    let pa = a.to_posture(&s).unwrap();
    let j = s.joint_index("l_talocrural").unwrap();
    assert_eq!(pa.values()[s.joints()[j].dof_start], 0.2);
    let t = TaskSpec::new(TaskKindSpec::Position {
        joint: "l_wrist".into(),
        point: [0.0; 3],
        axes: stance_ik::Axes::XYZ,
        target: [0.0, 1.0, 0.0],
    });
    let task = t.to_task(&s, &[]).unwrap();
    let wrist = s.joint_index("l_radiocarpal").unwrap();
    assert!(matches!(task.kind, TaskKind::Position { effector, .. } if effector.joint == wrist));
}

#[test]
fn every_task_kind_converts() {
    let s = loa2_body40().unwrap();
    let d = Document::from_json(&doc_with_tasks(
        r#"[{"kind":"orientation","joint":"skullbase","target":[0,0,0,2],"level":3,"weight":0.5,"active":false},
            {"kind":"gaze","joint":"skullbase","axis":[0,0,2],"point":[0,0.1,0],"target":[0,1.6,2]},
            {"kind":"posture","joints":["l_hip","l_knee"],"reference":{"l_knee":{"rx":0.4}}}]"#,
    ))
    .unwrap();
    let t = d.to_tasks(&s).unwrap();
    assert_eq!((t[0].level, t[0].weight, t[0].active), (3, 0.5, false));
    match &t[0].kind {
        TaskKind::Orientation { target, .. } => assert!((target.length() - 1.0).abs() < 1e-12),
        k => panic!("{k:?}"),
    }
    match &t[1].kind {
        TaskKind::Gaze { axis, .. } => assert!((axis.length() - 1.0).abs() < 1e-12),
        k => panic!("{k:?}"),
    }
    match &t[2].kind {
        TaskKind::PostureAttraction { dofs, reference } => {
            assert_eq!(dofs.len(), 4);
            assert!(reference.contains(&0.4));
        }
        k => panic!("{k:?}"),
    }
}

#[test]
fn direction_and_balance_convert() {
    let s = loa2_body40().unwrap();
    let d = Document::from_json(&doc_with_tasks(
        r#"[{"kind":"direction","joint":"sacroiliac","target":[0,2,0]},
            {"kind":"direction","joint":"r_wrist","axis":[3,0,0],"target":[0,-1,0],"level":2},
            {"kind":"balance","support":["l_talocrural","l_ankle","r_wrist"],"margin":0.05}]"#,
    ))
    .unwrap();
    let t = d.to_tasks(&s).unwrap();
    match &t[0].kind {
        TaskKind::Direction { axis, target, .. } => {
            // The axis defaults to +Y; both are made unit.
            assert_eq!((*axis, *target), (glam::DVec3::Y, glam::DVec3::Y));
        }
        k => panic!("{k:?}"),
    }
    match &t[1].kind {
        TaskKind::Direction { joint, axis, .. } => {
            assert_eq!(*joint, s.joint_index("r_radiocarpal").unwrap());
            assert_eq!(*axis, glam::DVec3::X);
        }
        k => panic!("{k:?}"),
    }
    match &t[2].kind {
        TaskKind::Balance {
            support, margin, ..
        } => {
            // The left foot once (named twice, one sole: 4 corners), the wrist as a
            // point.
            let ankle = s.joint_index("l_talocrural").unwrap();
            let wrist = s.joint_index("r_radiocarpal").unwrap();
            assert_eq!(support.len(), 5);
            assert_eq!(support.iter().filter(|e| e.joint == ankle).count(), 4);
            assert_eq!(support[4].joint, wrist);
            assert_eq!(*margin, 0.05);
        }
        k => panic!("{k:?}"),
    }
    // The JSON round trip keeps them.
    assert_eq!(Document::from_json(&d.to_json(false)).unwrap(), d);
}

#[test]
fn balance_without_support_stands_on_the_pinned_contacts() {
    let s = loa2_body40().unwrap();
    let joint_of = |t: &TaskKind| match t {
        TaskKind::Balance { support, .. } => {
            let mut joints: Vec<String> = support
                .iter()
                .map(|e| s.joints()[e.joint].name.clone())
                .collect();
            joints.dedup();
            joints
        }
        k => panic!("{k:?}"),
    };
    // The left ankle is pinned on the floor, the right hand on a table (1 m up), the right
    // knee on the floor at level 3, the left wrist's height is free (axes "xz").
    let d = Document::from_json(&doc_with_tasks(
        r#"[{"kind":"position","joint":"l_talocrural","target":[0.1,0.08,0]},
            {"kind":"position","joint":"r_radiocarpal","target":[0.3,1.0,0.4]},
            {"kind":"position","joint":"r_knee","point":[0,0,0.05],"target":[-0.1,0.05,0.3],"level":3},
            {"kind":"position","joint":"l_radiocarpal","axes":"xz","target":[0,0,0]},
            {"kind":"balance","level":2}]"#,
    ))
    .unwrap();
    let t = d.to_tasks(&s).unwrap();
    assert_eq!(joint_of(&t[4].kind), ["l_talocrural", "r_knee"]);
    match &t[4].kind {
        TaskKind::Balance {
            support, margin, ..
        } => {
            assert_eq!(*margin, stance_document::DEFAULT_BALANCE_MARGIN);
            assert_eq!(support[4].point, glam::DVec3::new(0.0, 0.0, 0.05));
        }
        k => panic!("{k:?}"),
    }
    // Nothing pinned on the floor: both feet.
    let d = Document::from_json(&doc_with_tasks(r#"[{"kind":"balance"}]"#)).unwrap();
    let t = d.to_tasks(&s).unwrap();
    assert_eq!(joint_of(&t[0].kind), ["l_talocrural", "r_talocrural"]);
}

#[test]
fn direction_and_balance_errors_name_the_field() {
    for (tasks, want) in [
        (
            r#"[{"kind":"direction","joint":"sacroiliac","target":[0,0,0]}]"#,
            "tasks[0].target: zero-length direction",
        ),
        (
            r#"[{"kind":"direction","joint":"sacroiliac","axis":[0,0,0],"target":[0,1,0]}]"#,
            "tasks[0].axis: zero-length axis",
        ),
        (
            r#"[{"kind":"direction","target":[0,1,0]}]"#,
            "tasks[0].joint",
        ),
        (
            r#"[{"kind":"balance","margin":-0.1}]"#,
            "tasks[0].margin: must be >= 0",
        ),
        (
            r#"[{"kind":"balance","support":[]}]"#,
            "tasks[0].support: empty",
        ),
        (
            r#"[{"kind":"balance","support":[3]}]"#,
            "tasks[0].support[0]",
        ),
    ] {
        let e = Document::from_json(&doc_with_tasks(tasks)).unwrap_err();
        assert!(e.to_string().contains(want), "{e} (wanted {want})");
    }
    let s = loa2_body40().unwrap();
    let d = Document::from_json(&doc_with_tasks(
        r#"[{"kind":"balance","support":["l_talocrural","tail"]}]"#,
    ))
    .unwrap();
    let e = d.to_tasks(&s).unwrap_err().to_string();
    assert!(
        e.contains("tasks[0].support[1]") && e.contains("tail"),
        "{e}"
    );
}

#[test]
fn a_saved_camera_round_trips_and_a_bad_one_is_named() {
    let text = r#"{"version": 1, "camera": {"target": [0.1, 1.2, -0.3], "yaw": 1.5707963267948966,
        "pitch": 0.2, "distance": 2.5, "orthographic": true}}"#;
    let d = Document::from_json(text).unwrap();
    let camera = d.camera.unwrap();
    assert_eq!(camera.target, [0.1, 1.2, -0.3]);
    assert!(camera.orthographic && camera.distance == 2.5);
    let back = Document::from_json(&d.to_json(false)).unwrap();
    assert_eq!(back, d);
    // Without one, none is written.
    assert!(!Document::default().to_json(false).contains("camera"));
    let with = |camera: &str| format!(r#"{{"version": 1, "camera": {camera}}}"#);
    let good = r#""target": [0, 1, 0], "yaw": 0, "pitch": 0.1, "distance": 3"#;
    assert!(Document::from_json(&with(&format!("{{{good}}}"))).is_ok());
    for (bad, field) in [
        (r#""pitch": 2.0"#, "camera.pitch"),
        (r#""distance": -1"#, "camera.distance"),
        (r#""orthographic": 3"#, "camera.orthographic"),
        (r#""target": [0, "a", 0]"#, "camera.target"),
    ] {
        let key = bad.split(':').next().unwrap();
        let kept: Vec<&str> = [
            r#""target": [0, 1, 0]"#,
            r#""yaw": 0"#,
            r#""pitch": 0.1"#,
            r#""distance": 3"#,
        ]
        .into_iter()
        .filter(|part| !part.starts_with(key))
        .collect();
        let camera = format!("{{{}, {bad}}}", kept.join(", "));
        let e = err(&with(&camera));
        assert!(e.contains(field), "{camera}: {e}");
    }
}

/// Catches a line or plane task that loses a field on the way through JSON, converts onto the
/// wrong joint or with its vector unnormalised, keeps `above` wrong, mirrors wrongly, or
/// accepts a zero direction or normal, a missing origin or a non-boolean `above` silently.
#[test]
fn line_and_plane_tasks_read_write_convert_and_mirror() {
    let s = loa2_body40().unwrap();
    let text = doc_with_tasks(
        r#"[{"kind":"line","joint":"l_wrist","point":[0,0.01,0],"origin":[0.3,1.2,0.35],"direction":[2,0,0]},
            {"kind":"plane","joint":"r_ankle","origin":[0,0.08,0],"level":2},
            {"kind":"plane","joint":"r_ankle","origin":[0,1,0],"normal":[0,0,-3],"above":true}]"#,
    );
    let d = Document::from_json(&text).unwrap();
    // Defaults filled in: no point is the joint centre, no normal is up, no `above` is on.
    assert_eq!(
        d.tasks[1].kind,
        TaskKindSpec::Plane {
            joint: "r_ankle".into(),
            point: [0.0; 3],
            origin: [0.0, 0.08, 0.0],
            normal: [0.0, 1.0, 0.0],
            above: false,
        }
    );
    assert_eq!(Document::from_json(&d.to_json(false)).unwrap(), d);
    let tasks = d.to_tasks(&s).unwrap();
    let wrist = s.joint_index("l_radiocarpal").or(s.joint_index("l_wrist"));
    match &tasks[0].kind {
        TaskKind::PointOnLine {
            effector,
            origin,
            direction,
        } => {
            assert_eq!(Some(effector.joint), wrist);
            assert_eq!(effector.point.to_array(), [0.0, 0.01, 0.0]);
            assert_eq!(origin.to_array(), [0.3, 1.2, 0.35]);
            assert_eq!(direction.to_array(), [1.0, 0.0, 0.0]);
        }
        k => panic!("{k:?}"),
    }
    match &tasks[2].kind {
        TaskKind::PointOnPlane { normal, above, .. } => {
            assert_eq!(normal.to_array(), [0.0, 0.0, -1.0]);
            assert!(*above);
        }
        k => panic!("{k:?}"),
    }
    assert_eq!(tasks[1].level, 2);
    // Back to the problem-file form: the same task.
    let back = TaskSpec::from_task(&s, &tasks[2]).unwrap();
    assert_eq!(back.kind.name(), "plane");
    // Mirrored: the other side's joint, x reflected.
    match d.tasks[0].mirrored().kind {
        TaskKindSpec::Line {
            joint,
            origin,
            direction,
            ..
        } => {
            assert_eq!(joint, "r_wrist");
            assert_eq!(origin, [-0.3, 1.2, 0.35]);
            assert_eq!(direction, [-2.0, 0.0, 0.0]);
        }
        k => panic!("{k:?}"),
    }
    assert_eq!(d.tasks[2].description(), "right ankle on or above a plane");
    for (tasks, want) in [
        (
            r#"[{"kind":"line","joint":"l_wrist","origin":[0,1,0],"direction":[0,0,0]}]"#,
            "tasks[0].direction: zero-length vector",
        ),
        (
            r#"[{"kind":"line","joint":"l_wrist","direction":[0,0,1]}]"#,
            "tasks[0].origin: missing",
        ),
        (
            r#"[{"kind":"plane","joint":"l_wrist","origin":[0,1,0],"normal":[0,0,0]}]"#,
            "tasks[0].normal: zero-length vector",
        ),
        (
            r#"[{"kind":"plane","joint":"l_wrist","origin":[0,1,0],"above":1}]"#,
            "tasks[0].above: expected true or false",
        ),
    ] {
        let e = err(&doc_with_tasks(tasks));
        assert!(e.starts_with(want), "{e}");
    }
}
