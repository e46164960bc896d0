//! The Stance application: the posture editor (tasks with priorities, grab-and-pull, undo,
//! posture links, pose library) around the 3D viewport, and the eframe [`App`](eframe::App)
//! that runs it natively and in the browser. The editor's state is `stance_model`'s (re-exported
//! here): this crate holds the views, the viewport and what draws with the GPU.

#![warn(missing_docs)]
#![warn(clippy::too_many_lines)]

mod app;
pub mod cast_models;
mod cast_view;
pub mod figure;
pub mod fonts;
pub mod image;
mod viewport;

pub use app::StanceApp;
pub use cast_view::OTHER_COLOR_LINEAR;
pub use stance_model::{
    AvatarImport, BackendSummary, Command, EditorModel, Gesture, HostHooks, HostJob, HostMessage,
    ImportedAvatar, JobHead, JobOutput, JobRequest, MemoryHost, MemoryHostState, NoHostHooks,
    Notice, SessionChange,
};
pub use stance_model::{avatar, history, library, model, posing, sensors};
pub use viewport::{CameraGesture, ViewportInput};
