//! Hostile and broken inputs: clear errors, never a panic (also fuzzed with proptest).

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use crate::common;

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

/// Structure-aware fuzzing: edits of the JSON fields of a valid file (accessor counts,
/// offsets, component types and views, view ranges and strides, buffer lengths, primitive
/// indices and attributes, node children (cycles, two parents), node meshes and skins, skin
/// joints and inverse bind matrices, sparse accessors) with the binary chunk kept intact.
/// Every result is an avatar or an error with a message; nothing panics.
#[cfg(not(target_arch = "wasm32"))]
mod structure {
    use proptest::prelude::*;
    use serde_json::Value;

    use super::*;

    /// A position in an array, taken modulo its length.
    type Index = u32;

    fn at(i: &Index, len: usize) -> usize {
        *i as usize % len.max(1)
    }

    /// One edit of the glTF JSON. Indices into arrays are [`Index`]es resolved against the
    /// array's length (plus a few past its end, to produce dangling references).
    #[derive(Debug, Clone)]
    enum Edit {
        Accessor(Index, &'static str, Value),
        View(Index, &'static str, Value),
        BufferLength(Value),
        PrimitiveIndices(Index, Index),
        PrimitiveAttribute(Index, &'static str, Index),
        AddChild(Index, Index),
        Node(Index, &'static str, Index),
        SkinJoint(Index, Index),
        SkinMatrices(Index),
        Sparse(Index, Value, Index, Index, Value),
        Remove(&'static str, Index, &'static str),
    }

    /// Numbers that hit edge cases: zero, one, small, just past 32 bits, huge, negative,
    /// fractional, and values of the wrong JSON type.
    fn number() -> impl Strategy<Value = Value> {
        prop_oneof![
            4 => (0u64..4).prop_map(Value::from),
            4 => (0u64..200_000).prop_map(Value::from),
            1 => Just(Value::from(u32::MAX)),
            1 => Just(Value::from(1u64 << 40)),
            1 => Just(Value::from(u64::MAX)),
            1 => Just(Value::from(-1)),
            1 => Just(Value::from(2.5)),
            1 => Just(Value::from("7")),
            1 => Just(Value::Null),
        ]
    }

    fn component_type() -> impl Strategy<Value = Value> {
        prop_oneof![
            6 => prop::sample::select(vec![5120u64, 5121, 5122, 5123, 5125, 5126]).prop_map(Value::from),
            1 => prop::sample::select(vec![0u64, 5124, 5127, 5130]).prop_map(Value::from),
        ]
    }

    fn accessor_type() -> impl Strategy<Value = Value> {
        prop::sample::select(vec![
            "SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4", "BOGUS",
        ])
        .prop_map(Value::from)
    }

    fn edit() -> impl Strategy<Value = Edit> {
        let idx = any::<Index>;
        prop_oneof![
            (
                idx(),
                prop::sample::select(vec!["count", "byteOffset", "bufferView"]),
                number()
            )
                .prop_map(|(i, k, v)| Edit::Accessor(i, k, v)),
            (idx(), component_type()).prop_map(|(i, v)| Edit::Accessor(i, "componentType", v)),
            (idx(), accessor_type()).prop_map(|(i, v)| Edit::Accessor(i, "type", v)),
            (idx(), any::<bool>()).prop_map(|(i, v)| Edit::Accessor(i, "normalized", v.into())),
            (
                idx(),
                prop::sample::select(vec!["byteOffset", "byteLength", "byteStride", "buffer"]),
                number()
            )
                .prop_map(|(i, k, v)| Edit::View(i, k, v)),
            number().prop_map(Edit::BufferLength),
            (idx(), idx()).prop_map(|(p, a)| Edit::PrimitiveIndices(p, a)),
            (
                idx(),
                prop::sample::select(vec![
                    "POSITION",
                    "NORMAL",
                    "TEXCOORD_0",
                    "JOINTS_0",
                    "WEIGHTS_0"
                ]),
                idx()
            )
                .prop_map(|(p, k, a)| Edit::PrimitiveAttribute(p, k, a)),
            (idx(), idx()).prop_map(|(n, c)| Edit::AddChild(n, c)),
            (idx(), prop::sample::select(vec!["mesh", "skin"]), idx())
                .prop_map(|(n, k, v)| Edit::Node(n, k, v)),
            (idx(), idx()).prop_map(|(k, n)| Edit::SkinJoint(k, n)),
            idx().prop_map(Edit::SkinMatrices),
            (idx(), number(), idx(), idx(), component_type())
                .prop_map(|(a, n, iv, vv, ct)| Edit::Sparse(a, n, iv, vv, ct)),
            (
                prop::sample::select(vec!["accessors", "bufferViews", "nodes", "skins"]),
                idx(),
                prop::sample::select(vec![
                    "bufferView",
                    "byteOffset",
                    "children",
                    "joints",
                    "inverseBindMatrices",
                    "count"
                ]),
            )
                .prop_map(|(a, i, k)| Edit::Remove(a, i, k)),
        ]
    }

    fn len(j: &Value, key: &str) -> usize {
        j[key].as_array().map_or(0, Vec::len)
    }

    /// An index into `key` (0..len + 3: the last three dangle).
    fn dangling(j: &Value, key: &str, i: &Index) -> usize {
        at(i, len(j, key) + 3)
    }

    fn apply(j: &mut Value, edit: &Edit) {
        let prims: Vec<(usize, usize)> = (0..len(j, "meshes"))
            .flat_map(|m| {
                let n = j["meshes"][m]["primitives"].as_array().map_or(0, Vec::len);
                (0..n).map(move |p| (m, p))
            })
            .collect();
        match edit {
            Edit::Accessor(i, k, v) if len(j, "accessors") > 0 => {
                let a = at(i, len(j, "accessors"));
                j["accessors"][a][*k] = v.clone();
            }
            Edit::View(i, k, v) if len(j, "bufferViews") > 0 => {
                let a = at(i, len(j, "bufferViews"));
                j["bufferViews"][a][*k] = v.clone();
            }
            Edit::BufferLength(v) if len(j, "buffers") > 0 => {
                j["buffers"][0]["byteLength"] = v.clone();
            }
            Edit::PrimitiveIndices(p, a) if !prims.is_empty() => {
                let (m, p) = prims[at(p, prims.len())];
                let a = dangling(j, "accessors", a);
                j["meshes"][m]["primitives"][p]["indices"] = a.into();
            }
            Edit::PrimitiveAttribute(p, k, a) if !prims.is_empty() => {
                let (m, p) = prims[at(p, prims.len())];
                let a = dangling(j, "accessors", a);
                j["meshes"][m]["primitives"][p]["attributes"][*k] = a.into();
            }
            Edit::AddChild(n, c) if len(j, "nodes") > 0 => {
                let n = at(n, len(j, "nodes"));
                let c = dangling(j, "nodes", c);
                let children = &mut j["nodes"][n]["children"];
                match children.as_array_mut() {
                    Some(list) => list.push(c.into()),
                    None => *children = serde_json::json!([c]),
                }
            }
            Edit::Node(n, k, v) if len(j, "nodes") > 0 => {
                let n = at(n, len(j, "nodes"));
                let count = if *k == "mesh" {
                    len(j, "meshes")
                } else {
                    len(j, "skins")
                };
                j["nodes"][n][*k] = at(v, count + 3).into();
            }
            Edit::SkinJoint(k, n) if len(j, "skins") > 0 => {
                let node = dangling(j, "nodes", n);
                if let Some(joints) = j["skins"][0]["joints"].as_array_mut()
                    && !joints.is_empty()
                {
                    let slot = at(k, joints.len());
                    joints[slot] = node.into();
                }
            }
            Edit::SkinMatrices(a) if len(j, "skins") > 0 => {
                let a = dangling(j, "accessors", a);
                j["skins"][0]["inverseBindMatrices"] = a.into();
            }
            Edit::Sparse(a, n, iv, vv, ct) if len(j, "accessors") > 0 => {
                let a = at(a, len(j, "accessors"));
                let iv = dangling(j, "bufferViews", iv);
                let vv = dangling(j, "bufferViews", vv);
                j["accessors"][a]["sparse"] = serde_json::json!({
                    "count": n,
                    "indices": {"bufferView": iv, "componentType": ct},
                    "values": {"bufferView": vv},
                });
            }
            Edit::Remove(array, i, k) if len(j, array) > 0 => {
                let row = at(i, len(j, array));
                if let Some(o) = j[*array][row].as_object_mut() {
                    o.remove(*k);
                }
            }
            _ => {}
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 128, ..ProptestConfig::default() })]

        #[test]
        fn mutated_json_fields_give_an_avatar_or_an_error(edits in prop::collection::vec(edit(), 1..6)) {
            let (mut j, bin) = common::split(&common::default_glb());
            for e in &edits {
                apply(&mut j, e);
            }
            let glb = common::join(&j, &bin);
            for options in [
                LoadOptions::default(),
                LoadOptions { require_humanoid: false, decode_textures: false, ..LoadOptions::default() },
            ] {
                match load_avatar(&glb, &options) {
                    Ok(avatar) => {
                        // What loads is usable: its rest pose is finite.
                        prop_assert!(avatar.hanim_from_file.is_finite());
                    }
                    Err(e) => {
                        let msg = e.to_string();
                        prop_assert!(msg.len() > 8, "{edits:?}: terse error `{msg}`");
                    }
                }
            }
        }
    }

    /// The edits above do reach the checks they aim at (guards against a generator that
    /// only ever produces files that fail at the first JSON check).
    #[test]
    fn targeted_json_edits_are_reported() {
        let cases: Vec<(Edit, &str)> = vec![
            (Edit::AddChild(0, 0), "own child"),
            (
                Edit::Accessor(0, "componentType", Value::from(5127)),
                "componentType",
            ),
            (Edit::View(0, "byteStride", Value::from(4)), "byteStride"),
            (Edit::BufferLength(Value::from(1u64 << 40)), "too large"),
            (
                Edit::Accessor(0, "byteOffset", Value::from(1u64 << 40)),
                "do not fit",
            ),
        ];
        for (edit, expected) in cases {
            let (mut j, bin) = common::split(&common::default_glb());
            apply(&mut j, &edit);
            let e = err(&common::join(&j, &bin));
            assert!(e.contains(expected), "{edit:?}: {e}");
        }
    }
}
