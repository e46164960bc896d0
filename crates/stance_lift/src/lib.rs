//! A posture lifted from 2D keypoints (`stance lift`): an OpenPose keypoints JSON read back
//! ([`ObservedPose`]), and for one person each visible keypoint's body point (the definition
//! `stance_hanim::keypoints` renders them with) kept on the camera ray through its pixel, a
//! point-on-a-line task at level 1; below it the feet on the floor, balance and comfort, so
//! that the solver picks a plausible posture among those that project the same ([`lift`]).
//! The camera is the one the keypoints were seen with, or one fitted to them. What a single
//! image cannot tell, a limb toward the camera or away from it, is undone by [`flip_depth`]
//! and a new [`solve`].

#![warn(missing_docs)]

mod flip;
mod lift;
mod place;
mod read;
mod stages;

pub use flip::flip_depth;
pub use lift::{Lifted, camera_spec, lift, lift_people, lifted_scene, solve};
pub use read::ObservedPose;

/// Why keypoints cannot be lifted. The messages are meant for the person who gave them.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LiftError {
    /// The JSON is not OpenPose keypoints (says what it is).
    #[error("not OpenPose keypoints: {0}")]
    NotOpenPose(String),
    /// Neither the file nor the caller gives the image's size.
    #[error(
        "the keypoints file gives no image size (canvas_width, canvas_height): give the size of the image they were found in"
    )]
    NoImageSize,
    /// The file lists nobody.
    #[error("the keypoints file lists no person (`people` is empty)")]
    NoPeople,
    /// One person of several (1-based) could not be lifted.
    #[error("person {0}: {1}")]
    Person(usize, Box<LiftError>),
    /// Every keypoint of the person is missing.
    #[error("every keypoint of the person is missing (0, 0, 0): nothing to lift")]
    NoKeypoints,
    /// Too few body keypoints to place the body.
    #[error(
        "{0} body keypoints seen: at least two joined by a bone (a shoulder and its elbow, a hip and its knee...) are needed to tell the body's size"
    )]
    TooFewKeypoints(usize),
    /// The camera's numbers make no view.
    #[error("bad camera: {0}")]
    BadCamera(String),
    /// A joint name the body does not have.
    #[error("the body has no joint `{0}`")]
    UnknownJoint(String),
    /// A joint with no turning parent (the root).
    #[error("`{0}` has no parent joint that turns: its depth cannot be flipped")]
    CannotFlip(String),
    /// The limb flipped in depth does not fit its keypoints within the joints' ranges.
    #[error(
        "`{joint}` on the other side in depth does not fit its keypoints within the joints' ranges (its closed form stops {off_mm:.0} mm from the mirrored place): it stays on its side"
    )]
    FlipOutOfRange {
        /// The joint asked to flip.
        joint: String,
        /// How far the limb's closed form stops from the mirrored place (mm).
        off_mm: f64,
    },
    /// The tasks could not be solved (an inconsistent body).
    #[error("the lift's problem cannot be solved: {0}")]
    Problem(String),
}

// Known limits (measured, docs/control-maps.md): a flip of an arm whose hand's keypoints are
// given can leave the hand's keypoints 9-11 px off (the flip moves the wrist in depth, and the
// rigid palm cannot match its keypoints at another size in the image: no turn of it does); a fitted camera leaves keypoints a few
// pixels off (its pitch and distance are the default's); on a random family of standing
// postures (examples/lift_bench, held-out seed) 4 of 20 lifts end over 2 px off (up to 10.3
// px: a hand's keypoints, where its arm's depth or the wrist's range leaves them; hips 2-3 px)
// and 4 of 20 take over 50 ms of CPU on a shared 2-core machine (the pose stage and the flip
// search); on a second family (arms raised, crouched, seated-looking) 4 of 21 end over 2 px
// (up to 19.4 px: a seated one seen from behind, whose start leads astray).
