//! stance_ik's integration tests as one binary: each file beside this one is a module
//! (one link of the crate and its dependencies instead of one per file). Run one file's
//! tests with `cargo test -p stance_ik --test all FILE::`.

#[cfg(target_arch = "wasm32")]
wasm_bindgen_test::wasm_bindgen_test_configure!(run_in_browser);

mod balance_direction;
mod bodies;
mod collision;
mod comfort;
mod common;
mod convergence;
mod damping;
mod joint_rotation;
mod kinematics;
mod limb;
mod line_plane;
mod priority;
mod table1;
mod timing;
