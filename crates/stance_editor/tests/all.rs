//! stance_editor's integration tests as one binary: each file beside this one is a module
//! (one link of the crate and its dependencies instead of one per file). Run one file's
//! tests with `cargo test -p stance_editor --test all FILE::`.

mod avatar_mapping;
mod avatar_render;
mod avatar_swap;
mod clip_opening;
mod clips;
mod clocked;
mod common;
mod editor_ui;
mod fonts;
mod frame_cost;
mod hands;
mod image;
mod kept_clips;
mod model;
mod motion;
mod sensors;
