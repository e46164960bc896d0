//! The body as capsules (`stance_ik::Capsule`): one per bone (a segment from a joint to its
//! child), a head above the skull base and two bars across the chest, each fixed in the frame
//! of the joint that carries it, with radii from the segment it stands for (thigh, forearm...).
//! The mannequin is drawn with them and the collision task holds them apart, so that what is
//! drawn is what collides.
//!
//! Radii (m) are for an adult of the default body's size, from segment girths of the
//! anthropometric tables the body's proportions come from, rounded: a modelling choice, not
//! a measurement of any one avatar.

use std::collections::BTreeMap;

use glam::DVec3;
use stance_ik::{
    COLLISION_BAND, Capsule, Collision, Frames, Posture, Skeleton, collision_pairs, floor_capsules,
};

/// The head's capsule above the skull base, along the joint's +Y: from, to (m) and radius.
const HEAD: (f64, f64, f64) = (0.07, 0.15, 0.095);
/// The chest bars' radius (m), and the share of their length cut from each end.
const CHEST: (f64, f64) = (0.085, 0.15);

/// Radius (m) of the bone from joint `parent` to joint `child` (H-Anim names; either side).
pub fn segment_radius(parent: &str, child: &str) -> f64 {
    let side_free = |name: &str| -> String {
        name.strip_prefix("l_")
            .or_else(|| name.strip_prefix("r_"))
            .unwrap_or(name)
            .to_owned()
    };
    let parent = side_free(parent);
    let child = side_free(child);
    match (parent.as_str(), child.as_str()) {
        ("humanoid_root", "sacroiliac") => 0.11,
        ("humanoid_root", _) => 0.12,
        ("sacroiliac", "hip") => 0.09,
        ("hip", _) => 0.068,
        ("knee", _) => 0.05,
        ("talocrural", _) => 0.038,
        ("tarsometatarsal_2", _) => 0.034,
        ("metatarsophalangeal_2", _) => 0.026,
        (p, "sternoclavicular") if p.starts_with('v') => 0.07,
        ("sternoclavicular", _) => 0.055,
        ("acromioclavicular", _) => 0.055,
        ("shoulder", _) => 0.047,
        ("elbow", _) => 0.038,
        ("radiocarpal", _) => 0.022,
        (p, _) if p.starts_with("carpometacarpal") => 0.014,
        (p, _) if p.starts_with("metacarpophalangeal") || p.starts_with("carpal") => 0.009,
        (p, c) if p.starts_with("vc") || c.starts_with("vc") || c == "skullbase" => 0.05,
        (p, _) if p.starts_with("vl") || p.starts_with("vt") => 0.125,
        _ => 0.03,
    }
}

/// The capsules of `skeleton` (H-Anim names give the radii; other names get 3 cm), placed at
/// its rest posture: a bone per joint with a parent, in the parent's frame; the head above
/// `skullbase`; bars between the collarbones and between the shoulders, carried by the
/// vertebra the left collarbone hangs from.
pub fn body_capsules(skeleton: &Skeleton) -> Vec<Capsule> {
    let rest = Frames::new(skeleton, &Posture::rest(skeleton));
    let joints = skeleton.joints();
    // A rest-pose world point in the frame of `joint`.
    let local = |joint: usize, world: DVec3| {
        rest.world_from_joint_rotation[joint].transpose() * (world - rest.joint_position[joint])
    };
    let mut capsules = Vec::with_capacity(joints.len() + 3);
    for (index, joint) in joints.iter().enumerate() {
        let Some(parent) = joint.parent else {
            continue;
        };
        capsules.push(Capsule {
            joint: parent,
            start: DVec3::ZERO,
            end: local(parent, rest.joint_position[index]),
            radius: segment_radius(&joints[parent].name, &joint.name),
        });
        if joint.name == "skullbase" {
            capsules.push(Capsule {
                joint: index,
                start: DVec3::Y * HEAD.0,
                end: DVec3::Y * HEAD.1,
                radius: HEAD.2,
            });
        }
    }
    let find = |name: &str| skeleton.joint_index(name);
    let Some(chest) = find("l_sternoclavicular").and_then(|j| joints[j].parent) else {
        return capsules;
    };
    for (left, right) in [
        ("l_sternoclavicular", "r_sternoclavicular"),
        ("l_shoulder", "r_shoulder"),
    ] {
        if let (Some(left), Some(right)) = (find(left), find(right)) {
            let (left, right) = (rest.joint_position[left], rest.joint_position[right]);
            let inset = (right - left) * CHEST.1;
            capsules.push(Capsule {
                joint: chest,
                start: local(chest, left + inset),
                end: local(chest, right - inset),
                radius: CHEST.0,
            });
        }
    }
    capsules
}

/// A body's collision task, as a problem file or a document asks for it: which collisions
/// it holds and how far apart, on [`body_capsules`] with some radii set by hand.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyCollision {
    /// Distance kept between surfaces (m).
    pub margin: f64,
    /// The body's capsules kept apart from each other ([`collision_pairs`]).
    pub self_collision: bool,
    /// The body's capsules kept above the floor ([`floor_capsules`]).
    pub floor: bool,
    /// Radius (m) of every capsule a joint (by index) carries, instead of its segment's.
    pub radius: BTreeMap<usize, f64>,
    /// Constraints held at once.
    pub rows: usize,
}

/// How much further than the margin and the band two capsules may be apart at rest and still
/// be taken as touching (m): the body's capsules are a coarse model, and pairs within a few
/// millimetres of contact standing at rest (an upper arm beside the collarbones' bar, a hand
/// beside the pelvis) touch as soon as the limb turns about its root; held apart, they would
/// stop an arm from crossing the chest.
pub const REST_TOUCH: f64 = 0.005;

/// A collision task's default margin (m).
pub const COLLISION_MARGIN: f64 = 0.01;
/// The most constraints a body's collision task holds at once: a level has rows only for the
/// constraints found, so a larger number costs nothing while the body is clear.
pub const COLLISION_ROWS: usize = 16;

impl Default for BodyCollision {
    fn default() -> Self {
        Self {
            margin: COLLISION_MARGIN,
            self_collision: true,
            floor: true,
            radius: BTreeMap::new(),
            rows: COLLISION_ROWS,
        }
    }
}

impl BodyCollision {
    /// The collision task's data on `skeleton`: its capsules (radii set by `radius` where
    /// given), the pairs clear at rest by the margin, the band and [`REST_TOUCH`]
    /// (`self_collision`), the
    /// capsules clear of the floor at rest (`floor`).
    pub fn collision(&self, skeleton: &Skeleton) -> Collision {
        let mut capsules = body_capsules(skeleton);
        for capsule in &mut capsules {
            if let Some(&r) = self.radius.get(&capsule.joint) {
                capsule.radius = r;
            }
        }
        let rest = Frames::new(skeleton, &Posture::rest(skeleton));
        let pairs = if self.self_collision {
            collision_pairs(
                skeleton,
                &capsules,
                &rest,
                self.margin + COLLISION_BAND + REST_TOUCH,
            )
        } else {
            Vec::new()
        };
        let floor = if self.floor {
            floor_capsules(&capsules, &rest)
        } else {
            Vec::new()
        };
        Collision::new(skeleton, capsules, pairs, floor, self.margin, self.rows)
    }

    /// What `collision` holds, where it is a body's collision task on `skeleton` (the body's
    /// capsules with the radii of one joint alike, the pairs and floor capsules of
    /// [`BodyCollision::collision`], any obstacles); `None` for any other.
    pub fn of(skeleton: &Skeleton, collision: &Collision) -> Option<Self> {
        let defaults = body_capsules(skeleton);
        if defaults.len() != collision.capsules().len() {
            return None;
        }
        let mut radius = BTreeMap::new();
        for (default, capsule) in defaults.iter().zip(collision.capsules()) {
            if capsule.radius != default.radius {
                radius.insert(capsule.joint, capsule.radius);
            }
        }
        let found = Self {
            margin: collision.margin(),
            self_collision: !collision.pairs().is_empty(),
            floor: !collision.floor().is_empty(),
            radius,
            rows: collision.rows(),
        };
        // Obstacles are the problem's or the scene's, not the body's: compared as they are.
        let rebuilt = found
            .collision(skeleton)
            .with_obstacles(collision.obstacles().to_vec());
        (rebuilt == *collision).then_some(found)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

    use super::*;
    use crate::{LevelOfArticulation, SkeletonOptions, default_skeleton};

    /// Catches capsules carried by the wrong joint or placed off their bones: at the rest
    /// posture each bone's capsule runs from its parent's centre to its child's, the thigh
    /// is thicker than the shank, the head sits above the skull base; a bent elbow carries
    /// the forearm's capsule with it (its end is the wrist's centre).
    #[test]
    fn capsules_follow_their_bones() {
        let body = default_skeleton(&SkeletonOptions {
            loa: LevelOfArticulation::Loa2,
            ..SkeletonOptions::default()
        })
        .unwrap();
        let s = &body.skeleton;
        let capsules = body_capsules(s);
        let rest = Frames::new(s, &Posture::rest(s));
        let at = |name: &str| s.joint_index(name).unwrap();
        let bone = |parent: &str| {
            capsules
                .iter()
                .find(|c| c.joint == at(parent) && c.start == DVec3::ZERO)
                .copied()
                .unwrap()
        };
        let (a, b) = bone("l_hip").world(&rest);
        assert!((a - rest.joint_position[at("l_hip")]).length() < 1e-12);
        assert!((b - rest.joint_position[at("l_knee")]).length() < 1e-12);
        assert!(bone("l_hip").radius > bone("l_knee").radius);
        let head = capsules
            .iter()
            .find(|c| c.joint == at("skullbase"))
            .unwrap();
        assert!(head.world(&rest).0.y > rest.joint_position[at("skullbase")].y);
        let mut posture = Posture::rest(s);
        let elbow = s.joints()[at("l_elbow")].rotation_dof[0].unwrap();
        posture.values_mut()[elbow] = -1.2;
        let bent = Frames::new(s, &posture);
        let (_, wrist) = bone("l_elbow").world(&bent);
        assert!((wrist - bent.joint_position[at("l_radiocarpal")]).length() < 1e-12);
        assert!((wrist - rest.joint_position[at("l_radiocarpal")]).length() > 0.1);
        // Two chest bars on the vertebra the collarbones hang from.
        let chest = s.joints()[at("l_sternoclavicular")].parent.unwrap();
        let bars = capsules
            .iter()
            .filter(|c| c.joint == chest && c.radius == CHEST.0)
            .count();
        assert_eq!(bars, 2);
    }
}
