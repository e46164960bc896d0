//! stance_model's integration tests as one binary: each file beside this one is a module (one
//! link of the crate and its dependencies instead of one per file). The model is driven by
//! commands alone, as the views drive it. Run one file's tests with
//! `cargo test -p stance_model --test all FILE::`.

mod avatar_swap;
mod between;
mod clips;
mod clocked;
mod collision;
mod hands;
mod kept_clips;
mod kept_prop_files;
mod keypoints;
mod mesh_props;
mod model;
mod motion;
mod photo;
mod scene;
mod tasks;
