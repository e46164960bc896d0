//! *File > Export control maps*: the posture as control images for image generation, seen
//! through the viewport's camera. The OpenPose map is the model's own (keypoints on the body,
//! seen by the camera, their JSON); the views draw its image, encode the PNG and send both
//! back ([`FileCommand::SaveOpenPose`]), which the model hands to the host as downloads. The
//! depth, normal and mask maps ([`RenderedMap`]) the views render with the GPU, as *Save
//! image* ([`FileCommand::SaveControlMap`]).
//!
//! [`FileCommand::SaveOpenPose`]: crate::model::FileCommand::SaveOpenPose
//! [`FileCommand::SaveControlMap`]: crate::model::FileCommand::SaveControlMap

use stance_hanim::keypoints::KeypointFinder;
use stance_render::{
    HiddenKeypoints, OpenPose, OrbitCamera, placed_capsule, placed_keypoints, scene_from_character,
};

use super::EditorModel;
use super::cast::Character;

/// The file name of the OpenPose skeleton image.
pub const OPENPOSE_IMAGE_FILE_NAME: &str = "stance-openpose.png";
/// The file name of the OpenPose keypoints (JSON).
pub const OPENPOSE_KEYPOINTS_FILE_NAME: &str = "stance-openpose.json";

/// A control map rendered with the GPU (`stance_render::Shading`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RenderedMap {
    /// Depth, near bright.
    Depth,
    /// View-space normals in ControlNet's normal colours.
    Normal,
    /// The figure white on black.
    Mask,
    /// Line art (from a depth and a normal map), white on black.
    Lines,
}

impl RenderedMap {
    /// Every one, in menu order.
    pub const ALL: [RenderedMap; 4] = [
        RenderedMap::Depth,
        RenderedMap::Normal,
        RenderedMap::Mask,
        RenderedMap::Lines,
    ];

    /// The file it downloads as.
    pub fn file_name(self) -> &'static str {
        match self {
            RenderedMap::Depth => "stance-depth.png",
            RenderedMap::Normal => "stance-normal.png",
            RenderedMap::Mask => "stance-mask.png",
            RenderedMap::Lines => "stance-lines.png",
        }
    }

    /// Its name in the window.
    pub fn label(self) -> &'static str {
        match self {
            RenderedMap::Depth => "Depth (near bright)",
            RenderedMap::Normal => "Normals (ControlNet colours)",
            RenderedMap::Mask => "Mask (white on black)",
            RenderedMap::Lines => "Line art (white on black)",
        }
    }
}

impl EditorModel {
    /// The body's OpenPose keypoints seen by `camera` in an image of `size_px` (the body
    /// posed now; `hidden`: what becomes of a keypoint the body hides).
    pub fn openpose(
        &self,
        camera: &OrbitCamera,
        size_px: [u32; 2],
        hidden: HiddenKeypoints,
    ) -> OpenPose {
        // Every character in view, in the scene's order, its keypoints and capsules placed in
        // the scene (the camera's frame), each hidden by every body.
        let characters: Vec<&Character> = self.characters().map(|(c, _)| c).collect();
        let people: Vec<_> = characters
            .iter()
            .map(|c| {
                let session = c.session();
                let skeleton = session.skeleton();
                let keypoints = KeypointFinder::new(skeleton).find(skeleton, session.frames());
                placed_keypoints(&keypoints, &c.placement())
            })
            .collect();
        let bodies: Vec<_> = characters
            .iter()
            .flat_map(|c| {
                let place = scene_from_character(&c.placement());
                c.bones()
                    .iter()
                    .map(move |bone| placed_capsule(bone.capsule, place))
            })
            .collect();
        OpenPose::of_scene(&people, camera, size_px, &bodies, hidden)
    }

    /// Hands a rendered control map (PNG, `width` x `height` pixels) to the host.
    pub(super) fn save_control_map(
        &mut self,
        map: RenderedMap,
        png: &[u8],
        width: u32,
        height: u32,
    ) {
        let file_name = map.file_name();
        match self.hooks.download_bytes(file_name, png) {
            Ok(()) => self.inform(format!("Saved a {width}x{height} map as {file_name}.")),
            Err(error) => self.warn(format!("Could not save {file_name}: {error}")),
        }
    }

    /// Hands the OpenPose map (its skeleton image, `width` x `height` pixels, and its
    /// keypoints' JSON) to the host as two downloads.
    pub(super) fn save_openpose(&mut self, png: &[u8], json: &str, width: u32, height: u32) {
        let saved = self
            .hooks
            .download_bytes(OPENPOSE_IMAGE_FILE_NAME, png)
            .and_then(|()| {
                self.hooks
                    .download_bytes(OPENPOSE_KEYPOINTS_FILE_NAME, json.as_bytes())
            });
        match saved {
            Ok(()) => self.inform(format!(
                "Saved the {width}x{height} OpenPose map as {OPENPOSE_IMAGE_FILE_NAME} and its keypoints as {OPENPOSE_KEYPOINTS_FILE_NAME}."
            )),
            Err(error) => self.warn(format!("Could not save the OpenPose map: {error}")),
        }
    }
}
