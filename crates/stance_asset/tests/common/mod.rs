//! GLB surgery for the tests: split a GLB into JSON and BIN, and put it back together.

#![allow(dead_code, clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use serde_json::{Value, json};

/// The fuzz targets' framing of parts, for the seeds the tests write.
#[path = "../../fuzz/common/parts.rs"]
pub mod parts;

pub fn split(glb: &[u8]) -> (Value, Vec<u8>) {
    let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let json: Value = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
    let bin_at = 20 + json_len;
    let bin = if glb.len() > bin_at + 8 {
        let len = u32::from_le_bytes(glb[bin_at..bin_at + 4].try_into().unwrap()) as usize;
        glb[bin_at + 8..bin_at + 8 + len].to_vec()
    } else {
        Vec::new()
    };
    (json, bin)
}

pub fn join(json: &Value, bin: &[u8]) -> Vec<u8> {
    let mut j = serde_json::to_vec(json).unwrap();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let mut b = bin.to_vec();
    while !b.len().is_multiple_of(4) {
        b.push(0);
    }
    let total = 12 + 8 + j.len() + if b.is_empty() { 0 } else { 8 + b.len() };
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(j.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x4E4F_534Au32.to_le_bytes());
    out.extend_from_slice(&j);
    if !b.is_empty() {
        out.extend_from_slice(&(b.len() as u32).to_le_bytes());
        out.extend_from_slice(&0x004E_4942u32.to_le_bytes());
        out.extend_from_slice(&b);
    }
    out
}

/// The generated default avatar as GLB.
pub fn default_glb() -> Vec<u8> {
    stance_asset::export_glb(&stance_asset::make_default_avatar().unwrap()).unwrap()
}

/// A memory figure of this process from `/proc/self/status` (`VmRSS:`, `VmHWM:`), in KiB;
/// 0 where the file does not exist.
#[cfg(not(target_arch = "wasm32"))]
pub fn status_kb(key: &str) -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with(key))
                .and_then(|l| l.split_whitespace().nth(1).and_then(|v| v.parse().ok()))
        })
        .unwrap_or(0)
}

/// The same GLB under a new root node that makes it Z up (Y -> Z), in centimetres, facing -X
/// and moved off the origin: what any importer must normalise back.
pub fn z_up_centimetres_facing_minus_x(glb: &[u8]) -> Vec<u8> {
    let (mut j, bin) = split(glb);
    let q = glam::DQuat::from_rotation_z(-std::f64::consts::FRAC_PI_2)
        * glam::DQuat::from_rotation_x(std::f64::consts::FRAC_PI_2);
    let old_roots = j["scenes"][0]["nodes"].clone();
    let Some(nodes) = j["nodes"].as_array_mut() else {
        panic!("a GLB with nodes");
    };
    nodes.push(
        serde_json::json!({"name": "Armature", "children": old_roots,
        "rotation": [q.x, q.y, q.z, q.w], "scale": [100.0, 100.0, 100.0],
        "translation": [12.0, -3.0, 40.0]}),
    );
    let armature = nodes.len() - 1;
    j["scenes"][0]["nodes"] = serde_json::json!([armature]);
    join(&j, &bin)
}

/// (VRM 1.0 bone, VRM 0.x bone, H-Anim joint).
pub const VRM_BONES: &[(&str, &str, &str)] = &[
    ("hips", "hips", "humanoid_root"),
    ("spine", "spine", "vl5"),
    ("chest", "chest", "vt10"),
    ("upperChest", "upperChest", "vt1"),
    ("neck", "neck", "vc4"),
    ("head", "head", "skullbase"),
    ("leftUpperLeg", "leftUpperLeg", "l_hip"),
    ("leftLowerLeg", "leftLowerLeg", "l_knee"),
    ("leftFoot", "leftFoot", "l_talocrural"),
    ("leftToes", "leftToes", "l_metatarsophalangeal_2"),
    ("rightUpperLeg", "rightUpperLeg", "r_hip"),
    ("rightLowerLeg", "rightLowerLeg", "r_knee"),
    ("rightFoot", "rightFoot", "r_talocrural"),
    ("rightToes", "rightToes", "r_metatarsophalangeal_2"),
    ("leftShoulder", "leftShoulder", "l_sternoclavicular"),
    ("leftUpperArm", "leftUpperArm", "l_shoulder"),
    ("leftLowerArm", "leftLowerArm", "l_elbow"),
    ("leftHand", "leftHand", "l_radiocarpal"),
    ("rightShoulder", "rightShoulder", "r_sternoclavicular"),
    ("rightUpperArm", "rightUpperArm", "r_shoulder"),
    ("rightLowerArm", "rightLowerArm", "r_elbow"),
    ("rightHand", "rightHand", "r_radiocarpal"),
    (
        "leftThumbMetacarpal",
        "leftThumbProximal",
        "l_carpometacarpal_1",
    ),
    (
        "leftThumbProximal",
        "leftThumbIntermediate",
        "l_metacarpophalangeal_1",
    ),
    (
        "leftThumbDistal",
        "leftThumbDistal",
        "l_carpal_interphalangeal_1",
    ),
    (
        "leftIndexProximal",
        "leftIndexProximal",
        "l_metacarpophalangeal_2",
    ),
    (
        "rightLittleDistal",
        "rightLittleDistal",
        "r_carpal_distal_interphalangeal_5",
    ),
];

/// `glb` with scrambled node names and a VRM humanoid extension (0.x or 1.0) naming the bones
/// of [`VRM_BONES`] it has: only the extension can map it.
pub fn vrm_from(glb: &[u8], version: u8) -> Vec<u8> {
    let (mut j, bin) = split(glb);
    let nodes = j["nodes"].as_array_mut().unwrap();
    let mut index = std::collections::HashMap::new();
    for (i, n) in nodes.iter_mut().enumerate() {
        index.insert(n["name"].as_str().unwrap().to_owned(), i);
        n["name"] = json!(format!("J{i:03}"));
    }
    let named: Vec<_> = VRM_BONES
        .iter()
        .filter(|(_, _, h)| index.contains_key(*h))
        .collect();
    let root = index["humanoid_root"];
    if version == 0 {
        // VRM 0.x models face -Z: turn the body around.
        j["nodes"][root]["rotation"] = json!([0.0, 1.0, 0.0, 0.0]);
        let bones: Vec<Value> = named
            .iter()
            .map(|(_, b0, h)| json!({"bone": b0, "node": index[*h], "useDefaultValues": true}))
            .collect();
        j["extensions"] = json!({"VRM": {"exporterVersion": "test", "humanoid": {"humanBones": bones},
            "meta": {"title": "test", "licenseName": "CC_BY"},
            "blendShapeMaster": {"blendShapeGroups": [{"name": "Joy", "presetName": "joy",
                "binds": [{"mesh": 0, "index": 0, "weight": 100}]}]},
            "materialProperties": [{"name": "skin", "shader": "VRM/MToon", "textureProperties": {},
                "vectorProperties": {"_Color": [0.5, 0.4, 0.3, 1.0]}}]}});
        j["extensionsUsed"] = json!(["VRM"]);
    } else {
        let mut bones = serde_json::Map::new();
        for (b1, _, h) in &named {
            bones.insert((*b1).into(), json!({"node": index[*h]}));
        }
        j["extensions"] = json!({"VRMC_vrm": {"specVersion": "1.0",
            "meta": {"name": "test", "licenseUrl": "https://vrm.dev/licenses/1.0/"},
            "humanoid": {"humanBones": bones},
            "expressions": {"preset": {"happy": {"morphTargetBinds": [{"node": 0, "index": 0, "weight": 1.0}]}}}}});
        j["materials"][0]["extensions"] = json!({"VRMC_materials_mtoon": {"specVersion": "1.0"}});
        j["extensionsUsed"] = json!(["VRMC_vrm", "VRMC_materials_mtoon"]);
    }
    join(&j, &bin)
}
