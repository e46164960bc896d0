//! Words of the H-Anim vocabulary: the side a joint is on, its mirror image, the limbs that
//! carry the closed-form IK, a joint name people can read, and joint lookup through the
//! H-Anim aliases.

use stance_ik::{IkError, Limb, Skeleton};

use crate::joint_by_name;

/// Which side of the body a joint is on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Side {
    /// Name starts with `l_`: the body's left, +X.
    Left,
    /// Name starts with `r_`: the body's right, -X.
    Right,
    /// On the mid-sagittal plane.
    Centre,
}

impl Side {
    /// The side of an H-Anim joint name.
    pub fn of(name: &str) -> Side {
        Side::split(name).0
    }

    /// The side of an H-Anim joint name and the name without its `l_`/`r_` prefix
    /// (`l_elbow` -> (Left, `elbow`); `skullbase` -> (Centre, `skullbase`)).
    pub fn split(name: &str) -> (Side, &str) {
        if let Some(rest) = name.strip_prefix("l_") {
            (Side::Left, rest)
        } else if let Some(rest) = name.strip_prefix("r_") {
            (Side::Right, rest)
        } else {
            (Side::Centre, name)
        }
    }

    /// The other side (the centre stays).
    pub fn mirrored(self) -> Side {
        match self {
            Side::Left => Side::Right,
            Side::Right => Side::Left,
            Side::Centre => Side::Centre,
        }
    }

    /// The name prefix of this side's joints (`l_`, `r_`, none).
    pub fn prefix(self) -> &'static str {
        match self {
            Side::Left => "l_",
            Side::Right => "r_",
            Side::Centre => "",
        }
    }
}

/// The other side's joint name (`l_` <-> `r_`); central joints keep theirs.
pub fn mirror_name(name: &str) -> String {
    let (side, rest) = Side::split(name);
    format!("{}{rest}", side.mirrored().prefix())
}

/// A joint name for people: `l_talocrural` -> "left ankle", `r_carpal_interphalangeal_2` ->
/// "right carpal interphalangeal 2".
pub fn readable_name(name: &str) -> String {
    let (side, rest) = Side::split(name);
    let side = match side {
        Side::Left => "left ",
        Side::Right => "right ",
        Side::Centre => "",
    };
    let common = match rest {
        "talocrural" => Some("ankle"),
        "radiocarpal" => Some("wrist"),
        "sternoclavicular" => Some("collarbone"),
        "acromioclavicular" => Some("shoulder blade"),
        "skullbase" => Some("head"),
        "sacroiliac" => Some("pelvis"),
        "humanoid_root" => Some("body root"),
        "metatarsophalangeal_2" => Some("toes"),
        "tarsometatarsal_2" => Some("midfoot"),
        _ => None,
    };
    match common {
        Some(common) => format!("{side}{common}"),
        None => format!("{side}{}", rest.replace('_', " ")),
    }
}

/// The joint of `skeleton` named `name`, or failing that one of its H-Anim aliases (an
/// avatar's skeleton keeps the names its file gave where they are H-Anim 1.1 names).
pub fn resolve_joint(skeleton: &Skeleton, name: &str) -> Option<usize> {
    if let Some(joint) = skeleton.joint_index(name) {
        return Some(joint);
    }
    let (_, definition) = joint_by_name(name)?;
    std::iter::once(definition.name)
        .chain(definition.aliases.iter().copied())
        .find_map(|alias| skeleton.joint_index(alias))
}

/// A limb the closed-form IK drives: three joints (upper, middle, end) and a swivel angle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LimbName {
    /// `l_shoulder`, `l_elbow`, `l_radiocarpal`.
    LeftArm,
    /// `r_shoulder`, `r_elbow`, `r_radiocarpal`.
    RightArm,
    /// `l_hip`, `l_knee`, `l_talocrural`.
    LeftLeg,
    /// `r_hip`, `r_knee`, `r_talocrural`.
    RightLeg,
}

/// The joints of an arm and of a leg, without their side prefix.
const ARM: [&str; 3] = ["shoulder", "elbow", "radiocarpal"];
const LEG: [&str; 3] = ["hip", "knee", "talocrural"];

impl LimbName {
    /// All four, in link order.
    pub const ALL: [LimbName; 4] = [
        LimbName::LeftArm,
        LimbName::RightArm,
        LimbName::LeftLeg,
        LimbName::RightLeg,
    ];

    /// `"l_arm"`, `"r_arm"`, `"l_leg"`, `"r_leg"`.
    pub fn name(self) -> &'static str {
        match self {
            LimbName::LeftArm => "l_arm",
            LimbName::RightArm => "r_arm",
            LimbName::LeftLeg => "l_leg",
            LimbName::RightLeg => "r_leg",
        }
    }

    /// Parses `"l_arm"`...
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|limb| limb.name() == name)
    }

    /// The side the limb is on.
    pub fn side(self) -> Side {
        match self {
            LimbName::LeftArm | LimbName::LeftLeg => Side::Left,
            LimbName::RightArm | LimbName::RightLeg => Side::Right,
        }
    }

    /// The same limb on the other side.
    pub fn mirrored(self) -> LimbName {
        match self {
            LimbName::LeftArm => LimbName::RightArm,
            LimbName::RightArm => LimbName::LeftArm,
            LimbName::LeftLeg => LimbName::RightLeg,
            LimbName::RightLeg => LimbName::LeftLeg,
        }
    }

    /// The H-Anim names of the root, middle and end joints of the limb.
    pub fn joints(self) -> [&'static str; 3] {
        match self {
            LimbName::LeftArm => ["l_shoulder", "l_elbow", "l_radiocarpal"],
            LimbName::RightArm => ["r_shoulder", "r_elbow", "r_radiocarpal"],
            LimbName::LeftLeg => ["l_hip", "l_knee", "l_talocrural"],
            LimbName::RightLeg => ["r_hip", "r_knee", "r_talocrural"],
        }
    }

    /// The limb a joint of it belongs to (`r_elbow` -> right arm); `None` elsewhere.
    pub fn of_joint(name: &str) -> Option<LimbName> {
        let (side, rest) = Side::split(name);
        let arm = ARM.contains(&rest);
        let leg = LEG.contains(&rest);
        match (side, arm, leg) {
            (Side::Left, true, _) => Some(LimbName::LeftArm),
            (Side::Right, true, _) => Some(LimbName::RightArm),
            (Side::Left, _, true) => Some(LimbName::LeftLeg),
            (Side::Right, _, true) => Some(LimbName::RightLeg),
            _ => None,
        }
    }

    /// The limb's (upper, middle, end) joint indices on `skeleton`, through the H-Anim aliases;
    /// `None` when one is missing.
    pub fn joint_indices(self, skeleton: &Skeleton) -> Option<[usize; 3]> {
        let [upper, middle, end] = self.joints();
        Some([
            resolve_joint(skeleton, upper)?,
            resolve_joint(skeleton, middle)?,
            resolve_joint(skeleton, end)?,
        ])
    }

    /// The closed-form limb on `skeleton`.
    pub fn on(self, skeleton: &Skeleton) -> Result<Limb, IkError> {
        let indices = self
            .joint_indices(skeleton)
            .ok_or_else(|| IkError::UnknownJoint(self.joints()[0].to_owned()))?;
        let names = indices.map(|joint| {
            skeleton
                .joints()
                .get(joint)
                .map_or("", |definition| definition.name.as_str())
        });
        Limb::from_names(skeleton, names)
    }

    /// The limbs of [`LimbName::ALL`] that `skeleton` has, for the solver's hybrid restarts
    /// (the paper's conclusion: a stalled solve restarts a limb from its closed form). The one
    /// list the editor, problem files and the `stance-ik` package give the solver.
    pub fn all_on(skeleton: &Skeleton) -> Vec<Limb> {
        Self::ALL
            .iter()
            .filter_map(|limb| limb.on(skeleton).ok())
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sides_split_and_mirror() {
        assert_eq!(Side::split("l_elbow"), (Side::Left, "elbow"));
        assert_eq!(Side::split("r_hip"), (Side::Right, "hip"));
        assert_eq!(Side::split("vl5"), (Side::Centre, "vl5"));
        assert_eq!(
            mirror_name("l_carpal_interphalangeal_2"),
            "r_carpal_interphalangeal_2"
        );
        assert_eq!(mirror_name("r_knee"), "l_knee");
        assert_eq!(mirror_name("skullbase"), "skullbase");
    }

    #[test]
    fn readable_names_use_everyday_words() {
        assert_eq!(readable_name("l_talocrural"), "left ankle");
        assert_eq!(readable_name("r_radiocarpal"), "right wrist");
        assert_eq!(readable_name("skullbase"), "head");
        assert_eq!(
            readable_name("r_carpal_interphalangeal_2"),
            "right carpal interphalangeal 2"
        );
    }

    #[test]
    fn every_limb_joint_names_its_limb_and_mirrors_onto_the_other() {
        for limb in LimbName::ALL {
            assert_eq!(LimbName::from_name(limb.name()), Some(limb));
            for joint in limb.joints() {
                assert_eq!(LimbName::of_joint(joint), Some(limb), "{joint}");
                assert_eq!(
                    LimbName::of_joint(&mirror_name(joint)),
                    Some(limb.mirrored())
                );
            }
            assert_eq!(limb.side(), Side::of(limb.joints()[0]));
        }
        assert_eq!(LimbName::of_joint("skullbase"), None);
        assert_eq!(LimbName::of_joint("l_sternoclavicular"), None);
    }

    #[test]
    fn limbs_are_found_on_the_built_skeleton() {
        let body = crate::default_skeleton(&crate::SkeletonOptions::default());
        let Ok(body) = body else {
            panic!("the LOA 2 body builds");
        };
        for limb in LimbName::ALL {
            let indices = limb.joint_indices(&body.skeleton);
            assert!(indices.is_some(), "{}", limb.name());
            assert!(limb.on(&body.skeleton).is_ok());
        }
    }
}
