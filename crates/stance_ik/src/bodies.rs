//! Several bodies in one problem: the skeletons of a scene's characters joined below a root
//! joint without DOF, each placed in the scene (a turn about the vertical and a translation),
//! so that a task between two characters (a hand in another's hand) is solved with both
//! bodies' DOF in one prioritized problem. Each body's tasks move into the scene's frame; a
//! task that means "the whole body" (centre of mass, balance) keeps meaning that body.
//!
//! The levels of the bodies merge by number: the Jacobians of two bodies' tasks share no
//! column, so at every level each body's projector is the one it would have alone, and each
//! body's priorities hold as they did; only a task between bodies couples them.

use glam::{DQuat, DVec3};

use crate::{Dof, Effector, IkError, JointDef, Posture, Skeleton, Task, TaskKind};

/// The name of the joint without DOF that carries every body.
pub const SCENE_ROOT: &str = "scene";

/// Where a body stands in the scene: `scene_from_body`, a turn and a translation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyPlacement {
    /// The body's turn (a rotation about +Y for a character on the floor).
    pub rotation: DQuat,
    /// The body's origin in the scene (m).
    pub translation: DVec3,
}

impl Default for BodyPlacement {
    fn default() -> Self {
        Self {
            rotation: DQuat::IDENTITY,
            translation: DVec3::ZERO,
        }
    }
}

impl BodyPlacement {
    /// A point of the body's frame in the scene.
    pub fn point(&self, p: DVec3) -> DVec3 {
        self.rotation * p + self.translation
    }

    /// A point of the scene in the body's frame.
    pub fn inverse_point(&self, p: DVec3) -> DVec3 {
        self.rotation.inverse() * (p - self.translation)
    }

    fn is_identity(&self) -> bool {
        self.translation == DVec3::ZERO && self.rotation.angle_between(DQuat::IDENTITY) < 1e-12
    }
}

/// One body of [`Bodies`].
#[derive(Debug, Clone)]
struct Member {
    placement: BodyPlacement,
    /// The body's joint `j` is the joined skeleton's joint `joints[j]`.
    joints: Vec<usize>,
    /// The body's DOF `d` is the joined skeleton's DOF `dofs[d]`.
    dofs: Vec<usize>,
    /// The body's own skeleton (its root's rest offset and DOF).
    skeleton: Skeleton,
}

/// Skeletons joined into one, each placed in the scene (see the module's text).
#[derive(Debug, Clone)]
pub struct Bodies {
    skeleton: Skeleton,
    members: Vec<Member>,
}

fn bad_body(body: usize, reason: impl Into<String>) -> IkError {
    IkError::BadBody {
        body,
        reason: reason.into(),
    }
}

impl Bodies {
    /// Joins `bodies`, each with its placement. A body that is turned or moved needs a root
    /// with all six DOF and no limits on them (its root's values are read in the scene's
    /// frame); one at the origin may have any root.
    pub fn new(bodies: &[(&Skeleton, BodyPlacement)]) -> Result<Self, IkError> {
        if bodies.is_empty() {
            return Err(IkError::Empty);
        }
        let mut defs = vec![JointDef::new(SCENE_ROOT, None, DVec3::ZERO, &[])];
        for (b, (skeleton, placement)) in bodies.iter().enumerate() {
            if !placement.translation.is_finite() || !placement.rotation.is_finite() {
                return Err(bad_body(b, "its placement is not finite"));
            }
            if !placement.is_identity() {
                check_placeable_root(skeleton).map_err(|reason| bad_body(b, reason))?;
            }
            for mut def in skeleton.joint_defs() {
                def.name = joined_name(b, &def.name);
                def.parent = Some(match &def.parent {
                    Some(parent) => joined_name(b, parent),
                    None => SCENE_ROOT.to_owned(),
                });
                defs.push(def);
            }
        }
        let joined = Skeleton::new(defs)?;
        let mut members = Vec::with_capacity(bodies.len());
        for (b, (skeleton, placement)) in bodies.iter().enumerate() {
            let mut joints = Vec::with_capacity(skeleton.joint_count());
            let mut dofs = vec![0; skeleton.dof_count()];
            for joint in skeleton.joints() {
                let there = joined.require_joint(&joined_name(b, &joint.name))?;
                joints.push(there);
                let other = &joined.joints()[there];
                for (k, dof) in joint.dofs.iter().enumerate() {
                    let m =
                        other.dofs.iter().position(|d| d == dof).ok_or_else(|| {
                            bad_body(b, format!("joint `{}` lost a DOF", joint.name))
                        })?;
                    dofs[joint.dof_start + k] = other.dof_start + m;
                }
            }
            members.push(Member {
                placement: *placement,
                joints,
                dofs,
                skeleton: (*skeleton).clone(),
            });
        }
        Ok(Self {
            skeleton: joined,
            members,
        })
    }

    /// The joined skeleton: [`SCENE_ROOT`], then each body's joints.
    pub fn skeleton(&self) -> &Skeleton {
        &self.skeleton
    }

    /// The number of bodies.
    pub fn len(&self) -> usize {
        self.members.len()
    }

    /// Whether there is no body (never: [`Bodies::new`] refuses none).
    pub fn is_empty(&self) -> bool {
        self.members.is_empty()
    }

    fn member(&self, body: usize) -> Result<&Member, IkError> {
        self.members
            .get(body)
            .ok_or_else(|| bad_body(body, format!("there are {} bodies", self.members.len())))
    }

    /// The joined skeleton's index of `body`'s joint `joint`.
    pub fn joint(&self, body: usize, joint: usize) -> Result<usize, IkError> {
        self.member(body)?
            .joints
            .get(joint)
            .copied()
            .ok_or_else(|| bad_body(body, format!("it has no joint {joint}")))
    }

    /// `body`'s point `effector` on the joined skeleton.
    pub fn effector(&self, body: usize, effector: Effector) -> Result<Effector, IkError> {
        Ok(Effector {
            joint: self.joint(body, effector.joint)?,
            point: effector.point,
        })
    }

    /// The joined posture of the bodies' `postures` (one each, in the bodies' order), each
    /// body's root carried into the scene by its placement.
    pub fn posture(&self, postures: &[&Posture]) -> Result<Posture, IkError> {
        if postures.len() != self.members.len() {
            return Err(bad_body(
                postures.len(),
                format!(
                    "{} postures for {} bodies",
                    postures.len(),
                    self.members.len()
                ),
            ));
        }
        let mut values = vec![0.0; self.skeleton.dof_count()];
        for (member, posture) in self.members.iter().zip(postures) {
            let placed = member.placed_values(posture.values(), true)?;
            for (d, v) in placed.into_iter().enumerate() {
                values[member.dofs[d]] = v;
            }
        }
        Posture::from_values(&self.skeleton, values)
    }

    /// Each body's posture in its own frame, out of a joined posture.
    pub fn split(&self, posture: &Posture) -> Result<Vec<Posture>, IkError> {
        let values = posture.values();
        self.members
            .iter()
            .map(|member| {
                let own: Vec<f64> = member
                    .dofs
                    .iter()
                    .map(|&d| values.get(d).copied().unwrap_or(0.0))
                    .collect();
                let own = member.placed_values(&own, false)?;
                Posture::from_values(&member.skeleton, own)
            })
            .collect()
    }

    /// `body`'s `task` (on its own skeleton, in its own frame) on the joined skeleton, in the
    /// scene's frame. A comfort task is refused (its model is built for one skeleton), a
    /// collision task too (the bodies' collision tasks join into one: [`Bodies::collision`]),
    /// as is a position or centre-of-mass task on axes that the body's turn does
    /// not keep (`x` alone on a body turned by 90 degrees).
    pub fn task(&self, body: usize, task: &Task) -> Result<Task, IkError> {
        let member = self.member(body)?;
        let place = member.placement;
        let rotation = place.rotation;
        let effector = |e: &Effector| self.effector(body, *e);
        let root = Some(self.joint(body, 0)?);
        let kept_axes = |axes: crate::Axes| {
            let kept = (0..3).filter(|&i| axes.has(i)).all(|i| {
                let v = rotation * DVec3::AXES[i];
                (0..3).all(|k| axes.has(k) || v[k].abs() < 1e-9)
            });
            if kept {
                Ok(axes)
            } else {
                Err(bad_body(
                    body,
                    format!(
                        "its turn does not keep the task's axes `{}`",
                        axes.to_letters()
                    ),
                ))
            }
        };
        let kind = match &task.kind {
            TaskKind::Position {
                effector: e,
                axes,
                target,
            } => TaskKind::Position {
                effector: effector(e)?,
                axes: kept_axes(*axes)?,
                target: place.point(*target),
            },
            TaskKind::Orientation { joint, target } => TaskKind::Orientation {
                joint: self.joint(body, *joint)?,
                target: rotation * *target,
            },
            TaskKind::Gaze {
                effector: e,
                axis,
                target,
            } => TaskKind::Gaze {
                effector: effector(e)?,
                axis: *axis,
                target: place.point(*target),
            },
            TaskKind::Direction {
                joint,
                axis,
                target,
            } => TaskKind::Direction {
                joint: self.joint(body, *joint)?,
                axis: *axis,
                target: rotation * *target,
            },
            TaskKind::CenterOfMass {
                axes,
                target,
                body: own,
            } => TaskKind::CenterOfMass {
                axes: kept_axes(*axes)?,
                target: place.point(*target),
                body: match own {
                    Some(j) => Some(self.joint(body, *j)?),
                    None => root,
                },
            },
            TaskKind::Balance {
                support,
                margin,
                body: own,
            } => TaskKind::Balance {
                support: support.iter().map(effector).collect::<Result<_, _>>()?,
                margin: *margin,
                body: match own {
                    Some(j) => Some(self.joint(body, *j)?),
                    None => root,
                },
            },
            TaskKind::Meet { a, b, axes } => TaskKind::Meet {
                a: effector(a)?,
                b: effector(b)?,
                axes: kept_axes(*axes)?,
            },
            TaskKind::PointOnLine {
                effector: e,
                origin,
                direction,
            } => TaskKind::PointOnLine {
                effector: effector(e)?,
                origin: place.point(*origin),
                direction: rotation * *direction,
            },
            TaskKind::PointOnPlane {
                effector: e,
                origin,
                normal,
                above,
            } => TaskKind::PointOnPlane {
                effector: effector(e)?,
                origin: place.point(*origin),
                normal: rotation * *normal,
                above: *above,
            },
            TaskKind::PostureAttraction { reference, dofs } => {
                let placed = member.placed_values(reference, true)?;
                let mut joined = vec![0.0; self.skeleton.dof_count()];
                for (d, v) in placed.into_iter().enumerate() {
                    joined[member.dofs[d]] = v;
                }
                TaskKind::PostureAttraction {
                    reference: joined,
                    dofs: dofs
                        .iter()
                        .map(|&d| {
                            member
                                .dofs
                                .get(d)
                                .copied()
                                .ok_or_else(|| bad_body(body, format!("it has no DOF {d}")))
                        })
                        .collect::<Result<_, _>>()?,
                }
            }
            TaskKind::Comfort { .. } => {
                return Err(bad_body(body, "comfort is solved for one body at a time"));
            }
            TaskKind::Collision(_) => {
                return Err(bad_body(
                    body,
                    "the bodies' collision tasks join into one (Bodies::collision)",
                ));
            }
        };
        Ok(Task {
            kind,
            ..task.clone()
        })
    }
}

impl Bodies {
    /// The bodies' collision tasks (`tasks`: each with the body it is for) as one on the joined
    /// skeleton: each body's capsules, pairs and floor capsules kept, its obstacles (a scene's
    /// props, in its own frame) moved into the scene, and every capsule of a body kept apart
    /// from every capsule of each other body, so that two characters do not pass through each
    /// other (the broad phase skips the pairs far apart). At the highest priority (smallest
    /// level) of theirs, the largest margin, the rows of all. `None` when none is active.
    ///
    /// `touching`: pairs of joints (of the joined skeleton) that meet (a hand in another's hand,
    /// on a shoulder): the limbs they end (everything below each one's parent) may touch each
    /// other and are not kept apart from each other; everything else is.
    pub fn collision(
        &self,
        tasks: &[(usize, &Task)],
        touching: &[(usize, usize)],
    ) -> Result<Option<Task>, IkError> {
        let mut capsules = Vec::new();
        let mut owner = Vec::new();
        let (mut pairs, mut floor, mut obstacles) = (Vec::new(), Vec::new(), Vec::new());
        let (mut level, mut margin, mut rows) = (u32::MAX, 0.0f64, 0);
        for &(body, task) in tasks {
            let TaskKind::Collision(c) = &task.kind else {
                continue;
            };
            if !task.active {
                continue;
            }
            let place = self.member(body)?.placement;
            let base = capsules.len();
            for capsule in c.capsules() {
                capsules.push(crate::Capsule {
                    joint: self.joint(body, capsule.joint)?,
                    ..*capsule
                });
                owner.push(body);
            }
            pairs.extend(c.pairs().iter().map(|&(i, j)| (base + i, base + j)));
            floor.extend(c.floor().iter().map(|&i| base + i));
            let turn = glam::DMat3::from_quat(place.rotation);
            obstacles.extend(c.obstacles().iter().map(|o| crate::Obstacle {
                world_from_obstacle_rotation: turn * o.world_from_obstacle_rotation,
                position: place.point(o.position),
                ..*o
            }));
            level = level.min(task.level);
            margin = margin.max(c.margin());
            rows += c.rows();
        }
        if capsules.is_empty() {
            return Ok(None);
        }
        let in_limb = |capsule: &crate::Capsule, joint: usize| {
            let root = self.skeleton.joints().get(joint).and_then(|j| j.parent);
            root.is_some_and(|root| self.skeleton.is_ancestor_or_self(root, capsule.joint))
        };
        let meeting = |x: &crate::Capsule, y: &crate::Capsule| {
            touching
                .iter()
                .any(|&(a, b)| (in_limb(x, a) && in_limb(y, b)) || (in_limb(x, b) && in_limb(y, a)))
        };
        for i in 0..capsules.len() {
            for j in i + 1..capsules.len() {
                if owner[i] != owner[j] && !meeting(&capsules[i], &capsules[j]) {
                    pairs.push((i, j));
                }
            }
        }
        let collision = crate::Collision::new(&self.skeleton, capsules, pairs, floor, margin, rows)
            .with_obstacles(obstacles);
        Ok(Some(Task {
            kind: TaskKind::Collision(collision),
            level,
            weight: 1.0,
            active: true,
        }))
    }
}

fn joined_name(body: usize, name: &str) -> String {
    format!("{body}:{name}")
}

/// Why a body's root cannot be placed, if it cannot: it needs all six DOF, unlimited.
fn check_placeable_root(skeleton: &Skeleton) -> Result<(), String> {
    let Some(root) = skeleton.joints().first() else {
        return Err("it has no joint".to_owned());
    };
    if let Some(missing) = Dof::ALL.iter().find(|d| !root.dofs.contains(d)) {
        return Err(format!(
            "its root `{}` has no {} DOF: a turned or moved body needs all six",
            root.name,
            missing.name()
        ));
    }
    let limited = root
        .dof_range()
        .any(|d| skeleton.lower_limits()[d].is_finite() || skeleton.upper_limits()[d].is_finite());
    if limited {
        return Err(format!(
            "its root `{}` has limits: a turned or moved body's root must be free",
            root.name
        ));
    }
    Ok(())
}

impl Member {
    /// The body's DOF values with the root carried into the scene (`into_scene`) or back
    /// out of it, by the placement; unchanged at the origin.
    fn placed_values(&self, values: &[f64], into_scene: bool) -> Result<Vec<f64>, IkError> {
        let mut out = values.to_vec();
        if self.placement.is_identity() {
            return Ok(out);
        }
        let posture = Posture::from_values(&self.skeleton, values.to_vec())?;
        let (position, rotation) = posture.root_transform(&self.skeleton);
        let (position, rotation) = if into_scene {
            (
                self.placement.point(position),
                self.placement.rotation * rotation,
            )
        } else {
            (
                self.placement.inverse_point(position),
                self.placement.rotation.inverse() * rotation,
            )
        };
        let Some(root) = self.skeleton.joints().first() else {
            return Ok(out);
        };
        let translation = position - root.offset;
        let rotation = if rotation.w < 0.0 {
            -rotation
        } else {
            rotation
        };
        let vector = rotation.normalize().to_scaled_axis();
        for (axis, dof) in root.translation_dof.iter().enumerate() {
            if let Some(d) = dof {
                out[*d] = translation[axis];
            }
        }
        for (axis, dof) in root.rotation_dof.iter().enumerate() {
            if let Some(d) = dof {
                out[*d] = vector[axis];
            }
        }
        Ok(out)
    }
}
