//! Files a document carries: a file named by its name, size and content hash and, in a saved
//! document, the file itself, DEFLATE-compressed in base64, checked against its size and hash
//! when it is read. One codec for the motion clip (`clip`, [`crate::clip`]) and the mesh
//! props' files (a scene's `files`, [`crate::scene::PROP_FILE`]); each says what its files
//! are and how large they may be ([`FileKind`]), and its errors name the field the caller
//! gives (`clip.deflate`, `files[2].deflate`). A posture link carries a reference at most,
//! never a file.

use std::sync::{Arc, OnceLock};

use base64::Engine as _;
use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};
use serde_json::Value;

use crate::DocumentError;
use crate::json::{field, number, obj, string};

/// The prefix of the `hash` field: the hash function, so that another can come later.
const HASH_PREFIX: &str = "crc32:";
/// DEFLATE level of embedded files (miniz's default; a BVH takes about half its size in
/// base64 characters).
const DEFLATE_LEVEL: u8 = 6;

/// CRC-32 (IEEE, as zlib and PNG compute it) of `bytes`: the content hash of a file a
/// document names (with its size, identifies the file; not a defence against a crafted
/// collision). `crc32fast` takes a 9 MB clip in a few milliseconds where a byte-wise hash
/// took tens: the page computes it when a clip opens.
pub fn content_hash(bytes: &[u8]) -> u64 {
    u64::from(crc32fast::hash(bytes))
}

/// What kind of file a reference names: the words its errors use and its limits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FileKind {
    /// What the file is, in messages ("clip", "prop file").
    pub what: &'static str,
    /// Largest file (bytes).
    pub max_bytes: u64,
    /// Longest name (bytes of UTF-8).
    pub max_name_bytes: usize,
    /// What to do with a document whose embedded file is damaged, in messages.
    pub instead: &'static str,
}

/// A file carried in the document: its bytes, and their DEFLATE form in base64 as the JSON
/// holds it, made when the document is first written (not when the file is opened: a long
/// clip takes a few hundred milliseconds to compress) and shared by the document's copies.
#[derive(Debug, Clone)]
pub struct EmbeddedFile {
    bytes: Arc<[u8]>,
    deflate_base64: Arc<OnceLock<Arc<str>>>,
}

impl PartialEq for EmbeddedFile {
    fn eq(&self, other: &Self) -> bool {
        // The autosave compares the scene every second: a file shared by both is not read.
        Arc::ptr_eq(&self.bytes, &other.bytes) || self.bytes == other.bytes
    }
}

impl EmbeddedFile {
    /// The file's bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }

    /// The file's bytes, shared.
    pub fn shared_bytes(&self) -> Arc<[u8]> {
        Arc::clone(&self.bytes)
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

/// A file a document names: its name, size and content hash, and the file itself when it is
/// embedded.
#[derive(Debug, Clone, PartialEq)]
pub struct FileReference {
    /// The file's name (`walk.bvh`, `chair.glb`): a clip's reader is chosen by its extension.
    pub name: String,
    /// Bytes of the file.
    pub size: u64,
    /// [`content_hash`] of the file's bytes.
    pub hash: u64,
    /// The file, when the document carries it; `None`: a reference only (a link).
    pub embedded: Option<EmbeddedFile>,
}

impl FileReference {
    /// The file `name` with `bytes`, embedded (compressed when first written).
    pub fn embed(name: &str, bytes: &[u8]) -> Self {
        Self::embed_shared(name, bytes.into())
    }

    /// The file `name` with `bytes`, embedded without a copy.
    pub fn embed_shared(name: &str, bytes: Arc<[u8]>) -> Self {
        Self {
            name: name.to_owned(),
            size: bytes.len() as u64,
            hash: content_hash(&bytes),
            embedded: Some(EmbeddedFile {
                bytes,
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

    /// Whether `other` names the same file (same size and content hash; the name aside).
    pub fn is_same_file(&self, other: &Self) -> bool {
        self.size == other.size && self.hash == other.hash
    }

    /// The hash as written in the JSON (`crc32:` and 8 hexadecimal digits).
    pub fn hash_text(&self) -> String {
        format!("{HASH_PREFIX}{:08x}", self.hash)
    }

    /// Checks the name and size against `kind`'s limits (errors at `{at}.file`, `{at}.size`).
    pub fn validate_at(&self, at: &str, kind: &FileKind) -> Result<(), DocumentError> {
        if self.name.trim().is_empty() {
            return Err(DocumentError::field(
                format!("{at}.file"),
                "empty file name",
            ));
        }
        if self.name.len() > kind.max_name_bytes {
            return Err(DocumentError::field(
                format!("{at}.file"),
                format!("longer than {} bytes", kind.max_name_bytes),
            ));
        }
        if self.size > kind.max_bytes {
            return Err(DocumentError::field(
                format!("{at}.size"),
                format!(
                    "larger than the {} bytes a {} may have",
                    kind.max_bytes, kind.what
                ),
            ));
        }
        Ok(())
    }

    /// Parses the reference object at `at` (`{"file", "size", "hash", "deflate"}`); an
    /// embedded file is decompressed and must have the size and content hash the reference
    /// gives (a damaged or truncated one is refused, named).
    pub fn from_json_value(v: &Value, at: &str, kind: &FileKind) -> Result<Self, DocumentError> {
        let o = obj(v, at)?;
        let name = string(field(o, "file", at)?, &format!("{at}.file"))?.to_owned();
        let size_at = format!("{at}.size");
        let size = number(field(o, "size", at)?, &size_at)?;
        if size < 0.0 || size.fract() != 0.0 || size > kind.max_bytes as f64 {
            return Err(DocumentError::field(
                size_at,
                format!("expected an integer from 0 to {}", kind.max_bytes),
            ));
        }
        let size = size as u64;
        let hash_at = format!("{at}.hash");
        let hash_text = string(field(o, "hash", at)?, &hash_at)?;
        let hash = hash_text
            .strip_prefix(HASH_PREFIX)
            .filter(|hex| hex.len() == 8)
            .and_then(|hex| u32::from_str_radix(hex, 16).ok())
            .map(u64::from)
            .ok_or_else(|| {
                DocumentError::field(
                    hash_at,
                    format!("expected \"{HASH_PREFIX}\" and 8 hexadecimal digits"),
                )
            })?;
        let mut file = Self {
            name,
            size,
            hash,
            embedded: None,
        };
        file.validate_at(at, kind)?;
        if let Some(data) = o.get("deflate").filter(|v| !v.is_null()) {
            let data_at = format!("{at}.deflate");
            let text = string(data, &data_at)?;
            file.embedded = Some(file.inflate(text, &data_at, kind)?);
        }
        Ok(file)
    }

    /// The embedded file from its JSON form, checked against the size and hash.
    fn inflate(
        &self,
        text: &str,
        at: &str,
        kind: &FileKind,
    ) -> Result<EmbeddedFile, DocumentError> {
        let damaged = |why: String| {
            DocumentError::field(
                at,
                format!(
                    "the embedded {} {} is damaged ({why}); the document cannot be opened as it is, {}",
                    kind.what, self.name, kind.instead
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
        Ok(EmbeddedFile {
            bytes: bytes.into(),
            deflate_base64: Arc::new(OnceLock::from(Arc::from(text.trim()))),
        })
    }
}

impl Serialize for FileReference {
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
