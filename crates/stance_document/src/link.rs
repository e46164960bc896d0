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

use crate::between::{BetweenTask, CharacterPoint};
use crate::document::{Document, TaskKindSpec};
use crate::scene::{Prop, PropShape, Scene};

/// The newest link format this version writes and reads: 2 adds the tasks' active intervals
/// and the timeline (frame rate, length, keys), 3 the comfort task (a 16-symbol model of the
/// task kinds), 4 the joint stiffness, 5 what the posture values are relative to (a document
/// made on an avatar, whose values are relative to the H-Anim standard pose), 6 the clip the
/// keys were made over (its file name, size and content hash; never the file), 7 the
/// point-on-a-line and point-on-a-plane tasks, 8 the collision task (its margin and whether it
/// holds the body and the floor), 9 a scene of several characters and props
/// ([`encode_scene`]), 10 a scene with tasks between its characters ([`BETWEEN_FORMAT`]), 11
/// a scene with mesh props ([`MESH_FORMAT`]). A document is written in the oldest format that
/// holds it.
pub const LINK_FORMAT: u8 = 11;
/// The format of a scene's link ([`encode_scene`]): several characters (or one with a name or
/// a placement) and the props, each character its name, placement and document payload in the
/// oldest format that holds it.
pub const SCENE_FORMAT: u8 = 9;
/// The format of a scene's link with tasks between its characters or tasks attached to
/// props: [`SCENE_FORMAT`]'s payload, then the tasks between characters (count; each its
/// level, weight, flags, axes and two points: the character, the joint's name, the point),
/// then the attached tasks (count; each the character, the task's index, the prop's name).
pub const BETWEEN_FORMAT: u8 = 10;
/// The format of a scene's link with mesh props: [`BETWEEN_FORMAT`]'s payload, where a prop's
/// shape may also be a mesh (shape 4), written as its file's name (length, UTF-8; never the
/// file) before its three sizes.
pub const MESH_FORMAT: u8 = 11;
/// Quantisation step of a character's turn on the floor: 0.005 degrees in radians.
const YAW_STEP_RAD: f64 = ROTATION_STEP_RAD;
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
/// Format 8 when a task is a collision task, else 7 when a task is a point-on-a-line or
/// point-on-a-plane task, else 6 when the document
/// names a clip, else 5 when the document names an avatar and its values are relative to the standard pose
/// (what the editor writes), else 4 when the document sets a joint stiffness, else 3 when a task is a comfort task,
/// else 2 when the document has a timeline or a task interval, else 1 (the oldest format that
/// holds it, for older readers).
pub fn encode(document: &Document) -> String {
    let (format, payload) = document_payload(document);
    frame(format, &payload)
}

/// The oldest format that holds `document`, and its payload in that format.
fn document_payload(document: &Document) -> (u8, Vec<u8>) {
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
    let collision = document
        .tasks
        .iter()
        .any(|t| matches!(t.kind, TaskKindSpec::Collision { .. }));
    let format = if collision {
        8
    } else if on_line_or_plane {
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
    (format, encode_payload(document, format))
}

/// The fragment of `payload` in `format`: the format, the length, the payload, the CRC-32.
fn frame(format: u8, payload: &[u8]) -> String {
    let mut frame = Vec::with_capacity(payload.len() + 8);
    frame.push(format);
    write_leb128(&mut frame, payload.len() as u64);
    frame.extend_from_slice(payload);
    let crc = crc32fast::hash(&frame);
    frame.extend_from_slice(&crc.to_le_bytes());
    engine().encode(frame)
}

/// The URL fragment (without `#`) that carries `scene`: a plain document's link
/// ([`encode`]) for a scene of one unnamed character at the origin, else format
/// [`SCENE_FORMAT`]: the count, the selected index, and per character its name (UTF-8), its
/// placement (position quantised to [`POSITION_STEP_M`], turn to 0.005 degrees) and its
/// document as [`encode`] writes its payload (format byte, length, payload).
pub fn encode_scene(scene: &Scene) -> String {
    if scene.is_plain_document()
        && let Some(only) = scene.characters.first()
    {
        return encode(&only.document);
    }
    let mut payload = Vec::new();
    write_leb128(&mut payload, scene.characters.len() as u64);
    write_leb128(&mut payload, scene.selected as u64);
    for character in &scene.characters {
        let name = character.name.as_bytes();
        write_leb128(&mut payload, name.len() as u64);
        payload.extend_from_slice(name);
        for value in character.placement.position {
            write_zigzag(&mut payload, models::quantise(value, POSITION_STEP_M));
        }
        let yaw = character.placement.yaw_degrees.to_radians();
        write_zigzag(&mut payload, models::quantise(yaw, YAW_STEP_RAD));
        let (format, document) = document_payload(&character.document);
        payload.push(format);
        write_leb128(&mut payload, document.len() as u64);
        payload.extend_from_slice(&document);
    }
    write_leb128(&mut payload, scene.props.len() as u64);
    for prop in &scene.props {
        let name = prop.name.as_bytes();
        write_leb128(&mut payload, name.len() as u64);
        payload.extend_from_slice(name);
        let shape = PropShape::WORDS
            .iter()
            .position(|word| *word == prop.shape.name())
            .unwrap_or(0);
        payload.push(shape as u8);
        if let Some(file) = prop.shape.file() {
            write_leb128(&mut payload, file.len() as u64);
            payload.extend_from_slice(file.as_bytes());
        }
        for value in prop.shape.dimensions().into_iter().chain(prop.position) {
            write_zigzag(&mut payload, models::quantise(value, POSITION_STEP_M));
        }
        for value in prop.rotation {
            write_zigzag(&mut payload, models::quantise(value, DIRECTION_STEP));
        }
    }
    let attached: Vec<(usize, usize, &str)> = scene
        .characters
        .iter()
        .enumerate()
        .flat_map(|(c, character)| {
            character
                .document
                .tasks
                .iter()
                .enumerate()
                .filter_map(move |(t, task)| task.on.as_deref().map(|on| (c, t, on)))
        })
        .collect();
    let meshes = scene.props.iter().any(|p| p.shape.file().is_some());
    if scene.between.is_empty() && attached.is_empty() && !meshes {
        return frame(SCENE_FORMAT, &payload);
    }
    write_leb128(&mut payload, scene.between.len() as u64);
    for task in &scene.between {
        write_leb128(&mut payload, u64::from(task.level));
        payload.extend_from_slice(&task.weight.to_le_bytes());
        payload.push(u8::from(task.active));
        payload.push(
            (0..3)
                .filter(|&i| task.axes.has(i))
                .fold(0u8, |mask, i| mask | (1 << i)),
        );
        for point in [&task.a, &task.b] {
            write_leb128(&mut payload, point.character as u64);
            let joint = point.joint.as_bytes();
            write_leb128(&mut payload, joint.len() as u64);
            payload.extend_from_slice(joint);
            for value in point.point {
                write_zigzag(&mut payload, models::quantise(value, POSITION_STEP_M));
            }
        }
    }
    write_leb128(&mut payload, attached.len() as u64);
    for (character, task, on) in attached {
        write_leb128(&mut payload, character as u64);
        write_leb128(&mut payload, task as u64);
        write_leb128(&mut payload, on.len() as u64);
        payload.extend_from_slice(on.as_bytes());
    }
    frame(if meshes { MESH_FORMAT } else { BETWEEN_FORMAT }, &payload)
}

/// [`encode_scene`]'s link to share: with every character's timeline when the link stays
/// within [`MAX_SHARE_CHARS`], else without their keys.
pub fn encode_scene_for_sharing(scene: &Scene) -> SharedLink {
    let fragment = encode_scene(scene);
    let timed = scene.characters.iter().any(|c| c.document.motion.is_some());
    if fragment.len() <= MAX_SHARE_CHARS || !timed {
        return SharedLink {
            fragment,
            keys_left_out: None,
        };
    }
    let mut without = scene.clone();
    for character in &mut without.characters {
        character.document.motion = None;
        character.document.camera = None;
    }
    SharedLink {
        fragment: encode_scene(&without),
        keys_left_out: Some(fragment.len()),
    }
}

/// The scene in a link of any format (a document's link is a scene of one character).
pub fn decode_scene(link: &str) -> Result<Scene, LinkError> {
    let (format, payload) = unframe(link)?;
    if format < SCENE_FORMAT {
        return document_from_payload(&payload, format).map(Scene::of_one);
    }
    let scene = decode_scene_payload(&payload, format).map_err(LinkError::Malformed)?;
    scene
        .validate()
        .map_err(|e| LinkError::Malformed(e.to_string()))?;
    Ok(scene)
}

/// The LEB128 number at `at` of a scene's payload (`at` moved past it); a cut one names
/// `what`.
fn scene_leb(bytes: &[u8], at: &mut usize, what: &str) -> Result<u64, String> {
    let (value, used) = bytes
        .get(*at..)
        .and_then(read_leb128)
        .ok_or_else(|| format!("the scene's {what} is cut"))?;
    *at += used;
    Ok(value)
}

fn decode_scene_payload(bytes: &[u8], format: u8) -> Result<Scene, String> {
    let mut at = 0usize;
    let leb = |at: &mut usize, what: &str| scene_leb(bytes, at, what);
    let count = leb(&mut at, "character count")?;
    if count == 0 || count > crate::scene::MAX_CHARACTERS as u64 {
        return Err(format!("a scene of {count} characters"));
    }
    let selected = leb(&mut at, "selection")?;
    let mut characters = Vec::new();
    for i in 0..count {
        let length = usize::try_from(leb(&mut at, "name")?).unwrap_or(usize::MAX);
        let name = bytes
            .get(at..at.saturating_add(length))
            .ok_or_else(|| format!("character {i}'s name is cut"))?;
        at += length;
        let name = std::str::from_utf8(name)
            .map_err(|_| format!("character {i}'s name is not UTF-8"))?
            .to_owned();
        let mut position = [0.0; 3];
        for value in &mut position {
            *value = models::dequantise(read_zigzag(leb(&mut at, "placement")?)?, POSITION_STEP_M);
        }
        let yaw = models::dequantise(read_zigzag(leb(&mut at, "placement")?)?, YAW_STEP_RAD);
        let format = *bytes
            .get(at)
            .ok_or_else(|| format!("character {i}'s document is cut"))?;
        at += 1;
        if format == 0 || format >= SCENE_FORMAT {
            return Err(format!("character {i}'s document is in format {format}"));
        }
        let length = usize::try_from(leb(&mut at, "document")?).unwrap_or(usize::MAX);
        let payload = bytes
            .get(at..at.saturating_add(length))
            .ok_or_else(|| format!("character {i}'s document is cut"))?;
        at += length;
        let document =
            decode_payload(payload, format).map_err(|e| format!("character {i}: {e}"))?;
        characters.push(crate::scene::SceneCharacter {
            name,
            placement: crate::scene::Placement {
                position,
                yaw_degrees: yaw.to_degrees(),
            },
            document,
        });
    }
    let count = leb(&mut at, "prop count")?;
    if count > crate::scene::MAX_PROPS as u64 {
        return Err(format!("a scene of {count} props"));
    }
    let mut props = Vec::new();
    for i in 0..count {
        let length = usize::try_from(leb(&mut at, "prop name")?).unwrap_or(usize::MAX);
        let name = bytes
            .get(at..at.saturating_add(length))
            .ok_or_else(|| format!("prop {i}'s name is cut"))?;
        at += length;
        let name = std::str::from_utf8(name)
            .map_err(|_| format!("prop {i}'s name is not UTF-8"))?
            .to_owned();
        let word = bytes
            .get(at)
            .and_then(|&b| PropShape::WORDS.get(usize::from(b)))
            .filter(|&&word| word != "mesh" || format >= MESH_FORMAT)
            .ok_or_else(|| format!("prop {i}'s shape is unknown"))?;
        at += 1;
        let file = if *word == "mesh" {
            let length = usize::try_from(leb(&mut at, "prop file")?).unwrap_or(usize::MAX);
            let file = bytes
                .get(at..at.saturating_add(length))
                .ok_or_else(|| format!("prop {i}'s file name is cut"))?;
            at += length;
            let file = std::str::from_utf8(file)
                .map_err(|_| format!("prop {i}'s file name is not UTF-8"))?;
            Some(file.to_owned())
        } else {
            None
        };
        let dimensions = match *word {
            "box" | "mesh" => 3,
            "sphere" => 1,
            _ => 2,
        };
        let mut values = Vec::with_capacity(dimensions + 3);
        for _ in 0..dimensions + 3 {
            values.push(models::dequantise(
                read_zigzag(leb(&mut at, "prop")?)?,
                POSITION_STEP_M,
            ));
        }
        let shape = match file {
            Some(file) => PropShape::Mesh {
                file,
                size: [0.0; 3],
            }
            .with_dimensions(&values[..dimensions]),
            None => PropShape::from_dimensions(word, &values[..dimensions]),
        }
        .ok_or_else(|| format!("prop {i}'s shape is unknown"))?;
        let mut rotation = [0.0; 4];
        for value in &mut rotation {
            *value = models::dequantise(read_zigzag(leb(&mut at, "prop")?)?, DIRECTION_STEP);
        }
        let norm = rotation.iter().map(|v| v * v).sum::<f64>().sqrt();
        if norm > 0.0 {
            rotation = rotation.map(|v| v / norm);
        }
        props.push(Prop {
            name,
            shape,
            position: [
                values[dimensions],
                values[dimensions + 1],
                values[dimensions + 2],
            ],
            rotation,
        });
    }
    let between = if format >= BETWEEN_FORMAT {
        let between = decode_between(bytes, &mut at)?;
        decode_attachments(bytes, &mut at, &mut characters)?;
        between
    } else {
        Vec::new()
    };
    if at != bytes.len() {
        return Err(format!("{} bytes after the scene", bytes.len() - at));
    }
    Ok(Scene {
        props,
        characters,
        selected: usize::try_from(selected).unwrap_or(usize::MAX),
        between,
        files: Vec::new(), // A link names a mesh prop's file, never carries it.
    })
}

/// The tasks attached to props of a [`BETWEEN_FORMAT`] link, from `at`: each (character, task,
/// prop name) sets that task's `on`.
fn decode_attachments(
    bytes: &[u8],
    at: &mut usize,
    characters: &mut [crate::scene::SceneCharacter],
) -> Result<(), String> {
    let leb = |at: &mut usize| scene_leb(bytes, at, "attached tasks");
    let count = leb(at)?;
    if count > 64 * crate::scene::MAX_CHARACTERS as u64 {
        return Err(format!("{count} attached tasks"));
    }
    for _ in 0..count {
        let character = usize::try_from(leb(at)?).unwrap_or(usize::MAX);
        let task = usize::try_from(leb(at)?).unwrap_or(usize::MAX);
        let length = usize::try_from(leb(at)?).unwrap_or(usize::MAX);
        let name = bytes
            .get(*at..at.saturating_add(length))
            .ok_or_else(|| "an attached task's prop name is cut".to_owned())?;
        *at += length;
        let name = std::str::from_utf8(name)
            .map_err(|_| "an attached task's prop name is not UTF-8".to_owned())?;
        let spec = characters
            .get_mut(character)
            .and_then(|c| c.document.tasks.get_mut(task))
            .ok_or_else(|| format!("character {character} has no task {task} to attach"))?;
        spec.on = Some(name.to_owned());
    }
    Ok(())
}

/// The tasks between characters of a [`BETWEEN_FORMAT`] link, from `at`.
fn decode_between(bytes: &[u8], at: &mut usize) -> Result<Vec<BetweenTask>, String> {
    let leb = |at: &mut usize, what: &str| scene_leb(bytes, at, what);
    let count = leb(at, "task count")?;
    if count > crate::between::MAX_BETWEEN_TASKS as u64 {
        return Err(format!("{count} tasks between characters"));
    }
    let mut tasks = Vec::new();
    for i in 0..count {
        let level = u32::try_from(leb(at, "task")?).map_err(|_| format!("task {i}'s level"))?;
        let fixed = bytes
            .get(*at..*at + 10)
            .ok_or_else(|| format!("task {i} between characters is cut"))?;
        *at += 10;
        let mut weight = [0u8; 8];
        weight.copy_from_slice(&fixed[..8]);
        let weight = f64::from_le_bytes(weight);
        let (active, mask) = (fixed[8] != 0, fixed[9]);
        let axes = stance_ik::Axes::new(mask & 1 != 0, mask & 2 != 0, mask & 4 != 0);
        if mask == 0 || mask > 7 {
            return Err(format!("task {i} between characters has no axes"));
        }
        let mut point = |side: &str| -> Result<CharacterPoint, String> {
            let character = usize::try_from(leb(at, "task")?).unwrap_or(usize::MAX);
            let length = usize::try_from(leb(at, "task")?).unwrap_or(usize::MAX);
            let joint = bytes
                .get(*at..at.saturating_add(length))
                .ok_or_else(|| format!("task {i}'s joint {side} is cut"))?;
            *at += length;
            let joint = std::str::from_utf8(joint)
                .map_err(|_| format!("task {i}'s joint {side} is not UTF-8"))?
                .to_owned();
            let mut point = [0.0; 3];
            for value in &mut point {
                *value = models::dequantise(read_zigzag(leb(at, "task")?)?, POSITION_STEP_M);
            }
            Ok(CharacterPoint {
                character,
                joint,
                point,
            })
        };
        let a = point("a")?;
        let b = point("b")?;
        tasks.push(BetweenTask {
            level,
            weight,
            active,
            a,
            b,
            axes,
        });
    }
    Ok(tasks)
}

fn write_zigzag(out: &mut Vec<u8>, value: i64) {
    write_leb128(out, ((value << 1) ^ (value >> 63)) as u64);
}

fn read_zigzag(value: u64) -> Result<i64, String> {
    let decoded = ((value >> 1) as i64) ^ -((value & 1) as i64);
    if decoded.unsigned_abs() > models::MAX_QUANTISED as u64 {
        return Err("a placement out of range".to_owned());
    }
    Ok(decoded)
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
    let (format, payload) = unframe(link)?;
    if format >= SCENE_FORMAT {
        let count = payload.first().copied().unwrap_or(0);
        return Err(LinkError::Malformed(format!(
            "it holds a scene of {count} characters, not one posture (open it in the editor)"
        )));
    }
    document_from_payload(&payload, format)
}

fn document_from_payload(payload: &[u8], format: u8) -> Result<Document, LinkError> {
    let document = decode_payload(payload, format).map_err(LinkError::Malformed)?;
    document
        .validate()
        .map_err(|e| LinkError::Malformed(e.to_string()))?;
    Ok(document)
}

/// The format and the payload of a link, its framing checked (characters, length, checksum,
/// format).
fn unframe(link: &str) -> Result<(u8, Vec<u8>), LinkError> {
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
    Ok((format, payload.to_vec()))
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
