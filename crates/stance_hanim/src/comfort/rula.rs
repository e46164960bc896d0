//! RULA, the Rapid Upper Limb Assessment (McAtamney L., Corlett E. N. (1993), *RULA: a survey
//! method for the investigation of work-related upper limb disorders*, Applied Ergonomics
//! 24(2):91-99): the posture scores of the arms, wrists, neck, trunk and legs measured on a
//! posture, Tables A, B and C, the grand score and its action level; and a smooth stand-in of
//! the score for the comfort task ([`rula_bands`]).
//!
//! # Tables
//! [`table_a`], [`table_b`] and [`table_c`] are the grids used by the large majority of
//! implementations (the "common" Table A, not the Cornell-style worksheet's, which differs in
//! 31 cells and is not monotone). Inputs are clamped to the tables' ranges (0 reads as 1,
//! score C above 8 as 8, score D above 7 as 7).
//!
//! # Part scores (the paper's rules, with Stance's default tolerances)
//! Every band owns its upper edge ("the lower band is closed"): an upper arm at exactly 20
//! degrees of flexion scores 1, at 20.5 degrees 2; at exactly 45 degrees 2, at 45.5 degrees 3.
//! The paper does not say who owns an edge; most code does this.
//!
//! - Upper arm: 1 from `e1` extension to `e1` flexion, 2 beyond `e1` extension or up to `e2`
//!   flexion, 3 up to `e3`, 4 beyond, with `(e1, e2, e3)` = (20, 45, 90) degrees
//!   ([`RulaVariant::Paper`]) or (15, 45, 90) ([`RulaVariant::Worksheet`]). +1 if the
//!   shoulder is raised (clavicle elevated more than [`SHOULDER_RAISED_DEG`]), +1 if the arm is
//!   abducted (more than `e1` out of the trunk's sagittal plane: the paper gives no angle,
//!   Stance uses the variant's neutral edge), -1 if the arm is supported
//!   ([`RulaSettings::arm_supported`]); kept within 1..6.
//! - Lower arm: 1 for more than 60 up to 100 degrees of elbow flexion, 2 otherwise; +1 if the
//!   hand works across the body's midline or out to the side ([`ArmAngles::across_midline`],
//!   [`ArmAngles::out_to_side`]; one +1 for either, as in the paper).
//! - Wrist: 1 when neutral (flexion or extension up to [`WRIST_NEUTRAL_DEG`]: the paper gives
//!   no tolerance, a measured wrist is never exactly straight), 2 up to 15 degrees, 3 beyond;
//!   +1 for radial or ulnar deviation beyond [`WRIST_NEUTRAL_DEG`].
//! - Wrist twist: 1 in the mid-range of forearm pronation/supination, 2 in the outer quarter
//!   of the range at either end ([`ArmAngles::wrist_twist`]).
//! - Neck: 1 up to 10 degrees of flexion, 2 up to 20, 3 beyond, 4 in extension (more than
//!   [`NECK_EXTENSION_DEG`] behind the trunk axis: the same tolerance as the wrist's); +1 if
//!   twisted, +1 if side-bent, each beyond [`TWIST_BEND_DEG`].
//! - Trunk: 2 up to 20 degrees of flexion, 3 up to 60, 4 beyond. An upright trunk (within
//!   [`TRUNK_UPRIGHT_DEG`] of vertical) scores 1: the paper's text gives 1 only to a trunk
//!   "sitting and well supported with a hip-trunk angle of 90 degrees or more"; the paper's
//!   figure and both worksheets also give 1 to an erect standing trunk, and Stance follows
//!   them. A trunk leaning back further than the upright tolerance scores 2 (RULA has no rule
//!   for trunk extension). [`RulaSettings::seated_supported`] gives 1 to any trunk flexed 20
//!   degrees or less. +1 if twisted, +1 if side-bent (each beyond [`TWIST_BEND_DEG`]).
//! - Legs: 1 if supported and balanced, 2 otherwise: [`RulaSettings::legs_supported`], or
//!   when that is `None` the measured [`RulaAngles::weight_balanced`].
//! - Muscle use (+1 when static or repeated, [`RulaSettings::muscle_use`]) and force/load
//!   ([`RulaLoad::score`]) are added to both posture scores A and B: score C and score D.
//!   Load follows the paper: more than 10 kg intermittent scores 2 (the worksheets fold it
//!   into 3).
//! - The grand score is Table C of score C and score D, per side; the report's score is the
//!   worse side's; [`action_level`] maps it to the paper's four action levels.
//!
//! # Variants
//! [`RulaVariant::Paper`] is the 1993 text. [`RulaVariant::Worksheet`] takes the Cornell-style
//! worksheet's upper-arm band edges, 15/45/90 degrees instead of 20/45/90 (so extension beyond
//! 15 degrees scores 2, and abduction counts beyond 15 degrees). Nothing else differs: Table A
//! stays the common one (not the worksheet's), the load scores stay the paper's, the lower arm
//! keeps a single +1.
//!
//! # Tolerances
//! The paper scores a wrist, neck or trunk as neutral only at exactly 0 degrees and adds 1 for
//! any twist, side-bend, deviation, abduction or raised shoulder. A measured posture is never
//! exactly neutral, so by default Stance counts an angle as neutral within a tolerance
//! ([`RulaTolerances::STANCE`]: [`WRIST_NEUTRAL_DEG`], [`NECK_EXTENSION_DEG`],
//! [`TRUNK_UPRIGHT_DEG`], [`TWIST_BEND_DEG`], [`SHOULDER_RAISED_DEG`], abduction beyond the
//! variant's `e1`). [`RulaTolerances::NONE`] scores by the paper as printed: every tolerance
//! 0 (wrist 1 only when straight, any neck extension 4, a trunk 1 only when upright, any
//! abduction, twist, side-bend or deviation +1). Either combines with either variant; the
//! smooth stand-in ([`rula_bands`]) keeps Stance's tolerances (a step at 0 degrees would give
//! a solver no direction either).
//!
//! # Measurement ([`measure`])
//! Angles are in degrees. The trunk frame is the world frame of the upper trunk: the spine
//! joint the shoulders hang from (`vl5` at LOA 1, `vt1` from LOA 2); the pelvis frame is
//! `sacroiliac`'s, the head frame `skullbase`'s. At rest every joint frame is parallel to the
//! body frame (+X left, +Y up, +Z front), and the H-Anim default body at rest is the neutral
//! posture: every angle below is 0 there. The default joint centres are not quite plumb (the
//! upper arm leans 5.6 degrees back, the forearm 2 forward), so a segment's axis is not the
//! line between its joint centres but its ideal anatomical direction (down for the arm
//! segments, up for the trunk and head) carried by the segment's joint frame; for a skeleton
//! whose rest pose differs from the H-Anim default (an avatar in a T-pose), that ideal is
//! first turned by the rotation from the H-Anim default segment direction to the skeleton's
//! rest direction, as the skeleton builder does with the joint ranges.
//!
//! - Upper arm: flexion is the angle of the arm's projection on the trunk's sagittal plane
//!   from the trunk's down axis (+ forward; an arm raised above the shoulder reads past 90
//!   rather than as extension: angles below -90 wrap to above 180). Abduction is the angle
//!   between the arm and the trunk's sagittal plane (+ outward), rather than a projection on
//!   the frontal plane, which swings wildly for an arm reaching forward. The sagittal
//!   projection is short, and its angle unstable, for an arm held sideways at shoulder level.
//! - Shoulder raised: the elevation of the clavicle (sternoclavicular joint to shoulder)
//!   in the trunk frame above its rest elevation; `None` without a sternoclavicular joint.
//! - Elbow flexion: the angle between the upper arm and forearm axes (0 = straight).
//! - Across the midline: the wrist lies on the other side of the trunk's mid-sagittal plane
//!   (through the shoulders' midpoint). Out to the side: the wrist is at least
//!   [`OUT_TO_SIDE_RATIO`] times as far from that plane as the shoulder.
//! - Wrist: the hand direction is the wrist-to-middle-knuckle line when a
//!   `*_metacarpophalangeal_3` joint exists, else the forearm's axis turned by the wrist's
//!   rotation. In the forearm's frame (the elbow's, pronation included), flexion is its angle
//!   about the front axis from the hand's neutral direction (+ toward the palm, which faces
//!   the thigh at rest), deviation its angle out of that plane (+ toward the thumb, radial).
//! - Wrist twist: the forearm's pronation/supination DOF (the elbow's rotation about the
//!   forearm's rest direction, `ry` on the default body) read from the frames; 2 in the outer
//!   quarter of its range at either end, 1 otherwise or without such a DOF.
//! - Neck: the head's up axis in the trunk frame: flexion about the trunk's left axis (+
//!   forward, - extension), side-bend out of the trunk's sagittal plane (+ toward the left),
//!   twist the head's rotation about the trunk's up axis (+ turned left).
//! - Trunk: the trunk's up axis against the world's vertical: flexion in the trunk's own
//!   sagittal plane (its left axis made horizontal), side-bend out of it; twist the trunk's
//!   rotation about its up axis relative to the pelvis (shoulder line against hip line).
//! - Weight balanced (legs): both ankles (knees, then hips, where the body has no ankles) at
//!   heights within [`FEET_LEVEL_M`] of each other, and the centre of mass over the middle
//!   half of the line between them ([`BALANCED_SHARE`] to `1 - BALANCED_SHARE` of the way,
//!   seen from above).
//!
//! # Smooth stand-in ([`rula_bands`])
//! A step score gives a solver no direction, so the comfort task sums logistic steps
//! ([`AngleBand`]) at the band edges of the 3D angles between the same segment axes: upper
//! arm against the trunk's down axis, forearm against upper arm, hand against its neutral in
//! the forearm, head against the trunk's up axis (plus a step of 3 for extension), trunk
//! against vertical. An [`AngleBand`] has no constant term, so a band's cost is the part score
//! minus a constant (the lower arm's is score - 2: a step down at 60 and up at 100 degrees).

use glam::{DMat3, DQuat, DVec3};
use stance_ik::comfort::{AngleBand, AngleReference};
use stance_ik::{Frames, Skeleton};

use crate::anatomy::JointClass;
use crate::{default_centre, joint_by_name, resolve_joint};

mod measure;

use measure::Body;
pub use measure::measure;

#[cfg(test)]
mod tests;

/// A wrist bent up to this many degrees (flexion/extension, or deviation) counts as neutral.
pub const WRIST_NEUTRAL_DEG: f64 = 5.0;
/// A head tilted back up to this many degrees is not "in extension".
pub const NECK_EXTENSION_DEG: f64 = 5.0;
/// A trunk within this many degrees of vertical (flexion or extension) is upright.
pub const TRUNK_UPRIGHT_DEG: f64 = 5.0;
/// Twist and side-bend of the neck or trunk add 1 beyond this many degrees.
pub const TWIST_BEND_DEG: f64 = 10.0;
/// A clavicle elevated more than this many degrees above rest: the shoulder is raised.
pub const SHOULDER_RAISED_DEG: f64 = 10.0;
/// A wrist at least this many times as far from the midline as its shoulder works out to the
/// side of the body.
pub const OUT_TO_SIDE_RATIO: f64 = 2.0;
/// Both feet count as level within this height difference of the ankles (m).
pub const FEET_LEVEL_M: f64 = 0.03;
/// The centre of mass must lie between this share and `1 - share` of the way from one ankle
/// to the other for the weight to count as balanced.
pub const BALANCED_SHARE: f64 = 0.25;
/// Width of the logistic steps of [`rula_bands`] (degrees). Chosen by measurement with
/// `stance bench --comfort` (80 reach problems): 3 deg lowered RULA in 14, 5 deg with the
/// ramp below in 37, 10 deg in 35.
pub const BAND_WIDTH_DEG: f64 = 5.0;
/// The bands' ramp past each edge (see [`stance_ik::comfort::AngleBand::ramp`]): without it a
/// posture deep inside a costly band (a straight elbow, far below 60 deg) feels no pull.
pub const BAND_RAMP: f64 = 0.5;

/// Table A: `[upper arm 1-6][lower arm 1-3][2 * (wrist - 1) + wrist twist - 1]`.
const TABLE_A: [[[u8; 8]; 3]; 6] = [
    [
        [1, 2, 2, 2, 2, 3, 3, 3],
        [2, 2, 2, 2, 3, 3, 3, 3],
        [2, 3, 3, 3, 3, 3, 4, 4],
    ],
    [
        [2, 3, 3, 3, 3, 4, 4, 4],
        [3, 3, 3, 3, 3, 4, 4, 4],
        [3, 4, 4, 4, 4, 4, 5, 5],
    ],
    [
        [3, 3, 4, 4, 4, 4, 5, 5],
        [3, 4, 4, 4, 4, 4, 5, 5],
        [4, 4, 4, 4, 4, 5, 5, 5],
    ],
    [
        [4, 4, 4, 4, 4, 5, 5, 5],
        [4, 4, 4, 4, 4, 5, 5, 5],
        [4, 4, 4, 5, 5, 5, 6, 6],
    ],
    [
        [5, 5, 5, 5, 5, 6, 6, 7],
        [5, 6, 6, 6, 6, 7, 7, 7],
        [6, 6, 6, 7, 7, 7, 7, 8],
    ],
    [
        [7, 7, 7, 7, 7, 8, 8, 9],
        [8, 8, 8, 8, 8, 9, 9, 9],
        [9, 9, 9, 9, 9, 9, 9, 9],
    ],
];

/// Table B: `[neck 1-6][2 * (trunk - 1) + legs - 1]`.
const TABLE_B: [[u8; 12]; 6] = [
    [1, 3, 2, 3, 3, 4, 5, 5, 6, 6, 7, 7],
    [2, 3, 2, 3, 4, 5, 5, 5, 6, 7, 7, 7],
    [3, 3, 3, 4, 4, 5, 5, 6, 6, 7, 7, 7],
    [5, 5, 5, 6, 6, 7, 7, 7, 7, 7, 8, 8],
    [7, 7, 7, 7, 7, 8, 8, 8, 8, 8, 8, 8],
    [8, 8, 8, 8, 8, 8, 8, 9, 9, 9, 9, 9],
];

/// Table C: `[score C 1-8][score D 1-7]`.
const TABLE_C: [[u8; 7]; 8] = [
    [1, 2, 3, 3, 4, 5, 5],
    [2, 2, 3, 4, 4, 5, 5],
    [3, 3, 3, 4, 4, 5, 6],
    [3, 3, 3, 4, 5, 6, 6],
    [4, 4, 4, 5, 6, 7, 7],
    [4, 4, 5, 6, 6, 7, 7],
    [5, 5, 6, 6, 7, 7, 7],
    [5, 5, 6, 7, 7, 7, 7],
];

/// The zero-based row of a score in a table of `count` rows (0 reads as 1, beyond as the last).
fn row(score: u8, count: usize) -> usize {
    usize::from(score.max(1)).min(count) - 1
}

/// Posture score A (Table A) of the upper arm (1-6), lower arm (1-3), wrist (1-4) and wrist
/// twist (1-2) scores; inputs are clamped to those ranges.
pub fn table_a(upper_arm: u8, lower_arm: u8, wrist: u8, wrist_twist: u8) -> u8 {
    TABLE_A[row(upper_arm, 6)][row(lower_arm, 3)][2 * row(wrist, 4) + row(wrist_twist, 2)]
}

/// Posture score B (Table B) of the neck (1-6), trunk (1-6) and legs (1-2) scores; inputs are
/// clamped to those ranges.
pub fn table_b(neck: u8, trunk: u8, legs: u8) -> u8 {
    TABLE_B[row(neck, 6)][2 * row(trunk, 6) + row(legs, 2)]
}

/// The grand score (Table C) of score C (1-8, 8 meaning 8 or more) and score D (1-7, 7 meaning
/// 7 or more); inputs are clamped to those ranges.
pub fn table_c(score_c: u8, score_d: u8) -> u8 {
    TABLE_C[row(score_c, 8)][row(score_d, 7)]
}

/// The paper's action level (1-4) of a grand score: 1-2 acceptable if not maintained or
/// repeated for long; 3-4 investigate, changes may be needed; 5-6 investigate and change soon;
/// 7 investigate and change immediately.
pub fn action_level(grand_score: u8) -> u8 {
    match grand_score {
        0..=2 => 1,
        3..=4 => 2,
        5..=6 => 3,
        _ => 4,
    }
}

/// Which RULA text the band edges follow (the module documentation lists the differences).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum RulaVariant {
    /// McAtamney & Corlett (1993): the upper arm's neutral band is 20 degrees either way.
    #[default]
    Paper,
    /// The Cornell-style employee worksheet: the upper arm's neutral band is 15 degrees either
    /// way (edges 15/45/90). Only these band edges differ from [`RulaVariant::Paper`].
    Worksheet,
}

impl RulaVariant {
    /// The upper arm's band edges `(e1, e2, e3)` in degrees: neutral within `e1` of the trunk
    /// axis (either way), then flexion bands up to `e2`, up to `e3` and beyond; an arm
    /// abducted beyond `e1` adds 1.
    pub fn upper_arm_edges(self) -> [f64; 3] {
        match self {
            RulaVariant::Paper => [20.0, 45.0, 90.0],
            RulaVariant::Worksheet => [15.0, 45.0, 90.0],
        }
    }
}

/// How far from neutral an angle must be before it counts (degrees; see the module
/// documentation's "Tolerances"). An angle counts when it is strictly beyond its tolerance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RulaTolerances {
    /// Wrist flexion or extension scores 1 up to this, and deviation adds 1 beyond it.
    pub wrist_neutral_deg: f64,
    /// A head tilted back beyond this is in extension (neck 4).
    pub neck_extension_deg: f64,
    /// A trunk within this of vertical (either way) is upright (trunk 1).
    pub trunk_upright_deg: f64,
    /// Twist and side-bend of the neck or trunk add 1 beyond this.
    pub twist_bend_deg: f64,
    /// A clavicle elevated beyond this above rest: the shoulder is raised (+1).
    pub shoulder_raised_deg: f64,
    /// An upper arm abducted beyond this adds 1; `None`: the variant's neutral edge `e1`
    /// ([`RulaVariant::upper_arm_edges`]).
    pub abduction_deg: Option<f64>,
}

impl RulaTolerances {
    /// Stance's tolerances (the default): a measured angle is never exactly 0.
    pub const STANCE: Self = Self {
        wrist_neutral_deg: WRIST_NEUTRAL_DEG,
        neck_extension_deg: NECK_EXTENSION_DEG,
        trunk_upright_deg: TRUNK_UPRIGHT_DEG,
        twist_bend_deg: TWIST_BEND_DEG,
        shoulder_raised_deg: SHOULDER_RAISED_DEG,
        abduction_deg: None,
    };
    /// The paper as printed: no tolerance anywhere.
    pub const NONE: Self = Self {
        wrist_neutral_deg: 0.0,
        neck_extension_deg: 0.0,
        trunk_upright_deg: 0.0,
        twist_bend_deg: 0.0,
        shoulder_raised_deg: 0.0,
        abduction_deg: Some(0.0),
    };
}

impl Default for RulaTolerances {
    fn default() -> Self {
        Self::STANCE
    }
}

/// The force or load handled (the paper's force/load score).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum RulaLoad {
    /// No resistance, or less than 2 kg intermittent load or force: 0.
    #[default]
    None,
    /// 2 to 10 kg intermittent: 1.
    Intermittent2To10,
    /// 2 to 10 kg static, or repeated: 2.
    Static2To10,
    /// More than 10 kg intermittent: 2 (the paper; the worksheets give 3).
    Intermittent10Plus,
    /// More than 10 kg static or repeated: 3.
    Static10Plus,
    /// Shocks or forces with a rapid build-up, of any magnitude: 3.
    Shock,
}

impl RulaLoad {
    /// The force/load score, 0 to 3.
    pub fn score(self) -> u8 {
        match self {
            RulaLoad::None => 0,
            RulaLoad::Intermittent2To10 => 1,
            RulaLoad::Static2To10 | RulaLoad::Intermittent10Plus => 2,
            RulaLoad::Static10Plus | RulaLoad::Shock => 3,
        }
    }
}

/// What RULA needs besides the posture: the task and the support of the body.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RulaSettings {
    /// Band edges (default [`RulaVariant::Paper`]).
    pub variant: RulaVariant,
    /// How far from neutral an angle must be to count (default [`RulaTolerances::STANCE`];
    /// [`RulaTolerances::NONE`] is the paper as printed).
    pub tolerances: RulaTolerances,
    /// The posture is mainly static (held longer than a minute) or repeated more than 4 times
    /// a minute: +1 to scores C and D.
    pub muscle_use: bool,
    /// The load or force handled: added to scores C and D.
    pub load: RulaLoad,
    /// The arms are supported or the person leans: -1 to the upper arm scores.
    pub arm_supported: bool,
    /// Legs and feet supported with the weight evenly balanced (`Some(true)`: legs score 1,
    /// `Some(false)`: 2); `None` measures it ([`RulaAngles::weight_balanced`]).
    pub legs_supported: Option<bool>,
    /// Seated with the trunk well supported: a trunk flexed 20 degrees or less scores 1.
    pub seated_supported: bool,
}

/// The angles RULA reads on one arm (degrees).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmAngles {
    /// In the trunk's sagittal plane from its down axis: + flexion (forward), - extension.
    pub upper_arm_flexion: f64,
    /// Out of the trunk's sagittal plane: + abduction (outward), - adduction (across).
    pub upper_arm_abduction: f64,
    /// Elevation of the clavicle above rest (+ up); `None` without a sternoclavicular joint.
    pub shoulder_elevation: Option<f64>,
    /// Elbow flexion: 0 with the arm straight.
    pub elbow_flexion: f64,
    /// The wrist lies across the body's midline.
    pub across_midline: bool,
    /// The wrist lies out to the side of the body.
    pub out_to_side: bool,
    /// + flexion (toward the palm), - extension.
    pub wrist_flexion: f64,
    /// + radial deviation (toward the thumb), - ulnar.
    pub wrist_deviation: f64,
    /// Forearm rotation, + pronation, - supination, from the rest (mid) position; `None`
    /// without a pronation/supination DOF.
    pub forearm_rotation: Option<f64>,
    /// Wrist twist score: 1 in the mid-range of pronation/supination, 2 near either end.
    pub wrist_twist: u8,
}

impl Default for ArmAngles {
    /// A neutral arm: every angle 0, wrist twist 1.
    fn default() -> Self {
        Self {
            upper_arm_flexion: 0.0,
            upper_arm_abduction: 0.0,
            shoulder_elevation: None,
            elbow_flexion: 0.0,
            across_midline: false,
            out_to_side: false,
            wrist_flexion: 0.0,
            wrist_deviation: 0.0,
            forearm_rotation: None,
            wrist_twist: 1,
        }
    }
}

/// The angles RULA reads on a posture (degrees; see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RulaAngles {
    /// The left arm.
    pub left: ArmAngles,
    /// The right arm.
    pub right: ArmAngles,
    /// Head against the trunk axis in the trunk's sagittal plane: + flexion, - extension.
    pub neck_flexion: f64,
    /// Head turned about the trunk's up axis (+ to the left).
    pub neck_twist: f64,
    /// Head tilted out of the trunk's sagittal plane (+ to the left).
    pub neck_side_bend: f64,
    /// Trunk against vertical in its sagittal plane: + flexion, - extension.
    pub trunk_flexion: f64,
    /// Shoulder line against hip line, about the trunk's up axis (+ trunk turned left).
    pub trunk_twist: f64,
    /// Trunk tilted out of its sagittal plane (+ to the left).
    pub trunk_side_bend: f64,
    /// Feet level and the centre of mass between them (the legs score 1 unless overridden).
    pub weight_balanced: bool,
}

impl Default for RulaAngles {
    /// The neutral standing posture: every angle 0, weight balanced.
    fn default() -> Self {
        Self {
            left: ArmAngles::default(),
            right: ArmAngles::default(),
            neck_flexion: 0.0,
            neck_twist: 0.0,
            neck_side_bend: 0.0,
            trunk_flexion: 0.0,
            trunk_twist: 0.0,
            trunk_side_bend: 0.0,
            weight_balanced: true,
        }
    }
}

/// The scores of one arm (group A) and its grand score.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RulaArm {
    /// Upper arm, 1-6 (adjustments included).
    pub upper_arm: u8,
    /// Lower arm, 1-3.
    pub lower_arm: u8,
    /// Wrist, 1-4.
    pub wrist: u8,
    /// Wrist twist, 1-2.
    pub wrist_twist: u8,
    /// Posture score A (Table A).
    pub posture_a: u8,
    /// Muscle use score, 0-1.
    pub muscle_use: u8,
    /// Force/load score, 0-3.
    pub load: u8,
    /// Score C = posture score A + muscle use + load.
    pub score_c: u8,
    /// Grand score of this arm with the body (Table C of score C and score D).
    pub grand: u8,
}

/// The brief's name of [`RulaArm`]: the group A part scores of one side.
pub type RulaParts = RulaArm;

/// The scores of the neck, trunk and legs (group B).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RulaBody {
    /// Neck, 1-6 (adjustments included).
    pub neck: u8,
    /// Trunk, 1-6 (adjustments included).
    pub trunk: u8,
    /// Legs, 1-2.
    pub legs: u8,
    /// Posture score B (Table B).
    pub posture_b: u8,
    /// Muscle use score, 0-1.
    pub muscle_use: u8,
    /// Force/load score, 0-3.
    pub load: u8,
    /// Score D = posture score B + muscle use + load.
    pub score_d: u8,
}

/// A RULA assessment.
#[derive(Debug, Clone, PartialEq)]
pub struct RulaReport {
    /// Grand score, 1-7: the worse side's.
    pub score: u8,
    /// Action level, 1-4 ([`action_level`]).
    pub action_level: u8,
    /// The left arm's scores.
    pub left: RulaArm,
    /// The right arm's scores.
    pub right: RulaArm,
    /// The neck, trunk and legs scores.
    pub body: RulaBody,
    /// The angles scored.
    pub angles: RulaAngles,
    /// The band edges used.
    pub variant: RulaVariant,
}

/// A score from a signed sum, kept within `1..=max`.
fn bounded(score: i32, max: u8) -> u8 {
    u8::try_from(score.clamp(1, i32::from(max))).unwrap_or(max)
}

/// The upper arm score of one arm, 1-6.
fn upper_arm_score(arm: &ArmAngles, settings: &RulaSettings) -> u8 {
    let [neutral, middle, high] = settings.variant.upper_arm_edges();
    let tolerances = &settings.tolerances;
    let flexion = arm.upper_arm_flexion;
    let mut score = if flexion < -neutral {
        2
    } else if flexion <= neutral {
        1
    } else if flexion <= middle {
        2
    } else if flexion <= high {
        3
    } else {
        4
    };
    if arm
        .shoulder_elevation
        .is_some_and(|e| e > tolerances.shoulder_raised_deg)
    {
        score += 1;
    }
    if arm.upper_arm_abduction > tolerances.abduction_deg.unwrap_or(neutral) {
        score += 1;
    }
    if settings.arm_supported {
        score -= 1;
    }
    bounded(score, 6)
}

/// The lower arm score of one arm, 1-3.
fn lower_arm_score(arm: &ArmAngles) -> u8 {
    let flexion = arm.elbow_flexion;
    let mut score = if flexion > 60.0 && flexion <= 100.0 {
        1
    } else {
        2
    };
    if arm.across_midline || arm.out_to_side {
        score += 1;
    }
    bounded(score, 3)
}

/// The wrist score of one arm, 1-4.
fn wrist_score(arm: &ArmAngles, tolerances: &RulaTolerances) -> u8 {
    let bend = arm.wrist_flexion.abs();
    let mut score = if bend <= tolerances.wrist_neutral_deg {
        1
    } else if bend <= 15.0 {
        2
    } else {
        3
    };
    if arm.wrist_deviation.abs() > tolerances.wrist_neutral_deg {
        score += 1;
    }
    bounded(score, 4)
}

/// The neck score, 1-6.
fn neck_score(angles: &RulaAngles, tolerances: &RulaTolerances) -> u8 {
    let flexion = angles.neck_flexion;
    let mut score = if flexion < -tolerances.neck_extension_deg {
        4
    } else if flexion <= 10.0 {
        1
    } else if flexion <= 20.0 {
        2
    } else {
        3
    };
    if angles.neck_twist.abs() > tolerances.twist_bend_deg {
        score += 1;
    }
    if angles.neck_side_bend.abs() > tolerances.twist_bend_deg {
        score += 1;
    }
    bounded(score, 6)
}

/// The trunk score, 1-6.
fn trunk_score(angles: &RulaAngles, settings: &RulaSettings) -> u8 {
    let tolerances = &settings.tolerances;
    let flexion = angles.trunk_flexion;
    let mut score = if flexion.abs() <= tolerances.trunk_upright_deg {
        1
    } else if flexion <= 20.0 {
        // Flexion up to 20 degrees, or extension beyond the upright tolerance.
        2
    } else if flexion <= 60.0 {
        3
    } else {
        4
    };
    if settings.seated_supported && flexion <= 20.0 {
        score = 1;
    }
    if angles.trunk_twist.abs() > tolerances.twist_bend_deg {
        score += 1;
    }
    if angles.trunk_side_bend.abs() > tolerances.twist_bend_deg {
        score += 1;
    }
    bounded(score, 6)
}

/// Scores measured angles with the paper's rules (band edges per `settings.variant`,
/// tolerances per `settings.tolerances`).
pub fn score(angles: &RulaAngles, settings: &RulaSettings) -> RulaReport {
    let muscle_use = u8::from(settings.muscle_use);
    let load = settings.load.score();
    let legs_ok = settings.legs_supported.unwrap_or(angles.weight_balanced);
    let neck = neck_score(angles, &settings.tolerances);
    let trunk = trunk_score(angles, settings);
    let legs = if legs_ok { 1 } else { 2 };
    let posture_b = table_b(neck, trunk, legs);
    let body = RulaBody {
        neck,
        trunk,
        legs,
        posture_b,
        muscle_use,
        load,
        score_d: posture_b + muscle_use + load,
    };
    let arm = |angles: &ArmAngles| {
        let upper_arm = upper_arm_score(angles, settings);
        let lower_arm = lower_arm_score(angles);
        let wrist = wrist_score(angles, &settings.tolerances);
        let wrist_twist = angles.wrist_twist.clamp(1, 2);
        let posture_a = table_a(upper_arm, lower_arm, wrist, wrist_twist);
        let score_c = posture_a + muscle_use + load;
        RulaArm {
            upper_arm,
            lower_arm,
            wrist,
            wrist_twist,
            posture_a,
            muscle_use,
            load,
            score_c,
            grand: table_c(score_c, body.score_d),
        }
    };
    let left = arm(&angles.left);
    let right = arm(&angles.right);
    let grand = left.grand.max(right.grand);
    RulaReport {
        score: grand,
        action_level: action_level(grand),
        left,
        right,
        body,
        angles: *angles,
        variant: settings.variant,
    }
}

/// Measures and scores a posture: [`measure`] then [`score`]; `None` when the skeleton lacks a
/// joint RULA needs.
pub fn rula(skeleton: &Skeleton, frames: &Frames, settings: &RulaSettings) -> Option<RulaReport> {
    measure(skeleton, frames).map(|angles| score(&angles, settings))
}

/// Smooth stand-ins of the RULA part scores for the comfort task
/// ([`stance_ik::comfort::ComfortModel::bands`]): per side `l_upper_arm`, `l_lower_arm`,
/// `l_wrist` (and `r_`), then `neck`, `neck_extension` and `trunk` (see the module
/// documentation). Empty when the skeleton lacks a joint [`measure`] needs.
pub fn rula_bands(skeleton: &Skeleton, variant: RulaVariant) -> Vec<AngleBand> {
    let Some(body) = Body::resolve(skeleton) else {
        return Vec::new();
    };
    let width = BAND_WIDTH_DEG.to_radians();
    let ramp = BAND_RAMP;
    let steps = |edges: &[(f64, f64)]| -> Vec<(f64, f64)> {
        edges
            .iter()
            .map(|&(edge, step)| (edge.to_radians(), step))
            .collect()
    };
    let [e1, e2, e3] = variant.upper_arm_edges();
    let mut bands = Vec::new();
    for (prefix, arm) in [("l", body.left), ("r", body.right)] {
        bands.push(AngleBand {
            name: format!("{prefix}_upper_arm"),
            joint: arm.shoulder,
            axis: arm.upper_axis,
            reference: AngleReference::Segment {
                joint: body.trunk,
                axis: DVec3::NEG_Y,
            },
            edges: steps(&[(e1, 1.0), (e2, 1.0), (e3, 1.0)]),
            width,
            ramp,
        });
        bands.push(AngleBand {
            name: format!("{prefix}_lower_arm"),
            joint: arm.elbow,
            axis: arm.forearm_axis,
            reference: AngleReference::Segment {
                joint: arm.shoulder,
                axis: arm.upper_axis,
            },
            edges: steps(&[(60.0, -1.0), (100.0, 1.0)]),
            width,
            ramp,
        });
        bands.push(AngleBand {
            name: format!("{prefix}_wrist"),
            joint: arm.wrist,
            axis: arm.hand_neutral,
            reference: AngleReference::Segment {
                joint: arm.elbow,
                axis: arm.hand_neutral,
            },
            edges: steps(&[(WRIST_NEUTRAL_DEG, 1.0), (15.0, 1.0)]),
            width,
            ramp,
        });
    }
    bands.push(AngleBand {
        name: "neck".into(),
        joint: body.head,
        axis: DVec3::Y,
        reference: AngleReference::Segment {
            joint: body.trunk,
            axis: DVec3::Y,
        },
        edges: steps(&[(10.0, 1.0), (20.0, 1.0)]),
        width,
        ramp,
    });
    // The head's up axis against the trunk's back axis: 90 degrees when not extended, less
    // in extension; the score steps from 1 to 4 there.
    bands.push(AngleBand {
        name: "neck_extension".into(),
        joint: body.head,
        axis: DVec3::Y,
        reference: AngleReference::Segment {
            joint: body.trunk,
            axis: DVec3::NEG_Z,
        },
        edges: steps(&[(90.0 - NECK_EXTENSION_DEG, -3.0)]),
        width,
        ramp,
    });
    bands.push(AngleBand {
        name: "trunk".into(),
        joint: body.trunk,
        axis: DVec3::Y,
        reference: AngleReference::World(DVec3::Y),
        edges: steps(&[(TRUNK_UPRIGHT_DEG, 1.0), (20.0, 1.0), (60.0, 1.0)]),
        width,
        ramp,
    });
    bands
}
