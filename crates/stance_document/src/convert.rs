//! From document specs to solver types (`stance_ik::Task`, `stance_ik::Posture`) and back.

use std::sync::Arc;

use glam::{DQuat, DVec3};
use stance_hanim::HumanoidSkeleton;
use stance_hanim::capsules::{BodyCollision, COLLISION_ROWS};
use stance_hanim::comfort::{ComfortSettings, comfort_model};
use stance_hanim::strength::{aligned_axes, built_axes};
use stance_ik::{Axes, Effector, Limb, LimbGoal, Posture, Skeleton, Task, TaskKind};

use crate::DocumentError;
use crate::document::{
    CONTACT_HEIGHT, Document, DofValues, LimbName, PostureRest, PostureValues, TaskKindSpec,
    TaskSpec,
};

pub use stance_hanim::resolve_joint;

fn joint_at(skeleton: &Skeleton, name: &str, at: &str) -> Result<usize, DocumentError> {
    resolve_joint(skeleton, name)
        .ok_or_else(|| DocumentError::field(at, format!("unknown joint `{name}`")))
}

fn v3(a: [f64; 3]) -> DVec3 {
    DVec3::from_array(a)
}

impl PostureValues {
    /// The posture on `skeleton` (missing DOF are 0). Errors name the field
    /// (`posture.l_knee.ry: joint `l_knee` has no DOF `ry``).
    pub fn to_posture(&self, skeleton: &Skeleton) -> Result<Posture, DocumentError> {
        self.to_posture_at(skeleton, "posture")
    }

    /// Like [`PostureValues::to_posture`], with `at` as the path of this posture in errors.
    pub fn to_posture_at(&self, skeleton: &Skeleton, at: &str) -> Result<Posture, DocumentError> {
        let mut p = Posture::rest(skeleton);
        self.for_each_dof(skeleton, at, |dof, value, there| {
            if !value.is_finite() {
                return Err(DocumentError::field(there, "not a finite number"));
            }
            p.values_mut()[dof] = value;
            Ok(())
        })?;
        Ok(p)
    }

    /// The values whose joint and DOF `skeleton` has (H-Anim aliases find joints too), the
    /// others left out: a document made on another body (undo across an avatar swap or a
    /// level of articulation) restored on this one.
    pub fn fitted(&self, skeleton: &Skeleton) -> PostureValues {
        let mut out = PostureValues::default();
        for (name, dofs) in &self.joints {
            let Some(joint) = resolve_joint(skeleton, name).and_then(|j| skeleton.joints().get(j))
            else {
                continue;
            };
            let mut kept = DofValues::default();
            for (d, value) in dofs.iter() {
                if joint.dofs.contains(&d) {
                    kept.set(d, value);
                }
            }
            out.joints.insert(name.clone(), kept);
        }
        out
    }

    /// Calls `f(dof, value, path)` for every value, its joint and DOF found on `skeleton`
    /// (H-Anim aliases too); errors at `{at}.joint` (unknown joint) or `{at}.joint.dof` (a DOF
    /// the joint does not have), and `f`'s own.
    pub(crate) fn for_each_dof(
        &self,
        skeleton: &Skeleton,
        at: &str,
        mut f: impl FnMut(usize, f64, &str) -> Result<(), DocumentError>,
    ) -> Result<(), DocumentError> {
        for (name, dofs) in &self.joints {
            let here = format!("{at}.{name}");
            let joint = &skeleton.joints()[joint_at(skeleton, name, &here)?];
            for (d, value) in dofs.iter() {
                let there = format!("{here}.{}", d.name());
                let k = joint.dofs.iter().position(|&x| x == d).ok_or_else(|| {
                    DocumentError::field(
                        &there,
                        format!("joint `{name}` has no DOF `{}`", d.name()),
                    )
                })?;
                f(joint.dof_start + k, value, &there)?;
            }
        }
        Ok(())
    }

    /// Every DOF of every joint that has DOF, by joint name (the shape `stance solve` prints).
    pub fn from_posture(skeleton: &Skeleton, posture: &Posture) -> Self {
        let mut out = PostureValues::default();
        for joint in skeleton.joints() {
            if joint.dofs.is_empty() {
                continue;
            }
            let mut values = DofValues::default();
            for (k, &d) in joint.dofs.iter().enumerate() {
                let v = posture.values().get(joint.dof_start + k).copied();
                values.set(d, v.unwrap_or(0.0));
            }
            out.joints.insert(joint.name.clone(), values);
        }
        out
    }
}

impl TaskSpec {
    /// The problem-file form of a solver task on `skeleton` (joints by name); `None` for the
    /// kinds a problem file cannot hold (comfort, posture attraction, one body's centre of
    /// mass or balance among several, a meet, a collision task on other capsules than the body's: `stance_hanim::capsules::BodyCollision`) and joints out
    /// of range. A collision task's radii set by hand are the skeleton's in a problem file
    /// (`skeleton.joints[].radius`, which [`crate::problem_json`] writes), not the task's.
    pub fn from_task(skeleton: &Skeleton, task: &Task) -> Option<Self> {
        let name = |j: usize| skeleton.joints().get(j).map(|joint| joint.name.clone());
        let kind = match &task.kind {
            TaskKind::Position {
                effector,
                axes,
                target,
            } => TaskKindSpec::Position {
                joint: name(effector.joint)?,
                point: effector.point.to_array(),
                axes: *axes,
                target: target.to_array(),
            },
            TaskKind::Orientation { joint, target } => TaskKindSpec::Orientation {
                joint: name(*joint)?,
                target: target.to_array(),
            },
            TaskKind::Gaze {
                effector,
                axis,
                target,
            } => TaskKindSpec::Gaze {
                joint: name(effector.joint)?,
                axis: axis.to_array(),
                point: effector.point.to_array(),
                target: target.to_array(),
            },
            TaskKind::Direction {
                joint,
                axis,
                target,
            } => TaskKindSpec::Direction {
                joint: name(*joint)?,
                axis: axis.to_array(),
                target: target.to_array(),
            },
            TaskKind::CenterOfMass {
                axes,
                target,
                body: None | Some(0),
            } => TaskKindSpec::Com {
                axes: *axes,
                target: target.to_array(),
            },
            TaskKind::Balance {
                support,
                margin,
                body: None | Some(0),
            } => TaskKindSpec::Balance {
                support: Some(support_names(skeleton, support)?),
                margin: *margin,
            },
            TaskKind::PointOnLine {
                effector,
                origin,
                direction,
            } => TaskKindSpec::Line {
                joint: name(effector.joint)?,
                point: effector.point.to_array(),
                origin: origin.to_array(),
                direction: direction.to_array(),
            },
            TaskKind::PointOnPlane {
                effector,
                origin,
                normal,
                above,
            } => TaskKindSpec::Plane {
                joint: name(effector.joint)?,
                point: effector.point.to_array(),
                origin: origin.to_array(),
                normal: normal.to_array(),
                above: *above,
            },
            TaskKind::Collision(c) => {
                // The radii set by hand go with the skeleton (`problem_json` writes them).
                let body = BodyCollision::of(skeleton, c).filter(|b| b.rows == COLLISION_ROWS)?;
                TaskKindSpec::Collision {
                    margin: body.margin,
                    self_collision: body.self_collision,
                    floor: body.floor,
                }
            }
            // One body of several (`stance_ik::Bodies`) and two points meeting: scene tasks.
            TaskKind::CenterOfMass { .. } | TaskKind::Balance { .. } | TaskKind::Meet { .. } => {
                return None;
            }
            TaskKind::Comfort { .. } | TaskKind::PostureAttraction { .. } => return None,
        };
        Some(Self {
            level: task.level,
            weight: task.weight,
            active: task.active,
            kind,
            interval: None,
            on: None,
        })
    }
}

/// The problem-file names of a balance task's support points: a foot's four sole corners
/// ([`stance_hanim::anatomy::sole`], in that order) give its ankle, the centre of a joint that is
/// not a foot's gives the joint; `None` for any other point (a foot joint's name in a file
/// stands for its whole sole: a point of the foot alone has no problem-file form).
fn support_names(skeleton: &Skeleton, support: &[Effector]) -> Option<Vec<String>> {
    let mut names = Vec::new();
    let mut rest = support;
    while let Some(first) = rest.first() {
        let name = skeleton.joints().get(first.joint)?.name.clone();
        let foot = stance_hanim::anatomy::ankle_of(skeleton, first.joint);
        let corners =
            (foot == Some(first.joint)).then(|| stance_hanim::anatomy::sole(skeleton, first.joint));
        let sole_here = corners.filter(|corners| {
            rest.len() >= 4
                && rest[..4]
                    .iter()
                    .zip(corners)
                    .all(|(e, c)| e.joint == first.joint && e.point.distance(*c) < 1e-12)
        });
        if sole_here.is_some() {
            rest = &rest[4..];
        } else if foot.is_none() && first.point == DVec3::ZERO {
            rest = &rest[1..];
        } else {
            return None;
        }
        names.push(name);
    }
    Some(names)
}

/// A `limb` task resolved on a skeleton: the closed-form limb, its goal and the requested
/// swivel, for the editor's closed-form start and swivel handle (as `stance solve` does).
#[derive(Debug, Clone)]
pub struct LimbStartSpec {
    /// The limb (upper, middle, end joints of the skeleton).
    pub limb: Limb,
    /// World goal of the end joint (position, optional orientation).
    pub goal: LimbGoal,
    /// Requested swivel angle (rad); `None`: keep the current posture's.
    pub swivel: Option<f64>,
}

impl TaskSpec {
    /// The three joint indices of a `limb` task on `skeleton` (`None` for other kinds).
    fn limb_joints(&self, skeleton: &Skeleton) -> Result<Option<[usize; 3]>, DocumentError> {
        let TaskKindSpec::Limb { limb, joints, .. } = &self.kind else {
            return Ok(None);
        };
        let mut out = [0usize; 3];
        match (limb, joints) {
            (Some(l), None) => out = limb_joint_indices(*l, skeleton)?,
            (None, Some(names)) => {
                for (k, name) in names.iter().enumerate() {
                    out[k] = joint_at(skeleton, name, &format!("joints[{k}]"))?;
                }
            }
            _ => {
                return Err(DocumentError::field(
                    "joints",
                    "give either `joints` or `limb`",
                ));
            }
        }
        Ok(Some(out))
    }

    /// For a `limb` task: the closed-form limb and its goal (`None` for other kinds).
    pub fn to_limb(&self, skeleton: &Skeleton) -> Result<Option<LimbStartSpec>, DocumentError> {
        self.validate()?;
        let Some(j) = self.limb_joints(skeleton)? else {
            return Ok(None);
        };
        let TaskKindSpec::Limb {
            target,
            swivel,
            orientation,
            ..
        } = &self.kind
        else {
            return Ok(None);
        };
        let names = j.map(|i| skeleton.joints()[i].name.clone());
        let limb = Limb::from_names(skeleton, [&names[0], &names[1], &names[2]])
            .map_err(|e| DocumentError::field("", e.to_string()))?;
        Ok(Some(LimbStartSpec {
            limb,
            goal: LimbGoal {
                position: v3(*target),
                orientation: orientation.map(|q| DQuat::from_array(q).normalize()),
            },
            swivel: *swivel,
        }))
    }

    /// Every solver task this task stands for: one, except a `limb` task with an `orientation`
    /// (a position task on the end joint and an orientation task, both at the task's level).
    /// `problem` is every task of the problem this one belongs to (see [`TaskSpec::to_task`]).
    pub fn to_solver_tasks(
        &self,
        skeleton: &Skeleton,
        problem: &[TaskSpec],
    ) -> Result<Vec<Task>, DocumentError> {
        self.solver_tasks_with(skeleton, None, problem)
    }

    /// [`TaskSpec::to_solver_tasks`] on a built body: its comfort tasks read the body's own
    /// anatomical axes ([`built_axes`]), right for an avatar whose joint frames are not the
    /// H-Anim rest frame (a T-pose, permuted or reversed axes).
    pub fn to_solver_tasks_on(
        &self,
        body: &HumanoidSkeleton,
        problem: &[TaskSpec],
    ) -> Result<Vec<Task>, DocumentError> {
        self.solver_tasks_with(&body.skeleton, Some(body), problem)
    }

    pub(crate) fn solver_tasks_with(
        &self,
        skeleton: &Skeleton,
        body: Option<&HumanoidSkeleton>,
        problem: &[TaskSpec],
    ) -> Result<Vec<Task>, DocumentError> {
        let task = self.task_with(skeleton, body, problem)?;
        let mut out = vec![task.clone()];
        if let TaskKindSpec::Limb {
            orientation: Some(q),
            ..
        } = &self.kind
            && let Some(j) = self.limb_joints(skeleton)?
        {
            out.insert(
                0,
                Task {
                    kind: TaskKind::Orientation {
                        joint: j[2],
                        target: DQuat::from_array(*q).normalize(),
                    },
                    ..task
                },
            );
        }
        Ok(out)
    }

    /// The solver task on `skeleton`. Error paths are relative to the task (`joint`,
    /// `target[0]`); [`Document::to_tasks`] prefixes them with `tasks[i]`.
    ///
    /// A `limb` task gives its variational part, the position task of the end joint (like
    /// `stance solve`); its closed-form start is [`TaskSpec::to_limb`], its optional orientation
    /// goal an extra task of [`TaskSpec::to_solver_tasks`].
    ///
    /// `problem` is every task of the problem this one belongs to: a `balance` task without
    /// `support` stands on the problem's pinned contacts ([`pinned_contacts`]).
    pub fn to_task(
        &self,
        skeleton: &Skeleton,
        problem: &[TaskSpec],
    ) -> Result<Task, DocumentError> {
        self.task_with(skeleton, None, problem)
    }

    /// [`TaskSpec::to_task`] on a built body (see [`TaskSpec::to_solver_tasks_on`]).
    pub fn to_task_on(
        &self,
        body: &HumanoidSkeleton,
        problem: &[TaskSpec],
    ) -> Result<Task, DocumentError> {
        self.task_with(&body.skeleton, Some(body), problem)
    }

    /// The solver task; a comfort task's anatomical axes are `body`'s, or without one those
    /// of a skeleton whose joint frames are the H-Anim rest frame ([`aligned_axes`]).
    pub(crate) fn task_with(
        &self,
        skeleton: &Skeleton,
        body: Option<&HumanoidSkeleton>,
        problem: &[TaskSpec],
    ) -> Result<Task, DocumentError> {
        self.validate()?;
        let kind = match &self.kind {
            TaskKindSpec::Position {
                joint,
                point,
                axes,
                target,
            } => TaskKind::Position {
                effector: Effector {
                    joint: joint_at(skeleton, joint, "joint")?,
                    point: v3(*point),
                },
                axes: *axes,
                target: v3(*target),
            },
            TaskKindSpec::Orientation { joint, target } => TaskKind::Orientation {
                joint: joint_at(skeleton, joint, "joint")?,
                target: DQuat::from_array(*target).normalize(),
            },
            TaskKindSpec::Gaze {
                joint,
                axis,
                point,
                target,
            } => TaskKind::Gaze {
                effector: Effector {
                    joint: joint_at(skeleton, joint, "joint")?,
                    point: v3(*point),
                },
                axis: v3(*axis).normalize(),
                target: v3(*target),
            },
            TaskKindSpec::Direction {
                joint,
                axis,
                target,
            } => TaskKind::Direction {
                joint: joint_at(skeleton, joint, "joint")?,
                axis: v3(*axis).normalize(),
                target: v3(*target).normalize(),
            },
            TaskKindSpec::Balance { support, margin } => TaskKind::Balance {
                support: support_points(skeleton, support.as_deref(), problem)?,
                margin: *margin,
                body: None,
            },
            TaskKindSpec::Com { axes, target } => TaskKind::CenterOfMass {
                axes: *axes,
                target: v3(*target),
                body: None,
            },
            TaskKindSpec::Posture { joints, reference } => {
                let reference = match reference {
                    None => Posture::rest(skeleton),
                    Some(r) => r.to_posture_at(skeleton, "reference")?,
                };
                let dofs = match joints {
                    None => match Task::rest_posture(skeleton).kind {
                        TaskKind::PostureAttraction { dofs, .. } => dofs,
                        _ => Vec::new(),
                    },
                    Some(list) => {
                        let mut dofs = Vec::new();
                        for (k, name) in list.iter().enumerate() {
                            let j = joint_at(skeleton, name, &format!("joints[{k}]"))?;
                            dofs.extend(skeleton.joints()[j].dof_range());
                        }
                        dofs
                    }
                };
                TaskKind::PostureAttraction {
                    reference: reference.values().to_vec(),
                    dofs,
                }
            }
            TaskKindSpec::Comfort {
                effort,
                range,
                rula,
            } => {
                let settings = ComfortSettings {
                    effort: *effort,
                    range: *range,
                    rula: *rula,
                    ..ComfortSettings::default()
                };
                let axes = body.map_or_else(|| aligned_axes(skeleton), built_axes);
                TaskKind::Comfort {
                    model: Arc::new(comfort_model(skeleton, &axes, &settings)),
                }
            }
            TaskKindSpec::Collision {
                margin,
                self_collision,
                floor,
            } => TaskKind::Collision(
                BodyCollision {
                    margin: *margin,
                    self_collision: *self_collision,
                    floor: *floor,
                    ..BodyCollision::default()
                }
                .collision(skeleton),
            ),
            TaskKindSpec::Limb { target, .. } => {
                let j = self
                    .limb_joints(skeleton)?
                    .ok_or_else(|| DocumentError::Unsupported {
                        path: "kind".to_owned(),
                        what: "this limb task".to_owned(),
                    })?;
                TaskKind::Position {
                    effector: Effector {
                        joint: j[2],
                        point: DVec3::ZERO,
                    },
                    axes: Axes::XYZ,
                    target: v3(*target),
                }
            }
            TaskKindSpec::Line {
                joint,
                point,
                origin,
                direction,
            } => TaskKind::PointOnLine {
                effector: Effector {
                    joint: joint_at(skeleton, joint, "joint")?,
                    point: v3(*point),
                },
                origin: v3(*origin),
                direction: v3(*direction).normalize(),
            },
            TaskKindSpec::Plane {
                joint,
                point,
                origin,
                normal,
                above,
            } => TaskKind::PointOnPlane {
                effector: Effector {
                    joint: joint_at(skeleton, joint, "joint")?,
                    point: v3(*point),
                },
                origin: v3(*origin),
                normal: v3(*normal).normalize(),
                above: *above,
            },
        };
        let task = Task {
            kind,
            level: self.level,
            weight: self.weight,
            active: self.active,
        };
        task.validate(skeleton, 0).map_err(|e| {
            let reason = match e {
                stance_ik::IkError::BadTask { reason, .. } => reason,
                other => other.to_string(),
            };
            DocumentError::field("", reason)
        })?;
        Ok(task)
    }
}

/// The joints that support the body in a problem: the active `position` (controlling the
/// height) and `limb` tasks whose target is at most [`CONTACT_HEIGHT`] above the floor, at any
/// level. A pin held elsewhere (a hand on a table) does not count.
pub fn pinned_contacts(problem: &[TaskSpec]) -> Vec<(String, [f64; 3])> {
    problem
        .iter()
        .filter(|t| t.active)
        .filter_map(|t| match &t.kind {
            TaskKindSpec::Position {
                joint,
                point,
                axes,
                target,
            } if axes.has(1) && target[1] <= CONTACT_HEIGHT => Some((joint.clone(), *point)),
            TaskKindSpec::Limb {
                limb: Some(limb),
                target,
                ..
            } if target[1] <= CONTACT_HEIGHT => Some((limb.joints()[2].to_owned(), [0.0; 3])),
            TaskKindSpec::Limb {
                joints: Some(joints),
                target,
                ..
            } if target[1] <= CONTACT_HEIGHT => Some((joints[2].clone(), [0.0; 3])),
            _ => None,
        })
        .collect()
}

/// The support points of a balance task: for each contact, the sole of its foot (a foot
/// joint: the four corners of [`stance_hanim::anatomy::sole`], once per foot) or the point
/// itself. `support: None` takes the problem's [`pinned_contacts`], or both ankles when
/// nothing is pinned on the floor.
fn support_points(
    skeleton: &Skeleton,
    support: Option<&[String]>,
    problem: &[TaskSpec],
) -> Result<Vec<Effector>, DocumentError> {
    let contacts: Vec<(usize, DVec3)> = match support {
        Some(names) => names
            .iter()
            .enumerate()
            .map(|(k, name)| {
                Ok((
                    joint_at(skeleton, name, &format!("support[{k}]"))?,
                    DVec3::ZERO,
                ))
            })
            .collect::<Result<_, DocumentError>>()?,
        None => {
            let pinned: Vec<(usize, DVec3)> = pinned_contacts(problem)
                .iter()
                .filter_map(|(name, point)| Some((resolve_joint(skeleton, name)?, v3(*point))))
                .collect();
            if pinned.is_empty() {
                ["l_talocrural", "r_talocrural"]
                    .iter()
                    .filter_map(|name| Some((resolve_joint(skeleton, name)?, DVec3::ZERO)))
                    .collect()
            } else {
                pinned
            }
        }
    };
    let mut feet = Vec::new();
    let mut points = Vec::new();
    for (joint, point) in contacts {
        match stance_hanim::anatomy::ankle_of(skeleton, joint) {
            Some(ankle) if !feet.contains(&ankle) => {
                feet.push(ankle);
                points.extend(
                    stance_hanim::anatomy::sole(skeleton, ankle).map(|point| Effector {
                        joint: ankle,
                        point,
                    }),
                );
            }
            Some(_) => {}
            None => points.push(Effector { joint, point }),
        }
    }
    if points.is_empty() {
        return Err(DocumentError::field(
            "support",
            "no support: pin a foot (or another part) on the floor, or name the support joints",
        ));
    }
    Ok(points)
}

/// Every solver task of `specs` (one problem's tasks) on `skeleton`, in order (the collision
/// tasks leaving off the parts placed on a surface: [`stance_ik::with_placed_parts`]); errors
/// at `tasks[i].<field>`.
pub fn solver_tasks(skeleton: &Skeleton, specs: &[TaskSpec]) -> Result<Vec<Task>, DocumentError> {
    let mut out = Vec::with_capacity(specs.len());
    for (i, t) in specs.iter().enumerate() {
        out.extend(
            t.to_solver_tasks(skeleton, specs)
                .map_err(|e| e.within(&format!("tasks[{i}]")))?,
        );
    }
    stance_ik::with_placed_parts(skeleton, &mut out);
    Ok(out)
}

/// The limb's (upper, middle, end) joint indices on `skeleton`, or an error at `limb`.
pub fn limb_joint_indices(
    limb: LimbName,
    skeleton: &Skeleton,
) -> Result<[usize; 3], DocumentError> {
    limb.joint_indices(skeleton).ok_or_else(|| {
        DocumentError::field(
            "limb",
            format!("the skeleton lacks the H-Anim joints of `{}`", limb.name()),
        )
    })
}

impl Document {
    /// The posture on `skeleton` (errors at `posture.<joint>.<dof>`).
    pub fn to_posture(&self, skeleton: &Skeleton) -> Result<Posture, DocumentError> {
        self.posture.to_posture(skeleton)
    }

    /// Every solver task on `skeleton`, in document order (errors at `tasks[i].<field>`); a
    /// `limb` task with an `orientation` gives two (see [`TaskSpec::to_solver_tasks`]).
    pub fn to_tasks(&self, skeleton: &Skeleton) -> Result<Vec<Task>, DocumentError> {
        solver_tasks(skeleton, &self.tasks)
    }

    /// The closed-form limbs of the `limb` tasks, with the index of their task.
    pub fn to_limbs(
        &self,
        skeleton: &Skeleton,
    ) -> Result<Vec<(usize, LimbStartSpec)>, DocumentError> {
        let mut out = Vec::new();
        for (i, t) in self.tasks.iter().enumerate() {
            if let Some(l) = t
                .to_limb(skeleton)
                .map_err(|e| e.within(&format!("tasks[{i}]")))?
            {
                out.push((i, l));
            }
        }
        Ok(out)
    }
}

impl Document {
    /// The document with its posture values relative to the H-Anim standard pose on `body`
    /// (built from the avatar the document was made on): a document whose values are relative
    /// to the avatar's own rest ([`PostureRest::Avatar`], written before Stance wrote `rest`)
    /// shows on `body` the pose it showed then. Each joint's world rotation from the avatar's
    /// rest is turned back by its rest match (`G · rest_match⁻¹`), the local rotations are
    /// projected onto the joint's DOF, the root keeps its place. The posture, the keys and
    /// the posture tasks' references are converted; joints the body lacks are left out. A
    /// document already relative to the standard pose comes back as it is.
    pub fn in_standard_rest(&self, body: &HumanoidSkeleton) -> Document {
        if self.rest == PostureRest::Standard {
            return self.clone();
        }
        let mut out = self.clone();
        out.rest = PostureRest::Standard;
        out.posture = standard_values(&self.posture, body);
        if let Some(motion) = &mut out.motion {
            for key in &mut motion.keys {
                key.posture = standard_values(&key.posture, body);
            }
        }
        for task in &mut out.tasks {
            if let TaskKindSpec::Posture {
                reference: Some(reference),
                ..
            } = &mut task.kind
            {
                *reference = standard_values(reference, body);
            }
        }
        out
    }
}

/// `values` relative to the avatar's own rest, relative to the standard pose of `body`.
fn standard_values(values: &PostureValues, body: &HumanoidSkeleton) -> PostureValues {
    let skeleton = &body.skeleton;
    let joints = skeleton.joints();
    let standard_rest = stance_ik::Frames::new(skeleton, &Posture::rest(skeleton)).joint_position;
    let mut own = Vec::with_capacity(joints.len());
    let mut standard: Vec<DQuat> = Vec::with_capacity(joints.len());
    let mut translation = DVec3::ZERO;
    for (k, joint) in joints.iter().enumerate() {
        let dofs = values.joints.get(&joint.name).copied().unwrap_or_default();
        let r = |d: stance_ik::Dof| dofs.get(d).unwrap_or(0.0);
        let local = DQuat::from_scaled_axis(DVec3::new(
            r(stance_ik::Dof::Rx),
            r(stance_ik::Dof::Ry),
            r(stance_ik::Dof::Rz),
        ));
        let parent = joint.parent.and_then(|p| own.get(p).copied());
        let world = parent.map_or(local, |p: DQuat| p * local).normalize();
        own.push(world);
        let rest_match = body.joints.get(k).map_or(DQuat::IDENTITY, |j| j.rest_match);
        standard.push((world * rest_match.inverse()).normalize());
        if joint.parent.is_none() {
            let t = DVec3::new(
                r(stance_ik::Dof::Tx),
                r(stance_ik::Dof::Ty),
                r(stance_ik::Dof::Tz),
            );
            let own_root = body.joints.get(k).map_or(standard_rest[k], |j| j.own_rest);
            translation = t + own_root - standard_rest[k];
        }
    }
    let locals: Vec<DQuat> = joints
        .iter()
        .zip(&standard)
        .map(
            |(joint, world)| match joint.parent.and_then(|p| standard.get(p)) {
                Some(parent) => (parent.inverse() * *world).normalize(),
                None => *world,
            },
        )
        .collect();
    match Posture::from_rotations(skeleton, translation, &locals) {
        Ok(posture) => PostureValues::from_posture(skeleton, &posture),
        Err(_) => values.clone(),
    }
}
