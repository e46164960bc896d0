//! Two characters hand in hand, driven by commands alone: a task between them poses both
//! together (each keeping its feet pinned), a pull on one drags the other's hand along, undo
//! takes the task away, removing a character removes its tasks, and the scene's link carries
//! the task.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use glam::DVec3;
use stance_document::Placement;
use stance_model::model::{GestureCommand, HistoryCommand, SceneCommand};
use stance_model::{Command, EditorModel};

use crate::clocked::Clocked;

/// Joint `name` of the character at scene index `index`, in the scene (its placement applied).
fn in_scene(model: &EditorModel, index: usize, name: &str) -> DVec3 {
    let (character, _) = model.characters().nth(index).unwrap();
    let session = character.session();
    let joint = session.skeleton().joint_index(name).unwrap();
    character
        .placement()
        .scene_from_character()
        .transform_point3(session.frames().joint_position[joint])
}

/// Joint `name` of the character at `index` in its own frame.
fn own(model: &EditorModel, index: usize, name: &str) -> DVec3 {
    let (character, _) = model.characters().nth(index).unwrap();
    let session = character.session();
    session.frames().joint_position[session.skeleton().joint_index(name).unwrap()]
}

/// Two characters facing each other 0.7 m apart (the first looking along +X, the second
/// along -X), the second selected.
fn facing() -> Clocked {
    let mut editor = Clocked::new();
    let first = editor.model.character().id();
    editor.apply(Command::Scene(SceneCommand::Place(
        first,
        Placement {
            position: [-0.35, 0.0, 0.0],
            yaw_degrees: 90.0,
        },
    )));
    editor.apply(Command::Scene(SceneCommand::Add));
    let second = editor.model.character().id();
    editor.apply(Command::Scene(SceneCommand::Place(
        second,
        Placement {
            position: [0.35, 0.0, 0.0],
            yaw_degrees: -90.0,
        },
    )));
    editor.settle();
    editor
}

/// *Hold hands with* the first character: face to face, the hands on the same side of the
/// space between them meet, one's left and the other's right (`hand`: the second's).
fn hold_hands(editor: &mut Clocked) -> (&'static str, &'static str) {
    let first = editor.model.characters().next().unwrap().0.id();
    let new = editor.model.hands_toward(first).unwrap();
    let (left, right) = (editor.joint("l_radiocarpal"), editor.joint("r_radiocarpal"));
    let pair = match (new.joint, new.other_joint.as_str()) {
        (j, "r_radiocarpal") if j == left => ("l_radiocarpal", "r_radiocarpal"),
        (j, "l_radiocarpal") if j == right => ("r_radiocarpal", "l_radiocarpal"),
        _ => panic!("not a left hand in a right one: {new:?}"),
    };
    assert_eq!(new.other, first);
    editor.apply(Command::Scene(SceneCommand::AddBetween(new)));
    pair
}

#[test]
fn a_task_between_two_characters_poses_both_and_each_keeps_its_feet() {
    // Catches: the task ignored (each character solved alone), only the selected one moved
    // (its arm stretched out to the other's hand at rest), a placement missing from the
    // joined solve, the feet given up for the hands.
    let mut editor = facing();
    let feet: Vec<(DVec3, DVec3)> = (0..2)
        .map(|i| {
            (
                own(&editor.model, i, "l_talocrural"),
                own(&editor.model, i, "r_talocrural"),
            )
        })
        .collect();
    let (mine, theirs) = hold_hands(&mut editor);
    let rest_hand = in_scene(&editor.model, 0, theirs);
    assert_eq!(editor.model.between_tasks().len(), 1);
    assert_eq!(editor.model.joined_with_selected(), vec![0, 1]);
    editor.settle();
    let apart = (in_scene(&editor.model, 0, theirs) - in_scene(&editor.model, 1, mine)).length();
    assert!(apart < 1e-3, "the hands are {apart} m apart");
    // The other character's hand came to meet it (not only the selected one's).
    let moved = (in_scene(&editor.model, 0, theirs) - rest_hand).length();
    assert!(moved > 0.05, "the first character's hand moved {moved} m");
    for (i, (l, r)) in feet.iter().enumerate() {
        assert!((own(&editor.model, i, "l_talocrural") - *l).length() < 1e-3);
        assert!((own(&editor.model, i, "r_talocrural") - *r).length() < 1e-3);
    }
    // A pull on the selected character's chest: the hands stay together, the feet pinned.
    let chest = editor.joint("vl1");
    let start = own(&editor.model, 1, "vl1");
    editor.apply(Command::Gesture(GestureCommand::BeginPull {
        joint: chest,
        point_world: start,
    }));
    for k in 1..=10 {
        let target = start + DVec3::new(0.0, -0.01 * k as f64, 0.015 * k as f64);
        editor.apply(Command::Gesture(GestureCommand::MoveGrab {
            target_world: target,
        }));
        editor.frames(3);
    }
    editor.apply(Command::Gesture(GestureCommand::EndGesture));
    editor.settle();
    let apart = (in_scene(&editor.model, 0, theirs) - in_scene(&editor.model, 1, mine)).length();
    assert!(apart < 1e-3, "after the pull the hands are {apart} m apart");
    for (i, (l, _)) in feet.iter().enumerate() {
        assert!((own(&editor.model, i, "l_talocrural") - *l).length() < 1e-3);
    }
}

#[test]
fn the_task_between_characters_is_undone_removed_with_a_character_and_shared() {
    let mut editor = facing();
    let (mine, theirs) = hold_hands(&mut editor);
    editor.settle();
    // The link carries it; another editor opens it and holds the hands together.
    let link = editor.model.share_link();
    let mut other = Clocked::new();
    other.model.open_startup(Some(&link.url));
    other.settle();
    assert_eq!(other.model.between_tasks(), editor.model.between_tasks());
    let apart = (in_scene(&other.model, 0, theirs) - in_scene(&other.model, 1, mine)).length();
    assert!(apart < 1e-3, "opened from the link: {apart} m apart");
    // Shared again, the same link.
    assert_eq!(other.model.share_link().url, link.url);
    // Undo takes the task away; redo brings it back.
    editor.apply(Command::History(HistoryCommand::Undo));
    assert!(editor.model.between_tasks().is_empty());
    editor.apply(Command::History(HistoryCommand::Redo));
    assert_eq!(editor.model.between_tasks().len(), 1);
    // Removing a character removes the tasks that name it; undo brings both back.
    let first = editor.model.characters().next().unwrap().0.id();
    editor.apply(Command::Scene(SceneCommand::Remove(first)));
    assert!(editor.model.between_tasks().is_empty());
    editor.apply(Command::History(HistoryCommand::Undo));
    assert_eq!(editor.model.between_tasks().len(), 1);
    assert_eq!(editor.model.character_count(), 2);
    // Removed by index.
    editor.apply(Command::Scene(SceneCommand::RemoveBetween(0)));
    assert!(editor.model.between_tasks().is_empty());
    assert_eq!(editor.model.joined_with_selected().len(), 1);
}
