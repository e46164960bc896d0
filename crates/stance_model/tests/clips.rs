//! Clips in and out of the editor, driven by commands: a dropped BVH goes on the timeline
//! (a broken one says where and keeps what was there), the retargeting settings take
//! effect, the body recorded frame by frame becomes a clip, and the timeline is exported as
//! BVH and as a GLB animation on the avatar that reads back with the same frames.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use glam::DQuat;
use stance_asset::{LoadOptions, export_glb, load_avatar, make_default_avatar};
use stance_ik::Frames;
use stance_model::model::{AnimationFormat, MotionCommand};
use stance_model::model::{AvatarCommand, FileCommand, PostureCommand};
use stance_model::{Command, EditorModel, MemoryHost};
use stance_motion::{BvhLimits, ContactSettings, RestMatch, RetargetOptions, read_bvh};

use crate::clocked::{editor_on, open};

const WALK: &[u8] = include_bytes!("../../../tests/fixtures/motion/walk.bvh");

fn editor() -> (EditorModel, MemoryHost, f64) {
    let host = MemoryHost::default();
    (editor_on(&host), host, 0.0)
}

#[test]
fn a_dropped_bvh_goes_on_the_timeline_and_a_broken_one_keeps_it() {
    let (mut model, _, _) = editor();
    open(&mut model, "walk.bvh", WALK);
    assert_eq!(model.frame_count(), 260);
    assert!((model.frame_time() - 0.0083333).abs() < 1e-12);
    assert_eq!(model.timeline().clip_name(), Some("walk"));
    assert!(model.timeline().contacts().len() >= 4);
    let opened = model.notice().unwrap().text.clone();
    assert!(
        opened.contains("contacts held: ")
            && opened.contains(" heel")
            && !opened.contains("the clip moves"),
        "{opened}"
    );
    // A speed threshold no foot meets: the walk moves, and the notice says which feet got no
    // contact and which thresholds to change.
    model.apply(Command::Motion(MotionCommand::SetRetargetOptions(
        Box::new(RetargetOptions {
            contacts: Some(ContactSettings {
                speed: 0.001,
                ..Default::default()
            }),
            ..Default::default()
        }),
    )));
    let text = model.notice().unwrap().text.clone();
    for words in [
        "the left foot got no contact",
        "the right foot got no contact",
        "speed (0.00 m/s",
    ] {
        assert!(text.contains(words), "{words}: {text}");
    }
    model.apply(Command::Motion(MotionCommand::SetRetargetOptions(
        Box::default(),
    )));
    let broken = String::from_utf8_lossy(WALK).replacen("CHANNELS 3", "CHANNELS 4", 1);
    open(&mut model, "broken.bvh", broken.as_bytes());
    let notice = model.notice().unwrap();
    assert!(notice.is_error);
    assert!(
        notice.text.contains("broken.bvh") && notice.text.contains("line 9"),
        "{}",
        notice.text
    );
    assert_eq!(model.timeline().clip_name(), Some("walk"));
    assert_eq!(model.frame_count(), 260);
}

#[test]
fn retargeting_settings_change_the_contacts_and_the_rest_match() {
    let (mut model, _, _) = editor();
    open(&mut model, "walk.bvh", WALK);
    let held = model.timeline().contacts().len();
    let set = |model: &mut EditorModel, options: RetargetOptions| {
        model.apply(Command::Motion(MotionCommand::SetRetargetOptions(
            Box::new(options),
        )));
    };
    set(
        &mut model,
        RetargetOptions {
            contacts: None,
            ..Default::default()
        },
    );
    assert_eq!(model.timeline().contacts().len(), 0);
    // A stricter speed threshold finds fewer (or shorter) contacts.
    let strict = ContactSettings {
        speed: 0.05,
        ..Default::default()
    };
    set(
        &mut model,
        RetargetOptions {
            contacts: Some(strict),
            ..Default::default()
        },
    );
    let frames = |model: &EditorModel| -> usize {
        model
            .timeline()
            .contacts()
            .iter()
            .map(|c| c.end + 1 - c.start)
            .sum()
    };
    assert!(model.timeline().contacts().len() <= held);
    let strict_frames = frames(&model);
    set(&mut model, RetargetOptions::default());
    assert!(frames(&model) > strict_frames);
    // The clip's first frame as the rest: frame 0 is the rest posture (root aside).
    set(
        &mut model,
        RetargetOptions {
            rest_match: RestMatch::FirstFrame,
            contacts: None,
            ..Default::default()
        },
    );
    let skeleton = model.session().skeleton().clone();
    let first = model.frame_posture(0);
    for j in 1..skeleton.joint_count() {
        let angle = first
            .local_rotation(&skeleton, j)
            .angle_between(DQuat::IDENTITY);
        assert!(angle < 1e-6, "{}: {angle}", skeleton.joints()[j].name);
    }
}

#[test]
fn the_body_recorded_frame_by_frame_becomes_a_clip() {
    let (mut model, _, _) = editor();
    let elbow = model.session().skeleton().joint_index("l_elbow").unwrap();
    let dof = model.session().skeleton().joints()[elbow].dof_start;
    model.apply(Command::Motion(MotionCommand::Record(true)));
    assert!(model.timeline().is_recording());
    // One second at an irregular display rate, the elbow bending at 1 rad/s.
    let mut t: f64 = 0.0;
    while t < 1.0 {
        t += if ((t * 100.0) as usize).is_multiple_of(2) {
            0.013
        } else {
            0.021
        };
        let now = t.min(1.0);
        model.apply(Command::Posture(PostureCommand::SetDof {
            dof,
            value: -now,
        }));
        model.step(now, None);
    }
    model.apply(Command::Motion(MotionCommand::Record(false)));
    assert!(!model.timeline().is_recording());
    assert_eq!(model.timeline().clip_name(), Some("recording"));
    // From the first captured frame to the last, at 30 fps.
    let count = model.frame_count();
    assert!((29..=31).contains(&count), "{count}");
    let skeleton = model.session().skeleton().clone();
    let bend = |f: usize| {
        model
            .frame_posture(f)
            .local_rotation(&skeleton, elbow)
            .angle_between(DQuat::IDENTITY)
    };
    // The bend grows by 1/30 rad per frame, as it did in real time.
    for f in 1..count - 1 {
        let step = bend(f + 1) - bend(f);
        assert!((step - 1.0 / 30.0).abs() < 2e-3, "frame {f}: {step}");
    }
}

#[test]
fn the_timeline_exports_as_bvh_and_as_a_glb_animation_on_the_avatar() {
    let (mut model, host, _) = editor();
    let glb = export_glb(&make_default_avatar().unwrap()).unwrap();
    model.apply(Command::Avatar(AvatarCommand::LoadAvatar {
        name: "default.glb".into(),
        bytes: glb,
    }));
    open(&mut model, "walk.bvh", WALK);
    let baked = model.baked_postures();
    assert_eq!(baked.len(), 260);
    model.apply(Command::File(FileCommand::ExportAnimation(
        AnimationFormat::Bvh,
    )));
    let (name, text) = host.inner.borrow().downloads.last().cloned().unwrap();
    assert_eq!(name, "walk.bvh");
    let clip = read_bvh(text.as_bytes(), "walk", &BvhLimits::default()).unwrap();
    assert_eq!(clip.frame_count(), 260);
    assert_eq!(clip.frame_time, model.frame_time());
    // The BVH's joints are where the baked postures put them.
    let skeleton = model.session().skeleton().clone();
    for f in [0, 130, 259] {
        let frames = Frames::new(&skeleton, &baked[f]);
        let world = clip.world(&clip.frames[f]);
        for name in ["l_talocrural", "r_radiocarpal", "skullbase"] {
            let a = frames.joint_position[skeleton.joint_index(name).unwrap()];
            let b = world[clip.joint_of(name).unwrap()].1;
            assert!((a - b).length() < 1e-5, "{name} frame {f}: {a} {b}");
        }
    }
    model.apply(Command::File(FileCommand::ExportAnimation(
        AnimationFormat::Glb,
    )));
    let (name, bytes) = host
        .inner
        .borrow()
        .binary_downloads
        .last()
        .cloned()
        .unwrap();
    assert_eq!(name, "walk.glb");
    let avatar = load_avatar(&bytes, &LoadOptions::default()).unwrap();
    assert_eq!(avatar.animations.len(), 1);
    let duration = avatar.animations[0].duration;
    assert!(
        (duration - 259.0 * model.frame_time()).abs() < 1e-4,
        "{duration}"
    );
    // Its own animation plays on the timeline again with the same frame count.
    model.apply(Command::Avatar(AvatarCommand::LoadAvatar {
        name: "walk.glb".into(),
        bytes,
    }));
    model.apply(Command::Motion(MotionCommand::CloseClip));
    model.apply(Command::Motion(MotionCommand::OpenAvatarAnimation(0)));
    assert_eq!(model.timeline().clip_name(), Some("walk"));
    assert!(model.frame_count() >= 64, "{}", model.frame_count());
}

#[test]
fn a_corrected_clip_mapping_retargets_the_clip() {
    let (mut model, _, _) = editor();
    open(&mut model, "walk.bvh", WALK);
    let skeleton = model.session().skeleton().clone();
    let elbow = skeleton.joint_index("l_elbow").unwrap();
    let bend = |model: &EditorModel, f: usize| {
        model
            .frame_posture(f)
            .local_rotation(&skeleton, elbow)
            .angle_between(DQuat::IDENTITY)
    };
    let most = |model: &EditorModel| (0..260).map(|f| bend(model, f)).fold(0.0, f64::max);
    let before = most(&model);
    assert!(before > 0.05, "the walk bends the left elbow: {before}");
    // The user says the clip has no left elbow: it moves with the upper arm from then on
    // in the copy.
    let mut mapping = model.timeline().clip().unwrap().mapping.clone();
    assert!(mapping.remove("l_elbow"));
    model.apply(Command::Motion(MotionCommand::SetClipMapping(Box::new(
        mapping,
    ))));
    let clip = model.timeline().clip().unwrap();
    assert!(clip.mapping.get("l_elbow").is_none());
    // (The wrist task at level 3 may still bend it a little.)
    let after = most(&model);
    assert!(after < 0.1 * before, "{after} vs {before}");
    // A mapping of another clip is refused and changes nothing.
    let other = stance_hanim::Mapping::empty(3);
    model.apply(Command::Motion(MotionCommand::SetClipMapping(Box::new(
        other,
    ))));
    assert!(model.notice().unwrap().is_error);
    assert_eq!(model.frame_count(), 260);
}
