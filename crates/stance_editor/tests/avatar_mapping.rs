//! A user's avatar through the editor (egui_kittest): the mapping window corrects which
//! H-Anim joint a joint of the file drives and the skeleton follows; the posed avatar is
//! exported as GLB and reads back in the same posture.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use egui::Modifiers;
use egui::accesskit::Role;
use egui_kittest::Harness;
use egui_kittest::kittest::{NodeT, Queryable};
use glam::DVec3;
use stance_asset::{LoadOptions, export_glb, load_avatar, make_default_avatar};
use stance_document::TaskSpec;
use stance_editor::model::{AvatarCommand, FileCommand};
use stance_editor::{Command, MemoryHost, NoHostHooks, StanceApp};
use stance_hanim::{LevelOfArticulation, SkeletonOptions};
use stance_ik::Frames;

use crate::common;
use common::{drag_right_forearm_up, harness_sized, release_at, settle, state};

/// A small skinned humanoid with H-Anim joint names (the generated default avatar), as GLB.
fn avatar_bytes() -> Vec<u8> {
    export_glb(&make_default_avatar().unwrap()).unwrap()
}

fn harness_with_avatar(host: &MemoryHost) -> Harness<'static, StanceApp> {
    let mut app = StanceApp::without_gpu(Box::new(host.clone())).unwrap();
    app.apply(Command::Avatar(AvatarCommand::LoadAvatar {
        name: "figure.glb".to_owned(),
        bytes: avatar_bytes(),
    }));
    assert!(app.model().avatar().is_some(), "{:?}", app.model().notice());
    harness_sized(app, egui::vec2(1280.0, 800.0))
}

fn notice(harness: &Harness<'static, StanceApp>) -> String {
    harness
        .state()
        .model()
        .notice()
        .map(|notice| notice.text.clone())
        .unwrap_or_default()
}

/// The node (joint of the file) that drives an H-Anim joint of the session's skeleton.
fn source_node(harness: &Harness<'static, StanceApp>, hanim: &str) -> Option<String> {
    let app = harness.state();
    let humanoid = app.model().session().humanoid();
    let index = humanoid.skeleton.joint_index(hanim)?;
    let source = humanoid.joints[index].source?;
    Some(app.model().avatar()?.avatar.nodes[source].name.clone())
}

fn type_filter(harness: &mut Harness<'static, StanceApp>, text: &str) {
    let field = harness.get_by_role_and_label(Role::TextInput, "Filter joints");
    field.focus();
    harness.run_steps(1);
    harness.key_press_modifiers(Modifiers::COMMAND, egui::Key::A);
    harness
        .get_by_role_and_label(Role::TextInput, "Filter joints")
        .type_text(text);
    // The grid's columns fit the rows left over the next frames.
    harness.run_steps(6);
}

/// Opens the H-Anim joint box of a row (a joint of the file) and picks `item`.
fn pick(harness: &mut Harness<'static, StanceApp>, row: &str, item: &str) {
    harness.get_by_role_and_label(Role::ComboBox, row).click();
    harness.run_steps(2);
    // The suggestions come first in the list, where the eye (and the pointer) is.
    harness.get_all_by_label(item).next().unwrap().click();
    harness.run_steps(2);
    assert!(
        harness.query_by_label(item).is_none(),
        "the list closed after the pick"
    );
}

fn is_enabled(harness: &Harness<'static, StanceApp>, label: &str) -> bool {
    !harness.get_by_label(label).accesskit_node().is_disabled()
}

#[test]
fn swapping_the_elbows_in_the_mapping_window_rebuilds_the_skeleton() {
    let host = MemoryHost::default();
    let mut harness = harness_with_avatar(&host);
    let joints_before = harness.state().model().session().skeleton().joint_count();
    let tasks_before = harness.state().model().session().tasks().to_vec();
    let left_elbow_x = harness
        .state()
        .model()
        .session()
        .joint_position("l_elbow")
        .unwrap()
        .x;
    assert!(left_elbow_x > 0.1, "the left elbow is on the body's left");
    assert_eq!(source_node(&harness, "l_elbow").as_deref(), Some("l_elbow"));

    harness.get_by_label("Avatar mapping…").click();
    harness.run_steps(2);
    assert!(state(&harness)["buttons"]["mapping_open"].is_array());
    type_filter(&mut harness, "elbow");

    // Half a swap leaves the left elbow without a joint: applying is refused until fixed.
    pick(&mut harness, "l_elbow", "r_elbow · right elbow");
    assert!(
        harness
            .query_by_label_contains("Every humanoid needs these joints: l_elbow")
            .is_some(),
        "the window says which joint is missing"
    );
    assert!(!is_enabled(&harness, "Apply"));
    assert_eq!(
        source_node(&harness, "l_elbow").as_deref(),
        Some("l_elbow"),
        "nothing changes before Apply"
    );
    pick(&mut harness, "r_elbow", "l_elbow · left elbow");
    assert!(is_enabled(&harness, "Apply"));
    harness.get_by_label("Apply").click();
    settle(&mut harness);

    assert_eq!(source_node(&harness, "l_elbow").as_deref(), Some("r_elbow"));
    assert_eq!(source_node(&harness, "r_elbow").as_deref(), Some("l_elbow"));
    // The rebuilt skeleton's left elbow is the node on the other arm (its own rest); the
    // skeleton's rest is still the standard pose, the elbow below its shoulder.
    let session = harness.state().model().session();
    let skeleton = session.skeleton();
    let elbow = skeleton.joint_index("l_elbow").unwrap();
    let swapped_x = session.humanoid().joints[elbow].own_rest.x;
    assert!(
        swapped_x < -0.1,
        "the left elbow now sits on the other arm: x = {swapped_x}"
    );
    let rest = stance_ik::Frames::new(skeleton, &stance_ik::Posture::rest(skeleton));
    assert!(rest.joint_position[elbow].x > 0.1);
    assert_eq!(session.skeleton().joint_count(), joints_before);
    assert_eq!(
        session.tasks().len(),
        tasks_before.len(),
        "the feet, balance and comfort tasks still fit"
    );
    let text = notice(&harness);
    assert!(text.contains("Mapping corrected"), "{text}");
    assert!(text.contains("Ctrl+Z does not undo"), "{text}");
    assert!(
        !harness.state().model().notice().unwrap().is_error,
        "{text} is no error"
    );

    // Unmapping a joint takes it out of the skeleton, and the task on it goes with it.
    let mut document = harness.state().model().session().document();
    let collarbone = harness
        .state()
        .model()
        .session()
        .joint_position("l_sternoclavicular")
        .unwrap();
    document
        .tasks
        .push(TaskSpec::pin("l_sternoclavicular", collarbone.to_array()));
    harness
        .state_mut()
        .apply(Command::File(FileCommand::OpenFile {
            name: "pose.json".to_owned(),
            bytes: document.to_json(false).as_bytes().to_vec(),
        }));
    settle(&mut harness);
    assert_eq!(
        harness.state().model().session().tasks().len(),
        tasks_before.len() + 1
    );
    type_filter(&mut harness, "sternoclavicular");
    pick(
        &mut harness,
        "l_sternoclavicular",
        "none (not an H-Anim joint)",
    );
    harness.get_by_label("Apply").click();
    settle(&mut harness);
    let session = harness.state().model().session();
    assert!(
        session
            .skeleton()
            .joint_index("l_sternoclavicular")
            .is_none()
    );
    assert_eq!(session.skeleton().joint_count(), joints_before - 1);
    assert!(session.skeleton().joint_index("l_shoulder").is_some());
    assert_eq!(
        session.tasks(),
        tasks_before.as_slice(),
        "the task on the unmapped joint was dropped, the others kept"
    );
    let text = notice(&harness);
    assert!(
        text.contains("Dropped") && text.contains("left collarbone position"),
        "{text}"
    );

    // The corrections stay with this avatar for the session: back to the mannequin, then
    // the same file again.
    harness
        .state_mut()
        .apply(Command::Avatar(AvatarCommand::UseMannequin));
    harness.run_steps(2);
    harness
        .state_mut()
        .apply(Command::Avatar(AvatarCommand::LoadAvatar {
            name: "figure.glb".to_owned(),
            bytes: avatar_bytes(),
        }));
    settle(&mut harness);
    assert!(
        notice(&harness).contains("made again"),
        "{}",
        notice(&harness)
    );
    assert_eq!(source_node(&harness, "l_elbow").as_deref(), Some("r_elbow"));
    assert!(
        harness
            .state()
            .model()
            .session()
            .skeleton()
            .joint_index("l_sternoclavicular")
            .is_none()
    );

    // Revert undoes the last correction only.
    harness.get_by_label("Avatar mapping…").click();
    harness.run_steps(2);
    harness.get_by_label("Revert last correction").click();
    settle(&mut harness);
    assert!(
        harness
            .state()
            .model()
            .session()
            .skeleton()
            .joint_index("l_sternoclavicular")
            .is_some(),
        "{}",
        notice(&harness)
    );
    assert_eq!(source_node(&harness, "l_elbow").as_deref(), Some("r_elbow"));
}

#[test]
fn the_posed_avatar_is_exported_as_glb_that_reads_back_in_the_same_posture() {
    let host = MemoryHost::default();
    let mut harness = harness_with_avatar(&host);

    // Pull the right forearm up and out.
    let (_, end) = drag_right_forearm_up(&mut harness);
    assert_eq!(state(&harness)["pulling"], true, "the drag grabbed the arm");
    harness.run_steps(20);
    release_at(&mut harness, end);
    settle(&mut harness);

    harness.get_by_label("File").click();
    harness.run_steps(2);
    harness.get_by_label("Export posed avatar (GLB)…").click();
    harness.run_steps(2);
    let downloads = host.inner.borrow().binary_downloads.clone();
    assert_eq!(downloads.len(), 1, "{}", notice(&harness));
    let (name, bytes) = &downloads[0];
    assert_eq!(name, "figure-posed.glb");
    assert!(notice(&harness).contains("figure-posed.glb"));

    let again = load_avatar(bytes, &LoadOptions::default()).unwrap();
    let body = again
        .skeleton(&SkeletonOptions {
            loa: LevelOfArticulation::Loa2,
            ..SkeletonOptions::default()
        })
        .unwrap();
    let read_back = again.current_posture(&body).unwrap();
    let exported = Frames::new(&body.skeleton, &read_back);
    let session = harness.state().model().session();
    let posed = session.frames();
    let mut largest_turn: f64 = 0.0;
    for (index, joint) in session.skeleton().joints().iter().enumerate() {
        let other = body.skeleton.joint_index(&joint.name).unwrap();
        let ours = posed.rotation(index);
        largest_turn = largest_turn.max(ours.angle_between(glam::DQuat::IDENTITY));
        let error = exported.rotation(other).angle_between(ours);
        assert!(
            error < 1e-5,
            "{}: the exported rotation is {error} rad off",
            joint.name
        );
    }
    assert!(
        largest_turn > 0.2,
        "the pull turned the arm ({largest_turn} rad)"
    );
    let hand: DVec3 = exported.joint_position[body.skeleton.joint_index("r_radiocarpal").unwrap()];
    let ours = session.joint_position("r_radiocarpal").unwrap();
    assert!((hand - ours).length() < 1e-4, "{hand} vs {ours}");
}

#[test]
fn an_export_the_host_cannot_download_says_why() {
    let mut app = StanceApp::without_gpu(Box::new(NoHostHooks)).unwrap();
    // The mannequin exports as its figure (the scene's file); the host cannot take it.
    app.apply(Command::Avatar(AvatarCommand::ExportPosedAvatar));
    let notice = app.model().notice().unwrap();
    assert!(notice.is_error, "{}", notice.text);
    assert!(
        notice.text.contains("stance-scene.glb") && notice.text.contains("cannot download"),
        "{}",
        notice.text
    );
    app.apply(Command::Avatar(AvatarCommand::LoadAvatar {
        name: "figure.glb".to_owned(),
        bytes: avatar_bytes(),
    }));
    app.apply(Command::Avatar(AvatarCommand::ExportPosedAvatar));
    let notice = app.model().notice().unwrap();
    assert!(notice.is_error, "{}", notice.text);
    assert!(notice.text.contains("cannot download"), "{}", notice.text);
}
