//! Problem families: generated prioritized IK problems that differ in structure (bodies,
//! levels, task counts and kinds, partial axes, active joint limits, spreads, starts), for
//! measuring the solver on problems it was not tuned on (`stance families`, `stance bench
//! --suite`, the convergence tests).
//!
//! Every problem is *feasible*: all its targets are read off one goal posture within the joint
//! limits, so every level can be met at once, and a solver that stops short of one has not
//! converged (it is not a conflict between levels). Each family says whether the solver's
//! settings were tuned on it ([`Family::tuned`]); the others are held out, and their figures
//! are reported apart.
//!
//! The pseudo-random numbers are xorshift (Marsaglia), whose sequence for a seed is fixed by
//! its definition: a family's problems for a seed are the same in every version.

use std::ops::RangeInclusive;

use glam::DVec3;
use rand::{RngExt, SeedableRng};
use rand_xorshift::XorShiftRng;
use stance_ik::{Axes, Effector, Frames, IkError, Posture, Skeleton, Task, TaskKind};

use crate::LevelOfArticulation;
use crate::anatomy::sole;
use crate::builder::{BuildError, SkeletonOptions, default_skeleton};
use crate::scenarios::{humanoid50, standing_posture};

/// The body of a family.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Body {
    /// The 50-DOF humanoid of the scenarios ([`humanoid50`]).
    Humanoid50,
    /// The H-Anim default body at LOA 1 (built by [`default_skeleton`]).
    Loa1,
    /// The H-Anim default body at LOA 2 (132 DOF).
    Loa2,
}

impl Body {
    /// The skeleton.
    pub fn skeleton(self) -> Result<Skeleton, BuildError> {
        let built = |loa| {
            default_skeleton(&SkeletonOptions {
                loa,
                ..SkeletonOptions::default()
            })
            .map(|h| h.skeleton)
        };
        match self {
            Body::Humanoid50 => Ok(humanoid50()?),
            Body::Loa1 => built(LevelOfArticulation::Loa1),
            Body::Loa2 => built(LevelOfArticulation::Loa2),
        }
    }
}

/// The kinds of task a family draws from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kinds {
    /// Positions on every axis.
    Positions,
    /// Positions, half of them on some axes only (`y`, `xz`, ...).
    PartialPositions,
    /// Positions (some partial), orientations, directions, one gaze, centres of mass.
    Mixed,
    /// Standing: both ankles held where they stand (level 1), balance over the soles of both
    /// feet (level 2, [`STANDING_MARGIN`] inside), then mixed kinds on the levels below; the
    /// goal posture is drawn again until its centre of mass stands over its soles.
    Standing,
    /// Aiming: mostly orientations and segment directions, gazes (the head's, and a hand
    /// pointing along its fingers), a few positions.
    Aiming,
    /// Centres of mass (on every axis, the floor plane, or one axis) among positions, most of
    /// them on some axes only.
    CentreOfMass,
}

/// The balance margin of the standing families (m).
pub const STANDING_MARGIN: f64 = 0.02;
/// How far inside the shrunk support polygon a standing family's goal posture keeps its
/// centre of mass (m): the goal is balanced, not on the edge.
const STANDING_SLACK: f64 = 0.01;
/// Goal postures drawn for a standing problem before its spread is halved.
const STANDING_DRAWS: usize = 50;

/// Where the solve starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Start {
    /// The relaxed standing posture.
    Rest,
    /// A random posture within the limits, this far from standing per DOF (rad).
    Random(f64),
}

/// A family of generated problems.
#[derive(Debug, Clone, PartialEq)]
pub struct Family {
    /// Short name (file names: `NAME-0000.json`).
    pub name: &'static str,
    /// What it is, in a line.
    pub description: &'static str,
    /// Whether the solver's settings were tuned on it (false: held out).
    pub tuned: bool,
    /// The body.
    pub body: Body,
    /// Number of priority levels.
    pub levels: RangeInclusive<u32>,
    /// Number of tasks (at least one per level).
    pub tasks: RangeInclusive<usize>,
    /// Task kinds.
    pub kinds: Kinds,
    /// Spread of the goal posture about standing, per rotation DOF (rad; drawn per problem).
    pub spread: (f64, f64),
    /// Goal postures drawn this far beyond the limits and clamped back onto them (rad; 0:
    /// within the limits), so that some joints sit on their limits at the solution.
    pub beyond_limits: f64,
    /// Where the solve starts.
    pub start: Start,
    /// Mixed into the seed (0 for the first eight families): a family added later draws
    /// from a seed of its own, not from the sequence the others were measured on.
    pub salt: u64,
}

/// One generated problem.
#[derive(Debug, Clone, PartialEq)]
pub struct FamilyProblem {
    /// `NAME-0000`.
    pub name: String,
    /// Its tasks (levels 1..).
    pub tasks: Vec<Task>,
    /// The start posture.
    pub start: Posture,
    /// The goal posture the targets were read off (one solution).
    pub goal: Posture,
}

/// The families, the tuned ones first. `loa2`, `limits`, `stand` and `wide` were held out
/// until the restarts of issue 29 were chosen looking at their figures, `com` until its
/// `com-0031` set their order, `poise` and `far` until their `poise-0033` and `far-0016` chose
/// the falling damping of whole solves; `aim`, `lean` and `point` (each with a seed of its own)
/// are held out now.
pub fn families() -> Vec<Family> {
    vec![
        Family {
            name: "reach",
            description: "50 DOF, 4 levels, 7 positions, spread 0.2-0.45, start at rest",
            tuned: true,
            body: Body::Humanoid50,
            levels: 4..=4,
            tasks: 7..=7,
            kinds: Kinds::Positions,
            spread: (0.2, 0.45),
            beyond_limits: 0.0,
            start: Start::Rest,
            salt: 0,
        },
        Family {
            name: "partial",
            description: "50 DOF, 5 levels, 12 positions (half on some axes), spread 0.3-0.6",
            tuned: true,
            body: Body::Humanoid50,
            levels: 5..=5,
            tasks: 12..=12,
            kinds: Kinds::PartialPositions,
            spread: (0.3, 0.6),
            beyond_limits: 0.0,
            start: Start::Rest,
            salt: 0,
        },
        Family {
            name: "mixed",
            description: "50 DOF, 2-6 levels, 5-12 mixed kinds, spread 0.1-0.5, random start",
            tuned: true,
            body: Body::Humanoid50,
            levels: 2..=6,
            tasks: 5..=12,
            kinds: Kinds::Mixed,
            spread: (0.1, 0.5),
            beyond_limits: 0.0,
            start: Start::Random(0.3),
            salt: 0,
        },
        Family {
            name: "loa1",
            description: "LOA 1 body, 3 levels, 6-10 mixed kinds, spread 0.2-0.5, at rest",
            tuned: true,
            body: Body::Loa1,
            levels: 3..=3,
            tasks: 6..=10,
            kinds: Kinds::Mixed,
            spread: (0.2, 0.5),
            beyond_limits: 0.0,
            start: Start::Rest,
            salt: 0,
        },
        Family {
            name: "loa2",
            description: "LOA 2 body (132 DOF), 2-6 levels, 8-25 mixed kinds, spread 0.1-0.4",
            tuned: true,
            body: Body::Loa2,
            levels: 2..=6,
            tasks: 8..=25,
            kinds: Kinds::Mixed,
            spread: (0.1, 0.4),
            beyond_limits: 0.0,
            start: Start::Random(0.2),
            salt: 0,
        },
        Family {
            name: "limits",
            description: "50 DOF, 3-4 levels, 6-12 mixed kinds, goals on the joint limits",
            tuned: true,
            body: Body::Humanoid50,
            levels: 3..=4,
            tasks: 6..=12,
            kinds: Kinds::Mixed,
            spread: (0.3, 0.6),
            beyond_limits: 0.6,
            start: Start::Rest,
            salt: 0,
        },
        Family {
            name: "stand",
            description: "50 DOF, 3-5 levels, feet held, balance over their soles, 8-16 tasks",
            tuned: true,
            body: Body::Humanoid50,
            levels: 3..=5,
            tasks: 8..=16,
            kinds: Kinds::Standing,
            spread: (0.3, 0.5),
            beyond_limits: 0.0,
            start: Start::Random(0.2),
            salt: 0,
        },
        Family {
            name: "wide",
            description: "50 DOF, 6 levels, 15-25 partial positions, spread 0.5-0.7",
            tuned: true,
            body: Body::Humanoid50,
            levels: 6..=6,
            tasks: 15..=25,
            kinds: Kinds::PartialPositions,
            spread: (0.5, 0.7),
            beyond_limits: 0.0,
            start: Start::Random(0.3),
            salt: 0,
        },
        Family {
            name: "aim",
            description: "LOA 2 body, 3-6 levels, 8-16 orientations, directions, gazes, on limits",
            tuned: false,
            body: Body::Loa2,
            levels: 3..=6,
            tasks: 8..=16,
            kinds: Kinds::Aiming,
            spread: (0.2, 0.5),
            beyond_limits: 0.4,
            start: Start::Random(0.2),
            salt: AIM_SALT,
        },
        Family {
            name: "com",
            description: "50 DOF, 4-6 levels, 10-20 centres of mass and partial positions, 0.5-0.7",
            tuned: true,
            body: Body::Humanoid50,
            levels: 4..=6,
            tasks: 10..=20,
            kinds: Kinds::CentreOfMass,
            spread: (0.5, 0.7),
            beyond_limits: 0.0,
            start: Start::Random(0.4),
            salt: COM_SALT,
        },
        Family {
            name: "poise",
            description: "LOA 2 body, 3-6 levels, feet held, balance, 10-20 tasks, random start",
            tuned: true,
            body: Body::Loa2,
            levels: 3..=6,
            tasks: 10..=20,
            kinds: Kinds::Standing,
            spread: (0.2, 0.45),
            beyond_limits: 0.0,
            start: Start::Random(0.25),
            salt: POISE_SALT,
        },
        Family {
            name: "far",
            description: "LOA 1 body, 2-5 levels, 5-12 mixed kinds, 0.4-0.7, on limits, far start",
            tuned: true,
            body: Body::Loa1,
            levels: 2..=5,
            tasks: 5..=12,
            kinds: Kinds::Mixed,
            spread: (0.4, 0.7),
            beyond_limits: 0.3,
            start: Start::Random(0.5),
            salt: FAR_SALT,
        },
        Family {
            name: "lean",
            description: "LOA 1 body, 3-5 levels, feet held, balance, 8-14 tasks, on limits",
            tuned: false,
            body: Body::Loa1,
            levels: 3..=5,
            tasks: 8..=14,
            kinds: Kinds::Standing,
            spread: (0.3, 0.6),
            beyond_limits: 0.2,
            start: Start::Random(0.3),
            salt: LEAN_SALT,
        },
        Family {
            name: "point",
            description: "50 DOF, 2-4 levels, 5-10 aims (orientations, directions, gazes), at rest",
            tuned: false,
            body: Body::Humanoid50,
            levels: 2..=4,
            tasks: 5..=10,
            kinds: Kinds::Aiming,
            spread: (0.2, 0.6),
            beyond_limits: 0.0,
            start: Start::Rest,
            salt: POINT_SALT,
        },
    ]
}

/// The seed salt of the `aim` family (added with issue 29, never tuned on).
const AIM_SALT: u64 = 0x2901;
/// The seed salt of the `com` family (added with issue 29 held out; tuned on since its
/// `com-0031` set the order of the restarts).
const COM_SALT: u64 = 0x2902;
/// The seed salt of the `poise` family (added with issue 29 after the restarts were chosen;
/// tuned on since its `poise-0033` chose the falling damping of whole solves).
const POISE_SALT: u64 = 0x2903;
/// The seed salt of the `far` family (added with issue 29 after the restarts were chosen;
/// tuned on since the falling damping of whole solves, looking at its `far-0016`).
const FAR_SALT: u64 = 0x2904;
/// The seed salt of the `lean` family (added with issue 29 after whole solves took the falling
/// damping, never tuned on).
const LEAN_SALT: u64 = 0x2905;
/// The seed salt of the `point` family (added with `lean`, never tuned on).
const POINT_SALT: u64 = 0x2906;

/// The family of this name.
pub fn family(name: &str) -> Option<Family> {
    families().into_iter().find(|f| f.name == name)
}

/// End joints and points on them (joint frame, m) that position tasks hold, by H-Anim name;
/// a body without one of them leaves it out.
const EFFECTORS: &[(&str, [f64; 3])] = &[
    ("l_radiocarpal", [0.0, -0.08, 0.0]),
    ("r_radiocarpal", [0.0, -0.08, 0.0]),
    ("l_talocrural", [0.0, -0.05, 0.0]),
    ("r_talocrural", [0.0, -0.05, 0.0]),
    ("l_metatarsophalangeal_2", [0.0, 0.0, 0.04]),
    ("r_metatarsophalangeal_2", [0.0, 0.0, 0.04]),
    ("skullbase", [0.0, 0.1, 0.05]),
    ("l_elbow", [0.0, 0.0, 0.0]),
    ("r_elbow", [0.0, 0.0, 0.0]),
    ("l_knee", [0.0, 0.0, 0.0]),
    ("r_knee", [0.0, 0.0, 0.0]),
    ("sacroiliac", [0.0, 0.0, 0.05]),
    ("vt1", [0.0, 0.0, 0.08]),
    ("l_carpal_distal_interphalangeal_3", [0.0, -0.01, 0.0]),
    ("r_carpal_distal_interphalangeal_2", [0.0, -0.01, 0.0]),
];
/// Joints whose orientation or a segment direction a task may hold.
const ORIENTED: &[&str] = &[
    "l_radiocarpal",
    "r_radiocarpal",
    "skullbase",
    "sacroiliac",
    "vt6",
    "l_talocrural",
    "r_elbow",
    "l_knee",
];
/// Partial axes of position tasks.
const PARTIAL: &[&str] = &["y", "xz", "x", "z", "xy", "yz"];
/// Axes of the centre-of-mass tasks of [`Kinds::CentreOfMass`].
const COM_AXES: &[&str] = &["xz", "xyz", "x", "z", "y"];
/// Joints that aim in [`Kinds::Aiming`]: the eye point in the joint's frame and the axis it
/// looks or points along (the head's eyes forward, a hand along its fingers).
const AIMERS: &[(&str, [f64; 3], [f64; 3])] = &[
    ("skullbase", [0.0, 0.08, 0.08], [0.0, 0.0, 1.0]),
    ("l_radiocarpal", [0.0, -0.08, 0.0], [0.0, -1.0, 0.0]),
    ("r_radiocarpal", [0.0, -0.08, 0.0], [0.0, -1.0, 0.0]),
];

impl Family {
    /// `count` problems from `seed` (the same ones for the same seed, in every version).
    pub fn problems(&self, seed: u64, count: usize) -> Result<Vec<FamilyProblem>, BuildError> {
        let skeleton = self.body.skeleton()?;
        (0..count)
            .map(|i| self.problem(&skeleton, seed, i).map_err(BuildError::from))
            .collect()
    }

    /// Problem `index` of `seed`.
    pub fn problem(
        &self,
        skeleton: &Skeleton,
        seed: u64,
        index: usize,
    ) -> Result<FamilyProblem, IkError> {
        let mut r = XorShiftRng::seed_from_u64(
            (seed ^ self.salt).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (index as u64).wrapping_add(1),
        );
        let spread = r.random_range(self.spread.0..=self.spread.1);
        let standing = self.kinds == Kinds::Standing;
        let (goal, mut tasks) = if standing {
            standing_goal(&mut r, skeleton, spread)?
        } else {
            let goal = random_posture(&mut r, skeleton, spread, self.beyond_limits);
            (goal, Vec::new())
        };
        let levels = r.random_range(self.levels.clone());
        let count = r.random_range(self.tasks.clone()).max(levels as usize);
        let frames = Frames::new(skeleton, &goal);
        let mut used_gaze = false;
        // A standing problem's feet and balance take levels 1 and 2.
        let first_free = if standing { 3 } else { 1 };
        let preset = tasks.len();
        for i in preset..count {
            // Every level gets one task, the rest fall on random levels.
            let next = first_free + (i - preset) as u32;
            let level = if next <= levels {
                next
            } else {
                r.random_range(first_free.min(levels)..=levels)
            };
            tasks.push(
                self.task(&mut r, skeleton, &frames, &mut used_gaze)?
                    .at_level(level),
            );
        }
        tasks.sort_by_key(|t| t.level);
        let start = match self.start {
            Start::Rest => standing_posture(skeleton),
            Start::Random(amplitude) => random_posture(&mut r, skeleton, amplitude, 0.0),
        };
        Ok(FamilyProblem {
            name: format!("{}-{index:04}", self.name),
            tasks,
            start,
            goal,
        })
    }

    fn task(
        &self,
        r: &mut XorShiftRng,
        skeleton: &Skeleton,
        frames: &Frames,
        used_gaze: &mut bool,
    ) -> Result<Task, IkError> {
        let effectors: Vec<(usize, DVec3)> = EFFECTORS
            .iter()
            .filter_map(|(name, p)| {
                skeleton
                    .joint_index(name)
                    .map(|j| (j, DVec3::from_array(*p)))
            })
            .collect();
        let oriented: Vec<usize> = ORIENTED
            .iter()
            .filter_map(|name| skeleton.joint_index(name))
            .filter(|&j| skeleton.joints()[j].has_rotation())
            .collect();
        let Some(&(first, _)) = effectors.first() else {
            return Err(IkError::BadTask {
                index: 0,
                reason: "the body has none of the families' end joints".to_owned(),
            });
        };
        let position = |r: &mut XorShiftRng, partial: bool| {
            let (j, point) = effectors[r.random_range(0..effectors.len())];
            let task = Task::position(j, point, frames.point(j, point));
            if partial {
                let axes = PARTIAL[r.random_range(0..PARTIAL.len())];
                task.with_axes(Axes::parse(axes).unwrap_or(Axes::XYZ))
            } else {
                task
            }
        };
        Ok(match self.kinds {
            Kinds::Positions => position(r, false),
            Kinds::PartialPositions => {
                let partial = r.random_bool(0.5);
                position(r, partial)
            }
            Kinds::Mixed | Kinds::Standing => match r.random_range(0..10) {
                0..=4 => {
                    let partial = r.random_bool(0.3);
                    position(r, partial)
                }
                5 | 6 if !oriented.is_empty() => {
                    let j = oriented[r.random_range(0..oriented.len())];
                    Task::orientation(j, frames.rotation(j))
                }
                7 if !oriented.is_empty() => {
                    let j = oriented[r.random_range(0..oriented.len())];
                    let axis = unit(r);
                    Task::direction(j, axis, frames.world_from_joint_rotation[j] * axis)
                }
                8 if !*used_gaze && skeleton.joint_index("skullbase").is_some() => {
                    *used_gaze = true;
                    let j = skeleton.require_joint("skullbase")?;
                    let eye = DVec3::new(0.0, 0.08, 0.08);
                    let forward = frames.world_from_joint_rotation[j] * DVec3::Z;
                    let target = frames.point(j, eye) + forward * r.random_range(0.5..3.0);
                    let mut task = Task::gaze(j, DVec3::Z, target);
                    if let TaskKind::Gaze { effector, .. } = &mut task.kind {
                        effector.point = eye;
                    }
                    task
                }
                9 => Task::center_of_mass(Axes::XZ, frames.center_of_mass()),
                _ => {
                    let point = DVec3::ZERO;
                    Task::position(first, point, frames.point(first, point))
                }
            },
            Kinds::Aiming => match r.random_range(0..10) {
                0..=2 if !oriented.is_empty() => {
                    let j = oriented[r.random_range(0..oriented.len())];
                    Task::orientation(j, frames.rotation(j))
                }
                3..=5 if !oriented.is_empty() => {
                    let j = oriented[r.random_range(0..oriented.len())];
                    let axis = unit(r);
                    Task::direction(j, axis, frames.world_from_joint_rotation[j] * axis)
                }
                6..=8 => {
                    // A gaze: the head's eyes, or a hand pointing along its fingers, at a
                    // point ahead of it in the goal posture.
                    let pointers: Vec<(usize, DVec3, DVec3)> = AIMERS
                        .iter()
                        .filter_map(|(name, eye, axis)| {
                            skeleton
                                .joint_index(name)
                                .map(|j| (j, DVec3::from_array(*eye), DVec3::from_array(*axis)))
                        })
                        .collect();
                    if pointers.is_empty() {
                        position(r, false)
                    } else {
                        let (j, eye, axis) = pointers[r.random_range(0..pointers.len())];
                        let forward = frames.world_from_joint_rotation[j] * axis;
                        let target = frames.point(j, eye) + forward * r.random_range(0.5..3.0);
                        let mut task = Task::gaze(j, axis, target);
                        if let TaskKind::Gaze { effector, .. } = &mut task.kind {
                            effector.point = eye;
                        }
                        task
                    }
                }
                _ => {
                    let partial = r.random_bool(0.3);
                    position(r, partial)
                }
            },
            Kinds::CentreOfMass => match r.random_range(0..10) {
                0..=2 => {
                    let axes = COM_AXES[r.random_range(0..COM_AXES.len())];
                    Task::center_of_mass(
                        Axes::parse(axes).unwrap_or(Axes::XZ),
                        frames.center_of_mass(),
                    )
                }
                _ => {
                    let partial = r.random_bool(0.7);
                    position(r, partial)
                }
            },
        })
    }
}

/// A standing problem's goal posture (drawn until its centre of mass stands over the soles of
/// its feet, [`STANDING_SLACK`] inside the balance margin; the spread halved after
/// [`STANDING_DRAWS`] draws) and its first tasks: both ankles held where they are (level 1),
/// balance over both soles (level 2).
fn standing_goal(
    r: &mut XorShiftRng,
    skeleton: &Skeleton,
    spread: f64,
) -> Result<(Posture, Vec<Task>), IkError> {
    let ankles = [
        skeleton.require_joint("l_talocrural")?,
        skeleton.require_joint("r_talocrural")?,
    ];
    let support: Vec<Effector> = ankles
        .iter()
        .flat_map(|&ankle| {
            sole(skeleton, ankle).map(|point| Effector {
                joint: ankle,
                point,
            })
        })
        .collect();
    let stricter = Task::balance(support.clone(), STANDING_MARGIN + STANDING_SLACK);
    let mut amplitude = spread;
    let mut draws = 0;
    let goal = loop {
        let goal = random_posture(r, skeleton, amplitude, 0.0);
        let frames = Frames::new(skeleton, &goal);
        if stricter.residual(skeleton, &frames, goal.values()) == 0.0 {
            break goal;
        }
        draws += 1;
        if draws % STANDING_DRAWS == 0 {
            amplitude *= 0.5;
        }
        if draws > 8 * STANDING_DRAWS {
            return Err(IkError::BadTask {
                index: 2,
                reason: "no balanced goal posture: the body does not stand over its feet"
                    .to_owned(),
            });
        }
    };
    let frames = Frames::new(skeleton, &goal);
    let mut tasks: Vec<Task> = ankles
        .iter()
        .map(|&ankle| Task::position(ankle, DVec3::ZERO, frames.joint_position[ankle]))
        .collect();
    tasks.push(Task::balance(support, STANDING_MARGIN).at_level(2));
    Ok((goal, tasks))
}

/// A random unit vector.
fn unit(r: &mut XorShiftRng) -> DVec3 {
    loop {
        let v = DVec3::new(
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
        );
        let length = v.length();
        if (0.1..=1.0).contains(&length) {
            return v / length;
        }
    }
}

/// Standing plus a uniform offset in `[-a, a]` per rotation DOF (`0.2 a` m per translation),
/// `a = amplitude + beyond` and then clamped into the limits.
fn random_posture(
    r: &mut XorShiftRng,
    skeleton: &Skeleton,
    amplitude: f64,
    beyond: f64,
) -> Posture {
    let mut posture = standing_posture(skeleton);
    let (lower, upper) = (skeleton.lower_limits(), skeleton.upper_limits());
    let kinds = skeleton.dof_kinds();
    let a = amplitude + beyond;
    for (d, value) in posture.values_mut().iter_mut().enumerate() {
        let scale = if kinds[d].is_rotation() { a } else { 0.2 * a };
        *value = (*value + r.random_range(-scale..=scale)).clamp(lower[d], upper[d]);
    }
    posture
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    /// Every family's problems are feasible (the goal posture meets every task, within the
    /// limits), have a task on every level, and are the same for the same seed.
    #[test]
    fn problems_are_feasible_and_reproducible() {
        for family in families() {
            let skeleton = family.body.skeleton().unwrap();
            for index in 0..5 {
                let p = family.problem(&skeleton, 3, index).unwrap();
                assert_eq!(p, family.problem(&skeleton, 3, index).unwrap());
                let frames = Frames::new(&skeleton, &p.goal);
                for task in &p.tasks {
                    let r = task.residual(&skeleton, &frames, p.goal.values());
                    assert!(r < 1e-9, "{}: {task:?} residual {r} at the goal", p.name);
                }
                let (lower, upper) = (skeleton.lower_limits(), skeleton.upper_limits());
                for (d, v) in p.goal.values().iter().enumerate() {
                    assert!(lower[d] <= *v && *v <= upper[d], "{}: DOF {d}", p.name);
                }
                let levels: Vec<u32> = p.tasks.iter().map(|t| t.level).collect();
                let top = *levels.iter().max().unwrap();
                assert!((1..=top).all(|l| levels.contains(&l)), "{}", p.name);
                assert!(family.levels.contains(&top) && family.tasks.contains(&p.tasks.len()));
            }
            assert_ne!(
                family.problem(&skeleton, 3, 0).unwrap(),
                family.problem(&skeleton, 4, 0).unwrap(),
                "another seed, other problems"
            );
        }
    }
}
