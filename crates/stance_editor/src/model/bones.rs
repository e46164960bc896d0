//! The posed mannequin's bones: one capsule per bone with the joint that carries it, as the
//! viewport draws and picks them.

use glam::{DVec3, Vec3};
use stance_render::{MannequinBone, MannequinJoint, mannequin_bones};

use crate::posing::PosingSession;

/// The bones of `session`'s body in its current posture.
pub fn posed_bones(session: &PosingSession) -> Vec<MannequinBone> {
    let skeleton = session.skeleton();
    let frames = session.frames();
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
                .map_or(Vec3::Y, |rotation| (*rotation * DVec3::Y).as_vec3()),
        })
        .collect();
    mannequin_bones(&joints)
}
