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
    // A problem file solves whole: the falling damping unless it says otherwise.
    assert_eq!(damping("{}"), stance_ik::WHOLE_SOLVE_DAMPING);
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

/// The H-Anim default body at LOA 2 as a problem file's skeleton, with `radius` set on the
/// joints named.
fn loa2_skeleton_json(radius: &[(&str, f64)]) -> (Skeleton, serde_json::Value) {
    let s = stance_hanim::default_skeleton(&stance_hanim::SkeletonOptions {
        loa: stance_hanim::LevelOfArticulation::Loa2,
        ..Default::default()
    })
    .unwrap()
    .skeleton;
    let mut json = stance_document::skeleton_json(&s);
    for joint in json["joints"].as_array_mut().unwrap() {
        if let Some((_, r)) = radius.iter().find(|(n, _)| joint["name"] == *n) {
            joint["radius"] = serde_json::json!(r);
        }
    }
    (s, json)
}

/// Catches a collision kind read with the wrong defaults, switches or radii, or lost on the
/// way back to a problem file: `{"kind": "collision"}` is the body's capsules held apart and
/// above the floor, 1 cm apart; `self`, `floor`, `margin` and the joints' `radius` change
/// exactly that; `TaskSpec::from_task` and `problem_json` give the same problem back.
#[test]
fn a_collision_task_reads_from_a_problem_file_and_back() {
    use stance_hanim::capsules::{BodyCollision, body_capsules};
    let (s, skeleton) = loa2_skeleton_json(&[("l_elbow", 0.06)]);
    let read = |task: &str| {
        let p =
            Problem::from_json(&format!(r#"{{"skeleton":{skeleton},"tasks":[{task}]}}"#)).unwrap();
        let TaskKind::Collision(c) = p.tasks[0].kind.clone() else {
            panic!("{task}: {:?}", p.tasks[0].kind);
        };
        (p, c)
    };
    let (p, c) = read(r#"{"kind":"collision","level":2}"#);
    assert_eq!(p.tasks[0].level, 2);
    assert_eq!(c.margin(), 0.01);
    assert!(!c.pairs().is_empty() && !c.floor().is_empty());
    // The forearm's capsule (carried by the elbow) 6 cm thick, every other one the body's.
    let elbow = s.joint_index("l_elbow").unwrap();
    for (got, default) in c.capsules().iter().zip(body_capsules(&s)) {
        let expected = if got.joint == elbow {
            0.06
        } else {
            default.radius
        };
        assert_eq!(got.radius, expected);
    }
    let (_, c) = read(r#"{"kind":"collision","margin":0.02,"self":false}"#);
    assert_eq!(c.margin(), 0.02);
    assert!(c.pairs().is_empty() && !c.floor().is_empty());
    let (_, c) = read(r#"{"kind":"collision","floor":false}"#);
    assert!(!c.pairs().is_empty() && c.floor().is_empty());
    // Back to a file and read again: the same task, radius included.
    let (p, c) = read(r#"{"kind":"collision","level":2,"margin":0.015}"#);
    let spec = stance_document::TaskSpec::from_task(&s, &p.tasks[0]).unwrap();
    assert_eq!(
        serde_json::to_value(&spec).unwrap()["kind"],
        serde_json::json!("collision")
    );
    let json = stance_document::problem_json(&s, &p.tasks, &p.start).unwrap();
    let back = Problem::from_json(&json.to_string()).unwrap();
    assert_eq!(back.tasks, p.tasks);
    assert_eq!(
        BodyCollision::of(&s, &c).map(|b| b.radius.len()),
        Some(1),
        "one joint's radius set by hand"
    );
}

/// Catches bad collision input read silently: each error names its field.
#[test]
fn bad_collision_input_names_its_field() {
    let (_, skeleton) = loa2_skeleton_json(&[]);
    let error = |task: &str, skeleton: &serde_json::Value| {
        Problem::from_json(&format!(r#"{{"skeleton":{skeleton},"tasks":[{task}]}}"#))
            .unwrap_err()
            .to_string()
    };
    let e = error(r#"{"kind":"collision","margin":-0.01}"#, &skeleton);
    assert!(e.contains("tasks[0].margin"), "{e}");
    let e = error(r#"{"kind":"collision","self":"yes"}"#, &skeleton);
    assert!(
        e.contains("tasks[0].self") && e.contains("true or false"),
        "{e}"
    );
    let (_, thin) = loa2_skeleton_json(&[("r_knee", 0.0)]);
    let e = error(r#"{"kind":"collision"}"#, &thin);
    assert!(e.contains("(`r_knee`).radius"), "{e}");
}

/// Catches a collision task that `stance solve`'s problem does not hold: the right wrist
/// pulled into the chest with the collision task at level 2 ends outside every capsule it
/// may touch (within a millimetre), the feet held.
#[test]
fn a_problem_with_a_collision_task_solves_clear_of_the_body() {
    let (s, skeleton) = loa2_skeleton_json(&[]);
    let rest = Frames::new(&s, &stance_ik::Posture::rest(&s));
    let at = |n: &str| rest.joint_position[s.joint_index(n).unwrap()];
    let chest = at("l_sternoclavicular").lerp(at("r_sternoclavicular"), 0.5);
    let (l, r) = (at("l_talocrural"), at("r_talocrural"));
    let p = Problem::from_json(&format!(
        r#"{{"skeleton":{skeleton},"tasks":[
          {{"kind":"position","joint":"l_talocrural","target":[{},{},{}]}},
          {{"kind":"position","joint":"r_talocrural","target":[{},{},{}]}},
          {{"kind":"collision","level":2}},
          {{"kind":"position","joint":"r_radiocarpal","level":3,"target":[{},{},{}]}}
        ],"settings":{{"max_iterations":300}}}}"#,
        l.x, l.y, l.z, r.x, r.y, r.z, chest.x, chest.y, chest.z
    ))
    .unwrap();
    let (posture, report) = p.solve().unwrap();
    assert!(report.levels[0].met && report.levels[1].met, "{report:?}");
    let collision = &p.tasks[2];
    let residual = collision.residual(&s, &Frames::new(&s, &posture), posture.values());
    assert!(residual < 1e-3, "{residual}");
}

/// Catches a problem file's obstacles read wrongly or not held: a box 60 x 10 x 40 cm before
/// the body, turned a quarter about Y (its 60 cm then run along Z), with the right wrist pulled
/// to its middle. The box reaches the collision task in the problem's frame (its size and turn
/// as written) and comes back through `problem_json`; solved, the collision task is met and the
/// wrist is outside the box but at it; a bad obstacle names its field.
#[test]
fn a_problem_file_s_obstacles_hold_the_body_off_them() {
    use stance_ik::{Obstacle, ObstacleShape};
    let (s, skeleton) = loa2_skeleton_json(&[]);
    let rest = Frames::new(&s, &stance_ik::Posture::rest(&s));
    let at = |n: &str| rest.joint_position[s.joint_index(n).unwrap()];
    let (l, r, wrist) = (at("l_talocrural"), at("r_talocrural"), at("r_radiocarpal"));
    let centre = wrist + glam::DVec3::new(0.0, 0.15, 0.45);
    let turn = glam::DQuat::from_rotation_y(std::f64::consts::FRAC_PI_2);
    let text = format!(
        r#"{{"skeleton":{skeleton},"tasks":[
          {{"kind":"position","joint":"l_talocrural","target":[{},{},{}]}},
          {{"kind":"position","joint":"r_talocrural","target":[{},{},{}]}},
          {{"kind":"collision","level":2}},
          {{"kind":"position","joint":"r_radiocarpal","level":3,"target":[{},{},{}]}}
        ],"settings":{{"max_iterations":300}},
        "obstacles":[{{"shape":"box","size":[0.6,0.1,0.4],"position":[{},{},{}],"rotation":[{},{},{},{}]}}]}}"#,
        l.x,
        l.y,
        l.z,
        r.x,
        r.y,
        r.z,
        centre.x,
        centre.y,
        centre.z,
        centre.x,
        centre.y,
        centre.z,
        turn.x,
        turn.y,
        turn.z,
        turn.w
    );
    let p = Problem::from_json(&text).unwrap();
    let TaskKind::Collision(c) = &p.tasks[2].kind else {
        panic!("{:?}", p.tasks[2].kind);
    };
    let Some(Obstacle {
        shape: ObstacleShape::Box { half },
        world_from_obstacle_rotation,
        position,
    }) = c.obstacles().first().copied()
    else {
        panic!("{:?}", c.obstacles());
    };
    assert!((half - glam::DVec3::new(0.3, 0.05, 0.2)).length() < 1e-12);
    assert!((position - centre).length() < 1e-12);
    assert!((world_from_obstacle_rotation * glam::DVec3::X - glam::DVec3::NEG_Z).length() < 1e-9);
    let (posture, report) = p.solve().unwrap();
    assert!(report.levels[0].met, "{report:?}");
    let f = Frames::new(&s, &posture);
    let residual = p.tasks[2].residual(&s, &f, posture.values());
    assert!(residual < 1e-3, "{residual}");
    // The wrist at the box, outside it: its distance from the box by the clamp in its frame.
    let hand = f.joint_position[s.joint_index("r_radiocarpal").unwrap()];
    let q = world_from_obstacle_rotation.transpose() * (hand - centre);
    let outside = (q - q.clamp(-half, half)).length();
    assert!(
        outside > 0.02 && outside < 0.08,
        "the wrist {outside} m from the box"
    );
    // Written back as a problem file (`problem_json`) and read again: the same obstacle.
    let json = stance_document::problem_json(&s, &p.tasks, &p.start).unwrap();
    let back = Problem::from_json(&json.to_string()).unwrap();
    let TaskKind::Collision(again) = &back.tasks[2].kind else {
        panic!("{:?}", back.tasks[2].kind);
    };
    let again = again.obstacles()[0];
    assert_eq!(again.shape, c.obstacles()[0].shape);
    assert!((again.position - position).length() < 1e-12);
    assert!(
        (again.world_from_obstacle_rotation - world_from_obstacle_rotation)
            .abs_diff_eq(glam::DMat3::ZERO, 1e-12)
    );
    let bad = text.replace("\"size\":[0.6,0.1,0.4]", "\"size\":[0.6,-0.1,0.4]");
    let e = Problem::from_json(&bad).unwrap_err().to_string();
    assert!(e.contains("obstacles[0]"), "{e}");
}
