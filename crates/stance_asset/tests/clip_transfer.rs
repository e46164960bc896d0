//! A clip file opened on another thread: the job (file, body, settings) and the opened clip
//! cross as bytes and come back the same; damaged bytes are refused by name, never a panic.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use stance_asset::{ClipJob, ClipTransfer, FRAMES_PER_PART, LoadOptions, OpenedClip, load_avatar};
use stance_hanim::{LevelOfArticulation, SkeletonOptions, default_skeleton};
use stance_motion::{RetargetOptions, retarget};

const WALK: &[u8] = include_bytes!("../../../tests/fixtures/motion/walk.bvh");

fn mannequin() -> stance_hanim::HumanoidSkeleton {
    default_skeleton(&SkeletonOptions {
        loa: LevelOfArticulation::Loa1,
        ..Default::default()
    })
    .unwrap()
}

#[path = "../../../tests/fixtures/motion/long_walk.rs"]
mod long_walk;
use long_walk::long_walk;

// Catches a body that changes on the trip (a limit, a stiffness, the joints' order or the
// avatar's rest match lost): the worker would retarget onto another body than the editor's.
#[test]
fn the_job_crosses_with_the_same_body_and_settings() {
    let avatar = load_avatar(&crate::common::default_glb(), &LoadOptions::default()).unwrap();
    let on_avatar = avatar.skeleton(&SkeletonOptions::default()).unwrap();
    for body in [mannequin(), on_avatar] {
        let job = ClipJob {
            name: "walk.bvh".into(),
            bytes: WALK.into(),
            body,
            options: RetargetOptions::default().with_arm_lift(12.0),
            mapping: None,
        };
        let back = ClipJob::from_bytes(&job.to_bytes().unwrap()).unwrap();
        assert_eq!(back, job);
    }
}

// Catches a corrected mapping lost on the way or not applied: the worker would put the clip
// on the body as the file maps it, not as the user corrected it; and a mapping made for
// another clip taken as it is.
#[test]
fn a_corrected_mapping_crosses_and_is_applied() {
    let clip =
        stance_asset::read_clip("walk.bvh", WALK, &LoadOptions::default(), &mut |_| None).unwrap();
    let mut mapping = clip.mapping.clone();
    assert!(mapping.remove("l_elbow"), "the walk maps an elbow");
    let job = ClipJob {
        name: "walk.bvh".into(),
        bytes: WALK.into(),
        body: mannequin(),
        options: RetargetOptions::default(),
        mapping: Some(mapping.clone()),
    };
    let back = ClipJob::from_bytes(&job.to_bytes().unwrap()).unwrap();
    assert_eq!(back, job);
    let opened = back.run(&mut |_| {}).unwrap();
    assert_eq!(opened.clip.mapping, mapping);
    assert_eq!(opened.clip.mapping.get("l_elbow"), None);
    let other = ClipJob {
        mapping: Some(stance_hanim::Mapping::empty(clip.joints.len() + 1)),
        ..job
    };
    let error = other.run(&mut |_| {}).unwrap_err();
    assert!(error.contains("corrected mapping"), "{error}");
}

// Catches a worker whose clip differs from the one the editor would open itself: the same
// postures, contacts and notes as the one-shot retargeting, with the clip as read, over
// several parts of frames.
#[test]
fn the_opened_clip_crosses_in_parts_and_is_the_one_shot_retargeting() {
    let frames = FRAMES_PER_PART + 300;
    let bytes = long_walk(frames);
    let options = RetargetOptions {
        contacts: None,
        ..Default::default()
    };
    let job = ClipJob {
        name: "long.bvh".into(),
        bytes: bytes.clone().into(),
        body: mannequin(),
        options: options.clone(),
        mapping: None,
    };
    let dofs = job.body.skeleton.dof_count();
    let mut reports = Vec::new();
    let opened = job.run(&mut |p| reports.push(p)).unwrap();
    assert!(reports.windows(2).all(|w| w[1] >= w[0]), "{reports:?}");
    assert_eq!(reports.last(), Some(&1.0));
    assert!(reports.len() > frames / stance_asset::FRAMES_PER_STEP / 2);
    let clip = stance_asset::read_clip("long.bvh", &bytes, &LoadOptions::default(), &mut |_| None)
        .unwrap();
    let mut whole = retarget(&clip, &mannequin(), &options).unwrap();
    whole.copy.clear();
    let transfer = ClipTransfer::new(&opened).unwrap();
    assert_eq!(transfer.parts.len(), 2);
    let back = transfer.into_opened(dofs).unwrap();
    assert_eq!(back.clip, clip);
    assert_eq!(back.retargeted, whole);
    assert_eq!(
        back,
        OpenedClip {
            clip,
            retargeted: whole
        }
    );
}

// Catches a damaged or mismatched transfer that panics or is taken (a truncated message, a
// result for a body of other DOF): each is refused with a reason.
#[test]
fn damaged_transfers_are_refused_by_name() {
    let job = ClipJob {
        name: "walk.bvh".into(),
        bytes: WALK.into(),
        body: mannequin(),
        options: RetargetOptions {
            contacts: None,
            ..Default::default()
        },
        mapping: None,
    };
    let dofs = job.body.skeleton.dof_count();
    let encoded = job.to_bytes().unwrap();
    for cut in (0..encoded.len()).step_by(97) {
        assert!(ClipJob::from_bytes(&encoded[..cut]).is_err());
    }
    let opened = job.run(&mut |_| {}).unwrap();
    let transfer = ClipTransfer::new(&opened).unwrap();
    let wrong_body = transfer.clone().into_opened(dofs + 1).unwrap_err();
    assert!(
        wrong_body.to_string().contains("do not add up"),
        "{wrong_body}"
    );
    for cut in (0..transfer.head.len()).step_by(13) {
        let mut damaged = transfer.clone();
        damaged.head.truncate(cut);
        assert!(damaged.into_opened(dofs).is_err());
    }
    for cut in (0..transfer.parts[0].len()).step_by(1009) {
        let mut damaged = transfer.clone();
        damaged.parts[0].truncate(cut);
        assert!(damaged.into_opened(dofs).is_err());
    }
    let mut missing = transfer.clone();
    missing.parts.clear();
    let error = missing.into_opened(dofs).unwrap_err().to_string();
    assert!(error.contains("0 frames"), "{error}");
}

// Catches a file that is not a clip crashing the worker or coming back without words.
#[test]
fn a_file_that_is_not_a_clip_says_why() {
    let job = ClipJob {
        name: "broken.bvh".into(),
        bytes: b"HIERARCHY\nROOT hips\n{".as_slice().into(),
        body: mannequin(),
        options: RetargetOptions::default(),
        mapping: None,
    };
    let error = job.run(&mut |_| {}).unwrap_err();
    assert!(
        error.starts_with("broken.bvh could not be opened as a clip"),
        "{error}"
    );
}

/// Writes the seeds of the `clip_transfer` fuzz target (see its header): a 10-frame walk's
/// job, and its opened clip on the LOA1 mannequin as a transfer.
#[cfg(not(target_arch = "wasm32"))]
#[test]
#[ignore = "writes fuzz/seeds/clip_transfer/"]
fn write_clip_transfer_seeds() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds/clip_transfer");
    std::fs::create_dir_all(&dir).unwrap();
    let job = ClipJob {
        name: "walk.bvh".into(),
        bytes: long_walk(10).into(),
        body: mannequin(),
        options: RetargetOptions::default(),
        mapping: None,
    };
    let mut seed = vec![0];
    seed.extend(job.to_bytes().unwrap());
    std::fs::write(dir.join("job.bin"), seed).unwrap();
    let dofs = u8::try_from(job.body.skeleton.dof_count()).unwrap();
    let transfer = ClipTransfer::new(&job.run(&mut |_| {}).unwrap()).unwrap();
    let mut seed = vec![1, dofs];
    seed.extend(crate::common::parts::join_parts(
        std::iter::once(&transfer.head).chain(&transfer.parts),
    ));
    std::fs::write(dir.join("opened.bin"), seed).unwrap();
}
