//! Degrees of freedom, anatomical ranges of motion and segment masses of the H-Anim joints.
//!
//! # Ranges of motion
//! Source: American Academy of Orthopaedic Surgeons, *Joint Motion: Method of Measuring and
//! Recording* (AAOS, 1965; the "normal" adult values reprinted by Greene & Heckman, *The
//! Clinical Measurement of Joint Motion*, AAOS 1994), completed for the shoulder girdle, the
//! pelvis and the fingers by I. A. Kapandji, *The Physiology of the Joints* (vol. 1-3).
//! Values are in degrees in the tables below and converted to radians.
//!
//! # Sign conventions
//! Stance joint frames are parallel to the H-Anim body frame at rest (+X the body's left,
//! +Y up, +Z front) and the rotational DOF are the components of a rotation vector in that
//! frame ([`stance_ik::Posture`]). For a segment hanging down (thigh, arm at rest):
//! `+rx` moves it backward (hip extension), `-rx` forward (hip flexion, shoulder flexion);
//! `+rz` moves it toward +X (abduction of a left limb, adduction of a right one);
//! `+ry` turns its front toward +X (external rotation of a left limb). Right-side limits are
//! the mirror images of the left ones (`ry` and `rz` swap sign).
//!
//! # Segment masses
//! de Leva P. (1996), *Adjustments to Zatsiorsky-Seluyanov's segment inertia parameters*,
//! J. Biomechanics 29(9):1223-1230, Table 4: mass fractions and longitudinal centre-of-mass
//! positions (percent of segment length from the proximal end), averaged over the female and
//! male columns.

use glam::DVec3;
use stance_ik::Dof::{self, Rx, Ry, Rz, Tx, Ty, Tz};
use stance_ik::{Frames, Posture, Skeleton};

pub use crate::names::Side;

/// Functional class of an H-Anim joint; decides its DOF, ranges and mass share.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum JointClass {
    /// `humanoid_root`: 3 translations + 3 rotations, free.
    Root,
    /// `sacroiliac`: pelvis on the root.
    Pelvis,
    /// Lumbar and thoracic vertebrae (`vl*`, `vt*`).
    Spine,
    /// Cervical vertebrae and `skullbase`.
    Neck,
    /// `*_sternoclavicular`.
    Clavicle,
    /// `*_acromioclavicular`.
    Acromion,
    /// `*_shoulder` (glenohumeral).
    Shoulder,
    /// `*_elbow` (with forearm pronation/supination).
    Elbow,
    /// `*_radiocarpal`.
    Wrist,
    /// `*_carpometacarpal_1`.
    ThumbBase,
    /// `*_carpometacarpal_2..5`.
    Metacarpal,
    /// `*_metacarpophalangeal_*`.
    Knuckle,
    /// `*_carpal_*interphalangeal_*`.
    FingerHinge,
    /// `*_hip`.
    Hip,
    /// `*_knee`.
    Knee,
    /// `*_talocrural` (with subtalar inversion/eversion at low LOA).
    Ankle,
    /// Mid-foot joints (`*_tarsometatarsal_*`, `*_talocalcaneonavicular`...).
    MidFoot,
    /// `*_metatarsophalangeal_*`.
    Toe,
    /// `*_tarsal_*interphalangeal_*`.
    ToeHinge,
    /// Eyes, eyelids, eyebrows, jaw: rotational, small.
    Face,
}

impl JointClass {
    /// The class of an H-Anim joint name (any LOA).
    pub fn of(name: &str) -> JointClass {
        let (_, bare) = Side::split(name);
        match bare {
            "humanoid_root" => JointClass::Root,
            "sacroiliac" => JointClass::Pelvis,
            "skullbase" => JointClass::Neck,
            "sternoclavicular" => JointClass::Clavicle,
            "acromioclavicular" => JointClass::Acromion,
            "shoulder" => JointClass::Shoulder,
            "elbow" => JointClass::Elbow,
            "radiocarpal" | "midcarpal" => JointClass::Wrist,
            "hip" => JointClass::Hip,
            "knee" => JointClass::Knee,
            "talocrural" => JointClass::Ankle,
            "carpometacarpal_1" => JointClass::ThumbBase,
            _ if bare.starts_with("vc") => JointClass::Neck,
            _ if bare.starts_with("vl") || bare.starts_with("vt") => JointClass::Spine,
            _ if bare.starts_with("carpometacarpal") => JointClass::Metacarpal,
            _ if bare.starts_with("metacarpophalangeal") => JointClass::Knuckle,
            _ if bare.starts_with("carpal_") => JointClass::FingerHinge,
            _ if bare.starts_with("metatarsophalangeal") => JointClass::Toe,
            _ if bare.starts_with("tarsal_") => JointClass::ToeHinge,
            _ if bare.starts_with("tarso")
                || bare.starts_with("talo")
                || bare.starts_with("cuneo")
                || bare.starts_with("calcaneo")
                || bare.starts_with("transverse") =>
            {
                JointClass::MidFoot
            }
            _ => JointClass::Face,
        }
    }
}

/// Range of one rotational DOF of a left or centre joint, degrees `(dof, lower, upper)`.
type Range = (Dof, f64, f64);

/// AAOS / Kapandji ranges, left side (see the module documentation for signs).
fn left_ranges(class: JointClass) -> &'static [Range] {
    match class {
        JointClass::Root => &[],
        // Pelvic tilt / obliquity / rotation on the hips (Kapandji vol. 3).
        JointClass::Pelvis => &[(Rx, -30.0, 30.0), (Ry, -30.0, 30.0), (Rz, -20.0, 20.0)],
        // Thoracolumbar spine, whole: flexion 80, extension 25, lateral 35, rotation 45
        // (AAOS). Shared among the spine joints present (see `ranges`).
        JointClass::Spine => &[(Rx, -25.0, 80.0), (Ry, -45.0, 45.0), (Rz, -35.0, 35.0)],
        // Cervical spine, whole: flexion 45, extension 45, lateral 45, rotation 60 (AAOS).
        JointClass::Neck => &[(Rx, -45.0, 45.0), (Ry, -60.0, 60.0), (Rz, -45.0, 45.0)],
        // Sternoclavicular: elevation 45, depression 5, protraction/retraction 15 (Kapandji 1).
        JointClass::Clavicle => &[(Ry, -15.0, 15.0), (Rz, -5.0, 45.0)],
        // Acromioclavicular: about 10 degrees each way (Kapandji 1).
        JointClass::Acromion => &[(Rx, -10.0, 10.0), (Ry, -10.0, 10.0), (Rz, -10.0, 10.0)],
        // Shoulder: flexion 180, extension 60, abduction 180, adduction 30 (cross-body),
        // internal rotation 70, external rotation 90 (AAOS). Capped at 170 to stay away from
        // the rotation-vector wrap at 180.
        JointClass::Shoulder => &[(Rx, -170.0, 60.0), (Ry, -70.0, 90.0), (Rz, -30.0, 170.0)],
        // Elbow flexion 150, extension 0; forearm pronation 80 / supination 80 (AAOS).
        JointClass::Elbow => &[(Rx, -150.0, 0.0), (Ry, -80.0, 80.0)],
        // Wrist: flexion 80, extension 70 (about z, palm facing the thigh); radial deviation
        // 20, ulnar deviation 30 (about x) (AAOS).
        JointClass::Wrist => &[(Rx, -20.0, 30.0), (Rz, -80.0, 70.0)],
        // Thumb carpometacarpal: flexion 15, extension 20, abduction 70 (AAOS).
        JointClass::ThumbBase => &[(Rx, -70.0, 0.0), (Ry, -15.0, 20.0), (Rz, -15.0, 20.0)],
        // Metacarpals 2-5: a few degrees of cupping (Kapandji 1).
        JointClass::Metacarpal => &[(Rz, -10.0, 5.0)],
        // Metacarpophalangeal: flexion 90, hyperextension 45, abduction 20 (AAOS).
        JointClass::Knuckle => &[(Rx, -20.0, 20.0), (Rz, -90.0, 45.0)],
        // Interphalangeal: PIP flexion 100, DIP flexion 90 / extension 10 (AAOS).
        JointClass::FingerHinge => &[(Rz, -100.0, 10.0)],
        // Hip: flexion 120, extension 30, abduction 45, adduction 30, internal and external
        // rotation 45 (AAOS).
        JointClass::Hip => &[(Rx, -120.0, 30.0), (Ry, -45.0, 45.0), (Rz, -30.0, 45.0)],
        // Knee: flexion 135, extension 0 (AAOS); a few degrees of hyperextension allowed.
        JointClass::Knee => &[(Rx, -5.0, 135.0)],
        // Ankle: dorsiflexion 20, plantar flexion 50; subtalar inversion 35, eversion 15 (AAOS).
        JointClass::Ankle => &[(Rx, -20.0, 50.0), (Rz, -35.0, 15.0)],
        // Mid-foot: small gliding, about 10 degrees (Kapandji 2).
        JointClass::MidFoot => &[(Rx, -10.0, 10.0), (Rz, -10.0, 10.0)],
        // First metatarsophalangeal: flexion 45, extension 70 (AAOS).
        JointClass::Toe => &[(Rx, -70.0, 45.0)],
        // Toe interphalangeal: flexion 90, extension 0 (AAOS).
        JointClass::ToeHinge => &[(Rx, 0.0, 90.0)],
        // Eyes: about 45 degrees each way; jaw opening about 30 degrees (Kapandji 3).
        JointClass::Face => &[(Rx, -30.0, 30.0), (Ry, -45.0, 45.0)],
    }
}

/// The DOF of a joint of this class: the axes of its ranges (the root has all six).
pub fn dofs(class: JointClass) -> Vec<Dof> {
    match class {
        JointClass::Root => vec![Tx, Ty, Tz, Rx, Ry, Rz],
        _ => left_ranges(class).iter().map(|&(d, _, _)| d).collect(),
    }
}

/// Limits in radians `(dof, lower, upper)` of the H-Anim joint `name`, mirrored for the right
/// side. `share` divides the range of a joint that shares a motion with others of its class
/// (the spine and the neck: the range of the whole region split over the joints present).
pub fn limits(name: &str, share: usize) -> Vec<(Dof, f64, f64)> {
    let class = JointClass::of(name);
    let side = Side::of(name);
    let divide = match class {
        JointClass::Spine | JointClass::Neck => share.max(1) as f64,
        _ => 1.0,
    };
    left_ranges(class)
        .iter()
        .map(|&(dof, lo, hi)| {
            let (lo, hi) = (lo / divide, hi / divide);
            let (lo, hi) = if side == Side::Right && matches!(dof, Ry | Rz) {
                (-hi, -lo)
            } else {
                (lo, hi)
            };
            (dof, lo.to_radians(), hi.to_radians())
        })
        .collect()
}

/// The default stiffness (H-Anim's `stiffness`, in [0, 1)) of the rotation DOF of a joint of
/// this class, when `share` joints of its region are present (the spine and the neck).
///
/// The solver weighs a DOF by `w = 1 / (1 - stiffness)` in its weighted pseudo-inverse, so a
/// chain of `k` joints of weight `w` bends like one joint of weight `w / k`: a region's weight
/// is multiplied by the joints sharing it, and the trunk resists as much at LOA 4 (17 thoracic
/// and lumbar vertebrae) as at LOA 1 (one). Region weights, a modelling choice from anatomy
/// rather than a measured constant: the trunk (pelvis, lumbar and thoracic spine) 2 (large
/// masses, ligament-bound, moving little in a reach: most of a reach is the shoulder and
/// elbow; Kapandji vol. 1 and 3), the neck 2, the hip 1.5; the shoulder girdle and the limbs 1
/// (stiffness 0). Stiffer defaults (trunk 3 or 4, girdle 3) left the editor's guarded
/// iterations stalled short of reachable pulls. A user sets any DOF's own value in problem
/// files.
pub fn stiffness(class: JointClass, share: usize) -> f64 {
    let region = match class {
        JointClass::Pelvis | JointClass::Spine => 2.0,
        JointClass::Neck => 2.0,
        JointClass::Hip => 1.5,
        _ => return 0.0,
    };
    let weight = region * share.max(1) as f64;
    1.0 - 1.0 / weight
}

/// A body segment of de Leva (1996).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    /// Segment name in de Leva's table.
    pub name: &'static str,
    /// Fraction of the whole-body mass (mean of the female and male columns).
    pub mass_fraction: f64,
    /// Centre of mass along the segment, fraction of its length from the proximal joint.
    pub com_fraction: f64,
}

/// de Leva (1996) Table 4, female/male means. Fractions sum to 1 over the body (two of each
/// limb segment).
pub const SEGMENTS: &[Segment] = &[
    Segment {
        name: "head",
        mass_fraction: 0.0681,
        com_fraction: 0.4005,
    },
    Segment {
        name: "upper trunk",
        mass_fraction: 0.1571,
        com_fraction: 0.4997,
    },
    Segment {
        name: "middle trunk",
        mass_fraction: 0.1549,
        com_fraction: 0.4504,
    },
    Segment {
        name: "lower trunk",
        mass_fraction: 0.1182,
        com_fraction: 0.4270,
    },
    Segment {
        name: "upper arm",
        mass_fraction: 0.0263,
        com_fraction: 0.5762,
    },
    Segment {
        name: "forearm",
        mass_fraction: 0.0150,
        com_fraction: 0.4589,
    },
    Segment {
        name: "hand",
        mass_fraction: 0.0059,
        com_fraction: 0.7687,
    },
    Segment {
        name: "thigh",
        mass_fraction: 0.1447,
        com_fraction: 0.3900,
    },
    Segment {
        name: "shank",
        mass_fraction: 0.0457,
        com_fraction: 0.4406,
    },
    Segment {
        name: "foot",
        mass_fraction: 0.0133,
        com_fraction: 0.4255,
    },
];

/// The de Leva segment carried by a joint class (the segment between it and the next joint
/// down the chain), if any. Trunk segments are shared among the joints of the region.
pub fn segment_of(class: JointClass) -> Option<&'static Segment> {
    let name = match class {
        JointClass::Pelvis => "lower trunk",
        JointClass::Spine => "middle trunk",
        JointClass::Neck => "head",
        JointClass::Shoulder => "upper arm",
        JointClass::Elbow => "forearm",
        JointClass::Wrist => "hand",
        JointClass::Hip => "thigh",
        JointClass::Knee => "shank",
        JointClass::Ankle => "foot",
        _ => return None,
    };
    SEGMENTS.iter().find(|s| s.name == name)
}

/// The ankle of a foot: `joint` itself when it is an ankle (`*_talocrural`), else its
/// nearest ancestor that is one, when `joint` is a mid-foot or toe joint.
pub fn ankle_of(skeleton: &Skeleton, joint: usize) -> Option<usize> {
    let class = |j: usize| JointClass::of(&skeleton.joints()[j].name);
    if !matches!(
        class(joint),
        JointClass::Ankle | JointClass::MidFoot | JointClass::Toe | JointClass::ToeHinge
    ) {
        return None;
    }
    let mut j = Some(joint);
    while let Some(k) = j {
        if class(k) == JointClass::Ankle {
            return Some(k);
        }
        j = skeleton.joints()[k].parent;
    }
    None
}

/// Foot length, breadth and the hip-to-ankle height as fractions of stature (Drillis &
/// Contini 1966, *Body segment parameters*, the segment lengths of Winter's *Biomechanics and
/// Motor Control of Human Movement*, fig. 4.1).
const FOOT_LENGTH: f64 = 0.152;
const FOOT_BREADTH: f64 = 0.055;
const HIP_TO_ANKLE: f64 = 0.491;
/// Share of the foot's length behind the ankle.
const HEEL_SHARE: f64 = 0.2;
/// Share of the foot's length from the ankle to the ball of the foot (the
/// metatarsophalangeal joints).
const BALL_SHARE: f64 = 0.55;

/// The sole of the foot whose ankle is `ankle`: its four corners (heel and toe, inside and
/// outside), horizontal around the ankle, in the ankle's joint frame at the rest posture
/// (where joint frames are parallel to the body frame: +Z ahead). Only their floor-plane
/// positions matter to a support polygon. The length comes from the foot's own joints when
/// the skeleton has them (the mean of its metatarsophalangeal joints is the ball of the foot,
/// `BALL_SHARE` of the length ahead), else from the leg's length in the anthropometric
/// proportions above.
pub fn sole(skeleton: &Skeleton, ankle: usize) -> [DVec3; 4] {
    let frames = Frames::new(skeleton, &Posture::rest(skeleton));
    let at = |j: usize| frames.joint_position[j];
    let balls: Vec<f64> = (0..skeleton.joint_count())
        .filter(|&j| {
            skeleton.is_ancestor_or_self(ankle, j)
                && JointClass::of(&skeleton.joints()[j].name) == JointClass::Toe
        })
        .map(|j| at(j).z - at(ankle).z)
        .collect();
    let ahead = balls.iter().sum::<f64>() / balls.len().max(1) as f64;
    let leg = skeleton.joints()[ankle]
        .parent
        .and_then(|knee| skeleton.joints()[knee].parent)
        .map(|hip| (at(hip) - at(ankle)).length());
    let stature = stature_of(leg);
    let length = foot_length(ahead, stature);
    let half = 0.5 * FOOT_BREADTH * stature;
    let (heel, toe) = (-HEEL_SHARE * length, (1.0 - HEEL_SHARE) * length);
    [
        DVec3::new(-half, 0.0, heel),
        DVec3::new(half, 0.0, heel),
        DVec3::new(half, 0.0, toe),
        DVec3::new(-half, 0.0, toe),
    ]
}

/// Stature from the hip-to-ankle length (1.7 m without one).
fn stature_of(hip_to_ankle: Option<f64>) -> f64 {
    hip_to_ankle
        .filter(|l| l.is_finite() && *l > 0.0)
        .map_or(1.7, |l| l / HIP_TO_ANKLE)
}

/// The foot's length: from the ball of the foot `ahead` of the ankle when the foot has toe
/// joints (over 2 cm), else from the stature.
fn foot_length(ahead: f64, stature: f64) -> f64 {
    if ahead > 0.02 {
        ahead / BALL_SHARE
    } else {
        FOOT_LENGTH * stature
    }
}

/// Ankle height above the sole as a fraction of stature (Drillis & Contini 1966).
const ANKLE_HEIGHT: f64 = 0.039;

/// The two points of a foot that touch the ground in a stance, on the sole, as offsets from
/// the ankle in its rest frame (the body frame: +Y up, +Z ahead): the heel (below the ankle,
/// `HEEL_SHARE` of the foot's length behind it) and the ball of the foot (the mean of the
/// foot's toe joints `toes` when it has them, else `BALL_SHARE` of the length ahead). The
/// sole is as far below the ankle as the lowest of `foot` (every joint and end point below the
/// ankle), or `ANKLE_HEIGHT` of the stature without one 2 cm lower. Metres; `hip_to_ankle`
/// (the leg's length) sizes a foot without toes.
pub fn heel_and_ball(toes: &[DVec3], foot: &[DVec3], hip_to_ankle: f64) -> [DVec3; 2] {
    let stature = stature_of(Some(hip_to_ankle));
    let toe = (!toes.is_empty()).then(|| toes.iter().copied().sum::<DVec3>() / toes.len() as f64);
    let length = foot_length(toe.map_or(0.0, |t| t.z), stature);
    let lowest = foot.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
    let depth = if lowest < -0.02 {
        lowest
    } else {
        -ANKLE_HEIGHT * stature
    };
    let ball = toe
        .filter(|t| t.z > 0.02)
        .map_or(DVec3::new(0.0, depth, BALL_SHARE * length), |t| {
            DVec3::new(t.x, depth, t.z)
        });
    [DVec3::new(0.0, depth, -HEEL_SHARE * length), ball]
}

#[cfg(test)]
mod tests {
    #[cfg(target_arch = "wasm32")]
    use wasm_bindgen_test::wasm_bindgen_test as test;

    use super::*;

    /// The case: the right arm raised sideways, the hand pulled 20 cm up and out with
    /// the feet pinned. With the default stiffness the shoulder does most of it; without, the
    /// trunk bends sideways. Angles: the trunk's bend is the rotation between the pelvis and
    /// the top of the thoracic spine, the shoulder's the change of its joint rotation.
    #[test]
    fn a_hand_pull_moves_the_spine_less_than_the_shoulder() {
        use stance_ik::{Solver, Task};

        use crate::{LevelOfArticulation, SkeletonOptions, default_skeleton};
        for loa in [LevelOfArticulation::Loa1, LevelOfArticulation::Loa2] {
            let body = default_skeleton(&SkeletonOptions {
                loa,
                ..SkeletonOptions::default()
            })
            .unwrap_or_else(|e| panic!("{e}"));
            let stiff = body.skeleton.clone();
            let mut free = stiff.clone();
            for d in 0..free.dof_count() {
                if free.dof_kinds()[d].is_rotation() {
                    free.set_stiffness(d, 0.0).unwrap_or_else(|e| panic!("{e}"));
                }
            }
            let j = |name: &str| stiff.joint_index(name).unwrap_or_else(|| panic!("{name}"));
            let shoulder = j("r_shoulder");
            let mut start = Posture::rest(&stiff);
            // Right arm abducted by 70 degrees (-rz abducts a right limb).
            start.values_mut()[stiff.joints()[shoulder].rotation_dof[2].unwrap_or(0)] = -1.2;
            let frames = Frames::new(&stiff, &start);
            let wrist = j("r_radiocarpal");
            let goal = frames.joint_position[wrist] + DVec3::new(-0.1, 0.2, 0.0);
            let mut tasks = Vec::new();
            for foot in ["l_talocrural", "r_talocrural"] {
                let f = j(foot);
                tasks.push(Task::position(f, DVec3::ZERO, frames.joint_position[f]));
                tasks.push(Task::orientation(f, frames.rotation(f)));
            }
            tasks.push(Task::position(wrist, DVec3::ZERO, goal).at_level(2));
            let top = ["vt1", "vt6", "vl1", "vl5"]
                .iter()
                .find_map(|n| stiff.joint_index(n))
                .unwrap_or_else(|| panic!("a thoracic joint"));
            let pelvis = j("sacroiliac");
            let measure = |skeleton: &Skeleton| {
                let mut posture = start.clone();
                let report = Solver::default()
                    .solve(skeleton, &tasks, &mut posture)
                    .unwrap_or_else(|e| panic!("{e}"));
                assert!(report.levels.iter().all(|l| l.met), "{report:?}");
                let f = Frames::new(skeleton, &posture);
                let bend = (f.rotation(pelvis).inverse() * f.rotation(top))
                    .angle_between(frames.rotation(pelvis).inverse() * frames.rotation(top));
                let arm = posture
                    .local_rotation(skeleton, shoulder)
                    .angle_between(start.local_rotation(skeleton, shoulder));
                (bend, arm)
            };
            let (bend, arm) = measure(&stiff);
            let (free_bend, free_arm) = measure(&free);
            assert!(
                bend < arm,
                "{loa:?}: trunk {:.1} deg, shoulder {:.1} deg",
                bend.to_degrees(),
                arm.to_degrees()
            );
            assert!(
                bend < free_bend,
                "{loa:?}: stiffness cuts the trunk's bend: {:.1} vs {:.1} deg (shoulder \
                 {:.1} vs {:.1})",
                bend.to_degrees(),
                free_bend.to_degrees(),
                arm.to_degrees(),
                free_arm.to_degrees()
            );
        }
    }

    #[test]
    fn soles_are_foot_sized_at_every_level_of_articulation() {
        use crate::{LevelOfArticulation, SkeletonOptions, default_skeleton};
        for loa in LevelOfArticulation::ALL {
            let body = default_skeleton(&SkeletonOptions {
                loa,
                ..SkeletonOptions::default()
            })
            .unwrap_or_else(|e| panic!("{e}"));
            let s = &body.skeleton;
            let ankle = s
                .joint_index("l_talocrural")
                .unwrap_or_else(|| panic!("ankle"));
            assert_eq!(ankle_of(s, ankle), Some(ankle));
            if let Some(toe) = s.joint_index("l_metatarsophalangeal_2") {
                assert_eq!(ankle_of(s, toe), Some(ankle));
            }
            assert_eq!(ankle_of(s, s.joint_index("l_knee").unwrap_or(0)), None);
            let corners = sole(s, ankle);
            let length = corners[2].z - corners[1].z;
            let breadth = corners[1].x - corners[0].x;
            // The H-Anim default body is about 1.75 m tall: a foot of 18-30 cm by 8-12 cm,
            // mostly ahead of the ankle.
            assert!((0.18..0.30).contains(&length), "{loa:?}: length {length}");
            assert!(
                (0.08..0.12).contains(&breadth),
                "{loa:?}: breadth {breadth}"
            );
            assert!(corners[2].z > 2.0 * -corners[1].z, "{loa:?}: {corners:?}");
        }
    }

    #[test]
    fn de_leva_fractions_sum_to_one() {
        let mut total = 0.0;
        for s in SEGMENTS {
            let count = if s.name.contains("trunk") || s.name == "head" {
                1.0
            } else {
                2.0
            };
            total += count * s.mass_fraction;
        }
        assert!((total - 1.0).abs() < 0.01, "{total}");
    }

    #[test]
    fn right_side_ranges_mirror_the_left() {
        let l = limits("l_shoulder", 1);
        let r = limits("r_shoulder", 1);
        for (a, b) in l.iter().zip(&r) {
            assert_eq!(a.0, b.0);
            if a.0 == Rx {
                assert_eq!((a.1, a.2), (b.1, b.2));
            } else {
                assert!((a.1 + b.2).abs() < 1e-12 && (a.2 + b.1).abs() < 1e-12);
            }
        }
        // Knee flexes backward (+rx), elbow forward (-rx).
        assert!(limits("l_knee", 1)[0].2 > 2.0);
        assert!(limits("l_elbow", 1)[0].1 < -2.0);
    }

    #[test]
    fn classes_cover_the_vocabulary() {
        assert_eq!(JointClass::of("vt6"), JointClass::Spine);
        assert_eq!(JointClass::of("vc4"), JointClass::Neck);
        assert_eq!(
            JointClass::of("r_carpal_distal_interphalangeal_3"),
            JointClass::FingerHinge
        );
        assert_eq!(JointClass::of("l_tarsometatarsal_2"), JointClass::MidFoot);
        assert_eq!(dofs(JointClass::Root).len(), 6);
    }
}
