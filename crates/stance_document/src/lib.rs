//! The Stance editor's document and its share-link codec. Pure Rust, no I/O; builds for
//! `wasm32-unknown-unknown`.
//!
//! - [`Document`]: the avatar reference, the posture ([`PostureValues`], `{"joint": {"dof":
//!   value}}`) and the task set ([`TaskSpec`]); its JSON form is `docs/document-format.md`,
//!   with the field names of the `stance solve` problem format.
//! - [`TaskSpec::to_task`], [`PostureValues::to_posture`], [`PostureValues::from_posture`]:
//!   to and from the solver's types; errors name the field (`tasks[2].joint: unknown joint ...`).
//! - [`FileReference`]: a file a document names by content hash and, saved, embeds
//!   (compressed): the motion clip the keys were made over ([`ClipReference`]) and the mesh
//!   props' files of a scene.
//! - [`Scene`]: several characters, each a document with a name and a placement.
//! - [`link`]: the compact, versioned, checksummed URL-fragment form of a document.
//! - [`Problem`]: the one way from tasks to a solver problem (tasks by level, closed-form limb
//!   starts, settings), from a problem file (`stance solve`) or a document on a skeleton;
//!   [`FrameProblem`]: one frame of interactive posing (the tasks, a part held, a pull), for
//!   the editor and the package's per-frame solver; [`task_statuses`]: how each task fares.

#![warn(missing_docs)]

pub mod between;
pub mod camera;
pub mod clip;
pub mod comfort;
mod convert;
mod document;
mod error;
pub mod file;
mod frame;
mod json;
pub mod link;
pub mod motion;
mod problem;
mod range_coder;
pub mod scene;
mod status;
pub mod stiffness;
mod task_json;
mod words;

pub use between::{
    BetweenTask, CharacterPoint, JoinedProblem, JoinedTasks, body_placement, joined_groups,
    joined_groups_of, joined_tasks,
};
pub use camera::CameraSpec;
pub use clip::{ClipReference, EmbeddedClip};
pub use convert::{
    LimbStartSpec, limb_joint_indices, pinned_contacts, resolve_joint, solver_tasks,
};
pub use document::{
    AvatarReference, CONTACT_HEIGHT, DEFAULT_BALANCE_MARGIN, DEFAULT_COMFORT, DOCUMENT_VERSION,
    Document, DofValues, LimbName, PostureRest, PostureValues, TaskKindSpec, TaskSpec,
};
pub use error::DocumentError;
pub use file::{EmbeddedFile, FileKind, FileReference, content_hash};
pub use frame::{FrameProblem, Grab, level_below_hard_tasks};
pub use link::LinkError;
pub use motion::{MotionKey, MotionSection, TaskInterval};
pub use problem::{
    LimbStart, Problem, ProblemSettings, parse_skeleton, problem_json, skeleton_json,
};
pub use scene::{
    Placement, Prop, PropShape, Scene, SceneCharacter, clean_name, default_character_name,
    default_prop_name,
};
pub use status::{MET_TOLERANCE, TaskStatus, statuses_json, task_statuses};
pub use stiffness::{StiffnessValues, apply_stiffness};
pub use words::COLLISION_LEVEL;
