//! The motion clip a document's keys and timed tasks were made over (the `clip` field):
//! the clip file named by its name, size and content hash, and, in a saved document, the file
//! itself, DEFLATE-compressed, so that the document reopens with its clip and no other file.
//! A posture link carries the reference only (a clip does not fit in a URL): opened without
//! the clip, the editor says which file to load and accepts it when it is loaded. The
//! reference is a [`FileReference`] of the [`CLIP_FILE`] kind (the codec the scene's prop
//! files share, [`crate::file`]).

use crate::file::{EmbeddedFile, FileKind, FileReference};

/// Largest clip file a document may embed or name (bytes): the BVH reader's own limit.
pub const MAX_CLIP_BYTES: u64 = 256 << 20;
/// Longest clip file name (bytes).
pub const MAX_CLIP_NAME_BYTES: usize = 1024;

/// The document's `clip`: its words and limits.
pub const CLIP_FILE: FileKind = FileKind {
    what: "clip",
    max_bytes: MAX_CLIP_BYTES,
    max_name_bytes: MAX_CLIP_NAME_BYTES,
    instead: "open it with the clip file instead (remove `deflate`)",
};

/// The clip a document was made over: the file's name, size and content hash, and the file
/// itself when it is embedded.
pub type ClipReference = FileReference;

/// A clip file carried in the document.
pub type EmbeddedClip = EmbeddedFile;
