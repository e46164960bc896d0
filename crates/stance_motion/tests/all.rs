//! stance_motion's integration tests as one binary: each file beside this one is a module
//! (one link of the crate and its dependencies instead of one per file). Run one file's
//! tests with `cargo test -p stance_motion --test all FILE::`.

#[cfg(target_arch = "wasm32")]
wasm_bindgen_test::wasm_bindgen_test_configure!(run_in_browser);

mod bvh_fixtures;
mod bvh_malformed;
mod bvh_proptest;
mod bvh_read;
#[cfg(not(target_arch = "wasm32"))]
mod clips;
mod common;
mod retarget;
