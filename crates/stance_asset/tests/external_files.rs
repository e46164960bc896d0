//! A `.gltf` with its buffer and image in separate files: found through the resolver by the
//! URIs the file uses (percent-encoded, in a folder), and a missing one named.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use crate::common;

use serde_json::json;
use stance_asset::{LoadOptions, find_resource, load_avatar_with};

/// The default avatar as `avatar.gltf` + `body data.bin` + `tex/skin.png` (a 2x2 red image as
/// the first material's base colour).
fn split_files() -> (Vec<u8>, Vec<(String, Vec<u8>)>) {
    let (mut j, bin) = common::split(&common::default_glb());
    j["buffers"] = json!([{"byteLength": bin.len(), "uri": "body%20data.bin"}]);
    j["images"] = json!([{"uri": "./tex/skin.png"}]);
    j["textures"] = json!([{"source": 0}]);
    j["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
    let mut png = Vec::new();
    image::RgbaImage::from_pixel(2, 2, image::Rgba([255, 0, 0, 255]))
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    let files = vec![
        ("avatar/body data.bin".to_owned(), bin),
        ("avatar/tex/skin.png".to_owned(), png),
    ];
    (serde_json::to_vec(&j).unwrap(), files)
}

fn load(gltf: &[u8], files: &[(String, Vec<u8>)]) -> Result<stance_asset::Avatar, String> {
    let mut resolve = |uri: &str| find_resource(files, uri).map(<[u8]>::to_vec);
    load_avatar_with(gltf, &LoadOptions::default(), &mut resolve).map_err(|e| e.to_string())
}

#[test]
fn a_gltf_finds_its_bin_and_image_among_the_files_given() {
    let (gltf, files) = split_files();
    let avatar = load(&gltf, &files).unwrap();
    assert!(
        avatar.warnings.iter().all(|w| !w.contains("missing")),
        "{:?}",
        avatar.warnings
    );
    let texture = &avatar.textures[0];
    assert_eq!((texture.width, texture.height), (2, 2));
    assert_eq!(&texture.rgba8[..4], &[255, 0, 0, 255]);
    assert!(avatar.meshes.iter().any(|m| !m.primitives.is_empty()));
    // The same file as a GLB: the same meshes.
    let glb = stance_asset::load_avatar(&common::default_glb(), &LoadOptions::default()).unwrap();
    assert_eq!(avatar.meshes, glb.meshes);
}

#[test]
fn a_missing_file_is_named() {
    let (gltf, files) = split_files();
    // Without its image: drawn white, the image named.
    let avatar = load(&gltf, &files[..1]).unwrap();
    assert!(
        avatar
            .warnings
            .iter()
            .any(|w| w.contains("./tex/skin.png") && w.contains("missing")),
        "{:?}",
        avatar.warnings
    );
    // Without its buffer: refused, the buffer named.
    let error = load(&gltf, &files[1..]).unwrap_err();
    assert!(
        error.contains("body%20data.bin") && error.contains("missing"),
        "{error}"
    );
}
