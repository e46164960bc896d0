//! `stance solve PROBLEM.json`: read a problem file (format in `docs/problem-format.md`),
//! solve it, print one JSON object with `joints`, `posture` and `report`.

use std::collections::BTreeMap;
use std::path::PathBuf;

use anyhow::{Context, Result, anyhow, bail};
use glam::{DQuat, DVec3};
use serde_json::{Map, Value, json};
use stance_document::{PostureValues, TaskKindSpec, TaskSpec};
use stance_ik::{
    Damping, Dof, Frames, JointDef, Limb, LimbGoal, Posture, Skeleton, SolveReport, Solver,
    SolverSettings, Task,
};

#[derive(clap::Args, Debug)]
pub struct SolveArgs {
    /// The problem file (JSON).
    pub problem: PathBuf,
    /// Pretty-print the output.
    #[arg(long)]
    pub pretty: bool,
}

/// A parsed problem file.
#[derive(Debug, Clone)]
pub struct Problem {
    pub skeleton: Skeleton,
    pub tasks: Vec<Task>,
    pub settings: SolverSettings,
    /// Per-level damping (`settings.levels`).
    pub level_damping: BTreeMap<u32, Damping>,
    pub start: Posture,
    /// The `limb` tasks (each also a position task in `tasks`), in file order.
    pub limb_tasks: Vec<LimbTask>,
    /// Limbs for the solver's hybrid restart: those of the limb tasks, plus every H-Anim limb
    /// of the skeleton with `settings.hybrid`.
    pub hybrid_limbs: Vec<Limb>,
}

/// A `{"kind": "limb"}` task: closed-form start for the limb, then the variational solve.
#[derive(Debug, Clone)]
pub struct LimbTask {
    pub limb: Limb,
    pub joints: [String; 3],
    pub goal: LimbGoal,
    /// Requested swivel angle (radians); `None`: keep the start posture's.
    pub swivel: Option<f64>,
}

/// H-Anim limb shorthands: (name, upper, middle, end candidates in order of preference).
const HANIM_LIMBS: &[(&str, &str, &str, &[&str])] = &[
    (
        "l_arm",
        "l_shoulder",
        "l_elbow",
        &["l_radiocarpal", "l_wrist"],
    ),
    (
        "r_arm",
        "r_shoulder",
        "r_elbow",
        &["r_radiocarpal", "r_wrist"],
    ),
    ("l_leg", "l_hip", "l_knee", &["l_talocrural", "l_ankle"]),
    ("r_leg", "r_hip", "r_knee", &["r_talocrural", "r_ankle"]),
];

/// Joint names of an H-Anim limb shorthand present in the skeleton.
fn hanim_limb(skeleton: &Skeleton, name: &str) -> Option<[String; 3]> {
    let (_, upper, middle, ends) = HANIM_LIMBS.iter().find(|l| l.0 == name)?;
    let end = ends.iter().find(|e| skeleton.joint_index(e).is_some())?;
    Some([(*upper).to_owned(), (*middle).to_owned(), (*end).to_owned()])
}

/// What the closed form did for one limb task.
#[derive(Debug, Clone)]
pub struct LimbStart {
    pub joints: [String; 3],
    /// Swivel angle of the closed-form start posture.
    pub swivel: f64,
    pub reached: bool,
    pub within_limits: bool,
}

pub fn run(args: SolveArgs) -> Result<()> {
    let problem = load_problem(&args.problem)?;
    let (posture, report) = solve(&problem)?;
    let mut out = solution_json(&problem.skeleton, &posture, &report)?;
    if !problem.limb_tasks.is_empty()
        && let Some(o) = out.as_object_mut()
    {
        let (_, starts) = start_posture(&problem);
        let limbs: Vec<Value> = problem
            .limb_tasks
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

/// Solves from the problem's start posture (with the limb tasks' closed-form solutions
/// applied, see [`start_posture`]).
pub fn solve(problem: &Problem) -> Result<(Posture, SolveReport)> {
    let (mut posture, _) = start_posture(problem);
    let mut solver = solver_for(problem, problem.settings)?;
    let report = solver.solve(&problem.skeleton, &problem.tasks, &mut posture)?;
    Ok((posture, report))
}

/// The start posture with every limb task's closed-form solution applied in file order (the
/// swivel asked, or the start posture's, moved to the nearest one within the joint limits).
pub fn start_posture(problem: &Problem) -> (Posture, Vec<LimbStart>) {
    let mut posture = problem.start.clone();
    let mut starts = Vec::with_capacity(problem.limb_tasks.len());
    for t in &problem.limb_tasks {
        let frames = Frames::new(&problem.skeleton, &posture);
        let base = t.limb.base(&problem.skeleton, &frames);
        let preferred = t
            .swivel
            .unwrap_or_else(|| t.limb.swivel_angle(&problem.skeleton, &posture));
        let solution = t.limb.solve_within_limits(base, &t.goal, preferred);
        t.limb.apply(&solution, &mut posture);
        starts.push(LimbStart {
            joints: t.joints.clone(),
            swivel: solution.swivel_angle,
            reached: solution.reached,
            within_limits: solution.within_limits,
        });
    }
    (posture, starts)
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
    let root: Value = serde_json::from_str(text).context("not valid JSON")?;
    let root = obj(&root, "the problem")?;
    let skeleton = parse_skeleton(field(root, "skeleton", "")?)?;
    let mut tasks = Vec::new();
    let mut limb_tasks = Vec::new();
    if let Some(v) = root.get("tasks").filter(|v| !v.is_null()) {
        // The fields and their errors are those of `stance_document::TaskSpec` (the editor's
        // document shares the problem file's task format), and so is the conversion: a `limb`
        // task gives its position task on the end joint (and an orientation task when it has
        // one); [`parse_limb_task`] adds the closed-form start.
        let specs = TaskSpec::list_from_json_value(v, "tasks").map_err(|e| anyhow!("{e}"))?;
        for (i, (spec, t)) in specs.iter().zip(arr(v, "tasks")?).enumerate() {
            let at = format!("tasks[{i}]");
            tasks.extend(
                spec.to_solver_tasks(&skeleton, &specs)
                    .map_err(|e| anyhow!("{}", e.within(&at)))?,
            );
            if matches!(spec.kind, TaskKindSpec::Limb { .. }) {
                limb_tasks.push(parse_limb_task(&skeleton, t, &at)?);
            }
        }
    }
    let (settings, hybrid, level_damping) = match root.get("settings") {
        None | Some(Value::Null) => (SolverSettings::default(), false, BTreeMap::new()),
        Some(v) => parse_settings(v)?,
    };
    let mut hybrid_limbs: Vec<Limb> = limb_tasks.iter().map(|t| t.limb.clone()).collect();
    if hybrid {
        for (name, ..) in HANIM_LIMBS {
            if let Some(names) = hanim_limb(&skeleton, name)
                && let Ok(limb) = Limb::from_names(&skeleton, [&names[0], &names[1], &names[2]])
                && !hybrid_limbs.iter().any(|l| l.joints() == limb.joints())
            {
                hybrid_limbs.push(limb);
            }
        }
    }
    let start = match root.get("posture") {
        None | Some(Value::Null) => Posture::rest(&skeleton),
        Some(v) => parse_posture(&skeleton, v, "posture")?,
    };
    for (i, t) in tasks.iter().enumerate() {
        t.validate(&skeleton, i)
            .map_err(|e| anyhow!("tasks[{i}]: {e}"))?;
    }
    Ok(Problem {
        skeleton,
        tasks,
        settings,
        level_damping,
        start,
        limb_tasks,
        hybrid_limbs,
    })
}

/// The solver of a problem: its settings, per-level damping and hybrid limbs.
pub fn solver_for(problem: &Problem, settings: SolverSettings) -> Result<Solver> {
    let mut solver = Solver::new(settings)?.with_limbs(problem.hybrid_limbs.clone());
    solver.level_damping = problem.level_damping.clone();
    Ok(solver)
}

/// The three joints of a limb task: `joints` (names) or the `limb` shorthand.
fn limb_joints(skeleton: &Skeleton, o: &Map<String, Value>, at: &str) -> Result<[String; 3]> {
    match (
        o.get("joints").filter(|v| !v.is_null()),
        o.get("limb").filter(|v| !v.is_null()),
    ) {
        (Some(list), None) => {
            let here = format!("{at}.joints");
            let list = arr(list, &here)?;
            if list.len() != 3 {
                bail!("{here}: expected 3 joint names (upper, middle, end)");
            }
            let mut names: [String; 3] = Default::default();
            for (k, (v, name)) in list.iter().zip(names.iter_mut()).enumerate() {
                let j = joint_index(skeleton, v, &format!("{here}[{k}]"))?;
                *name = skeleton.joints()[j].name.clone();
            }
            Ok(names)
        }
        (None, Some(limb)) => {
            let here = format!("{at}.limb");
            let name = string(limb, &here)?;
            if !HANIM_LIMBS.iter().any(|l| l.0 == name) {
                bail!("{here}: unknown limb `{name}` (expected l_arm, r_arm, l_leg or r_leg)");
            }
            hanim_limb(skeleton, name)
                .filter(|n| n.iter().all(|j| skeleton.joint_index(j).is_some()))
                .ok_or_else(|| anyhow!("{here}: the skeleton lacks the H-Anim joints of `{name}`"))
        }
        (Some(_), Some(_)) => bail!("{at}: give either `joints` or `limb`, not both"),
        (None, None) => bail!("{at}.joints: missing (or give `limb`)"),
    }
}

fn parse_limb_task(skeleton: &Skeleton, v: &Value, at: &str) -> Result<LimbTask> {
    let o = obj(v, at)?;
    let joints = limb_joints(skeleton, o, at)?;
    let limb = Limb::from_names(skeleton, [&joints[0], &joints[1], &joints[2]])
        .map_err(|e| anyhow!("{at}: {e}"))?;
    let target = vec3(field(o, "target", at)?, &format!("{at}.target"))?;
    let orientation = match o.get("orientation") {
        None | Some(Value::Null) => None,
        Some(q) => Some(quaternion(q, &format!("{at}.orientation"))?),
    };
    let swivel = match o.get("swivel") {
        None | Some(Value::Null) => None,
        Some(s) => Some(number(s, &format!("{at}.swivel"))?),
    };
    Ok(LimbTask {
        limb,
        joints,
        goal: LimbGoal {
            position: target,
            orientation,
        },
        swivel,
    })
}

fn quaternion(v: &Value, at: &str) -> Result<DQuat> {
    let q = numbers(v, at, 4)?;
    let q = DQuat::from_xyzw(q[0], q[1], q[2], q[3]);
    if q.length() < 1e-9 {
        bail!("{at}: the quaternion has zero length");
    }
    Ok(q.normalize())
}

fn parse_skeleton(v: &Value) -> Result<Skeleton> {
    let s = obj(v, "skeleton")?;
    let joints = arr(field(s, "joints", "skeleton")?, "skeleton.joints")?;
    let mut defs = Vec::with_capacity(joints.len());
    for (i, j) in joints.iter().enumerate() {
        let at = format!("skeleton.joints[{i}]");
        let o = obj(j, &at)?;
        let name = string(field(o, "name", &at)?, &format!("{at}.name"))?.to_owned();
        let at = format!("skeleton.joints[{i}] (`{name}`)");
        let parent = match o.get("parent") {
            None | Some(Value::Null) => None,
            Some(p) => Some(string(p, &format!("{at}.parent"))?.to_owned()),
        };
        let offset = match o.get("offset") {
            None => DVec3::ZERO,
            Some(v) => vec3(v, &format!("{at}.offset"))?,
        };
        let dofs = match o.get("dofs") {
            None | Some(Value::Null) => Vec::new(),
            Some(v) => arr(v, &format!("{at}.dofs"))?
                .iter()
                .enumerate()
                .map(|(k, d)| dof(d, &format!("{at}.dofs[{k}]")))
                .collect::<Result<_>>()?,
        };
        let mut def = JointDef::new(name, parent.as_deref(), offset, &dofs);
        if let Some(l) = o.get("limits").filter(|l| !l.is_null()) {
            for (key, range) in obj(l, &format!("{at}.limits"))? {
                let here = format!("{at}.limits.{key}");
                let d = Dof::from_name(key).ok_or_else(|| {
                    anyhow!("{here}: unknown DOF (expected tx, ty, tz, rx, ry or rz)")
                })?;
                let r = arr(range, &here)?;
                if r.len() != 2 {
                    bail!("{here}: expected [lower, upper]");
                }
                def = def.with_limit(d, number(&r[0], &here)?, number(&r[1], &here)?);
            }
        }
        if let Some(m) = o.get("mass").filter(|m| !m.is_null()) {
            def.mass = number(m, &format!("{at}.mass"))?;
        }
        if let Some(c) = o.get("com").filter(|c| !c.is_null()) {
            def.com = vec3(c, &format!("{at}.com"))?;
        }
        defs.push(def);
    }
    Skeleton::new(defs).map_err(|e| anyhow!("skeleton: {e}"))
}

fn joint_index(skeleton: &Skeleton, v: &Value, at: &str) -> Result<usize> {
    let name = string(v, at)?;
    skeleton
        .joint_index(name)
        .ok_or_else(|| anyhow!("{at}: unknown joint `{name}`"))
}

/// `lambda` (constant damping) or `adaptive_damping` (`{"lambda_max", "epsilon"}`) of `o`.
fn parse_damping(o: &Map<String, Value>, at: &str) -> Result<Option<Damping>> {
    let mut damping = None;
    if let Some(v) = o.get("lambda").filter(|v| !v.is_null()) {
        let lambda = number(v, &format!("{at}.lambda"))?;
        if !(lambda.is_finite() && lambda >= 0.0) {
            bail!("{at}.lambda: expected a number >= 0");
        }
        damping = Some(Damping::Constant { lambda });
    }
    if let Some(a) = o.get("adaptive_damping").filter(|a| !a.is_null()) {
        let here = format!("{at}.adaptive_damping");
        let a = obj(a, &here)?;
        let lambda_max = number(
            field(a, "lambda_max", &here)?,
            &format!("{here}.lambda_max"),
        )?;
        let epsilon = number(field(a, "epsilon", &here)?, &format!("{here}.epsilon"))?;
        if !(lambda_max.is_finite() && lambda_max >= 0.0 && epsilon.is_finite() && epsilon > 0.0) {
            bail!("{here}: expected lambda_max >= 0 and epsilon > 0");
        }
        damping = Some(Damping::Adaptive {
            lambda_max,
            epsilon,
        });
    }
    Ok(damping)
}

/// `settings.levels`: `{"3": {"lambda": 0.05}}` or `{"3": {"adaptive_damping": {..}}}`.
fn parse_level_damping(o: &Map<String, Value>) -> Result<BTreeMap<u32, Damping>> {
    let mut out = BTreeMap::new();
    let Some(levels) = o.get("levels").filter(|v| !v.is_null()) else {
        return Ok(out);
    };
    for (key, v) in obj(levels, "settings.levels")? {
        let at = format!("settings.levels.{key}");
        let level: u32 = key
            .parse()
            .ok()
            .filter(|&l| l >= 1)
            .ok_or_else(|| anyhow!("{at}: a level is a whole number >= 1"))?;
        let entry = obj(v, &at)?;
        let damping = parse_damping(entry, &at)?
            .ok_or_else(|| anyhow!("{at}: expected `lambda` or `adaptive_damping`"))?;
        out.insert(level, damping);
    }
    Ok(out)
}

fn parse_settings(v: &Value) -> Result<(SolverSettings, bool, BTreeMap<u32, Damping>)> {
    let o = obj(v, "settings")?;
    let mut s = SolverSettings::default();
    let num = |k: &str| -> Result<Option<f64>> {
        match o.get(k) {
            None | Some(Value::Null) => Ok(None),
            Some(v) => number(v, &format!("settings.{k}")).map(Some),
        }
    };
    if let Some(n) = num("max_iterations")? {
        if n < 0.0 || n.fract() != 0.0 {
            bail!("settings.max_iterations: expected a non-negative integer");
        }
        s.max_iterations = n as usize;
    }
    if let Some(n) = num("tolerance")? {
        s.tolerance = n;
    }
    if let Some(n) = num("stall_step")? {
        s.stall_step = n;
    }
    if let Some(n) = num("stall_improvement")? {
        s.stall_improvement = n;
    }
    if let Some(n) = num("time_budget_ms")? {
        s.time_budget_secs = Some(n / 1000.0);
    }
    if let Some(d) = parse_damping(o, "settings")? {
        s.damping = d;
    }
    if let Some(n) = num("rank_tolerance")? {
        s.rank_tolerance = n;
    }
    if let Some(n) = num("max_linear_step")? {
        s.max_linear_step = n;
    }
    if let Some(n) = num("max_angular_step")? {
        s.max_angular_step = n;
    }
    if let Some(n) = num("max_dof_step")? {
        s.max_dof_step = n;
    }
    match o.get("enforce_limits") {
        None | Some(Value::Null) => {}
        Some(Value::Bool(b)) => s.enforce_limits = *b,
        Some(_) => bail!("settings.enforce_limits: expected true or false"),
    }
    s.validate().map_err(|e| anyhow!("settings: {e}"))?;
    let hybrid = match o.get("hybrid") {
        None | Some(Value::Null) => false,
        Some(Value::Bool(b)) => *b,
        Some(_) => bail!("settings.hybrid: expected true or false"),
    };
    Ok((s, hybrid, parse_level_damping(o)?))
}

/// `{joint: {dof: value}}`; missing DOF are 0 (`stance_document::PostureValues`).
fn parse_posture(skeleton: &Skeleton, v: &Value, at: &str) -> Result<Posture> {
    PostureValues::from_json_value(v, at)
        .and_then(|p| p.to_posture_at(skeleton, at))
        .map_err(|e| anyhow!("{e}"))
}

fn obj<'a>(v: &'a Value, at: &str) -> Result<&'a Map<String, Value>> {
    v.as_object()
        .ok_or_else(|| anyhow!("{at}: expected an object"))
}

fn arr<'a>(v: &'a Value, at: &str) -> Result<&'a Vec<Value>> {
    v.as_array()
        .ok_or_else(|| anyhow!("{at}: expected an array"))
}

fn field<'a>(o: &'a Map<String, Value>, name: &str, at: &str) -> Result<&'a Value> {
    let path = if at.is_empty() {
        name.to_owned()
    } else {
        format!("{at}.{name}")
    };
    o.get(name)
        .filter(|v| !v.is_null())
        .ok_or_else(|| anyhow!("{path}: missing"))
}

fn string<'a>(v: &'a Value, at: &str) -> Result<&'a str> {
    v.as_str().ok_or_else(|| anyhow!("{at}: expected a string"))
}

fn number(v: &Value, at: &str) -> Result<f64> {
    let n = v
        .as_f64()
        .ok_or_else(|| anyhow!("{at}: expected a number"))?;
    if !n.is_finite() {
        bail!("{at}: not a finite number");
    }
    Ok(n)
}

fn numbers(v: &Value, at: &str, len: usize) -> Result<Vec<f64>> {
    let a = arr(v, at)?;
    if a.len() != len {
        bail!("{at}: expected {len} numbers, found {}", a.len());
    }
    a.iter()
        .enumerate()
        .map(|(i, x)| number(x, &format!("{at}[{i}]")))
        .collect()
}

fn vec3(v: &Value, at: &str) -> Result<DVec3> {
    let n = numbers(v, at, 3)?;
    Ok(DVec3::new(n[0], n[1], n[2]))
}

fn dof(v: &Value, at: &str) -> Result<Dof> {
    let s = string(v, at)?;
    Dof::from_name(s)
        .ok_or_else(|| anyhow!("{at}: unknown DOF `{s}` (expected tx, ty, tz, rx, ry or rz)"))
}
