//! The H-Anim 2.0 humanoid (ISO/IEC 19774-1:2019): the joint vocabulary, levels of
//! articulation (LOA) 1 to 4 and default joint centres.
//!
//! Also: per-joint DOF and anatomical ranges of motion ([`anatomy`], AAOS / Kapandji), segment
//! masses (de Leva 1996), bone-name mapping of avatars onto H-Anim ([`mapping`]) and the
//! builder of `stance_ik` skeletons at a chosen LOA ([`builder`]), and joint chains that act
//! together, such as the spine an upper-back sensor drives ([`chains`]), and hand poses: presets
//! and finger curl ([`hands`]).
//!
//! Frame: +Y up, +Z the front of the body, +X the body's left; metres.

#![warn(missing_docs)]

pub mod anatomy;
pub mod builder;
pub mod capsules;
pub mod chains;
pub mod comfort;
pub mod families;
pub mod frame;
pub mod hands;
mod joint_table;
pub mod keypoints;
pub mod mapping;
pub mod names;
pub mod rest_match;
pub mod scenarios;
pub mod sites;
pub mod strength;

pub use builder::{
    AnatomicalAxis, BuildError, BuiltJoint, HumanoidSkeleton, SkeletonOptions, build_skeleton,
    default_skeleton,
};
pub use mapping::{JointMatch, Mapping, MappingError, MatchMethod, SourceJoint, vrm_bone_to_hanim};
pub use names::{LimbName, Side, mirror_name, readable_name, resolve_joint};

use glam::DVec3;

/// One joint of the H-Anim 2.0 vocabulary, as listed by the X3D Unified Object Model 4.0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointDefinition {
    /// Normative joint name, e.g. `l_shoulder`.
    pub name: &'static str,
    /// Lowest level of articulation at which the joint is present (0 for `humanoid_root`).
    pub first_loa: u8,
    /// Index (into [`all_joints`]) of the nearest ancestor present at LOA 1, 2, 3, 4.
    pub parent_by_loa: [Option<usize>; 4],
    /// Default joint centre in metres, when X3DUOM gives one.
    pub default_centre: Option<[f64; 3]>,
    /// Joint centre of the Web3D "Jin" LOA4 example, present for every joint.
    pub jin_centre: [f64; 3],
    /// Older or alternative names of the joint (H-Anim 1.1 names among them).
    pub aliases: &'static [&'static str],
}

impl JointDefinition {
    /// The default centre, falling back on the Jin example where X3DUOM gives none.
    pub fn centre(&self) -> DVec3 {
        DVec3::from_array(self.default_centre.unwrap_or(self.jin_centre))
    }
}

/// A level of articulation: how many joints a humanoid has (H-Anim 2.0, Annex A).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum LevelOfArticulation {
    /// 18 joints: whole limbs, a 3-joint spine.
    Loa1 = 1,
    /// 71 joints: feet, hands with fingers, a fuller spine.
    Loa2 = 2,
    /// 94 joints.
    Loa3 = 3,
    /// All 146 joints.
    Loa4 = 4,
}

impl LevelOfArticulation {
    /// All levels, lowest first.
    pub const ALL: [Self; 4] = [Self::Loa1, Self::Loa2, Self::Loa3, Self::Loa4];

    /// The level's number, 1 to 4.
    pub fn number(self) -> u8 {
        self as u8
    }

    /// The level of a number, 1 to 4.
    pub fn from_number(n: u8) -> Option<Self> {
        Self::ALL.into_iter().find(|l| l.number() == n)
    }
}

/// All 146 H-Anim 2.0 joints in X3DUOM index order: a depth-first order, parents first.
pub fn all_joints() -> &'static [JointDefinition] {
    joint_table::JOINTS
}

/// Looks a joint up by its normative name or one of its aliases.
pub fn joint_by_name(name: &str) -> Option<(usize, &'static JointDefinition)> {
    all_joints()
        .iter()
        .enumerate()
        .find(|(_, joint)| joint.name == name || joint.aliases.contains(&name))
}

/// One joint of a humanoid at a given level of articulation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HumanoidJoint {
    /// The H-Anim definition of the joint.
    pub definition: &'static JointDefinition,
    /// Index of the parent in the same [`humanoid_joints`] list; `None` for the root.
    pub parent: Option<usize>,
    /// Joint centre in the rest pose, metres.
    pub rest_centre: DVec3,
}

/// The default centre of a joint; where X3DUOM gives none (2 joints up to LOA2:
/// `l_carpal_distal_interphalangeal_4`, `r_carpometacarpal_2`), the mirror image of its
/// other-side partner's default, else the Jin example's centre.
pub fn default_centre(definition: &JointDefinition) -> DVec3 {
    if let Some(c) = definition.default_centre {
        return DVec3::from_array(c);
    }
    let partner = (Side::of(definition.name) != Side::Centre).then(|| mirror_name(definition.name));
    partner
        .and_then(|p| joint_by_name(&p))
        .and_then(|(_, d)| d.default_centre)
        .map_or_else(|| definition.centre(), |c| DVec3::new(-c[0], c[1], c[2]))
}

/// The joints present at `loa`, parents first, with parents re-indexed into the returned list.
pub fn humanoid_joints(loa: LevelOfArticulation) -> Vec<HumanoidJoint> {
    let level = usize::from(loa.number());
    let mut position_in_list = vec![None; all_joints().len()];
    let mut joints = Vec::new();
    for (table_index, definition) in all_joints().iter().enumerate() {
        if usize::from(definition.first_loa) > level {
            continue;
        }
        let parent = definition.parent_by_loa[level - 1]
            .and_then(|parent_index| position_in_list.get(parent_index).copied().flatten());
        position_in_list[table_index] = Some(joints.len());
        joints.push(HumanoidJoint {
            definition,
            parent,
            rest_centre: default_centre(definition),
        });
    }
    joints
}

#[cfg(test)]
mod tests {
    #[cfg(target_arch = "wasm32")]
    use wasm_bindgen_test::wasm_bindgen_test as test;
    #[cfg(target_arch = "wasm32")]
    wasm_bindgen_test::wasm_bindgen_test_configure!(run_in_browser);

    use super::*;

    #[test]
    fn joint_counts_per_level_match_the_standard() {
        let counts: Vec<usize> = LevelOfArticulation::ALL
            .iter()
            .map(|&loa| humanoid_joints(loa).len())
            .collect();
        assert_eq!(counts, vec![18, 71, 94, 146]);
    }

    #[test]
    fn every_joint_but_the_root_has_a_parent_listed_before_it() {
        for loa in LevelOfArticulation::ALL {
            let joints = humanoid_joints(loa);
            assert_eq!(joints[0].definition.name, "humanoid_root");
            assert!(joints[0].parent.is_none());
            for (index, joint) in joints.iter().enumerate().skip(1) {
                let parent = joint.parent.unwrap_or_else(|| {
                    panic!("{} has no parent at {loa:?}", joint.definition.name)
                });
                assert!(parent < index);
            }
        }
    }

    #[test]
    fn skullbase_hangs_from_vc2_at_loa2_and_from_vl5_at_loa1() {
        let loa2 = humanoid_joints(LevelOfArticulation::Loa2);
        let skullbase = loa2
            .iter()
            .find(|j| j.definition.name == "skullbase")
            .unwrap();
        assert_eq!(loa2[skullbase.parent.unwrap()].definition.name, "vc2");
        let loa1 = humanoid_joints(LevelOfArticulation::Loa1);
        let skullbase = loa1
            .iter()
            .find(|j| j.definition.name == "skullbase")
            .unwrap();
        assert_eq!(loa1[skullbase.parent.unwrap()].definition.name, "vl5");
    }

    #[test]
    fn loa2_joints_without_a_default_take_their_partners_mirror_image() {
        let joints = humanoid_joints(LevelOfArticulation::Loa2);
        let at = |n: &str| {
            joints
                .iter()
                .find(|j| j.definition.name == n)
                .unwrap()
                .rest_centre
        };
        let l = at("l_carpal_distal_interphalangeal_4");
        let r = at("r_carpal_distal_interphalangeal_4");
        assert!((l - DVec3::new(-r.x, r.y, r.z)).length() < 1e-12);
        // Between its neighbours on the finger, not on another body's hand.
        assert!(l.y < at("l_carpal_proximal_interphalangeal_4").y && l.y > 0.65);
    }

    #[test]
    fn aliases_resolve_to_the_normative_joint() {
        let (_, ankle) = joint_by_name("l_ankle").unwrap();
        assert_eq!(ankle.name, "l_talocrural");
        assert!(joint_by_name("no_such_joint").is_none());
    }

    #[test]
    fn default_body_is_a_standing_person_about_1_7_metres_tall() {
        let joints = humanoid_joints(LevelOfArticulation::Loa2);
        let top = joints
            .iter()
            .map(|j| j.rest_centre.y)
            .fold(f64::MIN, f64::max);
        let bottom = joints
            .iter()
            .map(|j| j.rest_centre.y)
            .fold(f64::MAX, f64::min);
        assert!((1.55..1.75).contains(&top), "skullbase height {top}");
        assert!(bottom.abs() < 0.01, "the soles touch the floor: {bottom}");
        let (_, hip) = joint_by_name("l_hip").unwrap();
        assert!(hip.centre().x > 0.0, "l_ joints are on +X");
    }
}
