//! A scene's `files`: the mesh props' files a saved document carries (each once, embedded
//! with the clip's codec), checked on reading (a damaged or changed one refused naming
//! `files[i]` and the file), never carried by a link; an entry no prop names is ignored.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use serde_json::Value;
use stance_document::scene::MAX_PROP_FILE_BYTES;
use stance_document::{FileReference, Prop, PropShape, Scene, content_hash, link};
#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

/// The Khronos sample box (a `.gltf` with its buffer embedded as a data URI), 4,160 bytes.
const BOX_GLTF: &[u8] = include_bytes!("../../stance_asset/tests/fixtures/Box.gltf");

fn mesh_prop(name: &str, file: &str, x: f64) -> Prop {
    Prop::new(
        name.into(),
        PropShape::Mesh {
            file: file.into(),
            size: [1.0, 1.0, 1.0],
        },
        [x, 0.5, 1.0],
    )
}

/// Two boxes from `Box.gltf` (one file), a lamp from `lamp.glb` and a ball, with both files.
fn furnished() -> Scene {
    Scene {
        props: vec![
            mesh_prop("Box", "Box.gltf", 0.0),
            mesh_prop("Box 2", "Box.gltf", 1.5),
            mesh_prop("Lamp", "lamp.glb", -1.5),
            Prop::new(
                "Ball".into(),
                PropShape::Sphere { radius: 0.1 },
                [0.0, 1.0, 0.0],
            ),
        ],
        files: vec![
            FileReference::embed("Box.gltf", BOX_GLTF),
            FileReference::embed("lamp.glb", &lamp_bytes()),
        ],
        ..Scene::default()
    }
}

/// A stand-in for a second file: the document crate does not read meshes.
fn lamp_bytes() -> Vec<u8> {
    (0..3000u32).flat_map(|i| (i % 251).to_le_bytes()).collect()
}

fn json(scene: &Scene) -> (String, Value) {
    let text = scene.to_json(false);
    let value = serde_json::from_str(&text).unwrap();
    (text, value)
}

// Catches prop files that are not written (a saved scene reopened with boxes), written once
// per prop rather than per file, or not read back byte for byte.
#[test]
fn two_mesh_props_sharing_one_file_round_trip_with_it_listed_once() {
    let mut scene = furnished();
    scene.props.remove(2);
    scene.files.truncate(1);
    let (text, value) = json(&scene);
    let files = value["files"].as_array().expect("a files array");
    assert_eq!(files.len(), 1, "one entry for the two props: {files:?}");
    assert_eq!(files[0]["file"], "Box.gltf");
    assert_eq!(files[0]["size"], BOX_GLTF.len());
    assert_eq!(
        files[0]["hash"],
        format!("crc32:{:08x}", content_hash(BOX_GLTF))
    );
    let deflate = files[0]["deflate"].as_str().unwrap();
    println!(
        "[scene_files] Box.gltf: {} bytes, hash {}, embedded in {} characters ({}...)",
        BOX_GLTF.len(),
        files[0]["hash"],
        deflate.len(),
        &deflate[..24]
    );
    let back = Scene::from_json(&text).unwrap();
    assert_eq!(back, scene);
    let embedded = back.files[0].embedded.as_ref().unwrap();
    assert_eq!(embedded.bytes(), BOX_GLTF);
    // Written again, the same text (the compressed form read is kept, not made again).
    assert_eq!(back.to_json(false), text);
}

// Catches a damaged or changed embedded prop file that opened as garbage, or whose error
// named neither the entry nor the file.
#[test]
fn a_damaged_deflate_or_a_wrong_hash_is_refused_naming_files_i_and_the_file() {
    let (text, value) = json(&furnished());
    let data = value["files"][1]["deflate"].as_str().unwrap().to_owned();
    let cut = &data[..(data.len() / 2) & !3];
    let mut flipped = data.clone().into_bytes();
    let middle = flipped.len() / 2;
    flipped[middle] = if flipped[middle] == b'A' { b'B' } else { b'A' };
    let flipped = String::from_utf8(flipped).unwrap();
    let hash = format!("crc32:{:08x}", content_hash(&lamp_bytes()));
    let cases = [
        ("cut", text.replace(&data, cut), "cut"),
        ("flipped", text.replace(&data, &flipped), "damaged"),
        ("not base64", text.replace(&data, "%%%"), "not base64"),
        (
            "another hash",
            text.replace(&hash, "crc32:01234567"),
            "content hash does not match",
        ),
    ];
    for (what, damaged, words) in cases {
        let error = Scene::from_json(&damaged).unwrap_err().to_string();
        assert!(error.starts_with("files[1].deflate: "), "{what}: {error}");
        for words in [words, "lamp.glb", "prop file"] {
            assert!(error.contains(words), "{what}: {words}: {error}");
        }
    }
    let malformed = text.replace(&hash, "sha1:00");
    let error = Scene::from_json(&malformed).unwrap_err().to_string();
    assert!(error.starts_with("files[1].hash"), "{error}");
}

// Catches a link that carried the files (far too long for a URL) or a link made differently
// for a scene with files.
#[test]
fn a_link_from_the_same_scene_carries_no_file_bytes() {
    let scene = furnished();
    let (text, _) = json(&scene);
    assert!(text.contains("\"deflate\""), "the document carries them");
    let fragment = link::encode_scene(&scene);
    let without = Scene {
        files: Vec::new(),
        ..scene.clone()
    };
    assert_eq!(fragment, link::encode_scene(&without));
    let back = link::decode_scene(&fragment).unwrap();
    assert!(back.files.is_empty());
    assert_eq!(back.props[1].shape.file(), Some("Box.gltf"));
    assert!(
        fragment.len() * 4 < text.len(),
        "{} characters against the document's {}",
        fragment.len(),
        text.len()
    );
}

// Catches an entry no prop names that stopped the scene from opening (or was kept), and a
// mesh prop whose file is not listed that was refused.
#[test]
fn a_file_no_prop_names_is_ignored_and_an_unlisted_file_leaves_its_prop_named() {
    let scene = furnished();
    let (text, mut value) = json(&scene);
    // The lamp's entry renamed: no prop names `table.glb` (its data need not even be read),
    // and the lamp's file is no longer listed.
    value["files"][1]["file"] = Value::from("table.glb");
    value["files"][1]["deflate"] = Value::from("%%%");
    let back = Scene::from_json(&value.to_string()).unwrap();
    assert_eq!(back.files.len(), 1);
    assert_eq!(back.files[0].name, "Box.gltf");
    assert_eq!(back.props, scene.props);
    // More entries than props, a file listed twice, an entry that carries no file, a file
    // too large.
    let mut more = value.clone();
    let extra: Vec<Value> = (0..5).map(|_| value["files"][0].clone()).collect();
    more["files"] = Value::from(extra);
    let error = Scene::from_json(&more.to_string()).unwrap_err().to_string();
    assert!(error.starts_with("files: 5 files for 4 props"), "{error}");
    let mut twice: Value = serde_json::from_str(&text).unwrap();
    twice["files"][1] = twice["files"][0].clone();
    let error = Scene::from_json(&twice.to_string())
        .unwrap_err()
        .to_string();
    assert!(
        error.starts_with("files[1].file: `Box.gltf` is listed twice"),
        "{error}"
    );
    let mut named_only: Value = serde_json::from_str(&text).unwrap();
    named_only["files"][0]
        .as_object_mut()
        .unwrap()
        .remove("deflate");
    let error = Scene::from_json(&named_only.to_string())
        .unwrap_err()
        .to_string();
    assert!(error.starts_with("files[0].deflate: missing"), "{error}");
    // A file past a prop file's limit (64 MiB), refused by its entry.
    let mut huge: Value = serde_json::from_str(&text).unwrap();
    huge["files"][0]["size"] = Value::from(MAX_PROP_FILE_BYTES + 1);
    let error = Scene::from_json(&huge.to_string()).unwrap_err().to_string();
    assert!(
        error.starts_with("files[0].size: expected an integer"),
        "{error}"
    );
}
