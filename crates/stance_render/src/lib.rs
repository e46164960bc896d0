//! The wgpu renderer of Stance: the body as shaded capsules, the floor grid, and the orbit
//! camera that looks at them. It knows nothing of egui or the browser: it renders a [`Scene`]
//! into a `RenderTarget` texture that the editor shows (or a test reads back).
//!
//! Without its default feature `gpu` it is the renderer's plain data alone (capsules, the
//! mannequin's bones, the orbit camera, avatars' skinned meshes and palettes, picking), with
//! no wgpu: what the editor's model (`stance_model`) builds for the views to draw. The
//! OpenPose control map needs no GPU either: keypoints seen by the camera, their JSON and the
//! skeleton image drawn on the CPU ([`OpenPose`]).

#![warn(missing_docs)]

mod avatar;
mod body;
mod camera;
#[cfg(feature = "gpu")]
mod capture;
#[cfg(all(feature = "gpu", not(target_arch = "wasm32")))]
mod headless;
#[cfg(feature = "gpu")]
mod image;
mod line_art;
mod openpose;
mod openpose_draw;
mod pick;
mod placed;
mod props;
mod raster;
#[cfg(feature = "gpu")]
mod renderer;
mod skinned;
#[cfg(feature = "gpu")]
mod skinned_gpu;

pub use avatar::{AvatarPalettes, avatar_model};
pub use body::{BODY_COLOR_LINEAR, MannequinBone, posed_mannequin_bones, rest_pose_capsules};
pub use camera::{OrbitCamera, ViewPreset};
#[cfg(all(feature = "gpu", not(target_arch = "wasm32")))]
pub use capture::read_pixels;
#[cfg(feature = "gpu")]
pub use capture::{CaptureError, Pixels, Readback};
#[cfg(all(feature = "gpu", not(target_arch = "wasm32")))]
pub use headless::{HeadlessGpu, headless_gpu};
#[cfg(feature = "gpu")]
pub use image::{
    ImageError, ImageOptions, MAX_IMAGE_SIDE_PX, PendingImage, encode_png, render_image,
};
pub use line_art::{CREASE_DEGREES, DEPTH_JUMP, line_art};
pub use openpose::{HiddenKeypoints, KeypointUnits, OpenPose, OpenPosePerson};
pub use openpose_draw::{
    BODY_COLORS, HAND_BONES, HAND_POINT_COLOR, LIMBS, POINT_RADIUS_PX, STICK_WIDTH_PX,
    hand_bone_color,
};
pub use pick::{CapsuleHit, pick_capsule};
pub use placed::{
    PLANE_THICKNESS_M, PROP_COLOR_LINEAR, character_shadow, mesh_prop_instance, placed_capsule,
    placed_keypoints, placed_palettes, prop_corners, prop_instance, prop_shadow, prop_static_mesh,
    prop_template, scene_from_character,
};
pub use props::{MeshPropInstance, PropInstance, PropMesh, PropTemplate, normal_matrix, prop_mesh};
#[cfg(feature = "gpu")]
pub use renderer::{COLOR_FORMAT, DEPTH_FORMAT, RenderTarget, SceneRenderer};
pub use skinned::{
    MAX_PALETTE_MATRICES, SkinnedMaterial, SkinnedModel, SkinnedPrimitive, SkinnedTexture,
    SkinnedVertex,
};
#[cfg(feature = "gpu")]
pub use skinned_gpu::{AvatarGpu, AvatarUpload, UPLOAD_STEP_BYTES};

use glam::Vec3;

/// Every WGSL shader of the renderer, by file name (validated by naga in the tests), each ended
/// with the pieces it shares (`shaders/*.wgsl.part`, not shaders of their own): the frame's
/// uniforms and sRGB encoding (all), the capsules' and props' light (`lit`), the control maps'
/// colour (those that draw bodies and props).
pub const SHADERS: &[(&str, &str)] = &[
    (
        "capsule.wgsl",
        concat!(
            include_str!("shaders/capsule.wgsl"),
            include_str!("shaders/frame.wgsl.part"),
            include_str!("shaders/lit.wgsl.part"),
            include_str!("shaders/control_map.wgsl.part")
        ),
    ),
    (
        "floor.wgsl",
        concat!(
            include_str!("shaders/floor.wgsl"),
            include_str!("shaders/frame.wgsl.part")
        ),
    ),
    (
        "prop.wgsl",
        concat!(
            include_str!("shaders/prop.wgsl"),
            include_str!("shaders/frame.wgsl.part"),
            include_str!("shaders/lit.wgsl.part"),
            include_str!("shaders/control_map.wgsl.part")
        ),
    ),
    (
        "skinned.wgsl",
        concat!(
            include_str!("shaders/skinned.wgsl"),
            include_str!("shaders/frame.wgsl.part"),
            include_str!("shaders/control_map.wgsl.part")
        ),
    ),
];

/// A capsule: the segment from `start_world` to `end_world` swept by a sphere of `radius_m`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Capsule {
    /// Centre of the start cap, world frame, metres.
    pub start_world: Vec3,
    /// Centre of the end cap, world frame, metres.
    pub end_world: Vec3,
    /// Radius of the swept sphere, metres.
    pub radius_m: f32,
    /// Linear RGBA.
    pub color_linear: [f32; 4],
}

impl Capsule {
    /// A marker: a small sphere of `color_linear` at `point_world` (an image's task goal).
    pub fn marker(point_world: Vec3, color_linear: [f32; 4]) -> Self {
        Self {
            start_world: point_world,
            end_world: point_world,
            radius_m: MARKER_RADIUS_M,
            color_linear,
        }
    }
}

/// Radius of a [`Capsule::marker`], metres.
pub const MARKER_RADIUS_M: f32 = 0.035;
/// Colour of a goal marker whose task is met, or whose status is unknown (linear RGB).
pub const GOAL_COLOR_LINEAR: [f32; 4] = [0.1, 0.65, 0.2, 1.0];

/// The clear colour of the viewport and of images, sRGB-encoded.
pub const BACKGROUND_SRGB: [f32; 4] = [0.13, 0.145, 0.17, 1.0];

/// The most contact shadows a frame draws.
pub const MAX_CONTACT_SHADOWS: usize = 16;

/// A soft dark disc on the floor under something: darkest at its centre, fading out at
/// `radius_m`; `strength` in [0, 1] (1 for a thing resting on the floor, less the higher it
/// floats).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactShadow {
    /// Centre on the floor: world x and z (m).
    pub centre_xz: [f32; 2],
    /// Radius (m).
    pub radius_m: f32,
    /// Darkness at the centre, 0 to 1.
    pub strength: f32,
}

impl ContactShadow {
    /// The shadow under points (world) of a thing: under their horizontal middle, as wide as
    /// they spread (at least `min_radius_m`), fading as their lowest point rises to `fade_m`
    /// above the floor. `None` for no points.
    pub fn under(
        points: impl IntoIterator<Item = Vec3>,
        min_radius_m: f32,
        fade_m: f32,
    ) -> Option<Self> {
        let points: Vec<Vec3> = points.into_iter().filter(|p| p.is_finite()).collect();
        let lowest = points.iter().map(|p| p.y).fold(f32::INFINITY, f32::min);
        if !lowest.is_finite() {
            return None;
        }
        let (min, max) = points.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(min, max), p| (min.min(*p), max.max(*p)),
        );
        let centre = (min + max) / 2.0;
        let spread = ((max.x - min.x).max(max.z - min.z) / 2.0).max(min_radius_m);
        let strength = (1.0 - lowest.max(0.0) / fade_m.max(1e-3)).clamp(0.0, 1.0);
        Some(Self {
            centre_xz: [centre.x, centre.z],
            radius_m: spread * 1.3,
            strength,
        })
    }
}

/// A pose of one of the cast's models (`SceneRenderer::set_cast_models`): a character drawn on
/// an avatar of its own, beside others on other avatars.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CastPose {
    /// Which model: its index among those given to `SceneRenderer::set_cast_models`.
    pub model: usize,
    /// The pose's matrix palettes (mesh space -> world), one per palette of the model, as
    /// [`Scene::avatar_palettes`].
    pub palettes: Vec<Vec<glam::Mat4>>,
}

/// What one frame shows.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Scene {
    /// Capsules to draw this frame (the mannequin's bones when no avatar is shown).
    pub capsules: Vec<Capsule>,
    /// Draw the floor: the y = 0 plane with a metre grid.
    pub show_floor: bool,
    /// Draw the uploaded avatar (see `SceneRenderer::set_avatar`).
    pub show_avatar: bool,
    /// This frame's matrix palettes of the avatar (mesh space -> H-Anim world), one per palette
    /// (none: this pose is not drawn, [`Scene::more_avatar_poses`] are).
    pub avatar_palettes: Vec<Vec<glam::Mat4>>,
    /// More poses of the same uploaded avatar, drawn beside the first (other characters on the
    /// same model), each its palettes as `avatar_palettes`.
    pub more_avatar_poses: Vec<Vec<Vec<glam::Mat4>>>,
    /// Characters each on a model of its own among the cast's (`SceneRenderer::set_cast_models`,
    /// or each model kept by its key: `SceneRenderer::insert_cast_model`; several avatars in
    /// one frame), drawn whatever `show_avatar` says; a pose of a model not uploaded is left
    /// out.
    pub cast_poses: Vec<CastPose>,
    /// The scene's props (boxes, spheres, cylinders), shaded like the bodies.
    pub props: Vec<PropInstance>,
    /// The scene's mesh props drawn with their files' triangles, shaded like the bodies.
    pub mesh_props: Vec<MeshPropInstance>,
    /// Soft shadows on the floor under the characters and props (at most
    /// [`MAX_CONTACT_SHADOWS`] are drawn), so that heights read at a glance.
    pub shadows: Vec<ContactShadow>,
    /// Overlay markers drawn like capsules (an image's task goals); the viewport draws its
    /// overlays with egui instead and leaves this empty.
    pub markers: Vec<Capsule>,
    /// Clear to transparent black (alpha 0) instead of [`BACKGROUND_SRGB`]: the colours
    /// drawn then come out premultiplied by their coverage.
    pub transparent_background: bool,
    /// The shaded picture, or a control map for image generation.
    pub shading: Shading,
}

/// How the figure is coloured: shaded, or as one of the control maps image generation reads
/// (on black, unlit; the floor and markers are overlays and have no place in them).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub enum Shading {
    /// Lit and coloured: the viewport's picture.
    #[default]
    Shaded,
    /// Distance along the view, near bright: white at `near_m`, black at `far_m` (m from the
    /// eye), as the common depth models (MiDaS, ZoeDepth) draw theirs.
    Depth {
        /// The depth drawn white (m).
        near_m: f32,
        /// The depth drawn black (m).
        far_m: f32,
    },
    /// The view-space normal as ControlNet's normal model (normalbae: ScanNet's protocol,
    /// Bae et al.'s estimator) reads it: `(n + 1) / 2` with red toward the image's left,
    /// green up, blue toward the viewer; a surface facing the camera is (128, 128, 255).
    Normal,
    /// White where the figure is.
    Mask,
}

/// How far beyond the body's farthest point a depth map reaches black, as a fraction of its
/// depth range: the farthest point stays a dark grey, apart from the black background.
pub const DEPTH_MARGIN: f32 = 0.2;

impl Shading {
    /// The depth map of a body made of `capsules` seen by `camera`: white at its nearest
    /// point (the capsules widened by their radii), black [`DEPTH_MARGIN`] of its depth range
    /// beyond its farthest.
    pub fn depth_seen_by(camera: &OrbitCamera, capsules: &[Capsule]) -> Shading {
        let view_from_world = camera.view_from_world();
        let (near_m, far_m) = capsules
            .iter()
            .flat_map(|capsule| {
                [capsule.start_world, capsule.end_world].map(|end| (end, capsule.radius_m))
            })
            .map(|(end, radius)| (-view_from_world.transform_point3(end).z, radius))
            .fold(
                (f32::INFINITY, f32::NEG_INFINITY),
                |(near, far), (depth, radius)| (near.min(depth - radius), far.max(depth + radius)),
            );
        if !(near_m.is_finite() && far_m.is_finite()) {
            return Shading::Depth {
                near_m: 0.0,
                far_m: 1.0,
            };
        }
        let range = (far_m - near_m).max(0.01);
        Shading::Depth {
            near_m,
            far_m: near_m + range * (1.0 + DEPTH_MARGIN),
        }
    }

    /// The shaders' `control_map` uniform.
    #[cfg(feature = "gpu")]
    fn uniform(self) -> [f32; 4] {
        match self {
            Shading::Shaded => [0.0; 4],
            Shading::Depth { near_m, far_m } => [1.0, near_m, far_m, 0.0],
            Shading::Normal => [2.0, 0.0, 0.0, 0.0],
            Shading::Mask => [3.0, 0.0, 0.0, 0.0],
        }
    }
}

impl Scene {
    /// The clear colour, sRGB-encoded (premultiplied: transparent is all zeros).
    pub fn background_srgb(&self) -> [f32; 4] {
        if self.transparent_background {
            [0.0; 4]
        } else if self.shading != Shading::Shaded {
            [0.0, 0.0, 0.0, 1.0]
        } else {
            BACKGROUND_SRGB
        }
    }
}
