//! Hostile and broken inputs: clear errors, never a panic (also fuzzed with proptest).

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;
#[cfg(target_arch = "wasm32")]
wasm_bindgen_test::wasm_bindgen_test_configure!(run_in_browser);

mod common;

use serde_json::json;
use stance_asset::{AssetError, LoadOptions, load_avatar};

fn load(bytes: &[u8]) -> Result<stance_asset::Avatar, AssetError> {
    load_avatar(bytes, &LoadOptions::default())
}

fn err(bytes: &[u8]) -> String {
    match load(bytes) {
        Ok(_) => panic!("loaded a broken file"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn the_default_avatar_loads() {
    let avatar = load(&common::default_glb()).unwrap();
    assert!(
        avatar
            .mapping
            .missing(stance_hanim::LevelOfArticulation::Loa2)
            .is_empty()
    );
}

#[test]
fn truncated_glb() {
    let glb = common::default_glb();
    for cut in [0, 3, 11, 19, 100, glb.len() / 2, glb.len() - 1] {
        let e = err(&glb[..cut]);
        assert!(
            e.contains("truncated") || e.contains("not a glTF") || e.contains("past the end"),
            "cut at {cut}: {e}"
        );
    }
}

#[test]
fn bad_json() {
    assert!(err(b"{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [").starts_with("bad glTF JSON"));
    assert!(err(b"{\"nodes\": []}").contains("asset.version"));
    assert!(err(b"{\"asset\": {\"version\": \"1.0\"}}").contains("unsupported glTF version"));
    assert!(err(b"\x00\x01binary").contains("not a glTF"));
    let e = err(br#"{"asset":{"version":"2.0"},"nodes":[{"children":[0]}]}"#);
    assert!(e.contains("own child"), "{e}");
    let e = err(br#"{"asset":{"version":"2.0"},"nodes":[{"children":[1]},{"children":[0]}]}"#);
    assert!(e.contains("two parents") || e.contains("cycle"), "{e}");
    let e =
        err(br#"{"asset":{"version":"2.0"},"extensionsRequired":["KHR_draco_mesh_compression"]}"#);
    assert!(e.contains("KHR_draco_mesh_compression"), "{e}");
}

#[test]
fn wrong_accessor_counts() {
    let (mut j, bin) = common::split(&common::default_glb());
    let normal = j["meshes"][0]["primitives"][0]["attributes"]["NORMAL"]
        .as_u64()
        .unwrap() as usize;
    let n = j["accessors"][normal]["count"].as_u64().unwrap();
    j["accessors"][normal]["count"] = json!(n - 1);
    let e = err(&common::join(&j, &bin));
    assert!(
        e.contains("NORMAL has") && e.contains("elements but POSITION has"),
        "{e}"
    );
    // Past the end of the view.
    let (mut j, bin) = common::split(&common::default_glb());
    let pos = j["meshes"][0]["primitives"][0]["attributes"]["POSITION"]
        .as_u64()
        .unwrap() as usize;
    j["accessors"][pos]["count"] = json!(n + 10);
    let e = err(&common::join(&j, &bin));
    assert!(e.contains("do not fit in bufferView"), "{e}");
}

#[test]
fn out_of_range_indices() {
    let (j, mut bin) = common::split(&common::default_glb());
    let idx = j["meshes"][0]["primitives"][0]["indices"].as_u64().unwrap() as usize;
    let view = j["accessors"][idx]["bufferView"].as_u64().unwrap() as usize;
    let at = j["bufferViews"][view]["byteOffset"].as_u64().unwrap() as usize;
    bin[at..at + 4].copy_from_slice(&1_000_000u32.to_le_bytes());
    let e = err(&common::join(&j, &bin));
    assert!(e.contains("index 1000000 out of range"), "{e}");
    // An object index out of range.
    let (mut j, bin) = common::split(&common::default_glb());
    j["nodes"][0]["mesh"] = json!(42);
    let e = err(&common::join(&j, &bin));
    assert!(e.contains("node 0 refers to mesh 42"), "{e}");
    // A joint index past the skin.
    let (j, mut bin) = common::split(&common::default_glb());
    let joints = j["meshes"][0]["primitives"][0]["attributes"]["JOINTS_0"]
        .as_u64()
        .unwrap() as usize;
    let view = j["accessors"][joints]["bufferView"].as_u64().unwrap() as usize;
    let at = j["bufferViews"][view]["byteOffset"].as_u64().unwrap() as usize;
    bin[at..at + 2].copy_from_slice(&500u16.to_le_bytes());
    let e = err(&common::join(&j, &bin));
    assert!(e.contains("JOINTS_0 value 500 out of range"), "{e}");
}

#[test]
fn huge_declared_sizes() {
    let (mut j, bin) = common::split(&common::default_glb());
    let pos = j["meshes"][0]["primitives"][0]["attributes"]["POSITION"]
        .as_u64()
        .unwrap() as usize;
    j["accessors"][pos]["count"] = json!(4_000_000_000u64);
    let e = err(&common::join(&j, &bin));
    assert!(e.contains("too large"), "{e}");
    let (mut j, bin) = common::split(&common::default_glb());
    j["buffers"][0]["byteLength"] = json!(1u64 << 50);
    let e = err(&common::join(&j, &bin));
    assert!(e.contains("too large"), "{e}");
    // GLB header declaring more than the file.
    let mut glb = common::default_glb();
    glb[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
    assert!(err(&glb).contains("truncated"));
    // A chunk declaring more than the file.
    let mut glb = common::default_glb();
    glb[12..16].copy_from_slice(&(u32::MAX - 7).to_le_bytes());
    assert!(err(&glb).contains("past the end"));
}

#[test]
fn non_humanoid_skeletons() {
    let gltf = br#"{"asset":{"version":"2.0"},"nodes":[
        {"name":"Bone","children":[1]},{"name":"Bone.001","translation":[0,1,0],"children":[2]},
        {"name":"Bone.002","translation":[0,1,0]}],"scenes":[{"nodes":[0]}]}"#;
    let e = err(gltf);
    assert!(
        e.starts_with("not a humanoid") && e.contains("l_hip"),
        "{e}"
    );
    // Without the requirement it loads, with a warning.
    let a = load_avatar(
        gltf,
        &LoadOptions {
            require_humanoid: false,
            ..Default::default()
        },
    )
    .unwrap();
    assert!(
        a.warnings
            .iter()
            .any(|w| w.contains("not a complete humanoid"))
    );
    assert!(matches!(
        a.skeleton(&Default::default()),
        Err(AssetError::NotHumanoid { .. })
    ));
}

#[test]
fn gltf_with_data_uri_buffers() {
    use base64::Engine as _;
    let (mut j, bin) = common::split(&common::default_glb());
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bin)
    );
    j["buffers"][0]["uri"] = json!(uri);
    let text = serde_json::to_vec(&j).unwrap();
    let a = load(&text).unwrap();
    assert_eq!(a.format, stance_asset::SourceFormat::Gltf);
    assert!(a.vertex_count() > 1000);
    j["buffers"][0]["uri"] = json!("data:application/octet-stream;base64,!!!");
    let e = err(&serde_json::to_vec(&j).unwrap());
    assert!(e.contains("bad base64"), "{e}");
    j["buffers"][0]["uri"] = json!("missing.bin");
    let e = err(&serde_json::to_vec(&j).unwrap());
    assert!(e.contains("missing.bin"), "{e}");
}

#[cfg(not(target_arch = "wasm32"))]
mod fuzz {
    use proptest::prelude::*;

    use super::*;

    fn small_glb() -> Vec<u8> {
        common::default_glb()
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

        /// Random byte mutations of a valid GLB: an avatar or an error, never a panic.
        #[test]
        fn mutated_glb_never_panics(edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..12)) {
            let mut glb = small_glb();
            // Most edits land in the JSON chunk (the first ~40 kB) where they matter most.
            let json_len = u32::from_le_bytes([glb[12], glb[13], glb[14], glb[15]]) as usize;
            for (k, (at, byte)) in edits.iter().enumerate() {
                let span = if k % 2 == 0 { 20 + json_len } else { glb.len() };
                let i = at.index(span);
                glb[i] = *byte;
            }
            let _ = load(&glb);
        }

        /// Truncations anywhere.
        #[test]
        fn truncated_never_panics(at in any::<prop::sample::Index>()) {
            let glb = small_glb();
            let cut = at.index(glb.len());
            prop_assert!(load(&glb[..cut]).is_err());
        }
    }
}
