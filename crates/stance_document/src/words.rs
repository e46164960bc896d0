//! The document's words for people and its mirror image: a task described as the panels
//! name it, a task or posture mirrored left/right (H-Anim sides swap, the sagittal plane
//! reflects), and the tasks every editor makes (a pin, the comfort).

use stance_hanim::capsules::COLLISION_MARGIN;
use stance_hanim::{mirror_name, readable_name};
use stance_ik::{Axes, Frames, Skeleton};

use crate::{DEFAULT_BALANCE_MARGIN, DEFAULT_COMFORT, PostureValues, TaskKindSpec, TaskSpec};

/// The level of the body's collision task the editor adds: just below the pins (level 1),
/// beside balance.
pub const COLLISION_LEVEL: u32 = 2;

/// A point or direction reflected in the sagittal plane (x -> -x).
fn reflect(v: [f64; 3]) -> [f64; 3] {
    // `0.0 - x` keeps a zero positive (no "-0" in the saved document).
    [0.0 - v[0], v[1], v[2]]
}

/// A rotation `[qx, qy, qz, qw]` reflected in the sagittal plane (`M R M`, M = diag(-1, 1, 1)).
fn reflect_rotation(q: [f64; 4]) -> [f64; 4] {
    [q[0], 0.0 - q[1], 0.0 - q[2], q[3]]
}

/// Every name of `joints` on the other side.
fn mirror_names(joints: &[String]) -> Vec<String> {
    joints.iter().map(|joint| mirror_name(joint)).collect()
}

impl TaskSpec {
    /// A level-1 position task holding `joint` at `position`.
    pub fn pin(joint: &str, position: [f64; 3]) -> TaskSpec {
        TaskSpec::new(TaskKindSpec::Position {
            joint: joint.to_owned(),
            point: [0.0; 3],
            axes: Axes::new(true, true, true),
            target: position,
        })
    }

    /// Balance at level 2: the centre of mass over the support polygon of the parts pinned
    /// on the floor, `DEFAULT_BALANCE_MARGIN` inside its edges.
    pub fn balance() -> TaskSpec {
        let mut balance = TaskSpec::new(TaskKindSpec::Balance {
            support: None,
            margin: DEFAULT_BALANCE_MARGIN,
        });
        balance.level = 2;
        balance
    }

    /// The body's collision task just below the pins (level [`COLLISION_LEVEL`]): its
    /// capsules kept [`COLLISION_MARGIN`] apart from each other and above the floor.
    pub fn collision() -> TaskSpec {
        let mut collision = TaskSpec::new(TaskKindSpec::Collision {
            margin: COLLISION_MARGIN,
            self_collision: true,
            floor: true,
        });
        collision.level = COLLISION_LEVEL;
        collision
    }

    /// The tasks a new body starts with: feet on the floor before balance, balance before
    /// comfort. Each ankle (`l_talocrural`, `r_talocrural`) the skeleton has is pinned where
    /// `frames` put it; balance is the support polygon of the pinned feet (an inequality: the
    /// body leans freely while its centre of mass stays over them); comfort settles the rest.
    /// The editor's new session and the `stance-ik` package's `defaultTasks` alike. (The
    /// body's collision task, [`TaskSpec::collision`], is not among them yet: its rows in the
    /// margin's band hold the surfaces from parting as well as from meeting, so that with it
    /// on a pulled hand can stall against the body; the editor's toggle adds it.)
    pub fn defaults(skeleton: &Skeleton, frames: &Frames) -> Vec<TaskSpec> {
        let mut tasks: Vec<TaskSpec> = ["l_talocrural", "r_talocrural"]
            .into_iter()
            .filter_map(|foot| {
                let position = frames.joint_position.get(skeleton.joint_index(foot)?)?;
                Some(TaskSpec::pin(foot, position.to_array()))
            })
            .collect();
        tasks.push(TaskSpec::balance());
        tasks.push(TaskSpec::comfort());
        tasks
    }

    /// A light attraction of every joint toward the rest posture, at level 10.
    pub fn rest_attraction() -> TaskSpec {
        let mut rest = TaskSpec::new(TaskKindSpec::Posture {
            joints: None,
            reference: None,
        });
        rest.level = 10;
        rest.weight = 0.05;
        rest
    }

    /// Comfort (effort against gravity, joint ranges, RULA's stand-in) at level 10, the
    /// lowest: it takes whatever freedom every other task leaves.
    pub fn comfort() -> TaskSpec {
        let (effort, range, rula) = DEFAULT_COMFORT;
        let mut comfort = TaskSpec::new(TaskKindSpec::Comfort {
            effort,
            range,
            rula,
        });
        comfort.level = 10;
        comfort
    }

    /// The task moved rigidly by `m` (a turn and a translation of the frame its goals are in):
    /// goal points, line origins and plane points moved, directions, normals and orientations
    /// turned; a task attached to a prop follows it with this (`on`). Local points, balance,
    /// posture, comfort and collision stay.
    pub fn moved(&self, m: glam::DAffine3) -> TaskSpec {
        let point = |p: [f64; 3]| m.transform_point3(glam::DVec3::from_array(p)).to_array();
        let vector = |v: [f64; 3]| m.transform_vector3(glam::DVec3::from_array(v)).to_array();
        let turn = glam::DQuat::from_mat3(&m.matrix3);
        let rotation = |q: [f64; 4]| (turn * glam::DQuat::from_array(q)).to_array();
        let mut moved = self.clone();
        match &mut moved.kind {
            TaskKindSpec::Position { target, .. }
            | TaskKindSpec::Gaze { target, .. }
            | TaskKindSpec::Com { target, .. } => *target = point(*target),
            TaskKindSpec::Orientation { target, .. } => *target = rotation(*target),
            TaskKindSpec::Direction { target, .. } => *target = vector(*target),
            TaskKindSpec::Limb {
                target,
                orientation,
                ..
            } => {
                *target = point(*target);
                *orientation = orientation.map(rotation);
            }
            TaskKindSpec::Line {
                origin, direction, ..
            } => {
                *origin = point(*origin);
                *direction = vector(*direction);
            }
            TaskKindSpec::Plane { origin, normal, .. } => {
                *origin = point(*origin);
                *normal = vector(*normal);
            }
            TaskKindSpec::Balance { .. }
            | TaskKindSpec::Posture { .. }
            | TaskKindSpec::Comfort { .. }
            | TaskKindSpec::Collision { .. } => {}
        }
        moved
    }

    /// The task mirrored left/right: joints swap sides, goals and local points are reflected
    /// in the sagittal plane (x -> -x), orientations accordingly; level, weight and active flag
    /// stay.
    pub fn mirrored(&self) -> TaskSpec {
        let mut mirrored = self.clone();
        mirrored.kind = match &self.kind {
            TaskKindSpec::Position {
                joint,
                point,
                axes,
                target,
            } => TaskKindSpec::Position {
                joint: mirror_name(joint),
                point: reflect(*point),
                axes: *axes,
                target: reflect(*target),
            },
            TaskKindSpec::Orientation { joint, target } => TaskKindSpec::Orientation {
                joint: mirror_name(joint),
                target: reflect_rotation(*target),
            },
            TaskKindSpec::Gaze {
                joint,
                axis,
                point,
                target,
            } => TaskKindSpec::Gaze {
                joint: mirror_name(joint),
                axis: reflect(*axis),
                point: reflect(*point),
                target: reflect(*target),
            },
            TaskKindSpec::Direction {
                joint,
                axis,
                target,
            } => TaskKindSpec::Direction {
                joint: mirror_name(joint),
                axis: reflect(*axis),
                target: reflect(*target),
            },
            TaskKindSpec::Balance { support, margin } => TaskKindSpec::Balance {
                support: support.as_deref().map(mirror_names),
                margin: *margin,
            },
            TaskKindSpec::Com { axes, target } => TaskKindSpec::Com {
                axes: *axes,
                target: reflect(*target),
            },
            TaskKindSpec::Comfort { .. } | TaskKindSpec::Collision { .. } => self.kind.clone(),
            TaskKindSpec::Posture { joints, reference } => TaskKindSpec::Posture {
                joints: joints.as_deref().map(mirror_names),
                reference: reference.as_ref().map(PostureValues::mirrored),
            },
            TaskKindSpec::Limb {
                limb,
                joints,
                target,
                swivel,
                orientation,
            } => TaskKindSpec::Limb {
                limb: limb.map(|limb| limb.mirrored()),
                joints: joints
                    .as_ref()
                    .map(|joints| joints.clone().map(|joint| mirror_name(&joint))),
                target: reflect(*target),
                swivel: swivel.map(|angle| -angle),
                orientation: orientation.map(reflect_rotation),
            },
            TaskKindSpec::Line {
                joint,
                point,
                origin,
                direction,
            } => TaskKindSpec::Line {
                joint: mirror_name(joint),
                point: reflect(*point),
                origin: reflect(*origin),
                direction: reflect(*direction),
            },
            TaskKindSpec::Plane {
                joint,
                point,
                origin,
                normal,
                above,
            } => TaskKindSpec::Plane {
                joint: mirror_name(joint),
                point: reflect(*point),
                origin: reflect(*origin),
                normal: reflect(*normal),
                above: *above,
            },
        };
        mirrored
    }

    /// The task in words, as the panels and messages name it.
    pub fn description(&self) -> String {
        match &self.kind {
            TaskKindSpec::Position { joint, axes, .. } => {
                let axes = axes.to_letters();
                if axes == "xyz" {
                    format!("{} position", readable_name(joint))
                } else {
                    format!("{} position ({axes})", readable_name(joint))
                }
            }
            TaskKindSpec::Orientation { joint, .. } => {
                format!("{} orientation", readable_name(joint))
            }
            TaskKindSpec::Gaze { joint, .. } => format!("{} gaze", readable_name(joint)),
            TaskKindSpec::Direction { joint, .. } => format!("{} direction", readable_name(joint)),
            TaskKindSpec::Balance { support: None, .. } => {
                "balance (centre of mass over the pinned feet)".to_owned()
            }
            TaskKindSpec::Balance {
                support: Some(joints),
                ..
            } => format!(
                "balance (centre of mass over {})",
                joints
                    .iter()
                    .map(|joint| readable_name(joint))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            TaskKindSpec::Com { axes, .. } => {
                if axes.to_letters() == "xz" {
                    "balance (centre of mass over the floor)".to_owned()
                } else {
                    format!("centre of mass ({})", axes.to_letters())
                }
            }
            TaskKindSpec::Posture { .. } => "rest posture".to_owned(),
            TaskKindSpec::Comfort { .. } => "comfort (effort, ranges, RULA)".to_owned(),
            TaskKindSpec::Collision {
                margin,
                self_collision,
                floor,
            } => {
                let what = match (self_collision, floor) {
                    (true, true) => "body and floor",
                    (true, false) => "body",
                    (false, true) => "floor",
                    (false, false) => "nothing",
                };
                format!("collision: {what}, {:.0} mm apart", margin * 1e3)
            }
            TaskKindSpec::Limb { limb, joints, .. } => match (limb, joints) {
                (Some(limb), _) => format!("{} reach", limb.name().replace('_', " ")),
                (None, Some(joints)) => format!("{} limb", readable_name(&joints[2])),
                (None, None) => "limb".to_owned(),
            },
            TaskKindSpec::Line { joint, .. } => format!("{} on a line", readable_name(joint)),
            TaskKindSpec::Plane {
                joint, above: true, ..
            } => format!("{} on or above a plane", readable_name(joint)),
            TaskKindSpec::Plane { joint, .. } => format!("{} on a plane", readable_name(joint)),
        }
    }
}

impl PostureValues {
    /// The values mirrored left/right: joints swap sides; `tx`, `ry` and `rz` change sign
    /// (reflection in the sagittal plane).
    pub fn mirrored(&self) -> PostureValues {
        let mut mirrored = PostureValues::new();
        for (joint, dofs) in &self.joints {
            let name = mirror_name(joint);
            for (dof, value) in dofs.iter() {
                let sign = match dof.name() {
                    "tx" | "ry" | "rz" => -1.0,
                    _ => 1.0,
                };
                mirrored.set(&name, dof, sign * value);
            }
        }
        mirrored
    }
}

impl TaskKindSpec {
    /// A soft task is never met: it takes only what the levels above leave (the posture
    /// attraction, comfort). Grabs go above it, statuses do not say it gave way.
    pub fn is_soft(&self) -> bool {
        matches!(
            self,
            TaskKindSpec::Posture { .. } | TaskKindSpec::Comfort { .. }
        )
    }
}
