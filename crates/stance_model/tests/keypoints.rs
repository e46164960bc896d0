//! *File > Open keypoints…* and the one-click depth flip, driven by commands alone: keypoints
//! rendered from known postures through a known camera (the renderer's own keypoints and
//! JSON, as `stance_lift`'s round trip makes them) are opened, lifted (here at once: the
//! memory host runs no jobs; or handed to the host and answered), and seen again.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use glam::{DVec3, Vec3};
use stance_document::CameraSpec;
use stance_hanim::keypoints::KeypointFinder;
use stance_hanim::{SkeletonOptions, default_skeleton};
use stance_ik::{Frames, Posture, Skeleton, Solver, SolverSettings, Task};
use stance_model::model::{HistoryCommand, KeypointsCommand};
use stance_model::{Command, HostJob, HostMessage, MemoryHost};
use stance_render::{HiddenKeypoints, KeypointUnits, OpenPose, OpenPosePerson, OrbitCamera};

use crate::clocked::Clocked;

const SIZE: [u32; 2] = [768, 768];

fn body() -> Skeleton {
    default_skeleton(&SkeletonOptions::default())
        .unwrap()
        .skeleton
}

/// A camera framing two people side by side from the front.
fn camera() -> OrbitCamera {
    OrbitCamera {
        target_world: Vec3::new(0.45, 0.9, 0.0),
        yaw: 0.0,
        pitch: 0.0,
        distance_m: 3.8,
        ..OrbitCamera::default()
    }
}

/// The view of `stance_lift`'s flip test: one person from the front, on which the lift puts
/// the reaching arm on its side and a flip carries it across (on other views the lift's own
/// solve can bring a flipped arm back: see the report of `a_flip_…`).
fn front_camera() -> OrbitCamera {
    OrbitCamera {
        target_world: Vec3::new(0.0, 0.9, 0.0),
        distance_m: 3.4,
        ..camera()
    }
}

/// The default body with its feet where they stand at rest (shifted by `apart`) and its
/// wrists pulled to `hands` (world).
fn drawn(s: &Skeleton, apart: DVec3, hands: [DVec3; 2]) -> Posture {
    let rest = Frames::new(s, &Posture::rest(s));
    let at = |name: &str| s.joint_index(name).unwrap();
    let foot = |name: &str| rest.joint_position[at(name)] + apart;
    let tasks = vec![
        Task::position(at("l_talocrural"), DVec3::ZERO, foot("l_talocrural")),
        Task::position(at("r_talocrural"), DVec3::ZERO, foot("r_talocrural")),
        Task::position(at("l_radiocarpal"), DVec3::ZERO, hands[0] + apart).at_level(2),
        Task::position(at("r_elbow"), DVec3::ZERO, hands[1] + apart).at_level(2),
        Task::rest_posture(s).at_level(3).with_weight(0.05),
    ];
    let mut posture = Posture::rest(s);
    let mut solver = Solver::new(SolverSettings {
        max_iterations: 300,
        ..SolverSettings::default()
    })
    .unwrap();
    solver.solve(s, &tasks, &mut posture).unwrap();
    posture
}

/// Both hands reaching toward the camera.
fn reaching(s: &Skeleton, apart: DVec3) -> Posture {
    drawn(
        s,
        apart,
        [DVec3::new(0.15, 1.25, 0.5), DVec3::new(-0.2, 1.1, 0.45)],
    )
}

fn seen(s: &Skeleton, posture: &Posture, camera: &OrbitCamera) -> OpenPosePerson {
    let keypoints = KeypointFinder::new(s).find(s, &Frames::new(s, posture));
    OpenPosePerson::seen(&keypoints, camera, SIZE, &[], HiddenKeypoints::Keep)
}

/// The keypoints file of `postures` seen through [`camera`] (with the camera, as the
/// editor's *Export control maps* writes it).
fn keypoints_file(s: &Skeleton, postures: &[Posture]) -> Vec<u8> {
    keypoints_seen_by(s, postures, &camera())
}

fn keypoints_seen_by(s: &Skeleton, postures: &[Posture], camera: &OrbitCamera) -> Vec<u8> {
    OpenPose {
        size_px: SIZE,
        people: postures.iter().map(|p| seen(s, p, camera)).collect(),
    }
    .to_json_seen_by(KeypointUnits::Pixels, camera)
    .into_bytes()
}

/// The largest pixel distance between the body keypoints seen in both.
fn worst_px(a: &OpenPosePerson, b: &OpenPosePerson) -> f64 {
    a.body
        .iter()
        .zip(&b.body)
        .filter_map(|(p, q)| Some((*p.as_ref()? - *q.as_ref()?).length()))
        .fold(0.0, f64::max)
}

fn open(editor: &mut Clocked, name: &str, bytes: Vec<u8>) {
    editor.apply(Command::Keypoints(KeypointsCommand::Open {
        name: name.to_owned(),
        bytes,
    }));
}

/// The saved view as the orbit camera it names.
fn saved_camera(spec: &CameraSpec) -> OrbitCamera {
    OrbitCamera::saved(
        spec.target,
        spec.yaw,
        spec.pitch,
        spec.distance,
        spec.orthographic,
    )
}

/// The depth of the right elbow behind its shoulder, seen from the camera (m), in the
/// session's posture (its frames follow at the next solve).
fn arm_depth(editor: &Clocked) -> f64 {
    let session = editor.model.session();
    let frames = Frames::new(session.skeleton(), session.posture());
    let at = |name: &str| frames.joint_position[editor.joint(name)];
    let eye = front_camera().eye_world().as_dvec3();
    (at("r_elbow") - eye).length() - (at("r_shoulder") - eye).length()
}

#[test]
fn opened_keypoints_become_a_character_that_gives_them_back_through_its_saved_view() {
    // Catches: a lift that is not put in the scene, a saved view other than the keypoints'
    // camera, the posture not the lifted one (the keypoints off their pixels), or a lift
    // that undo does not take back in one step.
    let s = body();
    let posture = reaching(&s, DVec3::ZERO);
    let mut editor = Clocked::new();
    let before = editor.model.scene();
    let started = std::time::Instant::now();
    open(
        &mut editor,
        "reaching.json",
        keypoints_file(&s, std::slice::from_ref(&posture)),
    );
    println!(
        "one person opened and lifted in {:.0} ms (debug build)",
        started.elapsed().as_secs_f64() * 1e3
    );
    let notice = editor.model.notice().unwrap();
    assert!(!notice.is_error, "{}", notice.text);
    assert!(
        notice.text.contains("Lifted reaching.json"),
        "{}",
        notice.text
    );
    assert_eq!(editor.model.character_count(), 1);
    assert_eq!(editor.model.character().name(), "Person 1");
    let view = editor.model.session().camera().expect("the saved view");
    let view = saved_camera(&view);
    assert_eq!(view.target_world, camera().target_world);
    let skeleton = editor.model.session().skeleton().clone();
    let again = seen(&skeleton, editor.model.session().posture(), &view);
    let worst = worst_px(&seen(&s, &posture, &camera()), &again);
    assert!(worst < 3.0, "the lifted keypoints are {worst:.2} px off");

    editor.apply(Command::History(HistoryCommand::Undo));
    assert_eq!(editor.model.scene(), before, "undo restores the scene");
}

#[test]
fn two_people_become_two_characters() {
    // Catches: several people lifted into one character, or only the first kept.
    let s = body();
    let apart = DVec3::new(0.9, 0.0, 0.0);
    let file = keypoints_file(&s, &[reaching(&s, DVec3::ZERO), reaching(&s, apart)]);
    let mut editor = Clocked::new();
    open(&mut editor, "two.json", file);
    let names: Vec<String> = editor
        .model
        .characters()
        .map(|(c, _)| c.name().to_owned())
        .collect();
    assert_eq!(names, ["Person 1", "Person 2"]);
    assert!(editor.model.notice().unwrap().text.contains("2 people"));
}

#[test]
fn bad_keypoints_say_what_is_wrong_and_change_nothing() {
    // Catches: a file that is not OpenPose (or lists nobody) replacing the scene, or a
    // notice that does not name the problem.
    let mut editor = Clocked::new();
    let before = editor.model.scene();
    for (bytes, words) in [
        (br#"{"characters": []}"#.to_vec(), "not OpenPose keypoints"),
        (
            br#"{"canvas_width": 64, "canvas_height": 64, "people": []}"#.to_vec(),
            "no person",
        ),
        (b"\xff\xfe".to_vec(), "not a text"),
    ] {
        open(&mut editor, "bad.json", bytes);
        let notice = editor.model.notice().unwrap();
        assert!(notice.is_error, "{}", notice.text);
        assert!(notice.text.contains(words), "{}", notice.text);
        assert!(
            notice.text.contains("Nothing was changed"),
            "{}",
            notice.text
        );
        assert_eq!(editor.model.scene(), before);
    }
}

#[test]
fn a_lift_the_host_runs_is_applied_when_it_comes_back_and_cancel_drops_it() {
    // Catches: a lift run on the editor's thread where the host takes jobs, a reply to a
    // cancelled request applied, or a failure in the worker that is not told.
    let host = MemoryHost::default();
    host.inner.borrow_mut().runs_jobs = true;
    let mut editor = Clocked::with_host(host.clone());
    let before = editor.model.scene();
    let s = body();
    open(
        &mut editor,
        "k.json",
        keypoints_file(&s, &[reaching(&s, DVec3::ZERO)]),
    );
    assert!(editor.model.lifting().is_some(), "the busy notice shows");
    assert_eq!(editor.model.scene(), before, "nothing changes meanwhile");
    let request = host.inner.borrow().jobs.last().cloned().unwrap();
    assert_eq!(request.job.kind(), "lift");
    // The trip through bytes, as the page's worker takes it.
    let job = HostJob::from_bytes(&request.job.to_bytes().unwrap()).unwrap();
    assert_eq!(job, request.job);

    editor.apply(Command::Keypoints(KeypointsCommand::Cancel));
    assert!(editor.model.lifting().is_none());
    assert_eq!(host.inner.borrow().cancelled_jobs, vec![request.id]);
    let late = job.clone().run(&mut |_| {}).unwrap();
    let stance_model::JobOutput::Lift(scene) = late else {
        panic!("a lift's output");
    };
    editor.model.receive(HostMessage::KeypointsLifted {
        id: request.id,
        result: Ok(scene.clone()),
    });
    assert_eq!(
        editor.model.scene(),
        before,
        "a cancelled lift's reply is ignored"
    );

    open(
        &mut editor,
        "k.json",
        keypoints_file(&s, &[reaching(&s, DVec3::ZERO)]),
    );
    let failed = host.inner.borrow().jobs.last().cloned().unwrap();
    // The page hands ids to its worker and back as JavaScript numbers (f64): each lift's id
    // must come back as itself (at 2^63 the second came back as the first's).
    for id in [request.id, failed.id] {
        assert_eq!(id as f64 as u64, id, "the request id {id} is no exact f64");
    }
    assert_ne!(request.id as f64, failed.id as f64);
    editor.model.receive(HostMessage::JobFailed {
        id: failed.id,
        reason: "the loading worker stopped".to_owned(),
    });
    assert!(
        editor
            .model
            .notice()
            .unwrap()
            .text
            .contains("worker stopped")
    );
    assert_eq!(editor.model.scene(), before);

    open(
        &mut editor,
        "k.json",
        keypoints_file(&s, &[reaching(&s, DVec3::ZERO)]),
    );
    let answered = host.inner.borrow().jobs.last().cloned().unwrap();
    editor.model.receive(HostMessage::KeypointsLifted {
        id: answered.id,
        result: Ok(scene),
    });
    assert_eq!(editor.model.character().name(), "Person 1");
    assert!(editor.model.lifting().is_none());
}

#[test]
fn a_flip_the_keypoints_undo_is_refused_by_name_and_changes_nothing() {
    // Catches: a flip that does not fit the keypoints told as done (or recorded as a step), or
    // a flip whose failure changes the posture. On this view and posture the right elbow in
    // front of the shoulder does not fit its keypoints within the shoulder's range:
    // `stance_lift::flip_depth`'s closed form stops about 70 mm from the mirrored elbow.
    let s = body();
    let posture = reaching(&s, DVec3::ZERO);
    let mut editor = Clocked::new();
    let file = keypoints_seen_by(&s, std::slice::from_ref(&posture), &front_camera());
    open(&mut editor, "reaching.json", file);
    let limbs = editor.model.flippable_limbs();
    assert!(limbs.contains(&("right arm", "r_elbow")), "{limbs:?}");
    let depth = arm_depth(&editor);
    assert!(
        depth > 0.1,
        "the lift put the elbow {depth:.3} m behind the shoulder"
    );
    let lifted = editor.model.session().posture().clone();
    editor.apply(Command::Keypoints(KeypointsCommand::Flip {
        joint: "r_elbow".to_owned(),
    }));
    let notice = editor.model.notice().unwrap();
    assert!(notice.is_error, "{}", notice.text);
    assert!(
        notice.text.contains("right arm could not be flipped"),
        "{}",
        notice.text
    );
    assert!(notice.text.contains("joints' ranges"), "{}", notice.text);
    assert_eq!(editor.model.session().posture(), &lifted);
    assert!(editor.model.lifting().is_none());
}

#[test]
fn only_lifted_characters_offer_a_flip() {
    // Catches: flips offered (or carried out) on a character with no keypoints to solve.
    let mut editor = Clocked::new();
    assert!(editor.model.flippable_limbs().is_empty());
    let before = editor.model.session().posture().clone();
    editor.apply(Command::Keypoints(KeypointsCommand::Flip {
        joint: "r_elbow".to_owned(),
    }));
    assert!(editor.model.notice().unwrap().is_error);
    assert_eq!(editor.model.session().posture(), &before);
}
