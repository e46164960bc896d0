//! Kinematics and the prioritized damped least-squares IK solver of Stance.
//!
//! Pure `f64` math, no I/O; builds for `wasm32`. The method: variational IK with strict
//! priorities [SIC 91] in the recursive form of [BAE 98] (Boulic & Baerlocher), damped least
//! squares per level [MAC 90] (references in the repository's README).
//!
//! - [`Skeleton`]: joints with 0-3 rotational DOF (the root 6), limits, masses.
//! - [`Posture`] / [`Frames`]: DOF values (rotation vectors, no Euler singularity) and
//!   forward kinematics.
//! - [`Task`]: position, orientation, direction (partial orientation), gaze, centre of mass,
//!   a point on a line or on a plane (or above it),
//!   balance (the centre of mass inside the support polygon, an inequality), posture
//!   attraction; each with a level, a weight and an active flag.
//! - [`Solver`]: iterates prioritized steps with joint-limit clamping and per-level damping:
//!   textbook iterations in a trust region for a whole solve, or guarded ones (shared step
//!   budget, line search, cascade) for an editor that shows every iteration ([`Iteration`]);
//!   a stalled solve runs once more as the plain recursion, keeping the better result in
//!   priority order; returns a [`SolveReport`]; time budget through an injectable [`Clock`].
//! - [`prioritized_step`]: one step of [BAE 98] on contiguous slices (the default);
//!   [`prioritized_step_nalgebra`]: the same on nalgebra matrices (kept for the comparison).
//! - [`Limb`]: closed-form IK of a shoulder-elbow-wrist / hip-knee-ankle limb with the swivel
//!   angle [TOL 96], its feasible swivel intervals under joint limits, and the hybrid restart
//!   of a stalled [`Solver`] from the analytic solution (`Solver::limbs`);
//!   [`nearest_rotation_vector`]: the rotation of a joint's DOF (within its limits) nearest
//!   to a wanted rotation.
//! - [`conflict`]: why an unmet task is not met (which higher tasks stand in its way, the
//!   joint limits, or a goal out of reach), from the linearised tasks.

#![warn(missing_docs)]

mod bodies;
pub mod comfort;
pub mod conflict;
mod error;
mod joint_rotation;
mod kernel;
mod limb;
mod posture;
mod priority;
mod skeleton;
mod solver;
mod task;

pub use bodies::{Bodies, BodyPlacement, SCENE_ROOT};
pub use error::IkError;
pub use joint_rotation::{UNLIMITED_RANGE, nearest_rotation_vector, rotation_angle};
pub use kernel::prioritized_step;
pub use limb::{Limb, LimbBase, LimbGoal, LimbSolution, SwivelInterval, nearest_swivel};
pub use posture::{Frames, Posture};
pub use priority::{Damping, LevelSystem, StepParams, StepWorkspace, prioritized_step_nalgebra};
pub use skeleton::{Dof, Joint, JointDef, Skeleton};
#[cfg(not(all(target_arch = "wasm32", target_os = "unknown")))]
pub use solver::SystemClock;
pub use solver::{
    AnalyticRestart, Backend, CONSTANT_DAMPING, Clock, Iteration, LevelReport, SolveReport,
    SolveStatus, Solver, SolverSettings, TEXTBOOK_ANGULAR_STEP, TEXTBOOK_LINEAR_STEP,
    WHOLE_SOLVE_DAMPING,
};
pub use task::{
    Axes, BALANCE_BAND, COLLISION_AIM, COLLISION_BAND, COLLISION_LOOKAHEAD, CONTACT_REACH, Capsule,
    Collision, Contact, Effector, Obstacle, ObstacleShape, PLANE_BAND, Task, TaskFeature, TaskKind,
    closest_points, collision_pairs, floor_capsules, with_placed_parts,
};
