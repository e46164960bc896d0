//! Hand presets and finger curl through the editor's commands: one undo step each, mirrored,
//! kept by the solver, carried by links, refused with a reason on a body without fingers.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use crate::clocked;
use clocked::Clocked;
use stance_model::model::{AvatarCommand, FileCommand, HistoryCommand, PostureCommand};

use stance_document::link;
use stance_hanim::hands::{Finger, HandPreset};
use stance_hanim::{LevelOfArticulation, Side};
use stance_model::Command;
use stance_model::model::{HandCommand, Hands};

fn preset(hands: Hands, preset: HandPreset) -> Command {
    Command::Hands(HandCommand::Preset { hands, preset })
}

fn curl(hands: Hands, finger: Option<Finger>, curl: f64) -> Command {
    Command::Hands(HandCommand::Curl {
        hands,
        finger,
        curl,
    })
}

/// The finger DOF values of one hand in the current posture.
fn finger_values(editor: &Clocked, side: Side) -> Vec<(usize, f64)> {
    let session = editor.model.session();
    let rig = session.hand(side).unwrap();
    let values = session.posture().values();
    rig.fingers
        .iter()
        .flat_map(|finger| &finger.joints)
        .flat_map(|joint| {
            let skeleton = session.skeleton();
            skeleton.joints()[joint.joint].dof_range()
        })
        .map(|dof| (dof, values[dof]))
        .collect()
}

#[test]
fn a_fist_on_both_hands_is_one_undo_step_the_solver_keeps_and_undo_restores_exactly() {
    let mut editor = Clocked::new();
    editor.settle();
    assert!(editor.model.has_fingers());
    let before = editor.model.document();
    let steps = editor.model.history().undo_steps();
    editor.apply(preset(Hands::Both, HandPreset::Fist));
    assert_eq!(editor.model.history().undo_steps(), steps + 1);
    for hands in [Hands::Left, Hands::Right] {
        let closed = editor.model.hand_curl(hands, None).unwrap();
        assert!(closed > 0.8, "{} hand at {closed}", hands.name());
    }
    // The solver (feet, balance, the pull toward rest) leaves the fingers where they were put.
    let posed = finger_values(&editor, Side::Right);
    editor.settle();
    for ((dof, then), (_, now)) in posed.iter().zip(finger_values(&editor, Side::Right)) {
        assert!((then - now).abs() < 1e-3, "DOF {dof}: {then} became {now}");
    }
    editor.apply(Command::History(HistoryCommand::Undo));
    assert_eq!(editor.model.document(), before);
    editor.apply(Command::History(HistoryCommand::Redo));
    assert!(editor.model.hand_curl(Hands::Both, None).unwrap() > 0.8);
}

#[test]
fn a_curl_drag_is_one_undo_step_and_moves_only_that_finger_of_that_hand() {
    let mut editor = Clocked::new();
    editor.settle();
    let before = editor.model.document();
    let steps = editor.model.history().undo_steps();
    for step in 1..=20 {
        editor.apply(curl(
            Hands::Right,
            Some(Finger::Index),
            f64::from(step) / 20.0,
        ));
        editor.frames(1);
    }
    assert_eq!(editor.model.history().undo_steps(), steps + 1);
    assert!(
        (editor
            .model
            .hand_curl(Hands::Right, Some(Finger::Index))
            .unwrap()
            - 1.0)
            .abs()
            < 1e-3
    );
    for finger in [Finger::Thumb, Finger::Middle, Finger::Ring, Finger::Little] {
        assert!(editor.model.hand_curl(Hands::Right, Some(finger)).unwrap() < 1e-3);
    }
    assert!(editor.model.hand_curl(Hands::Left, None).unwrap() < 1e-3);
    // Another finger after the drag is another step.
    editor.frames(60);
    editor.apply(curl(Hands::Right, Some(Finger::Middle), 0.5));
    assert_eq!(editor.model.history().undo_steps(), steps + 2);
    editor.apply(Command::History(HistoryCommand::Undo));
    editor.apply(Command::History(HistoryCommand::Undo));
    assert_eq!(editor.model.document(), before);
}

#[test]
fn mirroring_the_posture_moves_a_fist_onto_the_other_hand() {
    let mut editor = Clocked::new();
    editor.apply(preset(Hands::Right, HandPreset::Fist));
    assert!(editor.model.hand_curl(Hands::Left, None).unwrap() < 1e-3);
    // The left fist as the left hand's own preset makes it.
    let session = editor.model.session();
    let expected = session
        .hand(Side::Left)
        .unwrap()
        .preset(session.skeleton(), HandPreset::Fist);
    editor.apply(Command::Posture(PostureCommand::Mirror));
    let values = editor.model.session().posture().values();
    for (dof, value) in expected {
        assert!(
            (values[dof] - value).abs() < 1e-9,
            "{}: {} mirrored, {value} from the preset",
            editor.model.session().skeleton().dof_name(dof),
            values[dof]
        );
    }
    assert!(editor.model.hand_curl(Hands::Right, None).unwrap() < 1e-3);
    // Both hands posed at once are mirror images: mirroring changes nothing in them. (Not
    // the pinch: its thumb meets the index by a search on each hand's own geometry, and the
    // default body's hands are not exact mirror images.)
    editor.apply(preset(Hands::Both, HandPreset::Grip));
    let left = finger_values(&editor, Side::Left);
    editor.apply(Command::Posture(PostureCommand::Mirror));
    for ((dof, before), (_, after)) in left.iter().zip(finger_values(&editor, Side::Left)) {
        assert!((before - after).abs() < 1e-9, "DOF {dof}");
    }
}

#[test]
fn a_body_without_fingers_poses_no_hand_and_says_why() {
    let mut editor = Clocked::new();
    editor.apply(Command::Avatar(AvatarCommand::SetLevelOfArticulation(
        LevelOfArticulation::Loa1,
    )));
    assert!(!editor.model.has_fingers());
    assert_eq!(editor.model.hand_curl(Hands::Both, None), None);
    let before = editor.model.document();
    let steps = editor.model.history().undo_steps();
    editor.apply(preset(Hands::Both, HandPreset::Fist));
    editor.apply(curl(Hands::Left, Some(Finger::Index), 1.0));
    assert_eq!(editor.model.document(), before);
    assert_eq!(editor.model.history().undo_steps(), steps);
    let notice = editor.model.notice().unwrap();
    assert!(notice.text.contains("no finger joints"), "{}", notice.text);
    // Back at LOA 3 the hands are there again.
    editor.apply(Command::Avatar(AvatarCommand::SetLevelOfArticulation(
        LevelOfArticulation::Loa3,
    )));
    assert!(editor.model.has_fingers());
}

#[test]
fn posed_fingers_travel_in_a_link() {
    let mut editor = Clocked::new();
    editor.apply(Command::Avatar(AvatarCommand::SetLevelOfArticulation(
        LevelOfArticulation::Loa3,
    )));
    editor.apply(preset(Hands::Left, HandPreset::Point));
    editor.apply(preset(Hands::Right, HandPreset::Grip));
    editor.apply(curl(Hands::Right, Some(Finger::Thumb), 0.3));
    let fragment = link::encode(&editor.model.document());
    let left = finger_values(&editor, Side::Left);
    let right = finger_values(&editor, Side::Right);
    let mut other = Clocked::new();
    other.apply(Command::Avatar(AvatarCommand::SetLevelOfArticulation(
        LevelOfArticulation::Loa3,
    )));
    other.apply(Command::File(FileCommand::OpenLink(fragment)));
    assert!(!other.model.notice().unwrap().is_error);
    let half_step = link::ROTATION_STEP_RAD / 2.0 + 1e-12;
    for (side, sent) in [(Side::Left, left), (Side::Right, right)] {
        let got = finger_values(&other, side);
        assert_eq!(got.len(), sent.len());
        for ((dof, sent), (_, got)) in sent.iter().zip(got) {
            assert!(
                (sent - got).abs() <= half_step,
                "DOF {dof}: {sent} sent, {got} opened"
            );
        }
    }
}
