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
//! 4. **Tasks over time**: foot contacts (detected on the copy, [`crate::contacts`]) as
//!    level-1 position tasks eased in and out, the root's path at level 2, the wrists at
//!    level 3, and the copied frame as the reference of a posture task at level 4 (the
//!    original motion as the null-space attraction). Each frame starts from the previous
//!    solution: the previous frame's correction of the copy is carried onto this frame's
//!    copy.

mod copy;
mod report;

use glam::DVec3;
use stance_hanim::HumanoidSkeleton;
use stance_ik::{Frames, IkError, Iteration, Posture, Solver, SolverSettings, Task};

use crate::clip::{Clip, ClipError};
use crate::contacts::{Contact, ContactSettings, contact_weight, detect_contacts};
pub use copy::{Placement, RestMatch, RotationCopy};
pub use report::{
    ContactMetrics, Deviation, Metrics, Smoothness, contact_metrics, deviation, metrics, smoothness,
};

/// The H-Anim feet held by contacts.
pub const CONTACT_JOINTS: [&str; 2] = ["l_talocrural", "r_talocrural"];
/// The H-Anim wrists kept at level 3.
const WRISTS: [&str; 2] = ["l_radiocarpal", "r_radiocarpal"];

/// Levels of the retargeting problem.
pub const CONTACT_LEVEL: u32 = 1;
/// The root's path.
pub const ROOT_LEVEL: u32 = 2;
/// The wrists.
pub const WRIST_LEVEL: u32 = 3;
/// The copied frame as a posture reference.
pub const POSTURE_LEVEL: u32 = 4;

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

/// Retargets `clip` onto `target` (see the module documentation).
pub fn retarget(
    clip: &Clip,
    target: &HumanoidSkeleton,
    options: &RetargetOptions,
) -> Result<Retargeted, MotionError> {
    clip.validate()?;
    if clip.frames.is_empty() {
        return Err(MotionError::Empty);
    }
    let copier = RotationCopy::new(clip, target, options)?;
    let copy: Vec<Posture> = (0..clip.frame_count())
        .map(|f| copier.frame(clip, target, f))
        .collect::<Result<_, _>>()?;
    let contacts = match options.contacts {
        Some(settings) => held_contacts(clip, target, &copy, &copier.placement, &settings),
        None => Vec::new(),
    };
    let mut out = Retargeted {
        postures: Vec::with_capacity(copy.len()),
        copy,
        contacts,
        levels: vec![CONTACT_LEVEL, ROOT_LEVEL, WRIST_LEVEL, POSTURE_LEVEL],
        residuals: Vec::new(),
        iterations: 0,
        frame_time: clip.frame_time,
        placement: copier.placement,
        notes: copier.notes.clone(),
    };
    if options.contacts.is_none() {
        out.postures = out.copy.clone();
        out.residuals = vec![vec![0.0; out.levels.len()]; out.postures.len()];
        return Ok(out);
    }
    let ease = options
        .contacts
        .map_or(0, |s| s.ease_frames(clip.frame_time));
    solve_frames(target, &mut out, ease, options.max_iterations)?;
    Ok(out)
}

/// The contacts of the clip's own feet (detected on the clip, so that every target gets the
/// same ones: low and slow as the clip moves), each held where the copy puts that foot on
/// average over the contact, never below the target's ankle height.
fn held_contacts(
    clip: &Clip,
    target: &HumanoidSkeleton,
    copy: &[Posture],
    placement: &Placement,
    settings: &ContactSettings,
) -> Vec<Contact> {
    let skeleton = &target.skeleton;
    let feet: Vec<(&str, usize, usize)> = CONTACT_JOINTS
        .iter()
        .filter_map(|&foot| Some((foot, clip.joint_of(foot)?, skeleton.joint_index(foot)?)))
        .collect();
    // Both feet's tracks in one pass: on the clip (for the detection) and on the target's
    // copy (where each contact is held).
    let on_clip: Vec<Vec<DVec3>> = clip
        .frames
        .iter()
        .map(|f| {
            let world = clip.world(f);
            feet.iter()
                .map(|&(_, s, _)| world.get(s).map_or(DVec3::ZERO, |x| x.1))
                .collect()
        })
        .collect();
    let joints: Vec<usize> = feet.iter().map(|&(_, _, j)| j).collect();
    let on_target = joint_positions(target, copy, &joints);
    let mut contacts = Vec::new();
    for (i, &(foot, _, _)) in feet.iter().enumerate() {
        let track: Vec<DVec3> = on_clip.iter().map(|f| f[i]).collect();
        for mut c in detect_contacts(
            foot,
            &track,
            placement.lowest_ankle,
            clip.frame_time,
            settings,
        ) {
            let run = &on_target[c.start..=c.end.min(on_target.len() - 1)];
            let mean = run.iter().map(|p| p[i]).sum::<DVec3>() / run.len().max(1) as f64;
            c.position = DVec3::new(mean.x, mean.y.max(placement.ankle_height), mean.z);
            contacts.push(c);
        }
    }
    contacts
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
    for foot in CONTACT_JOINTS {
        let Some(j) = skeleton.joint_index(foot) else {
            continue;
        };
        let held = contacts
            .iter()
            .filter(|c| c.joint == foot)
            .map(|c| (contact_weight(c, frame, ease), c.position))
            .max_by(|a, b| a.0.total_cmp(&b.0));
        if let Some((w, at)) = held.filter(|(w, _)| *w > 0.0) {
            let goal = frames.joint_position[j].lerp(at, w);
            tasks.push(Task::position(j, DVec3::ZERO, goal).at_level(CONTACT_LEVEL));
        }
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

/// Solves every frame from the previous frame's correction of the copy.
fn solve_frames(
    target: &HumanoidSkeleton,
    out: &mut Retargeted,
    ease: usize,
    max_iterations: usize,
) -> Result<(), MotionError> {
    let skeleton = &target.skeleton;
    let mut solver = Solver::new(SolverSettings {
        max_iterations,
        tolerance: 1e-5,
        iteration: Iteration::Textbook,
        restarts: false,
        stall_window: 2,
        ..SolverSettings::default()
    })?;
    let dofs = posture_dofs(skeleton);
    let mut correction = vec![0.0; skeleton.dof_count()];
    for (f, copy) in out.copy.iter().enumerate() {
        let tasks = frame_tasks(target, copy, &out.contacts, (f, ease), &dofs);
        let start: Vec<f64> = copy
            .values()
            .iter()
            .zip(&correction)
            .map(|(c, d)| c + d)
            .collect();
        let mut posture = Posture::from_values(skeleton, start)?;
        let report = solver.solve(skeleton, &tasks, &mut posture)?;
        out.iterations += report.iterations;
        out.residuals.push(
            out.levels
                .iter()
                .map(|l| {
                    report
                        .levels
                        .iter()
                        .find(|r| r.level == *l)
                        .map_or(0.0, |r| r.residual_after)
                })
                .collect(),
        );
        for ((d, p), c) in correction
            .iter_mut()
            .zip(posture.values())
            .zip(copy.values())
        {
            *d = p - c;
        }
        out.postures.push(posture);
    }
    Ok(())
}
