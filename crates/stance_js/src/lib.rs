//! Stance's solver for JavaScript: the core of the `stance-ik` npm package
//! (`packages/stance-ik`). Everything here is plain Rust, tested natively; the
//! `wasm-bindgen` layer in `js.rs` only converts between JavaScript values and these types.
//!
//! - [`solve_json`]: a problem file in, `stance solve`'s output out (same formats,
//!   `docs/problem-format.md`), through [`stance_document::Problem`].
//! - [`Body`]: a skeleton built once (the H-Anim default body at a level of articulation, a
//!   problem file's joints, or a skin's joints mapped onto H-Anim).
//! - [`PoseSolver`]: tasks by level set once, solved every frame into a caller's array of DOF
//!   values; world joint transforms; the closed-form limb and its swivel angle.
//! - [`Body::recipe_json`]: how a body was built, so that the package's retargeting
//!   (`stance_js_motion`, a WebAssembly module of its own loaded on demand) builds the same.

#![warn(missing_docs)]

#[cfg(all(target_arch = "wasm32", feature = "bindings"))]
mod js;

use glam::{DQuat, DVec3};
use serde_json::Value;
use stance_document::{
    FrameProblem, Grab, LimbName, Problem, ProblemSettings, TaskSpec, parse_skeleton, solver_tasks,
    statuses_json, task_statuses,
};
use stance_hanim::{
    HumanoidSkeleton, LevelOfArticulation, Mapping, SkeletonOptions, SourceJoint, build_skeleton,
    default_skeleton,
};
use stance_ik::{
    Clock, Frames, Iteration, Limb, LimbGoal, Posture, Skeleton, SolveReport, SolveStatus, Solver,
};

/// Guarded iterations without a meaningful gain before a frame's solve ends.
const PER_FRAME_STALL_WINDOW: usize = 5;

/// An error for JavaScript: the message names the field where there is one.
pub type JsResult<T> = Result<T, String>;

fn json(text: &str) -> JsResult<Value> {
    serde_json::from_str(text).map_err(|e| format!("not valid JSON: {e}"))
}

/// Solves a problem file (JSON text) as `stance solve` does and returns its output (JSON).
pub fn solve_json(problem: &str) -> JsResult<String> {
    let problem = Problem::from_json(problem).map_err(|e| e.to_string())?;
    let (posture, report) = problem.solve().map_err(|e| e.to_string())?;
    Ok(problem.solution_json(&posture, &report).to_string())
}

/// A level of articulation in a recipe (0 to 255; the body builder checks its range).
fn recipe_loa(what: &str, value: &Value) -> JsResult<u8> {
    value
        .as_u64()
        .and_then(|n| u8::try_from(n).ok())
        .ok_or_else(|| format!("{what}: {value} is not a level of articulation (1 to 4)"))
}

fn level_of_articulation(loa: u8) -> JsResult<LevelOfArticulation> {
    LevelOfArticulation::from_number(loa)
        .ok_or_else(|| format!("loa: {loa} is not a level of articulation (1 to 4)"))
}

/// A skeleton built once, and for a skin, which skin joint each of its joints stands for.
#[derive(Debug, Clone)]
pub struct Body {
    /// The solver's skeleton (H-Anim names for the H-Anim and skin bodies).
    pub skeleton: Skeleton,
    /// Per skeleton joint, the skin joint index it was built from (`-1`: none).
    pub source: Vec<i32>,
    /// Per skeleton joint, `qx qy qz qw` (4 numbers): the world rotation that turns its skin
    /// bone at the skin's rest onto the H-Anim standard pose, the skeleton's rest (identity
    /// but for a skin whose rest is another pose). A posture poses the bone as
    /// `world_from_joint · rest_match · (the bone's rest world rotation)`: the same posture
    /// shows the same pose on any skin (docs/avatars.md).
    pub rest_match: Vec<f64>,
    /// The H-Anim skeleton it was built as (H-Anim and skin bodies; `None` for a problem
    /// file's joints): what retargeting needs.
    pub humanoid: Option<HumanoidSkeleton>,
    /// How it was built ([`Body::recipe_json`]): enough to build the same body again in
    /// another WebAssembly module (the package's retargeting, loaded on demand).
    recipe: Value,
}

impl Body {
    /// The H-Anim default body at level of articulation `loa` (1 to 4).
    pub fn hanim(loa: u8) -> JsResult<Self> {
        let body = default_skeleton(&SkeletonOptions {
            loa: level_of_articulation(loa)?,
            ..SkeletonOptions::default()
        })
        .map_err(|e| e.to_string())?;
        let source = vec![-1; body.skeleton.joint_count()];
        Ok(Self {
            skeleton: body.skeleton.clone(),
            source,
            rest_match: rest_match(&body),
            humanoid: Some(body),
            recipe: serde_json::json!({ "hanim": loa }),
        })
    }

    /// A problem file's `skeleton` (JSON text: `{"joints": [...]}`).
    pub fn from_joints(skeleton: &str) -> JsResult<Self> {
        Self::from_joints_value(json(skeleton)?)
    }

    fn from_joints_value(value: Value) -> JsResult<Self> {
        let skeleton = parse_skeleton(&value).map_err(|e| e.to_string())?;
        let source = vec![-1; skeleton.joint_count()];
        let rest_match = [0.0, 0.0, 0.0, 1.0].repeat(skeleton.joint_count());
        Ok(Self {
            skeleton,
            source,
            rest_match,
            humanoid: None,
            recipe: serde_json::json!({ "joints": value }),
        })
    }

    /// A skin's joints (glTF `skin.joints` order): names, parent indices (`-1` for a root) and
    /// rest positions (`x y z` per joint, +Y up, the body facing +Z, metres), mapped onto
    /// H-Anim by name and geometry (as the editor maps avatars) and built at `loa`.
    pub fn from_skin(names: &[String], parents: &[i32], rest: &[f64], loa: u8) -> JsResult<Self> {
        let n = names.len();
        if parents.len() != n || rest.len() != 3 * n {
            return Err(format!(
                "fromSkin: {n} names need {n} parents and {} rest coordinates, got {} and {}",
                3 * n,
                parents.len(),
                rest.len()
            ));
        }
        let mut joints = Vec::with_capacity(n);
        for (i, name) in names.iter().enumerate() {
            let parent = match parents[i] {
                p if p < 0 => None,
                p if (p as usize) < n && p as usize != i => Some(p as usize),
                p => return Err(format!("parents[{i}]: {p} is not a joint index")),
            };
            let position = DVec3::new(rest[3 * i], rest[3 * i + 1], rest[3 * i + 2]);
            if !position.is_finite() {
                return Err(format!("rest[{}]: not a finite number", 3 * i));
            }
            joints.push(SourceJoint {
                name: name.clone(),
                parent,
                position,
            });
        }
        let mapping = Mapping::auto(&joints, &[], false);
        let positions: Vec<DVec3> = joints.iter().map(|j| j.position).collect();
        let options = SkeletonOptions {
            loa: level_of_articulation(loa)?,
            ..SkeletonOptions::default()
        };
        let body = build_skeleton(&mapping, &positions, &options).map_err(|e| e.to_string())?;
        let source = body
            .joints
            .iter()
            .map(|j| j.source.map_or(-1, |s| s as i32))
            .collect();
        Ok(Self {
            skeleton: body.skeleton.clone(),
            source,
            rest_match: rest_match(&body),
            humanoid: Some(body),
            recipe: serde_json::json!({
                "skin": { "names": names, "parents": parents, "rest": rest, "loa": loa }
            }),
        })
    }

    /// How this body was built, as JSON text: `{"hanim": loa}`, `{"joints": skeleton}` or
    /// `{"skin": {names, parents, rest, loa}}`. [`Body::from_recipe`] builds the same body
    /// from it (same joints, DOF order and rest match: numbers round-trip exactly).
    pub fn recipe_json(&self) -> String {
        self.recipe.to_string()
    }

    /// The body [`Body::recipe_json`] describes.
    pub fn from_recipe(recipe: &str) -> JsResult<Self> {
        let recipe = json(recipe)?;
        let field = |key: &str| recipe.get(key).cloned();
        if let Some(loa) = field("hanim") {
            return Self::hanim(recipe_loa("recipe.hanim", &loa)?);
        }
        if let Some(joints) = field("joints") {
            return Self::from_joints_value(joints);
        }
        let Some(skin) = field("skin") else {
            return Err("recipe: neither hanim, joints nor skin".to_string());
        };
        let list = |key: &str| -> JsResult<Vec<Value>> {
            skin.get(key)
                .and_then(Value::as_array)
                .cloned()
                .ok_or_else(|| format!("recipe.skin.{key}: not an array"))
        };
        let names = list("names")?
            .iter()
            .map(|v| v.as_str().map(str::to_string))
            .collect::<Option<Vec<_>>>()
            .ok_or("recipe.skin.names: not all strings")?;
        let parents = list("parents")?
            .iter()
            .map(|v| v.as_i64().and_then(|p| i32::try_from(p).ok()))
            .collect::<Option<Vec<_>>>()
            .ok_or("recipe.skin.parents: not all integers")?;
        let rest = list("rest")?
            .iter()
            .map(Value::as_f64)
            .collect::<Option<Vec<_>>>()
            .ok_or("recipe.skin.rest: not all numbers")?;
        let loa = recipe_loa("recipe.skin.loa", skin.get("loa").unwrap_or(&Value::Null))?;
        Self::from_skin(&names, &parents, &rest, loa)
    }

    /// The tasks a new body starts with at the posture `values` (JSON text of a task array,
    /// as `Solver::set_tasks` takes it): each ankle pinned where it is, balance over the
    /// pinned feet, comfort ([`TaskSpec::defaults`], the editor's defaults).
    pub fn default_tasks(&self, values: &[f64]) -> JsResult<String> {
        let posture = Posture::from_values(&self.skeleton, values.to_vec())
            .map_err(|e| format!("values: {e}"))?;
        let frames = Frames::new(&self.skeleton, &posture);
        let tasks = TaskSpec::defaults(&self.skeleton, &frames);
        serde_json::to_string(&tasks).map_err(|e| e.to_string())
    }

    /// Joint names, in skeleton order.
    pub fn joint_names(&self) -> Vec<String> {
        self.skeleton
            .joints()
            .iter()
            .map(|j| j.name.clone())
            .collect()
    }

    /// `joint.dof` names (`l_knee.rx`), in DOF order.
    pub fn dof_names(&self) -> Vec<String> {
        self.skeleton
            .joints()
            .iter()
            .flat_map(|j| {
                j.dofs
                    .iter()
                    .map(move |d| format!("{}.{}", j.name, d.name()))
            })
            .collect()
    }
}

/// Three finite numbers as a vector; errors name `what`.
fn vec3(what: &str, v: &[f64]) -> JsResult<DVec3> {
    let [x, y, z] = <[f64; 3]>::try_from(v).map_err(|_| format!("{what}: expected 3 numbers"))?;
    let v = DVec3::new(x, y, z);
    v.is_finite()
        .then_some(v)
        .ok_or_else(|| format!("{what}: not a finite number"))
}

/// Per joint of `body`, its rest match as `qx qy qz qw`.
fn rest_match(body: &HumanoidSkeleton) -> Vec<f64> {
    body.joints
        .iter()
        .flat_map(|j| {
            let q = j.rest_match;
            [q.x, q.y, q.z, q.w]
        })
        .collect()
}

/// Tasks by level on a body, solved every frame without re-parsing.
#[derive(Debug, Clone)]
pub struct PoseSolver {
    skeleton: Skeleton,
    /// The built body, when there is one: its comfort tasks read its own anatomical axes.
    humanoid: Option<HumanoidSkeleton>,
    solver: Solver,
    specs: Vec<TaskSpec>,
    /// The point being pulled (grab-and-pull), below every task.
    grab: Option<Grab>,
    report: Option<SolveReport>,
}

impl PoseSolver {
    /// A solver on `body` with a problem file's `settings` (JSON text; empty: defaults).
    /// Solved every frame, it takes guarded iterations unless `settings.iteration` says
    /// otherwise (each frame shows a posture that keeps the higher levels; 5 iterations
    /// without a gain end a frame's solve unless `stall_window` is given).
    pub fn new(body: &Body, settings: &str) -> JsResult<Self> {
        let given = if settings.trim().is_empty() {
            Value::Object(serde_json::Map::new())
        } else {
            json(settings)?
        };
        let mut settings = ProblemSettings::from_json_value(&given).map_err(|e| e.to_string())?;
        if given.get("iteration").is_none() {
            settings.solver.iteration = Iteration::Guarded;
            if given.get("stall_window").is_none() {
                settings.solver.stall_window = PER_FRAME_STALL_WINDOW;
            }
        }
        let mut solver = Solver::new(settings.solver).map_err(|e| format!("settings: {e}"))?;
        solver.level_damping = settings.level_damping;
        if settings.hybrid {
            solver = solver.with_limbs(LimbName::all_on(&body.skeleton));
        }
        Ok(Self {
            skeleton: body.skeleton.clone(),
            humanoid: body.humanoid.clone(),
            solver,
            specs: Vec::new(),
            grab: None,
            report: None,
        })
    }

    /// Sets the tasks (JSON text: an array of tasks as in a problem file's `tasks`); a task
    /// the body cannot hold (an unknown joint...) is an error naming it.
    pub fn set_tasks(&mut self, tasks: &str) -> JsResult<()> {
        let specs =
            TaskSpec::list_from_json_value(&json(tasks)?, "tasks").map_err(|e| e.to_string())?;
        solver_tasks(&self.skeleton, &specs).map_err(|e| e.to_string())?;
        self.specs = specs;
        Ok(())
    }

    /// Grab-and-pull: pulls the point `point` (3 numbers, in the frame of `joint`) toward
    /// `target` (world), one level below every task, from the next solve on; the editor's
    /// pull. Comfort tasks wait while a point is pulled.
    pub fn pull(&mut self, joint: &str, point: &[f64], target: &[f64]) -> JsResult<()> {
        let joint = self
            .skeleton
            .joint_index(joint)
            .ok_or_else(|| format!("joint: unknown joint `{joint}`"))?;
        self.grab = Some(Grab {
            joint,
            point_local: vec3("point", point)?,
            target_world: vec3("target", target)?,
        });
        Ok(())
    }

    /// Lets go of the pulled point.
    pub fn release(&mut self) {
        self.grab = None;
    }

    fn posture(&self, values: &[f64]) -> JsResult<Posture> {
        Posture::from_values(&self.skeleton, values.to_vec()).map_err(|e| format!("values: {e}"))
    }

    /// Solves from `values` (one per DOF) and writes the solution into them; returns the
    /// report (JSON text: status, iterations, per-level residuals, the level that gave way,
    /// and `tasks`: per task its level, residual, whether it is met and why it gave way, as
    /// `stance solve` prints them).
    pub fn solve(&mut self, values: &mut [f64]) -> JsResult<String> {
        self.solve_with_clock(values, None)
    }

    /// [`PoseSolver::solve`] with a clock for the settings' time budget (`time_budget_ms`):
    /// the JavaScript layer passes `performance.now()`.
    pub fn solve_with_clock(
        &mut self,
        values: &mut [f64],
        clock: Option<&dyn Clock>,
    ) -> JsResult<String> {
        let mut posture = self.posture(values)?;
        let body = self.humanoid.as_ref();
        let tasks = FrameProblem {
            specs: &self.specs,
            comfort: self.grab.is_none(),
            held: None,
            grab: self.grab,
            obstacles: &[],
            collisions: &[],
        }
        .tasks(&self.skeleton, body);
        let report = match clock {
            Some(clock) => {
                self.solver
                    .solve_with_clock(&self.skeleton, &tasks, &mut posture, Some(clock))
            }
            None => self.solver.solve(&self.skeleton, &tasks, &mut posture),
        }
        .map_err(|e| e.to_string())?;
        values.copy_from_slice(posture.values());
        let settled = matches!(report.status, SolveStatus::Converged | SolveStatus::Stalled);
        let frames = Frames::new(&self.skeleton, &posture);
        let statuses = task_statuses(
            &self.skeleton,
            body,
            &posture,
            &frames,
            &self.specs,
            settled,
        );
        let mut out = serde_json::to_value(&report).map_err(|e| e.to_string())?;
        if let Some(o) = out.as_object_mut() {
            o.insert("tasks".to_owned(), statuses_json(&self.specs, &statuses));
        }
        self.report = Some(report);
        Ok(out.to_string())
    }

    /// World transforms of every joint at `values` into `out`: 7 numbers per joint, the
    /// position `x y z` and the `world_from_joint` rotation `qx qy qz qw`.
    pub fn world_transforms(&self, values: &[f64], out: &mut [f64]) -> JsResult<()> {
        let n = self.skeleton.joint_count();
        if out.len() != 7 * n {
            return Err(format!(
                "out: {} numbers for {n} joints, expected {}",
                out.len(),
                7 * n
            ));
        }
        let frames = Frames::new(&self.skeleton, &self.posture(values)?);
        for j in 0..n {
            let p = frames.joint_position[j];
            let q = frames.rotation(j);
            out[7 * j..7 * j + 7].copy_from_slice(&[p.x, p.y, p.z, q.x, q.y, q.z, q.w]);
        }
        Ok(())
    }

    /// The closed-form limb (`l_arm`, `r_arm`, `l_leg`, `r_leg`): puts its end joint at
    /// `target` (world, 3 numbers) with the swivel angle `swivel` (rad; `None` keeps the
    /// current one) and the optional end orientation `[qx, qy, qz, qw]`, moved to the nearest
    /// swivel within the joint limits; writes into `values`. Returns
    /// `{"swivel", "reached", "within_limits"}` (JSON text).
    pub fn solve_limb(
        &self,
        values: &mut [f64],
        name: &str,
        target: &[f64],
        swivel: Option<f64>,
        orientation: Option<Vec<f64>>,
    ) -> JsResult<String> {
        let limb = limb(&self.skeleton, name)?;
        let position = vec3("target", target)?;
        let orientation = match orientation {
            None => None,
            Some(q) => {
                let [qx, qy, qz, qw] = <[f64; 4]>::try_from(q.as_slice())
                    .map_err(|_| "orientation: expected 4 numbers".to_owned())?;
                let q = DQuat::from_xyzw(qx, qy, qz, qw);
                if !(q.is_finite() && q.length() > 1e-9) {
                    return Err("orientation: the quaternion has zero length".to_owned());
                }
                Some(q.normalize())
            }
        };
        let mut posture = self.posture(values)?;
        let frames = Frames::new(&self.skeleton, &posture);
        let base = limb.base(&self.skeleton, &frames);
        let preferred = swivel.unwrap_or_else(|| limb.swivel_angle(&self.skeleton, &posture));
        let goal = LimbGoal {
            position,
            orientation,
        };
        let solution = limb.solve_within_limits(base, &goal, preferred);
        limb.apply(&solution, &mut posture);
        values.copy_from_slice(posture.values());
        Ok(serde_json::json!({
            "swivel": solution.swivel_angle,
            "reached": solution.reached,
            "within_limits": solution.within_limits,
        })
        .to_string())
    }

    /// The swivel angle of a limb at `values` (rad).
    pub fn swivel_angle(&self, values: &[f64], name: &str) -> JsResult<f64> {
        let limb = limb(&self.skeleton, name)?;
        Ok(limb.swivel_angle(&self.skeleton, &self.posture(values)?))
    }
}

/// A limb by its H-Anim shorthand on `skeleton`.
fn limb(skeleton: &Skeleton, name: &str) -> JsResult<Limb> {
    LimbName::from_name(name)
        .ok_or_else(|| {
            format!("limb: unknown limb `{name}` (expected l_arm, r_arm, l_leg or r_leg)")
        })?
        .on(skeleton)
        .map_err(|e| e.to_string())
}
