//! Retargeting: a clip of skeleton A onto body B of other proportions, naming and level of
//! articulation, through H-Anim as the intermediate skeleton ([MON 00]; the paper, section
//! 2.2), with the contacts kept by prioritized tasks over time.
//!
//! 1. **Rest match** ([`RestMatch`]): per H-Anim joint, a constant rotation `C` so that the
//!    target bone posed by the source's world rotation `G_s` points where the source bone
//!    points: `G_t = G_s · C · A` (`A`: the user's adjustment). Joints the clip lacks move
//!    rigidly with their parent, so a clip made at one LOA plays at another.
//! 2. **Root motion** scaled by hip height (hips above the ankles, target over source); the
//!    lowest ankle of the clip lands at the target's ankle height standing at rest.
//! 3. The result is the **plain rotation copy** (what three.js's `retargetClip` does).
//! 4. **Tasks over time**: contacts with the ground (detected on the clip,
//!    [`crate::contacts`]: the heel and the ball of each foot, hands, knees, pelvis) as
//!    level-1 position tasks on those points eased in and out (where both points of a foot
//!    are held, the one that gives way at level 2), the root's path at level 3, the wrists
//!    at level 4, and the copied frame as the reference of a posture task at level 5 (the
//!    original motion as the null-space attraction: the foot's roll about a held heel or
//!    ball is the clip's). Each frame starts from the previous solution: the previous
//!    frame's correction of the copy is carried onto this frame's copy.

mod copy;
mod held;
mod report;

use glam::DVec3;
use stance_hanim::HumanoidSkeleton;
use stance_ik::{
    CONSTANT_DAMPING, Frames, IkError, Iteration, Posture, Solver, SolverSettings, Task,
};

use crate::clip::{Clip, ClipError};
use crate::contacts::{
    Contact, ContactPart, ContactSettings, Thresholds, contact_weight, reference_frames,
};
pub use copy::{Placement, RestMatch, RotationCopy};
use held::{Found, held_contacts, stride_scale};
pub use report::{
    ContactMetrics, Deviation, Metrics, Smoothness, contact_metrics, deviation, metrics, smoothness,
};

/// The H-Anim feet (ankles) whose heel and ball are held by contacts.
pub const CONTACT_JOINTS: [&str; 2] = ["l_talocrural", "r_talocrural"];
/// The H-Anim knees held by contacts.
const KNEES: [&str; 2] = ["l_knee", "r_knee"];
/// The H-Anim wrists kept at [`WRIST_LEVEL`].
const WRISTS: [&str; 2] = ["l_radiocarpal", "r_radiocarpal"];

/// Levels of the retargeting problem.
pub const CONTACT_LEVEL: u32 = 1;
/// The point of a foot that gives way where the leg cannot hold both its heel and its ball
/// (the one whose contact ends first: the heel at heel-off), below the other.
pub const YIELDING_CONTACT_LEVEL: u32 = 2;
/// The sliding contacts: points of a foot kept from sinking under the floor while the clip
/// moves them along ([`Contact::slides`]).
pub const SLIDING_CONTACT_LEVEL: u32 = 3;
/// The root's path.
pub const ROOT_LEVEL: u32 = 4;
/// The wrists.
pub const WRIST_LEVEL: u32 = 5;
/// The copied frame as a posture reference.
pub const POSTURE_LEVEL: u32 = 6;
/// The levels, in the order of [`Retargeted::levels`] and of each frame's residuals.
const LEVELS: [u32; 6] = [
    CONTACT_LEVEL,
    YIELDING_CONTACT_LEVEL,
    SLIDING_CONTACT_LEVEL,
    ROOT_LEVEL,
    WRIST_LEVEL,
    POSTURE_LEVEL,
];

/// Errors of retargeting.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MotionError {
    /// The clip has no frames.
    #[error("the clip has no frames")]
    Empty,
    /// The clip maps none of the target's joints.
    #[error("the clip and the target share no H-Anim joint (is the clip a humanoid?)")]
    NoCommonJoints,
    /// The clip is malformed.
    #[error("clip: {0}")]
    Clip(#[from] ClipError),
    /// The solver refused the problem.
    #[error("solver: {0}")]
    Ik(#[from] IkError),
    /// [`Retargeting::finish`] before its steps were done.
    #[error("the retargeting is not finished")]
    Unfinished,
}

/// How to retarget.
#[derive(Debug, Clone, PartialEq)]
pub struct RetargetOptions {
    /// How the rest poses are matched (default: bone directions).
    pub rest_match: RestMatch,
    /// Per H-Anim joint, a world rotation applied to the matched rest (the user's
    /// correction, e.g. arms lowered by 10 degrees).
    pub adjustments: Vec<(String, glam::DQuat)>,
    /// Contact detection; `None`: no contacts, the result is the plain copy.
    pub contacts: Option<ContactSettings>,
    /// Root motion scale; `None`: hip height of the target over the source's.
    pub root_scale: Option<f64>,
    /// Iterations per frame (default 12).
    pub max_iterations: usize,
}

impl Default for RetargetOptions {
    fn default() -> Self {
        Self {
            rest_match: RestMatch::Directions,
            adjustments: Vec::new(),
            contacts: Some(ContactSettings::default()),
            root_scale: None,
            max_iterations: 12,
        }
    }
}

impl RetargetOptions {
    /// The same options with both arms' rest match turned outward (abduction, about the
    /// body's front axis) by `degrees`: raise them for a clip whose arms hang lower at rest
    /// than the body's (an A-pose clip on a T-pose body), lower them with a negative angle.
    /// Replaces any shoulder adjustment.
    pub fn with_arm_lift(mut self, degrees: f64) -> Self {
        self.adjustments
            .retain(|(joint, _)| joint != "l_shoulder" && joint != "r_shoulder");
        if degrees.is_finite() && degrees != 0.0 {
            let a = degrees.to_radians();
            self.adjustments
                .push(("l_shoulder".into(), glam::DQuat::from_rotation_z(a)));
            self.adjustments
                .push(("r_shoulder".into(), glam::DQuat::from_rotation_z(-a)));
        }
        self
    }

    /// The arms' lift set by [`RetargetOptions::with_arm_lift`] (degrees; 0 without one).
    pub fn arm_lift(&self) -> f64 {
        self.adjustments
            .iter()
            .find(|(joint, _)| joint == "l_shoulder")
            .map_or(0.0, |(_, q)| {
                let (axis, angle) = q.to_axis_angle();
                (angle * axis.z.signum()).to_degrees()
            })
    }
}

/// A retargeted clip.
#[derive(Debug, Clone, PartialEq)]
pub struct Retargeted {
    /// One posture of the target per frame of the clip (same count; same frame time).
    pub postures: Vec<Posture>,
    /// The plain rotation copy, per frame.
    pub copy: Vec<Posture>,
    /// The contacts held.
    pub contacts: Vec<Contact>,
    /// Frames at the start left out of the contacts as a reference pose
    /// ([`crate::contacts::reference_frames`]).
    pub reference_frames: usize,
    /// The contact thresholds as applied to this clip (scaled with its leg and pace).
    pub thresholds: Thresholds,
    /// The levels of the problem, in order.
    pub levels: Vec<u32>,
    /// Per frame, per level: the residual norm after the solve (m or rad; 0 where the level
    /// had no task that frame).
    pub residuals: Vec<Vec<f64>>,
    /// Solver iterations over the whole clip.
    pub iterations: usize,
    /// Seconds per frame (the clip's).
    pub frame_time: f64,
    /// Where clip positions land on the target (root scale, floor).
    pub placement: Placement,
    /// What was noticed (joints the clip lacks...).
    pub notes: Vec<String>,
}

/// World positions of `joints` (skeleton indices) of every posture (m).
pub fn joint_positions(
    target: &HumanoidSkeleton,
    postures: &[Posture],
    joints: &[usize],
) -> Vec<Vec<DVec3>> {
    postures
        .iter()
        .map(|p| {
            let frames = Frames::new(&target.skeleton, p);
            joints.iter().map(|&j| frames.joint_position[j]).collect()
        })
        .collect()
}

/// Retargets `clip` onto `target` (see the module documentation): [`Retargeting`] run to
/// the end in one call.
pub fn retarget(
    clip: &Clip,
    target: &HumanoidSkeleton,
    options: &RetargetOptions,
) -> Result<Retargeted, MotionError> {
    let mut job = Retargeting::new(clip.clone(), target.clone(), options.clone())?;
    while !job.step(usize::MAX)? {}
    job.finish().map(|(_, retargeted)| retargeted)
}

/// Work of one frame of the copy, relative to one frame of the solve (progress weights).
const COPY_WORK: f64 = 0.05;
/// Work of finding the contacts, per frame, relative to one frame of the solve.
const CONTACT_WORK: f64 = 0.1;

/// Where a [`Retargeting`] is.
#[derive(Debug)]
enum Stage {
    /// Copying frame `next` (`pass` 0: first copy; 1: again with the stride's scale).
    Copy { pass: u8, next: usize },
    /// Finding the contacts over the copy of `pass`.
    Contacts { pass: u8 },
    /// Solving frame `next`.
    Solve(Box<FrameSolver>),
    /// The result is ready.
    Done,
    /// The solver refused its settings.
    Failed(MotionError),
}

/// A retargeting run in steps, so that a caller can report its progress between them and
/// stop it (dropping it leaves nothing behind): the same result as [`retarget`], which runs
/// one. Steps copy the clip's frames onto the body (twice when the stride's scale is fitted),
/// find the contacts, then solve the frames one by one, each from the previous one's.
#[derive(Debug)]
pub struct Retargeting {
    clip: Clip,
    target: HumanoidSkeleton,
    options: RetargetOptions,
    copier: RotationCopy,
    stage: Stage,
    reference: usize,
    copy: Vec<Posture>,
    found: Option<Found>,
    out: Option<Retargeted>,
    /// Work done and expected in all (in frames of the solve).
    done: f64,
    total: f64,
}

impl Retargeting {
    /// Prepares the retargeting of `clip` onto `target` (the rest match); the frames are
    /// worked on by [`Retargeting::step`].
    pub fn new(
        clip: Clip,
        target: HumanoidSkeleton,
        options: RetargetOptions,
    ) -> Result<Self, MotionError> {
        clip.validate()?;
        if clip.frames.is_empty() {
            return Err(MotionError::Empty);
        }
        let copier = RotationCopy::new(&clip, &target, &options)?;
        let n = clip.frame_count() as f64;
        let total = match options.contacts {
            None => n * COPY_WORK,
            // The copy and the contacts a second time when the stride's scale is fitted.
            Some(_) if options.root_scale.is_none() => 2.0 * n * (COPY_WORK + CONTACT_WORK) + n,
            Some(_) => n * (COPY_WORK + CONTACT_WORK) + n,
        };
        Ok(Self {
            reference: reference_frames(&clip),
            copy: Vec::with_capacity(clip.frame_count()),
            clip,
            target,
            options,
            copier,
            stage: Stage::Copy { pass: 0, next: 0 },
            found: None,
            out: None,
            done: 0.0,
            total,
        })
    }

    /// The clip's frame count.
    pub fn frame_count(&self) -> usize {
        self.clip.frame_count()
    }

    /// How much of the work is done, from 0 to 1 (never decreasing).
    pub fn progress(&self) -> f64 {
        if matches!(self.stage, Stage::Done) {
            return 1.0;
        }
        (self.done / self.total).clamp(0.0, 1.0)
    }

    /// Works on at most `frames` frames (of the copy or of the solve; finding the contacts
    /// is one step). Returns whether the work is done ([`Retargeting::finish`] then).
    pub fn step(&mut self, frames: usize) -> Result<bool, MotionError> {
        let frames = frames.max(1);
        let n = self.clip.frame_count();
        match &mut self.stage {
            Stage::Copy { pass, next } => {
                let pass = *pass;
                let end = next.saturating_add(frames).min(n);
                for f in *next..end {
                    self.copy
                        .push(self.copier.frame(&self.clip, &self.target, f)?);
                }
                self.done += (end - *next) as f64 * COPY_WORK;
                *next = end;
                if end == n {
                    match self.options.contacts {
                        Some(_) => self.stage = Stage::Contacts { pass },
                        None => self.finish_setup(),
                    }
                }
            }
            Stage::Contacts { pass } => {
                let pass = *pass;
                self.find_contacts(pass);
            }
            Stage::Solve(solver) => {
                let Some(out) = self.out.as_mut() else {
                    self.stage = Stage::Done;
                    return Ok(true);
                };
                let end = solver.next.saturating_add(frames).min(n);
                for f in solver.next..end {
                    solver.solve_frame(&self.target, out, f)?;
                }
                self.done += (end - solver.next) as f64;
                solver.next = end;
                if end == n {
                    self.stage = Stage::Done;
                }
            }
            Stage::Done => {}
            Stage::Failed(error) => return Err(error.clone()),
        }
        Ok(matches!(self.stage, Stage::Done))
    }

    /// The contacts over the copy of `pass`; after the first, the stride's scale is fitted
    /// to them and the copy made again with it (when the user gave no root scale).
    fn find_contacts(&mut self, pass: u8) {
        let Some(settings) = self.options.contacts else {
            self.finish_setup();
            return;
        };
        let (clip, target) = (&self.clip, &self.target);
        let found = held_contacts(
            clip,
            target,
            &self.copy,
            &self.copier.placement,
            self.reference,
            &settings,
        );
        let n = clip.frame_count() as f64;
        self.done += n * CONTACT_WORK;
        if pass == 0 && self.options.root_scale.is_none() {
            if let Some(stride) = stride_scale(
                clip,
                target,
                &self.copy,
                &self.copier.placement,
                &found.contacts,
            ) {
                self.copier.placement.stride_scale = stride;
                self.copy.clear();
                self.stage = Stage::Copy { pass: 1, next: 0 };
                return;
            }
            // No second copy.
            self.done += n * (COPY_WORK + CONTACT_WORK);
        }
        self.found = Some(found);
        self.finish_setup();
    }

    /// The copy and contacts are ready: the result takes them, and the solve starts (or,
    /// without contacts, the copy is the result).
    fn finish_setup(&mut self) {
        let mut notes = self.copier.notes.clone();
        let (contacts, thresholds) = match self.found.take() {
            Some(found) => {
                notes.extend(found.notes);
                (found.contacts, found.thresholds)
            }
            None => (Vec::new(), Thresholds::default()),
        };
        let reference = self.reference;
        if reference > 0 {
            notes.push(format!(
                "the first {reference} frame(s) are a reference pose (a T-pose or an A-pose and \
                 the blend out of it): left out of the contacts and the floor"
            ));
        }
        let copy = std::mem::take(&mut self.copy);
        let mut out = Retargeted {
            postures: Vec::with_capacity(copy.len()),
            copy,
            contacts,
            reference_frames: reference,
            thresholds,
            levels: LEVELS.to_vec(),
            residuals: Vec::new(),
            iterations: 0,
            frame_time: self.clip.frame_time,
            placement: self.copier.placement,
            notes,
        };
        match self.options.contacts {
            None => {
                out.postures = out.copy.clone();
                out.residuals = vec![vec![0.0; out.levels.len()]; out.postures.len()];
                self.stage = Stage::Done;
            }
            Some(settings) => {
                let ease = settings.ease_frames(self.clip.frame_time);
                match FrameSolver::new(&self.target, ease, self.options.max_iterations) {
                    Ok(solver) => self.stage = Stage::Solve(Box::new(solver)),
                    // Settings the solver refuses: the next step says so.
                    Err(error) => self.stage = Stage::Failed(error),
                }
            }
        }
        self.out = Some(out);
    }

    /// The clip and its retargeting, once [`Retargeting::step`] said it is done.
    pub fn finish(self) -> Result<(Clip, Retargeted), MotionError> {
        match (self.stage, self.out) {
            (Stage::Done, Some(out)) => Ok((self.clip, out)),
            _ => Err(MotionError::Unfinished),
        }
    }
}

/// The rotations the tasks above the posture level can move (the feet's, the root's and the
/// wrists' chains, the root's rotation included: the body keeps the clip's attitude); the
/// others (fingers, the head...) keep the copy's values, which the step cannot change.
fn posture_dofs(skeleton: &stance_ik::Skeleton) -> Vec<usize> {
    let mut dofs: Vec<usize> = CONTACT_JOINTS
        .iter()
        .chain(&WRISTS)
        .filter_map(|name| skeleton.joint_index(name))
        .chain([0])
        .flat_map(|j| skeleton.chain_dofs(j))
        .filter(|&d| skeleton.dof_kinds()[d].is_rotation())
        .collect();
    dofs.sort_unstable();
    dofs.dedup();
    dofs
}

/// The tasks of one frame.
fn frame_tasks(
    target: &HumanoidSkeleton,
    copy: &Posture,
    contacts: &[Contact],
    (frame, ease): (usize, usize),
    dofs: &[usize],
) -> Vec<Task> {
    let skeleton = &target.skeleton;
    let frames = Frames::new(skeleton, copy);
    let mut tasks = Vec::new();
    // Per point (joint and part), the firmest of its contacts at this frame that hold it
    // still, and of those that keep it on the floor while it slides.
    let mut firmest: Vec<(&Contact, f64)> = Vec::new();
    for c in contacts {
        let w = contact_weight(c, frame, ease);
        if w <= 0.0 {
            continue;
        }
        match firmest
            .iter_mut()
            .find(|(h, _)| h.joint == c.joint && h.part == c.part && h.slides == c.slides)
        {
            Some(slot) if slot.1 < w => *slot = (c, w),
            Some(_) => {}
            None => firmest.push((c, w)),
        }
    }
    let (sliding, mut firmest): (Vec<_>, Vec<_>) = firmest.into_iter().partition(|h| h.0.slides);
    // Firmest first: a point easing in or out on a foot whose other point is held more
    // firmly eases from where the copy's foot puts it relative to that point's goal (not
    // from the copy's own position), so that the goals fit the foot and it rolls about the
    // held point as the clip's does.
    firmest.sort_by(|a, b| b.1.total_cmp(&a.1));
    let mut goals: Vec<(&Contact, f64, usize, DVec3)> = Vec::with_capacity(firmest.len());
    for (c, w) in firmest {
        let Some(j) = skeleton.joint_index(&c.joint) else {
            continue;
        };
        let own = frames.point(j, c.point);
        let from = goals
            .iter()
            .find(|(h, _, k, _)| *k == j && h.part.is_foot() && c.part.is_foot())
            .map_or(own, |(h, _, _, goal)| {
                *goal + (own - frames.point(j, h.point))
            });
        let mut goal = from.lerp(c.position, w);
        // Easing into or out of a slide of that point, the hold keeps it from sinking under
        // the floor the slide keeps (the copy's point can be under it).
        if let Some((s, _)) = sliding
            .iter()
            .find(|(s, _)| s.joint == c.joint && s.part == c.part)
        {
            goal.y = goal.y.max(c.position.y.min(s.position.y));
        }
        goals.push((c, w, j, goal));
    }
    // Where both points of a foot are held, one gives way to the other where the leg cannot
    // reach both, so that the foot rolls about the point that stays: the one held less
    // firmly (easing in or out: its goal is partly the copy's), or, both held in full, the
    // one whose contact ends first (the heel before heel-off, a ball that lands after the
    // heel and lifts before it).
    for &(c, w, j, goal) in &goals {
        let yields = c.part.is_foot()
            && goals.iter().any(|&(o, v, k, _)| {
                k == j
                    && o.part.is_foot()
                    && o.part != c.part
                    && (v > w
                        || (v == w
                            && (o.end > c.end || (o.end == c.end && c.part == ContactPart::Heel))))
            });
        let level = if yields {
            YIELDING_CONTACT_LEVEL
        } else {
            CONTACT_LEVEL
        };
        tasks.push(Task::position(j, c.point, goal).at_level(level));
    }
    // A sliding point goes along with the copy, kept on or above the floor (an inequality:
    // never pulled down). Easing in or out, the floor is eased from the copy's point where
    // that is lower: nothing pops. (A hold of that point easing in or out beside it is never
    // lower than the slide's floor: see above and `held_contacts`.)
    for (c, w) in sliding {
        let Some(j) = skeleton.joint_index(&c.joint) else {
            continue;
        };
        let own = frames.point(j, c.point).y;
        let floor = c.position.y - (1.0 - w) * (c.position.y - own).max(0.0);
        tasks.push(
            Task::point_on_plane(j, c.point, DVec3::new(0.0, floor, 0.0), DVec3::Y, true)
                .at_level(SLIDING_CONTACT_LEVEL),
        );
    }
    tasks.push(Task::position(0, DVec3::ZERO, frames.joint_position[0]).at_level(ROOT_LEVEL));
    for wrist in WRISTS {
        if let Some(j) = skeleton.joint_index(wrist) {
            let goal = frames.joint_position[j];
            tasks.push(Task::position(j, DVec3::ZERO, goal).at_level(WRIST_LEVEL));
        }
    }
    tasks.push(Task::posture(copy.values().to_vec(), dofs.to_vec()).at_level(POSTURE_LEVEL));
    tasks
}

/// Iterations of the guarded solve of the first frame (from the copy itself, however far its
/// contacts are held from it).
const FIRST_FRAME_ITERATIONS: usize = 100;

/// Iterations of the guarded solve of a frame whose short solve left its contacts unmet
/// (from there). On the FAIR jump's crouch and take-off (20 such frames) the contacts are
/// met within them; at 100 the levels below went on to use most of every retry (7.7
/// iterations a frame over the clip against 4.3; the corpus's drift within 0.05 mm of it);
/// at 25 a joint's jump next to a contact boundary on the CMU walk on legs 1.3 grows past
/// its bound (0.556 rad; 0.542 at 32).
const RETRY_ITERATIONS: usize = 32;

/// The firm contacts' residual (m) over which a frame is solved on (guarded), then again
/// from the copy.
const RETRY_RESIDUAL: f64 = 1e-3;

/// A frame's residual at `level` (its residuals are per level of [`LEVELS`]).
fn at_level(residual: &[f64], level: u32) -> Option<f64> {
    let k = LEVELS.iter().position(|&l| l == level)?;
    residual.get(k).copied()
}

/// Whether a frame's residuals leave its firm or sliding contacts unmet.
fn unmet(residual: &[f64]) -> bool {
    [CONTACT_LEVEL, SLIDING_CONTACT_LEVEL]
        .into_iter()
        .any(|level| at_level(residual, level).is_some_and(|r| r > RETRY_RESIDUAL))
}

/// Whether residuals `a` are better than `b`: the firm contacts closer, or, both met, the
/// sliding ones.
fn better(a: &[f64], b: &[f64]) -> bool {
    let (firm_a, firm_b) = (at_level(a, CONTACT_LEVEL), at_level(b, CONTACT_LEVEL));
    let met = |r: Option<f64>| r.is_some_and(|r| r <= RETRY_RESIDUAL);
    if met(firm_a) && met(firm_b) {
        at_level(a, SLIDING_CONTACT_LEVEL) < at_level(b, SLIDING_CONTACT_LEVEL)
    } else {
        firm_a < firm_b
    }
}

/// Solves the frames one by one, each from the previous frame's correction of the copy.
#[derive(Debug)]
struct FrameSolver {
    /// The short solve of each frame.
    solver: Solver,
    /// The first frame's.
    guarded: Solver,
    /// The frames' whose short solve leaves their contacts unmet.
    retry: Solver,
    dofs: Vec<usize>,
    correction: Vec<f64>,
    ease: usize,
    /// The next frame to solve.
    next: usize,
}

impl FrameSolver {
    fn new(
        target: &HumanoidSkeleton,
        ease: usize,
        max_iterations: usize,
    ) -> Result<Self, MotionError> {
        let skeleton = &target.skeleton;
        let solver = Solver::new(SolverSettings {
            max_iterations,
            tolerance: 1e-5,
            iteration: Iteration::Textbook,
            // Frame by frame from the last frame's posture, the steps are short: the plain
            // recursion (the priority budget is measured on whole solves, and moves held
            // contacts' boundary jumps past their bound).
            priority_budget: f64::INFINITY,
            restarts: false,
            stall_window: 2,
            damping: CONSTANT_DAMPING,
            ..SolverSettings::default()
        })?;
        let guarded_settings = SolverSettings {
            max_iterations: max_iterations.max(FIRST_FRAME_ITERATIONS),
            tolerance: 1e-5,
            iteration: Iteration::Guarded,
            restarts: false,
            damping: CONSTANT_DAMPING,
            ..SolverSettings::default()
        };
        let retry = Solver::new(SolverSettings {
            max_iterations: max_iterations.max(RETRY_ITERATIONS),
            ..guarded_settings
        })?;
        let guarded = Solver::new(guarded_settings)?;
        Ok(Self {
            solver,
            guarded,
            retry,
            dofs: posture_dofs(skeleton),
            correction: vec![0.0; skeleton.dof_count()],
            ease,
            next: 0,
        })
    }

    /// Solves frame `f` (the one after the last solved) into `out`.
    fn solve_frame(
        &mut self,
        target: &HumanoidSkeleton,
        out: &mut Retargeted,
        f: usize,
    ) -> Result<(), MotionError> {
        let skeleton = &target.skeleton;
        let Some(copy) = out.copy.get(f) else {
            return Ok(());
        };
        let tasks = frame_tasks(target, copy, &out.contacts, (f, self.ease), &self.dofs);
        let start: Vec<f64> = copy
            .values()
            .iter()
            .zip(&self.correction)
            .map(|(c, d)| c + d)
            .collect();
        let levels = &out.levels;
        let residuals = |report: &stance_ik::SolveReport| -> Vec<f64> {
            levels
                .iter()
                .map(|l| {
                    report
                        .levels
                        .iter()
                        .find(|r| r.level == *l)
                        .map_or(0.0, |r| r.residual_after)
                })
                .collect()
        };
        let mut posture = Posture::from_values(skeleton, start)?;
        // The first frame starts from the copy itself, however far its contacts are held
        // from it: it gets the iterations to get there.
        let report = if f == 0 {
            self.guarded.solve(skeleton, &tasks, &mut posture)?
        } else {
            self.solver.solve(skeleton, &tasks, &mut posture)?
        };
        out.iterations += report.iterations;
        let mut residual = residuals(&report);
        // The frame's short solve (textbook steps, stopped after two iterations without
        // gain) stalls where the goals move fast (a jump's crouch and take-off: held points
        // 15 to 54 mm off on the FAIR jump); a correction carried from earlier frames can lead
        // it astray (a held foot against a joint's range). When the contacts are not met,
        // the guarded iteration goes on from there, then the frame is solved again from the
        // copy itself; the best is kept. (Solving from the copy with the guarded iteration
        // holds as well but takes another branch: joint jumps over 0.55 rad at contact
        // boundaries on the CMU walk.)
        if unmet(&residual) {
            let mut more = posture.clone();
            let report = self.retry.solve(skeleton, &tasks, &mut more)?;
            out.iterations += report.iterations;
            let second = residuals(&report);
            if better(&second, &residual) {
                posture = more;
                residual = second;
            }
        }
        if unmet(&residual) {
            let mut again = copy.clone();
            let report = self.solver.solve(skeleton, &tasks, &mut again)?;
            out.iterations += report.iterations;
            let second = residuals(&report);
            if better(&second, &residual) {
                posture = again;
                residual = second;
            }
        }
        for ((d, p), c) in self
            .correction
            .iter_mut()
            .zip(posture.values())
            .zip(copy.values())
        {
            *d = p - c;
        }
        out.residuals.push(residual);
        out.postures.push(posture);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use stance_hanim::{SkeletonOptions, default_skeleton};

    use super::*;

    fn contact(part: ContactPart, start: usize, end: usize) -> Contact {
        Contact {
            joint: "l_talocrural".into(),
            part,
            point: DVec3::ZERO,
            start,
            end,
            position: DVec3::ZERO,
            floor: 0.0,
            clearance: 0.0,
            slides: false,
        }
    }

    /// The level each of the foot's held points gets at `frame`.
    fn levels_at(contacts: &[Contact], frame: usize) -> Vec<(ContactPart, u32)> {
        let Ok(body) = default_skeleton(&SkeletonOptions::default()) else {
            panic!("the default body");
        };
        let copy = Posture::rest(&body.skeleton);
        let dofs = posture_dofs(&body.skeleton);
        let tasks = frame_tasks(&body, &copy, contacts, (frame, 4), &dofs);
        let mut levels: Vec<(ContactPart, u32)> = tasks
            .iter()
            .filter(|t| t.level <= YIELDING_CONTACT_LEVEL)
            .filter_map(|t| match &t.kind {
                stance_ik::TaskKind::Position { effector, .. } => contacts
                    .iter()
                    .find(|c| c.point == effector.point)
                    .map(|c| (c.part, t.level)),
                _ => None,
            })
            .collect();
        levels.sort_by_key(|l| l.1);
        levels
    }

    #[test]
    fn of_a_foot_held_at_heel_and_ball_the_point_that_lifts_first_or_eases_gives_way() {
        // The heel from frame 10 to 30, the ball from 20 to 50 (points told apart by their
        // offsets).
        let mut heel = contact(ContactPart::Heel, 10, 30);
        heel.point = DVec3::new(0.0, -0.08, -0.05);
        let mut ball = contact(ContactPart::Ball, 20, 50);
        ball.point = DVec3::new(0.0, -0.08, 0.15);
        let both = [heel, ball];
        // The heel alone: firm.
        assert_eq!(
            levels_at(&both, 12),
            vec![(ContactPart::Heel, CONTACT_LEVEL)]
        );
        // The ball easing in while the heel is held in full: the ball gives way.
        assert_eq!(
            levels_at(&both, 18),
            vec![
                (ContactPart::Heel, CONTACT_LEVEL),
                (ContactPart::Ball, YIELDING_CONTACT_LEVEL)
            ]
        );
        // Both in full: the heel, whose contact ends first, gives way.
        assert_eq!(
            levels_at(&both, 25),
            vec![
                (ContactPart::Ball, CONTACT_LEVEL),
                (ContactPart::Heel, YIELDING_CONTACT_LEVEL)
            ]
        );
        // The heel easing out: it gives way; then the ball alone is firm.
        assert_eq!(
            levels_at(&both, 32),
            vec![
                (ContactPart::Ball, CONTACT_LEVEL),
                (ContactPart::Heel, YIELDING_CONTACT_LEVEL)
            ]
        );
        assert_eq!(
            levels_at(&both, 40),
            vec![(ContactPart::Ball, CONTACT_LEVEL)]
        );
    }
}
