//! The Stance application: the posture editor (tasks with priorities, grab-and-pull, undo,
//! posture links, pose library) around the 3D viewport, and the eframe [`App`](eframe::App)
//! that runs it natively and in the browser.

#![warn(missing_docs)]

mod app;
pub mod avatar;
pub mod figure;
pub mod fonts;
pub mod history;
mod host;
pub mod library;
pub mod model;
pub mod posing;
pub mod sensors;
mod viewport;

pub use app::StanceApp;
pub use host::{
    AvatarImport, BackendSummary, ClipRetarget, HostHooks, HostMessage, ImportedAvatar, MemoryHost,
    MemoryHostState, NoHostHooks,
};
pub use model::{Command, EditorModel, Gesture, Notice, SessionChange};
pub use viewport::{CameraGesture, ViewportInput};
