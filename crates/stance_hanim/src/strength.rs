//! Maximal voluntary joint torques of an H-Anim body, for the comfort measures: each rotation
//! DOF's strength about its +axis and -axis ([`stance_ik::comfort::DofStrength`]), in the
//! anatomical conventions of [`crate::anatomy`] (left side; the right side mirrors `ry` and
//! `rz`), mapped onto the built DOF through [`crate::AnatomicalAxis`].
//!
//! # Sources, per joint
//! - **Hip, knee, ankle (flexion and extension):** Anderson, Madigan & Nussbaum (2007),
//!   *Maximum voluntary joint torque as a function of joint angle and angular velocity*,
//!   J. Biomech. 40(14):3105-3113, Table 3, the 18-25-year-old rows (isometric: the angle term
//!   `C1 m g h cos(C2 (theta - C3))`, velocity 0); machine-readable transcription: RBDL's
//!   muscle addon (`addons/muscle/Millard2016TorqueMuscle.cc`, zlib licence). With no sex
//!   given, the mean of the male and female coefficients.
//! - **Shoulder flexion:** 89.9 N m (men, static, arm at 0 deg), "Dynamic shoulder flexion
//!   strength for use in occupational risk analysis and clinical assessment" (abstract).
//!   **Shoulder extension, horizontal ab-/adduction (standing in for frontal-plane abduction
//!   and adduction, for which no open population data was found), internal and external
//!   rotation:** RBDL's whole-body "gymnast" set (Jackson 2010; Kentel et al. 2011), scaled by
//!   the ratio of the population flexion above to the gymnast's (0.986). One elite athlete:
//!   these overstate a typical person, so the loads they give are on the low side.
//! - **Elbow:** flexion 0.78 and extension 0.67 N m per kg of body mass, Lategan & Krueger
//!   (2003), young men, isokinetic peaks (a lower bound of the isometric maximum).
//!   **Forearm pronation / supination:** RBDL gymnast, 13.0 N m both ways.
//! - **Wrist:** flexion 12.2, extension 7.1, radial deviation 11.0, ulnar deviation 9.5 N m
//!   (10 men, isometric; Delp, Grierson & Buchanan 1996, abstract).
//! - **Lower back (the lowest lumbar joint present, L5/S1):** extension 288 N m (men, trunk
//!   flexed 20 deg; Chaffin, Andersson & Martin, *Occupational Biomechanics*, Table 4.5, as
//!   quoted in J. Electromyogr. Kinesiol. 2012;22(6):814), flexion = extension / 1.3
//!   (Beimborn & Morrissey 1988). Lateral bending and twist: no source found, not counted.
//! - **Neck (the lowest cervical joint present, else the skull base):** flexion 30, extension
//!   51, lateral bending 32, axial rotation 13 N m (9 men, isometric; Fice, Siegmund & Blouin
//!   2014, abstract).
//!
//! Constants are for a 70 kg adult and scale with body mass; Anderson's curves scale with
//! mass times stature. DOF without a source (hip and ankle ab-/adduction and rotation, the
//! shoulder girdle, the upper spine, the fingers and toes) carry no strength: their loads
//! are reported in N m but not as shares, and not in the effort.

use stance_ik::Dof::{self, Rx, Ry, Rz};
use stance_ik::comfort::{DofStrength, StrengthCurve};

use stance_ik::Skeleton;

use crate::anatomy::JointClass;
use crate::names::Side;
use crate::{AnatomicalAxis, HumanoidSkeleton};

/// The body mass the constants are given for (kg).
const REFERENCE_MASS: f64 = 70.0;
/// A load above this share of a DOF's strength is flagged (the 15 %).
pub const FLAGGED_SHARE: f64 = 0.15;

/// Whose strength: Anderson's curves differ by sex; with none given, their mean.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Sex {
    /// The mean of the male and female coefficients.
    #[default]
    Unspecified,
    /// Male rows.
    Male,
    /// Female rows.
    Female,
}

/// The body the strengths are scaled to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StrengthProfile {
    /// Sex (Anderson's rows).
    pub sex: Sex,
    /// Body mass (kg).
    pub mass_kg: f64,
    /// Stature (m).
    pub stature_m: f64,
}

impl Default for StrengthProfile {
    fn default() -> Self {
        Self {
            sex: Sex::Unspecified,
            mass_kg: REFERENCE_MASS,
            stature_m: 1.75,
        }
    }
}

/// Anderson et al. (2007) Table 3, isometric columns `(C1, C2, C3)` of the 18-25-year-olds:
/// (male, female).
type Anderson = ([f64; 3], [f64; 3]);
const HIP_EXTENSION: Anderson = ([0.161, 0.958, 0.932], [0.181, 0.697, 1.242]);
const HIP_FLEXION: Anderson = ([0.113, 0.738, -0.214], [0.127, 0.650, -0.350]);
const KNEE_EXTENSION: Anderson = ([0.163, 1.258, 1.133], [0.159, 1.187, 1.274]);
const KNEE_FLEXION: Anderson = ([0.087, 0.869, 0.522], [0.080, 0.873, 0.635]);
/// "Extension" at the ankle is plantar flexion, "flexion" dorsiflexion.
const ANKLE_PLANTAR_FLEXION: Anderson = ([0.095, 1.391, 0.408], [0.104, 1.399, 0.424]);
const ANKLE_DORSIFLEXION: Anderson = ([0.033, 1.510, -0.187], [0.027, 1.079, -0.302]);

/// Anderson's curve for a DOF whose anatomical angle (Anderson's: hip and knee flexion,
/// ankle dorsiflexion positive) is `sign * q`.
fn anderson(coefficients: Anderson, sign: f64, profile: &StrengthProfile) -> StrengthCurve {
    let (male, female) = coefficients;
    let c = match profile.sex {
        Sex::Male => male,
        Sex::Female => female,
        Sex::Unspecified => [0, 1, 2].map(|i| 0.5 * (male[i] + female[i])),
    };
    StrengthCurve {
        peak: c[0] * profile.mass_kg * 9.81 * profile.stature_m,
        width: c[1],
        centre: c[2],
        sign,
        floor: 0.1,
    }
}

/// The strength of an anatomical DOF (left side, [`crate::anatomy`]'s signs), `None` where no
/// source was found.
fn anatomical_strength(
    class: JointClass,
    dof: Dof,
    profile: &StrengthProfile,
    lowest_of_region: bool,
) -> Option<DofStrength> {
    let scale = profile.mass_kg / REFERENCE_MASS;
    let constant = |positive: f64, negative: f64| {
        Some(DofStrength::constant(positive * scale, negative * scale))
    };
    const GYMNAST_TO_POPULATION: f64 = 89.9 / 91.1388;
    match (class, dof) {
        // Hip: +rx is extension; Anderson's hip angle is flexion (= -rx).
        (JointClass::Hip, Rx) => Some(DofStrength {
            positive: anderson(HIP_EXTENSION, -1.0, profile),
            negative: anderson(HIP_FLEXION, -1.0, profile),
        }),
        // Knee: +rx is flexion, Anderson's knee angle too.
        (JointClass::Knee, Rx) => Some(DofStrength {
            positive: anderson(KNEE_FLEXION, 1.0, profile),
            negative: anderson(KNEE_EXTENSION, 1.0, profile),
        }),
        // Ankle: +rx is plantar flexion; Anderson's ankle angle is dorsiflexion (= -rx).
        (JointClass::Ankle, Rx) => Some(DofStrength {
            positive: anderson(ANKLE_PLANTAR_FLEXION, -1.0, profile),
            negative: anderson(ANKLE_DORSIFLEXION, -1.0, profile),
        }),
        // Shoulder: +rx extension, -rx flexion; +rz abduction; +ry external rotation.
        (JointClass::Shoulder, Rx) => constant(127.401 * GYMNAST_TO_POPULATION, 89.9),
        (JointClass::Shoulder, Rz) => constant(
            94.6839 * GYMNAST_TO_POPULATION,
            128.496 * GYMNAST_TO_POPULATION,
        ),
        (JointClass::Shoulder, Ry) => constant(
            43.5837 * GYMNAST_TO_POPULATION,
            50.522 * GYMNAST_TO_POPULATION,
        ),
        // Elbow: +rx extension, -rx flexion (per kg of 70 kg); ry pronation / supination.
        (JointClass::Elbow, Rx) => constant(0.67 * REFERENCE_MASS, 0.78 * REFERENCE_MASS),
        (JointClass::Elbow, Ry) => constant(13.0, 13.0),
        // Wrist: +rz extension, -rz flexion; +rx ulnar, -rx radial deviation.
        (JointClass::Wrist, Rz) => constant(7.1, 12.2),
        (JointClass::Wrist, Rx) => constant(9.5, 11.0),
        // Lower back: +rx flexion (held by the extensors: the -axis strength).
        (JointClass::Spine, Rx) if lowest_of_region => constant(288.0 / 1.3, 288.0),
        // Neck: +rx flexion, rz lateral bending, ry axial rotation.
        (JointClass::Neck, Rx) if lowest_of_region => constant(30.0, 51.0),
        (JointClass::Neck, Rz) if lowest_of_region => constant(32.0, 32.0),
        (JointClass::Neck, Ry) if lowest_of_region => constant(13.0, 13.0),
        _ => None,
    }
}

/// Mirrors a left-side strength onto the right side, where `ry` and `rz` change sign.
fn mirrored(strength: DofStrength, side: Side, dof: Dof) -> DofStrength {
    if side == Side::Right && matches!(dof, Ry | Rz) {
        reversed(strength)
    } else {
        strength
    }
}

/// The same strength about an axis pointing the other way.
fn reversed(strength: DofStrength) -> DofStrength {
    let flip = |c: StrengthCurve| StrengthCurve { sign: -c.sign, ..c };
    DofStrength {
        positive: flip(strength.negative),
        negative: flip(strength.positive),
    }
}

/// The anatomical axis of every rotation DOF of a skeleton whose joint frames are the H-Anim
/// body frame at rest (a problem file's skeleton, the default body): each DOF is its own
/// anatomical axis.
pub fn aligned_axes(skeleton: &Skeleton) -> Vec<Vec<AnatomicalAxis>> {
    skeleton
        .joints()
        .iter()
        .map(|j| {
            j.dofs
                .iter()
                .filter(|d| d.is_rotation())
                .map(|&dof| AnatomicalAxis {
                    dof,
                    anatomical: dof,
                    sign: 1.0,
                })
                .collect()
        })
        .collect()
}

/// The anatomical axes of a built body's joints.
pub fn built_axes(body: &HumanoidSkeleton) -> Vec<Vec<AnatomicalAxis>> {
    body.joints.iter().map(|j| j.axes.clone()).collect()
}

/// Per DOF of `skeleton` (H-Anim joint names; `axes` per joint, see [`built_axes`] and
/// [`aligned_axes`]), its strength (`None`: no source, or a translation).
pub fn dof_strengths(
    skeleton: &Skeleton,
    axes: &[Vec<AnatomicalAxis>],
    profile: &StrengthProfile,
) -> Vec<Option<DofStrength>> {
    let mut out = vec![None; skeleton.dof_count()];
    // The lowest joint of the lumbar spine and of the neck present carry the region's load.
    let lowest = |class: JointClass| {
        skeleton
            .joints()
            .iter()
            .position(|j| !j.dofs.is_empty() && JointClass::of(&j.name) == class)
    };
    let (lowest_spine, lowest_neck) = (lowest(JointClass::Spine), lowest(JointClass::Neck));
    for (j, (joint, joint_axes)) in skeleton.joints().iter().zip(axes).enumerate() {
        let class = JointClass::of(&joint.name);
        let side = Side::of(&joint.name);
        let lowest_of_region = Some(j) == lowest_spine || Some(j) == lowest_neck;
        for axis in joint_axes {
            let Some(strength) =
                anatomical_strength(class, axis.anatomical, profile, lowest_of_region)
            else {
                continue;
            };
            let strength = mirrored(strength, side, axis.anatomical);
            let strength = if axis.sign < 0.0 {
                reversed(strength)
            } else {
                strength
            };
            if let Some(slot) = joint
                .dof_range()
                .find(|&d| skeleton.dof_kinds()[d] == axis.dof)
            {
                out[slot] = Some(strength);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests;
