//! `stance lift K.json --out DOC.json`: postures lifted from OpenPose keypoints
//! (`stance_lift`): each keypoint kept on its camera ray, the feet on the floor, comfort below;
//! the document keeps the camera as its saved view. One person gives a document; several give
//! a scene of one character each (or `--person N` lifts one of them).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, anyhow, bail};
use clap::Args;
use stance_hanim::{LevelOfArticulation, SkeletonOptions, default_skeleton};
use stance_lift::{ObservedPose, flip_depth, lift, lift_people, lifted_scene, solve};
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
    /// Lift only this person of the file (1 for the first): a document. Without it, a file
    /// of several people gives a scene with a character each.
    #[arg(long)]
    pub person: Option<usize>,
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
    let chosen = match args.person {
        Some(n) => {
            let count = observed.people.len();
            let person = n
                .checked_sub(1)
                .and_then(|i| observed.people.get(i))
                .ok_or_else(|| {
                    anyhow!("--person {n}: the file lists {count} people (1 to {count})")
                })?;
            Some(person)
        }
        None if observed.people.len() == 1 => observed.people.first(),
        None => None,
    };
    if chosen.is_none() && !args.flip.is_empty() {
        bail!(
            "--flip: {} people in {}: pick the one to flip with --person N",
            observed.people.len(),
            args.keypoints.display()
        );
    }
    let body = default_skeleton(&SkeletonOptions {
        loa,
        ..SkeletonOptions::default()
    })?;
    let skeleton = &body.skeleton;
    if args.out == args.keypoints {
        bail!("--out {}: the keypoints file itself", args.out.display());
    }
    let Some(person) = chosen else {
        return lift_scene(&args, &observed, skeleton, camera);
    };
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
        "{}: {} keypoints of person {} lifted with {camera_words}, feet on the floor: {}; {} iterations{}; lift {:.1} ms",
        args.out.display(),
        lifted.keypoints_used,
        args.person.unwrap_or(1),
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

/// Every person of `observed` lifted through one camera, written as a scene of one character
/// each.
fn lift_scene(
    args: &LiftArgs,
    observed: &ObservedPose,
    skeleton: &stance_ik::Skeleton,
    camera: Option<OrbitCamera>,
) -> Result<()> {
    let started = Instant::now();
    let people = lift_people(skeleton, observed, camera)
        .map_err(|e| anyhow!("{}: {e}", args.keypoints.display()))?;
    let lift_time = started.elapsed();
    let scene = lifted_scene(&people);
    std::fs::write(&args.out, scene.to_json(true))
        .with_context(|| format!("cannot write {}", args.out.display()))?;
    let fitted = people.first().is_some_and(|p| p.camera_fitted);
    eprintln!(
        "{}: {} people lifted as {} characters of one scene, through {}; keypoints used {}; lift {:.1} ms",
        args.out.display(),
        people.len(),
        scene.characters.len(),
        if camera.is_some() {
            "the camera of --camera"
        } else if fitted {
            "a camera fitted to the first person"
        } else {
            "the camera the keypoints file carries"
        },
        people
            .iter()
            .map(|p| p.keypoints_used.to_string())
            .collect::<Vec<_>>()
            .join(", "),
        lift_time.as_secs_f64() * 1e3
    );
    Ok(())
}
