//! The multi-start's later runs of a stalled solve, and the hybrid's closed-form restart of a
//! limb (the paper's conclusion).

use super::settings::{TEXTBOOK_DAMPING, TEXTBOOK_TRUST_REGION};
use super::{AnalyticRestart, Iteration, Solver, TEXTBOOK_ANGULAR_STEP, TEXTBOOK_LINEAR_STEP};
use crate::limb::LimbGoal;
use crate::priority::Damping;
use crate::{Posture, Skeleton, Task, TaskKind};

/// The stall window of the multi-start's runs from the start posture.
const RESTART_STALL_WINDOW: usize = 20;
/// The stall window of the multi-start's guarded run.
const GUARDED_STALL_WINDOW: usize = 5;
/// Below this error (m or rad) the damping of the restart with the textbook's recipe falls in
/// proportion (Levenberg-Marquardt style): its last iterations are undamped Newton steps
/// instead of a crawl near a singular level (the textbook's constant 0.01 shortens each by a
/// constant ratio there).
const RESTART_ERROR_SCALE: f64 = 0.01;

/// One run of a multi-start after the first.
#[derive(Debug, Clone, Copy)]
pub(super) struct RestartStage {
    pub(super) iteration: Iteration,
    pub(super) trust_region: f64,
    pub(super) stall_window: usize,
    /// The task clamps of the run (`max_linear_step`, `max_angular_step`).
    pub(super) max_linear_step: f64,
    pub(super) max_angular_step: f64,
    /// From the start posture (else from the best posture so far).
    pub(super) from_start: bool,
    /// The damping of the levels without their own.
    pub(super) damping: Damping,
    /// The levels' shared budget of a textbook iteration (`priority_budget`).
    pub(super) priority_budget: f64,
}

impl Solver {
    /// The runs a stalled solve goes on with, in order (none without `settings.restarts`),
    /// each within what the runs before left of the iteration budget and kept only if better
    /// in priority order. After textbook iterations (with a trust region), from the start
    /// posture:
    /// 1. the textbook's recipe (trust region pi/4, task clamps 0.1 m / 0.3 rad where the
    ///    settings' are longer, damping 0.01 falling with the error below 1 cm / 0.01 rad),
    ///    the priority budget kept;
    /// 2. the settings' own iteration without the priority budget (the plain recursion's
    ///    whole steps: another path, into another basin);
    /// 3. the textbook's recipe as the textbook has it: constant damping, no priority budget
    ///    (the path of the plain recursion, which some problems need whole: `com-0031`, where
    ///    both runs before stall with level 2 at 0.04-1.4 and this one converges in 30
    ///    iterations);
    ///
    /// then 4. guarded iterations from the best posture so far (their line search settles what
    /// whole steps leave oscillating). After guarded iterations: the textbook's recipe with its
    /// constant damping; after the plain recursion without a trust region: guarded iterations.
    ///
    /// Each stalled run has met a local minimum (a zero step on joint limits) or a crawl, and
    /// the runs from the start posture take other paths there: the first run and a restart
    /// alike may settle in a minimum one of the others avoids (docs/solver-families.md).
    pub(super) fn restart_stages(&self) -> Vec<RestartStage> {
        if !self.settings.restarts {
            return Vec::new();
        }
        let max_linear_step = self.settings.max_linear_step.min(TEXTBOOK_LINEAR_STEP);
        let max_angular_step = self.settings.max_angular_step.min(TEXTBOOK_ANGULAR_STEP);
        let guarded = RestartStage {
            iteration: Iteration::Guarded,
            trust_region: self.settings.trust_region,
            stall_window: GUARDED_STALL_WINDOW,
            max_linear_step,
            max_angular_step,
            from_start: false,
            damping: self.settings.damping,
            priority_budget: self.settings.priority_budget,
        };
        let textbook = RestartStage {
            iteration: Iteration::Textbook,
            trust_region: TEXTBOOK_TRUST_REGION,
            stall_window: RESTART_STALL_WINDOW,
            max_linear_step,
            max_angular_step,
            from_start: true,
            damping: Damping::Constant {
                lambda: TEXTBOOK_DAMPING,
            },
            priority_budget: self.settings.priority_budget,
        };
        match self.settings.iteration {
            Iteration::Guarded => vec![textbook],
            Iteration::Textbook if self.settings.trust_region == f64::INFINITY => vec![guarded],
            Iteration::Textbook => {
                let falling = RestartStage {
                    damping: Damping::Levenberg {
                        lambda: TEXTBOOK_DAMPING,
                        error_scale: RESTART_ERROR_SCALE,
                    },
                    ..textbook
                };
                let unbudgeted = RestartStage {
                    iteration: Iteration::Textbook,
                    trust_region: self.settings.trust_region,
                    stall_window: RESTART_STALL_WINDOW,
                    max_linear_step: self.settings.max_linear_step,
                    max_angular_step: self.settings.max_angular_step,
                    from_start: true,
                    damping: self.settings.damping,
                    priority_budget: f64::INFINITY,
                };
                let plain = RestartStage {
                    priority_budget: f64::INFINITY,
                    ..textbook
                };
                vec![falling, unbudgeted, plain, guarded]
            }
        }
    }

    /// The hybrid: for the first unmet level, a limb (not yet restarted in this solve) whose end
    /// joint carries one of its position tasks is put in its closed-form posture for the goal
    /// that task implies (the end joint moved by the task's error on its axes; an orientation
    /// task on the end joint at that level or above sets the end rotation). Relinearises.
    pub(super) fn analytic_restart(
        &mut self,
        skeleton: &Skeleton,
        tasks: &[Task],
        values: &mut [f64],
        iteration: usize,
        done: &[AnalyticRestart],
    ) -> Option<AnalyticRestart> {
        if self.limbs.is_empty() {
            return None;
        }
        let k = self.first_unmet_level()?;
        let level = self.layout[k].level;
        let name = |j: usize| skeleton.joints()[j].name.clone();
        for limb in &self.limbs {
            let [upper, middle, end] = limb.joints();
            let joints = [name(upper), name(middle), name(end)];
            if done.iter().any(|r| r.joints == joints) {
                continue;
            }
            let held = [upper, middle, end]
                .iter()
                .any(|&j| skeleton.joints()[j].dof_range().any(|d| self.is_locked(d)));
            if held {
                continue;
            }
            let goal = self.layout[k]
                .tasks
                .iter()
                .find_map(|&ti| match &tasks[ti].kind {
                    TaskKind::Position {
                        effector,
                        axes,
                        target,
                    } if effector.joint == end => {
                        let now = self.frames.point(end, effector.point);
                        let mut position = self.frames.joint_position[end];
                        for axis in 0..3 {
                            if axes.has(axis) {
                                position[axis] += target[axis] - now[axis];
                            }
                        }
                        Some(position)
                    }
                    _ => None,
                });
            let Some(position) = goal else {
                continue;
            };
            let orientation = tasks.iter().find_map(|t| match &t.kind {
                TaskKind::Orientation { joint, target }
                    if t.active && t.level <= level && *joint == end =>
                {
                    Some(*target)
                }
                _ => None,
            });
            let base = limb.base(skeleton, &self.frames);
            let current = Posture::from_values(skeleton, values.to_vec()).ok()?;
            let preferred = limb.swivel_angle(skeleton, &current);
            let goal = LimbGoal {
                position,
                orientation,
            };
            let solution = limb.solve_within_limits(base, &goal, preferred);
            limb.apply_values(&solution, values);
            self.clamp_free(skeleton, values);
            self.comfort_known = false;
            self.linearize(skeleton, tasks, values);
            return Some(AnalyticRestart {
                joints,
                iteration,
                level,
                swivel_angle: solution.swivel_angle,
            });
        }
        None
    }
}
