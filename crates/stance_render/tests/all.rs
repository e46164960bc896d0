//! stance_render's integration tests as one binary: each file beside this one is a module
//! (one link of the crate and its dependencies instead of one per file). Run one file's
//! tests with `cargo test -p stance_render --test all FILE::`.

mod offscreen;
mod openpose;
mod shaders;
