//! `stance retarget`: clips (BVH, glTF animations) onto an avatar, one file or a directory
//! of them in parallel, with a report and the joints' world positions per frame.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use anyhow::{Context, Result, anyhow, bail};
use serde_json::{Value, json};
use stance_asset::{Avatar, LoadOptions, read_clip};
use stance_hanim::{HumanoidSkeleton, LevelOfArticulation, SkeletonOptions};
use stance_motion::bvh::{BvhWriteOptions, write_bvh};
use stance_motion::retarget::{joint_positions, metrics};
use stance_motion::{Clip, ContactSettings, RestMatch, RetargetOptions, Retargeted, retarget};

/// `stance retarget CLIP --to AVATAR --out OUT`.
#[derive(clap::Args, Debug)]
pub struct RetargetArgs {
    /// A clip (.bvh, .glb, .gltf: its first animation) or a directory of them.
    pub clip: PathBuf,
    /// The avatar to play it on (.glb, .gltf, .vrm), or `default` for the generated
    /// default avatar.
    #[arg(long)]
    pub to: String,
    /// Output: .glb (the avatar with the animation) or .bvh (H-Anim names). For a directory
    /// of clips, a directory (created) that receives `<clip>.<format>`.
    #[arg(long)]
    pub out: PathBuf,
    /// Output format for a directory of clips.
    #[arg(long, value_enum, default_value = "glb")]
    pub format: OutFormat,
    /// Foot contacts: detected and held (`auto`), or the plain rotation copy (`none`).
    #[arg(long, value_enum, default_value = "auto")]
    pub contacts: ContactsArg,
    /// How the rest poses are matched.
    #[arg(long, value_enum, default_value = "directions")]
    pub rest_match: RestMatchArg,
    /// Raise (+) or lower (-) both arms' rest match by this many degrees (an A-pose clip on
    /// a T-pose avatar, or the reverse, when the bone directions are not enough).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub arms: f64,
    /// Level of articulation of the target's solver skeleton (1 to 4).
    #[arg(long, default_value_t = 2)]
    pub loa: u8,
    /// A JSON report: contacts, per-frame residuals per level, metrics, time (for a
    /// directory: a directory of `<clip>.json`).
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// World positions of the target's mapped joints per frame (JSON; for a directory: a
    /// directory of `<clip>.json`).
    #[arg(long)]
    pub joints_out: Option<PathBuf>,
    /// Worker threads for a directory (default: the machine's cores).
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Only this share of a directory, `I/N` (0-based I): the clips whose index in the
    /// sorted listing is I modulo N. N machines running the same command with 0/N..N-1/N
    /// process a library together, each file exactly once.
    #[arg(long)]
    pub shard: Option<String>,
}

/// Output formats.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutFormat {
    /// The avatar with the animation.
    Glb,
    /// BVH with H-Anim joint names.
    Bvh,
}

/// `--contacts`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ContactsArg {
    /// Detected and held.
    Auto,
    /// None: the plain rotation copy.
    None,
}

/// `--rest-match`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum RestMatchArg {
    /// Bone directions at rest.
    Directions,
    /// The same rest pose.
    Same,
    /// The clip's first frame is the target's rest.
    FirstFrame,
}

/// The target: the avatar file and its solver skeleton.
struct Target {
    avatar: Avatar,
    skeleton: HumanoidSkeleton,
    name: String,
}

fn load_target(to: &str, loa: u8) -> Result<Target> {
    let avatar = if to == "default" {
        stance_asset::make_default_avatar().context("making the default avatar")?
    } else {
        crate::avatar::load(Path::new(to), &LoadOptions::default())?
    };
    let loa = LevelOfArticulation::from_number(loa)
        .ok_or_else(|| anyhow!("--loa must be 1 to 4, got {loa}"))?;
    let skeleton = avatar
        .skeleton(&SkeletonOptions {
            loa,
            ..Default::default()
        })
        .with_context(|| format!("building the skeleton of {to}"))?;
    Ok(Target {
        avatar,
        skeleton,
        name: to.to_owned(),
    })
}

/// Reads a clip: BVH, or the first animation of a glTF/GLB/VRM (`stance_asset::read_clip`).
pub fn load_clip(path: &Path) -> Result<Clip> {
    let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    let name = path.to_string_lossy();
    let mut resolve = crate::avatar::resolver_next_to(path);
    read_clip(&name, &bytes, &LoadOptions::default(), &mut resolve)
        .with_context(|| format!("reading the clip {}", path.display()))
}

fn extension(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default()
}

fn options(args: &RetargetArgs) -> RetargetOptions {
    RetargetOptions {
        rest_match: match args.rest_match {
            RestMatchArg::Directions => RestMatch::Directions,
            RestMatchArg::Same => RestMatch::Same,
            RestMatchArg::FirstFrame => RestMatch::FirstFrame,
        },
        contacts: (args.contacts == ContactsArg::Auto).then(ContactSettings::default),
        ..RetargetOptions::default()
    }
    .with_arm_lift(args.arms)
}

/// What one clip produced.
struct Outputs<'a> {
    out: &'a Path,
    report: Option<&'a Path>,
    joints: Option<&'a Path>,
}

fn retarget_one(
    path: &Path,
    target: &Target,
    options: &RetargetOptions,
    outputs: &Outputs,
) -> Result<Value> {
    let started = Instant::now();
    let clip = load_clip(path)?;
    let loaded = started.elapsed().as_secs_f64();
    let solve_started = Instant::now();
    let result = retarget(&clip, &target.skeleton, options)
        .with_context(|| format!("retargeting {}", path.display()))?;
    let solve_secs = solve_started.elapsed().as_secs_f64();
    let write_started = Instant::now();
    write_clip(outputs.out, &clip, target, &result)?;
    if let Some(j) = outputs.joints {
        write_json(j, &joints_json(target, &result))?;
    }
    let write_secs = write_started.elapsed().as_secs_f64();
    let ease = options
        .contacts
        .map_or(0, |s| s.ease_frames(clip.frame_time));
    let m = metrics(&clip, &target.skeleton, &result, ease);
    let report = json!({
        "clip": path.display().to_string(),
        "target": target.name,
        "frames": clip.frame_count(),
        "fps": clip.fps(),
        "duration_s": clip.duration(),
        "contacts": result.contacts.iter().map(|c| json!({
            "joint": c.joint, "part": c.part, "start": c.start, "end": c.end,
            "slides": c.slides,
            "point": [c.point.x, c.point.y, c.point.z],
            "position": [c.position.x, c.position.y, c.position.z],
        })).collect::<Vec<_>>(),
        "reference_frames": result.reference_frames,
        "thresholds": result.thresholds,
        "levels": result.levels,
        "residuals": result.residuals,
        "iterations": result.iterations,
        "root_scale": result.placement.root_scale,
        "stride_scale": result.placement.stride_scale,
        "metrics": m,
        "time_s": {"load": loaded, "retarget": solve_secs, "write": write_secs},
        "frames_per_second": clip.frame_count() as f64 / solve_secs.max(1e-12),
        "notes": clip.notes.iter().chain(&result.notes).collect::<Vec<_>>(),
    });
    if let Some(r) = outputs.report {
        write_json(r, &report)?;
    }
    Ok(report)
}

fn write_clip(out: &Path, clip: &Clip, target: &Target, result: &Retargeted) -> Result<()> {
    let bytes = match extension(out).as_str() {
        "glb" => stance_asset::export_glb_animation(
            &target.avatar,
            &target.skeleton,
            &result.postures,
            clip.frame_time,
            &clip.name,
        )
        .context("writing the animation")?,
        "bvh" => {
            let baked = Clip::from_postures(
                &clip.name,
                &target.skeleton,
                &result.postures,
                clip.frame_time,
            );
            write_bvh(&baked, &BvhWriteOptions::default()).into_bytes()
        }
        _ => bail!("{}: the output is .glb or .bvh", out.display()),
    };
    std::fs::write(out, bytes).with_context(|| format!("writing {}", out.display()))
}

/// `{"fps", "joints": [H-Anim names], "frames": [[[x, y, z], ...], ...]}`: the mapped joints
/// of the target (those with a node in the avatar), metres, H-Anim frame.
fn joints_json(target: &Target, result: &Retargeted) -> Value {
    let joints: Vec<usize> = (0..target.skeleton.joints.len())
        .filter(|&k| target.skeleton.joints[k].source.is_some())
        .collect();
    let names: Vec<&str> = joints
        .iter()
        .map(|&k| target.skeleton.joints[k].hanim)
        .collect();
    let frames: Vec<Vec<[f64; 3]>> = joint_positions(&target.skeleton, &result.postures, &joints)
        .into_iter()
        .map(|f| f.into_iter().map(|p| p.to_array()).collect())
        .collect();
    json!({"fps": 1.0 / result.frame_time, "joints": names, "frames": frames})
}

fn write_json(path: &Path, value: &Value) -> Result<()> {
    let text = serde_json::to_string(value)?;
    std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))
}

fn parse_shard(shard: &str) -> Result<(usize, usize)> {
    let (i, n) = shard
        .split_once('/')
        .ok_or_else(|| anyhow!("--shard is I/N, got {shard}"))?;
    let (i, n): (usize, usize) = (i.trim().parse()?, n.trim().parse()?);
    if n == 0 || i >= n {
        bail!("--shard I/N needs 0 <= I < N, got {shard}");
    }
    Ok((i, n))
}

/// The clips of a directory, sorted, in this shard.
fn clips_in(dir: &Path, shard: Option<(usize, usize)>) -> Result<Vec<PathBuf>> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("listing {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| matches!(extension(p).as_str(), "bvh" | "glb" | "gltf"))
        .collect();
    files.sort();
    let (i, n) = shard.unwrap_or((0, 1));
    Ok(files
        .into_iter()
        .enumerate()
        .filter(|(k, _)| k % n == i)
        .map(|(_, p)| p)
        .collect())
}

/// Runs `stance retarget`.
pub fn run(args: RetargetArgs) -> Result<()> {
    let target = load_target(&args.to, args.loa)?;
    let options = options(&args);
    if !args.clip.is_dir() {
        let report = retarget_one(
            &args.clip,
            &target,
            &options,
            &Outputs {
                out: &args.out,
                report: args.report.as_deref(),
                joints: args.joints_out.as_deref(),
            },
        )?;
        eprintln!("{}", summary(&report));
        return Ok(());
    }
    let shard = args.shard.as_deref().map(parse_shard).transpose()?;
    let clips = clips_in(&args.clip, shard)?;
    for dir in [
        Some(&args.out),
        args.report.as_ref(),
        args.joints_out.as_ref(),
    ]
    .into_iter()
    .flatten()
    {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let ext = match args.format {
        OutFormat::Glb => "glb",
        OutFormat::Bvh => "bvh",
    };
    let jobs = args
        .jobs
        .or_else(|| std::thread::available_parallelism().ok().map(|n| n.get()))
        .unwrap_or(1)
        .clamp(1, clips.len().max(1));
    let next = AtomicUsize::new(0);
    let started = Instant::now();
    let failures: Vec<String> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..jobs)
            .map(|_| {
                scope.spawn(|| {
                    let mut failed = Vec::new();
                    loop {
                        let k = next.fetch_add(1, Ordering::Relaxed);
                        let Some(clip) = clips.get(k) else {
                            break;
                        };
                        let stem = clip.file_stem().map(|s| s.to_string_lossy().into_owned());
                        let stem = stem.unwrap_or_else(|| format!("clip{k}"));
                        let out = args.out.join(format!("{stem}.{ext}"));
                        let report = args.report.as_ref().map(|d| d.join(format!("{stem}.json")));
                        let joints = args
                            .joints_out
                            .as_ref()
                            .map(|d| d.join(format!("{stem}.json")));
                        let outputs = Outputs {
                            out: &out,
                            report: report.as_deref(),
                            joints: joints.as_deref(),
                        };
                        match retarget_one(clip, &target, &options, &outputs) {
                            Ok(r) => eprintln!("{}", summary(&r)),
                            Err(e) => failed.push(format!("{}: {e:#}", clip.display())),
                        }
                    }
                    failed
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|w| w.join().unwrap_or_else(|_| vec!["a worker stopped".into()]))
            .collect()
    });
    eprintln!(
        "{} clip(s) on {jobs} thread(s) in {:.2} s, {} failed",
        clips.len(),
        started.elapsed().as_secs_f64(),
        failures.len()
    );
    if !failures.is_empty() {
        bail!("{}", failures.join("\n"));
    }
    Ok(())
}

fn summary(report: &Value) -> String {
    format!(
        "{}: {} frames, {} contacts, {:.0} frames/s, foot drift max {:.2} mm (copy {:.2} mm)",
        report["clip"].as_str().unwrap_or("?"),
        report["frames"],
        report["contacts"].as_array().map_or(0, Vec::len),
        report["frames_per_second"].as_f64().unwrap_or(0.0),
        report["metrics"]["output"]["max_drift"]
            .as_f64()
            .unwrap_or(0.0)
            * 1e3,
        report["metrics"]["copy"]["max_drift"]
            .as_f64()
            .unwrap_or(0.0)
            * 1e3,
    )
}
