//! Materials, textures and frames: KHR_materials_unlit, PNG and JPEG base colours, and a
//! Z-up centimetre model facing -X normalised to the H-Anim frame.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use crate::common;

use glam::DVec3;
use serde_json::json;
use stance_asset::{LoadOptions, export_glb, load_avatar};

fn encoded(format: image::ImageFormat) -> Vec<u8> {
    let img = image::RgbaImage::from_fn(8, 4, |x, y| {
        image::Rgba([x as u8 * 30, y as u8 * 60, 200, 255])
    });
    let mut out = std::io::Cursor::new(Vec::new());
    image::DynamicImage::ImageRgba8(img)
        .to_rgb8()
        .write_to(&mut out, format)
        .unwrap();
    out.into_inner()
}

#[test]
fn unlit_and_png_jpeg_textures() {
    let (mut j, mut bin) = common::split(&common::default_glb());
    let mut add_image = |bytes: Vec<u8>, mime: &str, j: &mut serde_json::Value| {
        while bin.len() % 4 != 0 {
            bin.push(0);
        }
        let views = j["bufferViews"].as_array_mut().unwrap();
        views.push(json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len()}));
        let view = views.len() - 1;
        bin.extend_from_slice(&bytes);
        let images = j
            .as_object_mut()
            .unwrap()
            .entry("images")
            .or_insert(json!([]));
        images
            .as_array_mut()
            .unwrap()
            .push(json!({"bufferView": view, "mimeType": mime}));
        let image = images.as_array().unwrap().len() - 1;
        let textures = j
            .as_object_mut()
            .unwrap()
            .entry("textures")
            .or_insert(json!([]));
        textures
            .as_array_mut()
            .unwrap()
            .push(json!({"source": image}));
        textures.as_array().unwrap().len() - 1
    };
    let png = add_image(encoded(image::ImageFormat::Png), "image/png", &mut j);
    let jpeg = add_image(encoded(image::ImageFormat::Jpeg), "image/jpeg", &mut j);
    j["buffers"][0]["byteLength"] = json!(bin.len() + (4 - bin.len() % 4) % 4);
    j["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": png});
    j["materials"][0]["extensions"] = json!({"KHR_materials_unlit": {}});
    j["materials"][1]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": jpeg});
    j["extensionsUsed"] = json!(["KHR_materials_unlit"]);
    let avatar = load_avatar(&common::join(&j, &bin), &LoadOptions::default()).unwrap();
    assert!(avatar.materials[0].unlit);
    assert!(!avatar.materials[1].unlit);
    let t = &avatar.textures[avatar.materials[0].base_color_texture.unwrap()];
    assert_eq!((t.width, t.height, t.rgba8.len()), (8, 4, 128));
    assert_eq!(&t.rgba8[4..8], &[30, 0, 200, 255]);
    let t = &avatar.textures[avatar.materials[1].base_color_texture.unwrap()];
    assert_eq!((t.width, t.height), (8, 4));
    assert!(
        (t.rgba8[2] as i32 - 200).abs() < 20,
        "JPEG blue {}",
        t.rgba8[2]
    );
    // Written back: unlit kept, textures as PNG.
    let again = load_avatar(&export_glb(&avatar).unwrap(), &LoadOptions::default()).unwrap();
    assert!(again.materials[0].unlit);
    assert_eq!(again.textures.len(), 2);
    assert!(again.extensions.iter().any(|e| e == "KHR_materials_unlit"));
}

#[test]
fn z_up_centimetres_facing_minus_x_is_normalised() {
    let reference = load_avatar(&common::default_glb(), &LoadOptions::default()).unwrap();
    let expected = reference.hanim_rest_positions();
    let avatar = load_avatar(
        &common::z_up_centimetres_facing_minus_x(&common::default_glb()),
        &LoadOptions::default(),
    )
    .unwrap();
    let got = avatar.hanim_rest_positions();
    for (h, e) in expected.iter().enumerate() {
        assert!((got[h] - *e).length() < 1e-4, "node {h}: {} vs {e}", got[h]);
    }
    let head = got[avatar.mapping.source_of("skullbase").unwrap()];
    assert!(
        (head - DVec3::new(0.0044, 1.6209, 0.0236)).length() < 0.05,
        "{head}"
    );
}

/// A humanoid exported at 2.5 times human size (no standard unit makes it a person) is
/// scaled to the H-Anim default height, with a warning; the standard units load silently.
#[test]
fn arbitrary_scale_is_brought_to_human_height() {
    let reference = load_avatar(&common::default_glb(), &LoadOptions::default()).unwrap();
    assert!(
        !reference
            .warnings
            .iter()
            .any(|w| w.starts_with("model scale")),
        "{:?}",
        reference.warnings
    );
    let expected = reference.hanim_rest_positions();
    for (factor, warned) in [(2.5, true), (0.3, true), (100.0, false), (0.6, false)] {
        let (mut j, bin) = common::split(&common::default_glb());
        let old_roots = j["scenes"][0]["nodes"].clone();
        let nodes = j["nodes"].as_array_mut().unwrap();
        nodes.push(json!({"name": "Scaled", "children": old_roots,
            "scale": [factor, factor, factor]}));
        let root = nodes.len() - 1;
        j["scenes"][0]["nodes"] = json!([root]);
        let avatar = load_avatar(&common::join(&j, &bin), &LoadOptions::default()).unwrap();
        let warning = avatar
            .warnings
            .iter()
            .find(|w| w.starts_with("model scale"));
        assert_eq!(
            warning.is_some(),
            warned,
            "x{factor}: {:?}",
            avatar.warnings
        );
        let got = avatar.hanim_rest_positions();
        let head = got[avatar.mapping.source_of("skullbase").unwrap()].y;
        if warned {
            // Scaled to the H-Anim default body: skull base 1.5529 m from the ankles, the
            // same shape as the unscaled file (a uniform scale about the floor origin).
            let rise = |p: &[DVec3], a: &stance_asset::Avatar| {
                let at = |h: &str| p[a.mapping.source_of(h).unwrap()];
                (at("skullbase") - (at("l_talocrural") + at("r_talocrural")) / 2.0).length()
            };
            let got_rise = rise(&got, &avatar);
            assert!(
                (got_rise - (1.6209 - 0.068)).abs() < 1e-6,
                "x{factor}: {got_rise}"
            );
            let k = got_rise / rise(&expected, &reference);
            for (h, e) in expected.iter().enumerate() {
                assert!(
                    (got[h] - *e * k).length() < 1e-4,
                    "x{factor} node {h}: {} vs {}",
                    got[h],
                    *e * k
                );
            }
            // The warning gives the scale applied to the file's units.
            let said: f64 = warning
                .unwrap()
                .split("scaled by ")
                .nth(1)
                .and_then(|r| r.split_whitespace().next())
                .unwrap()
                .parse()
                .unwrap();
            assert!(
                (said - k / factor).abs() < 1e-5,
                "x{factor}: {said} vs {}",
                k / factor
            );
        } else {
            // A standard unit (cm) or a small person (0.6 x a 1.7 m body) keeps its size.
            let want = 1.6209 * if factor == 100.0 { 1.0 } else { factor };
            assert!(
                (head - want).abs() < 0.05,
                "x{factor}: skull base at {head}"
            );
        }
    }
}

/// A glTF whose first material's base colour is `bytes` (one image, one texture).
fn with_texture(bytes: &[u8], mime: &str) -> Vec<u8> {
    let (mut j, mut bin) = common::split(&common::default_glb());
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let views = j["bufferViews"].as_array_mut().unwrap();
    views.push(json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len()}));
    let view = views.len() - 1;
    bin.extend_from_slice(bytes);
    j["images"] = json!([{"bufferView": view, "mimeType": mime}]);
    j["textures"] = json!([{"source": 0}]);
    j["buffers"][0]["byteLength"] = json!(bin.len() + (4 - bin.len() % 4) % 4);
    j["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
    common::join(&j, &bin)
}

/// A 2 x 1 PNG of `color` and `depth` with `data` as its rows (and `palette`, `trns` chunks).
fn png_of(
    color: png::ColorType,
    depth: png::BitDepth,
    data: &[u8],
    palette: Option<&[u8]>,
    trns: Option<&[u8]>,
) -> Vec<u8> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, 2, 1);
    encoder.set_color(color);
    encoder.set_depth(depth);
    if let Some(palette) = palette {
        encoder.set_palette(palette.to_vec());
    }
    if let Some(trns) = trns {
        encoder.set_trns(trns.to_vec());
    }
    let mut writer = encoder.write_header().unwrap();
    writer.write_image_data(data).unwrap();
    writer.finish().unwrap();
    out
}

/// Every PNG colour type a texture comes in is read as the RGBA the file means, computed by
/// hand: grey expanded to three channels, a palette with its transparency chunk, 16-bit
/// channels to their high byte, and opaque alpha where the file has none. Catches a decoder
/// that hands grey or palette indices through as if they were RGBA (textures smeared or
/// transparent), or drops the tRNS chunk (cut-out hair drawn opaque).
#[test]
fn png_colour_types_are_read_as_rgba() {
    use png::{BitDepth, ColorType};
    let cases: [(&str, Vec<u8>, [u8; 8]); 5] = [
        (
            "grey",
            png_of(
                ColorType::Grayscale,
                BitDepth::Eight,
                &[10, 250],
                None,
                None,
            ),
            [10, 10, 10, 255, 250, 250, 250, 255],
        ),
        (
            "grey and alpha",
            png_of(
                ColorType::GrayscaleAlpha,
                BitDepth::Eight,
                &[10, 128, 250, 0],
                None,
                None,
            ),
            [10, 10, 10, 128, 250, 250, 250, 0],
        ),
        (
            "palette with transparency",
            png_of(
                ColorType::Indexed,
                BitDepth::Eight,
                &[1, 0],
                Some(&[255, 0, 0, 0, 0, 255]),
                Some(&[0, 200]),
            ),
            [0, 0, 255, 200, 255, 0, 0, 0],
        ),
        (
            "16-bit RGBA",
            png_of(
                ColorType::Rgba,
                BitDepth::Sixteen,
                &[
                    0xAB, 0xCD, 0x12, 0x34, 0xFF, 0xFF, 0x80, 0x00, 0, 0, 0, 0, 0, 0, 0x40, 0x01,
                ],
                None,
                None,
            ),
            [0xAB, 0x12, 0xFF, 0x80, 0, 0, 0, 0x40],
        ),
        (
            "RGB",
            png_of(
                ColorType::Rgb,
                BitDepth::Eight,
                &[1, 2, 3, 4, 5, 6],
                None,
                None,
            ),
            [1, 2, 3, 255, 4, 5, 6, 255],
        ),
    ];
    for (name, bytes, expected) in cases {
        let avatar = load_avatar(&with_texture(&bytes, "image/png"), &LoadOptions::default())
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let texture = &avatar.textures[avatar.materials[0].base_color_texture.unwrap()];
        assert_eq!((texture.width, texture.height), (2, 1), "{name}");
        assert_eq!(&texture.rgba8[..], &expected, "{name}");
    }
}

/// A PNG whose header reads and whose pixel data is cut short, and bytes that are no image at
/// all: the texture is drawn white and a warning names the image and what is wrong; the
/// avatar still loads. Catches a decoder error that fails the whole import, or a warning that
/// does not say which image.
#[test]
fn a_broken_or_unknown_image_is_named_and_drawn_white() {
    let whole = png_of(
        png::ColorType::Rgb,
        png::BitDepth::Eight,
        &[1, 2, 3, 4, 5, 6],
        None,
        None,
    );
    let truncated = &whole[..whole.len() - 20];
    for (name, bytes, says) in [
        ("truncated PNG", truncated, "PNG"),
        (
            "not an image",
            &b"GIF89a not a texture"[..],
            "not a PNG, JPEG or WebP",
        ),
    ] {
        let avatar = load_avatar(&with_texture(bytes, "image/png"), &LoadOptions::default())
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let texture = &avatar.textures[avatar.materials[0].base_color_texture.unwrap()];
        assert_eq!(&texture.rgba8[..], &[255; 4], "{name}");
        assert!(
            avatar
                .warnings
                .iter()
                .any(|w| w.contains("image 0") && w.contains(says)),
            "{name}: {:?}",
            avatar.warnings
        );
    }
}
