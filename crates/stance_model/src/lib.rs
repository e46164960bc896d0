//! The Stance editor's state without UI or GPU: the posing session (tasks with priorities,
//! grab-and-pull), the undo history, the timeline, the sensors, the pose library, the comfort
//! view and the avatar, changed by commands alone. The views (`stance_editor`, egui and wgpu)
//! read [`EditorModel`] and send it [`Command`]s; the tests drive it the same way.

#![warn(missing_docs)]
#![warn(clippy::too_many_lines)]

pub mod avatar;
pub mod history;
mod host;
pub mod jobs;
pub mod library;
pub mod model;
pub mod posing;
pub mod sensors;

pub use host::{
    AvatarImport, BackendSummary, HostHooks, HostMessage, ImportedAvatar, MemoryHost,
    MemoryHostState, NoHostHooks,
};
pub use jobs::{HostJob, JobHead, JobOutput, JobRequest, LiftJob};
pub use model::{Change, Command, EditorModel, Gesture, Notice, Outbox, SessionChange};
