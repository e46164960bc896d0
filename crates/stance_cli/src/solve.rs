//! `stance solve PROBLEM.json`: read a problem file (format in `docs/problem-format.md`),
//! solve it, print one JSON object with `joints`, `posture` and `report`.

use std::collections::BTreeMap;
use std::path::PathBuf;

use anyhow::{Context, Result, anyhow, bail};
use glam::{DQuat, DVec3};
use serde_json::{Map, Value, json};
use stance_ik::{
    Axes, Damping, Dof, Effector, Frames, JointDef, Posture, Skeleton, SolveReport, Solver,
    SolverSettings, Task, TaskKind,
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
    pub start: Posture,
}

pub fn run(args: SolveArgs) -> Result<()> {
    let problem = load_problem(&args.problem)?;
    let (posture, report) = solve(&problem)?;
    let out = solution_json(&problem.skeleton, &posture, &report)?;
    let text = if args.pretty {
        serde_json::to_string_pretty(&out)?
    } else {
        serde_json::to_string(&out)?
    };
    println!("{text}");
    Ok(())
}

/// Solves from the problem's start posture.
pub fn solve(problem: &Problem) -> Result<(Posture, SolveReport)> {
    let mut posture = problem.start.clone();
    let mut solver = Solver::new(problem.settings)?;
    let report = solver.solve(&problem.skeleton, &problem.tasks, &mut posture)?;
    Ok((posture, report))
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
    let tasks = match root.get("tasks") {
        None | Some(Value::Null) => Vec::new(),
        Some(v) => arr(v, "tasks")?
            .iter()
            .enumerate()
            .map(|(i, t)| parse_task(&skeleton, t, &format!("tasks[{i}]")))
            .collect::<Result<_>>()?,
    };
    let settings = match root.get("settings") {
        None | Some(Value::Null) => SolverSettings::default(),
        Some(v) => parse_settings(v)?,
    };
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
        start,
    })
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

fn parse_task(skeleton: &Skeleton, v: &Value, at: &str) -> Result<Task> {
    let o = obj(v, at)?;
    let kind_name = string(field(o, "kind", at)?, &format!("{at}.kind"))?;
    let f = |name: &str| field(o, name, at);
    let here = |name: &str| format!("{at}.{name}");
    let point = match o.get("point") {
        None | Some(Value::Null) => DVec3::ZERO,
        Some(p) => vec3(p, &here("point"))?,
    };
    let axes = match o.get("axes") {
        None | Some(Value::Null) => Axes::XYZ,
        Some(a) => {
            let s = string(a, &here("axes"))?;
            Axes::parse(s).ok_or_else(|| {
                anyhow!(
                    "{}: `{s}` is not a non-empty subset of \"xyz\"",
                    here("axes")
                )
            })?
        }
    };
    let kind = match kind_name {
        "position" => TaskKind::Position {
            effector: Effector {
                joint: joint_index(skeleton, f("joint")?, &here("joint"))?,
                point,
            },
            axes,
            target: vec3(f("target")?, &here("target"))?,
        },
        "orientation" => {
            let q = numbers(f("target")?, &here("target"), 4)?;
            let target = DQuat::from_xyzw(q[0], q[1], q[2], q[3]);
            if target.length() < 1e-9 {
                bail!("{}: the quaternion has zero length", here("target"));
            }
            TaskKind::Orientation {
                joint: joint_index(skeleton, f("joint")?, &here("joint"))?,
                target: target.normalize(),
            }
        }
        "gaze" => {
            let axis = match o.get("axis") {
                None | Some(Value::Null) => DVec3::Z,
                Some(a) => vec3(a, &here("axis"))?,
            };
            if axis.length() < 1e-9 {
                bail!("{}: zero-length axis", here("axis"));
            }
            TaskKind::Gaze {
                effector: Effector {
                    joint: joint_index(skeleton, f("joint")?, &here("joint"))?,
                    point,
                },
                axis: axis.normalize(),
                target: vec3(f("target")?, &here("target"))?,
            }
        }
        "com" => TaskKind::CenterOfMass {
            axes,
            target: vec3(f("target")?, &here("target"))?,
        },
        "posture" => {
            let reference = match o.get("reference") {
                None | Some(Value::Null) => Posture::rest(skeleton),
                Some(r) => parse_posture(skeleton, r, &here("reference"))?,
            };
            let dofs = match o.get("joints") {
                None | Some(Value::Null) => match Task::rest_posture(skeleton).kind {
                    TaskKind::PostureAttraction { dofs, .. } => dofs,
                    _ => Vec::new(),
                },
                Some(list) => {
                    let mut dofs = Vec::new();
                    for (k, j) in arr(list, &here("joints"))?.iter().enumerate() {
                        let ji = joint_index(skeleton, j, &format!("{}[{k}]", here("joints")))?;
                        dofs.extend(skeleton.joints()[ji].dof_range());
                    }
                    dofs
                }
            };
            TaskKind::PostureAttraction {
                reference: reference.values().to_vec(),
                dofs,
            }
        }
        other => bail!(
            "{}: unknown kind `{other}` (expected position, orientation, gaze, com or posture)",
            here("kind")
        ),
    };
    let level = match o.get("level") {
        None | Some(Value::Null) => 1,
        Some(l) => {
            let n = number(l, &here("level"))?;
            if n < 1.0 || n.fract() != 0.0 || n > f64::from(u32::MAX) {
                bail!(
                    "{}: levels are integers from 1 (highest priority)",
                    here("level")
                );
            }
            n as u32
        }
    };
    let weight = match o.get("weight") {
        None | Some(Value::Null) => 1.0,
        Some(w) => {
            let w = number(w, &here("weight"))?;
            if w < 0.0 {
                bail!("{}: must be >= 0", here("weight"));
            }
            w
        }
    };
    let active = match o.get("active") {
        None | Some(Value::Null) => true,
        Some(Value::Bool(b)) => *b,
        Some(_) => bail!("{}: expected true or false", here("active")),
    };
    Ok(Task {
        kind,
        level,
        weight,
        active,
    })
}

fn parse_settings(v: &Value) -> Result<SolverSettings> {
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
    if let Some(n) = num("lambda")? {
        s.damping = Damping::Constant { lambda: n };
    }
    if let Some(a) = o.get("adaptive_damping").filter(|a| !a.is_null()) {
        let a = obj(a, "settings.adaptive_damping")?;
        let lambda_max = number(
            field(a, "lambda_max", "settings.adaptive_damping")?,
            "settings.adaptive_damping.lambda_max",
        )?;
        let epsilon = number(
            field(a, "epsilon", "settings.adaptive_damping")?,
            "settings.adaptive_damping.epsilon",
        )?;
        s.damping = Damping::Adaptive {
            lambda_max,
            epsilon,
        };
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
    Ok(s)
}

/// `{joint: {dof: value}}`; missing DOF are 0.
fn parse_posture(skeleton: &Skeleton, v: &Value, at: &str) -> Result<Posture> {
    let mut p = Posture::rest(skeleton);
    for (name, dofs) in obj(v, at)? {
        let here = format!("{at}.{name}");
        let j = skeleton
            .joint_index(name)
            .ok_or_else(|| anyhow!("{here}: unknown joint `{name}`"))?;
        let joint = &skeleton.joints()[j];
        for (dname, value) in obj(dofs, &here)? {
            let there = format!("{here}.{dname}");
            let d = Dof::from_name(dname).ok_or_else(|| anyhow!("{there}: unknown DOF"))?;
            let k = joint
                .dofs
                .iter()
                .position(|&x| x == d)
                .ok_or_else(|| anyhow!("{there}: joint `{name}` has no DOF `{dname}`"))?;
            p.values_mut()[joint.dof_start + k] = number(value, &there)?;
        }
    }
    Ok(p)
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
