//! Clips kept with the document: a saved document carries its clip (compressed) and reopens
//! in a fresh editor with the same clip frames, keys and timed tasks; a damaged embedded clip
//! is refused by name and the open document stays; a link names the clip and the editor asks
//! for its file, then takes it; the autosave brings the clip back.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use stance_document::{
    Document, MotionKey, MotionSection, PostureValues, TaskInterval, TaskSpec, link,
};
use stance_ik::Dof;
use stance_model::model::MotionCommand;
use stance_model::model::{FileCommand, PostureCommand};
use stance_model::{Command, EditorModel, MemoryHost};
use stance_motion::{BvhLimits, read_bvh};

use crate::clocked::{editor_on, open};

const WALK: &[u8] = include_bytes!("../../../tests/fixtures/motion/walk.bvh");
const RUN: &[u8] = include_bytes!("../../../tests/fixtures/motion/run.bvh");

/// The walk on the timeline, a key at frame 40 (the left shoulder raised over the clip) and a
/// right-hand pin active from 0.1 s to 0.2 s: the keys and constraints over a clip.
fn walk_with_keys(model: &mut EditorModel) {
    open(model, "walk.bvh", WALK);
    assert_eq!(model.frame_count(), 260);
    let skeleton = model.session().skeleton();
    let mut raised = PostureValues::from_posture(skeleton, &model.frame_posture(40));
    raised.set("l_shoulder", Dof::Rz, 1.2);
    let mut pin = TaskSpec::pin("r_radiocarpal", [0.3, 1.0, 0.2]);
    pin.interval = Some(TaskInterval::new(0.1, 0.2));
    let document = Document {
        tasks: vec![pin],
        motion: Some(MotionSection {
            keys: vec![MotionKey {
                frame: 40,
                posture: raised,
            }],
            ..model.session().motion().cloned().unwrap_or_default()
        }),
        ..model.document()
    };
    open(model, "keys.json", document.to_json(true).as_bytes());
    assert!(!model.notice().unwrap().is_error, "{:?}", model.notice());
    assert_eq!(model.key_frames(), vec![40]);
}

/// What the user sees of a timeline: frames, rate, keys, tasks and a few frames' postures.
fn assert_same_timeline(a: &EditorModel, b: &EditorModel) {
    assert_eq!(a.frame_count(), b.frame_count());
    assert_eq!(a.frame_time(), b.frame_time());
    assert_eq!(a.key_frames(), b.key_frames());
    assert_eq!(a.session().tasks(), b.session().tasks());
    for frame in [0, 39, 40, 41, 120, 259] {
        let (pa, pb) = (a.frame_posture(frame), b.frame_posture(frame));
        let most = pa
            .values()
            .iter()
            .zip(pb.values())
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        assert!(most < 1e-9, "frame {frame}: postures differ by {most}");
    }
}

// Catches clips that are not kept with the document: a saved document reopened elsewhere
// showed its keys over the rest posture, its clip gone.
#[test]
fn a_saved_document_reopens_in_a_fresh_editor_with_its_clip_and_keys() {
    let host = MemoryHost::default();
    let mut model = editor_on(&host);
    walk_with_keys(&mut model);
    model.apply(Command::File(FileCommand::ExportDocument));
    let (file, text) = host.inner.borrow().downloads.last().cloned().unwrap();
    assert_eq!(file, "stance-pose.json");
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(json["clip"]["file"], "walk.bvh");
    assert_eq!(json["clip"]["size"], WALK.len());
    let compressed = json["clip"]["deflate"].as_str().unwrap().len();
    println!(
        "[kept_clips] walk.bvh: {} bytes, embedded in {compressed} characters, hash {}",
        WALK.len(),
        json["clip"]["hash"]
    );
    assert!(
        compressed < WALK.len() / 2,
        "the clip is compressed: {compressed} characters for {} bytes",
        WALK.len()
    );

    let mut fresh = editor_on(&MemoryHost::default());
    open(&mut fresh, "stance-pose.json", text.as_bytes());
    let notice = fresh.notice().unwrap().clone();
    assert!(!notice.is_error, "{}", notice.text);
    assert!(
        notice.text.contains("With its clip: the clip walk"),
        "{}",
        notice.text
    );
    let clip = fresh.timeline().clip().expect("the clip is back");
    let read = read_bvh(WALK, "walk", &BvhLimits::default()).unwrap();
    assert_eq!(clip.frames, read.frames, "the same clip frames");
    assert_eq!(fresh.timeline().clip_name(), Some("walk"));
    assert_eq!(
        fresh.session().tasks().len(),
        1,
        "the timed pin is not set aside"
    );
    assert_same_timeline(&model, &fresh);
    // Saved again, it carries the same clip, keys and tasks.
    let (again, saved) = (fresh.document(), Document::from_json(&text).unwrap());
    assert!(again.clip == saved.clip, "the same clip file");
    assert!(again.motion == saved.motion && again.tasks == saved.tasks);
}

// Catches a damaged embedded clip that crashed, opened half a document, or replaced the
// open one with nothing said.
#[test]
fn a_damaged_embedded_clip_is_named_and_the_open_document_stays() {
    let host = MemoryHost::default();
    let mut model = editor_on(&host);
    walk_with_keys(&mut model);
    model.apply(Command::File(FileCommand::ExportDocument));
    let text = host.inner.borrow().downloads.last().cloned().unwrap().1;
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    let data = json["clip"]["deflate"].as_str().unwrap().to_owned();

    let mut other = editor_on(&MemoryHost::default());
    open(&mut other, "run.bvh", RUN);
    let before = other.document();
    let frames = other.frame_count();
    let truncated = text.replace(&data, &data[..data.len() / 2]);
    let mut changed = data.clone().into_bytes();
    let middle = changed.len() / 2;
    changed[middle] = if changed[middle] == b'A' { b'B' } else { b'A' };
    let corrupted = text.replace(&data, std::str::from_utf8(&changed).unwrap());
    for (what, damaged) in [("truncated", truncated), ("corrupted", corrupted)] {
        open(&mut other, "saved.json", damaged.as_bytes());
        let notice = other.notice().unwrap().clone();
        assert!(notice.is_error, "{what}: {}", notice.text);
        for words in ["saved.json", "clip.deflate", "walk.bvh", "damaged"] {
            assert!(
                notice.text.contains(words),
                "{what}: {words}: {}",
                notice.text
            );
        }
        assert_eq!(other.document(), before, "{what}: the document stays");
        assert_eq!(other.timeline().clip_name(), Some("run"));
        assert_eq!(other.frame_count(), frames);
    }
}

// Catches a link that lost its clip without a word: the link names the clip, the editor says
// which file to open, takes it when it comes (or says it is another clip).
#[test]
fn a_link_names_its_clip_and_the_editor_asks_for_that_file_then_takes_it() {
    let mut model = editor_on(&MemoryHost::default());
    walk_with_keys(&mut model);
    let fragment = link::encode(&model.document());
    assert!(
        fragment.len() < 8 * 1024,
        "a link carries the clip's name, not the clip ({} characters)",
        fragment.len()
    );

    let mut fresh = editor_on(&MemoryHost::default());
    fresh.apply(Command::File(FileCommand::OpenLink(fragment.clone())));
    let notice = fresh.notice().unwrap().clone();
    assert!(notice.is_error, "{}", notice.text);
    assert!(
        notice.text.contains("walk.bvh") && notice.text.contains("open that file"),
        "{}",
        notice.text
    );
    assert!(fresh.timeline().clip().is_none());
    assert_eq!(fresh.key_frames(), vec![40]);
    // Saved before the file comes, the document still names its clip.
    assert_eq!(
        fresh.document().clip.map(|clip| clip.name),
        Some("walk.bvh".to_owned())
    );
    open(&mut fresh, "walk-copy.bvh", WALK);
    let text = fresh.notice().unwrap().text.clone();
    assert!(
        text.contains("It is the clip the document was made over (walk.bvh)"),
        "{text}"
    );
    assert_eq!(
        fresh.session().tasks().len(),
        1,
        "the link's timed pin stays"
    );
    let quantised = |m: &EditorModel| m.frame_posture(40).values().to_vec();
    let (a, b) = (quantised(&model), quantised(&fresh));
    let most = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    assert!(most < 1e-3, "the key over the clip is back: {most}");

    let mut wrong = editor_on(&MemoryHost::default());
    wrong.apply(Command::File(FileCommand::OpenLink(fragment)));
    open(&mut wrong, "run.bvh", RUN);
    let text = wrong.notice().unwrap().text.clone();
    assert!(text.contains("made over another clip, walk.bvh"), "{text}");
}

// Catches an autosave that dropped the clip: reloading the page brought the keys back over
// the rest posture.
#[test]
fn the_autosave_brings_the_clip_back() {
    let host = MemoryHost::default();
    let mut model = editor_on(&host);
    walk_with_keys(&mut model);
    model.step(5.0, None);
    assert!(host.stored_texts().iter().any(|v| v.contains("walk.bvh")));
    // The page opens the startup document before its first frame.
    let mut reloaded = EditorModel::new(Box::new(host.clone())).unwrap();
    reloaded.open_startup(None);
    reloaded.step(0.0, None);
    assert_eq!(reloaded.timeline().clip_name(), Some("walk"));
    assert_eq!(reloaded.key_frames(), vec![40]);
    assert_same_timeline(&model, &reloaded);
}

// Catches documents from before clips were kept that no longer open, or that close the open
// clip.
#[test]
fn a_document_without_a_clip_opens_over_the_open_clip() {
    let mut model = editor_on(&MemoryHost::default());
    open(&mut model, "walk.bvh", WALK);
    let old = r#"{"version": 1, "posture": {}, "tasks": [],
        "motion": {"frame_time": 0.0333, "frame_count": 60, "keys": []}}"#;
    open(&mut model, "old.json", old.as_bytes());
    assert!(!model.notice().unwrap().is_error, "{:?}", model.notice());
    assert_eq!(model.timeline().clip_name(), Some("walk"));
    assert_eq!(model.frame_count(), 260);
}

// Catches a clip that did not come from a BVH file (a recording) lost on saving, or written
// as a BVH that reads back as another motion (units or axes guessed wrong).
#[test]
fn a_recorded_clip_is_kept_as_bvh_and_reopens_with_the_same_motion() {
    let host = MemoryHost::default();
    let mut model = editor_on(&host);
    let elbow = model.session().skeleton().joint_index("l_elbow").unwrap();
    let dof = model.session().skeleton().joints()[elbow].dof_start;
    model.apply(Command::Motion(MotionCommand::Record(true)));
    for k in 1..=30 {
        let now = f64::from(k) / 30.0;
        model.apply(Command::Posture(PostureCommand::SetDof {
            dof,
            value: -now,
        }));
        model.step(now, None);
    }
    model.apply(Command::Motion(MotionCommand::Record(false)));
    assert_eq!(model.timeline().clip_name(), Some("recording"));
    model.apply(Command::File(FileCommand::ExportDocument));
    let text = host.inner.borrow().downloads.last().cloned().unwrap().1;
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(json["clip"]["file"], "recording.bvh");

    let mut fresh = editor_on(&MemoryHost::default());
    open(&mut fresh, "recorded.json", text.as_bytes());
    assert!(!fresh.notice().unwrap().is_error, "{:?}", fresh.notice());
    assert_eq!(fresh.frame_count(), model.frame_count());
    assert!((fresh.frame_time() - model.frame_time()).abs() < 1e-9);
    for frame in 0..model.frame_count() {
        let (a, b) = (model.frame_posture(frame), fresh.frame_posture(frame));
        let most = a
            .values()
            .iter()
            .zip(b.values())
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        assert!(most < 1e-6, "frame {frame}: {most}");
    }
}

// Catches a large clip that broke the autosave (the browser's storage is a few megabytes) or
// was dropped from it silently: it is autosaved by name and the restored work asks for it.
#[test]
fn a_clip_too_large_for_the_autosave_is_named_and_asked_for() {
    let text = String::from_utf8_lossy(WALK).into_owned();
    let (head, motion) = text.split_at(text.find("MOTION").unwrap());
    let rows: Vec<&str> = motion.lines().skip(3).collect();
    let mut long = format!("{head}MOTION\nFrames: 3200\nFrame Time: .0083333\n");
    for f in 0..3200 {
        long.push_str(rows[f % rows.len()]);
        long.push('\n');
    }
    assert!(long.len() as u64 > stance_model::model::AUTOSAVE_CLIP_BYTES);
    let host = MemoryHost::default();
    let mut model = editor_on(&host);
    // The plain copy: the contacts' solve would take seconds here and changes nothing kept.
    let plain = stance_motion::RetargetOptions {
        contacts: None,
        ..Default::default()
    };
    model.apply(Command::Motion(MotionCommand::SetRetargetOptions(
        Box::new(plain.clone()),
    )));
    open(&mut model, "long.bvh", long.as_bytes());
    assert_eq!(model.frame_count(), 3200);
    model.step(5.0, None);
    let saved = host.stored_texts();
    assert!(
        saved.iter().all(|v| v.len() < 64 * 1024),
        "the clip is named, not carried: {:?}",
        saved.iter().map(String::len).collect::<Vec<_>>()
    );
    let mut reloaded = EditorModel::new(Box::new(host.clone())).unwrap();
    reloaded.apply(Command::Motion(MotionCommand::SetRetargetOptions(
        Box::new(plain),
    )));
    reloaded.open_startup(None);
    let notice = reloaded.notice().unwrap().clone();
    assert!(notice.is_error, "{}", notice.text);
    assert!(
        notice.text.contains("long.bvh") && notice.text.contains("open that file"),
        "{}",
        notice.text
    );
    open(&mut reloaded, "long.bvh", long.as_bytes());
    assert!(
        reloaded
            .notice()
            .unwrap()
            .text
            .contains("It is the clip the document was made over"),
        "{:?}",
        reloaded.notice()
    );
}
