//! `stance lift K.json --out DOC.json`: a posture lifted from OpenPose keypoints
//! (`stance_lift`): each keypoint of the first person kept on its camera ray, the feet on the
//! floor, comfort below; the document keeps the camera as its saved view.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, anyhow, bail};
use clap::Args;
use stance_hanim::{LevelOfArticulation, SkeletonOptions, default_skeleton};
use stance_lift::{ObservedPose, flip_depth, lift, solve};
use stance_render::OrbitCamera;

use crate::render::parse_size;

/// `stance lift K.json --out DOC.json [--camera CAMERA] [--size WxH] [--flip JOINT]... [--loa N]`
#[derive(Debug, Args)]
pub struct LiftArgs {
    /// The OpenPose keypoints JSON (what `stance render --map openpose --keypoints-out`
    /// writes; pixels or fractions of the canvas).
    pub keypoints: PathBuf,
    /// The document to write.
    #[arg(long)]
    pub out: PathBuf,
    /// The camera the keypoints were seen with, as a document's saved view: a JSON object
    /// `{"target": [x, y, z], "yaw": rad, "pitch": rad, "distance": m, "orthographic": false}`,
    /// or a file holding one or a document with a `camera`. Without it: the camera the
    /// keypoints file carries (`stance_camera`), else one fitted to the keypoints.
    #[arg(long)]
    pub camera: Option<String>,
    /// The image's size when the keypoints file gives none (`canvas_width`, `canvas_height`).
    #[arg(long)]
    pub size: Option<String>,
    /// Mirror the depth of this joint and the limb below it (`r_elbow`, `l_knee`...) about
    /// its parent joint, then solve again: a limb toward the camera instead of away. Repeat
    /// for several.
    #[arg(long)]
    pub flip: Vec<String>,
    /// Level of articulation of the body (1 to 4).
    #[arg(long, default_value_t = 2)]
    pub loa: u8,
}

/// The camera of `--camera`: inline JSON, or a file of it or of a document.
fn camera_arg(text: &str) -> Result<OrbitCamera> {
    let json = if text.trim_start().starts_with('{') {
        text.to_owned()
    } else {
        std::fs::read_to_string(text).with_context(|| format!("--camera: cannot read {text}"))?
    };
    let value: serde_json::Value =
        serde_json::from_str(&json).map_err(|e| anyhow!("--camera: not JSON ({e})"))?;
    let spec = value.get("camera").unwrap_or(&value);
    let spec =
        stance_document::CameraSpec::from_json_value(spec).map_err(|e| anyhow!("--camera: {e}"))?;
    Ok(OrbitCamera::saved(
        spec.target,
        spec.yaw,
        spec.pitch,
        spec.distance,
        spec.orthographic,
    ))
}

pub fn run(args: LiftArgs) -> Result<()> {
    let loa = LevelOfArticulation::from_number(args.loa)
        .ok_or_else(|| anyhow!("--loa {}: expected 1, 2, 3 or 4", args.loa))?;
    let size = args.size.as_deref().map(parse_size).transpose()?;
    let camera = args.camera.as_deref().map(camera_arg).transpose()?;
    let text = std::fs::read_to_string(&args.keypoints)
        .with_context(|| format!("cannot read {}", args.keypoints.display()))?;
    let observed = ObservedPose::from_json(&text, size)
        .map_err(|e| anyhow!("{}: {e}", args.keypoints.display()))?;
    let person = observed
        .first_person()
        .map_err(|e| anyhow!("{}: {e}", args.keypoints.display()))?;
    if observed.people.len() > 1 {
        eprintln!(
            "note: {} people in {}: only the first is lifted (several people come with the scene)",
            observed.people.len(),
            args.keypoints.display()
        );
    }
    let body = default_skeleton(&SkeletonOptions {
        loa,
        ..SkeletonOptions::default()
    })?;
    let skeleton = &body.skeleton;
    let started = Instant::now();
    let mut lifted = lift(
        skeleton,
        person,
        observed.size_px,
        camera.or(observed.camera),
    )
    .map_err(|e| anyhow!("{}: {e}", args.keypoints.display()))?;
    let lift_time = started.elapsed();
    for joint in &args.flip {
        let flipped = flip_depth(skeleton, &lifted.posture, &lifted.camera, joint)
            .map_err(|e| anyhow!("--flip {joint}: {e}"))?;
        let (posture, report) = solve(skeleton, &lifted.document, &flipped)?;
        lifted.posture = posture;
        lifted.report = report;
    }
    lifted.document.posture =
        stance_document::PostureValues::from_posture(skeleton, &lifted.posture);
    if args.out == args.keypoints {
        bail!("--out {}: the keypoints file itself", args.out.display());
    }
    std::fs::write(&args.out, lifted.document.to_json(true))
        .with_context(|| format!("cannot write {}", args.out.display()))?;
    let camera_words = if lifted.camera_fitted {
        "a camera fitted to the keypoints"
    } else if camera.is_some() {
        "the camera of --camera"
    } else {
        "the camera the keypoints file carries"
    };
    eprintln!(
        "{}: {} keypoints of the first person lifted with {camera_words}, feet on the floor: {}; {} iterations{}; lift {:.1} ms",
        args.out.display(),
        lifted.keypoints_used,
        if lifted.standing.is_empty() {
            "none".to_owned()
        } else {
            lifted.standing.join(", ")
        },
        lifted.report.iterations,
        if lifted.flips.is_empty() {
            String::new()
        } else {
            format!(", depth flipped at {}", lifted.flips.join(", "))
        },
        lift_time.as_secs_f64() * 1e3
    );
    Ok(())
}
