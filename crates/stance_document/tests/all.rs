//! stance_document's integration tests as one binary: each file beside this one is a module
//! (one link of the crate and its dependencies instead of one per file). Run one file's
//! tests with `cargo test -p stance_document --test all FILE::`.

#[cfg(target_arch = "wasm32")]
wasm_bindgen_test::wasm_bindgen_test_configure!(run_in_browser);

mod between;
mod clip;
mod comfort_axes;
mod common;
mod document;
mod fuzz_seeds;
mod link;
mod problem;
mod scene;
mod scene_files;
mod stiffness;
