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
use stance_ik::{Obstacle, ObstacleShape};

use crate::between::{BetweenTask, MAX_BETWEEN_TASKS, between_from_json};
use crate::document::Document;
use crate::error::DocumentError;
use crate::file::FileReference;
use crate::json::{number, numbers, obj, string};

mod files;

pub use files::{MAX_PROP_FILE_BYTES, MAX_PROP_FILES_BYTES, PROP_FILE};

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

    /// `{"position": [x, y, z], "yaw": degrees}`, as a scene's character carries it.
    pub fn to_json_value(self) -> Value {
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

/// The most props a scene holds.
pub const MAX_PROPS: usize = 64;
/// The largest size of a prop along any axis (m).
pub const MAX_PROP_SIZE_M: f64 = 100.0;

/// How deep a plane prop is as an obstacle, under its surface (m).
pub const PLANE_DEPTH: f64 = 0.1;

/// The longest file name a mesh prop names (characters).
pub const MAX_FILE_NAME_CHARS: usize = 255;

/// A prop's shape, centred on its origin, in metres. A cylinder stands along its own +Y (a
/// vertical bar); a plane is a rectangle in its own XZ plane facing +Y (a floor patch, a
/// table top), drawn as a thin slab; a mesh is a static glTF/GLB file's triangles, named by
/// the file (the prop never carries it: a saved scene's [`Scene::files`] do, a link never),
/// scaled to fill `size` (its bounding box, centred on the prop's origin), so that a
/// document without the file still knows the box.
#[derive(Debug, Clone, PartialEq)]
pub enum PropShape {
    /// `size`: width (X), height (Y), depth (Z).
    Box {
        /// Full extents (m).
        size: [f64; 3],
    },
    /// A ball.
    Sphere {
        /// Radius (m).
        radius: f64,
    },
    /// A bar or a column.
    Cylinder {
        /// Radius (m).
        radius: f64,
        /// Length along +Y (m).
        height: f64,
    },
    /// A rectangle facing +Y: `size` along X and Z.
    Plane {
        /// Extents along X and Z (m).
        size: [f64; 2],
    },
    /// A static mesh from a glTF/GLB file.
    Mesh {
        /// The file's name (`chair.glb`): the editor's imported prop files and `stance
        /// render` resolve it.
        file: String,
        /// The mesh's bounding extents after the prop's scale (m).
        size: [f64; 3],
    },
}

impl PropShape {
    /// Its word in documents.
    pub fn name(&self) -> &'static str {
        match self {
            PropShape::Box { .. } => "box",
            PropShape::Sphere { .. } => "sphere",
            PropShape::Cylinder { .. } => "cylinder",
            PropShape::Plane { .. } => "plane",
            PropShape::Mesh { .. } => "mesh",
        }
    }

    /// Its extents along its own X, Y and Z (a plane has none along Y).
    pub fn extents(&self) -> [f64; 3] {
        match *self {
            PropShape::Box { size } => size,
            PropShape::Sphere { radius } => [2.0 * radius; 3],
            PropShape::Cylinder { radius, height } => [2.0 * radius, height, 2.0 * radius],
            PropShape::Plane { size } => [size[0], 0.0, size[1]],
            PropShape::Mesh { size, .. } => size,
        }
    }

    /// Its dimensions as numbers, in the order the link writes them.
    pub fn dimensions(&self) -> Vec<f64> {
        match *self {
            PropShape::Box { size } => size.to_vec(),
            PropShape::Sphere { radius } => vec![radius],
            PropShape::Cylinder { radius, height } => vec![radius, height],
            PropShape::Plane { size } => size.to_vec(),
            PropShape::Mesh { size, .. } => size.to_vec(),
        }
    }

    /// The mesh file it names, if it is a mesh.
    pub fn file(&self) -> Option<&str> {
        match self {
            PropShape::Mesh { file, .. } => Some(file),
            _ => None,
        }
    }

    /// The same shape (a mesh: the same file) with `dimensions` in [`Self::dimensions`]'
    /// order; `None` when their count does not fit.
    pub fn with_dimensions(&self, dimensions: &[f64]) -> Option<Self> {
        match (self, dimensions) {
            (PropShape::Mesh { file, .. }, [x, y, z]) => Some(PropShape::Mesh {
                file: file.clone(),
                size: [*x, *y, *z],
            }),
            (PropShape::Mesh { .. }, _) => None,
            _ => Self::from_dimensions(self.name(), dimensions),
        }
    }

    /// The shape named `word` with `dimensions` in [`Self::dimensions`]' order (a mesh,
    /// which needs its file, is made by [`Self::with_dimensions`]).
    pub fn from_dimensions(word: &str, dimensions: &[f64]) -> Option<Self> {
        match (word, dimensions) {
            ("box", [x, y, z]) => Some(PropShape::Box { size: [*x, *y, *z] }),
            ("sphere", [radius]) => Some(PropShape::Sphere { radius: *radius }),
            ("cylinder", [radius, height]) => Some(PropShape::Cylinder {
                radius: *radius,
                height: *height,
            }),
            ("plane", [x, z]) => Some(PropShape::Plane { size: [*x, *z] }),
            _ => None,
        }
    }

    /// The shape words, in the link's order.
    pub const WORDS: [&'static str; 5] = ["box", "sphere", "cylinder", "plane", "mesh"];

    fn validate_at(&self, at: &str) -> Result<(), DocumentError> {
        for value in self.dimensions() {
            if !value.is_finite() || value <= 0.0 || value > MAX_PROP_SIZE_M {
                return Err(DocumentError::field(
                    at,
                    format!("{value} m: a size is above 0 and at most {MAX_PROP_SIZE_M} m"),
                ));
            }
        }
        Ok(())
    }
}

/// Checks a mesh prop's file name: not empty, at most [`MAX_FILE_NAME_CHARS`], no control
/// characters, a name and not a path (no `/` nor `\\`).
fn check_file_name(file: &str, at: &str) -> Result<(), DocumentError> {
    if file.trim().is_empty() {
        return Err(DocumentError::field(at, "a mesh prop names its file"));
    }
    if file.chars().count() > MAX_FILE_NAME_CHARS {
        return Err(DocumentError::field(
            at,
            format!("a file name of at most {MAX_FILE_NAME_CHARS} characters"),
        ));
    }
    if file
        .chars()
        .any(|c| c.is_control() || c == '/' || c == '\\')
    {
        return Err(DocumentError::field(
            at,
            format!("`{file}`: a file's name, without a folder or control characters"),
        ));
    }
    Ok(())
}

/// A static object of the scene: a primitive or a mesh, placed and turned.
#[derive(Debug, Clone, PartialEq)]
pub struct Prop {
    /// Its name in the *Scene* panel.
    pub name: String,
    /// Its shape and size.
    pub shape: PropShape,
    /// Scene position of its centre (m).
    pub position: [f64; 3],
    /// Its turn in the scene (unit quaternion `[x, y, z, w]`).
    pub rotation: [f64; 4],
}

impl Prop {
    /// A prop of `shape` at `position`, unturned.
    pub fn new(name: String, shape: PropShape, position: [f64; 3]) -> Self {
        Self {
            name,
            shape,
            position,
            rotation: [0.0, 0.0, 0.0, 1.0],
        }
    }

    /// The transform from the prop's frame (centred on it) to the scene's.
    pub fn scene_from_prop(&self) -> DAffine3 {
        DAffine3::from_rotation_translation(
            DQuat::from_array(self.rotation).normalize(),
            DVec3::from_array(self.position),
        )
    }

    /// The prop as a collision task's obstacle in the frame `frame_from_scene` takes the
    /// scene to (a character's, where its tasks are): a plane is a slab [`PLANE_DEPTH`] deep
    /// under its surface (the body is kept above it, as above the floor).
    pub fn obstacle(&self, frame_from_scene: DAffine3) -> Obstacle {
        let mut frame_from_prop = frame_from_scene * self.scene_from_prop();
        if let PropShape::Plane { .. } = self.shape {
            frame_from_prop.translation =
                frame_from_prop.transform_point3(DVec3::new(0.0, -PLANE_DEPTH / 2.0, 0.0));
        }
        let shape = match self.shape {
            // A mesh is its bounding box, turned with it.
            PropShape::Box { size } | PropShape::Mesh { size, .. } => ObstacleShape::Box {
                half: DVec3::from_array(size) / 2.0,
            },
            PropShape::Sphere { radius } => ObstacleShape::Sphere { radius },
            PropShape::Cylinder { radius, height } => ObstacleShape::Cylinder {
                radius,
                half_height: height / 2.0,
            },
            PropShape::Plane { size } => ObstacleShape::Box {
                half: DVec3::new(size[0] / 2.0, PLANE_DEPTH / 2.0, size[1] / 2.0),
            },
        };
        Obstacle {
            shape,
            world_from_obstacle_rotation: frame_from_prop.matrix3,
            position: frame_from_prop.translation,
        }
    }

    /// Checks its numbers: sizes above 0 and at most [`MAX_PROP_SIZE_M`], a finite position,
    /// a rotation of unit length (within 1e-3).
    pub fn validate_at(&self, at: &str) -> Result<(), DocumentError> {
        self.shape
            .validate_at(&format!("{at}.{}", self.shape.name()))?;
        if let Some(file) = self.shape.file() {
            check_file_name(file, &format!("{at}.file"))?;
        }
        if self.position.iter().any(|v| !v.is_finite()) {
            return Err(DocumentError::field(
                format!("{at}.position"),
                "not a finite number",
            ));
        }
        let norm = self.rotation.iter().map(|v| v * v).sum::<f64>().sqrt();
        if !norm.is_finite() || (norm - 1.0).abs() > 1e-3 {
            return Err(DocumentError::field(
                format!("{at}.rotation"),
                "expected a unit quaternion [x, y, z, w]",
            ));
        }
        Ok(())
    }

    pub(crate) fn from_json_value(
        v: &Value,
        at: &str,
        index: usize,
    ) -> Result<Self, DocumentError> {
        let o = obj(v, at)?;
        let word = string(
            o.get("shape").unwrap_or(&Value::Null),
            &format!("{at}.shape"),
        )?;
        let dimension = |key: &str| -> Result<f64, DocumentError> {
            number(o.get(key).unwrap_or(&Value::Null), &format!("{at}.{key}"))
        };
        let pair_or_triple = |key: &str, len: usize| -> Result<Vec<f64>, DocumentError> {
            numbers(
                o.get(key).unwrap_or(&Value::Null),
                &format!("{at}.{key}"),
                len,
            )
        };
        let shape = match word {
            "box" => {
                let s = pair_or_triple("size", 3)?;
                PropShape::Box {
                    size: [s[0], s[1], s[2]],
                }
            }
            "sphere" => PropShape::Sphere {
                radius: dimension("radius")?,
            },
            "cylinder" => PropShape::Cylinder {
                radius: dimension("radius")?,
                height: dimension("height")?,
            },
            "plane" => {
                let s = pair_or_triple("size", 2)?;
                PropShape::Plane { size: [s[0], s[1]] }
            }
            "mesh" => {
                let file = string(o.get("file").unwrap_or(&Value::Null), &format!("{at}.file"))?;
                let s = pair_or_triple("size", 3)?;
                PropShape::Mesh {
                    file: file.to_owned(),
                    size: [s[0], s[1], s[2]],
                }
            }
            other => {
                return Err(DocumentError::field(
                    format!("{at}.shape"),
                    format!(
                        "unknown shape `{other}`: one of {}",
                        PropShape::WORDS.join(", ")
                    ),
                ));
            }
        };
        let name = match o.get("name") {
            None | Some(Value::Null) => default_prop_name(&shape, index + 1),
            Some(n) => clean_name(string(n, &format!("{at}.name"))?)
                .unwrap_or_else(|| default_prop_name(&shape, index + 1)),
        };
        let position = match o.get("position") {
            None | Some(Value::Null) => [0.0; 3],
            Some(_) => {
                let p = pair_or_triple("position", 3)?;
                [p[0], p[1], p[2]]
            }
        };
        let rotation = match o.get("rotation") {
            None | Some(Value::Null) => [0.0, 0.0, 0.0, 1.0],
            Some(_) => {
                let q = pair_or_triple("rotation", 4)?;
                [q[0], q[1], q[2], q[3]]
            }
        };
        let prop = Self {
            name,
            shape,
            position,
            rotation,
        };
        prop.validate_at(at)?;
        Ok(prop)
    }

    fn to_json_value(&self) -> Value {
        let mut fields = Map::new();
        fields.insert("name".into(), Value::String(self.name.clone()));
        fields.insert("shape".into(), Value::String(self.shape.name().into()));
        match &self.shape {
            PropShape::Box { size } => {
                fields.insert("size".into(), serde_json::json!(size));
            }
            PropShape::Mesh { file, size } => {
                fields.insert("file".into(), Value::String(file.clone()));
                fields.insert("size".into(), serde_json::json!(size));
            }
            PropShape::Sphere { radius } => {
                fields.insert("radius".into(), serde_json::json!(radius));
            }
            PropShape::Cylinder { radius, height } => {
                fields.insert("radius".into(), serde_json::json!(radius));
                fields.insert("height".into(), serde_json::json!(height));
            }
            PropShape::Plane { size } => {
                fields.insert("size".into(), serde_json::json!(size));
            }
        }
        fields.insert("position".into(), serde_json::json!(self.position));
        fields.insert("rotation".into(), serde_json::json!(self.rotation));
        Value::Object(fields)
    }
}

/// The name of the `n`th prop (from 1) of `shape` when it is not named: "Box 2".
pub fn default_prop_name(shape: &PropShape, n: usize) -> String {
    let word = shape.name();
    let mut chars = word.chars();
    let capital: String = chars
        .next()
        .map(|c| c.to_ascii_uppercase())
        .into_iter()
        .chain(chars)
        .collect();
    format!("{capital} {n}")
}

/// Several characters and props; one character selected (the one the editor's tools work on).
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// The characters, in the outliner's order (at least one).
    pub characters: Vec<SceneCharacter>,
    /// The props, in the outliner's order.
    pub props: Vec<Prop>,
    /// The selected character's index.
    pub selected: usize,
    /// Tasks between characters (a hand in another's hand): the characters they join are
    /// solved together ([`crate::between::JoinedProblem`]).
    pub between: Vec<BetweenTask>,
    /// The mesh props' files a saved document carries (embedded, each once; a link never
    /// carries them): read, only those a prop names; written, only those a prop names.
    pub files: Vec<FileReference>,
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
            props: Vec::new(),
            selected: 0,
            between: Vec::new(),
            files: Vec::new(),
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
        if self.props.len() > MAX_PROPS {
            return Err(DocumentError::field(
                "props",
                format!(
                    "{} props; a scene holds at most {MAX_PROPS}",
                    self.props.len()
                ),
            ));
        }
        for (i, prop) in self.props.iter().enumerate() {
            prop.validate_at(&format!("props[{i}]"))?;
        }
        files::validate_files(&self.files, &self.props)?;
        for (i, character) in self.characters.iter().enumerate() {
            let at = format!("characters[{i}]");
            character
                .placement
                .validate_at(&format!("{at}.placement"))?;
            character.document.validate().map_err(|e| e.within(&at))?;
            for (k, task) in character.document.tasks.iter().enumerate() {
                if let Some(on) = &task.on
                    && !self.props.iter().any(|p| &p.name == on)
                {
                    return Err(DocumentError::field(
                        format!("{at}.tasks[{k}].on"),
                        format!("no prop is named `{on}`"),
                    ));
                }
            }
        }
        if self.between.len() > MAX_BETWEEN_TASKS {
            return Err(DocumentError::field(
                "between",
                format!("more than {MAX_BETWEEN_TASKS} tasks between characters"),
            ));
        }
        for (i, task) in self.between.iter().enumerate() {
            task.validate(self.characters.len())
                .map_err(|e| e.within(&format!("between[{i}]")))?;
        }
        Ok(())
    }

    /// Whether it is one character at the origin with the first character's default name:
    /// written as a plain document (nothing is lost).
    pub fn is_plain_document(&self) -> bool {
        self.props.is_empty()
            && self.between.is_empty()
            && matches!(self.characters.as_slice(), [only]
            if only.placement.is_identity() && only.name == default_character_name(1))
    }

    /// Parses and validates a scene, or a plain document as a scene of one, from JSON text.
    pub fn from_json(text: &str) -> Result<Self, DocumentError> {
        let v: Value =
            serde_json::from_str(text).map_err(|e| DocumentError::Json(e.to_string()))?;
        Self::from_json_value(&v)
    }

    /// Parses and validates a scene from a JSON value: `{"characters": [...], "props": [...],
    /// "files": [...], "selected": i}`, each character a document with `"name"` and
    /// `"placement"`; any other object is read as a document, a scene of one character.
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
        let props = match o.get("props") {
            None | Some(Value::Null) => Vec::new(),
            Some(Value::Array(list)) => {
                if list.len() > MAX_PROPS {
                    return Err(DocumentError::field(
                        "props",
                        format!("more than {MAX_PROPS} props"),
                    ));
                }
                list.iter()
                    .enumerate()
                    .map(|(i, v)| Prop::from_json_value(v, &format!("props[{i}]"), i))
                    .collect::<Result<Vec<_>, _>>()?
            }
            Some(_) => return Err(DocumentError::field("props", "expected an array of props")),
        };
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
        let files = files::files_from_json(o, &props)?;
        let scene = Self {
            characters,
            props,
            selected,
            between: between_from_json(o)?,
            files,
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
        let props: Vec<Value> = self.props.iter().map(Prop::to_json_value).collect();
        let mut o = Map::new();
        o.insert("characters".into(), Value::Array(characters));
        if !props.is_empty() {
            o.insert("props".into(), Value::Array(props));
        }
        if let Some(files) = files::files_to_json(&self.files, &self.props) {
            o.insert("files".into(), files);
        }
        if !self.between.is_empty() {
            let between = self
                .between
                .iter()
                .map(BetweenTask::to_json_value)
                .collect();
            o.insert("between".into(), Value::Array(between));
        }
        o.insert("selected".into(), serde_json::json!(self.selected));
        Value::Object(o)
    }

    /// The JSON text (pretty or compact); a plain document's own (the autosave writes one
    /// every time it changed: no value tree made on the way).
    pub fn to_json(&self, pretty: bool) -> String {
        match self.characters.as_slice() {
            [only] if self.is_plain_document() => only.document.to_json(pretty),
            _ => crate::json::text(&self.to_json_value(), pretty),
        }
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
