//! `stance solve FILE.json`: read a problem file (format in `docs/problem-format.md`), solve
//! it, print one JSON object with `joints`, `posture` and `report`; or read a document or a
//! scene (`docs/document-format.md`) and solve each character's tasks on the H-Anim default
//! body from its posture: one such object per character, and the scene with the solved
//! postures written with `--out`.

use std::path::PathBuf;

use anyhow::{Context, Result, anyhow, bail};
use glam::DVec3;
use serde_json::{Value, json};
use stance_document::{
    CharacterPoint, JoinedProblem, PostureValues, Problem, Scene, joined_groups,
};
use stance_hanim::{LevelOfArticulation, SkeletonOptions, default_skeleton};
use stance_ik::{Frames, Posture, SolveReport};

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
/// joints in the character's own frame (its placement puts it in the scene). Characters that
/// tasks between characters join are solved together, as one problem over their bodies
/// (`stance_document::JoinedProblem`): each of them says with whom (`"solved_with"`) and which
/// of its tasks the joined solve left out (`"left_out"`), and `"between"` says how far apart
/// each such task's points ended (m).
/// Its collision tasks hold it off the scene's props (in its own frame).
fn solve_scene(args: &SolveArgs, text: &str) -> Result<Value> {
    let mut scene = Scene::from_json(text).map_err(|e| anyhow!("{e}"))?;
    let loa = LevelOfArticulation::from_number(args.loa)
        .ok_or_else(|| anyhow!("--loa {}: expected 1, 2, 3 or 4", args.loa))?;
    let body = default_skeleton(&SkeletonOptions {
        loa,
        ..SkeletonOptions::default()
    })?
    .skeleton;
    let problems = character_problems(&scene, &body)?;
    let mut solved: Vec<Value> = vec![Value::Null; scene.characters.len()];
    let mut postures: Vec<Option<Posture>> = vec![None; scene.characters.len()];
    for group in joined_groups(&scene) {
        for (i, posture, report, left_out) in solve_group(&scene, &problems, &group)? {
            let character = &scene.characters[i];
            let mut out = problems[i].solution_json(&posture, &report);
            if let Some(o) = out.as_object_mut() {
                o.insert("name".into(), json!(character.name));
                o.insert("placement".into(), character.placement.to_json_value());
                if group.len() > 1 {
                    let with: Vec<usize> = group.iter().copied().filter(|&j| j != i).collect();
                    o.insert("solved_with".into(), json!(with));
                    o.insert("left_out".into(), json!(left_out));
                }
            }
            solved[i] = out;
            postures[i] = Some(posture);
        }
    }
    let between = between_distances(&scene, &problems, &postures);
    for (character, (problem, posture)) in scene
        .characters
        .iter_mut()
        .zip(problems.iter().zip(&postures))
    {
        if let Some(posture) = posture {
            character.document.posture = PostureValues::from_posture(&problem.skeleton, posture);
        }
    }
    // Written back whole: its props' files too (`files`), as they came.
    if let Some(path) = &args.out {
        std::fs::write(path, scene.to_json(true))
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    let mut out = json!({ "characters": solved });
    if !scene.between.is_empty()
        && let Some(o) = out.as_object_mut()
    {
        o.insert("between".into(), json!(between));
    }
    Ok(out)
}

/// Each character's problem on `body` from its document, its collision tasks holding it off
/// the scene's props (in its own frame).
fn character_problems(scene: &Scene, body: &stance_ik::Skeleton) -> Result<Vec<Problem>> {
    let mut problems = Vec::with_capacity(scene.characters.len());
    for (i, character) in scene.characters.iter().enumerate() {
        let mut problem = Problem::from_document(&character.document, body.clone())
            .map_err(|e| anyhow!("character {i} ({}): {e}", character.name))?;
        let character_from_scene = character.placement.scene_from_character().inverse();
        let props: Vec<_> = scene
            .props
            .iter()
            .map(|prop| prop.obstacle(character_from_scene))
            .collect();
        problem.set_obstacles(&props);
        problems.push(problem);
    }
    Ok(problems)
}

/// A character solved: its index in the scene, its posture, the solve's report, and which of
/// its tasks a joined solve left out.
type Solved = (usize, Posture, SolveReport, Vec<String>);

/// The characters of `group` (indices into the scene) solved: one alone, several joined as
/// one problem.
fn solve_group(scene: &Scene, problems: &[Problem], group: &[usize]) -> Result<Vec<Solved>> {
    let named = |e: &dyn std::fmt::Display| {
        let names: Vec<String> = group
            .iter()
            .map(|&i| {
                let name = scene.characters.get(i).map_or("?", |c| c.name.as_str());
                format!("character {i} ({name})")
            })
            .collect();
        anyhow!("{}: {e}", names.join(" and "))
    };
    let problem = |i: usize| {
        problems
            .get(i)
            .ok_or_else(|| named(&format_args!("no character {i}")))
    };
    if let [only] = group[..] {
        let (posture, report) = problem(only)?.solve().map_err(|e| named(&e))?;
        return Ok(vec![(only, posture, report, Vec::new())]);
    }
    let members: Vec<Problem> = group
        .iter()
        .map(|&i| problem(i).cloned())
        .collect::<Result<_>>()?;
    let joined = JoinedProblem::new(scene, group, &members).map_err(|e| named(&e))?;
    let (each, report) = joined.solve().map_err(|e| named(&e))?;
    Ok(group
        .iter()
        .zip(each)
        .map(|(&i, posture)| {
            let prefix = format!("character {i} (");
            let left: Vec<String> = joined
                .left_out
                .iter()
                .filter(|m| m.starts_with(&prefix))
                .cloned()
                .collect();
            (i, posture, report.clone(), left)
        })
        .collect())
}

/// How far apart each task between characters left its two points (m, in the scene), each
/// character's posture placed by its placement; `null` for a joint its body lacks.
fn between_distances(
    scene: &Scene,
    problems: &[Problem],
    postures: &[Option<Posture>],
) -> Vec<Value> {
    let point = |p: &CharacterPoint| -> Option<DVec3> {
        let problem = problems.get(p.character)?;
        let posture = postures.get(p.character)?.as_ref()?;
        let joint = problem.skeleton.joint_index(&p.joint)?;
        let frames = Frames::new(&problem.skeleton, posture);
        let local = frames.point(joint, DVec3::from_array(p.point));
        let placement = scene.characters.get(p.character)?.placement;
        Some(placement.scene_from_character().transform_point3(local))
    };
    scene
        .between
        .iter()
        .map(|task| {
            let distance = point(&task.a)
                .zip(point(&task.b))
                .map(|(a, b)| (a - b).length());
            json!({ "level": task.level, "distance": distance })
        })
        .collect()
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
