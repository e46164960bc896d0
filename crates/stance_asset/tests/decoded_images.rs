//! Images decoded by the caller (the browser decodes textures off the main thread): used as
//! given, checked against the limits, and set aside for the file's own bytes when wrong.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use crate::common;

use serde_json::json;
use stance_asset::{
    AssetError, AvatarTransfer, DecodedImage, HostImages, Limits, LoadOptions,
    load_avatar_with_images,
};

/// The default avatar as a `.gltf` whose first material shows image 0: a 2x2 red PNG in a
/// data URI, or bytes no decoder reads.
fn gltf_with_image(png: bool) -> Vec<u8> {
    let (mut j, bin) = common::split(&common::default_glb());
    use base64::Engine as _;
    let encode = |bytes: &[u8]| base64::engine::general_purpose::STANDARD.encode(bytes);
    j["buffers"] = json!([{
        "byteLength": bin.len(),
        "uri": format!("data:application/octet-stream;base64,{}", encode(&bin)),
    }]);
    let image = if png {
        let mut bytes = Vec::new();
        image::RgbaImage::from_pixel(2, 2, image::Rgba([255, 0, 0, 255]))
            .write_to(
                &mut std::io::Cursor::new(&mut bytes),
                image::ImageFormat::Png,
            )
            .unwrap();
        bytes
    } else {
        b"not an image".to_vec()
    };
    j["images"] = json!([{"uri": format!("data:image/png;base64,{}", encode(&image))}]);
    j["textures"] = json!([{"source": 0}]);
    j["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
    serde_json::to_vec(&j).unwrap()
}

fn blue(width: u32, height: u32) -> DecodedImage {
    DecodedImage {
        index: 0,
        width,
        height,
        rgba8: [0, 0, 255, 255].repeat((width * height) as usize),
    }
}

/// The default options with textures of at most `side` pixels a side.
fn side_limit(side: u32) -> LoadOptions {
    LoadOptions {
        limits: Limits {
            max_texture_side: side,
            ..Limits::default()
        },
        ..LoadOptions::default()
    }
}

fn load(
    file: &[u8],
    decoded: &[DecodedImage],
    options: &LoadOptions,
) -> Result<stance_asset::Avatar, AssetError> {
    let images = HostImages {
        decoded: decoded.to_vec(),
        ..Default::default()
    };
    load_avatar_with_images(file, options, &mut |_| None, images)
}

#[test]
fn a_decoded_image_is_used_as_given_in_place_of_the_files_bytes() {
    // The file's own bytes cannot be decoded: the texture can only come from the caller.
    let avatar = load(
        &gltf_with_image(false),
        &[blue(3, 2)],
        &LoadOptions::default(),
    )
    .unwrap();
    let texture = &avatar.textures[0];
    assert_eq!((texture.width, texture.height), (3, 2));
    assert_eq!(&texture.rgba8[..4], &[0, 0, 255, 255]);
    assert!(
        avatar.warnings.iter().all(|w| !w.contains("image 0")),
        "{:?}",
        avatar.warnings
    );
    // Without it the same file's texture is the white placeholder, with the decoder's reason.
    let alone = load(&gltf_with_image(false), &[], &LoadOptions::default()).unwrap();
    assert_eq!(&alone.textures[0].rgba8[..4], &[255, 255, 255, 255]);
    assert!(alone.warnings.iter().any(|w| w.contains("image 0")));
}

#[test]
fn decoded_pixels_of_the_wrong_size_are_set_aside_and_the_file_decoded() {
    let mut short = blue(2, 2);
    short.rgba8.truncate(7);
    let avatar = load(&gltf_with_image(true), &[short], &LoadOptions::default()).unwrap();
    let texture = &avatar.textures[0];
    assert_eq!((texture.width, texture.height), (2, 2));
    assert_eq!(&texture.rgba8[..4], &[255, 0, 0, 255], "the file's red PNG");
    assert!(
        avatar
            .warnings
            .iter()
            .any(|w| w.contains("image 0") && w.contains("do not fit")),
        "{:?}",
        avatar.warnings
    );
}

#[test]
fn a_decoded_image_beyond_the_side_limit_is_refused_by_name() {
    let error = load(&gltf_with_image(true), &[blue(8, 1)], &side_limit(4)).unwrap_err();
    assert!(error.to_string().contains("image 0"), "{error}");
}

fn load_following(file: &[u8], options: &LoadOptions) -> Result<stance_asset::Avatar, AssetError> {
    let images = HostImages {
        to_follow: vec![0],
        ..Default::default()
    };
    load_avatar_with_images(file, options, &mut |_| None, images)
}

#[test]
fn an_image_to_follow_comes_with_its_size_and_no_pixels_and_fills_to_the_decoded_avatar() {
    // The oracle: the same file with its image decoded here.
    let file = gltf_with_image(true);
    let decoded = load(&file, &[], &LoadOptions::default()).unwrap();
    let followed = load_following(&file, &LoadOptions::default()).unwrap();
    let (texture, oracle) = (&followed.textures[0], &decoded.textures[0]);
    assert_eq!(
        (texture.width, texture.height),
        (2, 2),
        "the PNG header's size"
    );
    assert!(texture.rgba8.is_empty(), "no pixels yet");
    assert_eq!((texture.image, oracle.image), (Some(0), Some(0)));
    // Handed over without its pixels, the avatar is refused by name...
    let transfer = AvatarTransfer::new(followed).unwrap();
    let slot = transfer.pixels.iter().position(Vec::is_empty).unwrap();
    let error = transfer.clone().into_avatar().unwrap_err();
    assert!(
        error.to_string().contains("is 2x2 but has 0 bytes"),
        "{error}"
    );
    // ...and with the pixels the browser decoded, it is the avatar decoded here.
    let mut filled = transfer;
    filled.pixels[slot] = oracle.rgba8.to_vec();
    assert_eq!(filled.into_avatar().unwrap(), decoded);
}

#[test]
fn an_image_to_follow_is_checked_against_the_limits_as_a_decoded_one() {
    let small = side_limit(1);
    // Over the side limit, or a header no decoder reads: drawn white with the reason, as
    // when the importer decodes the image itself; no pixels are left to follow.
    for (file, options) in [
        (gltf_with_image(true), &small),
        (gltf_with_image(false), &LoadOptions::default()),
    ] {
        let followed = load_following(&file, options).expect("imported");
        let decoded = load(&file, &[], options).expect("imported");
        let texture = &followed.textures[0];
        assert_eq!((texture.width, texture.height), (1, 1));
        assert_eq!(&texture.rgba8[..], &[255; 4]);
        assert_eq!(followed.warnings, decoded.warnings);
        assert!(
            followed.warnings.iter().any(|w| w.contains("image 0")),
            "{:?}",
            followed.warnings
        );
    }
}
