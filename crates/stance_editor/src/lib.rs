//! The Stance application: the editor shell (menu bar, side panel, status bar) around the 3D
//! viewport, and the eframe [`App`](eframe::App) that runs it natively and in the browser.

mod app;
pub mod posing;
mod viewport;

pub use app::{BackendSummary, HostHooks, NoHostHooks, StanceApp};
pub use viewport::{CameraGesture, ViewportInput};
