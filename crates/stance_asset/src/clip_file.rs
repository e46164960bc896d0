//! A motion clip from a file, whatever its format: BVH (`stance_motion::read_bvh`) or the
//! first animation of a glTF, GLB or VRM file sampled at [`ANIMATION_SAMPLE_FPS`]. The
//! editor's *Open clip* and `stance retarget` read clips here.

use stance_motion::{BvhError, BvhLimits, Clip, read_bvh};

use crate::import::Resolver;
use crate::{AssetError, LoadOptions, clip_from_animation, load_avatar_with};

/// The rate a glTF animation is sampled at when it becomes a clip (frames per second).
pub const ANIMATION_SAMPLE_FPS: f64 = 30.0;

/// Why a file is not a clip.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ClipFileError {
    /// A malformed BVH file (the error names the line and the field).
    #[error("{0}")]
    Bvh(#[from] BvhError),
    /// A glTF file that cannot be read, or whose animation cannot be sampled.
    #[error("{0}")]
    Asset(#[from] AssetError),
    /// A glTF file without animations.
    #[error("it has no animation")]
    NoAnimation,
}

/// True for a file name that only a clip can be (`.bvh`); a glTF file is an avatar or a
/// clip depending on what it was opened for.
pub fn is_bvh_file(name: &str) -> bool {
    name.to_ascii_lowercase().ends_with(".bvh")
}

/// The clip in file `name` (`bytes`): BVH by its extension, else the first animation of a
/// glTF, GLB or VRM file (`resolve` finds a `.gltf`'s external buffers). The clip is named
/// after the file's stem.
pub fn read_clip(
    name: &str,
    bytes: &[u8],
    options: &LoadOptions,
    resolve: &mut Resolver<'_>,
) -> Result<Clip, ClipFileError> {
    let file = name.rsplit(['/', '\\']).next().unwrap_or(name);
    let stem = file.rsplit_once('.').map_or(file, |(stem, _)| stem);
    if is_bvh_file(name) {
        return Ok(read_bvh(bytes, stem, &BvhLimits::default())?);
    }
    let avatar = load_avatar_with(bytes, options, resolve)?;
    if avatar.animations.is_empty() {
        return Err(ClipFileError::NoAnimation);
    }
    Ok(clip_from_animation(&avatar, 0, ANIMATION_SAMPLE_FPS)?)
}
