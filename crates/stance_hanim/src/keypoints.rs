//! Pose keypoints on an H-Anim body: the 18 body points of OpenPose's COCO model and the 21
//! points of each hand, as world positions in a posture (the control maps of image
//! generation draw them; `stance_render::openpose` projects them).
//!
//! # Body (COCO-18, OpenPose's order)
//! | # | keypoint | on the body |
//! |---|---|---|
//! | 0 | nose | the tip of the nose, [`HeadSite::Pronasale`] |
//! | 1 | neck | the midpoint of the two shoulder joints |
//! | 2-4 | right shoulder, elbow, wrist | `r_shoulder`, `r_elbow`, `r_radiocarpal` |
//! | 5-7 | left shoulder, elbow, wrist | `l_shoulder`, `l_elbow`, `l_radiocarpal` |
//! | 8-10 | right hip, knee, ankle | `r_hip`, `r_knee`, `r_talocrural` |
//! | 11-13 | left hip, knee, ankle | `l_hip`, `l_knee`, `l_talocrural` |
//! | 14, 15 | right eye, left eye | the pupils, [`HeadSite::RightPupil`], [`HeadSite::LeftPupil`] |
//! | 16, 17 | right ear, left ear | [`HeadSite::RightTragion`], [`HeadSite::LeftTragion`] |
//!
//! COCO's 17 annotated points have no neck; OpenPose's COCO-18 model adds one, made for its
//! training data as the midpoint of the two annotated shoulders. The same midpoint is taken
//! here (rather than H-Anim's `vc*` or `skullbase` joints, which sit higher and further back):
//! a detector trained on it, and the ControlNet models trained on such detections, expect the
//! neck between the shoulders.
//!
//! # Hands (OpenPose's 21)
//! 0 the wrist (`*_radiocarpal`); then per digit, thumb to little finger, four points from
//! the palm outwards: the thumb's `carpometacarpal_1`, `metacarpophalangeal_1`,
//! `carpal_interphalangeal_1` and tip; each finger's `metacarpophalangeal_n` (the knuckle),
//! `carpal_proximal_interphalangeal_n`, `carpal_distal_interphalangeal_n` and tip. H-Anim has
//! no fingertip joint: a tip is [`HandRig::fingertip`]'s, beyond the last joint. A body without
//! finger joints (LOA 1) has no hand points.

use glam::DVec3;
use stance_ik::{Effector, Frames, Skeleton};

use crate::hands::{Finger, FingerJoint, HandRig};
use crate::names::{Side, resolve_joint};
use crate::sites::{HeadSite, HeadSites};

/// Number of body keypoints (COCO-18).
pub const BODY_KEYPOINTS: usize = 18;
/// Number of keypoints of one hand.
pub const HAND_KEYPOINTS: usize = 21;

/// The index of the neck among the body keypoints.
pub const NECK: usize = 1;

/// The body keypoints' names in OpenPose's COCO-18 order (as OpenPose's `poseParameters`
/// names them).
pub const BODY_KEYPOINT_NAMES: [&str; BODY_KEYPOINTS] = [
    "Nose",
    "Neck",
    "RShoulder",
    "RElbow",
    "RWrist",
    "LShoulder",
    "LElbow",
    "LWrist",
    "RHip",
    "RKnee",
    "RAnkle",
    "LHip",
    "LKnee",
    "LAnkle",
    "REye",
    "LEye",
    "REar",
    "LEar",
];

/// Where one body keypoint is found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BodySource {
    /// A joint's centre (H-Anim name, found through aliases too).
    Joint(&'static str),
    /// A landmark on the head.
    Site(HeadSite),
    /// The midpoint of two joints' centres.
    Midpoint(&'static str, &'static str),
}

/// Where each body keypoint is found, in COCO-18 order.
pub const BODY_SOURCES: [BodySource; BODY_KEYPOINTS] = [
    BodySource::Site(HeadSite::Pronasale),
    BodySource::Midpoint("l_shoulder", "r_shoulder"),
    BodySource::Joint("r_shoulder"),
    BodySource::Joint("r_elbow"),
    BodySource::Joint("r_radiocarpal"),
    BodySource::Joint("l_shoulder"),
    BodySource::Joint("l_elbow"),
    BodySource::Joint("l_radiocarpal"),
    BodySource::Joint("r_hip"),
    BodySource::Joint("r_knee"),
    BodySource::Joint("r_talocrural"),
    BodySource::Joint("l_hip"),
    BodySource::Joint("l_knee"),
    BodySource::Joint("l_talocrural"),
    BodySource::Site(HeadSite::RightPupil),
    BodySource::Site(HeadSite::LeftPupil),
    BodySource::Site(HeadSite::RightTragion),
    BodySource::Site(HeadSite::LeftTragion),
];

/// The keypoints of one body in one posture: world positions (m), `None` where the body has
/// no such point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseKeypoints {
    /// COCO-18, in OpenPose's order ([`BODY_KEYPOINT_NAMES`]).
    pub body: [Option<DVec3>; BODY_KEYPOINTS],
    /// For the points on the head's surface (nose, eyes, ears), the world direction the
    /// surface faces there ([`HeadSite::facing`]): seen only from that side. `None` for the
    /// joints, which lie inside the body.
    pub body_facing: [Option<DVec3>; BODY_KEYPOINTS],
    /// The left hand's 21 points (the body's left).
    pub left_hand: [Option<DVec3>; HAND_KEYPOINTS],
    /// The right hand's 21 points.
    pub right_hand: [Option<DVec3>; HAND_KEYPOINTS],
}

/// Where one keypoint lies on the body, as points of its segments (what a solver task can
/// hold): one point of a segment, or the midpoint of two (the neck, between the shoulders).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum KeypointSource {
    /// A point of one segment.
    On(Effector),
    /// The midpoint of two points.
    Between(Effector, Effector),
}

impl KeypointSource {
    /// Its world position in the posture of `frames`.
    pub fn position(&self, frames: &Frames) -> Option<DVec3> {
        let at = |e: &Effector| {
            (e.joint < frames.joint_position.len()).then(|| frames.point(e.joint, e.point))
        };
        match self {
            KeypointSource::On(e) => at(e),
            KeypointSource::Between(a, b) => Some((at(a)? + at(b)?) * 0.5),
        }
    }
}

/// Every keypoint of one skeleton as [`KeypointSource`]s, `None` where the body has none.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KeypointSources {
    /// COCO-18, in OpenPose's order.
    pub body: [Option<KeypointSource>; BODY_KEYPOINTS],
    /// The left hand's 21.
    pub left_hand: [Option<Effector>; HAND_KEYPOINTS],
    /// The right hand's 21.
    pub right_hand: [Option<Effector>; HAND_KEYPOINTS],
}

/// Finds the keypoints on one skeleton; built once, used for every posture.
#[derive(Debug, Clone)]
pub struct KeypointFinder {
    body: [Option<Located>; BODY_KEYPOINTS],
    head: Option<HeadSites>,
    hands: [Option<HandPoints>; 2],
}

/// A body keypoint resolved to the skeleton's joints.
#[derive(Debug, Clone, Copy)]
enum Located {
    Joint(usize),
    Site(HeadSite),
    Midpoint(usize, usize),
}

/// One hand's joints in OpenPose's order, and its rig for the fingertips.
#[derive(Debug, Clone)]
struct HandPoints {
    joints: [Option<usize>; HAND_KEYPOINTS],
    rig: HandRig,
}

impl KeypointFinder {
    /// The keypoints `skeleton` has.
    pub fn new(skeleton: &Skeleton) -> KeypointFinder {
        let head = HeadSites::new(skeleton);
        let body = BODY_SOURCES.map(|source| match source {
            BodySource::Joint(name) => resolve_joint(skeleton, name).map(Located::Joint),
            BodySource::Site(site) => head.map(|_| Located::Site(site)),
            BodySource::Midpoint(a, b) => Some(Located::Midpoint(
                resolve_joint(skeleton, a)?,
                resolve_joint(skeleton, b)?,
            )),
        });
        let hands = [Side::Left, Side::Right].map(|side| hand_points(skeleton, side));
        KeypointFinder { body, head, hands }
    }

    /// Where each keypoint lies on `skeleton` (the one the finder was made for), as points of
    /// its segments: what [`KeypointFinder::find`] places in a posture, and what a solver task
    /// holds (`stance_lift` keeps each on its camera ray).
    pub fn sources(&self, skeleton: &Skeleton) -> KeypointSources {
        let joint = |joint: usize| Effector {
            joint,
            point: DVec3::ZERO,
        };
        let body = self.body.map(|located| match located? {
            Located::Joint(index) => Some(KeypointSource::On(joint(index))),
            Located::Site(site) => Some(KeypointSource::On(self.head?.effector(site))),
            Located::Midpoint(a, b) => Some(KeypointSource::Between(joint(a), joint(b))),
        });
        let [left_hand, right_hand] = self.hands.each_ref().map(|hand| {
            hand.as_ref()
                .map_or([None; HAND_KEYPOINTS], |hand| hand.sources(skeleton))
        });
        KeypointSources {
            body,
            left_hand,
            right_hand,
        }
    }

    /// The keypoints in the posture of `frames` (forward kinematics of the skeleton the
    /// finder was made for).
    pub fn find(&self, skeleton: &Skeleton, frames: &Frames) -> PoseKeypoints {
        let sources = self.sources(skeleton);
        let body = sources.body.map(|source| source?.position(frames));
        let body_facing = self.body.map(|located| match located? {
            Located::Site(site) => self.head?.facing(frames, site),
            Located::Joint(_) | Located::Midpoint(..) => None,
        });
        let at = |e: Option<Effector>| KeypointSource::On(e?).position(frames);
        let left_hand = sources.left_hand.map(at);
        let right_hand = sources.right_hand.map(at);
        PoseKeypoints {
            body,
            body_facing,
            left_hand,
            right_hand,
        }
    }
}

/// The keypoints of `skeleton` in the posture of `frames` (a [`KeypointFinder`] made and used
/// once).
pub fn pose_keypoints(skeleton: &Skeleton, frames: &Frames) -> PoseKeypoints {
    KeypointFinder::new(skeleton).find(skeleton, frames)
}

/// Which finger joints give a digit's first three points (OpenPose's thumb starts at its
/// carpometacarpal joint, the fingers at their knuckles).
fn digit_roles(finger: Finger) -> [FingerJoint; 3] {
    use FingerJoint::*;
    match finger {
        Finger::Thumb => [
            Carpometacarpal,
            Metacarpophalangeal,
            ProximalInterphalangeal,
        ],
        _ => [
            Metacarpophalangeal,
            ProximalInterphalangeal,
            DistalInterphalangeal,
        ],
    }
}

fn hand_points(skeleton: &Skeleton, side: Side) -> Option<HandPoints> {
    let rig = HandRig::new(skeleton, side).ok()?;
    let mut joints = [None; HAND_KEYPOINTS];
    joints[0] = resolve_joint(skeleton, &format!("{}radiocarpal", side.prefix()));
    for (digit, finger) in Finger::ALL.into_iter().enumerate() {
        let Some(rigged) = rig.finger(finger) else {
            continue;
        };
        for (slot, role) in digit_roles(finger).into_iter().enumerate() {
            joints[1 + digit * 4 + slot] = rigged
                .joints
                .iter()
                .find(|joint| joint.role == role)
                .map(|joint| joint.joint);
        }
    }
    Some(HandPoints { joints, rig })
}

impl HandPoints {
    fn sources(&self, skeleton: &Skeleton) -> [Option<Effector>; HAND_KEYPOINTS] {
        let mut points = self.joints.map(|joint| {
            Some(Effector {
                joint: joint?,
                point: DVec3::ZERO,
            })
        });
        for (digit, finger) in Finger::ALL.into_iter().enumerate() {
            points[4 + digit * 4] = self.rig.fingertip_effector(skeleton, finger);
        }
        points
    }
}

#[cfg(test)]
mod tests {
    #[cfg(target_arch = "wasm32")]
    use wasm_bindgen_test::wasm_bindgen_test as test;

    use super::*;
    use crate::{LevelOfArticulation, SkeletonOptions, default_skeleton};
    use stance_ik::Posture;

    fn skeleton(loa: LevelOfArticulation) -> Skeleton {
        default_skeleton(&SkeletonOptions {
            loa,
            ..SkeletonOptions::default()
        })
        .unwrap()
        .skeleton
    }

    #[test]
    fn the_body_points_follow_cocos_order_by_name() {
        // Catches a swapped pair (left for right, eye for ear): each point is checked by the
        // name OpenPose gives its index against the joint or site it must come from.
        let skeleton = skeleton(LevelOfArticulation::Loa2);
        let rest = Frames::new(&skeleton, &Posture::rest(&skeleton));
        let points = pose_keypoints(&skeleton, &rest);
        let joint = |name| rest.joint_position[resolve_joint(&skeleton, name).unwrap()];
        let by_name = |name: &str| {
            let index = BODY_KEYPOINT_NAMES.iter().position(|n| *n == name).unwrap();
            points.body[index].unwrap()
        };
        for (name, hanim) in [
            ("RShoulder", "r_shoulder"),
            ("RElbow", "r_elbow"),
            ("RWrist", "r_radiocarpal"),
            ("LShoulder", "l_shoulder"),
            ("LElbow", "l_elbow"),
            ("LWrist", "l_radiocarpal"),
            ("RHip", "r_hip"),
            ("RKnee", "r_knee"),
            ("RAnkle", "r_talocrural"),
            ("LHip", "l_hip"),
            ("LKnee", "l_knee"),
            ("LAnkle", "l_talocrural"),
        ] {
            assert_eq!(by_name(name), joint(hanim), "{name}");
        }
        let neck = (joint("l_shoulder") + joint("r_shoulder")) * 0.5;
        assert_eq!(by_name("Neck"), neck);
        // The body's left is +X: left eye and ear at larger x than the right ones, the nose
        // between the eyes and in front of them, the ears behind the eyes.
        assert!(by_name("LEye").x > by_name("REye").x);
        assert!(by_name("LEar").x > by_name("LEye").x && by_name("REar").x < by_name("REye").x);
        assert!(by_name("Nose").z > by_name("LEye").z && by_name("LEye").z > by_name("LEar").z);
        assert!(by_name("Nose").y > neck.y && by_name("LEye").y > by_name("Nose").y);
    }

    #[test]
    fn hands_come_from_the_finger_joints_and_a_body_without_fingers_has_none() {
        let loa2 = skeleton(LevelOfArticulation::Loa2);
        let rest = Frames::new(&loa2, &Posture::rest(&loa2));
        let points = pose_keypoints(&loa2, &rest);
        for (hand, side) in [(points.left_hand, "l_"), (points.right_hand, "r_")] {
            assert!(hand.iter().all(Option::is_some), "{side}: {hand:?}");
            let joint = |name: &str| {
                rest.joint_position[resolve_joint(&loa2, &format!("{side}{name}")).unwrap()]
            };
            assert_eq!(hand[0], Some(joint("radiocarpal")));
            assert_eq!(hand[1], Some(joint("carpometacarpal_1")));
            assert_eq!(hand[5], Some(joint("metacarpophalangeal_2")));
            assert_eq!(hand[11], Some(joint("carpal_distal_interphalangeal_3")));
            // The tip beyond the last joint, away from the wrist.
            let last = joint("carpal_distal_interphalangeal_5");
            let tip = hand[20].unwrap();
            assert!((tip - joint("radiocarpal")).length() > (last - joint("radiocarpal")).length());
        }
        let loa1 = skeleton(LevelOfArticulation::Loa1);
        let rest = Frames::new(&loa1, &Posture::rest(&loa1));
        let points = pose_keypoints(&loa1, &rest);
        assert!(
            points
                .left_hand
                .iter()
                .chain(&points.right_hand)
                .all(Option::is_none)
        );
        assert!(points.body.iter().all(Option::is_some));
    }
}
