//! The editor's document: avatar reference, posture and task set, with its JSON form
//! (`docs/document-format.md`). Field names follow the `stance solve` problem format
//! (`docs/problem-format.md`), so a problem file's `tasks` array is a valid document `tasks`.

use std::collections::BTreeMap;

use serde::ser::{SerializeMap, SerializeStruct};
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use serde_json::Value;
use stance_ik::{Axes, Dof};

use crate::DocumentError;
use crate::camera::CameraSpec;
use crate::clip::{CLIP_FILE, ClipReference};
use crate::json::{field, number, obj, string};
use crate::motion::{MotionSection, TaskInterval};
use crate::stiffness::{StiffnessValues, validate_stiffness};

/// The version written in the `version` field of a document's JSON; newer versions are refused.
pub const DOCUMENT_VERSION: u32 = 1;

/// The whole editable state that a file or a link carries.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Document {
    /// Which avatar the posture is for.
    pub avatar: AvatarReference,
    /// DOF values by joint name.
    pub posture: PostureValues,
    /// The task set, in the editor's order.
    pub tasks: Vec<TaskSpec>,
    /// The timeline and its keyframes; `None` for a single posture.
    pub motion: Option<MotionSection>,
    /// The camera saved with the document; `None`: the viewer's own.
    pub camera: Option<CameraSpec>,
    /// Joint stiffness that replaces the body's anatomical defaults (see
    /// [`crate::stiffness`]); empty: the defaults.
    pub stiffness: StiffnessValues,
    /// What the posture values are relative to.
    pub rest: PostureRest,
    /// The motion clip the keys and timed tasks were made over; `None`: none (the keys are
    /// over the rest posture, or the document was written before clips were kept).
    pub clip: Option<ClipReference>,
}

/// What a document's posture values (its posture, keys and posture-task references) are
/// relative to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PostureRest {
    /// The H-Anim standard pose (the default mannequin's rest), on every body: the same
    /// values show the same pose on any avatar (`"rest": "standard"`).
    #[default]
    Standard,
    /// The avatar's own rest, as documents and links made on an avatar before Stance wrote
    /// `rest` were (`"rest": "avatar"`; on the default mannequin both are the same). Opened
    /// on that avatar, the values are converted
    /// ([`crate::Document::in_standard_rest`]).
    Avatar,
}

impl PostureRest {
    /// The JSON word.
    pub fn name(self) -> &'static str {
        match self {
            PostureRest::Standard => "standard",
            PostureRest::Avatar => "avatar",
        }
    }
}

/// The avatar a document is posed on.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub enum AvatarReference {
    /// The built-in default humanoid.
    #[default]
    Default,
    /// A glTF/GLB/VRM file at this URL.
    Url(String),
}

/// The values of one joint's DOF (`tx ty tz` metres, `rx ry rz` rotation-vector radians); a
/// DOF that is absent is 0 when the posture is applied.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DofValues {
    values: [Option<f64>; 6],
}

impl DofValues {
    /// The value of `dof`, if present.
    pub fn get(&self, dof: Dof) -> Option<f64> {
        self.values[dof_slot(dof)]
    }

    /// Sets the value of `dof`.
    pub fn set(&mut self, dof: Dof, value: f64) {
        self.values[dof_slot(dof)] = Some(value);
    }

    /// Removes `dof`.
    pub fn remove(&mut self, dof: Dof) {
        self.values[dof_slot(dof)] = None;
    }

    /// The present DOF and their values, in the order `tx ty tz rx ry rz`.
    pub fn iter(&self) -> impl Iterator<Item = (Dof, f64)> + '_ {
        Dof::ALL
            .into_iter()
            .zip(self.values)
            .filter_map(|(d, v)| v.map(|v| (d, v)))
    }

    /// Whether no DOF is present.
    pub fn is_empty(&self) -> bool {
        self.values.iter().all(Option::is_none)
    }
}

/// Index of a DOF in `Dof::ALL` order.
pub(crate) fn dof_slot(dof: Dof) -> usize {
    match dof {
        Dof::Tx => 0,
        Dof::Ty => 1,
        Dof::Tz => 2,
        Dof::Rx => 3,
        Dof::Ry => 4,
        Dof::Rz => 5,
    }
}

/// `{"joint": {"dof": value}}`, exactly the `posture` object of the problem format: root
/// translation `tx ty tz` in metres, rotation-vector components `rx ry rz` in radians.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PostureValues {
    /// DOF values by joint name.
    pub joints: BTreeMap<String, DofValues>,
}

impl PostureValues {
    /// An empty posture (the rest posture once applied).
    pub fn new() -> Self {
        Self::default()
    }

    /// Sets one value (builder-free helper for the editor and tests).
    pub fn set(&mut self, joint: &str, dof: Dof, value: f64) {
        self.joints
            .entry(joint.to_owned())
            .or_default()
            .set(dof, value);
    }

    /// One value, if present.
    pub fn get(&self, joint: &str, dof: Dof) -> Option<f64> {
        self.joints.get(joint).and_then(|v| v.get(dof))
    }

    /// Checks that every value is finite; `at` is the path of this posture (e.g. `posture`).
    pub fn validate_at(&self, at: &str) -> Result<(), DocumentError> {
        for (joint, dofs) in &self.joints {
            for (dof, v) in dofs.iter() {
                if !v.is_finite() {
                    return Err(DocumentError::field(
                        format!("{at}.{joint}.{}", dof.name()),
                        "not a finite number",
                    ));
                }
            }
        }
        Ok(())
    }
}

/// Which limb an analytic limb task drives (H-Anim words, kept in `stance_hanim`).
pub use stance_hanim::LimbName;

/// Default `margin` of a balance task (m).
pub const DEFAULT_BALANCE_MARGIN: f64 = 0.02;

/// A comfort task's default weights: effort, range, RULA's stand-in.
pub const DEFAULT_COMFORT: (f64, f64, f64) = (1.0, 0.1, 0.5);

/// A pinned part whose target is at most this high above the floor (y = 0) touches it and
/// supports the body (m): an ankle stands about 8 cm high, a hand or knee on the floor less.
pub const CONTACT_HEIGHT: f64 = 0.15;

/// One task of the document, as in the problem format's `tasks[]`.
#[derive(Debug, Clone, PartialEq)]
pub struct TaskSpec {
    /// Priority level, >= 1 (1 = highest).
    pub level: u32,
    /// Weight inside the level, >= 0.
    pub weight: f64,
    /// Inactive tasks are kept but not solved.
    pub active: bool,
    /// What the task controls.
    pub kind: TaskKindSpec,
    /// When the task acts on a timeline; `None`: always.
    pub interval: Option<TaskInterval>,
    /// The prop (by name) the task is attached to in a scene: its goal follows the prop when
    /// the prop or the character moves (the editor moves it with [`TaskSpec::moved`]; the
    /// solver reads the goal as written).
    pub on: Option<String>,
}

impl TaskSpec {
    /// A task at level 1, weight 1, active.
    pub fn new(kind: TaskKindSpec) -> Self {
        Self {
            level: 1,
            weight: 1.0,
            active: true,
            kind,
            interval: None,
            on: None,
        }
    }
}

/// The kinds of task, with the problem format's field names.
#[derive(Debug, Clone, PartialEq)]
pub enum TaskKindSpec {
    /// `"position"`: a point of a segment toward a world target along the chosen axes.
    Position {
        /// Joint name.
        joint: String,
        /// Point in the joint frame (m).
        point: [f64; 3],
        /// Controlled world axes.
        axes: Axes,
        /// World target (m); `axes` selects the components used.
        target: [f64; 3],
    },
    /// `"orientation"`: the segment's world orientation.
    Orientation {
        /// Joint name.
        joint: String,
        /// `world_from_joint` quaternion `[qx, qy, qz, qw]` (non-zero; normalised when used).
        target: [f64; 4],
    },
    /// `"gaze"`: a segment axis aims at a world point.
    Gaze {
        /// Joint name.
        joint: String,
        /// Aiming axis in the joint frame (non-zero).
        axis: [f64; 3],
        /// Eye point in the joint frame (m).
        point: [f64; 3],
        /// World point to look at (m).
        target: [f64; 3],
    },
    /// `"direction"`: partial orientation, a segment axis along a world direction (the
    /// rotation about it left free): pelvis upright, palm facing down.
    Direction {
        /// Joint name.
        joint: String,
        /// Axis in the joint frame (non-zero).
        axis: [f64; 3],
        /// World direction (non-zero).
        target: [f64; 3],
    },
    /// `"balance"`: the centre of mass's projection inside the support polygon, `margin` from
    /// its edges (an inequality: no constraint while it is inside).
    Balance {
        /// The contacts (joint names; a foot joint stands for its whole sole). `None`: the
        /// problem's pinned parts touching the floor ([`CONTACT_HEIGHT`]), else both feet.
        support: Option<Vec<String>>,
        /// Distance kept from the polygon's edges (m), >= 0.
        margin: f64,
    },
    /// `"com"`: the whole-body centre of mass.
    Com {
        /// Controlled world axes (`xz`: the horizontal projection).
        axes: Axes,
        /// World target (m).
        target: [f64; 3],
    },
    /// `"posture"`: attraction toward a reference posture.
    Posture {
        /// Attracted joints; `None` = every rotational DOF of every non-root joint.
        joints: Option<Vec<String>>,
        /// Reference posture; `None` = the rest posture.
        reference: Option<PostureValues>,
    },
    /// `"comfort"`: the posture's discomfort lowered along its gradient, projected into what
    /// the levels above leave (the paper's null-space term); alone at its level.
    Comfort {
        /// Weight of the effort against gravity (sum of squared shares of joint strength).
        effort: f64,
        /// Weight of the joint-range discomfort.
        range: f64,
        /// Weight of the smooth stand-in for RULA.
        rula: f64,
    },
    /// `"collision"`: the body's capsules (`stance_hanim::capsules`, radii from its
    /// proportions) kept `margin` apart from each other and above the floor; an inequality
    /// (no constraint while the body is clear).
    Collision {
        /// Distance kept between surfaces (m), >= 0.
        margin: f64,
        /// The capsules kept apart from each other (`"self"`).
        self_collision: bool,
        /// The capsules kept above the floor.
        floor: bool,
    },
    /// `"limb"`: the analytic arm/leg task (wrist/ankle goal plus swivel angle).
    Limb {
        /// The limb by name (`"l_arm"`...); either this or `joints`.
        limb: Option<LimbName>,
        /// The three joints (root, middle, end), when named explicitly.
        joints: Option<[String; 3]>,
        /// World goal of the end joint (m).
        target: [f64; 3],
        /// Swivel angle of the elbow/knee around the upper-end axis (rad); `None` = keep the
        /// current one.
        swivel: Option<f64>,
        /// Optional `world_from_end` quaternion `[qx, qy, qz, qw]` of the end joint.
        orientation: Option<[f64; 4]>,
    },
    /// `"line"`: a point of a segment kept on a world line (a hand on a bar, a keypoint on
    /// the camera ray through its pixel).
    Line {
        /// Joint name.
        joint: String,
        /// Point in the joint frame (m).
        point: [f64; 3],
        /// A point of the line (world, m).
        origin: [f64; 3],
        /// The line's direction (world, non-zero).
        direction: [f64; 3],
    },
    /// `"plane"`: a point of a segment kept on a world plane, or with `above` on or above it
    /// (an inequality: a hand or foot on a surface).
    Plane {
        /// Joint name.
        joint: String,
        /// Point in the joint frame (m).
        point: [f64; 3],
        /// A point of the plane (world, m).
        origin: [f64; 3],
        /// The plane's normal (world, non-zero); `above` means on its side.
        normal: [f64; 3],
        /// On or above the plane instead of on it.
        above: bool,
    },
}

impl TaskKindSpec {
    /// The `kind` string.
    pub fn name(&self) -> &'static str {
        match self {
            TaskKindSpec::Position { .. } => "position",
            TaskKindSpec::Orientation { .. } => "orientation",
            TaskKindSpec::Gaze { .. } => "gaze",
            TaskKindSpec::Direction { .. } => "direction",
            TaskKindSpec::Balance { .. } => "balance",
            TaskKindSpec::Com { .. } => "com",
            TaskKindSpec::Posture { .. } => "posture",
            TaskKindSpec::Comfort { .. } => "comfort",
            TaskKindSpec::Collision { .. } => "collision",
            TaskKindSpec::Limb { .. } => "limb",
            TaskKindSpec::Line { .. } => "line",
            TaskKindSpec::Plane { .. } => "plane",
        }
    }

    /// The world point the task aims at, for the kinds that have one (position, gaze, limb:
    /// m, H-Anim world frame); pictures mark it.
    pub fn goal_point(&self) -> Option<[f64; 3]> {
        match self {
            TaskKindSpec::Position { target, .. }
            | TaskKindSpec::Gaze { target, .. }
            | TaskKindSpec::Limb { target, .. } => Some(*target),
            _ => None,
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Validation

fn finite_all(values: &[f64], at: &str) -> Result<(), DocumentError> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(i) => Err(DocumentError::field(
            format!("{at}[{i}]"),
            "not a finite number",
        )),
        None => Ok(()),
    }
}

fn nonzero(values: &[f64], at: &str, what: &str) -> Result<(), DocumentError> {
    if values.iter().map(|v| v * v).sum::<f64>().sqrt() < 1e-9 {
        return Err(DocumentError::field(at, format!("zero-length {what}")));
    }
    Ok(())
}

/// A task's level (an integer from 1) and weight (finite, >= 0); paths `level`, `weight`.
pub(crate) fn check_level_and_weight(level: u32, weight: f64) -> Result<(), DocumentError> {
    if level < 1 {
        return Err(DocumentError::field(
            "level",
            "levels are integers from 1 (highest priority)",
        ));
    }
    if !weight.is_finite() || weight < 0.0 {
        return Err(DocumentError::field(
            "weight",
            "must be a finite number >= 0",
        ));
    }
    Ok(())
}

impl TaskSpec {
    /// Checks the task on its own (finite numbers, level >= 1, weight >= 0, non-zero
    /// quaternion and axis, a limb named once). Paths are relative (`target[0]`).
    pub fn validate(&self) -> Result<(), DocumentError> {
        check_level_and_weight(self.level, self.weight)?;
        if let Some(interval) = &self.interval {
            interval.validate()?;
        }
        match &self.kind {
            TaskKindSpec::Position { point, target, .. } => {
                finite_all(point, "point")?;
                finite_all(target, "target")?;
            }
            TaskKindSpec::Orientation { target, .. } => {
                finite_all(target, "target")?;
                if nonzero(target, "target", "").is_err() {
                    return Err(DocumentError::field(
                        "target",
                        "the quaternion has zero length",
                    ));
                }
            }
            TaskKindSpec::Gaze {
                axis,
                point,
                target,
                ..
            } => {
                finite_all(axis, "axis")?;
                nonzero(axis, "axis", "axis")?;
                finite_all(point, "point")?;
                finite_all(target, "target")?;
            }
            TaskKindSpec::Direction { axis, target, .. } => {
                finite_all(axis, "axis")?;
                nonzero(axis, "axis", "axis")?;
                finite_all(target, "target")?;
                nonzero(target, "target", "direction")?;
            }
            TaskKindSpec::Collision { margin, .. } => {
                if !margin.is_finite() || *margin < 0.0 {
                    return Err(DocumentError::field(
                        "margin",
                        "must be a finite number >= 0",
                    ));
                }
            }
            TaskKindSpec::Balance { support, margin } => {
                if !margin.is_finite() || *margin < 0.0 {
                    return Err(DocumentError::field(
                        "margin",
                        "must be a finite number >= 0",
                    ));
                }
                if support.as_ref().is_some_and(Vec::is_empty) {
                    return Err(DocumentError::field(
                        "support",
                        "empty (leave it out for the pinned contacts)",
                    ));
                }
            }
            TaskKindSpec::Com { target, .. } => finite_all(target, "target")?,
            TaskKindSpec::Posture { reference, .. } => {
                if let Some(r) = reference {
                    r.validate_at("reference")?;
                }
            }
            TaskKindSpec::Comfort {
                effort,
                range,
                rula,
            } => {
                for (name, w) in [("effort", effort), ("range", range), ("rula", rula)] {
                    if !(w.is_finite() && *w >= 0.0) {
                        return Err(DocumentError::field(name, "must be a finite number >= 0"));
                    }
                }
                if *effort + *range + *rula <= 0.0 {
                    return Err(DocumentError::field(
                        "effort",
                        "a comfort task needs a weight above 0 on effort, range or rula",
                    ));
                }
            }
            TaskKindSpec::Limb {
                limb,
                joints,
                target,
                swivel,
                orientation,
            } => {
                finite_all(target, "target")?;
                if let Some(s) = swivel
                    && !s.is_finite()
                {
                    return Err(DocumentError::field("swivel", "not a finite number"));
                }
                if let Some(q) = orientation {
                    finite_all(q, "orientation")?;
                    if nonzero(q, "orientation", "").is_err() {
                        return Err(DocumentError::field(
                            "orientation",
                            "the quaternion has zero length",
                        ));
                    }
                }
                match (limb, joints) {
                    (Some(_), Some(_)) => {
                        return Err(DocumentError::field(
                            "",
                            "give either `joints` or `limb`, not both",
                        ));
                    }
                    (None, None) => {
                        return Err(DocumentError::field("joints", "missing (or give `limb`)"));
                    }
                    _ => {}
                }
            }
            TaskKindSpec::Line {
                point,
                origin,
                direction: vector,
                ..
            }
            | TaskKindSpec::Plane {
                point,
                origin,
                normal: vector,
                ..
            } => {
                let (name, what) = match self.kind {
                    TaskKindSpec::Line { .. } => ("direction", "direction"),
                    _ => ("normal", "normal"),
                };
                finite_all(point, "point")?;
                finite_all(origin, "origin")?;
                finite_all(vector, name)?;
                nonzero(vector, name, what)?;
            }
        }
        Ok(())
    }
}

/// The top-level fields of a document (`docs/document-format.md`), as written and read.
const DOCUMENT_FIELDS: [&str; 9] = [
    "version",
    "avatar",
    "rest",
    "posture",
    "tasks",
    "motion",
    "camera",
    "stiffness",
    "clip",
];

impl Document {
    /// Checks every field: finite numbers (a document never holds NaN or infinity), levels,
    /// weights, quaternions, axes. Errors name the field (`tasks[2].target[0]`).
    pub fn validate(&self) -> Result<(), DocumentError> {
        if let AvatarReference::Url(u) = &self.avatar
            && u.is_empty()
        {
            return Err(DocumentError::field("avatar.url", "empty URL"));
        }
        self.posture.validate_at("posture")?;
        for (i, t) in self.tasks.iter().enumerate() {
            t.validate().map_err(|e| e.within(&format!("tasks[{i}]")))?;
        }
        if let Some(motion) = &self.motion {
            motion.validate()?;
        }
        if let Some(camera) = &self.camera {
            camera.validate()?;
        }
        validate_stiffness(&self.stiffness, "stiffness")?;
        if let Some(clip) = &self.clip {
            clip.validate_at("clip", &CLIP_FILE)?;
        }
        Ok(())
    }

    /// Parses and validates a document from its JSON text.
    pub fn from_json(text: &str) -> Result<Self, DocumentError> {
        let v: Value =
            serde_json::from_str(text).map_err(|e| DocumentError::Json(e.to_string()))?;
        Self::from_json_value(&v)
    }

    /// Parses and validates a document from a JSON value. An object with fields but none of
    /// a document's is refused, naming what it has (an OpenPose keypoints file, a glTF's JSON:
    /// read as an empty document, opening one would replace the user's work with nothing);
    /// `{}` is the empty document, and unknown fields beside a document's are ignored.
    pub fn from_json_value(v: &Value) -> Result<Self, DocumentError> {
        let o = obj(v, "the document")?;
        if !o.is_empty() && !o.keys().any(|k| DOCUMENT_FIELDS.contains(&k.as_str())) {
            let found: Vec<&str> = o.keys().take(4).map(String::as_str).collect();
            return Err(DocumentError::field(
                "the document",
                format!(
                    "none of a document's fields ({}); it has {}{}",
                    DOCUMENT_FIELDS.join(", "),
                    found.join(", "),
                    if o.len() > found.len() { ", ..." } else { "" }
                ),
            ));
        }
        if let Some(ver) = o.get("version").filter(|v| !v.is_null()) {
            let n = number(ver, "version")?;
            if n.fract() != 0.0 || n < 1.0 {
                return Err(DocumentError::field("version", "expected an integer >= 1"));
            }
            if n > f64::from(DOCUMENT_VERSION) {
                return Err(DocumentError::field(
                    "version",
                    format!(
                        "this document was written by a newer version of Stance (format {n}); this version reads format {DOCUMENT_VERSION}"
                    ),
                ));
            }
        }
        let avatar = match o.get("avatar") {
            None | Some(Value::Null) => AvatarReference::Default,
            Some(Value::String(s)) if s == "default" => AvatarReference::Default,
            Some(Value::Object(a)) => {
                let url = string(field(a, "url", "avatar")?, "avatar.url")?;
                AvatarReference::Url(url.to_owned())
            }
            Some(_) => {
                return Err(DocumentError::field(
                    "avatar",
                    "expected \"default\" or {\"url\": \"...\"}",
                ));
            }
        };
        let posture = match o.get("posture") {
            None | Some(Value::Null) => PostureValues::default(),
            Some(p) => PostureValues::from_json_value(p, "posture")?,
        };
        let tasks = match o.get("tasks") {
            None | Some(Value::Null) => Vec::new(),
            Some(t) => TaskSpec::list_from_json_value(t, "tasks")?,
        };
        let motion = match o.get("motion") {
            None | Some(Value::Null) => None,
            Some(m) => Some(MotionSection::from_json_value(m)?),
        };
        let camera = match o.get("camera") {
            None | Some(Value::Null) => None,
            Some(c) => Some(CameraSpec::from_json_value(c)?),
        };
        let stiffness = match o.get("stiffness") {
            None | Some(Value::Null) => StiffnessValues::default(),
            Some(p) => PostureValues::from_json_value(p, "stiffness")?,
        };
        // Absent: written before `rest` existed, when values were relative to the body's own
        // rest (the standard pose on the mannequin).
        let rest = match o.get("rest") {
            None | Some(Value::Null) => match avatar {
                AvatarReference::Default => PostureRest::Standard,
                AvatarReference::Url(_) => PostureRest::Avatar,
            },
            Some(Value::String(s)) if s == "standard" => PostureRest::Standard,
            Some(Value::String(s)) if s == "avatar" => PostureRest::Avatar,
            Some(_) => {
                return Err(DocumentError::field(
                    "rest",
                    "expected \"standard\" or \"avatar\"",
                ));
            }
        };
        let clip = match o.get("clip") {
            None | Some(Value::Null) => None,
            Some(c) => Some(ClipReference::from_json_value(c, "clip", &CLIP_FILE)?),
        };
        let doc = Document {
            avatar,
            posture,
            tasks,
            motion,
            camera,
            stiffness,
            rest,
            clip,
        };
        doc.validate()?;
        Ok(doc)
    }

    /// The JSON text (pretty or compact).
    pub fn to_json(&self, pretty: bool) -> String {
        crate::json::text(self, pretty)
    }
}

impl PostureValues {
    /// Parses `{"joint": {"dof": value}}`; `at` is the path used in errors (e.g. `posture`).
    pub fn from_json_value(v: &Value, at: &str) -> Result<Self, DocumentError> {
        let mut p = PostureValues::default();
        for (name, dofs) in obj(v, at)? {
            let here = format!("{at}.{name}");
            let mut values = DofValues::default();
            for (dname, value) in obj(dofs, &here)? {
                let there = format!("{here}.{dname}");
                let d = Dof::from_name(dname).ok_or_else(|| {
                    DocumentError::field(&there, "unknown DOF (expected tx, ty, tz, rx, ry or rz)")
                })?;
                values.set(d, number(value, &there)?);
            }
            p.joints.insert(name.clone(), values);
        }
        Ok(p)
    }
}

// ---------------------------------------------------------------------------------------------
// serde

impl Serialize for DofValues {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(None)?;
        for (d, v) in self.iter() {
            m.serialize_entry(d.name(), &v)?;
        }
        m.end()
    }
}

impl Serialize for PostureValues {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.joints.serialize(s)
    }
}

impl Serialize for AvatarReference {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            AvatarReference::Default => s.serialize_str("default"),
            AvatarReference::Url(u) => {
                let mut m = s.serialize_map(Some(1))?;
                m.serialize_entry("url", u)?;
                m.end()
            }
        }
    }
}

impl Serialize for Document {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut st = s.serialize_struct("Document", 4)?;
        st.serialize_field("version", &DOCUMENT_VERSION)?;
        st.serialize_field("avatar", &self.avatar)?;
        st.serialize_field("rest", self.rest.name())?;
        st.serialize_field("posture", &self.posture)?;
        st.serialize_field("tasks", &self.tasks)?;
        if let Some(motion) = &self.motion {
            st.serialize_field("motion", motion)?;
        }
        if let Some(camera) = &self.camera {
            st.serialize_field("camera", camera)?;
        }
        if !self.stiffness.joints.is_empty() {
            st.serialize_field("stiffness", &self.stiffness)?;
        }
        if let Some(clip) = &self.clip {
            st.serialize_field("clip", clip)?;
        }
        st.end()
    }
}

impl<'de> Deserialize<'de> for Document {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Value::deserialize(d)?;
        Document::from_json_value(&v).map_err(serde::de::Error::custom)
    }
}

impl<'de> Deserialize<'de> for PostureValues {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Value::deserialize(d)?;
        let p = PostureValues::from_json_value(&v, "posture").map_err(serde::de::Error::custom)?;
        p.validate_at("posture").map_err(serde::de::Error::custom)?;
        Ok(p)
    }
}
