//! Retargeting for JavaScript: the `stance-ik` package's second WebAssembly module
//! (`packages/stance-ik/pkg/stance_ik_motion*`), which the package's `retarget` loads the first
//! time it is called, so that a page that only poses downloads the solver alone. Everything
//! here is plain Rust, tested natively; `js.rs` converts to and from JavaScript values.
//!
//! The body is built here again from its recipe ([`stance_js::Body::recipe_json`]): the two
//! modules share no memory, and the recipe builds the same joints in the same DOF order.

#![warn(missing_docs)]

#[cfg(target_arch = "wasm32")]
mod js;

use serde_json::Value;
use stance_js::{Body, JsResult};

/// A clip retargeted onto a body: one posture (DOF values) per frame of the source.
#[derive(Debug, Clone)]
pub struct RetargetedClip {
    /// Seconds per frame (the source's).
    pub frame_time: f64,
    /// Number of frames (the source's).
    pub frame_count: usize,
    /// DOF values, frame after frame (`frame_count * dof_count`).
    pub values: Vec<f64>,
    /// The contacts held and the run's figures (JSON: `contacts` as `{joint, part, start, end,
    /// point}`, `iterations`, `notes`).
    pub report: Value,
}

/// Retargets a BVH clip (text) onto the H-Anim body a recipe describes, holding foot contacts
/// (`contacts`) or copying rotations only.
pub fn retarget_bvh(recipe: &str, bvh: &str, contacts: bool) -> JsResult<RetargetedClip> {
    let body = Body::from_recipe(recipe)?;
    let humanoid = body
        .humanoid
        .as_ref()
        .ok_or("retarget: the skeleton must be an H-Anim body (hanim or fromSkin)")?;
    let clip = stance_motion::bvh::read_bvh(
        bvh.as_bytes(),
        "clip",
        &stance_motion::bvh::BvhLimits::default(),
    )
    .map_err(|e| format!("bvh: {e}"))?;
    let options = stance_motion::RetargetOptions {
        contacts: contacts.then(stance_motion::ContactSettings::default),
        ..Default::default()
    };
    let result =
        stance_motion::retarget(&clip, humanoid, &options).map_err(|e| format!("retarget: {e}"))?;
    let values = result
        .postures
        .iter()
        .flat_map(|p| p.values().iter().copied())
        .collect();
    let report = serde_json::json!({
        "contacts": result.contacts.iter().map(|c| serde_json::json!({
            "joint": c.joint, "part": c.part, "start": c.start, "end": c.end,
            "slides": c.slides, "point": [c.point.x, c.point.y, c.point.z],
        })).collect::<Vec<_>>(),
        "iterations": result.iterations,
        "notes": clip.notes.iter().chain(&result.notes).collect::<Vec<_>>(),
    });
    Ok(RetargetedClip {
        frame_time: clip.frame_time,
        frame_count: clip.frame_count(),
        values,
        report,
    })
}
