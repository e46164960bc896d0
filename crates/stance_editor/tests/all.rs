//! stance_editor's integration tests as one binary: each file beside this one is a module
//! (one link of the crate and its dependencies instead of one per file). Run one file's
//! tests with `cargo test -p stance_editor --test all FILE::`. The model's own tests, by
//! commands alone, are stance_model's; these drive the views (egui, kittest) and the GPU.

mod avatar_mapping;
mod avatar_render;
mod clip_opening;
// The model frame by frame, shared with stance_model's tests.
#[path = "../../stance_model/tests/clocked/mod.rs"]
mod clocked;
mod common;
mod editor_ui;
mod fonts;
mod frame_cost;
mod image;
mod scene_ui;
mod sensors;
