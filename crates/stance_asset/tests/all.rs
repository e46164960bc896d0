//! stance_asset's integration tests as one binary: each file beside this one is a module
//! (one link of the crate and its dependencies instead of one per file). Run one file's
//! tests with `cargo test -p stance_asset --test all FILE::`.

#[cfg(target_arch = "wasm32")]
wasm_bindgen_test::wasm_bindgen_test_configure!(run_in_browser);

mod animation;
mod clip_transfer;
mod common;
mod decoded_images;
mod external_files;
mod formats;
mod fuzz_seeds;
mod hostile_sizes;
mod malformed;
mod prop_mesh;
mod shared_avatar;
mod standard_pose;
mod vrm;
