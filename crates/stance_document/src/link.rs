//! Posture links: a [`Document`] in the fragment of a URL (`https://host/#<fragment>`).
//!
//! # Format 1 (see `docs/document-format.md`)
//! ```text
//! base64url, no padding, of:
//!   [format: u8 = 1][payload length: LEB128][payload][CRC-32 (IEEE) of all previous bytes, LE]
//! ```
//! Every format keeps the frame's first byte (the format number) and its CRC-32 trailer, so a
//! link from a newer Stance is recognised as such. The payload is written with an adaptive
//! binary range coder (module `range_coder`): joints as indices into the H-Anim 2.0 joint
//! table (`stance_hanim::all_joints`), the joint set as a level of articulation plus exceptions,
//! rotation DOF quantised to [`ROTATION_STEP_RAD`] (0.005 degrees, so every decoded angle is
//! within 0.0025 degrees), positions to [`POSITION_STEP_M`] (0.1 mm), directions to
//! [`DIRECTION_STEP`]; weights exactly.
//!
//! This module holds the framing (base64url, length, CRC-32) and the public API; the payload's
//! shared contexts and helpers are in `models`, its writer in `write`, its reader in `read`.

mod models;
mod read;
mod write;

use base64::Engine as _;
use base64::alphabet;
use base64::engine::{DecodePaddingMode, GeneralPurpose, GeneralPurposeConfig};
use thiserror::Error;

#[cfg(test)]
pub(crate) use models::ROTATION_PRIOR;
use read::decode_payload;
use write::encode_payload;

use crate::document::{Document, TaskKindSpec};

/// The newest link format this version writes and reads: 2 adds the tasks' active intervals
/// and the timeline (frame rate, length, keys), 3 the comfort task (a 16-symbol model of the
/// task kinds), 4 the joint stiffness, 5 what the posture values are relative to (a document
/// made on an avatar, whose values are relative to the H-Anim standard pose), 6 the clip the
/// keys were made over (its file name, size and content hash; never the file), 7 the
/// point-on-a-line and point-on-a-plane tasks. A document is written in the oldest format that
/// holds it.
pub const LINK_FORMAT: u8 = 7;
/// Longest link [`encode_for_sharing`] makes with the timeline in it, in characters: beyond,
/// the keys are left out (a link is pasted into chats and mails).
pub const MAX_SHARE_CHARS: usize = 8 * 1024;
/// Quantisation step of rotation DOF and task angles: 0.005 degrees in radians.
pub const ROTATION_STEP_RAD: f64 = 0.005 * std::f64::consts::PI / 180.0;
/// Quantisation step of positions and translations: 0.1 mm.
pub const POSITION_STEP_M: f64 = 1e-4;
/// Quantisation step of the components of unit directions (gaze axes).
pub const DIRECTION_STEP: f64 = 1e-5;
/// Longest fragment accepted by [`decode`], in characters.
pub const MAX_LINK_CHARS: usize = 64 * 1024;

const MAX_COUNT: u64 = 4096;
const MAX_STRING_BYTES: u64 = 4096;
/// Zero bytes the payload decoder reads past the end before it calls the payload cut: the
/// most the encoder leaves off.
const MAX_OVERRUN: usize = crate::range_coder::MAX_DROPPED_ZEROS;

/// Why a link cannot be opened. The messages are meant for the person who opened the link.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum LinkError {
    /// Nothing after the `#`.
    #[error("the link holds no posture (there is nothing after `#`)")]
    Empty,
    /// Far longer than any posture link.
    #[error("the link is too long to be a Stance posture link ({0} characters)")]
    TooLong(usize),
    /// A character that base64url never produces.
    #[error(
        "the link is damaged: the character `{character}` at position {position} of the fragment cannot appear in a posture link"
    )]
    BadCharacter {
        /// The character.
        character: char,
        /// Its position in the fragment (0-based, in characters).
        position: usize,
    },
    /// Shorter than the length it declares: cut when copied.
    #[error(
        "the link is incomplete: it holds {got} of its {expected} bytes (it was probably cut when copied; copy the whole link)"
    )]
    Truncated {
        /// Bytes present.
        got: usize,
        /// Bytes the link declares.
        expected: usize,
    },
    /// The checksum does not match: characters were changed.
    #[error("the link is damaged: its checksum does not match (characters were changed or lost)")]
    Checksum,
    /// Made by a newer Stance.
    #[error(
        "this link was made by a newer version of Stance (format {found}); this version reads format {supported}"
    )]
    FutureVersion {
        /// The link's format.
        found: u8,
        /// The newest format this version reads.
        supported: u8,
    },
    /// The checksum matches but the content is not a valid document.
    #[error("the link is not a valid posture link: {0}")]
    Malformed(String),
}

fn engine() -> GeneralPurpose {
    GeneralPurpose::new(
        &alphabet::URL_SAFE,
        GeneralPurposeConfig::new()
            .with_encode_padding(false)
            .with_decode_allow_trailing_bits(true)
            .with_decode_padding_mode(DecodePaddingMode::Indifferent),
    )
}

// ---------------------------------------------------------------------------------------------
// Public API

/// The URL fragment (without `#`) that carries `document`. Values are quantised (see the module
/// documentation); non-finite numbers, which a validated document never holds, are written as 0.
/// Format 7 when a task is a point-on-a-line or point-on-a-plane task, else 6 when the document
/// names a clip, else 5 when the document names an avatar and its values are relative to the standard pose
/// (what the editor writes), else 4 when the document sets a joint stiffness, else 3 when a task is a comfort task,
/// else 2 when the document has a timeline or a task interval, else 1 (the oldest format that
/// holds it, for older readers).
pub fn encode(document: &Document) -> String {
    let timed = document.motion.is_some() || document.tasks.iter().any(|t| t.interval.is_some());
    let comfort = document
        .tasks
        .iter()
        .any(|t| matches!(t.kind, TaskKindSpec::Comfort { .. }));
    // Before format 5 a link on an avatar meant values relative to the avatar's own rest; on
    // the mannequin that rest is the standard pose.
    let standard_on_avatar = document.avatar != crate::document::AvatarReference::Default
        && document.rest == crate::document::PostureRest::Standard;
    let on_line_or_plane = document.tasks.iter().any(|t| {
        matches!(
            t.kind,
            TaskKindSpec::Line { .. } | TaskKindSpec::Plane { .. }
        )
    });
    let format = if on_line_or_plane {
        7
    } else if document.clip.is_some() {
        6
    } else if standard_on_avatar {
        5
    } else if !document.stiffness.joints.is_empty() {
        4
    } else if comfort {
        3
    } else if timed {
        2
    } else {
        1
    };
    let payload = encode_payload(document, format);
    let mut frame = Vec::with_capacity(payload.len() + 8);
    frame.push(format);
    write_leb128(&mut frame, payload.len() as u64);
    frame.extend_from_slice(&payload);
    let crc = crc32fast::hash(&frame);
    frame.extend_from_slice(&crc.to_le_bytes());
    engine().encode(frame)
}

/// A link to share: the fragment, and whether the timeline's keys had to be left out.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SharedLink {
    /// The URL fragment (without `#`).
    pub fragment: String,
    /// The keys would have made the link longer than [`MAX_SHARE_CHARS`] (this many
    /// characters): the link carries the posture, the tasks and their intervals only.
    pub keys_left_out: Option<usize>,
}

/// `document` as a link to share: with its timeline when the link stays within
/// [`MAX_SHARE_CHARS`], else without the keys (say so to the user).
pub fn encode_for_sharing(document: &Document) -> SharedLink {
    let fragment = encode(document);
    if fragment.len() <= MAX_SHARE_CHARS || document.motion.is_none() {
        return SharedLink {
            fragment,
            keys_left_out: None,
        };
    }
    let without = Document {
        motion: None,
        camera: None,
        ..document.clone()
    };
    SharedLink {
        fragment: encode(&without),
        keys_left_out: Some(fragment.len()),
    }
}

/// The document in a link: a bare fragment, `#fragment`, or a whole URL containing `#`.
pub fn decode(link: &str) -> Result<Document, LinkError> {
    let fragment = match link.find('#') {
        Some(i) => &link[i + 1..],
        None => link,
    };
    let fragment = fragment.trim();
    let fragment = fragment.trim_end_matches('=');
    if fragment.is_empty() {
        return Err(LinkError::Empty);
    }
    let chars = fragment.chars().count();
    if chars > MAX_LINK_CHARS {
        return Err(LinkError::TooLong(chars));
    }
    let mut text = String::with_capacity(fragment.len());
    for (position, c) in fragment.chars().enumerate() {
        match c {
            'A'..='Z' | 'a'..='z' | '0'..='9' | '-' | '_' => text.push(c),
            // Tolerate the standard alphabet.
            '+' => text.push('-'),
            '/' => text.push('_'),
            character => {
                return Err(LinkError::BadCharacter {
                    character,
                    position,
                });
            }
        }
    }
    // A single dangling character carries no whole byte: a cut link.
    if text.len() % 4 == 1 {
        text.pop();
    }
    let bytes = engine()
        .decode(text.as_bytes())
        .map_err(|e| LinkError::Malformed(format!("not base64url ({e})")))?;
    let declared = declared_length(&bytes);
    if bytes.len() < 5 {
        return Err(LinkError::Truncated {
            got: bytes.len(),
            expected: declared.unwrap_or(5).max(bytes.len() + 1),
        });
    }
    let (body, crc) = bytes.split_at(bytes.len() - 4);
    let crc_ok = crc32fast::hash(body).to_le_bytes() == crc;
    if !crc_ok {
        return Err(match declared {
            Some(expected) if expected > bytes.len() => LinkError::Truncated {
                got: bytes.len(),
                expected,
            },
            _ => LinkError::Checksum,
        });
    }
    let format = bytes[0];
    if format > LINK_FORMAT {
        return Err(LinkError::FutureVersion {
            found: format,
            supported: LINK_FORMAT,
        });
    }
    if format == 0 {
        return Err(LinkError::Malformed("format 0 does not exist".to_owned()));
    }
    let (len, header) = read_leb128(&body[1..])
        .ok_or_else(|| LinkError::Malformed("bad payload length".to_owned()))?;
    let payload = &body[1 + header..];
    if len != payload.len() as u64 {
        return Err(LinkError::Malformed(format!(
            "the payload has {} bytes but declares {len}",
            payload.len()
        )));
    }
    let document = decode_payload(payload, format).map_err(LinkError::Malformed)?;
    document
        .validate()
        .map_err(|e| LinkError::Malformed(e.to_string()))?;
    Ok(document)
}

/// The whole frame length a link declares, when its header can be read.
fn declared_length(bytes: &[u8]) -> Option<usize> {
    let (len, header) = read_leb128(bytes.get(1..)?)?;
    usize::try_from(len).ok()?.checked_add(1 + header + 4)
}

fn write_leb128(out: &mut Vec<u8>, mut v: u64) {
    loop {
        let byte = (v & 0x7F) as u8;
        v >>= 7;
        if v == 0 {
            out.push(byte);
            return;
        }
        out.push(byte | 0x80);
    }
}

/// The value and the number of bytes it took.
fn read_leb128(bytes: &[u8]) -> Option<(u64, usize)> {
    let mut v = 0u64;
    for (i, &b) in bytes.iter().enumerate().take(9) {
        v |= u64::from(b & 0x7F) << (7 * i);
        if b & 0x80 == 0 {
            return Some((v, i + 1));
        }
    }
    None
}
