//! Swapping the avatar keeps the document: the posture (which means the same pose on every
//! body) and the tasks carry over as one undoable edit, the history stays, and a task whose
//! joint the new body lacks is named; the new avatar shows the posture as the mannequin does.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use crate::clocked;
use clocked::Clocked;
use stance_model::model::{
    AvatarCommand, FileCommand, HistoryCommand, PostureCommand, TaskCommand,
};

use glam::{DQuat, DVec3};
use serde_json::{Value, json};
use stance_document::{TaskKindSpec, TaskSpec};
use stance_ik::{Axes, Frames};
use stance_model::Command;

/// The finger joint the T-pose avatar below lacks.
const FINGER: &str = "l_metacarpophalangeal_3";

/// The generated default avatar with its arms raised to a T-pose (the shoulder nodes carry
/// the quarter turn) and the left middle finger unnamed, as GLB: a body whose rest is not the
/// standard pose and which lacks a joint.
fn t_pose_glb() -> Vec<u8> {
    let glb = stance_asset::export_glb(&stance_asset::make_default_avatar().unwrap()).unwrap();
    let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let mut j: Value = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
    let nodes = j["nodes"].as_array_mut().unwrap();
    for node in nodes.iter_mut() {
        // Each node's transform is its rest (not the rest Stance wrote beside it).
        node.as_object_mut().unwrap().remove("extras");
        let name = node["name"].as_str().unwrap().to_owned();
        let turn = match name.as_str() {
            "l_shoulder" => Some(90f64),
            "r_shoulder" => Some(-90.0),
            _ => None,
        };
        if let Some(degrees) = turn {
            let q = DQuat::from_rotation_z(degrees.to_radians());
            node["rotation"] = json!([q.x, q.y, q.z, q.w]);
        }
        if name.starts_with("l_") && name.ends_with("_3") && name.contains("carp") {
            node["name"] = json!(format!("bone {name}").replace('_', " x"));
        }
    }
    let mut text = serde_json::to_vec(&j).unwrap();
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    let rest = &glb[20 + json_len..];
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&((20 + text.len() + rest.len()) as u32).to_le_bytes());
    out.extend_from_slice(&(text.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x4E4F_534Au32.to_le_bytes());
    out.extend_from_slice(&text);
    out.extend_from_slice(rest);
    out
}

/// The world direction (H-Anim frame) from joint `a` to `b` of the editor's current body.
fn bone(editor: &Clocked, a: &str, b: &str) -> DVec3 {
    (editor.position(b) - editor.position(a)).normalize()
}

#[test]
fn swapping_the_avatar_keeps_the_posture_and_tasks_as_one_undoable_edit() {
    let mut editor = Clocked::new();
    // The user's work: an arm reaching forward, the other bent, and a task on a finger.
    let set = |editor: &mut Clocked, joint: &str, k: usize, value: f64| {
        let j = editor.joint(joint);
        let dof = editor.model.session().skeleton().joints()[j].dof_start + k;
        editor.apply(Command::Posture(PostureCommand::SetDof { dof, value }));
    };
    set(&mut editor, "r_shoulder", 0, -1.3);
    set(&mut editor, "r_elbow", 0, -0.9);
    set(&mut editor, "l_shoulder", 2, 0.6);
    let mut tasks = editor.model.session().tasks().to_vec();
    tasks.push(TaskSpec::new(TaskKindSpec::Position {
        joint: FINGER.to_owned(),
        point: [0.0; 3],
        axes: Axes::XYZ,
        target: editor.position(FINGER).to_array(),
    }));
    editor.apply(Command::Task(TaskCommand::Set {
        kind: stance_model::history::EditKind::Command,
        tasks: tasks.clone(),
    }));
    editor.frames(1);
    let before = editor.model.document();
    let undo_steps = editor.model.history().undo_steps();
    let reach = bone(&editor, "r_shoulder", "r_elbow");
    let reach_on_mannequin = reach;
    let forearm = bone(&editor, "r_elbow", "r_radiocarpal");
    let lifted = bone(&editor, "l_shoulder", "l_elbow");

    editor.apply(Command::Avatar(AvatarCommand::LoadAvatar {
        name: "t-pose.glb".to_owned(),
        bytes: t_pose_glb(),
    }));
    let loaded = editor.model.avatar().expect("the avatar loads");
    assert_eq!(loaded.name, "t-pose.glb");
    let notice = editor.model.notice().unwrap().text.clone();
    assert!(
        notice.contains("Dropped") && notice.contains("metacarpophalangeal 3"),
        "the dropped task is named: {notice}"
    );
    // One undoable edit more; the earlier ones are kept.
    assert_eq!(editor.model.history().undo_steps(), undo_steps + 1);
    // The tasks but the finger's, and the posture, carried over.
    let after = editor.model.document();
    assert_eq!(after.tasks, tasks[..tasks.len() - 1]);
    for joint in ["r_shoulder", "r_elbow", "l_shoulder"] {
        let (a, b) = (&after.posture.joints[joint], &before.posture.joints[joint]);
        for dof in ["rx", "ry", "rz"] {
            let d = stance_ik::Dof::from_name(dof).unwrap();
            let (x, y) = (a.get(d).unwrap_or(0.0), b.get(d).unwrap_or(0.0));
            assert!((x - y).abs() < 1e-9, "{joint}.{dof}: {x} against {y}");
        }
    }
    // The new body's bones point where the mannequin's did.
    for (got, want, what) in [
        (
            bone(&editor, "r_shoulder", "r_elbow"),
            reach,
            "right upper arm",
        ),
        (
            bone(&editor, "r_elbow", "r_radiocarpal"),
            forearm,
            "right forearm",
        ),
        (
            bone(&editor, "l_shoulder", "l_elbow"),
            lifted,
            "left upper arm",
        ),
    ] {
        let angle = got.angle_between(want).to_degrees();
        assert!(angle < 2.0, "{what}: {angle} degrees off");
    }
    // The avatar, whose arms are out at rest, shows its skeleton's arm directions: its nodes
    // posed for the skinning, read in the H-Anim frame (after a frame of the solver).
    editor.frames(1);
    let (reach, forearm, lifted) = (
        bone(&editor, "r_shoulder", "r_elbow"),
        bone(&editor, "r_elbow", "r_radiocarpal"),
        bone(&editor, "l_shoulder", "l_elbow"),
    );
    let loaded = editor.model.avatar().unwrap();
    let humanoid = editor.model.session().humanoid();
    let locals = loaded
        .avatar
        .posed_locals(humanoid, editor.model.session().posture())
        .unwrap();
    let world = loaded.avatar.world_from_locals(&locals);
    let node = |name: &str| {
        let n = loaded
            .avatar
            .nodes
            .iter()
            .position(|n| n.name == name)
            .unwrap();
        loaded
            .avatar
            .hanim_from_file
            .transform_point3(world[n].w_axis.truncate())
    };
    let direction = |a: &str, b: &str| (node(b) - node(a)).normalize();
    for (got, want, what) in [
        (direction("r_shoulder", "r_elbow"), reach, "right upper arm"),
        (
            direction("r_elbow", "r_radiocarpal"),
            forearm,
            "right forearm",
        ),
        (direction("l_shoulder", "l_elbow"), lifted, "left upper arm"),
    ] {
        let angle = got.angle_between(want).to_degrees();
        assert!(angle < 2.0, "{what}: {angle} degrees off");
    }
    // And the elbow node sits where the skeleton's elbow is.
    let frames = Frames::new(
        editor.model.session().skeleton(),
        editor.model.session().posture(),
    );
    let elbow = editor.joint("r_elbow");
    assert!((frames.joint_position[elbow] - node("r_elbow")).length() < 1e-6);

    // Undo brings the mannequin back with the document as it was (the finger's task too);
    // the earlier steps are kept.
    editor.apply(Command::History(HistoryCommand::Undo));
    assert!(
        !editor.model.notice().is_some_and(|n| n.is_error),
        "{:?}",
        editor.model.notice()
    );
    assert!(editor.model.avatar().is_none(), "the mannequin is back");
    assert_eq!(editor.model.document().tasks, tasks);
    assert_eq!(editor.model.document().posture, before.posture);
    assert_eq!(editor.model.history().undo_steps(), undo_steps);
    assert!(bone(&editor, "r_shoulder", "r_elbow").angle_between(reach_on_mannequin) < 1e-9);
    // Redo brings the avatar back (its GPU model made again for the renderer), with the
    // document carried over.
    editor.apply(Command::History(HistoryCommand::Redo));
    let again = editor.model.avatar().expect("the avatar is back");
    assert_eq!(again.name, "t-pose.glb");
    assert!(again.mesh().is_some());
    assert_eq!(editor.model.document().tasks, tasks[..tasks.len() - 1]);
    assert_eq!(editor.model.history().undo_steps(), undo_steps + 1);

    // Back to the mannequin: the same document again, one more undoable edit, whose undo
    // brings the avatar back.
    let posture = editor.model.document().posture;
    editor.apply(Command::Avatar(AvatarCommand::UseMannequin));
    assert!(editor.model.avatar().is_none());
    assert_eq!(editor.model.history().undo_steps(), undo_steps + 2);
    let back = editor.model.document().posture;
    for joint in ["r_shoulder", "r_elbow", "l_shoulder"] {
        for (dof, value) in posture.joints[joint].iter() {
            let now = back.joints[joint].get(dof).unwrap();
            assert!(
                (now - value).abs() < 1e-9,
                "{joint}.{dof:?}: {now} against {value}"
            );
        }
    }
    editor.apply(Command::History(HistoryCommand::Undo));
    assert_eq!(
        editor.model.avatar().map(|a| a.name.as_str()),
        Some("t-pose.glb")
    );
}

/// A document saved on this avatar before a posture meant the same pose on every body (no
/// `rest`: its values relative to the avatar's own T-pose) opens in the pose it was saved
/// with, and the notice says it was converted.
#[test]
fn an_old_document_made_on_the_avatar_opens_as_it_was_saved() {
    let mut editor = Clocked::new();
    let url = "https://example.org/avatars/t-pose.glb";
    editor.apply(Command::Avatar(AvatarCommand::LoadAvatar {
        name: url.to_owned(),
        bytes: t_pose_glb(),
    }));
    assert!(editor.model.avatar().is_some());
    // Saved then: the left arm lowered from the T-pose by a quarter turn about the body's
    // front axis (straight down), the right arm as it was at rest (out to the side).
    let old = format!(
        r#"{{"avatar": {{"url": "{url}"}},
            "posture": {{"l_shoulder": {{"rz": -1.5707963267948966}}}}}}"#
    );
    editor.apply(Command::File(FileCommand::OpenFile {
        name: "old.json".to_owned(),
        bytes: old.into_bytes(),
    }));
    let notice = editor.model.notice().unwrap().text.clone();
    assert!(notice.contains("converted"), "{notice}");
    // By hand: the file's arms are the default centres' arms turned a quarter about z (out to
    // the sides); the old values turn the left one back, the right one stays out.
    let centre = |name: &str| stance_hanim::scenarios::hanim_centre(name).unwrap();
    let arm = |side: &str| {
        (centre(&format!("{side}_elbow")) - centre(&format!("{side}_shoulder"))).normalize()
    };
    let quarter = |degrees: f64| DQuat::from_rotation_z(degrees.to_radians());
    let left_then = quarter(-90.0) * (quarter(90.0) * arm("l"));
    let right_then = quarter(-90.0) * arm("r");
    for (side, then) in [("l", left_then), ("r", right_then)] {
        let now = bone(
            &editor,
            &format!("{side}_shoulder"),
            &format!("{side}_elbow"),
        );
        let angle = now.angle_between(then).to_degrees();
        assert!(angle < 1.0, "{side} upper arm {angle} degrees off");
    }
    assert!(right_then.x < -0.9, "the right arm is out to the side");
    // Saved again, the document says its values are relative to the standard pose.
    let saved = editor.model.document();
    assert_eq!(saved.rest, stance_document::PostureRest::Standard);
}

/// A scene whose two characters name the same avatar: the selected one's is fetched, the other
/// waits on the mannequin and still names it (saving loses nothing), and once the avatar has
/// loaded both stand on it, each in its own posture.
#[test]
fn characters_waiting_for_the_avatar_get_it_once_it_has_loaded() {
    let mut editor = Clocked::new();
    let url = "https://example.org/avatars/t-pose.glb";
    let scene = format!(
        r#"{{"characters": [
            {{"name": "Ann", "avatar": {{"url": "{url}"}}, "rest": "standard", "posture": {{"l_elbow": {{"rx": -0.7}}}}}},
            {{"name": "Bo", "placement": {{"position": [0.8, 0, 0]}}, "avatar": {{"url": "{url}"}},
              "rest": "standard", "posture": {{"r_elbow": {{"rx": -0.4}}}}}}],
          "selected": 0}}"#
    );
    editor.apply(Command::File(FileCommand::OpenFile {
        name: "scene.json".to_owned(),
        bytes: scene.into_bytes(),
    }));
    let names = |editor: &Clocked| -> Vec<String> {
        editor
            .model
            .scene()
            .characters
            .iter()
            .map(|c| format!("{:?}", c.document.avatar))
            .collect()
    };
    // Before the avatar arrives: nobody on it, both still name it.
    assert!(editor.model.characters().all(|(c, _)| c.avatar().is_none()));
    assert!(
        names(&editor).iter().all(|n| n.contains(url)),
        "{:?}",
        names(&editor)
    );
    editor.apply(Command::Avatar(AvatarCommand::LoadAvatar {
        name: url.to_owned(),
        bytes: t_pose_glb(),
    }));
    editor.settle();
    assert!(
        editor.model.characters().all(|(c, _)| c.avatar().is_some()),
        "{:?}",
        editor.model.notice()
    );
    assert!(names(&editor).iter().all(|n| n.contains(url)));
    // Each kept its own posture.
    let dof = |editor: &Clocked, index: usize, joint: &str| {
        let (character, _) = editor.model.characters().nth(index).unwrap();
        let session = character.session();
        let j = session.skeleton().joint_index(joint).unwrap();
        session.posture().values()[session.skeleton().joints()[j].dof_start]
    };
    assert!((dof(&editor, 0, "l_elbow") + 0.7).abs() < 1e-3);
    assert!((dof(&editor, 1, "r_elbow") + 0.4).abs() < 1e-3);
}

/// A scene saved on the avatar before postures meant the same pose on every body (no `rest`),
/// opened while that avatar is loaded: every character is converted as a single document is
/// (each one's left upper arm as `an_old_document_made_on_the_avatar_opens_as_it_was_saved`
/// finds it), not only the selected one.
#[test]
fn an_old_scene_on_the_loaded_avatar_converts_every_character() {
    let mut editor = Clocked::new();
    let url = "https://example.org/avatars/t-pose.glb";
    editor.apply(Command::Avatar(AvatarCommand::LoadAvatar {
        name: url.to_owned(),
        bytes: t_pose_glb(),
    }));
    let old = format!(
        r#"{{"avatar": {{"url": "{url}"}}, "posture": {{"l_shoulder": {{"rz": -1.5707963267948966}}}}}}"#
    );
    let mut single = Clocked::new();
    single.apply(Command::Avatar(AvatarCommand::LoadAvatar {
        name: url.to_owned(),
        bytes: t_pose_glb(),
    }));
    single.apply(Command::File(FileCommand::OpenFile {
        name: "old.json".to_owned(),
        bytes: old.clone().into_bytes(),
    }));
    let want = bone(&single, "l_shoulder", "l_elbow");
    let scene = format!(
        r#"{{"characters": [{old_a}, {old_b}], "selected": 1}}"#,
        old_a = old.replacen('{', r#"{"name": "Ann", "#, 1),
        old_b = old.replacen(
            '{',
            r#"{"name": "Bo", "placement": {"position": [0.8, 0, 0]}, "#,
            1
        ),
    );
    editor.apply(Command::File(FileCommand::OpenFile {
        name: "old-scene.json".to_owned(),
        bytes: scene.into_bytes(),
    }));
    for index in [1, 0] {
        let id = editor.model.characters().nth(index).unwrap().0.id();
        editor.apply(Command::Scene(stance_model::model::SceneCommand::Select(
            id,
        )));
        let angle = bone(&editor, "l_shoulder", "l_elbow")
            .angle_between(want)
            .to_degrees();
        assert!(
            angle < 1.0,
            "character {index}'s upper arm {angle} degrees off"
        );
    }
}
