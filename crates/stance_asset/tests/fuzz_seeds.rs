//! The seed corpora of the `import` fuzz target (`fuzz/seeds/import/`): small valid files of
//! every kind the importer reads, each prefixed with the target's selector byte (bit 0: no
//! humanoid required, bit 1: decode textures, bit 2: the second half is the external file, bit
//! 3: images 0 and 1 given decoded, bits 4 to 7 their size); and of the `transfer` target
//! (`fuzz/seeds/transfer/`): each of those avatars as the bytes the page's import worker hands
//! to the editor.
//!
//! `the_fuzz_seeds_load` checks the committed seeds; `write_fuzz_seeds` (ignored) writes them
//! again: `cargo test -p stance_asset --test all fuzz_seeds:: -- --ignored`.

#![cfg(not(target_arch = "wasm32"))]
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use crate::common;
use crate::common::parts::{join_parts, split_parts};

use std::collections::HashMap;

use base64::Engine as _;
use base64::engine::general_purpose::STANDARD;
use meshopt_rs::index::buffer::{encode_index_buffer, encode_index_buffer_bound};
use meshopt_rs::index::sequence::{encode_index_sequence, encode_index_sequence_bound};
use meshopt_rs::vertex::buffer::{encode_vertex_buffer, encode_vertex_buffer_bound};
use serde_json::{Value, json};
use stance_asset::{
    Avatar, DecodedImage, LoadOptions, Primitive, SourceFormat, export_glb, export_glb_animation,
    find_resource, load_avatar_with_images, make_default_avatar,
};

const NO_HUMANOID: u8 = 1;
const TEXTURES: u8 = 2;
const MULTI_FILE: u8 = 4;
const DECODED_IMAGES: u8 = 8;

fn seed_dir() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds/import")
}

/// A seed of the `transfer` target: the avatar's bytes, then each texture's pixels, each
/// part after its length (4 bytes, little-endian); see `fuzz_targets/transfer.rs`.
fn transfer_seed(transfer: &stance_asset::AvatarTransfer) -> Vec<u8> {
    let seed = join_parts(std::iter::once(&transfer.avatar).chain(&transfer.pixels));
    // The target reads back the parts written.
    assert_eq!(split_parts(&seed).len(), 1 + transfer.pixels.len());
    seed
}

/// The seeds of the `transfer` target: each import seed's avatar as transfer bytes.
fn transfer_dir() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds/transfer")
}

/// The fuzz target's reading of a seed (keep in step with `fuzz/fuzz_targets/import.rs`).
fn load_seed(data: &[u8]) -> Result<Avatar, String> {
    let (&selector, file) = data.split_first().ok_or("empty seed")?;
    let options = LoadOptions {
        require_humanoid: selector & NO_HUMANOID == 0,
        decode_textures: selector & TEXTURES != 0,
        ..LoadOptions::default()
    };
    let (file, resources) = if selector & MULTI_FILE != 0 {
        let (main, rest) = file.split_at(file.len() / 2);
        (main, vec![("any".to_owned(), rest.to_vec())])
    } else {
        (file, Vec::new())
    };
    let mut resolve = |uri: &str| {
        let found = find_resource(&resources, uri).map(<[u8]>::to_vec);
        found.or_else(|| resources.first().map(|(_, bytes)| bytes.clone()))
    };
    // The 1x1 images of selector bits 4 to 7 at 0: image 0 right, image 1 a pixel short.
    assert!(selector >> 4 == 0, "the seeds give 1x1 images");
    let decoded = if selector & DECODED_IMAGES != 0 {
        let image = |index, rgba8| DecodedImage {
            index,
            width: 1,
            height: 1,
            rgba8,
        };
        vec![image(0, vec![200; 4]), image(1, vec![100; 3])]
    } else {
        Vec::new()
    };
    let images = stance_asset::HostImages {
        decoded,
        ..Default::default()
    };
    load_avatar_with_images(file, &options, &mut resolve, images).map_err(|e| e.to_string())
}

// ---------------------------------------------------------------------------------------------
// The files

/// `keep` triangles spread over `p`, with the vertices they use.
fn thinned(p: &Primitive, keep: usize) -> Primitive {
    let triangles = p.indices.len() / 3;
    let step = (triangles / keep).max(1);
    let mut out = Primitive {
        material: p.material,
        ..Primitive::default()
    };
    let mut index = HashMap::new();
    for t in (0..triangles).step_by(step).take(keep) {
        for &v in &p.indices[3 * t..3 * t + 3] {
            let v = v as usize;
            let n = *index.entry(v).or_insert_with(|| {
                out.positions.push(p.positions[v]);
                if let Some(n) = p.normals.get(v) {
                    out.normals.push(*n);
                }
                if let Some(uv) = p.uvs.get(v) {
                    out.uvs.push(*uv);
                }
                if let Some(j) = p.joints.get(v) {
                    out.joints.push(*j);
                }
                if let Some(w) = p.weights.get(v) {
                    out.weights.push(*w);
                }
                out.positions.len() - 1
            });
            out.indices.push(n as u32);
        }
    }
    out
}

/// The default avatar (the 71 LOA2 joints, skinned) with a few triangles per primitive.
fn tiny_avatar() -> Avatar {
    let mut avatar = make_default_avatar().unwrap();
    for mesh in &mut avatar.meshes {
        for p in &mut mesh.primitives {
            *p = thinned(p, 12);
        }
    }
    avatar
}

fn tiny_glb() -> Vec<u8> {
    compact(&export_glb(&tiny_avatar()).unwrap(), false)
}

/// Rounds `v`'s numbers to 5 decimals (the f32 noise of the joint centres).
fn round_numbers(v: &mut Value) {
    match v {
        Value::Number(n) if n.is_f64() => {
            let x = (n.as_f64().unwrap() * 1e5).round() / 1e5;
            *v = json!(x);
        }
        Value::Array(a) => a.iter_mut().for_each(round_numbers),
        Value::Object(o) => o.values_mut().for_each(round_numbers),
        _ => {}
    }
}

/// A smaller GLB of the same avatar: node transforms rounded, identity rotations and scales
/// left out, and the nodes' rest transforms for Stance (`extras`) kept only with `extras`.
fn compact(glb: &[u8], extras: bool) -> Vec<u8> {
    let (mut j, bin) = common::split(glb);
    for node in j["nodes"].as_array_mut().unwrap() {
        let node = node.as_object_mut().unwrap();
        if !extras {
            node.remove("extras");
        }
        if node.get("rotation") == Some(&json!([0.0, 0.0, 0.0, 1.0])) {
            node.remove("rotation");
        }
        if node.get("scale") == Some(&json!([1.0, 1.0, 1.0])) {
            node.remove("scale");
        }
        node.values_mut().for_each(round_numbers);
    }
    common::join(&j, &bin)
}

fn encoded_image(format: image::ImageFormat) -> Vec<u8> {
    let img = image::RgbaImage::from_fn(4, 4, |x, y| {
        image::Rgba([x as u8 * 60, y as u8 * 60, 200, 255])
    });
    let mut out = std::io::Cursor::new(Vec::new());
    image::DynamicImage::ImageRgba8(img)
        .to_rgb8()
        .write_to(&mut out, format)
        .unwrap();
    out.into_inner()
}

fn push_aligned(bin: &mut Vec<u8>, bytes: &[u8]) -> usize {
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let at = bin.len();
    bin.extend_from_slice(bytes);
    at
}

fn array<'a>(j: &'a mut Value, key: &str) -> &'a mut Vec<Value> {
    let entry = j.as_object_mut().unwrap().entry(key).or_insert(json!([]));
    entry.as_array_mut().unwrap()
}

/// A GLB whose two first materials have a PNG and a JPEG base colour texture (in buffer
/// views), the first one also KHR_texture_transform.
fn textured_glb() -> Vec<u8> {
    let (mut j, mut bin) = common::split(&tiny_glb());
    for (k, (format, mime)) in [
        (image::ImageFormat::Png, "image/png"),
        (image::ImageFormat::Jpeg, "image/jpeg"),
    ]
    .into_iter()
    .enumerate()
    {
        let bytes = encoded_image(format);
        let at = push_aligned(&mut bin, &bytes);
        let views = array(&mut j, "bufferViews");
        views.push(json!({"buffer": 0, "byteOffset": at, "byteLength": bytes.len()}));
        let view = views.len() - 1;
        array(&mut j, "images").push(json!({"bufferView": view, "mimeType": mime}));
        array(&mut j, "samplers").push(json!({"magFilter": 9729, "wrapS": 33648}));
        array(&mut j, "textures").push(json!({"source": k, "sampler": k}));
        let material = &mut j["materials"][k];
        material["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": k});
    }
    j["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"] = json!({
        "KHR_texture_transform": {"offset": [0.5, 0.0], "scale": [0.5, 1.0]}});
    j["materials"][1]["extensions"] = json!({"KHR_materials_unlit": {}});
    j["extensionsUsed"] = json!(["KHR_texture_transform", "KHR_materials_unlit"]);
    j["buffers"][0]["byteLength"] = json!(bin.len());
    common::join(&j, &bin)
}

/// A `.gltf` with its buffer and a PNG as data URIs.
fn data_uri_gltf() -> Vec<u8> {
    let (mut j, bin) = common::split(&tiny_glb());
    j["buffers"] = json!([{"byteLength": bin.len(),
        "uri": format!("data:application/octet-stream;base64,{}", STANDARD.encode(&bin))}]);
    let png = encoded_image(image::ImageFormat::Png);
    j["images"] = json!([{"uri": format!("data:image/png;base64,{}", STANDARD.encode(png))}]);
    j["textures"] = json!([{"source": 0}]);
    j["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
    serde_json::to_vec(&j).unwrap()
}

/// A `.gltf` and its `.bin` in the fuzz target's multi-file layout: the file, padded with
/// spaces, then the buffer, padded with zeros, as two halves of the same length.
fn multi_file_gltf() -> Vec<u8> {
    let (mut j, bin) = common::split(&tiny_glb());
    j["buffers"] = json!([{"byteLength": bin.len(), "uri": "avatar.bin"}]);
    let mut gltf = serde_json::to_vec(&j).unwrap();
    let mut bin = bin;
    let half = gltf.len().max(bin.len());
    gltf.resize(half, b' ');
    bin.resize(half, 0);
    gltf.extend_from_slice(&bin);
    gltf
}

/// The tiny avatar with scrambled node names, mapped by its VRM humanoid extension alone
/// (as `tests/vrm.rs` builds them).
fn vrm_file(version: u8) -> Vec<u8> {
    common::vrm_from(&tiny_glb(), version)
}

/// The tiny avatar with a one-second animation: rest, the left elbow bent, rest.
fn animated_glb() -> Vec<u8> {
    let avatar = tiny_avatar();
    let body = avatar.skeleton(&Default::default()).unwrap();
    let rest = stance_ik::Posture::rest(&body.skeleton);
    let mut bent = rest.clone();
    let elbow = body.skeleton.joint_index("l_elbow").unwrap();
    bent.values_mut()[body.skeleton.joints()[elbow].dof_start] = -1.0;
    let root = body.skeleton.joint_index("humanoid_root").unwrap();
    bent.values_mut()[body.skeleton.joints()[root].dof_start] = 0.1;
    let glb = export_glb_animation(&avatar, &body, &[rest.clone(), bent, rest], 0.5, "wave");
    compact(&glb.unwrap(), true)
}

/// A static triangle in a `.gltf` with a data URI and no skin: loads only without the
/// humanoid requirement.
fn triangle_gltf() -> Vec<u8> {
    let mut bin = Vec::new();
    for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for c in v {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in [0u16, 1, 2, 0] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let j = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "tri", "mesh": 0, "translation": [0.0, 1.0, 0.0]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]},
            {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 6}
        ],
        "buffers": [{"byteLength": bin.len(),
            "uri": format!("data:application/octet-stream;base64,{}", STANDARD.encode(&bin))}]
    });
    serde_json::to_vec(&j).unwrap()
}

// ---------------------------------------------------------------------------------------------
// EXT_meshopt_compression

fn element_size(accessor: &Value) -> usize {
    let components = match accessor["type"].as_str().unwrap() {
        "SCALAR" => 1,
        "VEC2" => 2,
        "VEC3" => 3,
        "VEC4" | "MAT2" => 4,
        "MAT3" => 9,
        _ => 16,
    };
    let bytes = match accessor["componentType"].as_u64().unwrap() {
        5120 | 5121 => 1,
        5122 | 5123 => 2,
        _ => 4,
    };
    components * bytes
}

fn encode_attributes(data: &[u8], stride: usize) -> Vec<u8> {
    macro_rules! by_stride {
        ($($n:literal)*) => {
            match stride {
                $($n => {
                    let v: Vec<[u8; $n]> =
                        data.chunks_exact($n).map(|c| c.try_into().unwrap()).collect();
                    let mut out = vec![0; encode_vertex_buffer_bound(v.len(), $n)];
                    let len = encode_vertex_buffer(&mut out, &v, Default::default()).unwrap();
                    out.truncate(len);
                    out
                })*
                other => panic!("stride {other}"),
            }
        };
    }
    by_stride!(4 8 12 16)
}

fn read_indices(data: &[u8], stride: usize) -> Vec<u32> {
    data.chunks_exact(stride)
        .map(|c| {
            if stride == 2 {
                u32::from(u16::from_le_bytes([c[0], c[1]]))
            } else {
                u32::from_le_bytes([c[0], c[1], c[2], c[3]])
            }
        })
        .collect()
}

/// `f` as meshopt's exponential filter stores it (a 24-bit mantissa, exponent -15).
fn exponential(f: f32) -> [u8; 4] {
    let m = (f64::from(f) * 32768.0).round() as i32;
    (((-15i32 as u32) << 24) | (m as u32 & 0x00FF_FFFF)).to_le_bytes()
}

/// A unit vector as meshopt's 16-bit octahedral filter stores it.
fn octahedral(n: [f32; 3]) -> [u8; 8] {
    let l = n[0].abs() + n[1].abs() + n[2].abs();
    let s = if l > 0.0 { 1.0 / l } else { 0.0 };
    let (x, y) = (n[0] * s, n[1] * s);
    let (fx, fy) = if n[2] >= 0.0 {
        (x, y)
    } else {
        ((1.0 - y.abs()) * x.signum(), (1.0 - x.abs()) * y.signum())
    };
    let q = |v: f32| ((v * 32767.0).round() as i16).to_le_bytes();
    let mut out = [0u8; 8];
    out[0..2].copy_from_slice(&q(fx));
    out[2..4].copy_from_slice(&q(fy));
    out[4..6].copy_from_slice(&32767i16.to_le_bytes());
    out
}

/// The tiny avatar with every vertex stream and index list EXT_meshopt_compression'd (the
/// positions with the exponential filter, the normals octahedral as normalised shorts, the
/// second primitive's indices as an index sequence), the other views left plain; the
/// uncompressed data is a fallback buffer without bytes.
fn meshopt_glb() -> Vec<u8> {
    let (mut j, bin) = common::split(&tiny_glb());
    // (view, stride, mode, filter, bytes to compress).
    let mut compressed: HashMap<usize, (usize, &str, &str, Vec<u8>)> = HashMap::new();
    let accessors = j["accessors"].clone();
    let view_bytes = |view: &Value| -> Vec<u8> {
        let at = view["byteOffset"].as_u64().unwrap_or(0) as usize;
        bin[at..at + view["byteLength"].as_u64().unwrap() as usize].to_vec()
    };
    let primitives: Vec<Value> = j["meshes"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|m| m["primitives"].as_array().unwrap().clone())
        .collect();
    for (p, primitive) in primitives.iter().enumerate() {
        for (name, a) in primitive["attributes"].as_object().unwrap() {
            let a = a.as_u64().unwrap() as usize;
            let v = accessors[a]["bufferView"].as_u64().unwrap() as usize;
            let data = view_bytes(&j["bufferViews"][v]);
            let entry = match name.as_str() {
                "POSITION" => {
                    let data = data
                        .chunks_exact(4)
                        .flat_map(|c| exponential(f32::from_le_bytes(c.try_into().unwrap())));
                    (12, "ATTRIBUTES", "EXPONENTIAL", data.collect())
                }
                "NORMAL" => {
                    let data = data.chunks_exact(12).flat_map(|c| {
                        let f = |k: usize| f32::from_le_bytes(c[k..k + 4].try_into().unwrap());
                        octahedral([f(0), f(4), f(8)])
                    });
                    j["accessors"][a]["componentType"] = json!(5122);
                    j["accessors"][a]["normalized"] = json!(true);
                    j["bufferViews"][v]["byteStride"] = json!(8);
                    (8, "ATTRIBUTES", "OCTAHEDRAL", data.collect())
                }
                _ => {
                    let size = element_size(&accessors[a]);
                    assert!(size.is_multiple_of(4), "{name}: {size} bytes");
                    (size, "ATTRIBUTES", "NONE", data)
                }
            };
            compressed.insert(v, entry);
        }
        if let Some(a) = primitive["indices"].as_u64() {
            let a = a as usize;
            let v = accessors[a]["bufferView"].as_u64().unwrap() as usize;
            let size = element_size(&accessors[a]);
            let mode = if p == 1 { "INDICES" } else { "TRIANGLES" };
            compressed.insert(v, (size, mode, "NONE", view_bytes(&j["bufferViews"][v])));
        }
    }
    let mut packed = Vec::new();
    let mut fallback_len = 0usize;
    let count = j["bufferViews"].as_array().unwrap().len();
    for v in 0..count {
        let view = &mut j["bufferViews"][v];
        match compressed.get(&v) {
            None => {
                let bytes = view_bytes(view);
                view["byteOffset"] = json!(push_aligned(&mut packed, &bytes));
            }
            Some((stride, mode, filter, data)) => {
                let n = data.len() / stride;
                let stream = match *mode {
                    "ATTRIBUTES" => encode_attributes(data, *stride),
                    "TRIANGLES" => {
                        let indices = read_indices(data, *stride);
                        let mut out = vec![0; encode_index_buffer_bound(n, n)];
                        let len =
                            encode_index_buffer(&mut out, &indices, Default::default()).unwrap();
                        out.truncate(len);
                        out
                    }
                    _ => {
                        let indices = read_indices(data, *stride);
                        let mut out = vec![0; encode_index_sequence_bound(n, n)];
                        let len = encode_index_sequence(&mut out, &indices, Default::default());
                        out.truncate(len);
                        out
                    }
                };
                let at = push_aligned(&mut packed, &stream);
                let mut ext = json!({"buffer": 0, "byteOffset": at, "byteLength": stream.len(),
                    "byteStride": stride, "count": n, "mode": mode});
                if *filter != "NONE" {
                    ext["filter"] = json!(filter);
                }
                fallback_len = fallback_len.next_multiple_of(4);
                view["buffer"] = json!(1);
                view["byteOffset"] = json!(fallback_len);
                view["byteLength"] = json!(data.len());
                fallback_len += data.len();
                view["extensions"] = json!({"EXT_meshopt_compression": ext});
            }
        }
    }
    j["buffers"] = json!([{"byteLength": packed.len()}, {"byteLength": fallback_len,
        "extensions": {"EXT_meshopt_compression": {"fallback": true}}}]);
    j["extensionsUsed"] = json!(["EXT_meshopt_compression", "KHR_mesh_quantization"]);
    j["extensionsRequired"] = json!(["EXT_meshopt_compression", "KHR_mesh_quantization"]);
    common::join(&j, &packed)
}

/// The seeds' file names.
const SEEDS: [&str; 10] = [
    "humanoid.glb",
    "textured.glb",
    "decoded-images.glb",
    "data-uri.gltf",
    "multi-file.gltf+bin",
    "vrm0.vrm",
    "vrm1.vrm",
    "meshopt.glb",
    "animated.glb",
    "triangle.gltf",
];

/// The seed `name`: its selector and file.
fn seed(name: &str) -> (u8, Vec<u8>) {
    match name {
        "humanoid.glb" => (0, tiny_glb()),
        "textured.glb" => (TEXTURES, textured_glb()),
        "decoded-images.glb" => (TEXTURES | DECODED_IMAGES, textured_glb()),
        "data-uri.gltf" => (TEXTURES, data_uri_gltf()),
        "multi-file.gltf+bin" => (MULTI_FILE, multi_file_gltf()),
        "vrm0.vrm" => (0, vrm_file(0)),
        "vrm1.vrm" => (0, vrm_file(1)),
        "meshopt.glb" => (0, meshopt_glb()),
        "animated.glb" => (0, animated_glb()),
        "triangle.gltf" => (NO_HUMANOID, triangle_gltf()),
        _ => panic!("no seed {name}"),
    }
}

#[test]
#[ignore = "writes the seed corpus: run with --ignored after changing the generators"]
fn write_fuzz_seeds() {
    let dir = seed_dir();
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::create_dir_all(transfer_dir()).unwrap();
    for name in SEEDS {
        let (selector, file) = seed(name);
        let mut data = vec![selector];
        data.extend_from_slice(&file);
        let avatar = load_seed(&data).unwrap();
        std::fs::write(dir.join(name), data).unwrap();
        let transfer = stance_asset::AvatarTransfer::new(avatar).unwrap();
        std::fs::write(
            transfer_dir().join(format!("{name}.bin")),
            transfer_seed(&transfer),
        )
        .unwrap();
    }
}

#[test]
fn the_fuzz_seeds_load() {
    let mut total = 0;
    let mut found = Vec::new();
    for entry in std::fs::read_dir(seed_dir()).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let data = std::fs::read(&path).unwrap();
        assert!(data.len() < 64 * 1024, "{name}: {} bytes", data.len());
        total += data.len();
        let avatar = load_seed(&data).unwrap_or_else(|e| panic!("{name}: {e}"));
        // Handed between threads as bytes (the page's import worker), it comes back equal:
        // VRM extension, textures, animations and mapping included.
        let transfer = stance_asset::AvatarTransfer::new(avatar.clone()).unwrap();
        let seed = transfer_dir().join(format!("{name}.bin"));
        assert_eq!(
            std::fs::read(&seed).ok(),
            Some(transfer_seed(&transfer)),
            "{name}: the transfer seed is not the avatar's transfer (run write_fuzz_seeds)"
        );
        assert_eq!(transfer.into_avatar().unwrap(), avatar, "{name}");
        let expected = match name.as_str() {
            "vrm0.vrm" => Some(SourceFormat::Vrm0),
            "vrm1.vrm" => Some(SourceFormat::Vrm1),
            _ => None,
        };
        if let Some(format) = expected {
            assert_eq!(avatar.format, format, "{name}");
        }
        if name.starts_with("meshopt") {
            assert!(
                avatar
                    .extensions
                    .iter()
                    .any(|e| e == "EXT_meshopt_compression")
            );
        }
        if name.starts_with("decoded") {
            let t = &avatar.textures[avatar.materials[0].base_color_texture.unwrap()];
            assert_eq!((t.width, t.height, &t.rgba8[..]), (1, 1, &[200; 4][..]));
            assert!(avatar.warnings.iter().any(|w| w.starts_with("image 1")));
        }
        if name.starts_with("animated") {
            assert_eq!(avatar.animations.len(), 1, "{name}");
        }
        found.push(name);
    }
    found.sort();
    let mut expected = SEEDS.to_vec();
    expected.sort_unstable();
    assert_eq!(found, expected);
    assert!(total < 1024 * 1024, "{total} bytes of seeds");
}
