//! Small hostile files that would need far more memory than their size if the importer
//! copied or re-decoded shared data: each either loads within a tight decoded-bytes budget
//! or fails with an error naming the limit.
//!
//! In its own test binary, its tests one at a time ([`SERIAL`]), so that the peak-RSS check
//! is not disturbed by other tests.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use crate::common;

use serde_json::{Value, json};
use stance_asset::{AssetError, Limits, LoadOptions, load_avatar};

const MIB: u64 = 1 << 20;

/// Held by every test of this file: they run one after the other.
static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn serial() -> std::sync::MutexGuard<'static, ()> {
    SERIAL
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

fn options(max_decoded_bytes: u64) -> LoadOptions {
    LoadOptions {
        limits: Limits {
            max_decoded_bytes,
            ..Limits::default()
        },
        require_humanoid: false,
        decode_textures: true,
    }
}

/// `primitives` primitives, each reading a 1-element VEC3 accessor through its own buffer
/// view that spans the whole `buffer_bytes` buffer.
fn views_over_one_buffer(primitives: usize, buffer_bytes: usize) -> Vec<u8> {
    let views: Vec<Value> = (0..primitives)
        .map(|_| json!({"buffer": 0, "byteOffset": 0, "byteLength": buffer_bytes}))
        .collect();
    let accessors: Vec<Value> = (0..primitives)
        .map(|i| json!({"bufferView": i, "componentType": 5126, "count": 1, "type": "VEC3"}))
        .collect();
    let prims: Vec<Value> = (0..primitives)
        .map(|i| json!({"attributes": {"POSITION": i}}))
        .collect();
    let gltf = json!({
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": buffer_bytes}],
        "bufferViews": views,
        "accessors": accessors,
        "meshes": [{"primitives": prims}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
    });
    common::join(&gltf, &vec![0u8; buffer_bytes])
}

/// 4 000 views over one 4 MiB buffer: copying each view would allocate 16 GB from a
/// 4.6 MB file. Views are borrowed, so the file loads within a 16 MiB budget and the peak
/// memory grows by little more than the file.
#[test]
fn many_views_over_one_buffer_are_not_copied() {
    let _serial = serial();
    let glb = views_over_one_buffer(4_000, 4 << 20);
    assert!(glb.len() < 6 << 20, "{} bytes", glb.len());
    // Reset the peak (VmHWM) to the current RSS; earlier tests raised it.
    #[cfg(target_os = "linux")]
    let _ = std::fs::write("/proc/self/clear_refs", "5");
    #[cfg(target_os = "linux")]
    let before = common::status_kb("VmRSS:");
    let avatar = load_avatar(&glb, &options(16 * MIB)).unwrap();
    assert_eq!(avatar.meshes[0].primitives.len(), 4_000);
    #[cfg(target_os = "linux")]
    {
        let grown_mb = common::status_kb("VmHWM:").saturating_sub(before) / 1024;
        eprintln!("4 000 views over a 4 MiB buffer: peak RSS +{grown_mb} MB");
        assert!(grown_mb < 256, "peak RSS grew by {grown_mb} MB");
    }
}

/// Every primitive reading the same large accessor is charged: a 3 MB file cannot make
/// the importer build thousands of 256 Ki-vertex primitives.
#[test]
fn many_primitives_reading_one_large_accessor_hit_the_limit() {
    let _serial = serial();
    let vertices = 256 * 1024;
    let bytes = vertices * 12;
    let prims: Vec<Value> = (0..4_000)
        .map(|_| json!({"attributes": {"POSITION": 0}}))
        .collect();
    let gltf = json!({
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": bytes}],
        "bufferViews": [{"buffer": 0, "byteLength": bytes}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": vertices, "type": "VEC3"}],
        "meshes": [{"primitives": prims}],
        "nodes": [{"mesh": 0}],
    });
    let glb = common::join(&gltf, &vec![0u8; bytes]);
    match load_avatar(&glb, &options(64 * MIB)) {
        Err(e @ AssetError::TooLarge { limit, .. }) => {
            assert_eq!(limit, 64 * MIB);
            let msg = e.to_string();
            assert!(
                msg.starts_with("decoded data (at ") && msg.contains("limit 67108864"),
                "{msg}"
            );
        }
        other => panic!(
            "expected the decoded-bytes limit, got {:?}",
            other.map(|_| ())
        ),
    }
}

/// 300 textures (one material each) sharing one 2048x2048 image: each texture holds its
/// own 16 MiB of RGBA8, so the copies are charged and the limit stops them.
#[test]
fn many_textures_sharing_one_large_image_hit_the_limit() {
    let _serial = serial();
    let side = 2048u32;
    let mut png = Vec::new();
    image::RgbaImage::new(side, side)
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    assert!(png.len() < MIB as usize, "{} bytes of PNG", png.len());
    let textures: Vec<Value> = (0..300).map(|_| json!({"source": 0})).collect();
    let materials: Vec<Value> = (0..300)
        .map(|i| json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": i}}}))
        .collect();
    let gltf = json!({
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": png.len()}],
        "bufferViews": [{"buffer": 0, "byteLength": png.len()}],
        "images": [{"bufferView": 0, "mimeType": "image/png"}],
        "textures": textures,
        "materials": materials,
    });
    let glb = common::join(&gltf, &png);
    // Within a budget that holds a few copies, it fails naming the limit.
    match load_avatar(&glb, &options(128 * MIB)) {
        Err(e @ AssetError::TooLarge { limit, .. }) => {
            assert_eq!(limit, 128 * MIB);
            let msg = e.to_string();
            assert!(
                msg.contains("texture") && msg.contains("limit 134217728"),
                "{msg}"
            );
        }
        other => panic!(
            "expected the decoded-bytes limit, got {:?}",
            other.map(|_| ())
        ),
    }
    // Textures that no material draws are not decoded, so they cost nothing.
    let mut few = gltf.clone();
    few["materials"] = json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 7}}}]);
    let avatar = load_avatar(&common::join(&few, &png), &options(128 * MIB)).unwrap();
    assert_eq!(avatar.textures.len(), 300);
    assert_eq!(avatar.textures[7].width, side);
    assert_eq!(avatar.textures[8].width, 1);
}
