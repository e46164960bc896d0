//! The editor's panels and viewport driven like a user would, natively (egui_kittest): clicks
//! on buttons found by their labels, keyboard shortcuts, pointer drags in the viewport.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use egui::{Key, Modifiers, PointerButton, Pos2};
use egui_kittest::Harness;
use egui_kittest::kittest::{NodeT, Queryable};
use stance_document::{Document, TaskKindSpec};
use stance_editor::model::{
    AvatarCommand, FileCommand, HistoryCommand, PostureCommand, ViewCommand,
};
use stance_editor::{Command, MemoryHost, StanceApp};

use crate::common;
use common::{
    click_at, drag_right_forearm_up, harness_for, release_at, screen_position, settle, state,
};

fn harness(host: &MemoryHost) -> Harness<'static, StanceApp> {
    let app = StanceApp::without_gpu(Box::new(host.clone())).unwrap();
    harness_for(app)
}

fn document(harness: &Harness<'static, StanceApp>) -> Document {
    harness.state().model().session().document()
}

fn joint_world(harness: &Harness<'static, StanceApp>, joint: &str) -> [f64; 3] {
    let state = state(harness);
    let xyz = &state["joints"][joint];
    [0, 1, 2].map(|i| xyz[i].as_f64().unwrap())
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

#[test]
fn the_table1_example_is_added_by_a_click_and_undo_redo_restore_it_exactly() {
    let host = MemoryHost::default();
    let mut harness = harness(&host);
    let before = document(&harness);
    assert_eq!(
        before.tasks.len(),
        4,
        "feet, balance and comfort by default"
    );

    harness.get_by_label("Table 1 example").click();
    settle(&mut harness);
    let after = document(&harness);
    assert_eq!(after.tasks.len(), 7);
    // Level 1 (left foot, gaze, right hand) is met once the solver has settled.
    let statuses = state(&harness)["tasks"].as_array().unwrap().clone();
    for task in statuses.iter().filter(|task| task["level"] == 1) {
        let residual = task["residual"].as_f64().unwrap();
        assert!(residual < 1e-3, "{task}");
    }

    harness.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    harness.run_steps(2);
    assert_eq!(
        document(&harness),
        before,
        "undo gives the document back exactly"
    );
    harness.key_press_modifiers(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
    harness.run_steps(2);
    assert_eq!(
        document(&harness),
        after,
        "redo gives the edit back exactly"
    );
    harness.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    harness.key_press_modifiers(Modifiers::COMMAND, Key::Y);
    harness.run_steps(2);
    assert_eq!(document(&harness), after, "Ctrl+Y redoes too");
}

#[test]
fn a_task_is_added_from_the_menu_and_levels_are_reordered_by_the_arrows() {
    let host = MemoryHost::default();
    let mut harness = harness(&host);
    harness.get_by_label("Add task").click();
    harness.run_steps(2);
    harness.get_by_label("Gaze (head looks at a point)").click();
    settle(&mut harness);
    let tasks = document(&harness).tasks;
    assert_eq!(tasks.len(), 5);
    let gaze = tasks.last().unwrap();
    assert!(matches!(gaze.kind, TaskKindSpec::Gaze { .. }));
    assert_eq!(gaze.level, 3, "below the feet (1) and the balance (2)");

    // Lower level 1 below level 2: the feet now give way to the balance.
    harness.get_all_by_label("down").next().unwrap().click();
    harness.run_steps(2);
    let levels: Vec<u32> = document(&harness).tasks.iter().map(|t| t.level).collect();
    assert_eq!(levels, vec![2, 2, 1, 10, 3]);
    harness.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    harness.run_steps(2);
    let levels: Vec<u32> = document(&harness).tasks.iter().map(|t| t.level).collect();
    assert_eq!(levels, vec![1, 1, 2, 10, 3]);
}

#[test]
fn dragging_the_right_hand_pulls_it_while_the_pinned_feet_hold() {
    let host = MemoryHost::default();
    let mut harness = harness(&host);
    let foot_before = joint_world(&harness, "l_talocrural");
    let hand_before = joint_world(&harness, "r_radiocarpal");
    // Press on the forearm below the elbow, on the side away from the body.
    let (start, end) = drag_right_forearm_up(&mut harness);
    assert_eq!(
        state(&harness)["pulling"],
        true,
        "the drag started on the body"
    );
    assert_eq!(
        state(&harness)["selected"],
        "r_elbow",
        "the forearm was grabbed"
    );
    for _ in 0..40 {
        harness.step();
    }
    let hand_during = screen_position(&harness, "r_radiocarpal");
    release_at(&mut harness, end);
    settle(&mut harness);
    assert_eq!(state(&harness)["pulling"], false);

    let hand_after = joint_world(&harness, "r_radiocarpal");
    assert!(
        hand_after[1] > hand_before[1] + 0.1,
        "the hand rose toward the pointer: {hand_before:?} -> {hand_after:?}"
    );
    assert!(
        hand_during.distance(end) < start.distance(end) * 0.5,
        "on screen the hand followed the pointer: {start:?} -> {hand_during:?}, pointer at {end:?}"
    );
    let foot_after = joint_world(&harness, "l_talocrural");
    assert!(
        distance(foot_before, foot_after) < 1e-3,
        "the pinned foot moved {} m",
        distance(foot_before, foot_after)
    );
    // One undo step puts the hand back.
    harness.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    harness.run_steps(2);
    assert!(distance(joint_world(&harness, "r_radiocarpal"), hand_before) < 1e-9);
}

#[test]
fn a_pull_moves_the_body_in_the_frame_that_read_the_pointer() {
    // Catches: the pull's goal moved after the frame's solve (the viewport reads the pointer
    // after EditorModel::step), so that the body drawn lags the pointer by one frame.
    let host = MemoryHost::default();
    let mut harness = harness(&host);
    let (_, end) = drag_right_forearm_up(&mut harness);
    for _ in 0..40 {
        harness.step();
    }
    let grabbed = |harness: &Harness<'static, StanceApp>| {
        let session = harness.state().model().session();
        session.grabbed_point_world().unwrap()
    };
    let wrist_on_screen = screen_position(&harness, "r_radiocarpal");
    let before = grabbed(&harness);
    // One frame with the pointer 10 points further right: the body drawn in it has moved.
    harness.event(egui::Event::PointerMoved(end + egui::vec2(10.0, 0.0)));
    harness.step();
    let in_that_frame = grabbed(&harness);
    let wrist_moved = screen_position(&harness, "r_radiocarpal").x - wrist_on_screen.x;
    // A frame without input: the posture had already caught up.
    harness.step();
    let next_frame = grabbed(&harness);
    let moved = (in_that_frame - before).length();
    let left = (next_frame - in_that_frame).length();
    assert!(
        moved > 0.01,
        "the pulled point moved {moved} m in the frame that read the pointer"
    );
    assert!(
        left < moved * 0.05,
        "it moved {moved} m in that frame and {left} m more in the next"
    );
    assert!(
        wrist_moved > 5.0,
        "the wrist drawn moved {wrist_moved} points toward the pointer"
    );
    release_at(&mut harness, end + egui::vec2(10.0, 0.0));
    settle(&mut harness);
}

#[test]
fn a_copied_link_opens_the_same_posture_and_tasks_and_a_tampered_one_says_so() {
    let host = MemoryHost::default();
    let mut harness = harness(&host);
    harness.get_by_label("Table 1 example").click();
    settle(&mut harness);
    harness.get_by_label("Copy posture link").click();
    harness.run_steps(2);
    let fragment = host.inner.borrow().address_fragment.clone().unwrap();
    assert!(fragment.len() < 600, "{} characters", fragment.len());
    let original = document(&harness);

    let mut opened = StanceApp::without_gpu(Box::new(MemoryHost::default())).unwrap();
    opened.open_startup(Some(&format!("#{fragment}")));
    let reopened = opened.model().session().document();
    assert_eq!(reopened.tasks.len(), original.tasks.len());
    for (joint, dofs) in original.posture.joints.iter() {
        for (dof, value) in dofs.iter() {
            let other = reopened.posture.get(joint, dof).unwrap_or(0.0);
            assert!(
                (other - value).abs() < 1e-4,
                "{joint}.{}: {value} vs {other}",
                dof.name()
            );
        }
    }
    assert!(
        opened
            .model()
            .notice()
            .is_some_and(|notice| !notice.is_error)
    );

    let mut tampered_fragment = fragment.clone().into_bytes();
    let middle = tampered_fragment.len() / 2;
    tampered_fragment[middle] = if tampered_fragment[middle] == b'A' {
        b'B'
    } else {
        b'A'
    };
    let tampered = String::from_utf8(tampered_fragment).unwrap();
    let mut damaged = StanceApp::without_gpu(Box::new(MemoryHost::default())).unwrap();
    let default_document = damaged.model().session().document();
    damaged.open_startup(Some(&tampered));
    let notice = damaged.model().notice().unwrap();
    assert!(
        notice.is_error && notice.text.contains("could not be opened"),
        "{}",
        notice.text
    );
    assert_eq!(
        damaged.model().session().document(),
        default_document,
        "the editor opens normally"
    );
}

#[test]
fn a_long_notice_leaves_the_viewport_between_the_panels() {
    // Catches: the notice strip's dismiss button placed after a wrapped text, which widened
    // the central panel: the viewport's rectangle ran about 10 points under the tasks panel
    // (the state and the status bar gave a size larger than what was visible).
    let viewport = |harness: &Harness<'static, StanceApp>| {
        let rect = &state(harness)["viewport"];
        [0, 1, 2, 3].map(|i| rect[i].as_f64().unwrap())
    };
    let plain = harness(&MemoryHost::default());
    let mut app = StanceApp::without_gpu(Box::new(MemoryHost::default())).unwrap();
    app.open_startup(Some("#p=damaged-link-that-does-not-decode"));
    let notice = app.model().notice().unwrap().text.clone();
    let mut noticed = harness_for(app);
    noticed.run_steps(2);
    assert!(
        noticed.state().model().notice().is_some(),
        "the notice is still shown"
    );
    let [x0, y0, w0, _] = viewport(&plain);
    let [x1, y1, w1, _] = viewport(&noticed);
    assert!(notice.len() > 120, "a notice long enough to wrap: {notice}");
    assert!((x1 - x0).abs() < 0.5, "left edge {x0} -> {x1}");
    assert!(
        (x1 + w1 - (x0 + w0)).abs() < 0.5,
        "right edge {} -> {} with the notice",
        x0 + w0,
        x1 + w1
    );
    assert!(
        y1 > y0 + 10.0,
        "the notice pushes the viewport down: {y0} -> {y1}"
    );
}

#[test]
fn work_survives_a_reload_and_the_library_keeps_named_poses() {
    let host = MemoryHost::default();
    let mut harness = harness(&host);
    harness.get_by_label("Table 1 example").click();
    settle(&mut harness);
    // Save it in the library under a name typed in the panel.
    let name_field = harness.get_by_role_and_label(egui::accesskit::Role::TextInput, "Name");
    name_field.focus();
    name_field.type_text("reach for the ball");
    harness.run_steps(2);
    harness.get_by_label("Save").click();
    harness.run_steps(2);
    let edited = document(&harness);
    // Let the autosave interval pass.
    std::thread::sleep(std::time::Duration::from_millis(1100));
    harness.run_steps(2);
    drop(harness);

    let mut reloaded = StanceApp::without_gpu(Box::new(host.clone())).unwrap();
    reloaded.open_startup(None);
    assert_eq!(
        reloaded.model().session().document(),
        edited,
        "autosave restored the work"
    );
    let names: Vec<&str> = reloaded
        .model()
        .library()
        .entries()
        .iter()
        .map(|entry| entry.name.as_str())
        .collect();
    assert_eq!(names, vec!["reach for the ball"]);
}

#[test]
fn a_bad_file_says_what_is_wrong_and_changes_nothing() {
    let mut app = StanceApp::without_gpu(Box::new(MemoryHost::default())).unwrap();
    let before = app.model().session().document();
    app.apply(Command::File(FileCommand::OpenFile {
        name: "pose.json".to_owned(),
        bytes: br#"{"tasks":[{"kind":"position","joint":"l_wirst","target":[0,1]}]}"#.to_vec(),
    }));
    let notice = app.model().notice().unwrap();
    assert!(notice.is_error, "{}", notice.text);
    assert!(notice.text.contains("target"), "{}", notice.text);
    assert_eq!(app.model().session().document(), before);
    app.apply(Command::File(FileCommand::OpenFile {
        name: "avatar.glb".to_owned(),
        bytes: b"glTF".to_vec(),
    }));
    assert!(app.model().notice().unwrap().is_error);
    app.apply(Command::File(FileCommand::OpenFile {
        name: "binary.json".to_owned(),
        bytes: vec![0xff, 0xfe, 0x00],
    }));
    assert!(app.model().notice().unwrap().text.contains("not a text"));
    assert_eq!(app.model().session().document(), before);
}

fn drag(harness: &mut Harness<'static, StanceApp>, path: &[Pos2]) {
    let (Some(&first), Some(&last)) = (path.first(), path.last()) else {
        return;
    };
    harness.event(egui::Event::PointerMoved(first));
    harness.step();
    harness.event(egui::Event::PointerButton {
        pos: first,
        button: PointerButton::Primary,
        pressed: true,
        modifiers: Modifiers::NONE,
    });
    harness.step();
    for &point in &path[1..] {
        harness.event(egui::Event::PointerMoved(point));
        harness.step();
    }
    harness.event(egui::Event::PointerButton {
        pos: last,
        button: PointerButton::Primary,
        pressed: false,
        modifiers: Modifiers::NONE,
    });
    harness.step();
}

#[test]
fn dragging_a_goal_marker_moves_the_goal_and_the_hand_follows() {
    let host = MemoryHost::default();
    let mut harness = harness(&host);
    harness.get_by_label("Table 1 example").click();
    settle(&mut harness);
    let before = document(&harness);
    let hand_task = before
        .tasks
        .iter()
        .position(|task| matches!(&task.kind, TaskKindSpec::Position { joint, .. } if joint == "r_radiocarpal"))
        .unwrap();
    let goal = state(&harness)["goals"]
        .as_array()
        .unwrap()
        .iter()
        .find(|goal| goal["task"] == hand_task)
        .unwrap()["screen"]
        .clone();
    let start = Pos2::new(
        goal[0].as_f64().unwrap() as f32,
        goal[1].as_f64().unwrap() as f32,
    );
    let path: Vec<Pos2> = (0..=10)
        .map(|step| start + egui::vec2(0.0, -4.0 * step as f32))
        .collect();
    drag(&mut harness, &path);
    settle(&mut harness);
    let after = document(&harness);
    let target = |document: &Document| match &document.tasks[hand_task].kind {
        TaskKindSpec::Position { target, .. } => *target,
        _ => unreachable!(),
    };
    assert!(
        target(&after)[1] > target(&before)[1] + 0.05,
        "the goal rose: {:?} -> {:?}",
        target(&before),
        target(&after)
    );
    let hand = joint_world(&harness, "r_radiocarpal");
    assert!(
        distance(hand, target(&after)) < 1e-3,
        "the hand (level 1) is on its new goal"
    );
    harness.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    harness.run_steps(2);
    assert_eq!(
        target(&document(&harness)),
        target(&before),
        "one undo puts the goal back"
    );
}

#[test]
fn the_ring_gizmo_turns_the_selected_joint_within_its_limits() {
    let host = MemoryHost::default();
    let mut harness = harness(&host);
    // Select the right forearm (the elbow joint carries it) by clicking it.
    let wrist = screen_position(&harness, "r_radiocarpal");
    let elbow = screen_position(&harness, "r_elbow");
    let pelvis = screen_position(&harness, "sacroiliac");
    let outward = egui::vec2((wrist.x - pelvis.x).signum() * 3.0, 0.0);
    let on_forearm = elbow + (wrist - elbow) * 0.6 + outward;
    click_at(&mut harness, on_forearm);
    let selected = state(&harness);
    assert_eq!(selected["selected"], "r_elbow");
    let ring = selected["rings"].as_array().unwrap()[0].clone();
    let index = ring["index"].as_u64().unwrap() as usize;
    let before = ring["value"].as_f64().unwrap();
    let at = |key: &str| {
        Pos2::new(
            ring[key][0].as_f64().unwrap() as f32,
            ring[key][1].as_f64().unwrap() as f32,
        )
    };
    let (start, centre) = (at("screen"), at("centre"));
    // A quarter turn around the ring's centre on screen.
    let radius = start.distance(centre);
    let start_angle = (start.y - centre.y).atan2(start.x - centre.x);
    let path: Vec<Pos2> = (0..=12)
        .map(|step| {
            let angle = start_angle + std::f32::consts::FRAC_PI_2 * step as f32 / 12.0;
            centre + egui::vec2(angle.cos(), angle.sin()) * radius
        })
        .collect();
    drag(&mut harness, &path);
    settle(&mut harness);
    let skeleton = harness.state().model().session().skeleton().clone();
    let after = harness.state().model().session().posture().values()[index];
    assert!(
        (after - before).abs() > 0.2,
        "the joint turned: {before} -> {after}"
    );
    assert!(after >= skeleton.lower_limits()[index] - 1e-12);
    assert!(after <= skeleton.upper_limits()[index] + 1e-12);
}

// ---------------------------------------------------------------------------------------------
// Editing tasks in the tasks panel: every edit shows in the document and one undo takes it
// back exactly.

/// Clicks the widget labelled `label` (the only one).
fn click_label(harness: &mut Harness<'static, StanceApp>, label: &str) {
    let centre = harness.get_by_label(label).rect().center();
    click_at(harness, centre);
}

/// Opens the task whose row starts with `description` (its fields show).
fn open_task(harness: &mut Harness<'static, StanceApp>, description: &str) {
    let header = harness.get_by_label_contains(description);
    let centre = header.rect().center();
    if header.accesskit_node().data().is_expanded() != Some(true) {
        click_at(harness, centre);
    }
    harness.run_steps(2);
}

fn undo(harness: &mut Harness<'static, StanceApp>) {
    harness.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    harness.run_steps(2);
}

fn left_foot_task(document: &Document) -> &stance_document::TaskSpec {
    &document.tasks[0]
}

#[test]
fn weight_level_and_active_flag_are_edited_and_undone_exactly() {
    let host = MemoryHost::default();
    let mut harness = harness(&host);
    open_task(&mut harness, "left ankle position");
    let before = document(&harness);
    assert_eq!(left_foot_task(&before).weight, 1.0);

    harness.get_by_label("weight").set_value_accesskit(0.25);
    settle(&mut harness);
    assert_eq!(left_foot_task(&document(&harness)).weight, 0.25);
    undo(&mut harness);
    assert_eq!(document(&harness), before, "undo gives the weight back");

    harness.get_by_label("level").set_value_accesskit(4.0);
    settle(&mut harness);
    assert_eq!(left_foot_task(&document(&harness)).level, 4);
    let levels = state(&harness)["tasks"].as_array().unwrap().clone();
    assert_eq!(levels[0]["level"], 4, "the task moved to level 4");
    undo(&mut harness);
    assert_eq!(document(&harness), before, "undo gives the level back");

    open_task(&mut harness, "left ankle position");
    click_label(&mut harness, "active");
    settle(&mut harness);
    assert!(!left_foot_task(&document(&harness)).active);
    assert_eq!(state(&harness)["tasks"][0]["active"], false);
    undo(&mut harness);
    assert_eq!(document(&harness), before, "undo switches the task back on");
}

#[test]
fn axes_and_goal_are_edited_and_undone_exactly() {
    let host = MemoryHost::default();
    let mut harness = harness(&host);
    open_task(&mut harness, "left ankle position");
    let before = document(&harness);

    // Drop the vertical axis: the task now reads "(xz)".
    click_label(&mut harness, "y");
    settle(&mut harness);
    let after = document(&harness);
    match &left_foot_task(&after).kind {
        TaskKindSpec::Position { axes, .. } => assert_eq!(axes.to_letters(), "xz"),
        other => panic!("{other:?}"),
    }
    assert!(
        state(&harness)["tasks"][0]["description"]
            .as_str()
            .unwrap()
            .contains("(xz)")
    );
    undo(&mut harness);
    assert_eq!(document(&harness), before, "undo gives the axes back");

    // The goal's x, typed in: the foot follows it (level 1).
    open_task(&mut harness, "left ankle position");
    let goal_x = harness.get_all_by_label("x m").nth(1).unwrap();
    goal_x.set_value_accesskit(0.2);
    settle(&mut harness);
    match &left_foot_task(&document(&harness)).kind {
        TaskKindSpec::Position { target, .. } => assert_eq!(target[0], 0.2),
        other => panic!("{other:?}"),
    }
    let foot = joint_world(&harness, "l_talocrural");
    assert!(
        (foot[0] - 0.2).abs() < 1e-3,
        "the foot went to x = 0.2: {foot:?}"
    );
    undo(&mut harness);
    assert_eq!(document(&harness), before, "undo gives the goal back");
}

#[test]
fn the_effector_joint_and_point_are_edited_and_undone_exactly() {
    let host = MemoryHost::default();
    let mut harness = harness(&host);
    open_task(&mut harness, "left ankle position");
    let before = document(&harness);

    click_label(&mut harness, "joint");
    harness.get_by_label("left knee").click_accesskit();
    harness.run_steps(2);
    settle(&mut harness);
    let after = document(&harness);
    match &left_foot_task(&after).kind {
        TaskKindSpec::Position { joint, .. } => assert_eq!(joint, "l_knee"),
        other => panic!("{other:?}"),
    }
    assert_eq!(
        state(&harness)["tasks"][0]["description"],
        "left knee position"
    );
    // The knee is pulled to where the ankle was held (level 1).
    let knee = joint_world(&harness, "l_knee");
    let TaskKindSpec::Position { target, .. } = &left_foot_task(&after).kind else {
        unreachable!()
    };
    assert!(distance(knee, *target) < 1e-3, "knee at {knee:?}");
    undo(&mut harness);
    assert_eq!(document(&harness), before, "undo gives the ankle back");

    // The point on the segment, 10 cm along the joint's z.
    open_task(&mut harness, "left ankle position");
    harness
        .get_all_by_label("z m")
        .next()
        .unwrap()
        .set_value_accesskit(0.1);
    harness.run_steps(2);
    match &left_foot_task(&document(&harness)).kind {
        TaskKindSpec::Position { point, .. } => assert_eq!(*point, [0.0, 0.0, 0.1]),
        other => panic!("{other:?}"),
    }
    undo(&mut harness);
    assert_eq!(document(&harness), before, "undo gives the point back");
}

#[test]
fn an_orientation_goal_is_typed_in_degrees_and_a_gaze_axis_is_edited() {
    let host = MemoryHost::default();
    let mut harness = harness(&host);
    harness.get_by_label("Table 1 example").click();
    settle(&mut harness);
    let before = document(&harness);
    open_task(&mut harness, "left ankle orientation");
    harness.get_by_label("y °").set_value_accesskit(30.0);
    settle(&mut harness);
    let after = document(&harness);
    let TaskKindSpec::Orientation { target, .. } = &after.tasks[1].kind else {
        panic!("{:?}", after.tasks[1]);
    };
    let expected = glam::DQuat::from_rotation_y(30f64.to_radians());
    assert!(
        glam::DQuat::from_array(*target).dot(expected).abs() > 1.0 - 1e-9,
        "{target:?}"
    );
    assert!(
        state(&harness)["tasks"][1]["residual"].as_f64().unwrap() < 1e-3,
        "the foot turned to the typed orientation"
    );
    undo(&mut harness);
    assert_eq!(document(&harness), before);

    open_task(&mut harness, "head gaze");
    harness
        .get_by_role_and_label(egui::accesskit::Role::SpinButton, "x")
        .set_value_accesskit(1.0);
    harness.run_steps(2);
    let TaskKindSpec::Gaze { axis, .. } = &document(&harness).tasks[2].kind else {
        panic!();
    };
    assert_eq!(*axis, [1.0, 0.0, 1.0]);
    undo(&mut harness);
    assert_eq!(document(&harness), before);
}

#[test]
fn a_removed_task_comes_back_with_undo() {
    let host = MemoryHost::default();
    let mut harness = harness(&host);
    let before = document(&harness);
    open_task(&mut harness, "right ankle position");
    click_label(&mut harness, "Remove");
    settle(&mut harness);
    let after = document(&harness);
    assert_eq!(after.tasks.len(), before.tasks.len() - 1);
    assert!(!after.tasks.iter().any(|task| matches!(
        &task.kind,
        TaskKindSpec::Position { joint, .. } if joint == "r_talocrural"
    )));
    undo(&mut harness);
    assert_eq!(document(&harness), before);
}

// ---------------------------------------------------------------------------------------------
// Mirror and the swivel handle

#[test]
fn mirror_takes_the_tasks_along_and_the_mirrored_right_hand_task_holds() {
    let host = MemoryHost::default();
    let mut harness = harness(&host);
    harness.get_by_label("Table 1 example").click();
    settle(&mut harness);
    let before = document(&harness);
    let hand_before = joint_world(&harness, "r_radiocarpal");
    harness.get_by_label("Mirror").click();
    settle(&mut harness);
    let after = document(&harness);
    assert!(
        !after.tasks.iter().any(|task| task.level == 1
            && matches!(
                &task.kind,
                TaskKindSpec::Position { joint, .. } if joint == "r_radiocarpal"
            )),
        "the right-hand task became a left-hand task"
    );
    let hand_task = after
        .tasks
        .iter()
        .position(|task| {
            task.level == 1
                && matches!(&task.kind, TaskKindSpec::Position { joint, .. } if joint == "l_radiocarpal")
        })
        .expect("a level-1 left-hand task");
    let TaskKindSpec::Position { target, .. } = &after.tasks[hand_task].kind else {
        unreachable!()
    };
    assert_eq!(*target, [0.3, 1.15, 0.4], "the sphere reflected: x -> -x");
    let status = &state(&harness)["tasks"][hand_task];
    assert!(status["residual"].as_f64().unwrap() < 1e-3, "{status}");
    let hand_after = joint_world(&harness, "l_radiocarpal");
    assert!(
        distance(
            hand_after,
            [-hand_before[0], hand_before[1], hand_before[2]]
        ) < 1e-3,
        "the left hand is where the right one was, reflected: {hand_before:?} -> {hand_after:?}"
    );
    undo(&mut harness);
    assert_eq!(document(&harness), before, "one undo takes the mirror back");
}

#[test]
fn dragging_the_swivel_handle_turns_the_elbow_and_the_hand_stays() {
    let host = MemoryHost::default();
    let mut harness = harness(&host);
    // A pose with the right elbow bent, opened from a file.
    let mut pose = document(&harness);
    pose.posture.set("r_elbow", stance_ik::Dof::Rx, -1.2);
    harness
        .state_mut()
        .apply(Command::File(FileCommand::OpenFile {
            name: "bent.json".to_owned(),
            bytes: pose.to_json(false).as_bytes().to_vec(),
        }));
    settle(&mut harness);
    // Select the right upper arm by clicking it.
    let shoulder = screen_position(&harness, "r_shoulder");
    let elbow = screen_position(&harness, "r_elbow");
    let pelvis = screen_position(&harness, "sacroiliac");
    let outward = egui::vec2((elbow.x - pelvis.x).signum() * 3.0, 0.0);
    let on_arm = shoulder + (elbow - shoulder) * 0.5 + outward;
    click_at(&mut harness, on_arm);
    let selected = state(&harness);
    assert_eq!(selected["selected"], "r_shoulder");
    let swivel = selected["swivel"].clone();
    assert_eq!(swivel["limb"], "r_arm", "{swivel}");
    let angle_before = swivel["angle"].as_f64().unwrap();
    let wrist_before = joint_world(&harness, "r_radiocarpal");
    let elbow_before = joint_world(&harness, "r_elbow");
    let document_before = document(&harness);
    let circle: Vec<Pos2> = swivel["circle"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| Pos2::new(p[0].as_f64().unwrap() as f32, p[1].as_f64().unwrap() as f32))
        .collect();
    let handle = Pos2::new(
        swivel["screen"][0].as_f64().unwrap() as f32,
        swivel["screen"][1].as_f64().unwrap() as f32,
    );
    assert!(
        handle.distance(circle[0]) < 1.0,
        "the handle is on its circle"
    );
    // An eighth of a turn along the drawn circle.
    drag(&mut harness, &circle[..=6]);
    settle(&mut harness);
    let angle_after = state(&harness)["swivel"]["angle"].as_f64().unwrap();
    assert!(
        (angle_after - angle_before).abs() > 0.3,
        "the swivel turned: {angle_before} -> {angle_after}"
    );
    let elbow_on_screen = screen_position(&harness, "r_elbow");
    assert!(
        elbow_on_screen.distance(circle[6]) < 0.25 * circle[0].distance(circle[6]),
        "the elbow followed the pointer: at {elbow_on_screen:?}, released at {:?}",
        circle[6]
    );
    let elbow_after = joint_world(&harness, "r_elbow");
    assert!(
        distance(elbow_after, elbow_before) > 0.05,
        "the elbow moved: {elbow_before:?} -> {elbow_after:?}"
    );
    let wrist_after = joint_world(&harness, "r_radiocarpal");
    assert!(
        distance(wrist_after, wrist_before) < 1e-6,
        "the wrist stayed: moved {} m",
        distance(wrist_after, wrist_before)
    );
    undo(&mut harness);
    assert_eq!(
        document(&harness),
        document_before,
        "one undo turns it back"
    );
}

#[test]
fn the_pin_tool_pins_a_body_part_in_one_click_and_undo_removes_the_pin() {
    let host = MemoryHost::default();
    let mut harness = harness(&host);
    let before = document(&harness);
    harness.get_by_label("Pin tool").click();
    harness.run_steps(2);
    // The middle of the left forearm.
    let elbow = screen_position(&harness, "l_elbow");
    let wrist = screen_position(&harness, "l_radiocarpal");
    click_at(&mut harness, elbow.lerp(wrist, 0.5));
    settle(&mut harness);
    let after = document(&harness);
    assert_eq!(after.tasks.len(), before.tasks.len() + 1, "one pin added");
    let pin = after.tasks.last().unwrap();
    assert_eq!(pin.level, 1);
    match &pin.kind {
        TaskKindSpec::Position { joint, .. } => assert_eq!(joint, "l_elbow"),
        other => panic!("a position pin, got {other:?}"),
    }
    harness.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    settle(&mut harness);
    assert_eq!(document(&harness).tasks, before.tasks);
}

#[test]
fn a_level_dragged_by_its_title_takes_the_place_of_another_and_undo_restores_the_order() {
    let host = MemoryHost::default();
    let mut harness = harness(&host);
    let before = document(&harness);
    let levels_of = |document: &Document| -> Vec<(u32, String)> {
        document
            .tasks
            .iter()
            .map(|task| (task.level, task.kind.name().to_owned()))
            .collect()
    };
    // Default: feet at 1, balance at 2, comfort at 10.
    assert!(levels_of(&before).contains(&(10, "comfort".to_owned())));
    let from = harness.get_by_label("Level 10").rect().center();
    let onto = harness.get_by_label("Level 1").rect().center();
    let path: Vec<Pos2> = (0..=12)
        .map(|step| from + (onto - from) * (step as f32 / 12.0))
        .collect();
    drag(&mut harness, &path);
    settle(&mut harness);
    let after = document(&harness);
    let moved = levels_of(&after);
    assert!(moved.contains(&(1, "comfort".to_owned())), "{moved:?}");
    assert!(
        after
            .tasks
            .iter()
            .filter(|task| task.kind.name() == "position")
            .all(|task| task.level == 2),
        "the feet moved down one place: {moved:?}"
    );
    assert!(moved.contains(&(10, "balance".to_owned())), "{moved:?}");
    harness.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    settle(&mut harness);
    assert_eq!(document(&harness).tasks, before.tasks);
}

#[test]
fn a_key_shows_the_timeline_and_its_play_button_toggles_playing() {
    let host = MemoryHost::default();
    let mut harness = harness(&host);
    assert!(
        harness.query_by_label("Set key (K)").is_none(),
        "no timeline yet"
    );
    harness.key_press(Key::K);
    harness.run_steps(2);
    let motion = state(&harness)["motion"].clone();
    assert_eq!(motion["keys"], serde_json::json!([0]));
    assert_eq!(motion["playing"], false);
    harness.get_by_label("Set key (K)");
    harness.get_by_label("Play").click();
    harness.run_steps(2);
    assert_eq!(state(&harness)["motion"]["playing"], true);
    harness.get_by_label("Pause").click();
    harness.run_steps(2);
    assert_eq!(state(&harness)["motion"]["playing"], false);
}

#[test]
fn the_motion_menu_opens_the_clip_mapping_window_with_the_clip_joints() {
    let host = MemoryHost::default();
    let mut harness = harness(&host);
    harness
        .state_mut()
        .apply(Command::File(FileCommand::OpenFile {
            name: "walk.bvh".into(),
            bytes: include_bytes!("../../../tests/fixtures/motion/walk.bvh").to_vec(),
        }));
    harness.run_steps(2);
    assert!(harness.state().model().timeline().has_clip());
    harness.get_by_label("Motion").click();
    harness.run_steps(2);
    harness.get_by_label("Clip mapping…").click();
    harness.run_steps(2);
    // The clip's own joint names, each with its H-Anim joint.
    harness.get_by_label("LeftKnee");
    harness.get_by_label("Apply");
    assert!(harness.query_by_label("Revert last correction").is_none());
}

#[test]
fn numpad_views_orthographic_framing_and_a_view_saved_with_the_document() {
    use stance_render::{OrbitCamera, ViewPreset};
    let host = MemoryHost::default();
    let mut harness = harness(&host);
    let eye = |harness: &Harness<'static, StanceApp>| {
        let c = harness.state().camera();
        (c.eye_world() - c.target_world).normalize()
    };
    harness.key_press(Key::Num1);
    harness.run_steps(1);
    assert!((eye(&harness) - glam::Vec3::Z).length() < 1e-4, "front");
    harness.key_press_modifiers(Modifiers::CTRL, Key::Num3);
    harness.run_steps(1);
    assert!(
        (eye(&harness) - glam::Vec3::X).length() < 1e-4,
        "the body's left side"
    );
    harness.key_press(Key::Num7);
    harness.run_steps(1);
    assert!(eye(&harness).y > 0.99, "top");
    harness.key_press(Key::Num5);
    harness.run_steps(1);
    assert!(harness.state().camera().orthographic);
    // Frame the selected left hand: it comes to the middle, close up.
    let hand = harness
        .state()
        .model()
        .session()
        .skeleton()
        .joint_index("l_radiocarpal")
        .unwrap();
    harness
        .state_mut()
        .apply(Command::View(ViewCommand::Select(Some(hand))));
    harness.key_press(Key::Period);
    harness.run_steps(1);
    let camera = *harness.state().camera();
    let hand_at = harness.state().model().session().frames().joint_position[hand].as_vec3();
    assert!(
        (camera.target_world - hand_at).length() < 0.15,
        "{}",
        camera.target_world
    );
    assert!(camera.distance_m < OrbitCamera::default().distance_m * 0.5);
    // Save the view with the document, move away, then open the saved document: the view
    // comes back.
    harness.get_by_label("View").click();
    harness.run_steps(2);
    harness.get_by_label("Camera").hover();
    harness.run_steps(2);
    harness
        .get_by_label("Save this view with the document")
        .click();
    harness.run_steps(2);
    let document = harness.state().model().session().document();
    assert!(document.camera.unwrap().orthographic);
    harness.key_press(Key::Num1);
    harness.key_press(Key::Num5);
    harness.run_steps(1);
    assert!(!harness.state().camera().orthographic);
    harness
        .state_mut()
        .apply(Command::File(FileCommand::OpenFile {
            name: "saved.json".into(),
            bytes: document.to_json(true).into_bytes(),
        }));
    harness
        .state_mut()
        .apply(Command::Posture(PostureCommand::SaveCamera(None)));
    harness
        .state_mut()
        .apply(Command::History(HistoryCommand::Undo));
    harness.run_steps(2);
    let back = harness.state().camera();
    assert!(back.orthographic && (back.target_world - camera.target_world).length() < 1e-4);
    let _ = ViewPreset::ALL;
}

#[test]
fn the_hands_section_poses_both_hands_with_a_click_and_is_gone_without_fingers() {
    let host = MemoryHost::default();
    let mut harness = harness(&host);
    harness.get_by_label("fist").click();
    settle(&mut harness);
    let model = harness.state().model();
    let closed = model.hand_curl(stance_editor::model::Hands::Both, None);
    assert!(closed.unwrap() > 0.8, "{closed:?}");
    assert!(model.history().can_undo());
    harness
        .state_mut()
        .apply(Command::Avatar(AvatarCommand::SetLevelOfArticulation(
            stance_hanim::LevelOfArticulation::Loa1,
        )));
    settle(&mut harness);
    assert!(harness.query_by_label("fist").is_none());
    assert!(harness.query_by_label("Hands").is_none());
}

#[test]
fn file_open_keypoints_asks_the_page_for_a_file_and_the_file_is_lifted() {
    // Catches: the menu entry missing, not opening the picker, or the picked file opened as
    // something else (a document) instead of lifted.
    let host = MemoryHost::default();
    let mut harness = harness(&host);
    harness.get_by_label("File").click();
    harness.run_steps(2);
    harness
        .get_by_label("Open keypoints (OpenPose JSON)…")
        .click();
    harness.run_steps(2);
    assert_eq!(host.inner.borrow().file_requests, 1);
    // The page answers with a file that is not keypoints: the lift says so by name.
    harness
        .state_mut()
        .apply(Command::File(FileCommand::OpenFile {
            name: "pose.json".to_owned(),
            bytes: br#"{"people": [{"pose_keypoints_2d": [1, 2]}]}"#.to_vec(),
        }));
    harness.run_steps(2);
    let notice = harness.state().model().notice().cloned().unwrap();
    assert!(notice.is_error, "{}", notice.text);
    assert!(
        notice.text.contains("pose.json could not be lifted"),
        "{}",
        notice.text
    );
}

// ---------------------------------------------------------------------------------------------
// Props in the viewport: picked, moved over the floor, turned and scaled with their gizmo.

fn pos(value: &serde_json::Value) -> Pos2 {
    Pos2::new(
        value[0].as_f64().unwrap() as f32,
        value[1].as_f64().unwrap() as f32,
    )
}

fn straight(from: Pos2, to: Pos2) -> Vec<Pos2> {
    (0..=10)
        .map(|k| from + (to - from) * (k as f32 / 10.0))
        .collect()
}

#[test]
fn a_prop_is_dragged_over_the_floor_turned_and_scaled_with_its_gizmo() {
    // Catches: props not picked in the view (the drag orbits the camera instead), a drag
    // that lifts or sinks the prop, a gizmo that does not show or does nothing, a drag that
    // takes more than one undo step.
    use stance_document::PropShape;
    use stance_editor::model::SceneCommand;
    let host = MemoryHost::default();
    let mut harness = harness(&host);
    harness
        .state_mut()
        .apply(Command::Scene(SceneCommand::AddProp(PropShape::Box {
            size: [0.6, 0.2, 0.4],
        })));
    settle(&mut harness);
    let before = state(&harness)["props"]["list"][0].clone();
    let at = pos(&before["screen"]);
    // Dragged 80 px to the right: it slides over the floor, at the same height.
    drag(&mut harness, &straight(at, at + egui::vec2(80.0, 0.0)));
    settle(&mut harness);
    let moved = state(&harness)["props"]["list"][0].clone();
    let (x0, y0) = (
        before["position"][0].as_f64().unwrap(),
        before["position"][1].as_f64().unwrap(),
    );
    let (x1, y1) = (
        moved["position"][0].as_f64().unwrap(),
        moved["position"][1].as_f64().unwrap(),
    );
    assert!((x1 - x0).abs() > 0.1, "moved from {x0} to {x1}");
    assert!((y1 - y0).abs() < 1e-9, "its height {y0} -> {y1}");
    undo(&mut harness);
    assert_eq!(
        state(&harness)["props"]["list"][0]["position"],
        before["position"]
    );
    // A click selects it: its gizmo shows.
    click_at(&mut harness, at);
    settle(&mut harness);
    let selected = state(&harness);
    assert_eq!(selected["props"]["selected"], 0);
    let gizmo = selected["props"]["gizmo"].clone();
    assert!(gizmo.is_object(), "{selected}");
    // The square dragged outward: bigger.
    let square = pos(&gizmo["square"]);
    let centre = pos(&selected["props"]["list"][0]["screen"]);
    let outward = square + (square - centre) * 0.6;
    drag(&mut harness, &straight(square, outward));
    settle(&mut harness);
    let grown = state(&harness)["props"]["list"][0]["dimensions"][0]
        .as_f64()
        .unwrap();
    assert!(grown > 0.65, "width {grown}");
    // The ring dragged a quarter round: turned about the vertical.
    let gizmo = state(&harness)["props"]["gizmo"].clone();
    let (start, quarter) = (pos(&gizmo["ring"]), pos(&gizmo["ring_quarter"]));
    drag(&mut harness, &straight(start, quarter));
    settle(&mut harness);
    let rotation = &state(&harness)["props"]["list"][0]["rotation"];
    let w = rotation[3].as_f64().unwrap();
    assert!(w.abs() < 0.99, "turned: {rotation}");
    assert!(
        rotation[0].as_f64().unwrap().abs() < 1e-9 && rotation[2].as_f64().unwrap().abs() < 1e-9,
        "about the vertical only: {rotation}"
    );
}

#[test]
fn file_open_photo_asks_the_page_for_a_photo_and_view_toggles_it() {
    // Catches: the menu entry missing or not reaching the page's detector, or the View
    // menu's photo toggle missing once a photo is lifted.
    use stance_editor::model::photo::{DetectedPhoto, Landmark, MEDIAPIPE_LANDMARKS};
    let host = MemoryHost::default();
    let mut harness = harness(&host);
    harness.get_by_label("File").click();
    harness.run_steps(2);
    harness.get_by_label("Open photo…").click();
    harness.run_steps(2);
    assert_eq!(host.inner.borrow().photo_requests, 1);
    // The page answers with a person standing, seen from the front.
    let mut landmarks = vec![
        Landmark {
            x: 0.5,
            y: 0.5,
            z: 0.0,
            visibility: 0.0,
        };
        MEDIAPIPE_LANDMARKS
    ];
    // Shoulders, hips, knees and ankles of a body facing the camera (its left on the
    // image's right), a head above.
    let points = [
        (0, 0.50, 0.15),
        (11, 0.56, 0.28),
        (12, 0.44, 0.28),
        (23, 0.54, 0.55),
        (24, 0.46, 0.55),
        (25, 0.54, 0.72),
        (26, 0.46, 0.72),
        (27, 0.54, 0.90),
        (28, 0.46, 0.90),
        (13, 0.58, 0.42),
        (14, 0.42, 0.42),
        (15, 0.59, 0.55),
        (16, 0.41, 0.55),
    ];
    for (index, px, py) in points {
        landmarks[index] = Landmark {
            x: px,
            y: py,
            z: 0.0,
            visibility: 0.99,
        };
    }
    harness
        .state_mut()
        .apply(Command::from(stance_editor::HostMessage::PhotoDetected(
            Box::new(DetectedPhoto {
                name: "person.jpg".to_owned(),
                size_px: [400, 600],
                landmarks,
                reference_rgba: vec![200; 4 * 4 * 6],
                reference_size_px: [4, 6],
                detect_ms: 1.0,
            }),
        )));
    harness.run_steps(2);
    let notice = harness.state().model().notice().cloned().unwrap();
    assert!(!notice.is_error, "{}", notice.text);
    assert!(harness.state().model().photo_shown());
    harness.get_by_label("View").click();
    harness.run_steps(2);
    harness.get_by_label("Photo behind the view").click();
    harness.run_steps(2);
    assert!(!harness.state().model().photo_shown());
}

/// Catches a Collision toggle or capsules entry that does nothing, or one that edits the
/// document the wrong way: a click on the tasks panel's *Collision* adds the body's collision
/// task at level 2 (the state says it is on), a second click leaves it in the list inactive,
/// undo turns it back on; *View > Collision capsules* shows the capsules without changing the
/// document.
#[test]
fn the_collision_toggle_and_the_capsules_entry_work_from_the_panels() {
    let host = MemoryHost::default();
    let mut harness = harness(&host);
    let before = document(&harness);
    harness.get_by_label("Collision (body and floor)").click();
    settle(&mut harness);
    let on = document(&harness);
    assert_eq!(on.tasks.len(), before.tasks.len() + 1);
    let collision: Vec<_> = on
        .tasks
        .iter()
        .filter(|t| matches!(t.kind, TaskKindSpec::Collision { .. }))
        .collect();
    assert_eq!(collision.len(), 1);
    assert!(collision[0].active && collision[0].level == 2);
    assert_eq!(state(&harness)["collision"]["on"], true);
    harness.get_by_label("Collision (body and floor)").click();
    settle(&mut harness);
    assert_eq!(state(&harness)["collision"]["on"], false);
    assert_eq!(
        document(&harness).tasks.len(),
        on.tasks.len(),
        "kept, inactive"
    );
    harness.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    settle(&mut harness);
    assert_eq!(document(&harness), on);

    harness.get_by_label("View").click();
    harness.run_steps(2);
    harness.get_by_label("Collision capsules").click();
    harness.run_steps(2);
    assert!(harness.state().model().show_capsules());
    assert_eq!(state(&harness)["collision"]["capsules_shown"], true);
    assert_eq!(document(&harness), on);
}
