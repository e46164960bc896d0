//! Clips opened off the editor's thread: a host that retargets clips (the page's loading
//! worker) is handed the file, the body and the settings; the editor shows the progress it
//! reports and *Cancel*; the result goes on the timeline as the editor's own would; a
//! cancelled or stale request leaves the document and the timeline as they were.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use stance_editor::model::MotionCommand;
use stance_editor::model::{AvatarCommand, FileCommand, ViewCommand};
use stance_editor::{Command, HostMessage, JobOutput, JobRequest, MemoryHost, StanceApp};
use stance_hanim::LevelOfArticulation;

use egui_kittest::kittest::Queryable;

use crate::common::{click_button, editor_on, harness_for, open, state};

const WALK: &[u8] = include_bytes!("../../../tests/fixtures/motion/walk.bvh");
const RUN: &[u8] = include_bytes!("../../../tests/fixtures/motion/run.bvh");

/// A host that retargets clips (answered by the test).
fn worker_host() -> MemoryHost {
    let host = MemoryHost::default();
    host.inner.borrow_mut().runs_jobs = true;
    host
}

/// The last request the host took.
fn last_request(host: &MemoryHost) -> JobRequest {
    host.inner.borrow().jobs.last().cloned().unwrap()
}

/// The clip job of a request.
fn clip(request: &JobRequest) -> &stance_asset::ClipJob {
    match &request.job {
        stance_editor::HostJob::Clip(job) => job,
        stance_editor::HostJob::Lift(_) => panic!("a clip request"),
    }
}

/// What the worker does: the request read and retargeted (in steps), as the host's reply.
fn answer(request: JobRequest) -> HostMessage {
    let id = request.id;
    let result = request.job.run(&mut |_| {}).map(|output| match output {
        JobOutput::Clip(opened) => opened,
        JobOutput::Lift(_) => panic!("a clip request"),
    });
    HostMessage::ClipOpened { id, result }
}

// Catches a worker's result that differs from the editor's own (another body or settings
// sent, the clip's file not kept), and progress that goes back or is taken from another
// request.
#[test]
fn a_clip_opened_by_the_host_shows_its_progress_then_is_the_editors_own() {
    let host = worker_host();
    let mut model = editor_on(&host);
    let before = model.document();
    open(&mut model, "walk.bvh", WALK);
    let request = last_request(&host);
    assert_eq!(clip(&request).name, "walk.bvh");
    assert_eq!(&clip(&request).bytes[..], WALK);
    assert_eq!(&clip(&request).body, model.session().humanoid());
    assert_eq!(model.timeline().opening(), Some(("walk.bvh", 0.0)));
    assert!(!model.timeline().has_clip());
    assert_eq!(model.document(), before, "nothing changes while it opens");

    let id = request.id;
    for (from, fraction) in [(id, 0.4), (id + 7, 0.9), (id, 0.2), (id, f64::NAN)] {
        model.receive(HostMessage::JobProgress { id: from, fraction });
    }
    assert_eq!(model.timeline().opening(), Some(("walk.bvh", 0.4)));

    model.receive(answer(request));
    assert_eq!(model.timeline().opening(), None);
    let notice = model.notice().unwrap().clone();
    assert!(
        !notice.is_error && notice.text.starts_with("Opened the clip walk: 260 frames"),
        "{}",
        notice.text
    );
    let mut own = editor_on(&MemoryHost::default());
    open(&mut own, "walk.bvh", WALK);
    assert_eq!(model.frame_count(), own.frame_count());
    assert_eq!(model.timeline().contacts(), own.timeline().contacts());
    for frame in [0, 100, 259] {
        assert_eq!(model.frame_posture(frame), own.frame_posture(frame));
    }
    assert_eq!(
        model.document(),
        own.document(),
        "the clip and its tasks kept"
    );
}

// Catches Cancel leaving a trace: the tasks set aside, the clip on the timeline, a reply that
// arrives afterwards taken, the previous clip closed.
#[test]
fn cancel_leaves_the_document_and_the_timeline_as_they_were() {
    let host = worker_host();
    let mut model = editor_on(&host);
    open(&mut model, "run.bvh", RUN);
    model.receive(answer(last_request(&host)));
    assert_eq!(model.timeline().clip_name(), Some("run"));
    let before = model.document();
    let frames = model.frame_count();
    let undo_steps = model.history().undo_steps();

    open(&mut model, "walk.bvh", WALK);
    let request = last_request(&host);
    model.receive(HostMessage::JobProgress {
        id: request.id,
        fraction: 0.3,
    });
    model.apply(Command::Motion(MotionCommand::CancelOpening));
    assert_eq!(host.inner.borrow().cancelled_jobs, vec![request.id]);
    assert_eq!(model.timeline().opening(), None);
    let notice = model.notice().unwrap().text.clone();
    assert!(notice.contains("walk.bvh was cancelled"), "{notice}");
    // The worker's reply was already on its way.
    model.receive(answer(request));
    assert_eq!(model.document(), before);
    assert_eq!(model.timeline().clip_name(), Some("run"));
    assert_eq!(model.frame_count(), frames);
    assert_eq!(model.history().undo_steps(), undo_steps);
}

// Catches a clip retargeted onto a body that is no longer there: a change of body while the
// host works asks again on the new body (and a reply made for the old one is not taken).
#[test]
fn a_change_of_body_while_a_clip_opens_asks_again_on_the_new_body() {
    let host = worker_host();
    let mut model = editor_on(&host);
    open(&mut model, "walk.bvh", WALK);
    let first = last_request(&host);
    model.apply(Command::Avatar(AvatarCommand::SetLevelOfArticulation(
        LevelOfArticulation::Loa1,
    )));
    let second = last_request(&host);
    assert_ne!(second.id, first.id);
    assert_eq!(host.inner.borrow().cancelled_jobs, vec![first.id]);
    assert_eq!(&clip(&second).body, model.session().humanoid());
    assert_ne!(clip(&second).body, clip(&first).body);
    model.receive(answer(first));
    assert!(
        !model.timeline().has_clip(),
        "the old body's reply is dropped"
    );
    model.receive(answer(second));
    assert_eq!(model.timeline().clip_name(), Some("walk"));
    let dofs = model.session().skeleton().dof_count();
    assert_eq!(model.frame_posture(10).values().len(), dofs);
}

// Catches a document's clip that the host opens losing the document's keys, tasks or clip
// (cancelled: the document still names it), or setting the document's own tasks aside.
#[test]
fn a_documents_clip_is_opened_by_the_host_and_cancel_keeps_it_named() {
    let mut maker = editor_on(&MemoryHost::default());
    open(&mut maker, "walk.bvh", WALK);
    maker.apply(Command::Motion(MotionCommand::Seek(40)));
    maker.apply(Command::Motion(MotionCommand::SetKey));
    let saved = maker.document();
    let text = saved.to_json(true);

    for cancel in [false, true] {
        let host = worker_host();
        let mut model = editor_on(&host);
        open(&mut model, "saved.json", text.as_bytes());
        let notice = model.notice().unwrap().text.clone();
        assert!(notice.contains("is being read"), "{notice}");
        assert_eq!(model.key_frames(), vec![40]);
        assert_eq!(model.timeline().opening(), Some(("walk.bvh", 0.0)));
        let request = last_request(&host);
        if cancel {
            model.apply(Command::Motion(MotionCommand::CancelOpening));
            model.receive(answer(request));
            assert!(!model.timeline().has_clip());
            let named = model.document().clip.unwrap();
            assert_eq!(named.name, "walk.bvh");
            assert_eq!(named.hash, saved.clip.as_ref().unwrap().hash);
        } else {
            model.receive(answer(request));
            let notice = model.notice().unwrap().text.clone();
            assert!(
                notice.starts_with("The document's clip is on the timeline: the clip walk"),
                "{notice}"
            );
            assert_eq!(model.timeline().clip_name(), Some("walk"));
            assert_eq!(model.document().tasks, saved.tasks, "none set aside");
            assert_eq!(model.frame_posture(40), maker.frame_posture(40));
            assert_eq!(model.document().clip, saved.clip);
        }
    }
}

// Catches a progress strip without Cancel, or a Cancel that does nothing: the strip shows
// while the host opens the clip, and its button stops it.
#[test]
fn the_progress_strip_shows_and_its_cancel_button_stops_the_opening() {
    let host = worker_host();
    let app = StanceApp::without_gpu(Box::new(host.clone())).unwrap();
    let mut harness = harness_for(app);
    harness
        .state_mut()
        .apply(Command::File(FileCommand::OpenFile {
            name: "walk.bvh".into(),
            bytes: WALK.to_vec(),
        }));
    let id = last_request(&host).id;
    harness
        .state_mut()
        .apply(Command::Motion(MotionCommand::ClipProgress {
            id,
            fraction: 0.5,
        }));
    harness.run_steps(2);
    assert_eq!(state(&harness)["motion"]["opening"]["progress"], 0.5);
    harness.get_by_label_contains("Opening walk.bvh: 50 %");
    click_button(&mut harness, "cancel_clip");
    harness.run_steps(2);
    assert!(state(&harness)["motion"]["opening"].is_null());
    assert_eq!(host.inner.borrow().cancelled_jobs, vec![id]);
    assert!(state(&harness)["buttons"]["cancel_clip"].is_null());
}

#[path = "../../../tests/fixtures/motion/long_walk.rs"]
mod long_walk;
use long_walk::long_walk;

// Catches the trajectory of a long clip computed in one frame (10,000 frames held up the
// page's frame for about 100 ms): it grows by a thousand frames a step, the editor stays busy
// (drawing frames) until it is whole, and it is the same as the frames' own positions.
#[test]
fn a_long_clips_trajectory_is_computed_a_thousand_frames_a_step() {
    use stance_editor::model::TRAJECTORY_FRAMES_PER_STEP;
    let mut model = editor_on(&MemoryHost::default());
    let plain = stance_motion::RetargetOptions {
        contacts: None,
        ..Default::default()
    };
    model.apply(Command::Motion(MotionCommand::SetRetargetOptions(
        Box::new(plain),
    )));
    open(&mut model, "long.bvh", &long_walk(2500));
    assert_eq!(model.frame_count(), 2500);
    let wrist = model.session().skeleton().joint_index("l_radiocarpal");
    model.apply(Command::View(ViewCommand::Select(wrist)));
    let mut lengths = Vec::new();
    for step in 1..=4 {
        model.step(step as f64, None);
        lengths.push(model.timeline().trajectory().len());
        if lengths.last() == Some(&2500) {
            assert!(!model.is_busy() || !model.session().is_settled());
        } else {
            assert!(model.is_busy(), "busy while the trajectory grows");
        }
    }
    assert_eq!(lengths[0], TRAJECTORY_FRAMES_PER_STEP);
    assert_eq!(lengths[2..], [2500, 2500]);
    let skeleton = model.session().skeleton();
    let at = |frame: usize| {
        stance_ik::Frames::new(skeleton, &model.frame_posture(frame)).joint_position[wrist.unwrap()]
    };
    for frame in [0, 999, 1000, 2499] {
        assert!((model.timeline().trajectory()[frame] - at(frame)).length() < 1e-12);
    }
}

// Catches an open clip put on a new body on the editor's thread (a long clip froze the page
// for seconds after an avatar or LOA change): the file goes back to the host with the new
// body, the clip is hidden meanwhile (made for the old body) but still named by the document
// with its keys, and the host's result is the editor's own on that body, the playhead where
// it was.
#[test]
fn a_change_of_body_puts_the_open_clip_on_it_again_through_the_host() {
    let host = worker_host();
    let mut model = editor_on(&host);
    open(&mut model, "walk.bvh", WALK);
    model.receive(answer(last_request(&host)));
    model.apply(Command::Motion(MotionCommand::Seek(40)));
    let named = model.document().clip.unwrap();
    let requests = host.inner.borrow().jobs.len();

    model.apply(Command::Avatar(AvatarCommand::SetLevelOfArticulation(
        LevelOfArticulation::Loa1,
    )));
    assert_eq!(host.inner.borrow().jobs.len(), requests + 1);
    let request = last_request(&host);
    assert_eq!(&clip(&request).bytes[..], WALK);
    assert_eq!(&clip(&request).body, model.session().humanoid());
    assert_eq!(
        clip(&request).mapping.as_ref(),
        Some(&model.timeline().clip().unwrap().mapping)
    );
    assert!(
        !model.timeline().has_clip(),
        "hidden while it is put on the body"
    );
    assert_eq!(model.timeline().opening(), Some(("walk.bvh", 0.0)));
    assert_eq!(model.document().clip.unwrap().hash, named.hash);
    // Meanwhile the timeline keeps the clip's length and takes no key over the rest posture.
    assert_eq!(model.frame_count(), 260);
    model.apply(Command::Motion(MotionCommand::SetKey));
    assert!(model.key_frames().is_empty());
    let notice = model.notice().unwrap().text.clone();
    assert!(
        notice.contains("keys can be edited once it is back"),
        "{notice}"
    );

    model.receive(answer(request));
    let notice = model.notice().unwrap().text.clone();
    assert!(
        notice.starts_with("The clip walk is on the body again"),
        "{notice}"
    );
    let mut own = editor_on(&MemoryHost::default());
    own.apply(Command::Avatar(AvatarCommand::SetLevelOfArticulation(
        LevelOfArticulation::Loa1,
    )));
    open(&mut own, "walk.bvh", WALK);
    assert_eq!(model.frame_count(), own.frame_count());
    assert_eq!(model.timeline().contacts(), own.timeline().contacts());
    for frame in [0, 100, 259] {
        assert_eq!(model.frame_posture(frame), own.frame_posture(frame));
    }
    assert_eq!(model.timeline().frame(), 40, "the playhead stays");
    assert_eq!(model.document().clip, Some(named));
}

// Catches a corrected mapping dropped when the clip goes back to the host (the clip would come
// back mapped as the file says), and a cancelled re-targeting that leaves a clip made for
// another body on the timeline or forgets the document's clip.
#[test]
fn a_mapping_correction_goes_with_the_file_and_cancel_closes_the_clip_but_keeps_it_named() {
    let host = worker_host();
    let mut model = editor_on(&host);
    open(&mut model, "walk.bvh", WALK);
    model.receive(answer(last_request(&host)));
    model.apply(Command::Motion(MotionCommand::Seek(40)));
    model.apply(Command::Motion(MotionCommand::SetKey));
    let named = model.document().clip.unwrap();
    let mut mapping = model.timeline().clip().unwrap().mapping.clone();
    assert!(mapping.remove("l_elbow"));
    model.apply(Command::Motion(MotionCommand::SetClipMapping(Box::new(
        mapping.clone(),
    ))));
    let request = last_request(&host);
    assert_eq!(clip(&request).mapping.as_ref(), Some(&mapping));
    model.receive(answer(request));
    assert_eq!(model.timeline().clip().unwrap().mapping, mapping);
    assert!(model.timeline().has_clip());
    assert_eq!(model.key_frames(), vec![40], "the keys stay");

    model.apply(Command::Avatar(AvatarCommand::SetLevelOfArticulation(
        LevelOfArticulation::Loa1,
    )));
    let request = last_request(&host);
    model.apply(Command::Motion(MotionCommand::CancelOpening));
    model.receive(answer(request));
    assert!(!model.timeline().has_clip());
    assert!(model.timeline().clip().is_none());
    let notice = model.notice().unwrap().text.clone();
    assert!(
        notice.contains("was cancelled") && notice.contains("still names it"),
        "{notice}"
    );
    assert_eq!(model.document().clip.unwrap().hash, named.hash);
    assert_eq!(model.key_frames(), vec![40]);
}

// Catches the open clip lost while it is asked for again: another clip opened meanwhile and
// cancelled leaves it hidden for good (it is asked for again); a mapping corrected meanwhile
// dropped by the earlier request's reply (that reply is stale: the clip comes back with the
// new mapping); a clip closed meanwhile brought back by the reply.
#[test]
fn the_open_clip_asked_for_again_survives_another_clip_a_new_mapping_and_close() {
    let host = worker_host();
    let mut model = editor_on(&host);
    open(&mut model, "walk.bvh", WALK);
    model.receive(answer(last_request(&host)));
    let named = model.document().clip.unwrap();

    // Another clip opened while the walk is asked for again on LOA 1, then cancelled.
    model.apply(Command::Avatar(AvatarCommand::SetLevelOfArticulation(
        LevelOfArticulation::Loa1,
    )));
    let walk_again = last_request(&host);
    open(&mut model, "run.bvh", RUN);
    let run = last_request(&host);
    assert!(host.inner.borrow().cancelled_jobs.contains(&walk_again.id));
    model.apply(Command::Motion(MotionCommand::CancelOpening));
    let asked = last_request(&host);
    assert_ne!(asked.id, run.id, "the walk is asked for again");
    assert_eq!(&clip(&asked).bytes[..], WALK);
    assert_eq!(&clip(&asked).body, model.session().humanoid());
    model.receive(answer(walk_again));
    assert!(
        !model.timeline().has_clip(),
        "the cancelled request's reply is stale"
    );
    // A mapping corrected while that request is on its way: asked for with it.
    let mut mapping = model.timeline().clip().unwrap().mapping.clone();
    assert!(mapping.remove("r_elbow"));
    model.apply(Command::Motion(MotionCommand::SetClipMapping(Box::new(
        mapping.clone(),
    ))));
    let corrected = last_request(&host);
    assert_eq!(clip(&corrected).mapping.as_ref(), Some(&mapping));
    model.receive(answer(asked));
    assert!(
        !model.timeline().has_clip(),
        "the request before the correction is stale"
    );
    model.receive(answer(corrected));
    assert_eq!(model.timeline().clip_name(), Some("walk"));
    assert_eq!(model.timeline().clip().unwrap().mapping, mapping);
    assert_eq!(model.document().clip, Some(named));

    // Closed while it is asked for again: the request is cancelled, its reply not taken.
    model.apply(Command::Avatar(AvatarCommand::SetLevelOfArticulation(
        LevelOfArticulation::Loa2,
    )));
    let last = last_request(&host);
    model.apply(Command::Motion(MotionCommand::CloseClip));
    assert!(host.inner.borrow().cancelled_jobs.contains(&last.id));
    model.receive(answer(last));
    assert!(model.timeline().clip().is_none() && !model.timeline().has_clip());
    assert!(
        model.document().clip.is_none(),
        "closed: the document names no clip"
    );
}
