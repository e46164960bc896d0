//! The motion clip a document's keys and timed tasks were made over (the `clip` field):
//! the clip file named by its name, size and content hash, and, in a saved document, the file
//! itself, DEFLATE-compressed, so that the document reopens with its clip and no other file.
//! A posture link carries the reference only (a clip does not fit in a URL): opened without
//! the clip, the editor says which file to load and accepts it when it is loaded.

use std::sync::{Arc, OnceLock};

use base64::Engine as _;
use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};
use serde_json::Value;

use crate::DocumentError;
use crate::json::{field, number, obj, string};

/// Largest clip file a document may embed or name (bytes): the BVH reader's own limit.
pub const MAX_CLIP_BYTES: u64 = 256 << 20;
/// Longest clip file name (bytes).
pub const MAX_CLIP_NAME_BYTES: usize = 1024;
/// The prefix of the `hash` field: the hash function, so that another can come later.
const HASH_PREFIX: &str = "crc32:";
/// DEFLATE level of embedded clips (miniz's default; a BVH takes about half its size in
/// base64 characters).
const DEFLATE_LEVEL: u8 = 6;

/// CRC-32 (IEEE, as zlib and PNG compute it) of `bytes`: the content hash of a clip file
/// (with its size, identifies the file a document was made over; not a defence against a
/// crafted collision). `crc32fast` takes a 9 MB clip in a few milliseconds where a byte-wise
/// hash took tens: the page computes it when a clip opens.
pub fn content_hash(bytes: &[u8]) -> u64 {
    u64::from(crc32fast::hash(bytes))
}

/// A clip file carried in the document: its bytes, and their DEFLATE form in base64 as the
/// JSON holds it, made when the document is first written (not when a clip opens: a long clip
/// takes a few hundred milliseconds to compress) and shared by the document's copies.
#[derive(Debug, Clone)]
pub struct EmbeddedClip {
    bytes: Arc<[u8]>,
    deflate_base64: Arc<OnceLock<Arc<str>>>,
}

impl PartialEq for EmbeddedClip {
    fn eq(&self, other: &Self) -> bool {
        self.bytes == other.bytes
    }
}

impl EmbeddedClip {
    /// The clip file's bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }

    /// The compressed form as the JSON holds it (compressed on the first call).
    pub fn deflate_base64(&self) -> &str {
        self.deflate_base64.get_or_init(|| {
            let deflated = miniz_oxide::deflate::compress_to_vec(&self.bytes, DEFLATE_LEVEL);
            base64::engine::general_purpose::STANDARD
                .encode(deflated)
                .into()
        })
    }
}

/// The clip a document was made over: the file's name, size and content hash, and the file
/// itself when it is embedded.
#[derive(Debug, Clone, PartialEq)]
pub struct ClipReference {
    /// The file's name (`walk.bvh`): the reader is chosen by its extension.
    pub name: String,
    /// Bytes of the file.
    pub size: u64,
    /// [`content_hash`] of the file's bytes.
    pub hash: u64,
    /// The file, when the document carries it; `None`: a reference only (a link).
    pub embedded: Option<EmbeddedClip>,
}

impl ClipReference {
    /// The file `name` with `bytes`, embedded (compressed when first written).
    pub fn embed(name: &str, bytes: &[u8]) -> Self {
        Self {
            name: name.to_owned(),
            size: bytes.len() as u64,
            hash: content_hash(bytes),
            embedded: Some(EmbeddedClip {
                bytes: bytes.into(),
                deflate_base64: Arc::default(),
            }),
        }
    }

    /// The same reference without the file (what a link carries).
    pub fn without_file(&self) -> Self {
        Self {
            embedded: None,
            ..self.clone()
        }
    }

    /// Whether `bytes` are the referenced file's (same size and content hash).
    pub fn is_file(&self, bytes: &[u8]) -> bool {
        bytes.len() as u64 == self.size && content_hash(bytes) == self.hash
    }

    /// The hash as written in the JSON (`crc32:` and 8 hexadecimal digits).
    pub fn hash_text(&self) -> String {
        format!("{HASH_PREFIX}{:08x}", self.hash)
    }

    /// Checks the name and size (paths from `clip`).
    pub fn validate(&self) -> Result<(), DocumentError> {
        if self.name.trim().is_empty() {
            return Err(DocumentError::field("clip.file", "empty file name"));
        }
        if self.name.len() > MAX_CLIP_NAME_BYTES {
            return Err(DocumentError::field(
                "clip.file",
                format!("longer than {MAX_CLIP_NAME_BYTES} bytes"),
            ));
        }
        if self.size > MAX_CLIP_BYTES {
            return Err(DocumentError::field(
                "clip.size",
                format!("larger than the {MAX_CLIP_BYTES} bytes a clip may have"),
            ));
        }
        Ok(())
    }

    /// Parses the `clip` object; an embedded file is decompressed and must have the size and
    /// content hash the reference gives (a damaged or truncated one is refused, named).
    pub fn from_json_value(v: &Value) -> Result<Self, DocumentError> {
        let at = "clip";
        let o = obj(v, at)?;
        let name = string(field(o, "file", at)?, "clip.file")?.to_owned();
        let size = number(field(o, "size", at)?, "clip.size")?;
        if size < 0.0 || size.fract() != 0.0 || size > MAX_CLIP_BYTES as f64 {
            return Err(DocumentError::field(
                "clip.size",
                format!("expected an integer from 0 to {MAX_CLIP_BYTES}"),
            ));
        }
        let size = size as u64;
        let hash_text = string(field(o, "hash", at)?, "clip.hash")?;
        let hash = hash_text
            .strip_prefix(HASH_PREFIX)
            .filter(|hex| hex.len() == 8)
            .and_then(|hex| u32::from_str_radix(hex, 16).ok())
            .map(u64::from)
            .ok_or_else(|| {
                DocumentError::field(
                    "clip.hash",
                    format!("expected \"{HASH_PREFIX}\" and 8 hexadecimal digits"),
                )
            })?;
        let mut clip = Self {
            name,
            size,
            hash,
            embedded: None,
        };
        clip.validate()?;
        if let Some(data) = o.get("deflate").filter(|v| !v.is_null()) {
            let text = string(data, "clip.deflate")?;
            clip.embedded = Some(clip.inflate(text)?);
        }
        Ok(clip)
    }

    /// The embedded file from its JSON form, checked against the size and hash.
    fn inflate(&self, text: &str) -> Result<EmbeddedClip, DocumentError> {
        let damaged = |why: String| {
            DocumentError::field(
                "clip.deflate",
                format!(
                    "the embedded clip {} is damaged ({why}); the document cannot be opened as it is, open it with the clip file instead (remove `deflate`)",
                    self.name
                ),
            )
        };
        let deflated = base64::engine::general_purpose::STANDARD
            .decode(text.trim())
            .map_err(|e| damaged(format!("not base64: {e}")))?;
        // One byte over the size tells a longer file from the right one.
        let limit = usize::try_from(self.size.saturating_add(1)).unwrap_or(usize::MAX);
        let bytes =
            miniz_oxide::inflate::decompress_to_vec_with_limit(&deflated, limit).map_err(|e| {
                damaged(match e.status {
                    miniz_oxide::inflate::TINFLStatus::HasMoreOutput => {
                        format!("it holds more than its {} bytes", self.size)
                    }
                    miniz_oxide::inflate::TINFLStatus::FailedCannotMakeProgress => {
                        "its data ends early: it was cut".to_owned()
                    }
                    status => format!("not DEFLATE data: {status:?}"),
                })
            })?;
        if bytes.len() as u64 != self.size {
            return Err(damaged(format!(
                "it holds {} bytes, not {}",
                bytes.len(),
                self.size
            )));
        }
        if content_hash(&bytes) != self.hash {
            return Err(damaged("its content hash does not match".to_owned()));
        }
        Ok(EmbeddedClip {
            bytes: bytes.into(),
            deflate_base64: Arc::new(OnceLock::from(Arc::from(text.trim()))),
        })
    }
}

impl Serialize for ClipReference {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(None)?;
        m.serialize_entry("file", &self.name)?;
        m.serialize_entry("size", &self.size)?;
        m.serialize_entry("hash", &self.hash_text())?;
        if let Some(embedded) = &self.embedded {
            m.serialize_entry("deflate", embedded.deflate_base64())?;
        }
        m.end()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // Catches a hash that is not CRC-32/IEEE (a document written elsewhere would not match):
    // the standard check values.
    #[test]
    fn the_content_hash_is_crc32() {
        assert_eq!(content_hash(b""), 0);
        assert_eq!(content_hash(b"a"), 0xe8b7_be43);
        assert_eq!(content_hash(b"123456789"), 0xcbf4_3926);
    }
}
