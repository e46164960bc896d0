//! What a solve reports: why it stopped, the residuals of every level before and after,
//! and the hybrid restarts it made.

use serde::Serialize;

/// Why the solver stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SolveStatus {
    /// Every level (posture attraction aside) is within the tolerance.
    Converged,
    /// The step became negligible before every level was met (conflict or unreachable goal).
    Stalled,
    /// `max_iterations` spent.
    IterationBudget,
    /// `time_budget_secs` spent.
    TimeBudget,
}

/// Residuals of one priority level.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LevelReport {
    /// The level number.
    pub level: u32,
    /// Active tasks in the level.
    pub tasks: usize,
    /// Rows of the level's Jacobian (a level whose rows vary, a collision task's: the rows
    /// of the constraints found when it was last linearised, none while the body is clear).
    pub rows: usize,
    /// Norm of the residuals at the start (m / rad).
    pub residual_before: f64,
    /// Norm of the residuals at the end.
    pub residual_after: f64,
    /// `residual_after <= tolerance`.
    pub met: bool,
    /// Whether the level holds only posture attraction (never required to be met).
    pub posture_only: bool,
}

/// The outcome of a solve. Not converging is a normal outcome, reported here.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SolveReport {
    /// Why it stopped.
    pub status: SolveStatus,
    /// Steps taken.
    pub iterations: usize,
    /// One entry per level, highest priority first.
    pub levels: Vec<LevelReport>,
    /// The highest-priority level (posture-only levels aside) left unmet: the level that gave
    /// way to the ones above it (or to an unreachable goal).
    pub gave_way: Option<u32>,
    /// DOF that sat on a joint limit in the last step.
    pub clamped_dofs: usize,
    /// Seconds spent, when a clock was available.
    pub elapsed_secs: Option<f64>,
    /// Hybrid restarts: where the solver stalled and restarted a limb from its closed-form
    /// solution (see `Solver::limbs`); empty when it never did.
    pub analytic_restarts: Vec<AnalyticRestart>,
}

/// One hybrid restart: a stalled solve put a limb in its closed-form posture and went on.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AnalyticRestart {
    /// The limb's joints (upper, middle, end).
    pub joints: [String; 3],
    /// Iterations taken before the restart.
    pub iteration: usize,
    /// The level whose unmet task on the limb's end joint set the goal.
    pub level: u32,
    /// Swivel angle of the restart posture (radians): the feasible one nearest to the stalled
    /// posture's swivel.
    pub swivel_angle: f64,
}
