//! Avatar files for Stance: glTF 2.0 / GLB / VRM import into an in-memory [`Avatar`], GLB
//! export of posed avatars, and the generated default avatar.
//!
//! # Import ([`load_avatar`])
//! - `.glb`, `.gltf` with data URIs (external files through [`load_avatar_with`]), `.vrm`
//!   (VRM 0.x and 1.0: humanoid bones from the extension, MToon drawn as a plain textured
//!   material);
//! - several skins and meshes, triangle lists/strips/fans, sparse accessors;
//! - `KHR_mesh_quantization` (normalised and integer attributes are dequantised to `f32`),
//!   `EXT_meshopt_compression` (pure-Rust decoder, all modes and filters),
//!   `KHR_materials_unlit`, PNG/JPEG/WebP base-colour textures (`EXT_texture_webp`) decoded
//!   to RGBA8;
//! - any up axis, facing and unit normalised to the H-Anim frame through
//!   [`Avatar::hanim_from_file`] (metres, +Y up, +Z front, +X the body's left, soles on y=0);
//! - bone mapping onto H-Anim 2.0 in [`Avatar::mapping`] (see `stance_hanim::mapping`);
//! - animations on node transforms in [`Avatar::animations`] (LINEAR, STEP, CUBICSPLINE),
//!   turned into motion clips by [`clip_from_animation`].
//!
//! Hostile files: every size and count is checked against [`Limits`] before memory is
//! allocated; every index is checked; errors ([`AssetError`]) say what is wrong; nothing
//! panics (fuzzed in the tests).
//!
//! # Posing and export
//! [`Avatar::skeleton`] builds the solver skeleton at a chosen LOA;
//! [`Avatar::posed_locals`] / [`Avatar::apply_posture`] turn a solved posture into node
//! transforms; [`Avatar::skinning_matrices`] gives the renderer its joint matrices;
//! [`export_glb`] writes the posed avatar; importing that file and calling
//! [`Avatar::current_posture`] gives the posture back. [`export_glb_animation`] writes the
//! avatar with a sequence of postures as one glTF animation. [`export_scene_glb`] writes a
//! scene: several posed avatars and static meshes, each under a named, placed node.
//!
//! # Props
//! [`load_prop_mesh`] reads a static glTF/GLB file as a prop's triangles ([`PropMesh`]): the
//! default scene's primitives with their node transforms baked, by the same importer.

#![warn(missing_docs)]

pub mod animation;
mod clip_file;
mod clip_transfer;
mod error;
mod export;
mod export_animation;
mod export_scene;
mod generate;
mod import;
mod meshopt;
mod model;
mod normalize;
mod prop_mesh;
mod resources;
mod transfer;

pub use animation::{
    Animation, AnimationChannel, AnimationPath, Interpolation, clip_from_animation,
};
pub use clip_file::{ANIMATION_SAMPLE_FPS, ClipFileError, is_bvh_file, read_clip};
pub use clip_transfer::{
    ClipJob, ClipTransfer, FRAMES_PER_PART, FRAMES_PER_STEP, FramesPart, OpenedClip,
};
pub use error::AssetError;
pub use export::export_glb;
pub use export_animation::export_glb_animation;
pub use export_scene::{
    SceneContent, SceneNode, StaticMesh, export_scene_glb, posed_default_avatar,
};
pub use generate::make_default_avatar;
pub use import::{Resolver, SUPPORTED_EXTENSIONS};
pub use model::{
    AlphaMode, Avatar, Material, Mesh, Node, Primitive, Skin, SourceFormat, Texture, Trs,
    VrmExtension, Wrap,
};
pub use prop_mesh::{MAX_PROP_VERTICES, PropMesh, load_prop_mesh};
pub use resources::{find_resource, relative_path};
pub use transfer::AvatarTransfer;

/// Limits against hostile files. The defaults fit real avatars (tens of MB) with room.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Whole input (default 256 MiB).
    pub max_file_bytes: u64,
    /// JSON part (default 32 MiB).
    pub max_json_bytes: u64,
    /// One buffer's declared byteLength (default 512 MiB).
    pub max_buffer_bytes: u64,
    /// Everything decoded or built, counted as it is made (default 1 GiB): data-URI and
    /// external buffers, meshopt views, every accessor read, every stored primitive, every
    /// decoded image and every texture's copy of its pixels. Plain buffer views are borrowed
    /// from their buffer, never copied, so a file cannot multiply its size by pointing many
    /// views, accessors or primitives at the same bytes.
    pub max_decoded_bytes: u64,
    /// Nodes (default 10 000).
    pub max_nodes: usize,
    /// Meshes and skins (default 4 096).
    pub max_meshes: usize,
    /// Primitives over all meshes (default 16 384).
    pub max_primitives: usize,
    /// Accessors and buffer views (default 100 000).
    pub max_accessors: usize,
    /// Buffers (default 1 024).
    pub max_buffers: usize,
    /// Elements of one accessor (default 16 Mi).
    pub max_accessor_count: usize,
    /// Images (default 256).
    pub max_images: usize,
    /// Materials (default 4 096).
    pub max_materials: usize,
    /// Joints of one skin (default 1 024).
    pub max_joints_per_skin: usize,
    /// Width or height of one texture (default 8 192).
    pub max_texture_side: u32,
    /// Animations (default 1 024).
    pub max_animations: usize,
    /// Channels, and samplers, over all animations (default 100 000). Keys are bounded by
    /// `max_accessor_count` per accessor and `max_decoded_bytes` in all.
    pub max_animation_channels: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            max_file_bytes: 256 << 20,
            max_json_bytes: 32 << 20,
            max_buffer_bytes: 512 << 20,
            max_decoded_bytes: 1 << 30,
            max_nodes: 10_000,
            max_meshes: 4_096,
            max_primitives: 16_384,
            max_accessors: 100_000,
            max_buffers: 1_024,
            max_accessor_count: 16 << 20,
            max_images: 256,
            max_materials: 4_096,
            max_joints_per_skin: 1_024,
            max_texture_side: 8_192,
            max_animations: 1_024,
            max_animation_channels: 100_000,
        }
    }
}

/// Options of [`load_avatar`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LoadOptions {
    /// Size and count limits.
    pub limits: Limits,
    /// Fail with [`AssetError::NotHumanoid`] when the 18 LOA1 joints cannot all be mapped
    /// (default true; `false` loads any skinned or static model with a warning).
    pub require_humanoid: bool,
    /// Decode textures (default true; `false` gives 1x1 white placeholders, faster).
    pub decode_textures: bool,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self {
            limits: Limits::default(),
            require_humanoid: true,
            decode_textures: true,
        }
    }
}

/// Imports a `.glb`, `.vrm` or `.gltf` (data URIs only) from memory.
pub fn load_avatar(bytes: &[u8], options: &LoadOptions) -> Result<Avatar, AssetError> {
    import::import(bytes, options, &mut |_| None, HostImages::default())
}

/// Imports with a resolver for external URIs (`.gltf` next to its `.bin` and images).
pub fn load_avatar_with(
    bytes: &[u8],
    options: &LoadOptions,
    resolve: &mut Resolver<'_>,
) -> Result<Avatar, AssetError> {
    import::import(bytes, options, resolve, HostImages::default())
}

/// An image of the file already decoded by the caller (a browser's own decoder, off the main
/// thread): the glTF image `index` as `width x height` RGBA8 pixels, not premultiplied.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DecodedImage {
    /// Index in the file's `images`.
    pub index: usize,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height * 4` bytes.
    pub rgba8: Vec<u8>,
}

/// The images a caller decodes itself (a browser's own decoder, off the main thread).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct HostImages {
    /// Images already decoded.
    pub decoded: Vec<DecodedImage>,
    /// Indices (in the file's `images`) of images whose pixels the caller gives later: their
    /// textures come with the size their header declares (checked against the limits) and no
    /// pixels (`Texture::rgba8` empty, `Texture::image` naming the image), for the caller to
    /// fill, e.g. in [`AvatarTransfer::pixels`] before [`AvatarTransfer::into_avatar`]. The
    /// import then overlaps the caller's decoding.
    pub to_follow: Vec<usize>,
}

/// [`load_avatar_with`] where the caller decodes some images itself: those given decoded
/// are used as they are (within the same size limits; their pixels move into the textures,
/// uncopied), those to follow come without pixels (see [`HostImages::to_follow`]), the others
/// are decoded here. A decoded image of the wrong size is set aside with a warning and the
/// file's own bytes are decoded instead.
pub fn load_avatar_with_images(
    bytes: &[u8],
    options: &LoadOptions,
    resolve: &mut Resolver<'_>,
    images: HostImages,
) -> Result<Avatar, AssetError> {
    import::import(bytes, options, resolve, images)
}
