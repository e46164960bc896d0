//! A scene: several characters, each one a [`Document`] (its avatar, posture, tasks, timeline)
//! with a name and a placement on the floor.
//!
//! Each character's document is in the character's own frame (the solver's world for that
//! body: its pins, goals and keys); the placement puts that frame in the scene
//! (`scene_from_character`: a turn about the vertical, then a translation). A document
//! without `"characters"` is a scene of one character at the origin, so every document
//! written before scenes opens as one; a scene of one unnamed character at the origin is
//! written as that plain document, so older versions of Stance still read it.

use glam::{DAffine3, DQuat, DVec3};
use serde::Serialize;
use serde_json::{Map, Value};

use crate::document::Document;
use crate::error::DocumentError;
use crate::json::{number, numbers, obj, string};

/// The longest character name kept (characters; longer names are cut).
pub const MAX_NAME_CHARS: usize = 64;
/// The most characters a scene holds.
pub const MAX_CHARACTERS: usize = 32;

/// Where a character's frame stands in the scene: a turn about the vertical (degrees,
/// counter-clockwise seen from above), then a translation (m).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Placement {
    /// Scene position of the character frame's origin (m).
    pub position: [f64; 3],
    /// Turn about the vertical (degrees).
    pub yaw_degrees: f64,
}

impl Placement {
    /// The placement at `position` (m), unturned.
    pub fn at(position: [f64; 3]) -> Self {
        Self {
            position,
            yaw_degrees: 0.0,
        }
    }

    /// Whether it leaves the character's frame where the scene's is.
    pub fn is_identity(&self) -> bool {
        self.position == [0.0; 3] && self.yaw_degrees == 0.0
    }

    /// The transform from the character's frame to the scene's.
    pub fn scene_from_character(&self) -> DAffine3 {
        DAffine3::from_rotation_translation(
            DQuat::from_rotation_y(self.yaw_degrees.to_radians()),
            DVec3::from_array(self.position),
        )
    }

    /// Checks that every number is finite.
    pub fn validate_at(&self, at: &str) -> Result<(), DocumentError> {
        for (i, value) in self.position.iter().enumerate() {
            if !value.is_finite() {
                return Err(DocumentError::field(
                    format!("{at}.position[{i}]"),
                    "not a finite number",
                ));
            }
        }
        if !self.yaw_degrees.is_finite() {
            return Err(DocumentError::field(
                format!("{at}.yaw"),
                "not a finite number",
            ));
        }
        Ok(())
    }

    fn from_json_value(v: &Value, at: &str) -> Result<Self, DocumentError> {
        let o = obj(v, at)?;
        let position = match o.get("position") {
            None | Some(Value::Null) => [0.0; 3],
            Some(p) => {
                let p = numbers(p, &format!("{at}.position"), 3)?;
                [p[0], p[1], p[2]]
            }
        };
        let yaw_degrees = match o.get("yaw") {
            None | Some(Value::Null) => 0.0,
            Some(y) => number(y, &format!("{at}.yaw"))?,
        };
        let placement = Self {
            position,
            yaw_degrees,
        };
        placement.validate_at(at)?;
        Ok(placement)
    }

    fn to_json_value(self) -> Value {
        serde_json::json!({ "position": self.position, "yaw": self.yaw_degrees })
    }
}

/// One character of a scene.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SceneCharacter {
    /// Its name in the outliner (unique in a scene the editor makes; not required).
    pub name: String,
    /// Where it stands.
    pub placement: Placement,
    /// Its avatar, posture, tasks, timeline... in its own frame.
    pub document: Document,
}

/// Several characters; one of them selected (the one the editor's tools work on).
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// The characters, in the outliner's order (at least one).
    pub characters: Vec<SceneCharacter>,
    /// The selected character's index.
    pub selected: usize,
}

impl Default for Scene {
    fn default() -> Self {
        Self::of_one(Document::default())
    }
}

/// The name of the `n`th character (from 1) a scene gets when it is not named.
pub fn default_character_name(n: usize) -> String {
    format!("Character {n}")
}

impl Scene {
    /// A scene of one character at the origin, named as the first character is.
    pub fn of_one(document: Document) -> Self {
        Self {
            characters: vec![SceneCharacter {
                name: default_character_name(1),
                placement: Placement::default(),
                document,
            }],
            selected: 0,
        }
    }

    /// Checks every character's document and placement, the count and the selection.
    pub fn validate(&self) -> Result<(), DocumentError> {
        if self.characters.is_empty() {
            return Err(DocumentError::field(
                "characters",
                "a scene has at least one character",
            ));
        }
        if self.characters.len() > MAX_CHARACTERS {
            return Err(DocumentError::field(
                "characters",
                format!(
                    "{} characters; a scene holds at most {MAX_CHARACTERS}",
                    self.characters.len()
                ),
            ));
        }
        if self.selected >= self.characters.len() {
            return Err(DocumentError::field(
                "selected",
                format!("character {} of {}", self.selected, self.characters.len()),
            ));
        }
        for (i, character) in self.characters.iter().enumerate() {
            let at = format!("characters[{i}]");
            character
                .placement
                .validate_at(&format!("{at}.placement"))?;
            character.document.validate().map_err(|e| e.within(&at))?;
        }
        Ok(())
    }

    /// Whether it is one character at the origin with the first character's default name:
    /// written as a plain document (nothing is lost).
    pub fn is_plain_document(&self) -> bool {
        matches!(self.characters.as_slice(), [only]
            if only.placement.is_identity() && only.name == default_character_name(1))
    }

    /// Parses and validates a scene, or a plain document as a scene of one, from JSON text.
    pub fn from_json(text: &str) -> Result<Self, DocumentError> {
        let v: Value =
            serde_json::from_str(text).map_err(|e| DocumentError::Json(e.to_string()))?;
        Self::from_json_value(&v)
    }

    /// Parses and validates a scene from a JSON value: `{"characters": [...], "selected": i}`,
    /// each character a document with `"name"` and `"placement"`; any other object is read as
    /// a document, a scene of one character.
    pub fn from_json_value(v: &Value) -> Result<Self, DocumentError> {
        let o = obj(v, "the document")?;
        let Some(list) = o.get("characters") else {
            return Document::from_json_value(v).map(Self::of_one);
        };
        let Value::Array(list) = list else {
            return Err(DocumentError::field(
                "characters",
                "expected an array of characters",
            ));
        };
        let mut characters = Vec::with_capacity(list.len().min(MAX_CHARACTERS));
        for (i, entry) in list.iter().enumerate() {
            let at = format!("characters[{i}]");
            if i >= MAX_CHARACTERS {
                return Err(DocumentError::field(
                    "characters",
                    format!("more than {MAX_CHARACTERS} characters"),
                ));
            }
            let fields = obj(entry, &at)?;
            let name = match fields.get("name") {
                None | Some(Value::Null) => default_character_name(i + 1),
                Some(n) => clean_name(string(n, &format!("{at}.name"))?)
                    .unwrap_or_else(|| default_character_name(i + 1)),
            };
            let placement = match fields.get("placement") {
                None | Some(Value::Null) => Placement::default(),
                Some(p) => Placement::from_json_value(p, &format!("{at}.placement"))?,
            };
            let document_fields: Map<String, Value> = fields
                .iter()
                .filter(|(key, _)| !matches!(key.as_str(), "name" | "placement"))
                .map(|(key, value)| (key.clone(), value.clone()))
                .collect();
            let document = Document::from_json_value(&Value::Object(document_fields))
                .map_err(|e| e.within(&at))?;
            characters.push(SceneCharacter {
                name,
                placement,
                document,
            });
        }
        let selected = match o.get("selected") {
            None | Some(Value::Null) => 0,
            Some(s) => {
                let n = number(s, "selected")?;
                if n.fract() != 0.0 || n < 0.0 {
                    return Err(DocumentError::field("selected", "expected an index >= 0"));
                }
                n as usize
            }
        };
        let scene = Self {
            characters,
            selected,
        };
        scene.validate()?;
        Ok(scene)
    }

    /// The JSON value: a plain document for one character at the origin (older versions read
    /// it), else `{"characters": [...], "selected": i}`.
    pub fn to_json_value(&self) -> Value {
        if self.is_plain_document()
            && let Some(only) = self.characters.first()
        {
            return serde_json::to_value(&only.document).unwrap_or(Value::Null);
        }
        let characters: Vec<Value> = self
            .characters
            .iter()
            .map(|character| {
                let mut fields = Map::new();
                fields.insert("name".into(), Value::String(character.name.clone()));
                fields.insert("placement".into(), character.placement.to_json_value());
                if let Ok(Value::Object(document)) = serde_json::to_value(&character.document) {
                    fields.extend(document);
                }
                Value::Object(fields)
            })
            .collect();
        serde_json::json!({ "characters": characters, "selected": self.selected })
    }

    /// The JSON text (pretty or compact).
    pub fn to_json(&self, pretty: bool) -> String {
        let value = self.to_json_value();
        let text = if pretty {
            serde_json::to_string_pretty(&value)
        } else {
            serde_json::to_string(&value)
        };
        text.unwrap_or_default()
    }
}

impl Serialize for Scene {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.to_json_value().serialize(s)
    }
}

/// A character's name as kept: trimmed, control characters dropped, at most
/// [`MAX_NAME_CHARS`]; `None` when nothing is left.
pub fn clean_name(name: &str) -> Option<String> {
    let cleaned: String = name
        .trim()
        .chars()
        .filter(|c| !c.is_control())
        .take(MAX_NAME_CHARS)
        .collect();
    let cleaned = cleaned.trim().to_owned();
    (!cleaned.is_empty()).then_some(cleaned)
}
