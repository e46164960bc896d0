//! Errors of avatar import and export. Each names what is wrong and where.

/// What went wrong while reading or writing an avatar file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AssetError {
    /// An avatar handed between threads as bytes did not decode (see `avatar_from_bytes`).
    #[error("the imported avatar did not arrive intact: {0}")]
    Transfer(String),
    /// The input is neither a GLB container nor glTF JSON.
    #[error("not a glTF file: {0}")]
    NotGltf(String),
    /// The GLB container is damaged (header, chunk lengths...).
    #[error("bad GLB container: {0}")]
    BadGlb(String),
    /// The JSON does not parse as glTF 2.0.
    #[error("bad glTF JSON: {0}")]
    BadJson(String),
    /// Only glTF 2.x is supported.
    #[error("unsupported glTF version `{0}` (expected 2.0)")]
    UnsupportedVersion(String),
    /// A required extension this importer does not implement.
    #[error("required extension `{0}` is not supported")]
    UnsupportedExtension(String),
    /// An index points past the end of its array.
    #[error("{what} refers to {kind} {index}, but the file has {count}")]
    BadIndex {
        /// The referring object, e.g. `mesh 0 primitive 1 POSITION`.
        what: String,
        /// The kind of the referred object, e.g. `accessor`.
        kind: &'static str,
        /// The index given.
        index: usize,
        /// How many such objects exist.
        count: usize,
    },
    /// A size or count exceeds a limit of [`crate::Limits`].
    #[error("{what} is too large: {size} > limit {limit}")]
    TooLarge {
        /// What was measured.
        what: String,
        /// Its size or count.
        size: u64,
        /// The limit.
        limit: u64,
    },
    /// Data is out of the range its container declares (an accessor past its view...).
    #[error("{0}")]
    OutOfBounds(String),
    /// A buffer could not be loaded.
    #[error("buffer {index}: {reason}")]
    Buffer {
        /// Buffer index.
        index: usize,
        /// Why.
        reason: String,
    },
    /// Accessor data is inconsistent (wrong type, count mismatch, non-finite values...).
    #[error("{0}")]
    BadAccessor(String),
    /// EXT_meshopt_compression data failed to decode.
    #[error("buffer view {view}: meshopt decoding failed: {reason}")]
    Meshopt {
        /// Buffer view index.
        view: usize,
        /// Why.
        reason: String,
    },
    /// The node hierarchy is not a forest (cycle, several parents).
    #[error("node hierarchy: {0}")]
    BadHierarchy(String),
    /// An image failed to decode.
    #[error("image {index}: {reason}")]
    Image {
        /// Image index.
        index: usize,
        /// Why.
        reason: String,
    },
    /// The skeleton is not recognisably humanoid.
    #[error("not a humanoid: no joint found for {}", .missing.join(", "))]
    NotHumanoid {
        /// The H-Anim LOA1 joints that could not be mapped.
        missing: Vec<String>,
    },
    /// Building the solver skeleton failed.
    #[error("skeleton: {0}")]
    Skeleton(String),
    /// A posture does not fit the avatar.
    #[error("posture: {0}")]
    Posture(String),
    /// An animation is malformed, or cannot be sampled or written as asked.
    #[error("animation {animation}: {reason}")]
    Animation {
        /// The animation: its index in the file and name.
        animation: String,
        /// What is wrong, naming the channel where there is one.
        reason: String,
    },
    /// A prop's file has no triangles in its default scene.
    #[error("the file has no triangles in its default scene (a prop is a triangle mesh)")]
    NoTriangles,
    /// Writing failed.
    #[error("export: {0}")]
    Export(String),
}

impl From<stance_hanim::BuildError> for AssetError {
    fn from(e: stance_hanim::BuildError) -> Self {
        match e {
            stance_hanim::BuildError::NotHumanoid { missing } => {
                AssetError::NotHumanoid { missing }
            }
            other => AssetError::Skeleton(other.to_string()),
        }
    }
}
