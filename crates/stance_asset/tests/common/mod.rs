//! GLB surgery for the tests: split a GLB into JSON and BIN, and put it back together.

#![allow(dead_code, clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use serde_json::Value;

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
