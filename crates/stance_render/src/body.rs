//! The mannequin: a humanoid drawn as one shaded capsule per bone, with radii from the
//! segment each bone stands for (thigh, forearm, ...), so that any H-Anim skeleton reads
//! as a person before it has a skinned mesh.

use glam::Vec3;

use crate::Capsule;

/// The mannequin's colour (linear RGB): a warm clay tone.
pub const BODY_COLOR_LINEAR: [f32; 4] = [0.62, 0.26, 0.12, 1.0];

/// Radius of the bone that goes from joint `parent` to joint `child` (H-Anim names), metres.
fn bone_radius_m(parent: &str, child: &str) -> f32 {
    let side_free = |name: &str| {
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

/// One joint of a posed skeleton, as the mannequin needs it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MannequinJoint<'a> {
    /// The joint's H-Anim name (`r_shoulder`, `skullbase`...).
    pub name: &'a str,
    /// Index of the parent joint in the same slice; `None` for the root.
    pub parent: Option<usize>,
    /// Joint centre, world frame, metres.
    pub position_world: Vec3,
    /// World direction of the joint's local +Y axis (up the body in the rest pose).
    pub up_world: Vec3,
}

/// One capsule of the mannequin and the joint whose frame carries it (a bone from a joint to
/// its child moves with the joint: the upper arm belongs to the shoulder).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MannequinBone {
    /// The capsule drawn for this bone.
    pub capsule: Capsule,
    /// Index into the joints the mannequin was built from.
    pub owner: usize,
}

/// Capsules for a posed skeleton: one per bone, a head above `skullbase`, a chest bar
/// between the collarbones.
pub fn mannequin_capsules(joints: &[MannequinJoint<'_>]) -> Vec<Capsule> {
    mannequin_bones(joints)
        .into_iter()
        .map(|bone| bone.capsule)
        .collect()
}

/// The mannequin's capsules with the joint that owns each (for picking and highlighting).
pub fn mannequin_bones(joints: &[MannequinJoint<'_>]) -> Vec<MannequinBone> {
    let mut bones = Vec::with_capacity(joints.len() + 2);
    let bone = |start_world, end_world, radius_m, owner| MannequinBone {
        capsule: Capsule {
            start_world,
            end_world,
            radius_m,
            color_linear: BODY_COLOR_LINEAR,
        },
        owner,
    };
    for (index, joint) in joints.iter().enumerate() {
        let Some((parent_index, parent)) = joint
            .parent
            .and_then(|parent_index| Some((parent_index, joints.get(parent_index)?)))
        else {
            continue;
        };
        bones.push(bone(
            parent.position_world,
            joint.position_world,
            bone_radius_m(parent.name, joint.name),
            parent_index,
        ));
        if joint.name == "skullbase" {
            let up = joint.up_world.normalize_or(Vec3::Y);
            bones.push(bone(
                joint.position_world + up * 0.07,
                joint.position_world + up * 0.15,
                0.095,
                index,
            ));
        }
    }
    let find = |name: &str| joints.iter().find(|joint| joint.name == name);
    // The chest moves with the vertebra the collarbones hang from.
    let Some(chest_owner) = find("l_sternoclavicular").and_then(|joint| joint.parent) else {
        return bones;
    };
    for (left, right) in [
        ("l_sternoclavicular", "r_sternoclavicular"),
        ("l_shoulder", "r_shoulder"),
    ] {
        if let (Some(left), Some(right)) = (find(left), find(right)) {
            let owner = chest_owner;
            let inset = (right.position_world - left.position_world) * 0.15;
            bones.push(bone(
                left.position_world + inset,
                right.position_world - inset,
                0.085,
                owner,
            ));
        }
    }
    bones
}

/// The mannequin's bones of `skeleton` posed as `frames` (its forward kinematics) say.
pub fn posed_mannequin_bones(
    skeleton: &stance_ik::Skeleton,
    frames: &stance_ik::Frames,
) -> Vec<MannequinBone> {
    let joints: Vec<MannequinJoint<'_>> = skeleton
        .joints()
        .iter()
        .enumerate()
        .map(|(index, joint)| MannequinJoint {
            name: &joint.name,
            parent: joint.parent,
            position_world: frames
                .joint_position
                .get(index)
                .copied()
                .unwrap_or_default()
                .as_vec3(),
            up_world: frames
                .world_from_joint_rotation
                .get(index)
                .map_or(Vec3::Y, |rotation| (*rotation * glam::DVec3::Y).as_vec3()),
        })
        .collect();
    mannequin_bones(&joints)
}

/// The mannequin of the H-Anim default humanoid standing in its rest pose at `loa`.
pub fn rest_pose_capsules(loa: stance_hanim::LevelOfArticulation) -> Vec<Capsule> {
    let joints = stance_hanim::humanoid_joints(loa);
    let mannequin: Vec<MannequinJoint<'_>> = joints
        .iter()
        .map(|joint| MannequinJoint {
            name: joint.definition.name,
            parent: joint.parent,
            position_world: joint.rest_centre.as_vec3(),
            up_world: Vec3::Y,
        })
        .collect();
    mannequin_capsules(&mannequin)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_leg_gets_a_thigh_thicker_than_its_shank_and_the_skull_a_head() {
        let joints = [
            MannequinJoint {
                name: "sacroiliac",
                parent: None,
                position_world: Vec3::Y,
                up_world: Vec3::Y,
            },
            MannequinJoint {
                name: "l_hip",
                parent: Some(0),
                position_world: Vec3::new(0.1, 0.9, 0.0),
                up_world: Vec3::Y,
            },
            MannequinJoint {
                name: "l_knee",
                parent: Some(1),
                position_world: Vec3::new(0.1, 0.5, 0.0),
                up_world: Vec3::Y,
            },
            MannequinJoint {
                name: "l_talocrural",
                parent: Some(2),
                position_world: Vec3::new(0.1, 0.07, 0.0),
                up_world: Vec3::Y,
            },
            MannequinJoint {
                name: "skullbase",
                parent: Some(0),
                position_world: Vec3::new(0.0, 1.6, 0.0),
                up_world: Vec3::Y,
            },
        ];
        let capsules = mannequin_capsules(&joints);
        assert_eq!(capsules.len(), 5);
        assert!(capsules[1].radius_m > capsules[2].radius_m);
        let head = capsules[4];
        assert!(head.start_world.y > 1.6 && head.radius_m > 0.08);
    }
}
