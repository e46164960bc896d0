//! *File > Open photo…*, driven by commands alone: the host's detector is stood in for by
//! MediaPipe-ordered landmarks made from a known posture's keypoints seen through a camera,
//! which the model turns into COCO-18 keypoints and lifts like a keypoints file; the photo
//! then stays behind the viewport. Bad photos change nothing. (The detector itself runs in
//! the browser: tests/photo.test.mjs.)

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use glam::Vec3;
use stance_hanim::keypoints::KeypointFinder;
use stance_hanim::{SkeletonOptions, default_skeleton};
use stance_ik::{Frames, Posture, Skeleton};
use stance_model::model::photo::{
    COCO18_FROM_MEDIAPIPE, DetectedPhoto, Landmark, MEDIAPIPE_LANDMARKS, coco18_from_landmarks,
    openpose_from_landmarks,
};
use stance_model::model::{HistoryCommand, KeypointsCommand};
use stance_model::{Command, HostMessage, MemoryHost};
use stance_render::{HiddenKeypoints, OpenPosePerson, OrbitCamera};

use crate::clocked::Clocked;

const SIZE: [u32; 2] = [640, 480];

fn body() -> Skeleton {
    default_skeleton(&SkeletonOptions::default())
        .unwrap()
        .skeleton
}

/// MediaPipe's 33 landmarks standing for the keypoints of `person` in an image of [`SIZE`]:
/// each COCO-18 point where MediaPipe has it, fully visible; the other landmarks (hands,
/// feet, mouth) invisible.
fn landmarks_of(person: &OpenPosePerson) -> Vec<Landmark> {
    let mut out = vec![
        Landmark {
            x: 0.5,
            y: 0.5,
            z: 0.0,
            visibility: 0.0,
        };
        MEDIAPIPE_LANDMARKS
    ];
    for (point, source) in person.body.iter().zip(COCO18_FROM_MEDIAPIPE) {
        if let (Some(p), Some(index)) = (point, source) {
            out[index] = Landmark {
                x: (p.x / f64::from(SIZE[0])) as f32,
                y: (p.y / f64::from(SIZE[1])) as f32,
                z: 0.0,
                visibility: 0.99,
            };
        }
    }
    out
}

fn photo(name: &str, landmarks: Vec<Landmark>) -> DetectedPhoto {
    DetectedPhoto {
        name: name.to_owned(),
        size_px: SIZE,
        landmarks,
        reference_rgba: vec![128; 32 * 24 * 4],
        reference_size_px: [32, 24],
        detect_ms: 12.0,
    }
}

/// The rest body seen from the front at [`SIZE`].
fn standing() -> (Skeleton, OpenPosePerson) {
    let s = body();
    let camera = OrbitCamera {
        target_world: Vec3::new(0.0, 0.9, 0.0),
        distance_m: 3.4,
        ..OrbitCamera::default()
    };
    let keypoints = KeypointFinder::new(&s).find(&s, &Frames::new(&s, &Posture::rest(&s)));
    let person = OpenPosePerson::seen(&keypoints, &camera, SIZE, &[], HiddenKeypoints::Keep);
    (s, person)
}

#[test]
fn mediapipe_landmarks_become_coco18_keypoints_in_the_photos_pixels() {
    // Catches: a landmark mapped to the wrong COCO-18 point or side, fractions not scaled
    // by the photo's size, a neck not at the shoulders' midpoint, or faint or outside
    // points kept.
    let mut landmarks: Vec<Landmark> = (0..MEDIAPIPE_LANDMARKS)
        .map(|i| Landmark {
            x: 0.01 * i as f32,
            y: 0.02 * i as f32,
            z: 0.0,
            visibility: 0.9,
        })
        .collect();
    landmarks[7].visibility = 0.2; // left ear: faint
    landmarks[28].x = 1.3; // right ankle: outside the picture
    let k = coco18_from_landmarks(&landmarks, [1000, 500]).unwrap();
    let at = |i: usize| [10.0 * i as f64, 10.0 * i as f64];
    let close = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).abs() < 1e-3 && (a[1] - b[1]).abs() < 1e-3;
    for (coco, mediapipe) in [
        (0, 0),
        (2, 12),
        (3, 14),
        (4, 16),
        (5, 11),
        (8, 24),
        (13, 27),
    ] {
        assert!(
            close(k[coco].unwrap(), at(mediapipe)),
            "COCO {coco}: {:?}",
            k[coco]
        );
    }
    assert!(close(k[1].unwrap(), [115.0, 115.0]), "the neck: {:?}", k[1]);
    assert!(
        close(k[14].unwrap(), at(5)),
        "the right eye is MediaPipe's 5"
    );
    assert_eq!(k[17], None, "a faint point is missing");
    assert_eq!(k[10], None, "a point outside the picture is missing");

    landmarks[11].visibility = 0.0;
    let k = coco18_from_landmarks(&landmarks, [1000, 500]).unwrap();
    assert_eq!(k[1], None, "no neck without both shoulders");

    let error = coco18_from_landmarks(&landmarks[..17], [1000, 500]).unwrap_err();
    assert!(error.contains("17 landmarks"), "{error}");
    let json = openpose_from_landmarks(&landmarks, [1000, 500]).unwrap();
    assert!(json.contains("\"canvas_width\":1000"), "{json}");
}

#[test]
fn a_photos_person_is_lifted_and_the_photo_stays_behind_the_view() {
    // Catches: the detection not reaching the lift, a camera not fitted to the photo's size
    // (the keypoints off their pixels), the photo not kept or not shown, or a lift that
    // undo does not take back in one step.
    let (_, person) = standing();
    let mut editor = Clocked::new();
    let before = editor.model.scene();
    editor.apply(Command::from(HostMessage::PhotoDetected(Box::new(photo(
        "skier.jpg",
        landmarks_of(&person),
    )))));
    let notice = editor.model.notice().unwrap();
    assert!(!notice.is_error, "{}", notice.text);
    assert!(notice.text.contains("Lifted skier.jpg"), "{}", notice.text);
    assert!(
        notice.text.contains("photo is behind the view"),
        "{}",
        notice.text
    );
    let shown = editor.model.photo().expect("the photo is kept");
    assert_eq!(shown.size_px, SIZE);
    assert_eq!(shown.reference_size_px, [32, 24]);
    assert!(shown.keypoints[1].is_some(), "the neck is made");
    assert!(editor.model.photo_shown());
    // The lifted posture seen through its saved view (fitted to a 640x480 image) lands on
    // the detections.
    let view = editor.model.session().camera().unwrap();
    let view = OrbitCamera::saved(
        view.target,
        view.yaw,
        view.pitch,
        view.distance,
        view.orthographic,
    );
    let skeleton = editor.model.session().skeleton().clone();
    let keypoints = KeypointFinder::new(&skeleton).find(
        &skeleton,
        &Frames::new(&skeleton, editor.model.session().posture()),
    );
    let again = OpenPosePerson::seen(&keypoints, &view, SIZE, &[], HiddenKeypoints::Keep);
    let worst = person
        .body
        .iter()
        .zip(&again.body)
        .filter_map(|(p, q)| Some((*p.as_ref()? - *q.as_ref()?).length()))
        .fold(0.0, f64::max);
    assert!(
        worst < 5.0,
        "the lifted keypoints are {worst:.2} px off the detections"
    );

    editor.apply(Command::Keypoints(KeypointsCommand::ShowPhoto(false)));
    assert!(!editor.model.photo_shown());
    editor.apply(Command::History(HistoryCommand::Undo));
    assert_eq!(editor.model.scene(), before, "undo restores the scene");
}

#[test]
fn a_photo_that_cannot_be_read_or_lifted_says_why_and_changes_nothing() {
    // Catches: a failed photo replacing the scene or the photo shown, or a notice that does
    // not name the problem.
    let mut editor = Clocked::new();
    let before = editor.model.scene();
    let nobody = vec![
        Landmark {
            x: 0.5,
            y: 0.5,
            z: 0.0,
            visibility: 0.1,
        };
        MEDIAPIPE_LANDMARKS
    ];
    for (command, words) in [
        (
            Command::from(HostMessage::PhotoFailed {
                name: "notes.txt".to_owned(),
                reason: "it is not an image this browser can decode".to_owned(),
            }),
            "notes.txt could not be opened as a photo: it is not an image",
        ),
        (
            Command::from(HostMessage::PhotoDetected(Box::new(photo(
                "faint.jpg",
                nobody,
            )))),
            "faint.jpg could not be lifted",
        ),
        (
            Command::from(HostMessage::PhotoDetected(Box::new(photo(
                "few.jpg",
                Vec::new(),
            )))),
            "the detector gave 0 landmarks",
        ),
        (
            Command::from(HostMessage::PhotoDetected(Box::new(DetectedPhoto {
                reference_size_px: [u32::MAX, u32::MAX],
                ..photo("torn.jpg", landmarks_of(&standing().1))
            }))),
            "torn.jpg could not be opened as a photo: its pixels did not arrive whole",
        ),
    ] {
        editor.apply(command);
        let notice = editor.model.notice().unwrap();
        assert!(notice.is_error, "{}", notice.text);
        assert!(notice.text.contains(words), "{}", notice.text);
        assert!(
            notice.text.contains("Nothing was changed"),
            "{}",
            notice.text
        );
        assert_eq!(editor.model.scene(), before);
        assert!(editor.model.photo().is_none());
    }
}

#[test]
fn open_photo_asks_the_host_and_says_so_where_it_has_no_detector() {
    // Catches: the menu entry not reaching the host, or a silent failure where the shell
    // cannot detect poses.
    let host = MemoryHost::default();
    let mut editor = Clocked::with_host(host.clone());
    editor.apply(Command::Keypoints(KeypointsCommand::PickPhoto));
    assert_eq!(host.inner.borrow().photo_requests, 1);

    let mut plain = stance_model::EditorModel::new(Box::new(stance_model::NoHostHooks)).unwrap();
    plain.apply(Command::Keypoints(KeypointsCommand::PickPhoto));
    let notice = plain.notice().unwrap();
    assert!(
        notice.is_error && notice.text.contains("no pose detector"),
        "{}",
        notice.text
    );
}

#[test]
fn photo_after_photo_each_lift_answered_through_the_pages_numbers() {
    // Catches: lift request ids the page cannot carry exactly (it holds them as JavaScript
    // numbers, f64): from the second lift on, the reply came back with another id and was
    // dropped, the editor left lifting for ever.
    let host = MemoryHost::default();
    host.inner.borrow_mut().runs_jobs = true;
    let mut editor = Clocked::with_host(host.clone());
    let (_, person) = standing();
    for round in 0..3 {
        editor.apply(Command::from(HostMessage::PhotoDetected(Box::new(photo(
            &format!("photo-{round}.jpg"),
            landmarks_of(&person),
        )))));
        let request = host.inner.borrow().jobs.last().cloned().unwrap();
        // The page's trip: the id as a JavaScript number, the job run by the worker.
        let id = request.id as f64 as u64;
        assert_eq!(
            id, request.id,
            "request {round}'s id survives the page's numbers"
        );
        let result =
            stance_model::HostJob::run_for_transfer(&request.job.to_bytes().unwrap(), &mut |_| {})
                .unwrap();
        let Ok(stance_model::JobHead::Lift(scene)) = stance_model::JobHead::from_bytes(&result[0])
        else {
            panic!("a lift's head");
        };
        editor.apply(Command::from(HostMessage::KeypointsLifted {
            id,
            result: Ok(Box::new(scene)),
        }));
        assert!(editor.model.lifting().is_none(), "photo {round} lifted");
        let notice = editor.model.notice().unwrap();
        assert!(
            notice.text.contains(&format!("Lifted photo-{round}.jpg")),
            "{}",
            notice.text
        );
    }
}
