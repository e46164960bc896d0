//! `stance solve FILE.json`: read a problem file (format in `docs/problem-format.md`), solve
//! it, print one JSON object with `joints`, `posture` and `report`; or read a document or a
//! scene (`docs/document-format.md`) and solve each character's tasks on the H-Anim default
//! body from its posture: one such object per character, and the scene with the solved
//! postures written with `--out`.

use std::path::PathBuf;

use anyhow::{Context, Result, anyhow, bail};
use serde_json::{Value, json};
use stance_document::{PostureValues, Problem, Scene};
use stance_hanim::{LevelOfArticulation, SkeletonOptions, default_skeleton};

#[derive(clap::Args, Debug)]
pub struct SolveArgs {
    /// The problem file (JSON), or a document or scene (each character's tasks solved on the
    /// H-Anim default body, from its posture).
    pub problem: PathBuf,
    /// Pretty-print the output.
    #[arg(long)]
    pub pretty: bool,
    /// A document or scene: the level of articulation of the default body (1-4).
    #[arg(long, default_value_t = 2)]
    pub loa: u8,
    /// A document or scene: write it here with every character's solved posture.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

pub fn run(args: SolveArgs) -> Result<()> {
    let path = &args.problem;
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    // A problem file has a skeleton; text that is not JSON at all gets the problem file's
    // message (which names where it breaks).
    let root: Option<Value> = serde_json::from_str(&text).ok();
    let out = if root.is_none_or(|root| root.get("skeleton").is_some()) {
        if args.out.is_some() {
            bail!(
                "--out writes a document or scene; {} is a problem file",
                path.display()
            );
        }
        let problem = parse_problem(&text)
            .with_context(|| format!("invalid problem file {}", path.display()))?;
        let (posture, report) = problem.solve()?;
        problem.solution_json(&posture, &report)
    } else {
        solve_scene(&args, &text).with_context(|| format!("{}", path.display()))?
    };
    let text = if args.pretty {
        serde_json::to_string_pretty(&out)?
    } else {
        serde_json::to_string(&out)?
    };
    println!("{text}");
    Ok(())
}

/// Each character of the scene (a document: a scene of one) solved on the default body:
/// `{"characters": [{"name", "placement", "joints", "posture", "report", "tasks"}...]}`, the
/// joints in the character's own frame (its placement puts it in the scene); its collision
/// tasks hold it off the scene's props.
fn solve_scene(args: &SolveArgs, text: &str) -> Result<Value> {
    let mut scene = Scene::from_json(text).map_err(|e| anyhow!("{e}"))?;
    let loa = LevelOfArticulation::from_number(args.loa)
        .ok_or_else(|| anyhow!("--loa {}: expected 1, 2, 3 or 4", args.loa))?;
    let body = default_skeleton(&SkeletonOptions {
        loa,
        ..SkeletonOptions::default()
    })?
    .skeleton;
    let mut solved = Vec::with_capacity(scene.characters.len());
    for (i, character) in scene.characters.iter_mut().enumerate() {
        let named = |e: &dyn std::fmt::Display| anyhow!("character {i} ({}): {e}", character.name);
        let mut problem =
            Problem::from_document(&character.document, body.clone()).map_err(|e| named(&e))?;
        // Its collision tasks hold it off the scene's props, in its own frame.
        let character_from_scene = character.placement.scene_from_character().inverse();
        let props: Vec<_> = scene
            .props
            .iter()
            .map(|prop| prop.obstacle(character_from_scene))
            .collect();
        problem.set_obstacles(&props);
        let (posture, report) = problem.solve().map_err(|e| named(&e))?;
        let mut out = problem.solution_json(&posture, &report);
        if let Some(o) = out.as_object_mut() {
            o.insert("name".into(), json!(character.name));
            o.insert("placement".into(), character.placement.to_json_value());
        }
        character.document.posture = PostureValues::from_posture(&problem.skeleton, &posture);
        solved.push(out);
    }
    if let Some(path) = &args.out {
        std::fs::write(path, scene.to_json(true))
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    Ok(json!({ "characters": solved }))
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
