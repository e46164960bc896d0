//! stance_cli's integration tests as one binary: each file beside this one is a module
//! (one link of the crate and its dependencies instead of one per file). Run one file's
//! tests with `cargo test -p stance_cli --test all FILE::`.

mod avatar_cli;
mod cli;
mod limb_cli;
mod link_cli;
mod mocap_cli;
mod render_avatars_cli;
mod render_cli;
mod render_props_cli;
