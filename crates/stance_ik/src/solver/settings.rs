//! The solver's settings (iteration kind, step limits, damping, stall criteria, budgets)
//! with their defaults and checks, the linear-algebra backend choice, and the [`Clock`]
//! behind the time budget.

use crate::IkError;
use crate::priority::{Damping, StepParams};

/// A source of time in seconds, for the wall-clock budget. The solver never reads a clock by
/// itself on `wasm32-unknown-unknown` (where `std::time::Instant` panics): pass one built on
/// `performance.now()` there.
pub trait Clock {
    /// Monotonic time in seconds (any origin).
    fn now_secs(&self) -> f64;
}

impl<F: Fn() -> f64> Clock for F {
    fn now_secs(&self) -> f64 {
        self()
    }
}

/// `std::time::Instant`, on targets where it works.
#[cfg(not(all(target_arch = "wasm32", target_os = "unknown")))]
#[derive(Debug, Clone, Copy)]
pub struct SystemClock {
    origin: std::time::Instant,
}

#[cfg(not(all(target_arch = "wasm32", target_os = "unknown")))]
impl Default for SystemClock {
    fn default() -> Self {
        Self {
            origin: std::time::Instant::now(),
        }
    }
}

#[cfg(not(all(target_arch = "wasm32", target_os = "unknown")))]
impl Clock for SystemClock {
    fn now_secs(&self) -> f64 {
        self.origin.elapsed().as_secs_f64()
    }
}

/// Plain, documented solver settings with defaults.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverSettings {
    /// Iteration budget, shared by the multi-start's runs (default 300).
    pub max_iterations: usize,
    /// A level is met when the norm of its residuals is at most this (m / rad; default 1e-6).
    pub tolerance: f64,
    /// Stalled when no DOF moves more than this in an iteration (default 1e-10).
    pub stall_step: f64,
    /// Stalled when for `stall_window` iterations in a row the residuals (in priority order,
    /// met levels aside) beat the best so far by no more than this (m / rad, default 1e-10) or
    /// 1e-4 of themselves.
    pub stall_improvement: f64,
    /// How each iteration is taken (default [`Iteration::Textbook`]; an interactive editor
    /// that shows every iteration takes [`Iteration::Guarded`]).
    pub iteration: Iteration,
    /// Stalled when this many iterations in a row bring no meaningful improvement in priority
    /// order (default 40: the textbook recursion wanders for a while before it settles; 5
    /// suits guarded iterations; the multi-start's run from the start posture takes 20).
    pub stall_window: usize,
    /// Largest DOF change of a textbook iteration (rad or m, default 0.5): a longer step is
    /// scaled down as a whole, its direction kept. A trust region: the plain recursion's first
    /// steps near a singularity swing DOF by several radians onto their limits and throw the
    /// problem into another basin. Infinity gives the plain recursion. Guarded iterations use
    /// `max_dof_step` instead.
    pub trust_region: f64,
    /// Largest DOF change the levels of a textbook iteration take together, spent in priority
    /// order (rad or m, default 1.0): a level's step longer than what the levels above it left
    /// is scaled down alone, so that a lower level's long step near its algorithmic singularity
    /// no longer shortens the whole step (and the higher levels' progress) through the trust
    /// region. Infinity gives the plain recursion. Guarded iterations share `max_dof_step`
    /// instead.
    pub priority_budget: f64,
    /// Wall-clock budget in seconds (needs a [`Clock`]; default none).
    pub time_budget_secs: Option<f64>,
    /// Damping of every level without its own (default [`WHOLE_SOLVE_DAMPING`]: 0.002 falling
    /// with the error below 0.01; frame-by-frame solves and fits take [`CONSTANT_DAMPING`]; see
    /// [`Solver::level_damping`](crate::Solver::level_damping)).
    pub damping: Damping,
    /// Relative rank threshold of the projector (default 1e-9).
    pub rank_tolerance: f64,
    /// Largest position / centre-of-mass change asked of a task per iteration (m, default 0.3).
    pub max_linear_step: f64,
    /// Largest orientation / gaze / posture change asked per iteration (rad, default 0.5).
    pub max_angular_step: f64,
    /// Largest DOF change per guarded iteration, shared by the levels in priority order
    /// (default 0.2; the textbook iteration has none).
    pub max_dof_step: f64,
    /// Enforce the joint limits by clamping (default true).
    pub enforce_limits: bool,
    /// Linear-algebra implementation of the step (default: the slice kernel).
    pub backend: Backend,
    /// When a solve stalls with a level unmet (and at least half the time budget is left), go
    /// on with other runs within what is left of the iteration budget, each kept only if
    /// better in priority order (default true): after textbook iterations, from the start
    /// posture the textbook's recipe (damping 0.01 falling with the error below 0.01, trust
    /// region pi/4, task clamps 0.1 m / 0.3 rad), then these settings without the priority
    /// budget, then guarded iterations from the best posture so far; after guarded
    /// iterations, the textbook's recipe (constant damping) from the start posture.
    pub restarts: bool,
}

/// How the solver takes an iteration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Iteration {
    /// The prioritized step with safeguards for strict priority through the non-linearity:
    /// the levels share `max_dof_step` in priority order, the levels below the first unmet
    /// level wait while it still makes real progress (the cascade), and a step that leaves a
    /// level clearly worse is halved, then loses its lowest levels (see
    /// `Solver::guarded_iteration`). Every iteration's posture keeps the higher levels: what
    /// an interactive editor shows frame by frame.
    Guarded,
    /// The textbook recursion: every level's step at once, joint-limit clamping, the whole
    /// step scaled into [`SolverSettings::trust_region`], nothing else. Converges on
    /// multi-level problems where the guarded safeguards stop lower levels short (5 to 8
    /// iterations median on the tuned problem families of docs/solver-families.md), but an
    /// iteration may leave a
    /// higher level worse on the way: a solve returns the best posture met in priority order.
    #[default]
    Textbook,
}

/// Which implementation computes the prioritized step (same mathematics; kept selectable for
/// the benchmark comparison).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Backend {
    /// [`crate::prioritized_step`]: contiguous slices, no allocation per call.
    #[default]
    Kernel,
    /// [`crate::prioritized_step_nalgebra`]: nalgebra dynamic matrices.
    Nalgebra,
}

impl Default for SolverSettings {
    fn default() -> Self {
        Self {
            max_iterations: 300,
            tolerance: 1e-6,
            stall_step: 1e-10,
            stall_improvement: 1e-10,
            iteration: Iteration::Textbook,
            stall_window: STALL_WINDOW,
            trust_region: 0.5,
            priority_budget: 1.0,
            time_budget_secs: None,
            damping: WHOLE_SOLVE_DAMPING,
            rank_tolerance: 1e-9,
            max_linear_step: 0.3,
            max_angular_step: 0.5,
            max_dof_step: 0.2,
            enforce_limits: true,
            backend: Backend::Kernel,
            restarts: true,
        }
    }
}

impl SolverSettings {
    /// Checks every field.
    pub fn validate(&self) -> Result<(), IkError> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        if !(self.tolerance.is_finite() && self.tolerance >= 0.0) {
            return Err(IkError::BadSetting("tolerance"));
        }
        if !(self.stall_step.is_finite() && self.stall_step >= 0.0) {
            return Err(IkError::BadSetting("stall_step"));
        }
        if !(self.stall_improvement.is_finite() && self.stall_improvement >= 0.0) {
            return Err(IkError::BadSetting("stall_improvement"));
        }
        if let Some(t) = self.time_budget_secs
            && !(t.is_finite() && t >= 0.0)
        {
            return Err(IkError::BadSetting("time_budget_secs"));
        }
        validate_damping(self.damping)?;
        if !(self.rank_tolerance.is_finite() && self.rank_tolerance > 0.0) {
            return Err(IkError::BadSetting("rank_tolerance"));
        }
        if !pos(self.max_linear_step) {
            return Err(IkError::BadSetting("max_linear_step"));
        }
        if !pos(self.max_angular_step) {
            return Err(IkError::BadSetting("max_angular_step"));
        }
        if !pos(self.max_dof_step) {
            return Err(IkError::BadSetting("max_dof_step"));
        }
        if self.trust_region.is_nan() || self.trust_region <= 0.0 {
            return Err(IkError::BadSetting("trust_region"));
        }
        if self.priority_budget.is_nan() || self.priority_budget <= 0.0 {
            return Err(IkError::BadSetting("priority_budget"));
        }
        Ok(())
    }

    pub(super) fn step_params(&self) -> StepParams {
        StepParams {
            damping: self.damping,
            rank_tolerance: self.rank_tolerance,
            max_dof_step: match self.iteration {
                Iteration::Guarded => self.max_dof_step,
                Iteration::Textbook => self.priority_budget,
            },
        }
    }
}

/// Checks a damping's parameters.
pub(super) fn validate_damping(damping: Damping) -> Result<(), IkError> {
    match damping {
        Damping::Constant { lambda } if !(lambda.is_finite() && lambda >= 0.0) => {
            Err(IkError::BadSetting("damping.lambda"))
        }
        Damping::Levenberg {
            lambda,
            error_scale,
        } if !(lambda.is_finite()
            && lambda >= 0.0
            && error_scale.is_finite()
            && error_scale > 0.0) =>
        {
            Err(IkError::BadSetting("damping"))
        }
        Damping::Adaptive {
            lambda_max,
            epsilon,
        } if !(epsilon.is_finite()
            && epsilon > 0.0
            && lambda_max.is_finite()
            && lambda_max >= 0.0) =>
        {
            Err(IkError::BadSetting("damping"))
        }
        _ => Ok(()),
    }
}

/// The textbook's per-iteration task clamp of positions and centres of mass (m; Buss & Kim's
/// 0.1 m): shorter than the default [`SolverSettings::max_linear_step`], so more iterations,
/// but whole steps fall into the basin of the posture nearest the start more often. The
/// restarts of a stalled solve use it, and so do frame-by-frame guarded solves (a line search
/// halves a long ask before it takes it).
pub const TEXTBOOK_LINEAR_STEP: f64 = 0.1;
/// The textbook's per-iteration task clamp of orientations, gazes and postures (rad).
pub const TEXTBOOK_ANGULAR_STEP: f64 = 0.3;

/// The textbook's trust region (rad): Buss & Kim's whole step scaled so that no DOF moves more
/// than a quarter turn's half. The plain recursion's restart of a stalled solve uses it.
pub const TEXTBOOK_TRUST_REGION: f64 = std::f64::consts::FRAC_PI_4;
/// The textbook's damping of every level's pseudo-inverse ([MAC 90]'s order of magnitude): more
/// than the default 0.002, so steps near a singularity are shorter and fall into the basin
/// nearest the start more often. The plain recursion's restart of a stalled solve uses it.
pub const TEXTBOOK_DAMPING: f64 = 0.01;

/// The damping of a whole solve (the default): Levenberg-Marquardt style, 0.002 while a level's
/// error is 1 cm / 0.01 rad or more and falling in proportion below, so that the last iterations
/// are undamped Newton steps that converge quadratically instead of a crawl near a singular level
/// (issue 29: on the problem families it met every problem the constant damping met and more,
/// at fewer iterations; docs/solver-families.md).
pub const WHOLE_SOLVE_DAMPING: Damping = Damping::Levenberg {
    lambda: 0.002,
    error_scale: 0.01,
};

/// The damping of frame-by-frame solves (the editor's frames, retargeting, a timeline's
/// frames) and of fits that leave levels unmet (the keypoints' lift): constant 0.002. A frame
/// starts where the last one ended, near its goal, and an undamped last step near a straight
/// knee throws the next frame off (retargeting a CMU walk with contacts drifted by 29 mm with
/// the falling damping, 0.01 mm with this one); the lift's round trip left keypoints 2.4 px
/// off and a foot 2 cm low with the falling damping.
pub const CONSTANT_DAMPING: Damping = Damping::Constant { lambda: 0.002 };

/// Iterations without a meaningful new best (in priority order) before "stalled".
const STALL_WINDOW: usize = 40;
