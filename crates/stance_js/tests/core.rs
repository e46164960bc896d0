//! The package's core, natively: problem files solved as `stance solve` solves them, bodies
//! built from H-Anim, joints and a real avatar's skin, per-frame solving into a values array,
//! world transforms, the closed-form limb; errors name the field.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use glam::{DQuat, DVec3};
use serde_json::Value;
use stance_asset::{LoadOptions, load_avatar};
use stance_hanim::{LevelOfArticulation, SkeletonOptions};
use stance_js::{Body, PoseSolver, solve_json};

const AVATAR: &[u8] = include_bytes!("../../../tests/fixtures/avatars/Black_F_2_Casual.glb");

const PROBLEM: &str = r#"{"skeleton":{"joints":[
 {"name":"root","parent":null,"offset":[0,0,0],"dofs":["rx","ry","rz"]},
 {"name":"elbow","parent":"root","offset":[0,0.3,0],"dofs":["rx"],"limits":{"rx":[-2.5,0]}},
 {"name":"wrist","parent":"elbow","offset":[0,0.3,0]}
]},
"posture":{"elbow":{"rx":-0.5}},
"tasks":[{"kind":"position","joint":"wrist","target":[0.1,0.4,0.2]}]}"#;

fn at(v: &Value, key: &str) -> Vec<f64> {
    v[key]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

#[test]
fn a_problem_file_is_solved_and_reported_like_stance_solve() {
    let out: Value = serde_json::from_str(&solve_json(PROBLEM).unwrap()).unwrap();
    let wrist = at(&out["joints"], "wrist");
    let target = [0.1, 0.4, 0.2];
    for i in 0..3 {
        assert!((wrist[i] - target[i]).abs() < 1e-6, "{wrist:?}");
    }
    assert_eq!(out["report"]["status"], "converged");
    assert!(out["posture"]["elbow"]["rx"].as_f64().unwrap() <= 0.0);
    for (text, want) in [
        (
            PROBLEM.replace("\"wrist\",\"target\"", "\"wirst\",\"target\""),
            "tasks[0].joint",
        ),
        (
            PROBLEM.replace("[0.1,0.4,0.2]", "[0.1,0.4]"),
            "tasks[0].target",
        ),
        ("{".to_owned(), "not valid JSON"),
    ] {
        let e = solve_json(&text).unwrap_err();
        assert!(e.contains(want), "{e}");
    }
}

#[test]
fn bodies_from_hanim_joints_and_a_real_skin() {
    let loa2 = Body::hanim(2).unwrap();
    let reference = stance_hanim::default_skeleton(&SkeletonOptions::default()).unwrap();
    assert_eq!(loa2.skeleton.dof_count(), reference.skeleton.dof_count());
    assert_eq!(loa2.dof_names().len(), loa2.skeleton.dof_count());
    assert!(loa2.dof_names().contains(&"l_knee.rx".to_owned()));
    assert!(Body::hanim(5).unwrap_err().contains("loa"));

    let joints =
        r#"{"joints":[{"name":"a","dofs":["rz"]},{"name":"b","parent":"a","offset":[1,0,0]}]}"#;
    assert_eq!(Body::from_joints(joints).unwrap().joint_names(), ["a", "b"]);
    assert!(
        Body::from_joints(r#"{"joints":[{"name":"a","dofs":["rq"]}]}"#)
            .unwrap_err()
            .contains("dofs[0]")
    );

    // The vendored avatar's nodes, as a three.js page would pass a skin's bones: the same
    // H-Anim skeleton as the editor builds from the file.
    let avatar = load_avatar(AVATAR, &LoadOptions::default()).unwrap();
    let (names, parents, rest) = skin_of(&avatar);
    let body = Body::from_skin(&names, &parents, &rest, 2).unwrap();
    let editor = avatar
        .skeleton(&SkeletonOptions {
            loa: LevelOfArticulation::Loa2,
            ..SkeletonOptions::default()
        })
        .unwrap();
    assert_eq!(
        body.joint_names(),
        editor
            .skeleton
            .joints()
            .iter()
            .map(|j| j.name.clone())
            .collect::<Vec<_>>()
    );
    let hips = body
        .joint_names()
        .iter()
        .position(|n| n == "humanoid_root")
        .unwrap();
    assert!(body.source[hips] >= 0, "the root stands for a skin joint");
    let bad = Body::from_skin(&names, &parents[1..], &rest, 2).unwrap_err();
    assert!(bad.contains("parents"), "{bad}");
}

#[test]
fn a_pose_solver_solves_into_the_values_and_reports() {
    let body = Body::hanim(2).unwrap();
    let s = &body.skeleton;
    let mut solver = PoseSolver::new(&body, r#"{"max_iterations": 200}"#).unwrap();
    let mut values = vec![0.0; s.dof_count()];
    let mut out = vec![0.0; 7 * s.joint_count()];
    solver.world_transforms(&values, &mut out).unwrap();
    let index = |name: &str| s.joint_index(name).unwrap();
    let position = |out: &[f64], name: &str| {
        let j = index(name);
        DVec3::new(out[7 * j], out[7 * j + 1], out[7 * j + 2])
    };
    let ankle_l = position(&out, "l_talocrural");
    let ankle_r = position(&out, "r_talocrural");
    let hand = position(&out, "r_radiocarpal") + DVec3::new(0.0, 0.35, 0.3);
    solver
        .set_tasks(&format!(
            r#"[{{"kind":"position","joint":"l_talocrural","target":{:?}}},
                {{"kind":"position","joint":"r_talocrural","target":{:?}}},
                {{"kind":"balance","level":2}},
                {{"kind":"position","joint":"r_radiocarpal","target":{:?},"level":3}}]"#,
            ankle_l.to_array(),
            ankle_r.to_array(),
            hand.to_array()
        ))
        .unwrap();
    let report: Value = serde_json::from_str(&solver.solve(&mut values).unwrap()).unwrap();
    assert_eq!(report["status"], "converged", "{report}");
    solver.world_transforms(&values, &mut out).unwrap();
    assert!((position(&out, "r_radiocarpal") - hand).length() < 1e-6);
    assert!((position(&out, "l_talocrural") - ankle_l).length() < 1e-6);
    let j = index("r_radiocarpal");
    let q = DQuat::from_xyzw(
        out[7 * j + 3],
        out[7 * j + 4],
        out[7 * j + 5],
        out[7 * j + 6],
    );
    assert!((q.length() - 1.0).abs() < 1e-9);

    // The closed-form arm: the wrist on a goal with a chosen swivel.
    let goal = [0.35, 1.1, 0.25];
    let limb: Value = serde_json::from_str(
        &solver
            .solve_limb(&mut values, "l_arm", &goal, Some(0.4), None)
            .unwrap(),
    )
    .unwrap();
    assert_eq!(limb["reached"], true, "{limb}");
    solver.world_transforms(&values, &mut out).unwrap();
    assert!((position(&out, "l_radiocarpal") - DVec3::from_array(goal)).length() < 1e-6);
    let swivel = solver.swivel_angle(&values, "l_arm").unwrap();
    assert!((swivel - limb["swivel"].as_f64().unwrap()).abs() < 1e-6);

    // Errors name what is wrong and leave the values alone.
    let before = values.clone();
    assert!(
        solver
            .solve(&mut values[1..])
            .unwrap_err()
            .contains("values")
    );
    assert!(
        solver
            .world_transforms(&values, &mut out[1..])
            .unwrap_err()
            .contains("out")
    );
    assert!(
        solver
            .solve_limb(&mut values, "l_tail", &goal, None, None)
            .unwrap_err()
            .contains("l_tail")
    );
    assert!(
        solver
            .set_tasks(r#"[{"kind":"gaze"}]"#)
            .unwrap_err()
            .contains("tasks[0].joint")
    );
    assert!(
        PoseSolver::new(&body, r#"{"tolerance": -1}"#)
            .unwrap_err()
            .contains("settings")
    );
    assert_eq!(values, before);
}

/// The Table-1-like problem of `tests/fixtures/problems/table1-loa2-tasks.json`, solved from
/// the rest posture: every level met; prints the time per solve (the package's test prints
/// the same figure from JavaScript, for the wasm/native ratio; no time is asserted).
#[test]
fn table1_on_the_hanim_body_is_solved_and_timed() {
    let fixture: Value = serde_json::from_str(include_str!(
        "../../../tests/fixtures/problems/table1-loa2-tasks.json"
    ))
    .unwrap();
    let body = Body::hanim(2).unwrap();
    let mut solver = PoseSolver::new(&body, "").unwrap();
    solver.set_tasks(&fixture["tasks"].to_string()).unwrap();
    let mut values = vec![0.0; body.skeleton.dof_count()];
    let report: Value = serde_json::from_str(&solver.solve(&mut values).unwrap()).unwrap();
    assert_eq!(report["status"], "converged", "{report}");
    let runs = 20;
    let start = std::time::Instant::now();
    for _ in 0..runs {
        values.fill(0.0);
        solver.solve(&mut values).unwrap();
    }
    let us = start.elapsed().as_secs_f64() * 1e6 / f64::from(runs);
    println!(
        "table1 native: {us:.0} us/solve, {} iterations",
        report["iterations"]
    );
}

/// A body's recipe builds the same body again (what the package's retargeting module does
/// with `Skeleton.recipe`): same joints, offsets, DOF order, limits, skin joints and rest
/// match, bit for bit, for each way of building one. Catches a recipe that loses a field (the
/// level of articulation, a parent) or rounds a rest position (the skin's proportions).
#[test]
fn a_recipe_builds_the_same_body_again() {
    let (_, skin) = vendored_avatar_as_skin();
    let joints = Body::from_joints(
        r#"{"joints":[{"name":"a","dofs":["rz"],"limits":{"rz":[-1,1]}},
                      {"name":"b","parent":"a","offset":[0.1,0.2,0.30000000000000004]}]}"#,
    )
    .unwrap();
    for body in [
        Body::hanim(1).unwrap(),
        Body::hanim(3).unwrap(),
        skin,
        joints,
    ] {
        let again = Body::from_recipe(&body.recipe_json()).unwrap();
        assert_eq!(again.dof_names(), body.dof_names());
        assert_eq!(again.source, body.source);
        assert_eq!(again.rest_match, body.rest_match);
        assert_eq!(again.humanoid.is_some(), body.humanoid.is_some());
        for (a, b) in again.skeleton.joints().iter().zip(body.skeleton.joints()) {
            assert_eq!((a.parent, a.offset, &a.dofs), (b.parent, b.offset, &b.dofs));
            assert_eq!((a.mass, a.com), (b.mass, b.com));
        }
        assert_eq!(again.skeleton.lower_limits(), body.skeleton.lower_limits());
        assert_eq!(again.skeleton.upper_limits(), body.skeleton.upper_limits());
        assert_eq!(again.skeleton.stiffness(), body.skeleton.stiffness());
    }
    for (recipe, says) in [
        ("{}", "neither hanim, joints nor skin"),
        (r#"{"hanim": 9}"#, "loa"),
        (r#"{"hanim": "x"}"#, "recipe.hanim"),
        (
            r#"{"skin": {"names": ["a"], "parents": [-1], "rest": [0, 0], "loa": 2}}"#,
            "rest",
        ),
        (
            r#"{"skin": {"names": [1], "parents": [-1], "rest": [0, 0, 0], "loa": 2}}"#,
            "names",
        ),
        ("not json", "not valid JSON"),
    ] {
        let e = Body::from_recipe(recipe).unwrap_err();
        assert!(e.contains(says), "{recipe}: {e}");
    }
}

/// `Skeleton.fromSkin` poses a skin as the editor poses the avatar: by the three.js example's
/// rule (a mapped bone's world rotation is its joint's `worldTransforms` rotation times the
/// joint's `restMatch` times the bone's rest world rotation; the last joint on a bone drives
/// it), a document's posture turns the vendored avatar's bones (a T-pose) as `posed_locals`
/// turns its nodes for the editor and `stance export-posed`.
#[test]
fn a_skin_posed_through_the_rest_match_shows_what_the_editor_shows() {
    use glam::{DMat3, DMat4};
    let (avatar, body) = vendored_avatar_as_skin();
    let editor = avatar.skeleton(&SkeletonOptions::default()).unwrap();
    let document = stance_document::Document::from_json(
        r#"{"posture": {"humanoid_root": {"ry": 0.4}, "r_shoulder": {"rx": -1.2, "rz": -0.3},
            "r_elbow": {"rx": -0.9}, "l_shoulder": {"rz": 0.6}, "l_hip": {"rx": -0.5},
            "l_knee": {"rx": 0.8}, "vl5": {"rx": 0.2}}}"#,
    )
    .unwrap();
    let posture = document.posture.to_posture(&body.skeleton).unwrap();
    let solver = PoseSolver::new(&body, "").unwrap();
    let n = body.skeleton.joint_count();
    let mut out = vec![0.0; 7 * n];
    solver.world_transforms(posture.values(), &mut out).unwrap();
    // The editor's nodes, in the H-Anim frame.
    let locals = avatar.posed_locals(&editor, &posture).unwrap();
    let posed = avatar.world_from_locals(&locals);
    let rest_world = avatar.rest_world();
    let rotation = |m: &DMat4| {
        let r = DMat3::from_mat4(avatar.hanim_from_file * *m);
        DQuat::from_mat3(&DMat3::from_cols(
            r.x_axis.normalize(),
            r.y_axis.normalize(),
            r.z_axis.normalize(),
        ))
    };
    let mut driver = vec![None; avatar.nodes.len()];
    for (j, &s) in body.source.iter().enumerate() {
        if s >= 0 {
            driver[s as usize] = Some(j);
        }
    }
    let mut compared = 0;
    let mut moved = 0;
    for (node, j) in driver.iter().enumerate() {
        let Some(j) = *j else { continue };
        let joint = DQuat::from_slice(&out[7 * j + 3..7 * j + 7]);
        let rest_match = DQuat::from_slice(&body.rest_match[4 * j..4 * j + 4]);
        let three = joint * rest_match * rotation(&rest_world[node]);
        let editor = rotation(&posed[node]);
        let angle = three.angle_between(editor).to_degrees();
        // (Within the noise of composing and decomposing the node transforms.)
        assert!(angle < 0.05, "{}: {angle} degrees", avatar.nodes[node].name);
        compared += 1;
        moved += usize::from(rest_match.angle_between(DQuat::IDENTITY) > 0.1);
    }
    assert!(compared > 40, "{compared} bones");
    assert!(moved > 4, "the T-pose's arms are matched: {moved} bones");
}

/// The vendored avatar, and its nodes passed to `Body::from_skin` as a three.js page passes a
/// skin's bones.
fn vendored_avatar_as_skin() -> (stance_asset::Avatar, Body) {
    let avatar = load_avatar(AVATAR, &LoadOptions::default()).unwrap();
    let (names, parents, rest) = skin_of(&avatar);
    let body = Body::from_skin(&names, &parents, &rest, 2).unwrap();
    (avatar, body)
}

/// An avatar's nodes as `Body::from_skin` takes them: names, parent indices (-1: none), H-Anim
/// rest positions (x y z per node).
fn skin_of(avatar: &stance_asset::Avatar) -> (Vec<String>, Vec<i32>, Vec<f64>) {
    let names = avatar.nodes.iter().map(|n| n.name.clone()).collect();
    let parents = avatar
        .nodes
        .iter()
        .map(|n| n.parent.map_or(-1, |p| p as i32))
        .collect();
    let rest = avatar
        .hanim_rest_positions()
        .iter()
        .flat_map(|p| p.to_array())
        .collect();
    (names, parents, rest)
}

/// The package's default tasks are the editor's (feet pinned where they stand, balance,
/// comfort) at the posture given: a kneeling posture's ankles are pinned where that posture
/// puts them (from `worldTransforms`, not the rest), and solving the defaults with a pull on the
/// hand keeps both feet within a micrometre. Catches defaults pinned at the rest posture's
/// ankles (the body jumps back), the wrong levels, or a second list drifting from the editor's.
#[test]
fn default_tasks_pin_the_feet_where_they_stand() {
    let body = Body::hanim(2).unwrap();
    let s = &body.skeleton;
    let mut values = vec![0.0; s.dof_count()];
    let dof = |joint: &str| {
        let j = s.joint_index(joint).unwrap();
        s.joints()[..j]
            .iter()
            .map(|joint| joint.dofs.len())
            .sum::<usize>()
    };
    values[dof("l_knee")] = 0.8;
    values[dof("r_hip")] = -0.4;
    let tasks: Value = serde_json::from_str(&body.default_tasks(&values).unwrap()).unwrap();
    let tasks = tasks.as_array().unwrap();
    let kinds: Vec<(&str, u64)> = tasks
        .iter()
        .map(|t| {
            (
                t["kind"].as_str().unwrap(),
                t["level"].as_u64().unwrap_or(1),
            )
        })
        .collect();
    assert_eq!(
        kinds,
        [
            ("position", 1),
            ("position", 1),
            ("balance", 2),
            ("comfort", 10)
        ]
    );
    let mut solver = PoseSolver::new(&body, r#"{"max_iterations": 300}"#).unwrap();
    let mut out = vec![0.0; 7 * s.joint_count()];
    solver.world_transforms(&values, &mut out).unwrap();
    let position = |out: &[f64], name: &str| {
        let j = s.joint_index(name).unwrap();
        DVec3::new(out[7 * j], out[7 * j + 1], out[7 * j + 2])
    };
    for (task, foot) in tasks.iter().zip(["l_talocrural", "r_talocrural"]) {
        assert_eq!(task["joint"], foot);
        let target = DVec3::from_array(at(task, "target").try_into().expect("three coordinates"));
        assert!(
            (target - position(&out, foot)).length() < 1e-9,
            "{foot}: {target}"
        );
    }
    let before = [
        position(&out, "l_talocrural"),
        position(&out, "r_talocrural"),
    ];
    let hand = position(&out, "r_radiocarpal") + DVec3::new(0.1, 0.2, 0.2);
    let mut with_pull = tasks.clone();
    with_pull.push(
        serde_json::json!({"kind": "position", "joint": "r_radiocarpal",
        "target": hand.to_array(), "level": 3}),
    );
    solver
        .set_tasks(&Value::Array(with_pull).to_string())
        .unwrap();
    solver.solve(&mut values).unwrap();
    solver.world_transforms(&values, &mut out).unwrap();
    for (foot, was) in ["l_talocrural", "r_talocrural"].iter().zip(before) {
        assert!((position(&out, foot) - was).length() < 1e-6, "{foot} moved");
    }
    assert!(
        body.default_tasks(&[0.0; 3])
            .unwrap_err()
            .contains("values")
    );
}

/// Grab-and-pull through the package: a point pulled out of reach moves toward the pointer
/// while the pinned feet stay where they are; the report says per task how it fares, and a
/// task that conflicts with a higher one names it; released, the pull is gone.
#[test]
fn a_pull_moves_the_body_below_every_task_and_the_report_says_why_a_task_gave_way() {
    let body = Body::hanim(2).unwrap();
    let s = &body.skeleton;
    let mut values = vec![0.0; s.dof_count()];
    let mut out = vec![0.0; 7 * s.joint_count()];
    let mut solver = PoseSolver::new(&body, r#"{"max_iterations": 60}"#).unwrap();
    solver.world_transforms(&values, &mut out).unwrap();
    let position = |out: &[f64], name: &str| {
        let j = s.joint_index(name).unwrap();
        DVec3::new(out[7 * j], out[7 * j + 1], out[7 * j + 2])
    };
    let feet = [
        position(&out, "l_talocrural"),
        position(&out, "r_talocrural"),
    ];
    let wrist = position(&out, "l_radiocarpal");
    // The left wrist pinned at level 1 and asked elsewhere at level 2: a conflict.
    solver
        .set_tasks(&format!(
            r#"[{{"kind":"position","joint":"l_talocrural","target":{:?}}},
                {{"kind":"position","joint":"r_talocrural","target":{:?}}},
                {{"kind":"position","joint":"l_radiocarpal","target":{:?}}},
                {{"kind":"position","joint":"l_radiocarpal","target":{:?},"level":2}}]"#,
            feet[0].to_array(),
            feet[1].to_array(),
            wrist.to_array(),
            (wrist + DVec3::new(0.0, 0.3, 0.0)).to_array(),
        ))
        .unwrap();
    let head = position(&out, "skullbase");
    let target = head + DVec3::new(0.0, 0.0, 2.0);
    solver
        .pull("skullbase", &[0.0; 3], &target.to_array())
        .unwrap();
    let mut last = f64::INFINITY;
    for _ in 0..5 {
        solver.solve(&mut values).unwrap();
        solver.world_transforms(&values, &mut out).unwrap();
        let gap = (position(&out, "skullbase") - target).length();
        assert!(
            gap <= last + 1e-9,
            "the pulled head comes no closer: {gap} after {last}"
        );
        last = gap;
    }
    assert!(
        last < 2.0 - 0.1,
        "the head followed the pull: {last} m left of 2 m"
    );
    for (foot, name) in feet.iter().zip(["l_talocrural", "r_talocrural"]) {
        assert!(
            (position(&out, name) - *foot).length() < 1e-6,
            "{name} moved"
        );
    }
    assert!((position(&out, "l_radiocarpal") - wrist).length() < 1e-6);
    solver.release();
    let report: Value = serde_json::from_str(&solver.solve(&mut values).unwrap()).unwrap();
    let tasks = report["tasks"].as_array().unwrap();
    assert_eq!(tasks.len(), 4, "{report}");
    assert!(tasks[..3].iter().all(|t| t["met"] == true), "{report}");
    assert_eq!(tasks[3]["met"], false);
    let why = tasks[3]["gave_way"].as_str().unwrap();
    assert!(
        why.contains("conflicts with level 1") && why.contains("wrist"),
        "{why}"
    );
    let residual = tasks[3]["residual"].as_f64().unwrap();
    assert!(
        (residual - 0.3).abs() < 1e-3,
        "the wrist is 0.3 m from its level-2 goal: {residual}"
    );
    assert!(
        solver
            .pull("l_tail", &[0.0; 3], &[0.0; 3])
            .unwrap_err()
            .contains("l_tail")
    );
    assert!(
        solver
            .pull("skullbase", &[0.0; 2], &[0.0; 3])
            .unwrap_err()
            .contains("point")
    );
    assert!(
        solver
            .pull("skullbase", &[0.0; 3], &[f64::NAN, 0.0, 0.0])
            .unwrap_err()
            .contains("target")
    );
}
