//! The JavaScript surface (`wasm-bindgen`): converts JavaScript values to and from the core's
//! types; errors become thrown `Error`s whose message names the field. The package's
//! `index.js` wraps these with friendlier names and JSON handling.

use wasm_bindgen::prelude::*;

use crate::{Body, PoseSolver};

/// JSON text of a JavaScript value: a string is taken as JSON text already.
fn text_of(value: &JsValue) -> Result<String, JsError> {
    if let Some(s) = value.as_string() {
        return Ok(s);
    }
    if value.is_undefined() || value.is_null() {
        return Ok(String::new());
    }
    js_sys::JSON::stringify(value)
        .map(String::from)
        .map_err(|_| JsError::new("not serialisable as JSON"))
}

fn parsed(text: &str) -> Result<JsValue, JsError> {
    js_sys::JSON::parse(text).map_err(|_| JsError::new("internal: invalid JSON output"))
}

/// `performance.now()` (browsers and Node), for the solver's time budget.
fn performance_now_ms() -> f64 {
    js_sys::Reflect::get(&js_sys::global(), &"performance".into())
        .ok()
        .and_then(|performance| {
            let now = js_sys::Reflect::get(&performance, &"now".into()).ok()?;
            js_sys::Function::from(now)
                .call0(&performance)
                .ok()?
                .as_f64()
        })
        .unwrap_or_else(js_sys::Date::now)
}

fn error(message: String) -> JsError {
    JsError::new(&message)
}

/// Solves a problem (an object or JSON text in the format of `stance solve`) and returns the
/// same object as `stance solve` prints: `joints`, `posture`, `report` (and `limbs`).
#[wasm_bindgen(js_name = solve)]
pub fn solve(problem: &JsValue) -> Result<JsValue, JsError> {
    parsed(&crate::solve_json(&text_of(problem)?).map_err(error)?)
}

/// A skeleton built once.
#[wasm_bindgen(js_name = Skeleton)]
pub struct JsSkeleton {
    body: Body,
}

#[wasm_bindgen(js_class = Skeleton)]
impl JsSkeleton {
    /// The H-Anim default body at level of articulation 1 to 4.
    pub fn hanim(loa: u8) -> Result<JsSkeleton, JsError> {
        Ok(Self {
            body: Body::hanim(loa).map_err(error)?,
        })
    }

    /// A problem file's `skeleton` object (`{joints: [{name, parent, offset, dofs, limits,
    /// mass, com}]}`) or its JSON text.
    #[wasm_bindgen(js_name = fromJoints)]
    pub fn from_joints(skeleton: &JsValue) -> Result<JsSkeleton, JsError> {
        Ok(Self {
            body: Body::from_joints(&text_of(skeleton)?).map_err(error)?,
        })
    }

    /// A skin's joints mapped onto H-Anim: names, parent indices (-1 for a root), rest
    /// positions (x y z per joint, +Y up, facing +Z, metres) and the level of articulation.
    #[wasm_bindgen(js_name = fromSkin)]
    pub fn from_skin(
        names: Vec<String>,
        parents: &[i32],
        rest: &[f64],
        loa: u8,
    ) -> Result<JsSkeleton, JsError> {
        Ok(Self {
            body: Body::from_skin(&names, parents, rest, loa).map_err(error)?,
        })
    }

    /// The tasks a new body starts with at the posture `values` (a task array, as
    /// `Solver.setTasks` takes it): each ankle pinned where it is, balance over the pinned
    /// feet, then comfort; the editor's defaults.
    #[wasm_bindgen(js_name = defaultTasks)]
    pub fn default_tasks(&self, values: &[f64]) -> Result<JsValue, JsError> {
        parsed(&self.body.default_tasks(values).map_err(error)?)
    }

    /// Joint names, in skeleton order.
    #[wasm_bindgen(getter, js_name = jointNames)]
    pub fn joint_names(&self) -> Vec<String> {
        self.body.joint_names()
    }

    /// `joint.dof` names, in DOF order (the order of the values arrays).
    #[wasm_bindgen(getter, js_name = dofNames)]
    pub fn dof_names(&self) -> Vec<String> {
        self.body.dof_names()
    }

    /// Number of DOF (the length of a values array).
    #[wasm_bindgen(getter, js_name = dofCount)]
    pub fn dof_count(&self) -> usize {
        self.body.skeleton.dof_count()
    }

    /// For a skeleton built from a skin: per joint, the skin joint index it stands for (-1:
    /// none).
    #[wasm_bindgen(getter, js_name = skinJoints)]
    pub fn skin_joints(&self) -> Vec<i32> {
        self.body.source.clone()
    }

    /// Per joint, `qx qy qz qw`: the world rotation that turns its skin bone at the skin's
    /// rest onto the H-Anim standard pose (the skeleton's rest). A bone's world rotation at a
    /// posture is `worldTransforms`' rotation × `restMatch` × its rest world rotation.
    #[wasm_bindgen(getter, js_name = restMatch)]
    pub fn rest_match(&self) -> Vec<f64> {
        self.body.rest_match.clone()
    }

    /// How the skeleton was built (JSON text): the package's retargeting module builds the
    /// same skeleton from it.
    #[wasm_bindgen(getter)]
    pub fn recipe(&self) -> String {
        self.body.recipe_json()
    }
}

/// Tasks by level on a skeleton, solved every frame into a reused `Float64Array`.
#[wasm_bindgen(js_name = Solver)]
pub struct JsSolver {
    inner: PoseSolver,
}

#[wasm_bindgen(js_class = Solver)]
impl JsSolver {
    /// A solver on `skeleton` with optional `settings` (a problem file's `settings`).
    #[wasm_bindgen(constructor)]
    pub fn new(skeleton: &JsSkeleton, settings: &JsValue) -> Result<JsSolver, JsError> {
        Ok(Self {
            inner: PoseSolver::new(&skeleton.body, &text_of(settings)?).map_err(error)?,
        })
    }

    /// Sets the tasks: an array (or its JSON text) of tasks as in a problem file's `tasks`.
    #[wasm_bindgen(js_name = setTasks)]
    pub fn set_tasks(&mut self, tasks: &JsValue) -> Result<(), JsError> {
        self.inner.set_tasks(&text_of(tasks)?).map_err(error)
    }

    /// Grab-and-pull: pulls `point` (in the frame of `joint`) toward `target` (world), one
    /// level below every task, from the next `solve` on (comfort waits meanwhile).
    pub fn pull(&mut self, joint: &str, point: &[f64], target: &[f64]) -> Result<(), JsError> {
        self.inner.pull(joint, point, target).map_err(error)
    }

    /// Lets go of the pulled point.
    pub fn release(&mut self) {
        self.inner.release();
    }

    /// Solves from `values` (one per DOF), writes the solution into them and returns the
    /// report (`status`, `iterations`, `levels`, `gave_way`, and `tasks`: per task its level,
    /// residual, whether it is met and why it gave way).
    pub fn solve(&mut self, values: &mut [f64]) -> Result<JsValue, JsError> {
        let clock = || performance_now_ms() / 1000.0;
        parsed(
            &self
                .inner
                .solve_with_clock(values, Some(&clock))
                .map_err(error)?,
        )
    }

    /// Writes 7 numbers per joint into `out` (position x y z, rotation qx qy qz qw).
    #[wasm_bindgen(js_name = worldTransforms)]
    pub fn world_transforms(&self, values: &[f64], out: &mut [f64]) -> Result<(), JsError> {
        self.inner.world_transforms(values, out).map_err(error)
    }

    /// The closed-form limb (`l_arm`, `r_arm`, `l_leg`, `r_leg`) to `target` with an optional
    /// swivel angle and end orientation; writes into `values`; returns `{swivel, reached,
    /// within_limits}`.
    #[wasm_bindgen(js_name = solveLimb)]
    pub fn solve_limb(
        &self,
        values: &mut [f64],
        limb: &str,
        target: &[f64],
        swivel: Option<f64>,
        orientation: Option<Vec<f64>>,
    ) -> Result<JsValue, JsError> {
        parsed(
            &self
                .inner
                .solve_limb(values, limb, target, swivel, orientation)
                .map_err(error)?,
        )
    }

    /// The swivel angle of a limb at `values` (rad).
    #[wasm_bindgen(js_name = swivelAngle)]
    pub fn swivel_angle(&self, values: &[f64], limb: &str) -> Result<f64, JsError> {
        self.inner.swivel_angle(values, limb).map_err(error)
    }
}
