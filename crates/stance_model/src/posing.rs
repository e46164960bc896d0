//! The posing session: the humanoid's skeleton and posture, the user's tasks with their
//! priorities, the temporary grab-and-pull task, and the solver that runs a few iterations
//! every frame within a time budget. No egui here: everything is tested natively.

use glam::{DQuat, DVec3};
mod stiffness;
mod timed;

use stance_document::{
    CameraSpec, Document, FrameProblem, LimbName, MotionSection, PostureValues, StiffnessValues,
    TaskKindSpec, TaskSpec,
};
use stance_hanim::hands::{HandError, HandRig};
use stance_hanim::{
    HumanoidSkeleton, LevelOfArticulation, Side, SkeletonOptions, default_skeleton, mirror_name,
};
use stance_ik::{
    CONSTANT_DAMPING, Clock, Collision, Contact, Frames, Iteration, Limb, LimbGoal, Obstacle,
    Posture, Skeleton, SolveReport, SolveStatus, Solver, SolverSettings, SwivelInterval,
    TEXTBOOK_ANGULAR_STEP, TEXTBOOK_LINEAR_STEP, Task, TaskKind,
};

pub use self::timed::{TimedFrame, blended, timed_tasks, timed_tasks_at};

pub use stance_document::{Grab, MET_TOLERANCE, TaskStatus};

/// Iterations per frame and the time they may take: the page stays interactive. The time
/// bounds a frame; the count is enough for the Table 1 example to converge in one frame
/// (33 iterations, about 1.7 ms natively) and a pull converges in 2 or 3 a frame.
const ITERATIONS_PER_FRAME: usize = 40;
/// Guarded iterations without a meaningful gain before a frame's solve stalls.
const GUARDED_STALL_WINDOW: usize = 5;
const FRAME_BUDGET_SECS: f64 = 0.008;

/// A humanoid being posed.
pub struct PosingSession {
    humanoid: HumanoidSkeleton,
    posture: Posture,
    tasks: Vec<TaskSpec>,
    grab: Option<Grab>,
    /// A joint held where it is (level 1) while the swivel handle turns its limb.
    held: Option<(usize, DVec3)>,
    solver: Solver,
    report: Option<SolveReport>,
    frames: Frames,
    statuses: Vec<TaskStatus>,
    settled: bool,
    /// Whether the comfort levels may move the posture in the next solves: after a change of
    /// tasks or a released pull, not after a direct edit of the posture (see [`Wake`]).
    comfort_armed: bool,
    revision: u64,
    /// The document's timeline and keys.
    motion: Option<MotionSection>,
    /// Changes whenever `motion` is replaced.
    motion_revision: u64,
    /// The camera saved with the document.
    camera: Option<CameraSpec>,
    /// The timeline frame shown, if any: the tasks act with their interval weights.
    timed: Option<TimedFrame>,
    /// The body's stiffness as built (the anatomical defaults), per DOF.
    anatomical_stiffness: Vec<f64>,
    /// The document's stiffness overrides, applied to `humanoid.skeleton`.
    stiffness: StiffnessValues,
    /// The left and right hands' finger joints (or why they cannot be posed).
    hands: [Result<HandRig, HandError>; 2],
    /// The body's collision tasks as the solver takes them (with `obstacles`), by their spec
    /// (built once: building one searches every pair of capsules at rest).
    collisions: Vec<(TaskKindSpec, Collision)>,
    /// The contacts the collision tasks hold in the current posture.
    contacts: Vec<Contact>,
    /// Fixed solids the collision tasks hold the body off (the scene's props, in the body's
    /// frame).
    obstacles: Vec<Obstacle>,
}

impl std::fmt::Debug for PosingSession {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PosingSession")
            .field("joints", &self.skeleton().joint_count())
            .field("tasks", &self.tasks.len())
            .field("grab", &self.grab)
            .field("settled", &self.settled)
            .finish()
    }
}

/// What woke the solver. A comfort level never says "met": it moves the posture while its
/// cost falls. It does so after a change of what the body must do (a task added, edited or
/// removed, a pin, a document loaded, a stiffness); a posture edited directly (a pull, a DOF
/// typed in, a hand preset, a swivel, undo, sensors, a timeline frame) stays as the user left
/// it, the other tasks still holding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Wake {
    /// The tasks changed: every level, comfort included, acts.
    Tasks,
    /// The posture was edited directly: comfort waits for the next change of tasks.
    Posture,
}

/// Why a session could not be made.
#[derive(Debug, thiserror::Error)]
pub enum PosingError {
    /// The H-Anim skeleton could not be built.
    #[error("the humanoid could not be built: {0}")]
    Build(#[from] stance_hanim::BuildError),
    /// The solver refused its settings.
    #[error("the solver settings were rejected: {0}")]
    Solver(#[from] stance_ik::IkError),
    /// The document does not fit this body (unknown joints, wrong number of values...).
    #[error("{0}")]
    Document(#[from] stance_document::DocumentError),
}

impl PosingSession {
    /// The solver's settings for one frame of posing (a session's own solve, and a solve of
    /// characters joined by tasks between them).
    pub fn frame_settings() -> SolverSettings {
        SolverSettings {
            max_iterations: ITERATIONS_PER_FRAME,
            time_budget_secs: Some(FRAME_BUDGET_SECS),
            // Every frame is shown and starts where the last one ended: the guarded
            // iteration only (each iteration keeps the higher levels), no restart from the
            // frame's start posture.
            iteration: Iteration::Guarded,
            stall_window: GUARDED_STALL_WINDOW,
            restarts: false,
            // A pull asks the textbook's short steps of its guarded iterations: a longer ask
            // is halved by their line search before it is taken.
            max_linear_step: TEXTBOOK_LINEAR_STEP,
            max_angular_step: TEXTBOOK_ANGULAR_STEP,
            damping: CONSTANT_DAMPING,
            ..SolverSettings::default()
        }
    }

    /// The H-Anim default body at `loa`, standing in its rest posture, with the default tasks:
    /// both feet pinned (level 1), balance over the feet (level 2), a light pull toward the
    /// rest posture (level 10).
    pub fn new(loa: LevelOfArticulation) -> Result<Self, PosingError> {
        let humanoid = default_skeleton(&SkeletonOptions {
            loa,
            ..SkeletonOptions::default()
        })?;
        Self::with_humanoid(humanoid)
    }

    /// A session on any humanoid skeleton (an avatar's), standing in its rest posture with
    /// the default tasks.
    pub fn with_humanoid(humanoid: HumanoidSkeleton) -> Result<Self, PosingError> {
        let settings = Self::frame_settings();
        let posture = Posture::rest(&humanoid.skeleton);
        let frames = Frames::new(&humanoid.skeleton, &posture);
        // The hybrid of the paper's conclusion: a pull stuck in a local minimum restarts the
        // limb from its closed-form solution.
        let limbs = LimbName::all_on(&humanoid.skeleton);
        let anatomical_stiffness = humanoid.skeleton.stiffness().to_vec();
        let hands = [Side::Left, Side::Right].map(|side| HandRig::new(&humanoid.skeleton, side));
        let mut session = Self {
            hands,
            humanoid,
            posture,
            tasks: Vec::new(),
            grab: None,
            held: None,
            solver: Solver::new(settings)?.with_limbs(limbs),
            report: None,
            frames,
            statuses: Vec::new(),
            settled: false,
            // A new body stands at rest as built until the user gives it something to do.
            comfort_armed: false,
            revision: 0,
            motion: None,
            motion_revision: 0,
            camera: None,
            timed: None,
            anatomical_stiffness,
            stiffness: StiffnessValues::default(),
            collisions: Vec::new(),
            contacts: Vec::new(),
            obstacles: Vec::new(),
        };
        session.tasks = session.default_tasks();
        session.refresh();
        Ok(session)
    }

    /// Feet on the floor before balance, balance before comfort ([`TaskSpec::defaults`]).
    pub fn default_tasks(&self) -> Vec<TaskSpec> {
        TaskSpec::defaults(self.skeleton(), &self.frames)
    }

    /// The kinematic skeleton the solver works on: joints, DOFs and their limits.
    pub fn skeleton(&self) -> &Skeleton {
        &self.humanoid.skeleton
    }

    /// The H-Anim body: the skeleton, how each joint was built, the level of articulation.
    pub fn humanoid(&self) -> &HumanoidSkeleton {
        &self.humanoid
    }

    /// The body's H-Anim level of articulation.
    pub fn level_of_articulation(&self) -> LevelOfArticulation {
        self.humanoid.loa
    }

    /// The `side` hand's finger joints, ready for presets and curl; why not, when the body
    /// has no fingers there.
    pub fn hand(&self, side: Side) -> Result<&HandRig, &HandError> {
        match side {
            Side::Left => self.hands[0].as_ref(),
            Side::Right => self.hands[1].as_ref(),
            Side::Centre => Err(&HandError::NotASide),
        }
    }

    /// The current posture: every DOF's value (rad; m for the root's translation).
    pub fn posture(&self) -> &Posture {
        &self.posture
    }

    /// Forward kinematics of the current posture: each joint's world position (m) and
    /// rotation, and each DOF's world axis.
    pub fn frames(&self) -> &Frames {
        &self.frames
    }

    /// The user's tasks, in the document's order.
    pub fn tasks(&self) -> &[TaskSpec] {
        &self.tasks
    }

    /// How each task fares in the current posture, one per task in the same order.
    pub fn statuses(&self) -> &[TaskStatus] {
        &self.statuses
    }

    /// The last solve's report; `None` before the first solve and after a restored document.
    pub fn report(&self) -> Option<&SolveReport> {
        self.report.as_ref()
    }

    /// The grab-and-pull task while a pull goes on.
    pub fn grab(&self) -> Option<&Grab> {
        self.grab.as_ref()
    }

    /// Whether an active collision task keeps the body out of itself or the floor.
    pub fn collision_on(&self) -> bool {
        self.tasks
            .iter()
            .any(|task| task.active && matches!(task.kind, TaskKindSpec::Collision { .. }))
    }

    /// The contacts the active collision tasks hold in the current posture: the pairs of
    /// surfaces (and surfaces and the floor) within their margin, nearest first.
    pub fn contacts(&self) -> &[Contact] {
        &self.contacts
    }

    /// Holds the body off these fixed solids in its collision tasks (the scene's props, in
    /// the body's frame); when they changed and a collision task acts, the solver runs again
    /// (comfort armed or not as it was: a prop moved is neither a change of tasks nor an edit
    /// of the posture).
    pub fn set_obstacles(&mut self, obstacles: Vec<Obstacle>) {
        if obstacles != self.obstacles {
            self.obstacles = obstacles;
            self.collisions.clear();
            if self.collision_on() {
                self.settled = false;
                self.refresh();
            }
        }
    }

    /// The fixed solids the collision tasks hold the body off.
    pub fn obstacles(&self) -> &[Obstacle] {
        &self.obstacles
    }

    /// Whether the solver has nothing left to do until something changes.
    pub fn is_settled(&self) -> bool {
        self.settled
    }

    /// World position of a joint centre by name.
    pub fn joint_position(&self, name: &str) -> Option<DVec3> {
        let index = self.skeleton().joint_index(name)?;
        self.frames.joint_position.get(index).copied()
    }

    /// Replaces the task list (an edit from the panels); the solver runs again.
    pub fn set_tasks(&mut self, tasks: Vec<TaskSpec>) {
        self.tasks = tasks;
        self.wake(Wake::Tasks);
    }

    /// Replaces the posture (undo, reset, mirror, sensors); the solver runs again.
    pub fn set_posture(&mut self, posture: Posture) {
        self.posture = posture;
        self.wake(Wake::Posture);
    }

    /// Holds these joints where they are in the following solves (driven from outside: the
    /// motion-capture sensors); an empty slice frees them all. The other joints keep solving
    /// the tasks around them.
    pub fn hold_joints(&mut self, joints: &[usize]) {
        let skeleton = &self.humanoid.skeleton;
        let dofs: Vec<usize> = joints
            .iter()
            .filter_map(|&joint| skeleton.joints().get(joint))
            .flat_map(|joint| joint.rotation_dof.iter().flatten().copied())
            .collect();
        let unchanged =
            (0..skeleton.dof_count()).all(|d| self.solver.is_locked(d) == dofs.contains(&d));
        if !unchanged {
            self.solver.set_locked_dofs(&dofs);
            self.wake(Wake::Posture);
        }
    }

    /// Joints held by [`PosingSession::hold_joints`].
    pub fn held_joints(&self) -> Vec<usize> {
        let skeleton = &self.humanoid.skeleton;
        (0..skeleton.joint_count())
            .filter(|&joint| {
                skeleton.joints()[joint]
                    .rotation_dof
                    .iter()
                    .flatten()
                    .any(|&d| self.solver.is_locked(d))
            })
            .collect()
    }

    /// Sets the local rotations of these joints (projected onto each joint's DOF; the
    /// measurement is kept even where it leaves the anatomical range) and solves the rest of
    /// the body again around them.
    pub fn drive_joints(&mut self, rotations: &[(usize, DQuat)]) {
        let skeleton = &self.humanoid.skeleton;
        let values = self.posture.values_mut();
        let mut changed = false;
        for &(joint, rotation) in rotations {
            let Some(definition) = skeleton.joints().get(joint) else {
                continue;
            };
            if !rotation.is_finite() {
                continue;
            }
            let rotation = if rotation.w < 0.0 {
                -rotation
            } else {
                rotation
            };
            let vector = rotation.normalize().to_scaled_axis();
            if !vector.is_finite() {
                continue;
            }
            for axis in 0..3 {
                if let Some(slot) = definition.rotation_dof[axis].and_then(|d| values.get_mut(d))
                    && (*slot - vector[axis]).abs() > 1e-9
                {
                    *slot = vector[axis];
                    changed = true;
                }
            }
        }
        if changed {
            self.wake(Wake::Posture);
        }
    }

    /// The document: avatar, posture and tasks (the grab is not part of it).
    pub fn document(&self) -> Document {
        Document {
            posture: PostureValues::from_posture(self.skeleton(), &self.posture),
            tasks: self.tasks.clone(),
            motion: self.motion.clone(),
            camera: self.camera,
            stiffness: self.stiffness.clone(),
            ..Document::default()
        }
    }

    /// The camera saved with the document, if any.
    pub fn camera(&self) -> Option<CameraSpec> {
        self.camera
    }

    /// Saves a camera with the document (`None`: the viewer's own).
    pub fn set_camera(&mut self, camera: Option<CameraSpec>) {
        self.camera = camera;
        self.revision = self.revision.wrapping_add(1);
    }

    /// Changes whenever the posture, the tasks or their statuses change.
    pub fn revision(&self) -> u64 {
        self.revision
    }

    /// Restores a document exactly as it was saved, without solving: undo, redo, opening a
    /// link or a saved pose show that very posture. On error the session stays as it was.
    pub fn restore_document(&mut self, document: &Document) -> Result<(), PosingError> {
        self.take_document(document)?;
        self.report = None;
        self.settled = true;
        self.comfort_armed = false;
        self.refresh();
        Ok(())
    }

    /// The document's posture, tasks, stiffness, timeline and camera in place of the
    /// session's (a grab ends); nothing changes on error.
    fn take_document(&mut self, document: &Document) -> Result<(), PosingError> {
        let posture = document.posture.to_posture(self.skeleton())?;
        self.apply_stiffness_overrides(&document.stiffness)?;
        self.posture = posture;
        self.tasks = document.tasks.clone();
        self.motion = document.motion.clone();
        self.motion_revision = self.motion_revision.wrapping_add(1);
        self.camera = document.camera;
        self.grab = None;
        Ok(())
    }

    /// Sets one DOF (joint mode), clamped to its limits; the solver runs again so that the
    /// tasks above still hold.
    pub fn set_dof(&mut self, dof: usize, value: f64) {
        self.set_dofs(&[(dof, value)]);
    }

    /// Sets several DOF at once (a hand preset), each clamped into its limits (a value that
    /// is not finite or a DOF the body lacks is left out); the solver runs again once.
    pub fn set_dofs(&mut self, values: &[(usize, f64)]) {
        let skeleton = &self.humanoid.skeleton;
        let (lower, upper) = (skeleton.lower_limits(), skeleton.upper_limits());
        let posture = self.posture.values_mut();
        let mut changed = false;
        for &(dof, value) in values {
            let (Some(&low), Some(&high), Some(slot)) =
                (lower.get(dof), upper.get(dof), posture.get_mut(dof))
            else {
                continue;
            };
            if value.is_finite() {
                *slot = if low <= high {
                    value.clamp(low, high)
                } else {
                    value
                };
                changed = true;
            }
        }
        if changed {
            self.wake(Wake::Posture);
        }
    }

    /// The swivel angle of a limb in the current posture and the swivel intervals that keep
    /// the limb within its limits for the current end position.
    pub fn limb_swivel(&self, limb: LimbName) -> Option<(f64, Vec<SwivelInterval>)> {
        let [upper, middle, end] = limb.joints();
        let skeleton = self.skeleton();
        let limb = Limb::from_names(skeleton, [upper, middle, end]).ok()?;
        let swivel = limb.swivel_angle(skeleton, &self.posture);
        let base = limb.base(skeleton, &self.frames);
        let goal = LimbGoal::position(self.joint_position(end)?);
        Some((swivel, limb.swivel_intervals(base, &goal)))
    }

    /// Turns the elbow/knee around the limb's axis, the hand/foot staying where it is (the
    /// feasible swivel nearest to the one asked). Returns whether the posture changed.
    pub fn set_limb_swivel(&mut self, limb: LimbName, swivel_angle: f64) -> bool {
        let [upper, middle, end] = limb.joints();
        let Some(end_position) = self.joint_position(end) else {
            return false;
        };
        let skeleton = &self.humanoid.skeleton;
        let Ok(limb) = Limb::from_names(skeleton, [upper, middle, end]) else {
            return false;
        };
        let base = limb.base(skeleton, &self.frames);
        let solution =
            limb.solve_within_limits(base, &LimbGoal::position(end_position), swivel_angle);
        let mut posture = self.posture.clone();
        limb.apply(&solution, &mut posture);
        if posture.values().iter().any(|value| !value.is_finite()) {
            return false;
        }
        self.set_posture(posture);
        true
    }

    /// Holds the end joint of `limb` where it is now (level 1) until [`Self::release_hold`]:
    /// while the swivel handle turns the elbow or knee, the balance that follows does not
    /// move the hand or foot.
    pub fn hold_limb_end(&mut self, limb: LimbName) {
        let end = limb.joints()[2];
        if let (Some(joint), Some(position)) =
            (self.skeleton().joint_index(end), self.joint_position(end))
        {
            self.held = Some((joint, position));
        }
    }

    /// Ends [`Self::hold_limb_end`].
    pub fn release_hold(&mut self) {
        if self.held.take().is_some() {
            self.wake(Wake::Posture);
        }
    }

    /// Mirrors left and right: the posture, and the tasks with it (left and right joints
    /// swap, goals are reflected in the sagittal plane), so that the solver keeps the mirror.
    pub fn mirror(&mut self) {
        let posture = self.mirrored_posture();
        self.tasks = self.tasks.iter().map(TaskSpec::mirrored).collect();
        self.grab = None;
        self.set_posture(posture);
    }

    /// The document's timeline and keys, if any.
    pub fn motion(&self) -> Option<&MotionSection> {
        self.motion.as_ref()
    }

    /// Changes whenever the timeline and keys are replaced (an edit, undo, an opened
    /// document).
    pub fn motion_revision(&self) -> u64 {
        self.motion_revision
    }

    /// Replaces the timeline and keys (the posture stays).
    pub fn set_motion(&mut self, motion: Option<MotionSection>) {
        self.motion = motion;
        self.motion_revision = self.motion_revision.wrapping_add(1);
        self.revision = self.revision.wrapping_add(1);
    }

    /// Shows a timeline frame: its posture at `time` seconds, the tasks acting with their
    /// interval weights from there; `None` leaves the timeline (every task acts fully).
    pub fn show_timed(&mut self, frame: Option<(Posture, f64)>) {
        self.timed = frame.map(|(posture, time)| {
            let frames = Frames::new(&self.humanoid.skeleton, &posture);
            self.posture = posture;
            TimedFrame { time, frames }
        });
        self.grab = None;
        self.wake(Wake::Posture);
    }

    /// The tasks as the solver takes them now (see [`timed_tasks`]).
    pub fn timed_tasks(&self) -> Vec<TaskSpec> {
        timed_tasks(&self.tasks, self.skeleton(), self.timed.as_ref())
    }

    /// Loads a document; on error the session stays as it was.
    pub fn load_document(&mut self, document: &Document) -> Result<(), PosingError> {
        self.take_document(document)?;
        self.wake(Wake::Tasks);
        Ok(())
    }

    /// Starts pulling the point `point_world` of the segment of `joint`.
    pub fn begin_grab(&mut self, joint: usize, point_world: DVec3) {
        let (Some(&position), Some(rotation)) = (
            self.frames.joint_position.get(joint),
            self.frames.world_from_joint_rotation.get(joint),
        ) else {
            return;
        };
        let point_local = rotation.transpose() * (point_world - position);
        self.grab = Some(Grab {
            joint,
            point_local,
            target_world: point_world,
        });
        self.wake(Wake::Tasks);
    }

    /// Moves the pulled point's goal.
    pub fn move_grab(&mut self, target_world: DVec3) {
        if let Some(grab) = &mut self.grab
            && target_world.is_finite()
        {
            grab.target_world = target_world;
            // Only the goal moved: the posture, its frames and the tasks' statuses are as
            // they were until the next frame's solve (which refreshes them once).
            self.settled = false;
            self.revision = self.revision.wrapping_add(1);
        }
    }

    /// Releases the pulled point: the body keeps the posture it reached (a pull is a direct
    /// edit: comfort does not take the hand back down).
    pub fn end_grab(&mut self) {
        self.grab = None;
        self.wake(Wake::Posture);
    }

    /// The world position of the grabbed point in the current posture.
    pub fn grabbed_point_world(&self) -> Option<DVec3> {
        let grab = self.grab?;
        Some(self.frames.point(grab.joint, grab.point_local))
    }

    /// A level-1 position task that holds the joint where it is now.
    pub fn pin(&mut self, joint: usize) {
        let Some(joint_def) = self.skeleton().joints().get(joint) else {
            return;
        };
        let name = joint_def.name.clone();
        let Some(position) = self.frames.joint_position.get(joint).copied() else {
            return;
        };
        self.tasks.push(TaskSpec::pin(&name, position.to_array()));
        self.wake(Wake::Tasks);
    }

    /// Back to the rest posture (tasks kept).
    pub fn reset_to_rest(&mut self) {
        let rest = Posture::rest(self.skeleton());
        self.set_posture(rest);
    }

    /// The posture mirrored left/right: each side takes the other's rotations, reflected
    /// in the body's sagittal plane.
    pub fn mirrored_posture(&self) -> Posture {
        let skeleton = self.skeleton();
        let mut values = vec![0.0; skeleton.dof_count()];
        for (index, joint) in skeleton.joints().iter().enumerate() {
            let other_name = mirror_name(&joint.name);
            let source = skeleton.joint_index(&other_name).unwrap_or(index);
            let source_joint = &skeleton.joints()[source];
            for (dof_position, dof) in joint.dofs.iter().enumerate() {
                let Some(source_position) = source_joint.dofs.iter().position(|d| d == dof) else {
                    continue;
                };
                let Some(value) = self
                    .posture
                    .values()
                    .get(source_joint.dof_range().start + source_position)
                else {
                    continue;
                };
                // Reflection x -> -x: positions flip x; rotation vectors (axial) keep x and
                // flip y and z.
                let sign = match dof.name() {
                    "tx" | "ry" | "rz" => -1.0,
                    _ => 1.0,
                };
                if let Some(slot) = values.get_mut(joint.dof_range().start + dof_position) {
                    *slot = sign * value;
                }
            }
        }
        Posture::from_values(skeleton, values).unwrap_or_else(|_| self.posture.clone())
    }

    /// Runs the solver for this frame (a few iterations within the frame budget) when there
    /// is something to do. Returns whether the posture changed.
    pub fn solve_frame(&mut self, clock: Option<&dyn Clock>) -> bool {
        if self.settled {
            return false;
        }
        let tasks = self.frame_tasks();
        let before = self.posture.values().to_vec();
        match self.solver.solve_with_clock(
            &self.humanoid.skeleton,
            &tasks,
            &mut self.posture,
            clock,
        ) {
            Ok(report) => self.take_report(report),
            Err(error) => {
                log::warn!("solver: {error}");
                self.settled = true;
            }
        }
        self.refresh();
        before != self.posture.values()
    }

    /// The solver tasks of this frame: the document's (timed), the held joint, the pull, and
    /// comfort once armed and nothing is held or pulled.
    pub fn frame_tasks(&self) -> Vec<Task> {
        let specs = self.timed_tasks();
        FrameProblem {
            specs: &specs,
            comfort: self.comfort_armed && self.grab.is_none() && self.held.is_none(),
            held: self.held,
            grab: self.grab,
            obstacles: &self.obstacles,
            collisions: &self.collisions,
        }
        .tasks(&self.humanoid.skeleton, Some(&self.humanoid))
    }

    /// Takes the posture a solve of several characters together found for this one (see
    /// `EditorModel`'s joined solve), as its own solve would: settled when that solve
    /// converged or stalled.
    pub fn take_joined_solve(&mut self, posture: Posture, report: SolveReport) {
        if posture.values().len() != self.posture.values().len() {
            return;
        }
        self.posture = posture;
        self.take_report(report);
        self.refresh();
    }

    /// A solve's report: settled when it converged or stalled.
    fn take_report(&mut self, report: SolveReport) {
        self.settled = matches!(report.status, SolveStatus::Converged | SolveStatus::Stalled);
        self.report = Some(report);
    }

    /// Wakes the solver after something outside the session changed what the body must do
    /// (a task between it and another character added or removed).
    pub fn wake_for_tasks(&mut self) {
        self.wake(Wake::Tasks);
    }

    fn wake(&mut self, cause: Wake) {
        self.comfort_armed = cause == Wake::Tasks;
        self.settled = false;
        self.refresh();
    }

    /// The collision tasks built for their specs (each once), and the active ones' contacts
    /// in the current posture.
    fn refresh_contacts(&mut self) {
        let mut built: Vec<(TaskKindSpec, Collision)> = Vec::new();
        for spec in &self.tasks {
            if !matches!(spec.kind, TaskKindSpec::Collision { .. })
                || built.iter().any(|(kind, _)| *kind == spec.kind)
            {
                continue;
            }
            let kept = self
                .collisions
                .iter()
                .position(|(kind, _)| *kind == spec.kind);
            match kept {
                Some(i) => built.push(self.collisions.swap_remove(i)),
                None => {
                    if let Ok(stance_ik::Task {
                        kind: TaskKind::Collision(collision),
                        ..
                    }) = spec.to_task_on(&self.humanoid, &self.tasks)
                    {
                        built.push((
                            spec.kind.clone(),
                            collision.with_obstacles(self.obstacles.clone()),
                        ));
                    }
                }
            }
        }
        self.collisions = built;
        let frames = &self.frames;
        let active = &self.tasks;
        let mut contacts: Vec<Contact> = self
            .collisions
            .iter()
            .filter(|(kind, _)| active.iter().any(|t| t.active && t.kind == *kind))
            .flat_map(|(_, collision)| collision.contacts(frames))
            .collect();
        contacts.sort_by(|a, b| a.distance.total_cmp(&b.distance));
        self.contacts = contacts;
    }

    /// Forward kinematics and the per-task statuses of the current posture.
    fn refresh(&mut self) {
        self.revision = self.revision.wrapping_add(1);
        self.frames = Frames::new(&self.humanoid.skeleton, &self.posture);
        self.refresh_contacts();
        self.statuses = stance_document::task_statuses(
            &self.humanoid.skeleton,
            Some(&self.humanoid),
            &self.posture,
            &self.frames,
            &self.tasks,
            self.settled,
        );
    }
}

/// The world rotation of a joint as a quaternion (for orientation tasks made from the pose).
pub fn joint_rotation(frames: &Frames, joint: usize) -> DQuat {
    if joint < frames.world_from_joint_rotation.len() {
        frames.rotation(joint)
    } else {
        DQuat::IDENTITY
    }
}

/// `tasks` with collision avoidance on (every collision task active; the body's own, just
/// below the pins, added where there is none) or off (every collision task inactive).
pub(crate) fn collision_switched(tasks: &mut Vec<TaskSpec>, on: bool) {
    let mut found = false;
    for task in tasks
        .iter_mut()
        .filter(|task| matches!(task.kind, TaskKindSpec::Collision { .. }))
    {
        task.active = on;
        found = true;
    }
    if on && !found {
        // After the tasks above it, so that the list reads in priority order.
        let at = tasks
            .iter()
            .position(|task| task.level >= stance_document::COLLISION_LEVEL)
            .unwrap_or(tasks.len());
        tasks.insert(at, TaskSpec::collision());
    }
}

#[cfg(test)]
mod tests;
