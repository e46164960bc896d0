//! `stance solve PROBLEM.json`: read a problem file (format in `docs/problem-format.md`),
//! solve it, print one JSON object with `joints`, `posture` and `report`.

use std::collections::BTreeMap;
use std::path::PathBuf;

use anyhow::{Context, Result, anyhow};
use serde_json::{Map, Value, json};
use stance_document::Problem;
use stance_ik::{Frames, Posture, Skeleton, SolveReport};

#[derive(clap::Args, Debug)]
pub struct SolveArgs {
    /// The problem file (JSON).
    pub problem: PathBuf,
    /// Pretty-print the output.
    #[arg(long)]
    pub pretty: bool,
}

pub fn run(args: SolveArgs) -> Result<()> {
    let problem = load_problem(&args.problem)?;
    let (posture, report) = problem.solve()?;
    let mut out = solution_json(&problem.skeleton, &posture, &report)?;
    if !problem.limb_starts.is_empty()
        && let Some(o) = out.as_object_mut()
    {
        let (_, starts) = problem.start_posture();
        let limbs: Vec<Value> = problem
            .limb_starts
            .iter()
            .zip(starts)
            .map(|(t, s)| {
                json!({
                    "joints": s.joints,
                    "swivel": t.limb.swivel_angle(&problem.skeleton, &posture),
                    "start_swivel": s.swivel,
                    "reached": s.reached,
                    "within_limits": s.within_limits,
                })
            })
            .collect();
        o.insert("limbs".to_owned(), Value::Array(limbs));
    }
    let text = if args.pretty {
        serde_json::to_string_pretty(&out)?
    } else {
        serde_json::to_string(&out)?
    };
    println!("{text}");
    Ok(())
}

/// `{"joints": {name: [x,y,z]}, "posture": {joint: {dof: value}}, "report": {...}}`.
pub fn solution_json(
    skeleton: &Skeleton,
    posture: &Posture,
    report: &SolveReport,
) -> Result<Value> {
    let frames = Frames::new(skeleton, posture);
    let mut joints = Map::new();
    for (j, joint) in skeleton.joints().iter().enumerate() {
        let p = frames.joint_position[j];
        joints.insert(joint.name.clone(), json!([p.x, p.y, p.z]));
    }
    Ok(json!({
        "joints": joints,
        "posture": posture_json(skeleton, posture),
        "report": serde_json::to_value(report)?,
    }))
}

fn posture_json(skeleton: &Skeleton, posture: &Posture) -> Value {
    let mut out = Map::new();
    for joint in skeleton.joints() {
        if joint.dofs.is_empty() {
            continue;
        }
        let mut dofs = BTreeMap::new();
        for (k, d) in joint.dofs.iter().enumerate() {
            dofs.insert(d.name().to_owned(), posture.values()[joint.dof_start + k]);
        }
        out.insert(joint.name.clone(), json!(dofs));
    }
    Value::Object(out)
}

pub fn load_problem(path: &std::path::Path) -> Result<Problem> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    parse_problem(&text).with_context(|| format!("invalid problem file {}", path.display()))
}

/// Parses a problem file; errors name the offending field (`tasks[2].target`).
pub fn parse_problem(text: &str) -> Result<Problem> {
    Problem::from_json(text).map_err(|e| anyhow!("{e}"))
}
