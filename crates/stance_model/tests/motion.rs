//! The timeline driven by commands alone: a clip opened on the body, playback, keys as an
//! additive layer, gestures that become keys, tasks over time, documents with motion.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use crate::clocked;
use clocked::Clocked;
use stance_model::model::{
    AvatarCommand, FileCommand, GestureCommand, HistoryCommand, PostureCommand, TaskCommand,
    ViewCommand,
};

use std::f64::consts::FRAC_PI_2;

use glam::DVec3;
use stance_document::motion::smoothstep;
use stance_document::{
    Document, MotionKey, MotionSection, PostureValues, TaskInterval, TaskKindSpec, TaskSpec,
};
use stance_ik::{Dof, Frames, Posture};
use stance_model::Command;
use stance_model::model::{IntervalEdge, MotionCommand};
use stance_motion::Clip;

/// `count` postures of the session's body: the left arm raises and the right elbow bends
/// slowly; the feet stay where they stand (so the clip's contacts change nothing).
fn clip_postures(editor: &Clocked, count: usize) -> Vec<Posture> {
    let skeleton = editor.model.session().skeleton();
    let shoulder = &skeleton.joints()[editor.joint("l_shoulder")];
    let elbow = &skeleton.joints()[editor.joint("r_elbow")];
    (0..count)
        .map(|f| {
            let mut posture = Posture::rest(skeleton);
            let values = posture.values_mut();
            values[shoulder.rotation_dof[2].unwrap()] = 0.02 * f as f64;
            values[elbow.rotation_dof[0].unwrap()] = -0.01 * f as f64;
            posture
        })
        .collect()
}

fn open_clip(editor: &mut Clocked, count: usize, frame_time: f64) -> Vec<Posture> {
    let postures = clip_postures(editor, count);
    let clip = Clip::from_postures(
        "arms",
        editor.model.session().humanoid(),
        &postures,
        frame_time,
    );
    editor.motion(MotionCommand::OpenClip(Box::new(clip)));
    editor.frames(1);
    postures
}

#[test]
fn an_opened_clip_keeps_its_frames_and_a_seek_shows_the_clip_frame() {
    let mut editor = Clocked::new();
    let postures = open_clip(&mut editor, 40, 1.0 / 30.0);
    assert_eq!(editor.model.frame_count(), 40);
    assert_eq!(editor.model.frame_time(), 1.0 / 30.0);
    assert!(editor.model.has_timeline());
    assert!(
        editor.model.session().tasks().is_empty(),
        "the standing tasks are set aside"
    );
    for k in [0, 17, 39] {
        editor.motion(MotionCommand::Seek(k));
        editor.settle();
        assert_eq!(editor.model.timeline().frame(), k);
        let skeleton = editor.model.session().skeleton();
        let source = Frames::new(skeleton, &postures[k]);
        let root = editor.joint("humanoid_root");
        let offset =
            editor.model.session().frames().joint_position[root] - source.joint_position[root];
        for name in [
            "l_radiocarpal",
            "r_radiocarpal",
            "skullbase",
            "l_talocrural",
        ] {
            let j = editor.joint(name);
            let expected = source.joint_position[j] + offset;
            let got = editor.position(name);
            assert!(
                (got - expected).length() < 1e-6,
                "frame {k} {name}: {got} vs {expected}"
            );
        }
    }
}

#[test]
fn playback_advances_by_real_time_times_speed_and_loops_or_stops() {
    let mut editor = Clocked::new();
    open_clip(&mut editor, 40, 1.0 / 30.0);
    editor.motion(MotionCommand::SetSpeed(2.0));
    editor.motion(MotionCommand::Play);
    assert!(editor.model.timeline().is_playing());
    let now = editor.now + 0.5;
    editor.model.step(now, None);
    assert_eq!(editor.model.timeline().frame(), 30);
    assert!(editor.model.timeline().is_playing());

    let mut looping = Clocked::new();
    open_clip(&mut looping, 20, 1.0 / 30.0);
    looping.motion(MotionCommand::SetSpeed(2.0));
    looping.motion(MotionCommand::SetLooping(true));
    looping.motion(MotionCommand::Play);
    looping.model.step(looping.now + 0.5, None);
    assert_eq!(
        looping.model.timeline().frame(),
        10,
        "30 wraps to 10 on 20 frames"
    );

    let mut stopping = Clocked::new();
    open_clip(&mut stopping, 20, 1.0 / 30.0);
    stopping.motion(MotionCommand::SetSpeed(2.0));
    stopping.motion(MotionCommand::SetLooping(false));
    stopping.motion(MotionCommand::TogglePlay);
    stopping.model.step(stopping.now + 0.5, None);
    assert_eq!(stopping.model.timeline().frame(), 19);
    assert!(!stopping.model.timeline().is_playing());
    // The speed stays within its range.
    stopping.motion(MotionCommand::SetSpeed(10.0));
    assert_eq!(stopping.model.timeline().speed(), 4.0);
}

/// A document with keys at 0 (rest) and 10 (left shoulder 90 degrees about z), no tasks.
fn keyed_document(editor: &Clocked) -> Document {
    let skeleton = editor.model.session().skeleton();
    let rest = PostureValues::from_posture(skeleton, &Posture::rest(skeleton));
    let mut raised = rest.clone();
    raised.set("l_shoulder", Dof::Rz, FRAC_PI_2);
    Document {
        posture: rest.clone(),
        motion: Some(MotionSection {
            keys: vec![
                MotionKey {
                    frame: 0,
                    posture: rest,
                },
                MotionKey {
                    frame: 10,
                    posture: raised,
                },
            ],
            ..MotionSection::default()
        }),
        ..Document::default()
    }
}

/// The left shoulder's angle about z at `frame` (degrees).
fn shoulder_degrees(editor: &mut Clocked, frame: usize) -> f64 {
    editor.motion(MotionCommand::Seek(frame));
    editor.settle();
    let skeleton = editor.model.session().skeleton();
    let j = editor.joint("l_shoulder");
    let r = editor
        .model
        .session()
        .posture()
        .rotation_vector(skeleton, j);
    assert!(r.x.abs() < 1e-9 && r.y.abs() < 1e-9, "{r}");
    r.z.to_degrees()
}

fn open_document(editor: &mut Clocked, document: &Document) {
    editor.apply(Command::File(FileCommand::OpenFile {
        name: "keys.json".to_owned(),
        bytes: document.to_json(true).into_bytes(),
    }));
    editor.frames(1);
}

#[test]
fn keys_interpolate_with_ease_and_move_copy_delete_and_undo_change_that() {
    let mut editor = Clocked::new();
    let document = keyed_document(&editor);
    open_document(&mut editor, &document);
    assert_eq!(editor.model.key_frames(), vec![0, 10]);
    assert!(editor.model.has_timeline());
    let close = |a: f64, b: f64| (a - b).abs() < 1e-6;
    assert!(close(shoulder_degrees(&mut editor, 5), 45.0));
    assert!(close(
        shoulder_degrees(&mut editor, 2),
        90.0 * smoothstep(0.2)
    ));
    assert!(close(shoulder_degrees(&mut editor, 10), 90.0));
    assert!(
        close(shoulder_degrees(&mut editor, 30), 90.0),
        "held after the last key"
    );

    editor.motion(MotionCommand::MoveKey { from: 10, to: 20 });
    assert_eq!(editor.model.key_frames(), vec![0, 20]);
    assert!(close(
        shoulder_degrees(&mut editor, 5),
        90.0 * smoothstep(0.25)
    ));
    editor.motion(MotionCommand::CopyKey { from: 0, to: 10 });
    assert_eq!(editor.model.key_frames(), vec![0, 10, 20]);
    assert!(close(shoulder_degrees(&mut editor, 5), 0.0));
    assert!(close(shoulder_degrees(&mut editor, 15), 45.0));
    editor.motion(MotionCommand::DeleteKey(10));
    assert_eq!(editor.model.key_frames(), vec![0, 20]);
    assert!(close(shoulder_degrees(&mut editor, 10), 45.0));

    for _ in 0..3 {
        editor.apply(Command::History(HistoryCommand::Undo));
    }
    assert_eq!(editor.model.key_frames(), vec![0, 10]);
    assert!(close(shoulder_degrees(&mut editor, 5), 45.0));
    editor.apply(Command::History(HistoryCommand::Redo));
    assert_eq!(editor.model.key_frames(), vec![0, 20]);
}

#[test]
fn a_key_set_by_hand_is_the_posture_and_short_timelines_travel_in_links() {
    let mut editor = Clocked::new();
    editor.apply(Command::Task(TaskCommand::Set {
        kind: stance_model::history::EditKind::Command,
        tasks: Vec::new(),
    }));
    editor.motion(MotionCommand::SetKey);
    assert_eq!(editor.model.key_frames(), vec![0]);
    editor.motion(MotionCommand::Seek(12));
    let skeleton = editor.model.session().skeleton();
    let dof = skeleton.joints()[editor.joint("l_elbow")].rotation_dof[0].unwrap();
    editor.apply(Command::Posture(PostureCommand::SetDof {
        dof,
        value: -1.0,
    }));
    editor.settle();
    assert_eq!(
        editor.model.key_frames(),
        vec![0, 12],
        "a posture edit while paused keys"
    );
    assert_eq!(
        editor.model.document().motion.unwrap().keys[1]
            .posture
            .get("l_elbow", Dof::Rx),
        Some(-1.0)
    );
    // A short timeline travels in the link; a long one is left out, and the notice says so.
    let shared = stance_document::link::encode_for_sharing(&editor.model.document());
    assert_eq!(shared.keys_left_out, None);
    let back = stance_document::link::decode(&shared.fragment).unwrap();
    assert_eq!(back.motion.unwrap().keys.len(), 2);
    let link = editor.model.share_link();
    assert_eq!(link.characters, shared.fragment.len());
    editor.apply(Command::File(FileCommand::LinkShared {
        characters: link.characters,
        keys_left_out: link.keys_left_out,
    }));
    let notice = editor.model.notice().unwrap().text.clone();
    assert!(notice.contains("with the timeline's keys"), "{notice}");
    editor.apply(Command::File(FileCommand::LinkShared {
        characters: 900,
        keys_left_out: Some(12_000),
    }));
    let notice = editor.model.notice().unwrap().text.clone();
    assert!(
        notice.contains("The 2 keys are not in it") && notice.contains("12000 characters"),
        "{notice}"
    );
}

#[test]
fn a_pull_while_paused_on_a_clip_frame_becomes_a_key_there_and_undo_takes_it_back() {
    let mut editor = Clocked::new();
    open_clip(&mut editor, 30, 1.0 / 30.0);
    editor.motion(MotionCommand::Seek(5));
    editor.settle();
    assert!(editor.model.key_frames().is_empty());
    let wrist = editor.joint("r_radiocarpal");
    let start = editor.position("r_radiocarpal");
    editor.apply(Command::Gesture(GestureCommand::BeginPull {
        joint: wrist,
        point_world: start,
    }));
    for step in 1..=10 {
        let target = start + DVec3::new(0.0, 0.02, 0.02) * f64::from(step);
        editor.apply(Command::Gesture(GestureCommand::MoveGrab {
            target_world: target,
        }));
        editor.frames(1);
    }
    editor.apply(Command::Gesture(GestureCommand::EndGesture));
    editor.settle();
    assert_eq!(editor.model.key_frames(), vec![5]);
    let moved = editor.position("r_radiocarpal");
    assert!((moved - start).length() > 0.1);
    // The key holds the pulled posture: the frame shows it again after a scrub.
    editor.motion(MotionCommand::Seek(20));
    editor.motion(MotionCommand::Seek(5));
    editor.settle();
    assert!((editor.position("r_radiocarpal") - moved).length() < 1e-6);
    editor.apply(Command::History(HistoryCommand::Undo));
    assert!(editor.model.key_frames().is_empty());
}

const INTERVAL: TaskInterval = TaskInterval {
    start: 1.0,
    end: 2.0,
    ease_in: 0.5,
    ease_out: 0.5,
};

/// The right wrist's position at `frame` of the timeline (without the tasks).
fn own_wrist(editor: &Clocked, frame: usize) -> DVec3 {
    let wrist = editor.joint("r_radiocarpal");
    let posture = editor.model.frame_posture(frame);
    Frames::new(editor.model.session().skeleton(), &posture).joint_position[wrist]
}

/// A 2.5 s clip at 20 fps with a right-hand goal 17 cm from where the clip has the hand at
/// 0.75 s, active over [1 s, 2 s] with 0.5 s of ease on both sides. Returns the goal.
fn hand_goal_over_time(editor: &mut Clocked) -> DVec3 {
    open_clip(editor, 50, 0.05);
    let goal = own_wrist(editor, 15) + DVec3::new(0.1, 0.1, 0.1);
    editor.apply(Command::Task(TaskCommand::Set {
        kind: stance_model::history::EditKind::Command,
        tasks: vec![TaskSpec::pin("r_radiocarpal", goal.to_array())],
    }));
    editor.motion(MotionCommand::SetInterval {
        task: 0,
        interval: Some(INTERVAL),
    });
    assert_eq!(editor.model.session().tasks()[0].interval, Some(INTERVAL));
    goal
}

fn timed_target(editor: &Clocked) -> DVec3 {
    let timed = editor.model.session().timed_tasks();
    let TaskKindSpec::Position { target, .. } = &timed[0].kind else {
        panic!("{timed:?}");
    };
    DVec3::from_array(*target)
}

#[test]
fn a_task_interval_weighs_the_goal_between_the_frame_and_the_task() {
    assert_eq!(INTERVAL.weight(0.4), 0.0);
    assert!((INTERVAL.weight(0.75) - 0.5).abs() < 1e-12);
    assert_eq!(INTERVAL.weight(1.5), 1.0);
    let mut editor = Clocked::new();
    let goal = hand_goal_over_time(&mut editor);
    editor.motion(MotionCommand::Seek(8));
    assert!(
        editor.model.session().timed_tasks().is_empty(),
        "weight 0 at 0.4 s"
    );
    editor.motion(MotionCommand::Seek(15));
    let halfway = (own_wrist(&editor, 15) + goal) / 2.0;
    assert!((timed_target(&editor) - halfway).length() < 1e-6);
    editor.motion(MotionCommand::Seek(30));
    assert_eq!(timed_target(&editor), goal);
}

#[test]
fn a_task_interval_eases_the_hand_in_without_a_pop_and_its_ends_drag() {
    let mut editor = Clocked::new();
    let goal = hand_goal_over_time(&mut editor);
    // Solved frame by frame across the ramp: no jump bigger than the ramp's steepest step.
    let distance = (goal - own_wrist(&editor, 15)).length();
    let mut last: Option<DVec3> = None;
    for frame in 6..=24 {
        editor.motion(MotionCommand::Seek(frame));
        editor.settle();
        let hand = editor.position("r_radiocarpal");
        if frame <= 10 {
            assert!(
                (hand - own_wrist(&editor, frame)).length() < 1e-6,
                "frame {frame}"
            );
        }
        if frame >= 20 {
            assert!((hand - goal).length() < 1e-3, "frame {frame}");
        }
        if let Some(last) = last {
            let jump = (hand - last).length();
            assert!(jump < 0.2 * distance + 0.01, "frame {frame}: {jump} m");
        }
        last = Some(hand);
    }
    // A drag a while later is an undo step of its own.
    editor.frames(60);
    editor.motion(MotionCommand::DragInterval {
        task: 0,
        edge: IntervalEdge::End,
        secs: 2.3,
    });
    editor.motion(MotionCommand::DragInterval {
        task: 0,
        edge: IntervalEdge::Start,
        secs: 3.0,
    });
    let dragged = editor.model.session().tasks()[0].interval.unwrap();
    assert_eq!((dragged.start, dragged.end), (2.3, 2.3));
    editor.apply(Command::History(HistoryCommand::Undo));
    assert_eq!(editor.model.session().tasks()[0].interval, Some(INTERVAL));
}

#[test]
fn a_document_with_keys_and_intervals_round_trips_and_an_old_one_loads_as_before() {
    let editor = Clocked::new();
    let mut document = keyed_document(&editor);
    let mut task = TaskSpec::pin("l_talocrural", [0.1, 0.08, 0.0]);
    task.interval = Some(TaskInterval {
        start: 0.5,
        end: 1.25,
        ease_in: 0.25,
        ease_out: 0.0,
    });
    document.tasks.push(task);
    let text = document.to_json(true);
    assert!(text.contains("\"interval\"") && text.contains("\"motion\""));
    assert_eq!(Document::from_json(&text).unwrap(), document);

    let old = r#"{"version": 1, "posture": {"l_knee": {"rx": 0.3}},
        "tasks": [{"kind": "position", "joint": "l_talocrural", "target": [0.1, 0.07, 0]}]}"#;
    let read = Document::from_json(old).unwrap();
    assert!(read.motion.is_none());
    assert!(read.tasks[0].interval.is_none());
    assert!(!read.to_json(false).contains("interval"));

    let bad = r#"{"tasks": [{"kind": "com", "target": [0, 0, 0],
        "interval": {"start": 2, "end": 1}}]}"#;
    let error = Document::from_json(bad).unwrap_err().to_string();
    assert!(error.starts_with("tasks[0].interval.end"), "{error}");
    let unordered =
        r#"{"motion": {"keys": [{"frame": 3, "posture": {}}, {"frame": 1, "posture": {}}]}}"#;
    let error = Document::from_json(unordered).unwrap_err().to_string();
    assert!(error.starts_with("motion.keys[1].frame"), "{error}");
}

#[test]
fn the_trajectory_follows_the_selected_joint_over_every_frame() {
    let mut editor = Clocked::new();
    let postures = open_clip(&mut editor, 20, 1.0 / 30.0);
    assert!(editor.model.timeline().trajectory().is_empty());
    let wrist = editor.joint("l_radiocarpal");
    editor.apply(Command::View(ViewCommand::Select(Some(wrist))));
    editor.frames(1);
    let trajectory = editor.model.timeline().trajectory().to_vec();
    assert_eq!(trajectory.len(), 20);
    let skeleton = editor.model.session().skeleton();
    let first = Frames::new(skeleton, &postures[0]).joint_position[wrist];
    let last = Frames::new(skeleton, &postures[19]).joint_position[wrist];
    assert!(((trajectory[19] - trajectory[0]) - (last - first)).length() < 1e-6);
    editor.motion(MotionCommand::SetTrajectory(Some("skullbase".to_owned())));
    let head = editor.model.timeline().trajectory().to_vec();
    assert!(
        (head[0] - head[19]).length() < 1e-6,
        "the head does not move"
    );
}

#[test]
fn a_new_level_of_articulation_retargets_the_clip_and_keeps_the_keys() {
    let mut editor = Clocked::new();
    open_clip(&mut editor, 24, 0.04);
    editor.motion(MotionCommand::Seek(6));
    editor.motion(MotionCommand::SetKey);
    let joints = editor.model.session().skeleton().joint_count();
    editor.apply(Command::Avatar(AvatarCommand::SetLevelOfArticulation(
        stance_hanim::LevelOfArticulation::Loa1,
    )));
    editor.frames(1);
    assert!(editor.model.session().skeleton().joint_count() < joints);
    assert!(editor.model.timeline().has_clip());
    assert_eq!(editor.model.frame_count(), 24);
    assert_eq!(editor.model.frame_time(), 0.04);
    assert_eq!(editor.model.key_frames(), vec![6]);
    assert_eq!(editor.model.timeline().frame(), 6);
    editor.motion(MotionCommand::CloseClip);
    assert!(!editor.model.timeline().has_clip());
    assert!(editor.model.has_timeline(), "the key stays");
}
