//! The mannequin: a humanoid drawn as the body's capsules (`stance_hanim::capsules`: one per
//! bone, radii from the segment each stands for), so that any H-Anim skeleton reads as a
//! person before it has a skinned mesh, and what is drawn is what collides.

use crate::Capsule;

/// The mannequin's colour (linear RGB): a warm clay tone.
pub const BODY_COLOR_LINEAR: [f32; 4] = [0.62, 0.26, 0.12, 1.0];

/// One capsule of the mannequin and the joint whose frame carries it (a bone from a joint to
/// its child moves with the joint: the upper arm belongs to the shoulder).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MannequinBone {
    /// The capsule drawn for this bone.
    pub capsule: Capsule,
    /// The skeleton joint that carries it.
    pub owner: usize,
}

/// The mannequin's capsules of `skeleton` posed as `frames` (its forward kinematics) say:
/// the body's capsules of [`stance_hanim::capsules`], the ones collisions are tested with.
pub fn posed_mannequin_bones(
    skeleton: &stance_ik::Skeleton,
    frames: &stance_ik::Frames,
) -> Vec<MannequinBone> {
    stance_hanim::capsules::body_capsules(skeleton)
        .into_iter()
        .filter(|capsule| capsule.joint < frames.joint_position.len())
        .map(|capsule| {
            let (start, end) = capsule.world(frames);
            MannequinBone {
                capsule: Capsule {
                    start_world: start.as_vec3(),
                    end_world: end.as_vec3(),
                    radius_m: capsule.radius as f32,
                    color_linear: BODY_COLOR_LINEAR,
                },
                owner: capsule.joint,
            }
        })
        .collect()
}

/// The mannequin of the H-Anim default humanoid standing in its rest pose at `loa`.
pub fn rest_pose_capsules(loa: stance_hanim::LevelOfArticulation) -> Vec<Capsule> {
    let Ok(body) = stance_hanim::default_skeleton(&stance_hanim::SkeletonOptions {
        loa,
        ..stance_hanim::SkeletonOptions::default()
    }) else {
        return Vec::new();
    };
    let skeleton = &body.skeleton;
    let frames = stance_ik::Frames::new(skeleton, &stance_ik::Posture::rest(skeleton));
    posed_mannequin_bones(skeleton, &frames)
        .into_iter()
        .map(|bone| bone.capsule)
        .collect()
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    /// Catches a mannequin drawn from other capsules than the body's: the rest pose's thigh
    /// runs from the hip to the knee with the thigh's radius, and the head is drawn.
    #[test]
    fn the_mannequin_is_the_body_capsules_posed() {
        let capsules = rest_pose_capsules(stance_hanim::LevelOfArticulation::Loa2);
        let joints = stance_hanim::humanoid_joints(stance_hanim::LevelOfArticulation::Loa2);
        let at = |name: &str| {
            joints
                .iter()
                .find(|j| j.definition.name == name)
                .map(|j| j.rest_centre.as_vec3())
                .unwrap_or_default()
        };
        let thigh = capsules
            .iter()
            .find(|c| (c.start_world - at("l_hip")).length() < 1e-5)
            .copied()
            .unwrap_or(Capsule::marker(Vec3::ZERO, BODY_COLOR_LINEAR));
        assert!((thigh.end_world - at("l_knee")).length() < 1e-5);
        let radius = stance_hanim::capsules::segment_radius("l_hip", "l_knee") as f32;
        assert_eq!(thigh.radius_m, radius);
        assert!(
            capsules
                .iter()
                .any(|c| c.start_world.y > at("skullbase").y + 0.05)
        );
    }
}
