//! The editor's model driven by commands alone, without egui: gestures, undo, sessions,
//! files, the per-frame step.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use crate::clocked;
use clocked::Clocked;
use stance_model::model::{
    AvatarCommand, FileCommand, GestureCommand, HistoryCommand, LibraryCommand, PostureCommand,
    TaskCommand, ViewCommand,
};

use std::f64::consts::FRAC_PI_4;

use glam::DVec3;
use stance_document::{Document, TaskKindSpec, TaskSpec};
use stance_hanim::{LevelOfArticulation, LimbName};
use stance_model::{Command, Gesture, MemoryHost};

#[test]
fn a_pull_moves_the_hand_while_the_pinned_feet_hold_and_undo_restores_the_document() {
    let mut editor = Clocked::new();
    editor.settle_within(200);
    let before = editor.model.document();
    let foot = editor.position("l_talocrural");
    let wrist = editor.joint("r_radiocarpal");
    let start = editor.position("r_radiocarpal");
    editor.apply(Command::Gesture(GestureCommand::BeginPull {
        joint: wrist,
        point_world: start,
    }));
    assert!(editor.model.is_pulling());
    assert_eq!(editor.model.selected_joint(), Some(wrist));
    let target = start + DVec3::new(0.0, 0.2, 0.1);
    for step in 1..=20 {
        let along = start + (target - start) * (f64::from(step) / 20.0);
        editor.apply(Command::Gesture(GestureCommand::MoveGrab {
            target_world: along,
        }));
        editor.frames(1);
    }
    editor.settle_within(300);
    let reached = editor.position("r_radiocarpal");
    assert!(
        (reached - target).length() < 0.01,
        "the wrist is {:.3} m from the pulled point",
        (reached - target).length()
    );
    assert!(
        (editor.position("l_talocrural") - foot).length() < 1e-3,
        "the pinned foot moved"
    );
    // The trace followed the pull.
    assert!(editor.model.trace().len() > 5);
    editor.apply(Command::Gesture(GestureCommand::EndGesture));
    assert!(editor.model.gesture().is_none());
    editor.apply(Command::History(HistoryCommand::Undo));
    assert_eq!(editor.model.document(), before);
}

#[test]
fn escape_during_a_pull_puts_the_body_back() {
    let mut editor = Clocked::new();
    editor.settle_within(200);
    let before = editor.model.document();
    let wrist = editor.joint("l_radiocarpal");
    let start = editor.position("l_radiocarpal");
    editor.apply(Command::Gesture(GestureCommand::BeginPull {
        joint: wrist,
        point_world: start,
    }));
    editor.apply(Command::Gesture(GestureCommand::MoveGrab {
        target_world: start + DVec3::new(0.1, 0.3, 0.0),
    }));
    editor.frames(10);
    assert_ne!(editor.model.document().posture, before.posture);
    editor.apply(Command::Gesture(GestureCommand::CancelGesture));
    assert!(editor.model.gesture().is_none());
    assert_eq!(editor.model.document(), before);
}

#[test]
fn a_goal_drag_moves_the_goals_it_took_and_is_one_undo_step() {
    let mut editor = Clocked::new();
    let hand = editor.position("r_radiocarpal");
    let mut tasks = editor.model.session().tasks().to_vec();
    let mut reach = TaskSpec::pin("r_radiocarpal", hand.to_array());
    reach.level = 3;
    tasks.push(reach);
    let index = tasks.len() - 1;
    editor.apply(Command::Task(TaskCommand::Set {
        kind: stance_model::history::EditKind::Command,
        tasks,
    }));
    let with_task = editor.model.document();
    editor.apply(Command::Gesture(GestureCommand::BeginHandle(
        Gesture::Goal {
            tasks: vec![index],
            plane_point_world: hand,
        },
    )));
    for step in 1..=5 {
        editor.apply(Command::Gesture(GestureCommand::MoveGoal {
            goal_world: hand + DVec3::new(0.0, 0.02 * f64::from(step), 0.0),
            floor_world: None,
        }));
        editor.frames(1);
    }
    editor.apply(Command::Gesture(GestureCommand::EndGesture));
    let TaskKindSpec::Position { target, .. } = &editor.model.session().tasks()[index].kind else {
        panic!("the task is a position task");
    };
    assert!((target[1] - (hand.y + 0.1)).abs() < 1e-12);
    editor.apply(Command::History(HistoryCommand::Undo));
    assert_eq!(editor.model.document().tasks, with_task.tasks);
}

#[test]
fn a_ring_turns_its_dof_by_the_pointer_angle() {
    let mut editor = Clocked::new();
    let elbow = editor.joint("l_elbow");
    let dof = editor.model.session().skeleton().joints()[elbow].dof_start;
    let start_value = editor.model.session().posture().values()[dof];
    editor.apply(Command::Gesture(GestureCommand::BeginHandle(
        Gesture::Ring {
            dof,
            centre_px: [100.0, 100.0],
            last_angle: 0.0,
            accumulated: 0.0,
            start_value,
            sign: 1.0,
        },
    )));
    // A quarter turn in two steps: the turn accumulates.
    editor.apply(Command::Gesture(GestureCommand::TurnRing {
        screen_angle: std::f32::consts::FRAC_PI_8,
    }));
    editor.apply(Command::Gesture(GestureCommand::TurnRing {
        screen_angle: std::f32::consts::FRAC_PI_4,
    }));
    let value = editor.model.session().posture().values()[dof];
    // Screen y points down: a positive screen angle is a clockwise turn, against the axis
    // that points toward the camera (sign +1).
    assert!(
        (value - (start_value - FRAC_PI_4)).abs() < 1e-6,
        "{value} vs {}",
        start_value - FRAC_PI_4
    );
    editor.apply(Command::Gesture(GestureCommand::EndGesture));
    assert!(editor.model.gesture().is_none());
}

#[test]
fn a_ring_drag_across_the_pi_seam_keeps_turning_the_same_way() {
    // Catches a ring that takes the pointer's screen angle as it comes, without unwrapping it
    // across the ±π seam: the angle jumps from just below +π to just above -π there, a turn
    // of 0.1 rad read as -2π + 0.1, and the DOF spins the other way to its limit. (The test
    // above, named for the seam until now, never reached it: it turned from 0 to π/4.)
    //
    // By hand: the pointer starts at π - 0.1 and moves to π - 0.05, then -π + 0.05 (that is
    // π + 0.05, past the seam), then -π + 0.15 (π + 0.15): turns of 0.05, 0.1 and 0.1, in all
    // 0.25 rad clockwise, so the DOF goes to start - 0.25 (sign +1). Back across the seam to
    // π - 0.1: a turn of -0.25, the DOF back at its start.
    use std::f32::consts::PI;
    let mut editor = Clocked::new();
    let elbow = editor.joint("l_elbow");
    let dof = editor.model.session().skeleton().joints()[elbow].dof_start;
    // The elbow flexes toward -rx: start a little bent so that the turn stays in its range.
    editor.apply(Command::Posture(PostureCommand::SetDof {
        dof,
        value: -0.5,
    }));
    let start_value = editor.model.session().posture().values()[dof];
    assert!((start_value + 0.5).abs() < 1e-12, "{start_value}");
    editor.apply(Command::Gesture(GestureCommand::BeginHandle(
        Gesture::Ring {
            dof,
            centre_px: [100.0, 100.0],
            last_angle: PI - 0.1,
            accumulated: 0.0,
            start_value,
            sign: 1.0,
        },
    )));
    let accumulated = |editor: &Clocked| match editor.model.gesture() {
        Some(Gesture::Ring { accumulated, .. }) => *accumulated,
        other => panic!("a ring drag: {other:?}"),
    };
    for screen_angle in [PI - 0.05, -PI + 0.05, -PI + 0.15] {
        editor.apply(Command::Gesture(GestureCommand::TurnRing { screen_angle }));
    }
    let turned = accumulated(&editor);
    assert!(
        (turned - 0.25).abs() < 1e-5,
        "turned {turned} rad, by hand 0.25"
    );
    let value = editor.model.session().posture().values()[dof];
    assert!(
        (value - (start_value - 0.25)).abs() < 1e-5,
        "{value} vs {}",
        start_value - 0.25
    );
    editor.apply(Command::Gesture(GestureCommand::TurnRing {
        screen_angle: PI - 0.1,
    }));
    assert!(
        accumulated(&editor).abs() < 1e-5,
        "{}",
        accumulated(&editor)
    );
    let value = editor.model.session().posture().values()[dof];
    assert!(
        (value - start_value).abs() < 1e-5,
        "{value} vs {start_value}"
    );
    editor.apply(Command::Gesture(GestureCommand::EndGesture));
}

#[test]
fn a_swivel_drag_turns_the_elbow_around_the_arm_and_holds_the_hand() {
    let mut editor = Clocked::new();
    editor.settle_within(200);
    // Bend the elbow so that the arm has a swivel circle.
    let elbow = editor.joint("r_elbow");
    let dof = editor.model.session().skeleton().joints()[elbow].dof_start;
    editor.apply(Command::Posture(PostureCommand::SetDof {
        dof,
        value: -1.2,
    }));
    editor.settle_within(200);
    let limb = LimbName::RightArm;
    let Some((swivel, feasible)) = editor.model.session().limb_swivel(limb) else {
        panic!("the right arm has a swivel angle");
    };
    // A turn the joint limits allow.
    let Some(wanted) = [0.4, -0.4, 0.2, -0.2].into_iter().find(|turn| {
        feasible
            .iter()
            .any(|interval| interval.contains(swivel + turn))
    }) else {
        panic!("the arm can swivel a little: {feasible:?}");
    };
    let shoulder = editor.position("r_shoulder");
    let wrist = editor.position("r_radiocarpal");
    let middle = editor.position("r_elbow");
    let axis = (wrist - shoulder).normalize();
    let centre = shoulder + axis * (middle - shoulder).dot(axis);
    let start_direction = (middle - centre).normalize();
    editor.apply(Command::Gesture(GestureCommand::BeginHandle(
        Gesture::Swivel {
            limb,
            start_swivel: swivel,
            start_direction,
            centre_world: centre,
            axis_world: axis,
        },
    )));
    // The pointer `wanted` around the axis (right-handed).
    let turned = centre
        + (start_direction * wanted.cos() + axis.cross(start_direction) * wanted.sin()) * 0.1;
    editor.apply(Command::Gesture(GestureCommand::TurnSwivel {
        point_world: turned,
    }));
    editor.frames(5);
    let Some((now, _)) = editor.model.session().limb_swivel(limb) else {
        panic!("the right arm has a swivel angle");
    };
    let turn = (now - swivel + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
        - std::f64::consts::PI;
    assert!(
        (turn - wanted).abs() < 0.02,
        "the swivel turned {turn} rad for {wanted}"
    );
    assert!(
        (editor.position("r_radiocarpal") - wrist).length() < 0.01,
        "the hand stayed"
    );
    editor.apply(Command::Gesture(GestureCommand::EndGesture));
}

#[test]
fn there_is_one_gesture_at_a_time() {
    let mut editor = Clocked::new();
    let elbow = editor.joint("l_elbow");
    let dof = editor.model.session().skeleton().joints()[elbow].dof_start;
    editor.apply(Command::Gesture(GestureCommand::BeginHandle(
        Gesture::Ring {
            dof,
            centre_px: [0.0, 0.0],
            last_angle: 0.0,
            accumulated: 0.0,
            start_value: 0.0,
            sign: 1.0,
        },
    )));
    let wrist = editor.joint("r_radiocarpal");
    let point = editor.position("r_radiocarpal");
    editor.apply(Command::Gesture(GestureCommand::BeginPull {
        joint: wrist,
        point_world: point,
    }));
    assert!(editor.model.is_pulling());
    // A ring command now does nothing: the ring gesture is over.
    let before = editor.model.session().posture().values()[dof];
    editor.apply(Command::Gesture(GestureCommand::TurnRing {
        screen_angle: 1.0,
    }));
    assert_eq!(editor.model.session().posture().values()[dof], before);
}

#[test]
fn switching_the_level_of_articulation_replaces_the_session_and_keeps_the_history() {
    let mut editor = Clocked::new();
    // A finger bent: a joint the LOA 1 body lacks.
    let finger = editor.joint("l_metacarpophalangeal_2");
    let dof = editor.model.session().skeleton().joints()[finger].dof_start;
    editor.apply(Command::Posture(PostureCommand::SetDof { dof, value: 0.4 }));
    let wrist = editor.joint("r_radiocarpal");
    editor.apply(Command::View(ViewCommand::Select(Some(wrist))));
    editor.apply(Command::Gesture(GestureCommand::BeginPull {
        joint: wrist,
        point_world: editor.position("r_radiocarpal"),
    }));
    let generation = editor.model.session_generation();
    editor.apply(Command::Avatar(AvatarCommand::SetLevelOfArticulation(
        LevelOfArticulation::Loa1,
    )));
    assert_eq!(
        editor.model.notice().map(|notice| notice.text.clone()),
        None,
        "no complaint"
    );
    assert_eq!(
        editor.model.level_of_articulation(),
        LevelOfArticulation::Loa1
    );
    assert!(editor.model.gesture().is_none());
    assert_eq!(editor.model.selected_joint(), None);
    assert!(editor.model.session_generation() > generation);
    assert!(editor.model.history().can_undo());
    editor.frames(1);
    // The bones follow the new body.
    let owners: Vec<usize> = editor.model.bones().iter().map(|bone| bone.owner).collect();
    let joints = editor.model.session().skeleton().joint_count();
    assert!(owners.iter().all(|&owner| owner < joints));
    // Undo restores the LOA 2 document on the LOA 1 body, its joints the body lacks left out.
    editor.apply(Command::History(HistoryCommand::Undo));
    assert!(
        !editor.model.notice().is_some_and(|notice| notice.is_error),
        "{:?}",
        editor.model.notice()
    );
}

#[test]
fn a_bad_avatar_or_document_leaves_the_work_as_it_was() {
    let mut editor = Clocked::new();
    editor.apply(Command::Posture(PostureCommand::Mirror));
    let before = editor.model.document();
    editor.apply(Command::Avatar(AvatarCommand::LoadAvatar {
        name: "broken.glb".to_owned(),
        bytes: b"glTF\x02\x00\x00\x00garbage".to_vec(),
    }));
    let Some(notice) = editor.model.notice() else {
        panic!("a notice says why");
    };
    assert!(notice.is_error);
    assert!(notice.text.contains("broken.glb"), "{}", notice.text);
    assert!(editor.model.avatar().is_none());
    assert_eq!(editor.model.document(), before);
    editor.apply(Command::File(FileCommand::OpenFile {
        name: "pose.json".to_owned(),
        bytes: br#"{"posture": {"l_elbow": "bent"}}"#.to_vec(),
    }));
    assert!(editor.model.notice().is_some_and(|notice| notice.is_error));
    assert_eq!(editor.model.document(), before);
}

#[test]
fn a_document_opens_as_one_undoable_edit_and_the_step_shows_it() {
    let mut editor = Clocked::new();
    let rest = editor.model.document();
    let mut bent = Clocked::new();
    let elbow = bent.joint("l_elbow");
    let dof = bent.model.session().skeleton().joints()[elbow].dof_start;
    bent.apply(Command::Posture(PostureCommand::SetDof {
        dof,
        value: -1.0,
    }));
    bent.frames(1);
    let document: Document = bent.model.document();
    let bones_before: Vec<_> = editor.model.bones().to_vec();
    editor.apply(Command::File(FileCommand::OpenFile {
        name: "bent.json".to_owned(),
        bytes: document.to_json(false).into_bytes(),
    }));
    assert_eq!(editor.model.document().posture, document.posture);
    editor.frames(1);
    let moved = editor
        .model
        .bones()
        .iter()
        .zip(&bones_before)
        .any(|(now, before)| now.capsule.end_world != before.capsule.end_world);
    assert!(moved, "the cached bones follow the opened posture");
    editor.apply(Command::History(HistoryCommand::Undo));
    assert_eq!(editor.model.document(), rest);
}

#[test]
fn the_step_autosaves_the_document_once_it_changed() {
    let host = MemoryHost::default();
    let storage = host.inner.clone();
    let mut editor = Clocked::with_host(host);
    editor.apply(Command::Posture(PostureCommand::Mirror));
    editor.apply(Command::Posture(PostureCommand::ResetToRest));
    let elbow = editor.joint("l_elbow");
    let dof = editor.model.session().skeleton().joints()[elbow].dof_start;
    editor.apply(Command::Posture(PostureCommand::SetDof {
        dof,
        value: -0.8,
    }));
    // More than the autosave interval later.
    editor.frames(90);
    let saved = storage
        .borrow()
        .storage
        .get(stance_model::library::AUTOSAVE_KEY)
        .cloned();
    let Some(saved) = saved else {
        panic!("the document was autosaved");
    };
    let Ok(document) = Document::from_json(&saved) else {
        panic!("the autosave is a document");
    };
    assert_eq!(document.posture, editor.model.document().posture);
}

#[test]
fn library_commands_save_load_and_delete() {
    let mut editor = Clocked::new();
    let elbow = editor.joint("l_elbow");
    let dof = editor.model.session().skeleton().joints()[elbow].dof_start;
    editor.apply(Command::Posture(PostureCommand::SetDof {
        dof,
        value: -0.9,
    }));
    let bent = editor.model.document();
    editor.apply(Command::Library(LibraryCommand::Save("bent".to_owned())));
    editor.apply(Command::Posture(PostureCommand::ResetToRest));
    assert_ne!(editor.model.document().posture, bent.posture);
    editor.apply(Command::Library(LibraryCommand::Load(0)));
    assert_eq!(editor.model.document().posture, bent.posture);
    editor.apply(Command::Library(LibraryCommand::Delete(0)));
    assert!(editor.model.library().entries().is_empty());
}

#[test]
fn a_limb_task_with_an_orientation_holds_the_hand_turned_as_in_the_cli() {
    // The same limb task as `stance_document`'s problem test: the editor solves it with the
    // orientation too (it used to drop it). A document without a posture is posed when
    // opened.
    let document = r#"{"avatar":"default","posture":{},"tasks":[
      {"kind":"position","joint":"l_talocrural","target":[0.09,0.08,0.0]},
      {"kind":"limb","limb":"r_arm","target":[-0.25,1.15,0.3],"orientation":[0,0,0.3826834,0.9238795],"level":2},
      {"kind":"balance","level":3}
    ]}"#;
    let mut editor = Clocked::new();
    editor.apply(Command::File(FileCommand::OpenFile {
        name: "reach.json".to_owned(),
        bytes: document.as_bytes().to_vec(),
    }));
    assert!(editor.model.notice().is_some_and(|notice| !notice.is_error));
    editor.settle_within(600);
    let wrist = editor.joint("r_radiocarpal");
    let frames = editor.model.session().frames();
    let want = glam::DQuat::from_xyzw(0.0, 0.0, 0.382_683_4, 0.923_879_5).normalize();
    let angle = frames.rotation(wrist).angle_between(want);
    assert!(
        angle < 1e-3,
        "the hand is {angle} rad from the asked orientation"
    );
    let reached = editor.position("r_radiocarpal");
    assert!(
        (reached - DVec3::new(-0.25, 1.15, 0.3)).length() < 1e-3,
        "the hand is at {reached}"
    );
}

/// The same pull (right wrist 20 cm up and out, the feet pinned) with the right shoulder at
/// its default stiffness and made stiff: the stiff shoulder turns less, the goal is reached
/// either way; the stiffness is in the document, one undo step, and undo brings back the
/// default.
#[test]
fn a_stiffer_shoulder_turns_less_in_a_pull_and_the_change_is_one_undo_step() {
    let pull = |stiffness: Option<f64>| {
        let mut editor = Clocked::new();
        editor.settle_within(200);
        let shoulder = editor.joint("r_shoulder");
        let start = editor.model.session().skeleton().joints()[shoulder].dof_start;
        if let Some(value) = stiffness {
            for dof in start..start + 3 {
                editor.apply(Command::Posture(PostureCommand::SetStiffness {
                    dof,
                    value: Some(value),
                }));
            }
        }
        let wrist = editor.joint("r_radiocarpal");
        let from = editor.position("r_radiocarpal");
        editor.apply(Command::Gesture(GestureCommand::BeginPull {
            joint: wrist,
            point_world: from,
        }));
        let target = from + DVec3::new(-0.1, 0.2, 0.1);
        editor.apply(Command::Gesture(GestureCommand::MoveGrab {
            target_world: target,
        }));
        editor.settle_within(300);
        editor.apply(Command::Gesture(GestureCommand::EndGesture));
        let reached = editor.position("r_radiocarpal").distance(target);
        let values = editor.model.session().posture().values()[start..start + 3].to_vec();
        let turned: f64 = values.iter().map(|v| v.abs()).sum();
        (editor, turned, reached)
    };
    let (_, free, reached_free) = pull(None);
    let (mut editor, stiff, reached_stiff) = pull(Some(0.9));
    assert!(
        reached_free < 0.01 && reached_stiff < 0.01,
        "{reached_free} {reached_stiff}"
    );
    assert!(
        stiff < 0.6 * free,
        "shoulder turned {free} rad, stiff {stiff} rad"
    );
    // In the document, and undone: the pull first, then the three stiffness edits (one step,
    // they coalesce per DOF: three steps).
    let shoulder = editor.joint("r_shoulder");
    let start = editor.model.session().skeleton().joints()[shoulder].dof_start;
    let document = editor.model.document();
    assert_eq!(
        document.stiffness.get("r_shoulder", stance_ik::Dof::Rx),
        Some(0.9)
    );
    for _ in 0..4 {
        editor.apply(Command::History(HistoryCommand::Undo));
    }
    let session = editor.model.session();
    for dof in start..start + 3 {
        assert_eq!(
            session.skeleton().stiffness()[dof],
            session.default_stiffness(dof),
            "undo brings back the anatomical default"
        );
    }
    assert!(editor.model.document().stiffness.joints.is_empty());
}

/// The default avatar as a `.gltf` and its `.bin`.
fn gltf_and_bin() -> (Vec<u8>, Vec<u8>) {
    let glb = stance_asset::export_glb(&stance_asset::make_default_avatar().unwrap()).unwrap();
    let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let mut json: serde_json::Value = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
    let bin = glb[20 + json_len + 8..].to_vec();
    json["buffers"] = serde_json::json!([{"byteLength": bin.len(), "uri": "mannequin.bin"}]);
    (serde_json::to_vec(&json).unwrap(), bin)
}

/// A `.gltf` dropped with its `.bin` opens as one avatar, a document dropped with them opens
/// too; a `.gltf` alone names the missing `.bin` and the mannequin stays.
#[test]
fn a_gltf_opens_with_its_bin_and_a_missing_bin_is_named() {
    let (gltf, bin) = gltf_and_bin();
    let mut editor = Clocked::new();
    editor.apply(Command::File(FileCommand::OpenFiles(vec![(
        "mannequin.gltf".to_owned(),
        gltf.clone(),
    )])));
    let notice = editor.model.notice().unwrap();
    assert!(
        notice.is_error && notice.text.contains("mannequin.bin"),
        "{}",
        notice.text
    );
    assert!(editor.model.avatar().is_none(), "the mannequin stays");

    let mut bent = Clocked::new();
    let elbow = bent.joint("l_elbow");
    let dof = bent.model.session().skeleton().joints()[elbow].dof_start;
    bent.apply(Command::Posture(PostureCommand::SetDof {
        dof,
        value: -1.0,
    }));
    let document = bent.model.document().to_json(false).into_bytes();
    editor.apply(Command::File(FileCommand::OpenFiles(vec![
        ("folder/mannequin.bin".to_owned(), bin),
        ("folder/mannequin.gltf".to_owned(), gltf),
        ("pose.json".to_owned(), document),
    ])));
    let avatar = editor.model.avatar().expect("the avatar opened");
    assert_eq!(avatar.name, "folder/mannequin.gltf");
    let values = editor.model.session().posture().values();
    let elbow = editor.joint("l_elbow");
    let dof = editor.model.session().skeleton().joints()[elbow].dof_start;
    assert!(
        (values[dof] + 1.0).abs() < 1e-6,
        "the document opened on it: {}",
        values[dof]
    );
}

/// What the page's worker does with an import request: the editor's own importer, the
/// avatar handed back as transfer bytes.
fn import_as_the_worker_does(request: &stance_model::AvatarImport) -> stance_model::ImportedAvatar {
    let imported = stance_model::avatar::LoadedAvatar::import(
        &request.bytes,
        &request.resources,
        Default::default(),
    )
    .unwrap();
    let transfer = stance_asset::AvatarTransfer::new(imported.avatar.clone()).unwrap();
    stance_model::ImportedAvatar {
        avatar: transfer.into_avatar().unwrap(),
        in_worker: true,
        ..imported
    }
}

#[test]
fn an_avatar_imported_by_the_host_opens_when_it_arrives_and_only_the_last_asked_for() {
    let host = MemoryHost::default();
    host.inner.borrow_mut().imports_avatars = true;
    let asked = host.inner.clone();
    let mut editor = Clocked::with_host(host);
    let bytes = stance_asset::export_glb(&stance_asset::make_default_avatar().unwrap()).unwrap();
    editor.apply(Command::Avatar(AvatarCommand::LoadAvatar {
        name: "first.glb".to_owned(),
        bytes: bytes.clone(),
    }));
    // Asked of the host, not imported here: the body stays the mannequin meanwhile.
    assert_eq!(asked.borrow().avatar_imports.len(), 1);
    assert_eq!(asked.borrow().avatar_imports[0].bytes, bytes);
    assert!(editor.model.avatar().is_none());
    assert_eq!(editor.model.importing(), Some("first.glb"));
    editor.frames(2);

    // A second file asked for before the first arrives: the first's reply is dropped.
    editor.apply(Command::Avatar(AvatarCommand::LoadAvatar {
        name: "second.glb".to_owned(),
        bytes: bytes.clone(),
    }));
    let requests = asked.borrow().avatar_imports.clone();
    let first = import_as_the_worker_does(&requests[0]);
    editor.apply(Command::Avatar(AvatarCommand::AvatarImported {
        name: "first.glb".to_owned(),
        result: Ok(Box::new(first)),
    }));
    assert!(editor.model.avatar().is_none(), "a reply no longer awaited");
    let second = import_as_the_worker_does(&requests[1]);
    let vertices: usize = second
        .avatar
        .meshes
        .iter()
        .flat_map(|m| &m.primitives)
        .map(|p| p.positions.len())
        .sum();
    editor.apply(Command::Avatar(AvatarCommand::AvatarImported {
        name: "second.glb".to_owned(),
        result: Ok(Box::new(second)),
    }));
    let avatar = editor.model.avatar().expect("the awaited avatar opened");
    assert_eq!(editor.model.importing(), None);
    assert_eq!(avatar.name, "second.glb");
    assert_eq!(avatar.vertex_count, vertices);
    assert!(avatar.load.in_worker);
    assert!(avatar.mapping_summary().0 >= 18);
    // Its body is posed: the wrist of the new session follows a pull as on any avatar.
    editor.settle_within(300);
    let before = editor.position("r_radiocarpal");
    let wrist = editor.joint("r_radiocarpal");
    editor.apply(Command::Gesture(GestureCommand::BeginPull {
        joint: wrist,
        point_world: before,
    }));
    editor.apply(Command::Gesture(GestureCommand::MoveGrab {
        target_world: before + DVec3::new(0.0, 0.1, 0.05),
    }));
    editor.settle_within(300);
    editor.apply(Command::Gesture(GestureCommand::EndGesture));
    assert!((editor.position("r_radiocarpal") - before).length() > 0.05);

    // A file the host could not import: the notice names it and the avatar stays.
    editor.apply(Command::Avatar(AvatarCommand::LoadAvatar {
        name: "broken.glb".to_owned(),
        bytes: b"glTF".to_vec(),
    }));
    editor.apply(Command::Avatar(AvatarCommand::AvatarImported {
        name: "broken.glb".to_owned(),
        result: Err("bad GLB container: too short".to_owned()),
    }));
    let notice = editor.model.notice().unwrap();
    assert!(notice.is_error);
    assert!(
        notice.text.contains("broken.glb") && notice.text.contains("too short"),
        "{}",
        notice.text
    );
    assert_eq!(editor.model.avatar().unwrap().name, "second.glb");
}

#[test]
fn the_outbox_carries_the_views_commands_out_in_order_and_says_the_most_they_changed() {
    // Catches: commands dropped or reordered (a select then a pin of that part), the outbox
    // not emptied (a command carried out twice), the change of the last command reported
    // instead of the largest.
    let mut editor = Clocked::new();
    editor.settle();
    let joint = editor.joint("l_elbow");
    let mut outbox = stance_model::Outbox::default();
    outbox.send(Command::View(ViewCommand::Select(Some(joint))));
    outbox.send(Command::Posture(PostureCommand::Mirror));
    outbox.send(Command::Posture(PostureCommand::PinSelected));
    outbox.send(Command::View(ViewCommand::Hover(None)));
    assert_eq!(
        editor.model.apply_outbox(&mut outbox),
        stance_model::Change::Posture
    );
    assert!(outbox.is_empty());
    assert_eq!(editor.model.selected_joint(), Some(joint));
    let pinned = editor
        .model
        .session()
        .tasks()
        .iter()
        .filter(|task| task.level == 1)
        .count();
    assert_eq!(
        editor.model.apply_outbox(&mut outbox),
        stance_model::Change::Nothing
    );
    // Undo takes back the pin, then the mirror: two edits, each carried out once.
    editor.apply(Command::History(HistoryCommand::Undo));
    let after_undo = editor
        .model
        .session()
        .tasks()
        .iter()
        .filter(|task| task.level == 1)
        .count();
    assert_eq!(after_undo + 1, pinned);
}

#[test]
fn the_openpose_map_sees_the_posed_body_through_the_camera_and_downloads_as_two_files() {
    // Catches: keypoints taken from another posture or skeleton than the session's, the
    // camera or size ignored, hidden keypoints kept when asked to leave them out, one of the
    // two files not handed to the host.
    use stance_render::{HiddenKeypoints, OrbitCamera};
    let host = MemoryHost::default();
    let downloads = host.inner.clone();
    let mut editor = Clocked::with_host(host);
    editor.settle_within(200);
    let elbow = editor.joint("l_elbow");
    let dof = editor.model.session().skeleton().joints()[elbow].dof_start;
    editor.apply(Command::Posture(PostureCommand::SetDof {
        dof,
        value: -1.2,
    }));
    editor.settle_within(200);
    let front = OrbitCamera {
        target_world: glam::Vec3::new(0.0, 1.0, 0.0),
        yaw: 0.0,
        pitch: 0.0,
        distance_m: 4.0,
        ..OrbitCamera::default()
    };
    let size = [640, 480];
    let pose = editor.model.openpose(&front, size, HiddenKeypoints::Keep);
    let person = pose.people[0];
    assert!(person.body.iter().all(Option::is_some));
    assert!(
        person
            .left_hand
            .iter()
            .chain(&person.right_hand)
            .all(Option::is_some)
    );
    let expected = |name| {
        front
            .project(
                editor.position(name).as_vec3(),
                glam::Vec2::new(640.0, 480.0),
            )
            .unwrap()
            .as_dvec2()
    };
    // COCO-18: 6 is the left elbow, 7 the left wrist (moved by the posture).
    assert!((person.body[6].unwrap() - expected("l_elbow")).length() < 1e-3);
    assert!((person.body[7].unwrap() - expected("l_radiocarpal")).length() < 1e-3);
    let mut side = front;
    side.set_view(stance_render::ViewPreset::Left);
    let hidden = editor.model.openpose(&side, size, HiddenKeypoints::Missing);
    assert_eq!(
        hidden.people[0].body[2], None,
        "the right shoulder behind the body"
    );
    assert!(
        hidden.people[0].body[5].is_some(),
        "the left shoulder in view"
    );

    editor.apply(Command::File(FileCommand::SaveOpenPose {
        png: vec![137, 80, 78, 71],
        json: pose.to_json(stance_render::KeypointUnits::Pixels),
        width: 640,
        height: 480,
    }));
    let names: Vec<String> = downloads
        .borrow()
        .binary_downloads
        .iter()
        .map(|(name, _)| name.clone())
        .collect();
    assert_eq!(names, ["stance-openpose.png", "stance-openpose.json"]);
    assert!(editor.model.notice().is_some_and(|notice| !notice.is_error));
}
