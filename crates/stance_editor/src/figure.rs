//! The mannequin drawn as a figure: the generated default avatar (smooth skinned body, skin
//! and clothes, `stance_asset::make_default_avatar`) posed by the mannequin's posture, joint
//! by joint by H-Anim name. The capsule view stays a display option (and the heat map's).

use std::sync::Arc;

use glam::Mat4;
use stance_asset::make_default_avatar;
use stance_hanim::{HumanoidSkeleton, LevelOfArticulation, SkeletonOptions};
use stance_ik::{Posture, Skeleton};
use stance_render::SkinnedModel;

use crate::avatar::LoadedAvatar;

/// The default avatar's mesh, skinned to its own H-Anim skeleton.
pub struct MannequinFigure {
    avatar: LoadedAvatar,
    humanoid: HumanoidSkeleton,
}

impl std::fmt::Debug for MannequinFigure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MannequinFigure")
            .field("vertices", &self.avatar.vertex_count)
            .finish_non_exhaustive()
    }
}

impl MannequinFigure {
    /// The figure for a mannequin at `loa` (its skeleton at LOA 2 where the generated mesh
    /// has no joints of a higher level: those joints' turns are not drawn).
    pub fn new(loa: LevelOfArticulation) -> Result<Self, String> {
        let avatar = make_default_avatar().map_err(|error| error.to_string())?;
        let humanoid = avatar
            .skeleton_or_loa2(&SkeletonOptions {
                loa,
                ..SkeletonOptions::default()
            })
            .map_err(|error| error.to_string())?;
        let avatar = LoadedAvatar::with_mesh("mannequin", avatar)?;
        Ok(Self { avatar, humanoid })
    }

    /// The mesh for the GPU (once).
    pub fn take_model(&mut self) -> Option<Arc<SkinnedModel>> {
        self.avatar.take_mesh()
    }

    /// The mesh for the GPU, kept (the figure's is small): the same at every level of
    /// articulation. `None` once taken.
    pub fn model(&self) -> Option<Arc<SkinnedModel>> {
        self.avatar.mesh().cloned()
    }

    /// The skinning palettes that show `posture` of the mannequin `skeleton`: each DOF of
    /// the figure's skeleton takes the value of the same joint's same DOF.
    pub fn palettes(&self, skeleton: &Skeleton, posture: &Posture) -> Option<Vec<Vec<Mat4>>> {
        let own = &self.humanoid.skeleton;
        let values = Posture::carried_over(own, skeleton, posture);
        self.avatar.palettes(&self.humanoid, &values)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

    use glam::Vec3;
    use stance_hanim::{SkeletonOptions, default_skeleton};
    use stance_ik::Frames;

    use super::*;

    /// Where the figure draws the point of its mesh that sits on `joint` at rest, with the
    /// palettes of `posture`.
    fn drawn(
        figure: &MannequinFigure,
        skeleton: &Skeleton,
        posture: &Posture,
        joint: &str,
    ) -> Vec3 {
        let avatar = &figure.avatar.avatar;
        let skin = &avatar.skins[0];
        let k = skin
            .joints
            .iter()
            .position(|&node| avatar.nodes[node].name == joint)
            .unwrap();
        let own = &figure.humanoid.skeleton;
        let rest_frames = Frames::new(own, &Posture::rest(own));
        let rest_world = rest_frames.joint_position[own.joint_index(joint).unwrap()].as_vec3();
        let at_rest = figure.palettes(own, &Posture::rest(own)).unwrap()[0][k];
        let mesh_point = at_rest.inverse().transform_point3(rest_world);
        figure.palettes(skeleton, posture).unwrap()[0][k].transform_point3(mesh_point)
    }

    /// The figure follows the mannequin: its wrist is drawn where the mannequin's posed
    /// skeleton puts the wrist (an arm raised and bent, the trunk turned), at each level.
    #[test]
    fn the_figure_is_drawn_in_the_mannequins_posture() {
        for loa in [
            LevelOfArticulation::Loa1,
            LevelOfArticulation::Loa2,
            LevelOfArticulation::Loa3,
        ] {
            let body = default_skeleton(&SkeletonOptions {
                loa,
                ..Default::default()
            })
            .unwrap();
            let s = &body.skeleton;
            let mut posture = Posture::rest(s);
            for (joint, k, value) in [
                ("r_shoulder", 2, -1.2),
                ("r_elbow", 0, -1.0),
                ("vl5", 1, 0.3),
            ] {
                if let Some(j) = s.joint_index(joint) {
                    posture.values_mut()[s.joints()[j].dof_start + k] = value;
                }
            }
            let figure = MannequinFigure::new(loa).unwrap();
            let frames = Frames::new(s, &posture);
            let wrist = frames.joint_position[s.joint_index("r_radiocarpal").unwrap()];
            let rest = Frames::new(s, &Posture::rest(s)).joint_position
                [s.joint_index("r_radiocarpal").unwrap()];
            assert!((wrist - rest).length() > 0.2, "the posture moves the wrist");
            let got = drawn(&figure, s, &posture, "r_radiocarpal").as_dvec3();
            assert!(
                (got - wrist).length() < 0.01,
                "{loa:?}: drawn at {got}, the skeleton's wrist at {wrist}"
            );
        }
    }
}
