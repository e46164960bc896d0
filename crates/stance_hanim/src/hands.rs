//! Hand poses: presets (relaxed, fist, open, point, pinch, grip) and finger curl, on any
//! skeleton mapped onto H-Anim that has finger joints (LOA 2 and above, or an avatar's hands).
//!
//! # The H-Anim finger joints
//! Digits are numbered as in H-Anim 2.0: 1 the thumb, 2 the index, 3 the middle, 4 the ring
//! and 5 the little finger. The thumb is `*_carpometacarpal_1`, `*_metacarpophalangeal_1`,
//! `*_carpal_interphalangeal_1`; each finger `n` of 2 to 5 is `*_carpometacarpal_n` (a few
//! degrees of cupping of the palm), `*_metacarpophalangeal_n` (the knuckle),
//! `*_carpal_proximal_interphalangeal_n` and `*_carpal_distal_interphalangeal_n`. Joints are
//! found through the H-Anim aliases too (`l_index1`...); missing ones are skipped.
//!
//! # Which way is flexion
//! Nothing here assumes a sign or an axis: an avatar's hand may rest in any direction and its
//! joints' DOF may be permuted (see [`crate::builder`]). The palm's normal comes from the rest
//! geometry of the hand (the wrist, the finger bases and which side the hand is on: the left
//! hand is the mirror image of the right one), and for each finger joint the DOF whose axis
//! best turns its segment toward the palm carries flexion, with the sign that does. Spreading
//! the fingers (abduction) is found the same way, in the plane of the palm, away from the
//! middle finger (for the thumb, away from the fingers). A preset or a curl gives each motion a
//! fraction of the joint's range in that direction, so every value is within the joint's limits.

use glam::DVec3;
use stance_ik::{Effector, Frames, Posture, Skeleton};

use crate::names::{Side, resolve_joint};

/// Smallest alignment (cosine) of a DOF axis with the wanted axis for the DOF to carry a motion.
const MIN_ALIGNMENT: f64 = 0.2;
/// The reach of a motion whose DOF has no finite limit in that direction (rad).
const UNLIMITED_REACH: f64 = std::f64::consts::FRAC_PI_2;
/// How far apart the thumb and index tips stay in a pinch (m): the two finger pads.
const PINCH_GAP_M: f64 = 0.012;
/// The pinch search's first step, smallest step and most rounds (rad, rad, count).
const PINCH_FIRST_STEP: f64 = 0.2;
const PINCH_LAST_STEP: f64 = 1e-3;
const PINCH_MAX_ROUNDS: usize = 400;
/// The distal phalanx's length over the middle phalanx's: the fingertip is this far beyond the
/// last joint, along the segment before it (the H-Anim skeleton has no fingertip joint).
const TIP_RATIO: f64 = 0.8;

/// A digit of the hand, numbered as in H-Anim (1 the thumb to 5 the little finger).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Finger {
    /// Digit 1.
    Thumb,
    /// Digit 2.
    Index,
    /// Digit 3.
    Middle,
    /// Digit 4.
    Ring,
    /// Digit 5.
    Little,
}

/// A joint of a digit, proximal first.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FingerJoint {
    /// `*_carpometacarpal_n`: the thumb's base, or the cupping of a finger's metacarpal.
    Carpometacarpal,
    /// `*_metacarpophalangeal_n`: the knuckle.
    Metacarpophalangeal,
    /// `*_carpal_proximal_interphalangeal_n`, and the thumb's one interphalangeal joint
    /// (`*_carpal_interphalangeal_1`).
    ProximalInterphalangeal,
    /// `*_carpal_distal_interphalangeal_n` (fingers 2 to 5).
    DistalInterphalangeal,
}

impl FingerJoint {
    fn slot(self) -> usize {
        match self {
            FingerJoint::Carpometacarpal => 0,
            FingerJoint::Metacarpophalangeal => 1,
            FingerJoint::ProximalInterphalangeal => 2,
            FingerJoint::DistalInterphalangeal => 3,
        }
    }
}

impl Finger {
    /// The five, thumb first.
    pub const ALL: [Finger; 5] = [
        Finger::Thumb,
        Finger::Index,
        Finger::Middle,
        Finger::Ring,
        Finger::Little,
    ];

    /// The H-Anim digit number, 1 (thumb) to 5 (little finger).
    pub fn number(self) -> u8 {
        match self {
            Finger::Thumb => 1,
            Finger::Index => 2,
            Finger::Middle => 3,
            Finger::Ring => 4,
            Finger::Little => 5,
        }
    }

    /// The everyday name: "thumb", "index"...
    pub fn name(self) -> &'static str {
        match self {
            Finger::Thumb => "thumb",
            Finger::Index => "index",
            Finger::Middle => "middle",
            Finger::Ring => "ring",
            Finger::Little => "little",
        }
    }

    /// The H-Anim joints of the digit without their side prefix, proximal first.
    pub fn joints(self) -> &'static [(FingerJoint, &'static str)] {
        use FingerJoint::*;
        match self {
            Finger::Thumb => &[
                (Carpometacarpal, "carpometacarpal_1"),
                (Metacarpophalangeal, "metacarpophalangeal_1"),
                (ProximalInterphalangeal, "carpal_interphalangeal_1"),
            ],
            Finger::Index => &[
                (Carpometacarpal, "carpometacarpal_2"),
                (Metacarpophalangeal, "metacarpophalangeal_2"),
                (ProximalInterphalangeal, "carpal_proximal_interphalangeal_2"),
                (DistalInterphalangeal, "carpal_distal_interphalangeal_2"),
            ],
            Finger::Middle => &[
                (Carpometacarpal, "carpometacarpal_3"),
                (Metacarpophalangeal, "metacarpophalangeal_3"),
                (ProximalInterphalangeal, "carpal_proximal_interphalangeal_3"),
                (DistalInterphalangeal, "carpal_distal_interphalangeal_3"),
            ],
            Finger::Ring => &[
                (Carpometacarpal, "carpometacarpal_4"),
                (Metacarpophalangeal, "metacarpophalangeal_4"),
                (ProximalInterphalangeal, "carpal_proximal_interphalangeal_4"),
                (DistalInterphalangeal, "carpal_distal_interphalangeal_4"),
            ],
            Finger::Little => &[
                (Carpometacarpal, "carpometacarpal_5"),
                (Metacarpophalangeal, "metacarpophalangeal_5"),
                (ProximalInterphalangeal, "carpal_proximal_interphalangeal_5"),
                (DistalInterphalangeal, "carpal_distal_interphalangeal_5"),
            ],
        }
    }

    fn index(self) -> usize {
        usize::from(self.number() - 1)
    }
}

/// A named hand pose.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum HandPreset {
    /// The hand at ease: fingers slightly flexed, more so toward the little finger.
    Relaxed,
    /// Every finger closed, the thumb across them.
    Fist,
    /// Fingers straight and spread, the thumb away from them.
    Open,
    /// The index straight, the other fingers closed, the thumb over them.
    Point,
    /// Thumb and index flexed toward each other, their tips meeting where the thumb's limits
    /// allow; the other fingers at ease.
    Pinch,
    /// Fingers wrapped around a handle, the thumb across.
    Grip,
}

impl HandPreset {
    /// All six, in the order the editor shows them.
    pub const ALL: [HandPreset; 6] = [
        HandPreset::Relaxed,
        HandPreset::Fist,
        HandPreset::Open,
        HandPreset::Point,
        HandPreset::Pinch,
        HandPreset::Grip,
    ];

    /// The preset's name: "relaxed", "fist"...
    pub fn name(self) -> &'static str {
        match self {
            HandPreset::Relaxed => "relaxed",
            HandPreset::Fist => "fist",
            HandPreset::Open => "open",
            HandPreset::Point => "point",
            HandPreset::Pinch => "pinch",
            HandPreset::Grip => "grip",
        }
    }

    /// Parses a name of [`HandPreset::name`].
    pub fn from_name(name: &str) -> Option<HandPreset> {
        HandPreset::ALL.into_iter().find(|p| p.name() == name)
    }

    /// Per digit (thumb first): the flexion of each joint as a fraction of its range toward
    /// the palm (slots as [`FingerJoint`]: carpometacarpal, metacarpophalangeal, proximal and
    /// distal interphalangeal), and the spread as a fraction of the abduction range.
    fn shape(self) -> [([f64; 4], f64); 5] {
        // The metacarpals cup the palm in a closed hand (a few degrees at most).
        const CLOSED: [f64; 4] = [1.0, 1.0, 1.0, 0.75];
        match self {
            HandPreset::Relaxed => [
                ([0.3, 0.2, 0.2, 0.0], 0.0),
                ([0.0, 0.15, 0.25, 0.15], 0.1),
                ([0.0, 0.2, 0.3, 0.2], 0.0),
                ([0.2, 0.25, 0.35, 0.2], 0.1),
                ([0.3, 0.3, 0.4, 0.25], 0.15),
            ],
            HandPreset::Fist => [
                ([1.0, 0.6, 0.6, 0.0], 0.0),
                (CLOSED, 0.0),
                (CLOSED, 0.0),
                (CLOSED, 0.0),
                (CLOSED, 0.0),
            ],
            HandPreset::Open => [
                ([0.0; 4], 0.5),
                ([0.0; 4], 0.8),
                ([0.0; 4], 0.0),
                ([0.0; 4], 0.8),
                ([0.0; 4], 0.8),
            ],
            HandPreset::Point => [
                ([0.8, 0.5, 0.5, 0.0], 0.0),
                ([0.0; 4], 0.0),
                (CLOSED, 0.0),
                (CLOSED, 0.0),
                (CLOSED, 0.0),
            ],
            HandPreset::Pinch => [
                ([1.0, 0.4, 0.3, 0.0], 0.0),
                ([0.0, 0.45, 0.5, 0.35], 0.0),
                ([0.0, 0.25, 0.35, 0.2], 0.0),
                ([0.2, 0.3, 0.4, 0.25], 0.1),
                ([0.3, 0.35, 0.45, 0.3], 0.15),
            ],
            HandPreset::Grip => [
                ([0.7, 0.3, 0.3, 0.0], 0.0),
                ([0.0, 0.55, 0.65, 0.45], 0.0),
                ([0.0, 0.55, 0.65, 0.45], 0.0),
                ([0.3, 0.55, 0.65, 0.45], 0.0),
                ([0.6, 0.55, 0.65, 0.45], 0.0),
            ],
        }
    }
}

/// Why a hand cannot be posed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum HandError {
    /// A joint on the mid-sagittal plane was asked for as a hand.
    #[error("a hand is on the left or the right, not on the body's centre")]
    NotASide,
    /// The body has no finger joints on that side.
    #[error(
        "the {side} hand has no finger joints (a body at LOA 1, or an avatar without fingers): hand poses need fingers"
    )]
    NoFingers {
        /// "left" or "right".
        side: &'static str,
    },
    /// The hand has fingers, but too few joints to tell which way its palm faces.
    #[error(
        "which way the {side} palm faces cannot be told: the hand needs its wrist and two finger bases"
    )]
    NoPalm {
        /// "left" or "right".
        side: &'static str,
    },
}

fn side_word(side: Side) -> &'static str {
    match side {
        Side::Left => "left",
        Side::Right => "right",
        Side::Centre => "centre",
    }
}

/// A DOF that carries one anatomical motion of a finger joint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionDof {
    /// The DOF (index in the posture's values).
    pub dof: usize,
    /// +1 when a positive value moves the joint the anatomical way (toward the palm; away from
    /// the middle finger), else -1.
    pub sign: f64,
    /// How far the joint's limits let it go that way (rad, at least 0).
    pub reach: f64,
}

impl MotionDof {
    /// The DOF value for `fraction` of the reach (negative fractions go the other way, within
    /// the limits).
    fn value(&self, skeleton: &Skeleton, fraction: f64) -> f64 {
        clamp_to_limits(skeleton, self.dof, self.sign * fraction * self.reach)
    }

    /// The fraction of the reach of `value`.
    fn fraction(&self, value: f64) -> Option<f64> {
        (self.reach > 1e-9).then(|| self.sign * value / self.reach)
    }
}

/// One finger joint of a rigged hand.
#[derive(Debug, Clone, PartialEq)]
pub struct RiggedJoint {
    /// Which joint of the digit it is.
    pub role: FingerJoint,
    /// The joint (skeleton index).
    pub joint: usize,
    /// The DOF that flexes it toward the palm, if one does.
    pub flexion: Option<MotionDof>,
    /// The DOF that spreads it in the palm's plane (knuckles and the thumb's base), if any.
    pub spread: Option<MotionDof>,
    /// Its other rotation DOF: presets set them to 0.
    pub others: Vec<usize>,
}

/// One digit of a rigged hand: its joints present on the skeleton, proximal first.
#[derive(Debug, Clone, PartialEq)]
pub struct RiggedFinger {
    /// Which digit.
    pub finger: Finger,
    /// Its joints on the skeleton, proximal first (at least one).
    pub joints: Vec<RiggedJoint>,
    /// The unit direction it points at rest, from its first joint to its last (world frame).
    pub pointing: DVec3,
}

/// A hand of a skeleton, ready to be posed: each finger joint's flexion and spread DOF.
#[derive(Debug, Clone, PartialEq)]
pub struct HandRig {
    /// Left or right.
    pub side: Side,
    /// The digits present, thumb first.
    pub fingers: Vec<RiggedFinger>,
    /// The unit direction the palm faces in the rest posture (world frame).
    pub palm_normal: DVec3,
}

/// Whether `skeleton` has finger joints on either hand.
pub fn has_fingers(skeleton: &Skeleton) -> bool {
    [Side::Left, Side::Right].into_iter().any(|side| {
        Finger::ALL.into_iter().any(|finger| {
            finger.joints().iter().any(|(_, bare)| {
                resolve_joint(skeleton, &format!("{}{bare}", side.prefix())).is_some()
            })
        })
    })
}

fn clamp_to_limits(skeleton: &Skeleton, dof: usize, value: f64) -> f64 {
    let lower = skeleton
        .lower_limits()
        .get(dof)
        .copied()
        .unwrap_or(f64::NEG_INFINITY);
    let upper = skeleton
        .upper_limits()
        .get(dof)
        .copied()
        .unwrap_or(f64::INFINITY);
    if lower <= upper {
        value.clamp(lower, upper)
    } else {
        value
    }
}

/// The DOF of `joint` (not in `taken`) whose rest axis best turns `segment` toward `toward`.
fn motion_dof(
    skeleton: &Skeleton,
    rest: &Frames,
    joint: usize,
    segment: DVec3,
    toward: DVec3,
    taken: &[usize],
) -> Option<MotionDof> {
    let wanted = segment
        .normalize_or_zero()
        .cross(toward.normalize_or_zero());
    let wanted = wanted.normalize_or_zero();
    if wanted == DVec3::ZERO {
        return None;
    }
    let definition = skeleton.joints().get(joint)?;
    let (dof, alignment) = definition
        .rotation_dof
        .iter()
        .flatten()
        .filter(|dof| !taken.contains(dof))
        .filter_map(|&dof| Some((dof, rest.dof_axis.get(dof)?.dot(wanted))))
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))?;
    if alignment.abs() < MIN_ALIGNMENT {
        return None;
    }
    let sign = alignment.signum();
    let limit = if sign > 0.0 {
        skeleton.upper_limits().get(dof).copied()
    } else {
        skeleton.lower_limits().get(dof).map(|lower| -lower)
    }
    .unwrap_or(f64::INFINITY);
    let reach = if limit.is_finite() {
        limit.max(0.0)
    } else {
        UNLIMITED_REACH
    };
    Some(MotionDof { dof, sign, reach })
}

/// The digits' joints found on the skeleton, by digit.
type FoundFingers = Vec<(Finger, Vec<(FingerJoint, usize)>)>;

fn find_fingers(skeleton: &Skeleton, side: Side) -> FoundFingers {
    Finger::ALL
        .into_iter()
        .filter_map(|finger| {
            let joints: Vec<(FingerJoint, usize)> = finger
                .joints()
                .iter()
                .filter_map(|&(role, bare)| {
                    let joint = resolve_joint(skeleton, &format!("{}{bare}", side.prefix()))?;
                    Some((role, joint))
                })
                .collect();
            (!joints.is_empty()).then_some((finger, joints))
        })
        .collect()
}

/// The palm's normal at rest and, per finger (2 to 5), the direction away from the middle
/// finger in the palm's plane; the direction the fingers point.
struct Palm {
    normal: DVec3,
    pointing: DVec3,
    base_of: [Option<DVec3>; 5],
    reference: DVec3,
}

fn palm(skeleton: &Skeleton, rest: &Frames, side: Side, found: &FoundFingers) -> Option<Palm> {
    let position = |joint: usize| rest.joint_position.get(joint).copied();
    // Each digit's base: its knuckle, else its first joint present.
    let mut base_of = [None; 5];
    for (finger, joints) in found {
        let knuckle = joints
            .iter()
            .find(|(role, _)| *role == FingerJoint::Metacarpophalangeal)
            .or(joints.first());
        base_of[finger.index()] = knuckle.and_then(|&(_, joint)| position(joint));
    }
    let fingers: Vec<DVec3> = base_of[1..].iter().flatten().copied().collect();
    let wrist =
        resolve_joint(skeleton, &format!("{}radiocarpal", side.prefix())).and_then(position)?;
    let (first, last) = (fingers.first()?, fingers.last()?);
    // From the little-finger side to the thumb side: the index-most base against the little-most,
    // or the thumb against the one finger present.
    let radial = if fingers.len() >= 2 {
        *first - *last
    } else {
        base_of[0]? - *first
    };
    let reference =
        base_of[2].unwrap_or_else(|| fingers.iter().sum::<DVec3>() / fingers.len() as f64);
    let pointing =
        (fingers.iter().sum::<DVec3>() / fingers.len() as f64 - wrist).normalize_or_zero();
    // The left hand is the mirror image of the right: its palm faces pointing x radial.
    let normal = match side {
        Side::Left => pointing.cross(radial),
        _ => radial.cross(pointing),
    }
    .normalize_or_zero();
    (normal != DVec3::ZERO && pointing != DVec3::ZERO).then_some(Palm {
        normal,
        pointing,
        base_of,
        reference,
    })
}

impl HandRig {
    /// The `side` hand of `skeleton`. Errors when the skeleton has no finger joints there, or
    /// too few to tell which way the palm faces.
    pub fn new(skeleton: &Skeleton, side: Side) -> Result<HandRig, HandError> {
        if side == Side::Centre {
            return Err(HandError::NotASide);
        }
        let found = find_fingers(skeleton, side);
        if found.is_empty() {
            return Err(HandError::NoFingers {
                side: side_word(side),
            });
        }
        let rest = Frames::new(skeleton, &Posture::rest(skeleton));
        let palm = palm(skeleton, &rest, side, &found).ok_or(HandError::NoPalm {
            side: side_word(side),
        })?;
        let fingers = found
            .iter()
            .map(|(finger, joints)| {
                let pointing = pointing(skeleton, &rest, joints);
                RiggedFinger {
                    finger: *finger,
                    joints: rig_finger(skeleton, &rest, &palm, *finger, joints, pointing),
                    pointing,
                }
            })
            .collect();
        Ok(HandRig {
            side,
            fingers,
            palm_normal: palm.normal,
        })
    }

    /// The rigged digit, if the hand has it.
    pub fn finger(&self, finger: Finger) -> Option<&RiggedFinger> {
        self.fingers.iter().find(|rigged| rigged.finger == finger)
    }

    /// The DOF values (index, value) of `preset`: every rotation DOF of every finger joint,
    /// within its limits.
    pub fn preset(&self, skeleton: &Skeleton, preset: HandPreset) -> Vec<(usize, f64)> {
        let shape = preset.shape();
        let mut values = Vec::new();
        for rigged in &self.fingers {
            let (flexion, spread) = shape[rigged.finger.index()];
            for joint in &rigged.joints {
                if let Some(motion) = &joint.flexion {
                    values.push((
                        motion.dof,
                        motion.value(skeleton, flexion[joint.role.slot()]),
                    ));
                }
                if let Some(motion) = &joint.spread {
                    values.push((motion.dof, motion.value(skeleton, spread)));
                }
                values.extend(
                    joint
                        .others
                        .iter()
                        .map(|&dof| (dof, clamp_to_limits(skeleton, dof, 0.0))),
                );
            }
        }
        if preset == HandPreset::Pinch {
            self.meet_thumb_and_index(skeleton, &mut values);
        }
        values
    }

    /// The pinch: the thumb's and the index's DOF (within their limits, from the preset's
    /// values) bring the two tips to [`PINCH_GAP_M`] of each other, or as near as the limits
    /// allow (a thumb that rests far from the index, as H-Anim's default one, stops short).
    /// A pattern search:
    /// each DOF tries a step both ways and keeps the better, the step halves when none helps
    /// (both ways are compared so that mirror-image hands take mirror-image steps).
    fn meet_thumb_and_index(&self, skeleton: &Skeleton, values: &mut [(usize, f64)]) {
        let (Some(thumb), Some(index)) = (self.finger(Finger::Thumb), self.finger(Finger::Index))
        else {
            return;
        };
        let dofs: Vec<usize> = thumb
            .joints
            .iter()
            .chain(&index.joints)
            .filter_map(|joint| skeleton.joints().get(joint.joint))
            .flat_map(|joint| joint.rotation_dof.iter().flatten().copied())
            .collect();
        let mut posture = Posture::rest(skeleton);
        for &(dof, value) in values.iter() {
            if let Some(slot) = posture.values_mut().get_mut(dof) {
                *slot = value;
            }
        }
        let mut frames = Frames::new(skeleton, &posture);
        let mut miss = |posture: &Posture| {
            frames.update(skeleton, posture.values());
            match (
                self.fingertip(skeleton, &frames, Finger::Thumb),
                self.fingertip(skeleton, &frames, Finger::Index),
            ) {
                (Some(thumb), Some(index)) => ((thumb - index).length() - PINCH_GAP_M).max(0.0),
                _ => 0.0,
            }
        };
        let mut best = miss(&posture);
        let mut step = PINCH_FIRST_STEP;
        for _ in 0..PINCH_MAX_ROUNDS {
            if step < PINCH_LAST_STEP || best <= 0.0 {
                break;
            }
            let mut improved = false;
            for &dof in &dofs {
                let Some(&start) = posture.values().get(dof) else {
                    continue;
                };
                let mut tries = [1.0, -1.0].map(|direction| {
                    let value = clamp_to_limits(skeleton, dof, start + direction * step);
                    posture.values_mut()[dof] = value;
                    (miss(&posture), value)
                });
                tries.sort_by(|a, b| a.0.total_cmp(&b.0));
                let (reached, value) = tries[0];
                if reached < best - 1e-12 {
                    best = reached;
                    improved = true;
                    posture.values_mut()[dof] = value;
                } else {
                    posture.values_mut()[dof] = start;
                }
            }
            if !improved {
                step /= 2.0;
            }
        }
        for (dof, value) in values.iter_mut() {
            if dofs.contains(dof)
                && let Some(&searched) = posture.values().get(*dof)
            {
                *value = searched;
            }
        }
    }

    /// The DOF values (index, value) that curl `finger` (every digit for `None`) by `curl`
    /// (0 straight, 1 closed as far as its limits let it): each joint flexes by that fraction
    /// of its range toward the palm, together; spread and the other DOF are left alone.
    pub fn curl(
        &self,
        skeleton: &Skeleton,
        finger: Option<Finger>,
        curl: f64,
    ) -> Vec<(usize, f64)> {
        let curl = if curl.is_finite() {
            curl.clamp(0.0, 1.0)
        } else {
            0.0
        };
        self.fingers
            .iter()
            .filter(|rigged| finger.is_none_or(|f| f == rigged.finger))
            .flat_map(|rigged| rigged.joints.iter())
            .filter_map(|joint| joint.flexion.as_ref())
            .map(|motion| (motion.dof, motion.value(skeleton, curl)))
            .collect()
    }

    /// How curled `finger` (every digit for `None`) is in `posture`: the mean over its joints of
    /// the flexion as a fraction of the range, in [0, 1]. `None` when it has no flexion DOF.
    pub fn curl_of(&self, posture: &Posture, finger: Option<Finger>) -> Option<f64> {
        let fractions: Vec<f64> = self
            .fingers
            .iter()
            .filter(|rigged| finger.is_none_or(|f| f == rigged.finger))
            .flat_map(|rigged| rigged.joints.iter())
            .filter_map(|joint| joint.flexion.as_ref())
            .filter_map(|motion| motion.fraction(*posture.values().get(motion.dof)?))
            .collect();
        (!fractions.is_empty())
            .then(|| (fractions.iter().sum::<f64>() / fractions.len() as f64).clamp(0.0, 1.0))
    }

    /// The world position of the tip of `finger` in the posture of `frames`: beyond its last
    /// joint, along the direction the digit points at rest, by `TIP_RATIO` of the segment
    /// before it.
    pub fn fingertip(&self, skeleton: &Skeleton, frames: &Frames, finger: Finger) -> Option<DVec3> {
        let tip = self.fingertip_effector(skeleton, finger)?;
        (tip.joint < frames.joint_position.len()).then(|| frames.point(tip.joint, tip.point))
    }

    /// The fingertip as a point of the digit's last segment (what [`HandRig::fingertip`]
    /// places in a posture; a solver task can hold it).
    pub fn fingertip_effector(&self, skeleton: &Skeleton, finger: Finger) -> Option<Effector> {
        let rigged = self.finger(finger)?;
        let last = rigged.joints.last()?.joint;
        let length = skeleton.joints().get(last)?.offset.length();
        Some(Effector {
            joint: last,
            point: rigged.pointing * length * TIP_RATIO,
        })
    }
}

/// The unit direction a digit points at rest, from its first joint to its last (every joint
/// of it turns this segment: the phalanges of a digit are nearly aligned at rest, and one short
/// phalanx of a file's rest pose may point astray; so do some of H-Anim's default centres, such
/// as `r_carpal_distal_interphalangeal_5`). A digit of one joint points along that joint's
/// offset from its parent.
fn pointing(skeleton: &Skeleton, rest: &Frames, joints: &[(FingerJoint, usize)]) -> DVec3 {
    let position = |joint: usize| rest.joint_position.get(joint).copied();
    let along = match (joints.first(), joints.last()) {
        (Some(&(_, first)), Some(&(_, last))) if first != last => {
            position(last).zip(position(first)).map(|(l, f)| l - f)
        }
        _ => None,
    };
    along
        .or_else(|| {
            let &(_, joint) = joints.first()?;
            Some(skeleton.joints().get(joint)?.offset)
        })
        .unwrap_or(DVec3::ZERO)
        .normalize_or_zero()
}

fn rig_finger(
    skeleton: &Skeleton,
    rest: &Frames,
    palm: &Palm,
    finger: Finger,
    joints: &[(FingerJoint, usize)],
    segment: DVec3,
) -> Vec<RiggedJoint> {
    // Spreading: away from the middle finger in the palm's plane; the thumb away from the
    // fingers.
    let away = match finger {
        Finger::Thumb => -palm.pointing,
        _ => palm.base_of[finger.index()].map_or(DVec3::ZERO, |base| base - palm.reference),
    };
    let away = away - palm.normal * away.dot(palm.normal);
    let mut rigged = Vec::with_capacity(joints.len());
    for &(role, joint) in joints {
        let flexion = motion_dof(skeleton, rest, joint, segment, palm.normal, &[]);
        let spreads = match finger {
            Finger::Thumb => role == FingerJoint::Carpometacarpal,
            _ => role == FingerJoint::Metacarpophalangeal,
        };
        let taken: Vec<usize> = flexion.iter().map(|motion| motion.dof).collect();
        let spread = spreads
            .then(|| motion_dof(skeleton, rest, joint, segment, away, &taken))
            .flatten();
        let others = skeleton
            .joints()
            .get(joint)
            .map(|definition| {
                definition
                    .rotation_dof
                    .iter()
                    .flatten()
                    .copied()
                    .filter(|dof| !taken.contains(dof) && spread.is_none_or(|s| s.dof != *dof))
                    .collect()
            })
            .unwrap_or_default();
        rigged.push(RiggedJoint {
            role,
            joint,
            flexion,
            spread,
            others,
        });
    }
    rigged
}
