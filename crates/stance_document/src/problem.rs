//! The one way from tasks to a solver problem: a skeleton, its tasks by level (through
//! [`TaskSpec::to_solver_tasks`]), the `limb` tasks' closed-form starts, the settings with
//! per-level damping, and the start posture. Built from a problem file (`stance solve`,
//! `docs/problem-format.md`) or from a document on a skeleton (the editor, the tests); every
//! error names the field (`tasks[2].joint: unknown joint ...`, `settings.levels.3.lambda`).

use std::collections::BTreeMap;

use serde_json::{Map, Value, json};
use stance_ik::{
    Damping, Dof, Frames, IkError, Iteration, JointDef, Limb, Obstacle, ObstacleShape, Posture,
    Skeleton, SolveReport, Solver, SolverSettings, Task, TaskKind,
};

use stance_hanim::capsules::BodyCollision;
use stance_hanim::comfort::ComfortSettings;

use crate::comfort::{comfort_json, parse_comfort_settings};
use crate::convert::LimbStartSpec;
use crate::convert::solver_tasks;
use crate::json::{arr, field, number, obj, optional_bool, string, vec3};
use crate::{Document, DocumentError, LimbName, PostureValues, TaskSpec};

/// A solver problem (see the module documentation).
#[derive(Debug, Clone)]
pub struct Problem {
    /// The body.
    pub skeleton: Skeleton,
    /// The tasks as written (document form).
    pub specs: Vec<TaskSpec>,
    /// The solver tasks, in order (a `limb` task with an orientation gives two).
    pub tasks: Vec<Task>,
    /// Solver settings.
    pub settings: SolverSettings,
    /// Per-level damping (`settings.levels`).
    pub level_damping: BTreeMap<u32, Damping>,
    /// Where solving starts, before the closed-form limb starts.
    pub start: Posture,
    /// The `limb` tasks' closed forms, in task order.
    pub limb_starts: Vec<LimbStartSpec>,
    /// Limbs for the solver's hybrid restart: those of the limb tasks, plus every H-Anim limb
    /// of the skeleton with `settings.hybrid`.
    pub hybrid_limbs: Vec<Limb>,
    /// RULA's inputs and the strength profile for the comfort report (the file's `comfort`).
    pub comfort: ComfortSettings,
}

/// What the closed form did for one limb task.
#[derive(Debug, Clone, PartialEq)]
pub struct LimbStart {
    /// The limb's upper, middle and end joints.
    pub joints: [String; 3],
    /// Swivel angle of the closed-form start posture (rad).
    pub swivel: f64,
    /// Whether the goal was reached.
    pub reached: bool,
    /// Whether the solution is inside the joint limits.
    pub within_limits: bool,
}

impl Problem {
    /// A document's tasks, posture and joint stiffness on `skeleton`, with default settings.
    pub fn from_document(document: &Document, skeleton: Skeleton) -> Result<Self, DocumentError> {
        let skeleton = crate::apply_stiffness(&document.stiffness, &skeleton)?;
        let start = document.to_posture(&skeleton)?;
        Self::build(
            skeleton,
            document.tasks.clone(),
            start,
            SolverSettings::default(),
            BTreeMap::new(),
            false,
        )
    }

    /// Parses a problem file (`docs/problem-format.md`).
    pub fn from_json(text: &str) -> Result<Self, DocumentError> {
        let root: Value =
            serde_json::from_str(text).map_err(|e| DocumentError::Json(e.to_string()))?;
        let root = obj(&root, "the problem")?;
        let skeleton = parse_skeleton(field(root, "skeleton", "")?)?;
        let specs = match root.get("tasks").filter(|v| !v.is_null()) {
            None => Vec::new(),
            Some(v) => TaskSpec::list_from_json_value(v, "tasks")?,
        };
        let (settings, hybrid, level_damping) = match root.get("settings") {
            None | Some(Value::Null) => (SolverSettings::default(), false, BTreeMap::new()),
            Some(v) => parse_settings(v)?,
        };
        let start = match root.get("posture") {
            None | Some(Value::Null) => Posture::rest(&skeleton),
            Some(v) => {
                PostureValues::from_json_value(v, "posture")?.to_posture_at(&skeleton, "posture")?
            }
        };
        let radius = parse_radii(field(root, "skeleton", "")?, &skeleton)?;
        let mut problem = Self::build(skeleton, specs, start, settings, level_damping, hybrid)?;
        if !radius.is_empty() {
            problem.set_capsule_radii(&radius);
        }
        if let Some(v) = root.get("obstacles").filter(|v| !v.is_null()) {
            let list = arr(v, "obstacles")?;
            let obstacles = list
                .iter()
                .enumerate()
                .map(|(i, o)| {
                    crate::Prop::from_json_value(o, &format!("obstacles[{i}]"), i)
                        .map(|prop| prop.obstacle(glam::DAffine3::IDENTITY))
                })
                .collect::<Result<Vec<_>, _>>()?;
            problem.set_obstacles(&obstacles);
        }
        if let Some(v) = root.get("comfort").filter(|v| !v.is_null()) {
            problem.comfort = parse_comfort_settings(v, "comfort")?;
        }
        Ok(problem)
    }

    fn build(
        skeleton: Skeleton,
        specs: Vec<TaskSpec>,
        start: Posture,
        settings: SolverSettings,
        level_damping: BTreeMap<u32, Damping>,
        hybrid: bool,
    ) -> Result<Self, DocumentError> {
        let tasks = solver_tasks(&skeleton, &specs)?;
        let mut limb_starts = Vec::new();
        for (i, spec) in specs.iter().enumerate() {
            if let Some(limb) = spec
                .to_limb(&skeleton)
                .map_err(|e| e.within(&format!("tasks[{i}]")))?
            {
                limb_starts.push(limb);
            }
        }
        let mut hybrid_limbs: Vec<Limb> = limb_starts.iter().map(|l| l.limb.clone()).collect();
        if hybrid {
            for limb in LimbName::all_on(&skeleton) {
                if !hybrid_limbs.iter().any(|h| h.joints() == limb.joints()) {
                    hybrid_limbs.push(limb);
                }
            }
        }
        Ok(Self {
            skeleton,
            specs,
            tasks,
            settings,
            level_damping,
            start,
            limb_starts,
            hybrid_limbs,
            comfort: ComfortSettings::default(),
        })
    }

    /// Gives the capsules every joint of `radius` carries that radius (m) in the collision
    /// tasks (a problem file's `skeleton.joints[].radius`).
    fn set_capsule_radii(&mut self, radius: &BTreeMap<usize, f64>) {
        for task in &mut self.tasks {
            if let TaskKind::Collision(c) = &task.kind
                && let Some(mut body) = BodyCollision::of(&self.skeleton, c)
            {
                body.radius.clone_from(radius);
                task.kind = TaskKind::Collision(body.collision(&self.skeleton));
            }
        }
        stance_ik::with_placed_parts(&self.skeleton, &mut self.tasks);
    }

    /// Holds the body's capsules off these fixed solids in every collision task (a problem
    /// file's `obstacles`, a scene's props in the character's frame); none: as before.
    pub fn set_obstacles(&mut self, obstacles: &[Obstacle]) {
        for task in &mut self.tasks {
            if let TaskKind::Collision(c) = &task.kind {
                task.kind = TaskKind::Collision(c.clone().with_obstacles(obstacles.to_vec()));
            }
        }
        // The parts placed on the solids now there.
        stance_ik::with_placed_parts(&self.skeleton, &mut self.tasks);
    }

    /// The solver of this problem with `settings` (usually [`Problem::settings`]): its
    /// per-level damping and hybrid limbs.
    pub fn solver(&self, settings: SolverSettings) -> Result<Solver, IkError> {
        let mut solver = Solver::new(settings)?.with_limbs(self.hybrid_limbs.clone());
        solver.level_damping = self.level_damping.clone();
        Ok(solver)
    }

    /// The start posture with every limb task's closed-form solution applied in task order
    /// (the swivel asked, or the start posture's, moved to the nearest one within the joint
    /// limits), and what each closed form did.
    pub fn start_posture(&self) -> (Posture, Vec<LimbStart>) {
        let mut posture = self.start.clone();
        let mut starts = Vec::with_capacity(self.limb_starts.len());
        for t in &self.limb_starts {
            let frames = Frames::new(&self.skeleton, &posture);
            let base = t.limb.base(&self.skeleton, &frames);
            let preferred = t
                .swivel
                .unwrap_or_else(|| t.limb.swivel_angle(&self.skeleton, &posture));
            let solution = t.limb.solve_within_limits(base, &t.goal, preferred);
            t.limb.apply(&solution, &mut posture);
            starts.push(LimbStart {
                joints: t
                    .limb
                    .joints()
                    .map(|j| self.skeleton.joints()[j].name.clone()),
                swivel: solution.swivel_angle,
                reached: solution.reached,
                within_limits: solution.within_limits,
            });
        }
        (posture, starts)
    }

    /// The solution as `stance solve` prints it: `{"joints": {name: [x, y, z]}, "posture":
    /// {joint: {dof: value}}, "report": {...}, "tasks": [...]}` (per task of the file, in its
    /// order: level, description, residual, met, and why it gave way; see [`crate::TaskStatus`]),
    /// and with limb tasks `"limbs"`: per limb task
    /// its joints, final swivel, the closed-form start's swivel and whether that start reached
    /// the goal within the limits.
    pub fn solution_json(&self, posture: &Posture, report: &SolveReport) -> Value {
        let frames = Frames::new(&self.skeleton, posture);
        let joints: Map<String, Value> = self
            .skeleton
            .joints()
            .iter()
            .enumerate()
            .map(|(j, joint)| {
                let p = frames.joint_position[j];
                (joint.name.clone(), json!([p.x, p.y, p.z]))
            })
            .collect();
        let mut report = serde_json::to_value(report).unwrap_or(Value::Null);
        if let Some(o) = report.as_object_mut() {
            o.insert(
                "comfort".to_owned(),
                comfort_json(&self.skeleton, posture, &self.comfort),
            );
        }
        let statuses =
            crate::task_statuses(&self.skeleton, None, posture, &frames, &self.specs, true);
        let tasks = crate::status::statuses_json(&self.specs, &statuses);
        let mut out = json!({
            "joints": joints,
            "posture": PostureValues::from_posture(&self.skeleton, posture),
            "report": report,
            "tasks": tasks,
        });
        if !self.limb_starts.is_empty()
            && let Some(o) = out.as_object_mut()
        {
            let (_, starts) = self.start_posture();
            let limbs: Vec<Value> = self
                .limb_starts
                .iter()
                .zip(starts)
                .map(|(t, s)| {
                    json!({
                        "joints": s.joints,
                        "swivel": t.limb.swivel_angle(&self.skeleton, posture),
                        "start_swivel": s.swivel,
                        "reached": s.reached,
                        "within_limits": s.within_limits,
                    })
                })
                .collect();
            o.insert("limbs".to_owned(), Value::Array(limbs));
        }
        out
    }

    /// Solves from [`Problem::start_posture`] with the problem's settings.
    pub fn solve(&self) -> Result<(Posture, SolveReport), IkError> {
        let (mut posture, _) = self.start_posture();
        let mut solver = self.solver(self.settings)?;
        let report = solver.solve(&self.skeleton, &self.tasks, &mut posture)?;
        Ok((posture, report))
    }
}

/// Parses a problem file's `skeleton` (`{"joints": [{"name", "parent", "offset", "dofs",
/// "limits", "mass", "com"}]}`); errors at `skeleton.joints[i] (`name`).<field>`.
pub fn parse_skeleton(v: &Value) -> Result<Skeleton, DocumentError> {
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
            None => [0.0; 3],
            Some(v) => vec3(v, &format!("{at}.offset"))?,
        };
        let dofs = match o.get("dofs") {
            None | Some(Value::Null) => Vec::new(),
            Some(v) => arr(v, &format!("{at}.dofs"))?
                .iter()
                .enumerate()
                .map(|(k, d)| dof(d, &format!("{at}.dofs[{k}]")))
                .collect::<Result<_, _>>()?,
        };
        let mut def = JointDef::new(
            name,
            parent.as_deref(),
            glam::DVec3::from_array(offset),
            &dofs,
        );
        if let Some(l) = o.get("limits").filter(|l| !l.is_null()) {
            for (key, range) in obj(l, &format!("{at}.limits"))? {
                let here = format!("{at}.limits.{key}");
                let d = Dof::from_name(key).ok_or_else(|| {
                    DocumentError::field(&here, "unknown DOF (expected tx, ty, tz, rx, ry or rz)")
                })?;
                let r = arr(range, &here)?;
                if r.len() != 2 {
                    return Err(DocumentError::field(here, "expected [lower, upper]"));
                }
                def = def.with_limit(d, number(&r[0], &here)?, number(&r[1], &here)?);
            }
        }
        if let Some(l) = o.get("stiffness").filter(|l| !l.is_null()) {
            for (key, value) in obj(l, &format!("{at}.stiffness"))? {
                let here = format!("{at}.stiffness.{key}");
                let d = Dof::from_name(key)
                    .filter(|d| d.is_rotation())
                    .ok_or_else(|| DocumentError::field(&here, "expected rx, ry or rz"))?;
                let value = number(value, &here)?;
                if !(0.0..1.0).contains(&value) {
                    return Err(DocumentError::field(here, "expected a number in [0, 1)"));
                }
                def = def.with_stiffness(d, value);
            }
        }
        if let Some(m) = o.get("mass").filter(|m| !m.is_null()) {
            def.mass = number(m, &format!("{at}.mass"))?;
        }
        if let Some(c) = o.get("com").filter(|c| !c.is_null()) {
            def.com = glam::DVec3::from_array(vec3(c, &format!("{at}.com"))?);
        }
        defs.push(def);
    }
    Skeleton::new(defs).map_err(|e| DocumentError::field("skeleton", e.to_string()))
}

/// The capsule radii of a problem file's `skeleton.joints[].radius` (m, > 0), by joint index
/// on `skeleton`; errors at `skeleton.joints[i] (`name`).radius`.
fn parse_radii(v: &Value, skeleton: &Skeleton) -> Result<BTreeMap<usize, f64>, DocumentError> {
    let mut radius = BTreeMap::new();
    let joints = arr(
        field(obj(v, "skeleton")?, "joints", "skeleton")?,
        "skeleton.joints",
    )?;
    for (i, j) in joints.iter().enumerate() {
        let o = obj(j, &format!("skeleton.joints[{i}]"))?;
        let Some(r) = o.get("radius").filter(|r| !r.is_null()) else {
            continue;
        };
        let name = string(field(o, "name", "")?, "name")?;
        let here = format!("skeleton.joints[{i}] (`{name}`).radius");
        let r = number(r, &here)?;
        if r <= 0.0 {
            return Err(DocumentError::field(here, "must be a number > 0 (m)"));
        }
        if let Some(index) = skeleton.joint_index(name) {
            radius.insert(index, r);
        }
    }
    Ok(radius)
}

fn dof(v: &Value, at: &str) -> Result<Dof, DocumentError> {
    let s = string(v, at)?;
    Dof::from_name(s).ok_or_else(|| {
        DocumentError::field(
            at,
            format!("unknown DOF `{s}` (expected tx, ty, tz, rx, ry or rz)"),
        )
    })
}

/// `lambda` (constant damping), `levenberg` (`{"lambda", "error_scale"}`) or
/// `adaptive_damping` (`{"lambda_max", "epsilon"}`) of `o`.
fn parse_damping(o: &Map<String, Value>, at: &str) -> Result<Option<Damping>, DocumentError> {
    let mut damping = None;
    if let Some(v) = o.get("lambda").filter(|v| !v.is_null()) {
        let here = format!("{at}.lambda");
        let lambda = number(v, &here)?;
        if lambda < 0.0 {
            return Err(DocumentError::field(here, "expected a number >= 0"));
        }
        damping = Some(Damping::Constant { lambda });
    }
    if let Some(l) = o.get("levenberg").filter(|l| !l.is_null()) {
        let here = format!("{at}.levenberg");
        let l = obj(l, &here)?;
        let lambda = number(field(l, "lambda", &here)?, &format!("{here}.lambda"))?;
        let error_scale = number(
            field(l, "error_scale", &here)?,
            &format!("{here}.error_scale"),
        )?;
        if !(lambda >= 0.0 && error_scale > 0.0) {
            return Err(DocumentError::field(
                here,
                "expected lambda >= 0 and error_scale > 0",
            ));
        }
        damping = Some(Damping::Levenberg {
            lambda,
            error_scale,
        });
    }
    if let Some(a) = o.get("adaptive_damping").filter(|a| !a.is_null()) {
        let here = format!("{at}.adaptive_damping");
        let a = obj(a, &here)?;
        let lambda_max = number(
            field(a, "lambda_max", &here)?,
            &format!("{here}.lambda_max"),
        )?;
        let epsilon = number(field(a, "epsilon", &here)?, &format!("{here}.epsilon"))?;
        if !(lambda_max >= 0.0 && epsilon > 0.0) {
            return Err(DocumentError::field(
                here,
                "expected lambda_max >= 0 and epsilon > 0",
            ));
        }
        damping = Some(Damping::Adaptive {
            lambda_max,
            epsilon,
        });
    }
    Ok(damping)
}

/// `settings.levels`: `{"3": {"lambda": 0.05}}` or `{"3": {"adaptive_damping": {..}}}`.
fn parse_level_damping(o: &Map<String, Value>) -> Result<BTreeMap<u32, Damping>, DocumentError> {
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
            .ok_or_else(|| DocumentError::field(&at, "a level is a whole number >= 1"))?;
        let entry = obj(v, &at)?;
        let damping = parse_damping(entry, &at)?.ok_or_else(|| {
            DocumentError::field(&at, "expected `lambda`, `levenberg` or `adaptive_damping`")
        })?;
        out.insert(level, damping);
    }
    Ok(out)
}

/// A problem file's `settings`: the solver's, per-level damping (`levels`) and `hybrid`.
#[derive(Debug, Clone, Default)]
pub struct ProblemSettings {
    /// The solver settings.
    pub solver: SolverSettings,
    /// Per-level damping.
    pub level_damping: BTreeMap<u32, Damping>,
    /// Whether a stalled solve may restart every H-Anim limb from its closed form.
    pub hybrid: bool,
}

impl ProblemSettings {
    /// Parses a `settings` object (`docs/problem-format.md`); errors at `settings.<field>`.
    pub fn from_json_value(v: &Value) -> Result<Self, DocumentError> {
        let (solver, hybrid, level_damping) = parse_settings(v)?;
        Ok(Self {
            solver,
            level_damping,
            hybrid,
        })
    }
}

type Settings = (SolverSettings, bool, BTreeMap<u32, Damping>);

fn parse_settings(v: &Value) -> Result<Settings, DocumentError> {
    let o = obj(v, "settings")?;
    let mut s = SolverSettings::default();
    let num = |k: &str| -> Result<Option<f64>, DocumentError> {
        match o.get(k) {
            None | Some(Value::Null) => Ok(None),
            Some(v) => number(v, &format!("settings.{k}")).map(Some),
        }
    };
    let flag = |k: &str| optional_bool(o, "settings", k);
    // A whole number of at least `least`.
    let count = |k: &str, least: f64, expected: &str| -> Result<Option<usize>, DocumentError> {
        match num(k)? {
            Some(n) if n < least || n.fract() != 0.0 => {
                Err(DocumentError::field(format!("settings.{k}"), expected))
            }
            Some(n) => Ok(Some(n as usize)),
            None => Ok(None),
        }
    };
    if let Some(n) = count("max_iterations", 0.0, "expected a non-negative integer")? {
        s.max_iterations = n;
    }
    if let Some(n) = count("stall_window", 1.0, "expected a positive integer")? {
        s.stall_window = n;
    }
    let set = |k: &str, slot: &mut f64| -> Result<(), DocumentError> {
        if let Some(n) = num(k)? {
            *slot = n;
        }
        Ok(())
    };
    set("tolerance", &mut s.tolerance)?;
    set("stall_step", &mut s.stall_step)?;
    set("stall_improvement", &mut s.stall_improvement)?;
    set("rank_tolerance", &mut s.rank_tolerance)?;
    set("max_linear_step", &mut s.max_linear_step)?;
    set("max_angular_step", &mut s.max_angular_step)?;
    set("max_dof_step", &mut s.max_dof_step)?;
    set("trust_region", &mut s.trust_region)?;
    set("priority_budget", &mut s.priority_budget)?;
    if let Some(n) = num("time_budget_ms")? {
        s.time_budget_secs = Some(n / 1000.0);
    }
    if let Some(d) = parse_damping(o, "settings")? {
        s.damping = d;
    }
    if let Some(b) = flag("enforce_limits")? {
        s.enforce_limits = b;
    }
    if let Some(b) = flag("restarts")? {
        s.restarts = b;
    }
    match o.get("iteration") {
        None | Some(Value::Null) => {}
        Some(Value::String(name)) if name == "guarded" => s.iteration = Iteration::Guarded,
        Some(Value::String(name)) if name == "textbook" => s.iteration = Iteration::Textbook,
        Some(_) => {
            return Err(DocumentError::field(
                "settings.iteration",
                "expected \"guarded\" or \"textbook\"",
            ));
        }
    }
    s.validate()
        .map_err(|e| DocumentError::field("settings", e.to_string()))?;
    let hybrid = flag("hybrid")?.unwrap_or(false);
    Ok((s, hybrid, parse_level_damping(o)?))
}

/// A skeleton in the problem format's `skeleton` form (what [`parse_skeleton`] reads back).
pub fn skeleton_json(skeleton: &Skeleton) -> Value {
    let (lower, upper) = (skeleton.lower_limits(), skeleton.upper_limits());
    let stiffness = skeleton.stiffness();
    let joints: Vec<Value> = skeleton
        .joints()
        .iter()
        .map(|joint| {
            let mut limits = Map::new();
            let mut stiff = Map::new();
            for (k, d) in joint.dofs.iter().enumerate() {
                let i = joint.dof_start + k;
                // A skeleton's limits are finite on both sides, or absent (infinite).
                if lower[i].is_finite() && upper[i].is_finite() {
                    limits.insert(d.name().to_owned(), json!([lower[i], upper[i]]));
                }
                if d.is_rotation() && stiffness.get(i).is_some_and(|&s| s != 0.0) {
                    stiff.insert(d.name().to_owned(), json!(stiffness[i]));
                }
            }
            let mut o = Map::new();
            o.insert("name".into(), json!(joint.name));
            o.insert(
                "parent".into(),
                joint
                    .parent
                    .map_or(Value::Null, |p| json!(skeleton.joints()[p].name)),
            );
            o.insert("offset".into(), json!(joint.offset.to_array()));
            let dofs: Vec<&str> = joint.dofs.iter().map(|d| d.name()).collect();
            o.insert("dofs".into(), json!(dofs));
            if !limits.is_empty() {
                o.insert("limits".into(), Value::Object(limits));
            }
            if !stiff.is_empty() {
                o.insert("stiffness".into(), Value::Object(stiff));
            }
            o.insert("mass".into(), json!(joint.mass));
            o.insert("com".into(), json!(joint.com.to_array()));
            Value::Object(o)
        })
        .collect();
    json!({ "joints": joints })
}

/// A problem file (`docs/problem-format.md`) of solver tasks on a skeleton from a start
/// posture, with default settings; errors name the first task the format cannot hold
/// (comfort, posture attraction).
pub fn problem_json(
    skeleton: &Skeleton,
    tasks: &[Task],
    start: &Posture,
) -> Result<Value, DocumentError> {
    let specs = tasks
        .iter()
        .enumerate()
        .map(|(i, task)| {
            TaskSpec::from_task(skeleton, task).ok_or_else(|| {
                DocumentError::field(
                    format!("tasks[{i}]"),
                    "this kind of solver task has no problem-file form",
                )
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let mut skeleton_value = skeleton_json(skeleton);
    // A collision task's radii set by hand, on the joints that carry the capsules.
    let radius = tasks.iter().find_map(|t| match &t.kind {
        TaskKind::Collision(c) => BodyCollision::of(skeleton, c).map(|b| b.radius),
        _ => None,
    });
    if let Some(joints) = skeleton_value
        .get_mut("joints")
        .and_then(Value::as_array_mut)
    {
        for (&j, &r) in radius.iter().flatten() {
            if let Some(o) = joints.get_mut(j).and_then(Value::as_object_mut) {
                o.insert("radius".into(), json!(r));
            }
        }
    }
    let mut out = json!({
        "skeleton": skeleton_value,
        "tasks": specs,
        "posture": PostureValues::from_posture(skeleton, start),
    });
    // The collision tasks' obstacles (the problem's, the same for each), as props.
    let obstacles = tasks.iter().find_map(|t| match &t.kind {
        TaskKind::Collision(c) if !c.obstacles().is_empty() => Some(c.obstacles()),
        _ => None,
    });
    if let (Some(obstacles), Some(o)) = (obstacles, out.as_object_mut()) {
        o.insert(
            "obstacles".into(),
            Value::Array(obstacles.iter().map(obstacle_json).collect()),
        );
    }
    Ok(out)
}

/// An obstacle as a problem file's `obstacles` entry (a prop's JSON; a plane's slab is a box).
fn obstacle_json(obstacle: &Obstacle) -> Value {
    let rotation = glam::DQuat::from_mat3(&obstacle.world_from_obstacle_rotation).normalize();
    let mut o = match obstacle.shape {
        ObstacleShape::Box { half } => json!({"shape": "box", "size": (half * 2.0).to_array()}),
        ObstacleShape::Sphere { radius } => json!({"shape": "sphere", "radius": radius}),
        ObstacleShape::Cylinder {
            radius,
            half_height,
        } => json!({"shape": "cylinder", "radius": radius, "height": half_height * 2.0}),
    };
    if let Some(fields) = o.as_object_mut() {
        fields.insert("position".into(), json!(obstacle.position.to_array()));
        fields.insert("rotation".into(), json!(rotation.to_array()));
    }
    o
}
