//! The iterative solver: linearise every level, take a prioritized step, enforce joint
//! limits, repeat until converged, stalled or out of budget; report per-level residuals.
//!
//! The settings live in the submodule `settings`, the report types in `report`, the
//! multi-start's later runs and the hybrid's limb restart in `restart`, a comfort level's
//! share of a step kept inside the joint limits in `comfort_step`, and an inequality's rows
//! added where a step would carry it past its bound in `active_set`.

mod active_set;
mod comfort_step;
mod report;
mod restart;
mod settings;

use std::collections::BTreeMap;

use nalgebra::{DMatrix, DVector};

pub use report::{AnalyticRestart, LevelReport, SolveReport, SolveStatus};
#[cfg(not(all(target_arch = "wasm32", target_os = "unknown")))]
pub use settings::SystemClock;
use settings::validate_damping;
pub use settings::{
    Backend, CONSTANT_DAMPING, Clock, Iteration, SolverSettings, TEXTBOOK_ANGULAR_STEP,
    TEXTBOOK_LINEAR_STEP, WHOLE_SOLVE_DAMPING,
};

use crate::kernel::prioritized_step;
use crate::limb::Limb;
use crate::posture::clamp_and_wrap;
use crate::priority::{Damping, LevelSystem, StepWorkspace, prioritized_step_nalgebra};
use crate::task::{NearList, StepLimits};
use crate::{Frames, IkError, Posture, Skeleton, Task};
use active_set::Candidates;
use comfort_step::StepLimitsAt;

/// Relative decrease below which an unmet level counts as not progressing.
const STALL_RELATIVE: f64 = 1e-4;
/// Iterations without a meaningful fall of a comfort level's cost, every other level met,
/// before the solve has converged.
const COMFORT_STALL_WINDOW: usize = 3;
/// The comfort step's gain grows by this after a step that lowered the cost...
const COMFORT_GAIN_UP: f64 = 1.5;
/// ... up to this...
const COMFORT_GAIN_MAX: f64 = 20.0;
/// ... and halves after a step that did not, down to this.
const COMFORT_GAIN_MIN: f64 = 0.05;

/// Cached per-solve task layout.
#[derive(Debug, Clone, Default)]
struct LevelLayout {
    level: u32,
    tasks: Vec<usize>,
    rows: usize,
    /// Never "met" (posture attraction, comfort): not in the convergence test.
    posture_only: bool,
    /// A comfort level: never met, but compared in priority order (its residual is the
    /// cost), so that the solve goes on while the cost falls.
    comfort: bool,
    /// Holds a task whose rows in use vary with the posture (collision): `rows` is then the
    /// most the level has, and its support is found at each linearisation.
    variable: bool,
}

/// How one run of iterations ended.
struct RunOutcome {
    status: SolveStatus,
    iterations: usize,
    clamped_dofs: usize,
    analytic_restarts: Vec<AnalyticRestart>,
}

/// The prioritized inverse-kinematics solver. Keeps its buffers between solves.
#[derive(Debug, Clone, Default)]
pub struct Solver {
    /// Settings used by [`Solver::solve`].
    pub settings: SolverSettings,
    /// Limbs for the hybrid (the paper's conclusion): when a solve stalls with an unmet
    /// position task on a limb's end joint, the limb restarts once from its closed-form
    /// solution (swivel kept as far as the limits allow) and the iterations go on. Empty by
    /// default (pure variational solver).
    pub limbs: Vec<Limb>,
    /// Damping of particular levels (level number -> damping), overriding
    /// `settings.damping` there: e.g. more damping on a level that is expected to conflict
    /// with the ones above (an algorithmic singularity), none on a level that must converge
    /// fast. Empty by default.
    pub level_damping: BTreeMap<u32, Damping>,
    /// DOF held where they are (driven from outside, e.g. by motion-capture sensors): they
    /// leave every step like clamped DOF, and no hybrid restart moves them. Empty: none.
    locked: Vec<bool>,
    frames: Frames,
    layout: Vec<LevelLayout>,
    supports: Vec<Vec<usize>>,
    systems: Vec<LevelSystem>,
    /// Each level's inequality rows not yet held (see `active_set`).
    candidates: Vec<Candidates>,
    /// Each task's pairs near enough to search (collision), kept from one linearisation to
    /// the next while the body moves little.
    near: Vec<NearList>,
    residual_sq: Vec<f64>,
    workspace: StepWorkspace,
    fixed: DVector<f64>,
    weighted_sq: Vec<f64>,
    scratch: Vec<f64>,
    /// The level systems in the stiffness-weighted coordinates (see `compute_step`).
    weighted: Vec<LevelSystem>,
    /// Gain of the comfort levels' gradient step, adapted along a run (see `run`).
    comfort_gain: f64,
    /// Whether the last linearisation let a comfort level step.
    comfort_stepping: bool,
    /// Whether the comfort levels' residuals hold their cost at a posture of this run: a
    /// comfort level waiting for the levels above keeps that cost instead of weighing it
    /// again (see `linearize_at_frames`).
    comfort_known: bool,
}

impl Solver {
    /// A solver with these settings (checked).
    pub fn new(settings: SolverSettings) -> Result<Self, IkError> {
        settings.validate()?;
        Ok(Self {
            settings,
            ..Self::default()
        })
    }

    /// The same solver with limbs for the hybrid restart (builder style; see `limbs`).
    pub fn with_limbs(mut self, limbs: Vec<Limb>) -> Self {
        self.limbs = limbs;
        self
    }

    /// Holds these DOF (posture indices) where they are in the following solves; an empty
    /// slice frees them all. Indices past the skeleton's DOF are ignored.
    pub fn set_locked_dofs(&mut self, dofs: &[usize]) {
        self.locked.clear();
        if let Some(&last) = dofs.iter().max() {
            self.locked.resize(last + 1, false);
            for &dof in dofs {
                self.locked[dof] = true;
            }
        }
    }

    /// Clamps into the limits and re-wraps, except the held DOF, which stay as they were set.
    fn clamp_free(&self, skeleton: &Skeleton, values: &mut [f64]) {
        let held: Vec<(usize, f64)> = self
            .locked
            .iter()
            .enumerate()
            .filter(|&(_, &locked)| locked)
            .filter_map(|(d, _)| values.get(d).map(|&v| (d, v)))
            .collect();
        clamp_and_wrap(skeleton, values);
        for (d, v) in held {
            values[d] = v;
        }
    }

    /// True when `dof` is held by [`Solver::set_locked_dofs`].
    pub fn is_locked(&self, dof: usize) -> bool {
        self.locked.get(dof).copied().unwrap_or(false)
    }

    /// Solves from `posture`, which receives the result; reads the system clock for the time
    /// budget where one exists (never on `wasm32-unknown-unknown`).
    pub fn solve(
        &mut self,
        skeleton: &Skeleton,
        tasks: &[Task],
        posture: &mut Posture,
    ) -> Result<SolveReport, IkError> {
        #[cfg(not(all(target_arch = "wasm32", target_os = "unknown")))]
        {
            let clock = SystemClock::default();
            self.solve_with_clock(skeleton, tasks, posture, Some(&clock))
        }
        #[cfg(all(target_arch = "wasm32", target_os = "unknown"))]
        {
            self.solve_with_clock(skeleton, tasks, posture, None)
        }
    }

    /// Solves with an explicit clock (or none: the time budget is then ignored).
    pub fn solve_with_clock(
        &mut self,
        skeleton: &Skeleton,
        tasks: &[Task],
        posture: &mut Posture,
        clock: Option<&dyn Clock>,
    ) -> Result<SolveReport, IkError> {
        self.settings.validate()?;
        for &d in self.level_damping.values() {
            validate_damping(d)?;
        }
        self.prepare(skeleton, tasks, posture)?;
        let start = clock.map(|c| c.now_secs());
        let values = posture.values_mut();
        self.clamp_free(skeleton, values);
        let initial = values.to_vec();
        let before = self.linearize(skeleton, tasks, values);
        let mut run = self.run(skeleton, tasks, values, clock, start);
        // Multi-start: the trust region, the guarded safeguards and the plain recursion stop
        // short on different problems (a step's length decides which basin a problem falls
        // into; an inequality that switches on and off makes whole steps oscillate). A stalled
        // solve goes on with the other kinds of run in turn, each kept only if better in
        // priority order.
        for stage in self.restart_stages() {
            let time_left = match (clock, start, self.settings.time_budget_secs) {
                (Some(c), Some(s), Some(budget)) => c.now_secs() - s < 0.5 * budget,
                _ => true,
            };
            let iterations_left = self.settings.max_iterations.saturating_sub(run.iterations);
            if !(run.status == SolveStatus::Stalled && iterations_left > 0 && time_left) {
                break;
            }
            let first_values = values.to_vec();
            let first_residuals = self.residual_sq.clone();
            let saved = self.settings;
            self.settings.iteration = stage.iteration;
            self.settings.trust_region = stage.trust_region;
            self.settings.stall_window = stage.stall_window;
            self.settings.max_linear_step = stage.max_linear_step;
            self.settings.max_angular_step = stage.max_angular_step;
            self.settings.damping = stage.damping;
            self.settings.priority_budget = stage.priority_budget;
            self.settings.max_iterations = iterations_left;
            if stage.from_start {
                values.copy_from_slice(&initial);
            }
            self.comfort_known = false;
            self.linearize(skeleton, tasks, values);
            let next = self.run(skeleton, tasks, values, clock, start);
            self.settings = saved;
            let iterations = run.iterations + next.iterations;
            if self.lexicographically_better(&self.residual_sq, &first_residuals) {
                let mut restarts = run.analytic_restarts;
                restarts.extend(next.analytic_restarts);
                run = RunOutcome {
                    analytic_restarts: restarts,
                    ..next
                };
            } else {
                values.copy_from_slice(&first_values);
                self.residual_sq = first_residuals;
            }
            run.iterations = iterations;
        }
        let RunOutcome {
            status,
            iterations,
            clamped_dofs,
            analytic_restarts,
        } = run;
        if self.layout.iter().any(|l| l.comfort) {
            self.weigh_levels(skeleton, tasks, values, true);
        }
        let levels = self.level_reports(&before);
        let gave_way = levels
            .iter()
            .find(|l| !l.posture_only && !l.met)
            .map(|l| l.level);
        Ok(SolveReport {
            status,
            iterations,
            levels,
            gave_way,
            clamped_dofs,
            elapsed_secs: match (clock, start) {
                (Some(c), Some(s)) => Some(c.now_secs() - s),
                _ => None,
            },
            analytic_restarts,
        })
    }

    /// One report per level: its residuals `before` (squared) and now.
    fn level_reports(&self, before: &[f64]) -> Vec<LevelReport> {
        let tol = self.settings.tolerance;
        self.layout
            .iter()
            .zip(&self.systems)
            .zip(before.iter().zip(&self.residual_sq))
            .map(|((l, system), (b, a))| LevelReport {
                level: l.level,
                tasks: l.tasks.len(),
                // A level whose rows vary (collisions): those in use when last linearised.
                rows: if l.variable { system.dx.len() } else { l.rows },
                residual_before: b.sqrt(),
                residual_after: a.sqrt(),
                met: a.sqrt() <= tol,
                posture_only: l.posture_only,
            })
            .collect()
    }

    /// Iterates from `values` (linearised) until converged, stalled or out of budget, and
    /// leaves the best posture met on the way in `values` (the last one unless a lower
    /// level's pull left a higher level worse than it was), with its residuals.
    fn run(
        &mut self,
        skeleton: &Skeleton,
        tasks: &[Task],
        values: &mut [f64],
        clock: Option<&dyn Clock>,
        start: Option<f64>,
    ) -> RunOutcome {
        let mut best_values = values.to_vec();
        let mut best_residuals = self.residual_sq.clone();
        let mut iterations = 0;
        let mut clamped_dofs = 0;
        let mut flat_iterations = 0;
        let mut analytic_restarts = Vec::new();
        let tol = self.settings.tolerance;
        let comfort = self.layout.iter().any(|l| l.comfort);
        // The comfort cost where the last comfort step not yet judged started.
        let mut stepped_from: Option<f64> = None;
        let status = loop {
            // With a comfort level, "met" is not the end: the cost falls while it can.
            if self.all_met(tol) && (!comfort || flat_iterations >= COMFORT_STALL_WINDOW) {
                break SolveStatus::Converged;
            }
            if iterations >= self.settings.max_iterations {
                break SolveStatus::IterationBudget;
            }
            if let (Some(c), Some(s), Some(budget)) = (clock, start, self.settings.time_budget_secs)
                && c.now_secs() - s >= budget
            {
                break SolveStatus::TimeBudget;
            }
            // Whether this iteration's comfort level steps (see `linearize_at_frames`).
            if self.comfort_stepping && stepped_from.is_none() {
                stepped_from = Some(self.comfort_cost());
            }
            let (moved, clamped) = self.iteration(skeleton, tasks, values);
            // A gradient step with an adaptive length: longer while the cost falls, half as
            // long when it rose. Judged where the cost is next weighed, with the comfort level
            // stepping again (the iterations between pull back the drift of the levels above).
            if self.comfort_stepping
                && let Some(before) = stepped_from.take()
            {
                self.comfort_gain = if self.comfort_cost() < before {
                    (self.comfort_gain * COMFORT_GAIN_UP).min(COMFORT_GAIN_MAX)
                } else {
                    (self.comfort_gain * 0.5).max(COMFORT_GAIN_MIN)
                };
            }
            clamped_dofs = clamped;
            iterations += 1;
            if self.meaningfully_better(&self.residual_sq, &best_residuals) {
                flat_iterations = 0;
            } else {
                flat_iterations += 1;
            }
            if self.lexicographically_better(&self.residual_sq, &best_residuals) {
                best_values.copy_from_slice(values);
                best_residuals.clone_from(&self.residual_sq);
            }
            if moved <= self.settings.stall_step
                || flat_iterations >= self.settings.stall_window.max(1)
            {
                if self.all_met(tol) {
                    break SolveStatus::Converged;
                }
                if let Some(restart) =
                    self.analytic_restart(skeleton, tasks, values, iterations, &analytic_restarts)
                {
                    analytic_restarts.push(restart);
                    flat_iterations = 0;
                    continue;
                }
                break SolveStatus::Stalled;
            }
        };
        if self.lexicographically_better(&best_residuals, &self.residual_sq) {
            values.copy_from_slice(&best_values);
            self.residual_sq = best_residuals;
        }
        RunOutcome {
            status,
            iterations,
            clamped_dofs,
            analytic_restarts,
        }
    }

    /// One prioritized iteration from `posture` (for interactive use: a few per frame).
    /// Returns the largest DOF change.
    pub fn iterate(
        &mut self,
        skeleton: &Skeleton,
        tasks: &[Task],
        posture: &mut Posture,
    ) -> Result<f64, IkError> {
        self.settings.validate()?;
        self.prepare(skeleton, tasks, posture)?;
        let values = posture.values_mut();
        self.clamp_free(skeleton, values);
        self.linearize(skeleton, tasks, values);
        Ok(self.iteration(skeleton, tasks, values).0)
    }

    /// The linearised levels at `posture` (for tests and tools): `J_k^T` and `dx_k` per level.
    pub fn linear_systems(
        &mut self,
        skeleton: &Skeleton,
        tasks: &[Task],
        posture: &Posture,
    ) -> Result<Vec<LevelSystem>, IkError> {
        self.prepare(skeleton, tasks, posture)?;
        self.linearize(skeleton, tasks, posture.values());
        Ok(self.systems.clone())
    }

    fn all_met(&self, tol: f64) -> bool {
        self.layout
            .iter()
            .zip(&self.residual_sq)
            .all(|(l, r)| l.posture_only || r.sqrt() <= tol)
    }

    fn prepare(
        &mut self,
        skeleton: &Skeleton,
        tasks: &[Task],
        posture: &Posture,
    ) -> Result<(), IkError> {
        if posture.values().len() != skeleton.dof_count() {
            return Err(IkError::PostureSize {
                expected: skeleton.dof_count(),
                got: posture.values().len(),
            });
        }
        if let Some(i) = posture.values().iter().position(|v| !v.is_finite()) {
            return Err(IkError::NotFinite {
                what: format!("posture value {i}"),
            });
        }
        for (i, t) in tasks.iter().enumerate() {
            t.validate(skeleton, i)?;
        }
        let mut levels: Vec<u32> = tasks
            .iter()
            .filter(|t| t.active && t.rows() > 0)
            .map(|t| t.level)
            .collect();
        levels.sort_unstable();
        levels.dedup();
        self.layout = levels
            .iter()
            .map(|&level| {
                let members: Vec<usize> = tasks
                    .iter()
                    .enumerate()
                    .filter(|(_, t)| t.active && t.rows() > 0 && t.level == level)
                    .map(|(i, _)| i)
                    .collect();
                LevelLayout {
                    level,
                    rows: members.iter().map(|&i| tasks[i].rows()).sum(),
                    posture_only: members.iter().all(|&i| tasks[i].is_posture()),
                    comfort: members.iter().any(|&i| tasks[i].is_comfort()),
                    variable: members.iter().any(|&i| tasks[i].rows_vary()),
                    tasks: members,
                }
            })
            .collect();
        for layout in &self.layout {
            if layout.comfort
                && let Some(&other) = layout.tasks.iter().find(|&&i| !tasks[i].is_comfort())
            {
                return Err(IkError::BadTask {
                    index: other,
                    reason: format!(
                        "level {} holds a comfort task: it cannot share it with other kinds",
                        layout.level
                    ),
                });
            }
        }
        self.supports = tasks.iter().map(|t| t.support(skeleton)).collect();
        let n = skeleton.dof_count();
        self.systems.resize_with(self.layout.len(), || LevelSystem {
            level: 0,
            jacobian_t: DMatrix::zeros(0, 0),
            dx: DVector::zeros(0),
            support: Vec::new(),
            damping: None,
            projection: false,
        });
        for (sys, l) in self.systems.iter_mut().zip(&self.layout) {
            sys.level = l.level;
            sys.damping = self.level_damping.get(&l.level).copied();
            sys.projection = l.comfort;
            let mut support: Vec<usize> = l
                .tasks
                .iter()
                .flat_map(|&t| self.supports[t].iter().copied())
                .collect();
            support.sort_unstable();
            support.dedup();
            sys.support = support;
            if sys.jacobian_t.shape() != (n, l.rows) {
                sys.jacobian_t = DMatrix::zeros(n, l.rows);
                sys.dx = DVector::zeros(l.rows);
            }
        }
        self.candidates
            .resize_with(self.layout.len(), Candidates::default);
        self.near.resize_with(tasks.len(), NearList::default);
        self.residual_sq = vec![0.0; self.layout.len()];
        self.weighted_sq = vec![0.0; self.layout.len()];
        self.comfort_gain = 1.0;
        self.comfort_known = false;
        Ok(())
    }

    /// Forward kinematics + all level systems; returns the squared residual per level.
    fn linearize(&mut self, skeleton: &Skeleton, tasks: &[Task], values: &[f64]) -> Vec<f64> {
        self.frames.update(skeleton, values);
        self.linearize_at_frames(skeleton, tasks, values)
    }

    /// All level systems at `values`, whose forward kinematics `self.frames` already holds.
    fn linearize_at_frames(
        &mut self,
        skeleton: &Skeleton,
        tasks: &[Task],
        values: &[f64],
    ) -> Vec<f64> {
        let n = skeleton.dof_count();
        let limits = StepLimits {
            linear: self.settings.max_linear_step,
            angular: self.settings.max_angular_step,
        };
        let tol2 = self.settings.tolerance * self.settings.tolerance;
        let mut above_met = true;
        let mut comfort_stepping = false;
        for ((((layout, sys), res), wres), candidates) in self
            .layout
            .iter()
            .zip(self.systems.iter_mut())
            .zip(self.residual_sq.iter_mut())
            .zip(self.weighted_sq.iter_mut())
            .zip(self.candidates.iter_mut())
        {
            candidates.clear();
            if layout.comfort && !above_met && self.comfort_known {
                // A comfort level waiting for the levels above it (see below) keeps the cost
                // it had when last weighed: a zero step, which the kernel skips. The levels
                // above only pull back the drift of its last step; its cost is weighed again
                // with its gradient once they are met (the solve's report weighs it afresh).
                sys.dx.fill(0.0);
                sys.jacobian_t.as_mut_slice().fill(0.0);
                continue;
            }
            // The level's rows written on plain buffers at full size (no allocation once they
            // have it), then cut to the rows in use: a collision task uses only the rows of the
            // constraints it found, and a level without any has no rows at all (the kernel
            // skips it).
            let mut jt_all: Vec<f64> = std::mem::take(&mut sys.jacobian_t).data.into();
            let mut dx_all: Vec<f64> = std::mem::take(&mut sys.dx).data.into();
            jt_all.clear();
            jt_all.resize(n * layout.rows, 0.0);
            dx_all.clear();
            dx_all.resize(layout.rows, 0.0);
            let mut row = 0;
            *res = 0.0;
            *wres = 0.0;
            for &ti in &layout.tasks {
                let task = &tasks[ti];
                let rows = task.rows();
                let err = &mut dx_all[row..row + rows];
                let jt = &mut jt_all[row * n..(row + rows) * n];
                let support = &self.supports[ti];
                // A comfort level waiting for the levels above it (see below) only weighs its
                // cost: no gradient, an empty row the kernel skips. Comfort and collision find
                // their rows and errors at once.
                let waiting = layout.comfort && !above_met;
                let at_once = if waiting {
                    err.fill(0.0);
                    task.comfort_cost(skeleton, &self.frames, values)
                        .map(|cost| (cost, rows, rows))
                } else {
                    task.system_at_once(
                        skeleton,
                        &self.frames,
                        values,
                        support,
                        (err, jt, n),
                        Some(limits),
                        &mut self.near[ti],
                    )
                };
                let (r, used, held) = match at_once {
                    Some(r) => r,
                    None => {
                        let r = task.error(skeleton, &self.frames, values, err, Some(limits));
                        task.jacobian_t(skeleton, &self.frames, values, support, jt, n);
                        (r, rows, rows)
                    }
                };
                *res += r * r;
                *wres += task.weight * r * r;
                let w = task.weight.sqrt();
                if w != 1.0 {
                    err[..used].iter_mut().for_each(|v| *v *= w);
                    jt[..used * n].iter_mut().for_each(|v| *v *= w);
                }
                // An inequality's rows past those held wait as candidates (`active_set`);
                // their space is the next task's, zeroed.
                for k in held..used {
                    candidates.push(&jt[k * n..(k + 1) * n], err[k]);
                }
                jt[held * n..used * n].fill(0.0);
                err[held..used].fill(0.0);
                row += held;
            }
            dx_all.truncate(row);
            jt_all.truncate(row * n);
            sys.dx = DVector::from_vec(dx_all);
            sys.jacobian_t = DMatrix::from_vec(n, row, jt_all);
            if layout.variable {
                // The support of the rows in use: the DOF with a nonzero entry.
                sys.support.clear();
                sys.support
                    .extend((0..n).filter(|&d| (0..row).any(|c| sys.jacobian_t[(d, c)] != 0.0)));
            }
            candidates.linearised(sys);
            if layout.comfort {
                if above_met {
                    // The adaptive gain of the comfort's gradient step (see `run`).
                    let most = self.settings.max_angular_step;
                    sys.dx
                        .iter_mut()
                        .for_each(|v| *v = (*v * self.comfort_gain).clamp(-most, most));
                    comfort_stepping = true;
                } else {
                    // A comfort level waits until every level above it is met: its steps would
                    // keep disturbing them through the non-linearity; once they are met it
                    // moves along the surface they leave, and the next iterations pull back
                    // the drift.
                    sys.dx.fill(0.0);
                }
            }
            above_met &= layout.posture_only || *res <= tol2;
        }
        self.comfort_stepping = comfort_stepping;
        self.comfort_known = true;
        self.residual_sq.clone()
    }

    /// Forward kinematics at `values` and the squared residuals of the comfort levels
    /// (`comfort`) or of the others (no Jacobian). A guarded step's candidates weigh the other
    /// levels only: no candidate is judged by a comfort level, and the candidate taken is
    /// linearised, which weighs it (or keeps the cost of a waiting one, see
    /// `linearize_at_frames`); a solve's report weighs the comfort levels afresh.
    fn weigh_levels(&mut self, skeleton: &Skeleton, tasks: &[Task], values: &[f64], comfort: bool) {
        self.frames.update(skeleton, values);
        for ((layout, res), wres) in self
            .layout
            .iter()
            .zip(self.residual_sq.iter_mut())
            .zip(self.weighted_sq.iter_mut())
            .filter(|((l, _), _)| l.comfort == comfort)
        {
            *res = 0.0;
            *wres = 0.0;
            for &ti in &layout.tasks {
                let task = &tasks[ti];
                let r = task.residual_with(skeleton, &self.frames, values, &mut self.scratch);
                *res += r * r;
                *wres += task.weight * r * r;
            }
        }
    }

    /// One iteration as the textbook recursion takes it: the prioritized step of every level
    /// at once (each task's error clamped by the linearisation) with the joint-limit clamping
    /// loop, scaled into the trust region, nothing else (no cascade, no line search, no
    /// shared budget). Leaves the systems
    /// linearised at the new `values`. Returns (largest DOF change, clamped DOF count).
    fn textbook_iteration(
        &mut self,
        skeleton: &Skeleton,
        tasks: &[Task],
        values: &mut [f64],
    ) -> (f64, usize) {
        let (mut step, clamped) = self.compute_step(skeleton, values, self.layout.len());
        // The trust region: the whole step scaled, its direction kept (`values + step` stays
        // inside the limits: both ends are).
        let longest = step.amax();
        if longest > self.settings.trust_region {
            step *= self.settings.trust_region / longest;
        }
        let mut moved: f64 = 0.0;
        for (v, d) in values.iter_mut().zip(step.iter()) {
            *v += d;
            moved = moved.max(d.abs());
        }
        self.clamp_free(skeleton, values);
        self.linearize(skeleton, tasks, values);
        (moved, clamped)
    }

    /// One iteration of the kind the settings ask for.
    fn iteration(
        &mut self,
        skeleton: &Skeleton,
        tasks: &[Task],
        values: &mut [f64],
    ) -> (f64, usize) {
        match self.settings.iteration {
            Iteration::Guarded => self.guarded_iteration(skeleton, tasks, values),
            Iteration::Textbook => self.textbook_iteration(skeleton, tasks, values),
        }
    }

    /// One iteration from `values`, where the systems are linearised: prioritized step with
    /// joint limits, then step-length control. While the step makes the residuals clearly
    /// worse in priority order (see `first_worse_level`), it is halved (up to 3 times); if
    /// that is not enough, the levels below the one that got worse are dropped and the step
    /// is recomputed and halved again. Leaves the systems linearised at the new `values`.
    /// Returns (largest DOF change, clamped DOF count).
    fn guarded_iteration(
        &mut self,
        skeleton: &Skeleton,
        tasks: &[Task],
        values: &mut [f64],
    ) -> (f64, usize) {
        const MAX_HALVINGS: usize = 3;
        // Cascade: while the first unmet level can still make real progress (its linear model
        // promises at least a tenth of what it asks), the levels below wait; their null-space
        // motion would otherwise keep disturbing it through the non-linearity. A level stuck
        // in a conflict promises little and lets the levels below move. (Its promise does not
        // depend on the levels below: the priority is strict.)
        let all_levels = self.layout.len();
        let first_unmet = self.first_unmet_level().filter(|&k| k + 1 < all_levels);
        let (mut step, mut clamped) =
            self.compute_step(skeleton, values, first_unmet.map_or(all_levels, |k| k + 1));
        if let Some(k) = first_unmet {
            let sys = &self.systems[k];
            let mut rest = sys.dx.clone();
            rest.gemv_tr(-1.0, &sys.jacobian_t, &step, 1.0);
            let asked = sys.dx.norm();
            if asked - rest.norm() <= 0.1 * asked {
                (step, clamped) = self.compute_step(skeleton, values, all_levels);
            }
        }
        let start = values.to_vec();
        let old = self.residual_sq.clone();
        let mut moved: f64;
        // Candidates after the full step: the lowest levels dropped one at a time (their large
        // null-space motions disturb the levels above through the non-linearity), then halvings.
        let mut keep_levels = self.layout.len();
        let mut halvings = 0;
        loop {
            moved = 0.0;
            for i in 0..values.len() {
                values[i] = start[i] + step[i];
                moved = moved.max(step[i].abs());
            }
            self.clamp_free(skeleton, values);
            self.weigh_levels(skeleton, tasks, values, false);
            let Some(worse) = self.rejecting_level(&old) else {
                break;
            };
            if halvings < MAX_HALVINGS {
                // A shorter step: the disturbance of the levels above is second order.
                step *= 0.5;
                halvings += 1;
                continue;
            }
            if keep_levels > worse + 1 {
                // Still worse: drop every level below the one that got worse and retry (the
                // step is recomputed: the joint-limit clamping depends on the levels).
                keep_levels = worse + 1;
                (step, clamped) = self.compute_step(skeleton, &start, keep_levels);
                halvings = 0;
                continue;
            }
            break;
        }
        // The last candidate evaluated is `values`: `self.frames` holds its kinematics.
        self.linearize_at_frames(skeleton, tasks, values);
        (moved, clamped)
    }

    /// The summed cost of the comfort levels (their residuals), 0 without one.
    fn comfort_cost(&self) -> f64 {
        self.layout
            .iter()
            .zip(&self.residual_sq)
            .filter(|(l, _)| l.comfort)
            .map(|(_, r)| r.sqrt())
            .sum()
    }

    /// Whether `a` beats `b` in priority order by a margin worth iterating for.
    fn meaningfully_better(&self, a: &[f64], b: &[f64]) -> bool {
        // Met levels drift a little while the levels below move: up to 10x the tolerance
        // counts as met here.
        let tol = 10.0 * self.settings.tolerance;
        for ((layout, &a), &b) in self.layout.iter().zip(a).zip(b) {
            let (a, b) = (a.sqrt(), b.sqrt());
            // A comfort level that waits keeps the cost it last had: nothing to judge by.
            let kept = layout.comfort && !self.comfort_stepping;
            if (layout.posture_only && !layout.comfort) || kept || (a <= tol && b <= tol) {
                continue;
            }
            let margin = self.settings.stall_improvement.max(STALL_RELATIVE * b);
            if a < b - margin {
                return true;
            }
            if a > b + margin {
                return false;
            }
        }
        false
    }

    /// Whether residuals `a` beat `b` in priority order (levels met in both count as equal).
    fn lexicographically_better(&self, a: &[f64], b: &[f64]) -> bool {
        let tol2 = self.settings.tolerance * self.settings.tolerance;
        for ((layout, &a), &b) in self.layout.iter().zip(a).zip(b) {
            if (layout.posture_only && !layout.comfort) || (a <= tol2 && b <= tol2) {
                continue;
            }
            if a < b {
                return true;
            }
            if a > b {
                return false;
            }
        }
        false
    }

    /// Index of the first level (posture-only levels aside) not within the tolerance.
    fn first_unmet_level(&self) -> Option<usize> {
        let tol2 = self.settings.tolerance * self.settings.tolerance;
        self.layout
            .iter()
            .zip(&self.residual_sq)
            .position(|(l, &r)| !l.posture_only && r > tol2)
    }

    /// The level that rejects the candidate step (priority order, posture-only levels aside):
    /// a met level that drifted (second order, while the levels below moved) by more than a
    /// tenth of the step limits (the next iteration pulls a smaller drift back), or an unmet
    /// level whose residual got clearly worse (by more than `1e-3 * old + 10 * tolerance`)
    /// before any got better.
    fn rejecting_level(&self, old: &[f64]) -> Option<usize> {
        let tol = self.settings.tolerance;
        let drift = 0.1
            * self
                .settings
                .max_linear_step
                .min(self.settings.max_angular_step);
        for (k, layout) in self.layout.iter().enumerate() {
            if layout.posture_only {
                continue;
            }
            let (new, old) = (self.residual_sq[k].sqrt(), old[k].sqrt());
            let slack = if old <= tol {
                drift
            } else {
                1e-3 * old + 10.0 * tol
            };
            if new < old - slack {
                return None;
            }
            if new > old + slack {
                return Some(k);
            }
        }
        None
    }

    /// Prioritized step with the joint-limit clamping loop. Returns (step, clamped DOF count);
    /// `values + step` is inside the limits.
    fn step_within_limits(
        &mut self,
        skeleton: &Skeleton,
        values: &[f64],
        levels: usize,
    ) -> (DVector<f64>, usize) {
        let n = skeleton.dof_count();
        let params = self.settings.step_params();
        let (lo, hi) = (skeleton.lower_limits(), skeleton.upper_limits());
        let has_limits = self.settings.enforce_limits
            && lo
                .iter()
                .zip(hi)
                .any(|(l, h)| l.is_finite() || h.is_finite());
        let mut clamped: Vec<bool> = (0..n).map(|d| self.is_locked(d)).collect();
        let mut fixed = std::mem::take(&mut self.fixed);
        fixed.resize_vertically_mut(n, 0.0);
        fixed.fill(0.0);
        let mut any_clamped = clamped.iter().any(|&c| c);
        // Stiffness: the weighted pseudo-inverse `W^-1 J^T (J W^-1 J^T)^-1` (and its
        // projector) is the plain one in the coordinates `theta' = W^(1/2) theta`: the
        // Jacobian's DOF rows scaled by `sqrt(1 - stiffness)`, the step scaled back.
        let scale: Option<Vec<f64>> = skeleton.stiffness().iter().any(|&s| s > 0.0).then(|| {
            skeleton
                .stiffness()
                .iter()
                .map(|s| (1.0 - s).sqrt())
                .collect()
        });
        let used = levels.min(self.systems.len());
        if let Some(scale) = &scale {
            self.weighted.clone_from(&self.systems);
            for sys in &mut self.weighted[..used] {
                for mut column in sys.jacobian_t.column_iter_mut() {
                    column.component_mul_assign(&DVector::from_column_slice(scale));
                }
            }
        }
        let mut total;
        let mut passes = 0;
        loop {
            let step_fn = match self.settings.backend {
                Backend::Kernel => prioritized_step,
                Backend::Nalgebra => prioritized_step_nalgebra,
            };
            let systems = if scale.is_some() {
                &self.weighted[..used]
            } else {
                &self.systems[..used]
            };
            // The moves already fixed, in the weighted coordinates.
            let fixed_weighted = scale
                .as_ref()
                .map(|scale| DVector::from_fn(n, |i, _| fixed[i] / scale[i]));
            let mut step = step_fn(
                systems,
                n,
                &params,
                any_clamped.then_some(clamped.as_slice()),
                any_clamped.then_some(fixed_weighted.as_ref().unwrap_or(&fixed)),
                &mut self.workspace,
                None,
            );
            if let Some(scale) = &scale {
                step.component_mul_assign(&DVector::from_column_slice(scale));
            }
            total = step + &fixed;
            if !has_limits {
                break;
            }
            let limits = StepLimitsAt {
                values,
                lo,
                hi,
                scale: scale.as_deref(),
                fixed: &fixed,
                clamped: &clamped,
            };
            if self.comfort_within_limits(&limits, used, &params, &mut total) {
                break;
            }
            let mut new_clamp = false;
            for i in 0..n {
                if clamped[i] {
                    continue;
                }
                let next = values[i] + total[i];
                let bound = if next > hi[i] {
                    hi[i]
                } else if next < lo[i] {
                    lo[i]
                } else {
                    continue;
                };
                clamped[i] = true;
                fixed[i] = bound - values[i];
                new_clamp = true;
            }
            passes += 1;
            if !new_clamp || passes > n {
                break;
            }
            any_clamped = true;
        }
        for v in total.iter_mut() {
            if !v.is_finite() {
                *v = 0.0;
            }
        }
        self.fixed = fixed;
        let clamped_by_limits = clamped
            .iter()
            .enumerate()
            .filter(|&(d, &c)| c && !self.is_locked(d))
            .count();
        (total, clamped_by_limits)
    }
}
