//! GLB export of the avatar with a sequence of postures as one glTF animation.

use glam::{DQuat, DVec3};
use serde_json::{Value, json};
use stance_hanim::HumanoidSkeleton;
use stance_ik::Posture;

use crate::AssetError;
use crate::export::{Bin, FLOAT, export_with, f32s};
use crate::model::{Avatar, Trs};

/// Rotation difference (sine of half the angle) under which a node does not move.
const ROTATION_TOLERANCE: f64 = 1e-9;
/// Relative translation and scale difference under which a node does not move.
const LENGTH_TOLERANCE: f64 = 1e-9;

fn rotation_differs(a: DQuat, b: DQuat) -> bool {
    let d = a.conjugate() * b;
    DVec3::new(d.x, d.y, d.z).length() > ROTATION_TOLERANCE
}

fn vector_differs(a: DVec3, b: DVec3) -> bool {
    (a - b).length() > LENGTH_TOLERANCE * a.length().max(b.length()).max(1.0)
}

/// Writes `avatar` as [`crate::export_glb`] does (meshes, skins, materials, textures, the
/// nodes' current transforms and rest) plus one animation `name` showing `postures` of
/// `skeleton` (built from this avatar) at `frame_time` seconds apart.
///
/// The animation has exactly `postures.len()` keys, at `k x frame_time` for `k` in
/// `0..postures.len()` (an input accessor with `min`/`max`, shared by all samplers), all
/// LINEAR: a `rotation` channel for every node whose rotation ([`Avatar::posed_locals`])
/// differs from its written transform in some frame, a `translation` channel for every
/// node whose translation does (the root), a `scale` channel where the scale does. When
/// nothing moves, the root joint's node still gets a constant rotation channel (glTF wants
/// at least one). Consecutive rotation keys have positive dot products.
pub fn export_glb_animation(
    avatar: &Avatar,
    skeleton: &HumanoidSkeleton,
    postures: &[Posture],
    frame_time: f64,
    name: &str,
) -> Result<Vec<u8>, AssetError> {
    let fail = |reason: String| AssetError::Animation {
        animation: format!("`{name}`"),
        reason,
    };
    if postures.is_empty() {
        return Err(fail(
            "no postures: an animation needs at least one key".into(),
        ));
    }
    if !(frame_time.is_finite() && frame_time > 0.0) {
        return Err(fail(format!(
            "the frame time must be positive and finite, got {frame_time}"
        )));
    }
    let times: Vec<f32> = (0..postures.len())
        .map(|k| (k as f64 * frame_time) as f32)
        .collect();
    if !times.iter().all(|t| t.is_finite()) || times.windows(2).any(|w| w[1] <= w[0]) {
        return Err(fail(format!(
            "{} keys at {frame_time} s apart are not strictly increasing finite f32 times",
            postures.len()
        )));
    }
    let frames: Vec<Vec<Trs>> = postures
        .iter()
        .enumerate()
        .map(|(k, p)| {
            avatar
                .posed_locals(skeleton, p)
                .map_err(|e| fail(format!("posture {k}: {e}")))
        })
        .collect::<Result<_, _>>()?;

    // (node, path) pairs to animate.
    let mut channels: Vec<(usize, &'static str)> = Vec::new();
    for (n, node) in avatar.nodes.iter().enumerate() {
        let written = node.pose;
        let at = |f: &Vec<Trs>| f.get(n).copied().unwrap_or(written);
        if frames
            .iter()
            .any(|f| vector_differs(at(f).translation, written.translation))
        {
            channels.push((n, "translation"));
        }
        if frames
            .iter()
            .any(|f| rotation_differs(at(f).rotation, written.rotation))
        {
            channels.push((n, "rotation"));
        }
        if frames
            .iter()
            .any(|f| vector_differs(at(f).scale, written.scale))
        {
            channels.push((n, "scale"));
        }
    }
    if channels.is_empty() {
        let root = skeleton
            .joints
            .first()
            .and_then(|j| j.source)
            .filter(|&s| s < avatar.nodes.len())
            .or_else(|| avatar.scene_roots.first().copied())
            .filter(|&s| s < avatar.nodes.len())
            .ok_or_else(|| fail("the avatar has no node to animate".into()))?;
        channels.push((root, "rotation"));
    }

    export_with(avatar, |bin: &mut Bin| {
        let last = times.last().copied().unwrap_or(0.0);
        let input = bin.accessor(
            &f32s(&times.iter().map(|&t| [t]).collect::<Vec<_>>()),
            None,
            FLOAT,
            times.len(),
            "SCALAR",
            Some((vec![0.0], vec![last])),
        );
        let mut samplers = Vec::with_capacity(channels.len());
        let mut targets = Vec::with_capacity(channels.len());
        for (s, &(node, path)) in channels.iter().enumerate() {
            let at = |f: &Vec<Trs>| f.get(node).copied().unwrap_or_default();
            let output = match path {
                "rotation" => {
                    let mut previous: Option<DQuat> = None;
                    let keys: Vec<[f32; 4]> = frames
                        .iter()
                        .map(|f| {
                            let mut q = at(f).rotation.normalize();
                            if !q.is_finite() {
                                q = DQuat::IDENTITY;
                            }
                            if previous.is_some_and(|p| p.dot(q) < 0.0) {
                                q = -q;
                            }
                            previous = Some(q);
                            unit_f32(q)
                        })
                        .collect();
                    bin.accessor(&f32s(&keys), None, FLOAT, keys.len(), "VEC4", None)
                }
                _ => {
                    let keys: Vec<[f32; 3]> = frames
                        .iter()
                        .map(|f| {
                            let trs = at(f);
                            let v = if path == "scale" {
                                trs.scale
                            } else {
                                trs.translation
                            };
                            v.to_array().map(|x| x as f32)
                        })
                        .collect();
                    bin.accessor(&f32s(&keys), None, FLOAT, keys.len(), "VEC3", None)
                }
            };
            samplers.push(json!({"input": input, "output": output, "interpolation": "LINEAR"}));
            targets.push(json!({"sampler": s, "target": {"node": node, "path": path}}));
        }
        Ok(vec![Value::Object(
            [
                ("name".to_owned(), json!(name)),
                ("channels".to_owned(), Value::Array(targets)),
                ("samplers".to_owned(), Value::Array(samplers)),
            ]
            .into_iter()
            .collect(),
        )])
    })
}

/// A quaternion as unit-length `f32` (the validator checks unit length in `f32`).
fn unit_f32(q: DQuat) -> [f32; 4] {
    let r = [q.x as f32, q.y as f32, q.z as f32, q.w as f32];
    let n = r.iter().map(|x| x * x).sum::<f32>().sqrt();
    if n > 0.0 && n.is_finite() {
        r.map(|x| x / n)
    } else {
        [0.0, 0.0, 0.0, 1.0]
    }
}
