//! Tasks (the paper's "contraintes"): what the solver is asked to achieve, each with a
//! priority level, a weight and an active flag. Each task's error and Jacobian rows are
//! computed in the submodule `rows`; the gaze/direction geometry, the balance support
//! polygon, the line and plane loci and the collision search live in `gaze`, `balance`,
//! `locus` and `collision`.

mod balance;
mod collision;
mod gaze;
mod locus;
mod obstacle;
mod rows;

use glam::{DQuat, DVec3};

pub use balance::BALANCE_BAND;
pub(crate) use collision::NearList;
pub use collision::{
    COLLISION_AIM, COLLISION_BAND, COLLISION_LOOKAHEAD, CONTACT_REACH, Capsule, Collision, Contact,
    closest_points, collision_pairs, floor_capsules,
};
pub use locus::PLANE_BAND;
pub use obstacle::{Obstacle, ObstacleShape};

use std::sync::Arc;

use crate::comfort::ComfortModel;
use crate::{IkError, Skeleton};

/// A subset of the world axes x, y, z.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Axes {
    mask: u8,
}

impl Axes {
    /// x, y and z.
    pub const XYZ: Axes = Axes { mask: 0b111 };
    /// The horizontal plane of the H-Anim frame (+Y up).
    pub const XZ: Axes = Axes { mask: 0b101 };

    /// From three flags.
    pub fn new(x: bool, y: bool, z: bool) -> Self {
        Self {
            mask: u8::from(x) | (u8::from(y) << 1) | (u8::from(z) << 2),
        }
    }

    /// Parses `"xyz"`, `"xz"`, `"y"`... (each letter at most once, at least one).
    pub fn parse(s: &str) -> Option<Self> {
        let mut mask = 0u8;
        for c in s.chars() {
            let bit = match c {
                'x' | 'X' => 1,
                'y' | 'Y' => 2,
                'z' | 'Z' => 4,
                _ => return None,
            };
            if mask & bit != 0 {
                return None;
            }
            mask |= bit;
        }
        (mask != 0).then_some(Self { mask })
    }

    /// Whether axis `i` (0 = x) is selected.
    pub fn has(self, i: usize) -> bool {
        i < 3 && self.mask & (1 << i) != 0
    }

    /// Number of selected axes.
    pub fn count(self) -> usize {
        self.mask.count_ones() as usize
    }

    /// The letters, e.g. `"xz"`.
    pub fn to_letters(self) -> String {
        ["x", "y", "z"]
            .iter()
            .enumerate()
            .filter(|(i, _)| self.has(*i))
            .map(|(_, s)| *s)
            .collect()
    }
}

/// A point fixed on a body segment: the frame of `joint`, at `point` in that frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Effector {
    /// The joint whose frame carries the point.
    pub joint: usize,
    /// The point in the joint frame (m).
    pub point: DVec3,
}

/// What a task controls.
#[derive(Debug, Clone, PartialEq)]
pub enum TaskKind {
    /// Position of an effector point along the selected world axes.
    Position {
        /// The controlled point.
        effector: Effector,
        /// Which world axes are controlled.
        axes: Axes,
        /// World target (all three components are stored; `axes` selects).
        target: DVec3,
    },
    /// World orientation of a segment (`world_from_joint`), 3 rows.
    Orientation {
        /// The joint.
        joint: usize,
        /// Target `world_from_joint` rotation.
        target: DQuat,
    },
    /// Gaze / direction: the segment axis `axis`, from the point `effector`, aims at `target`.
    /// 2 rows (the components of the unit direction to the target, in the joint frame,
    /// orthogonal to `axis`).
    Gaze {
        /// Eye point on the segment.
        effector: Effector,
        /// Aiming axis in the joint frame (unit).
        axis: DVec3,
        /// World point to look at.
        target: DVec3,
    },
    /// Partial orientation: the segment axis `axis` (joint frame) points along the world
    /// direction `target`, the rotation about it left free. 2 rows, like a gaze at infinity:
    /// pelvis upright (its up axis along world up), a palm facing down (the palm normal
    /// along -Y), a forearm horizontal...
    Direction {
        /// The joint.
        joint: usize,
        /// Axis in the joint frame (unit).
        axis: DVec3,
        /// World direction (unit).
        target: DVec3,
    },
    /// Whole-body centre of mass along the selected world axes (`Axes::XZ`: horizontal).
    CenterOfMass {
        /// Controlled axes.
        axes: Axes,
        /// World target.
        target: DVec3,
        /// The body whose centre of mass it is, by its root joint: the subtree from it (one
        /// character of a skeleton that holds several, [`crate::Bodies`]); `None`: the whole
        /// skeleton.
        body: Option<usize>,
    },
    /// Balance as an inequality: the horizontal projection of the centre of mass stays inside
    /// the support polygon (the convex hull, in the floor plane XZ, of the `support` points)
    /// shrunk by `margin`. 1 row, along the outward normal of the nearest boundary: active
    /// (with an error) when the projection is outside, active with a zero error within
    /// [`BALANCE_BAND`] inside the boundary (the centre of mass may slide along it but not
    /// leave), and empty (a zero row, no constraint on the lower levels) deeper inside.
    /// With one support point the polygon is that point, with two the segment between them;
    /// the margin only applies to a polygon with an area.
    Balance {
        /// Contact points on the body (e.g. the corners of the soles of the pinned feet).
        support: Vec<Effector>,
        /// Distance kept from the polygon's edges (m), >= 0.
        margin: f64,
        /// The body whose centre of mass is balanced, by its root joint (as for
        /// [`TaskKind::CenterOfMass`]); `None`: the whole skeleton.
        body: Option<usize>,
    },
    /// Comfort (the paper's open question): the cost of a [`ComfortModel`] (effort against
    /// gravity, joint-range discomfort, angle bands) lowered along its gradient projected into
    /// what the levels above leave (the null-space term `z` of the paper's formula). One row,
    /// the unit gradient; never "met": the solve goes on while the cost falls. A comfort task
    /// shares its level with no other kind of task.
    Comfort {
        /// The cost.
        model: Arc<ComfortModel>,
    },
    /// Collision avoidance as an inequality ([`Collision`]): the surfaces of pairs of capsules
    /// (and some capsules and the floor `y = 0`) keep at least a margin apart. Up to
    /// [`Collision::rows`] rows, one per constraint along its line of closest approach, the
    /// nearest first: an error where two surfaces are closer than the margin, a zero error
    /// within [`COLLISION_BAND`] beyond it. The solver's level has rows only for the
    /// constraints under the margin, and those within [`COLLISION_LOOKAHEAD`] beyond it where
    /// a step would bring them inside it (they may slide along each other or part, not come
    /// closer; see
    /// [`Task::rows_vary`]); [`Task::error_vector`] and [`Task::feature`] keep all of them,
    /// the others empty.
    Collision(Collision),
    /// Point on a line: the effector point kept on the world line through `origin` along
    /// `direction` (a hand on a bar, a keypoint on the camera ray through its pixel). 2 rows:
    /// the point's offset from the line along two unit vectors orthogonal to the direction.
    PointOnLine {
        /// The controlled point.
        effector: Effector,
        /// A point of the line (world, m).
        origin: DVec3,
        /// The line's direction (world, non-zero; normalised when used).
        direction: DVec3,
    },
    /// Point on a plane: the effector point kept on the world plane through `origin` with
    /// normal `normal` (a hand or foot on a surface). 1 row, the signed distance. With
    /// `above`, an inequality: on or above the plane (the side the normal points to), the row
    /// active with an error below it, active with a zero error within [`PLANE_BAND`] over it,
    /// empty further above.
    PointOnPlane {
        /// The controlled point.
        effector: Effector,
        /// A point of the plane (world, m).
        origin: DVec3,
        /// The plane's normal (world, non-zero; normalised when used).
        normal: DVec3,
        /// On or above the plane (an inequality) instead of on it.
        above: bool,
    },
    /// Two points of the body meet along the selected world axes: hands clasped, a hand on
    /// a shoulder; on a skeleton that holds several characters ([`crate::Bodies`]) a hand in
    /// another's hand. Each point moves toward the other; the rows are `b - a`.
    Meet {
        /// The first point.
        a: Effector,
        /// The second point.
        b: Effector,
        /// Which world axes are controlled.
        axes: Axes,
    },
    /// Attraction of the chosen DOF toward a reference posture (Jacobian = identity rows).
    PostureAttraction {
        /// Reference value for every DOF of the skeleton.
        reference: Vec<f64>,
        /// The attracted DOF (posture indices).
        dofs: Vec<usize>,
    },
}

/// One task with its priority level (1 = highest), weight inside its level and active flag.
#[derive(Debug, Clone, PartialEq)]
pub struct Task {
    /// What is controlled.
    pub kind: TaskKind,
    /// Priority level; smaller is more important. Levels need not be contiguous.
    pub level: u32,
    /// Weight inside the level (rows are scaled by `sqrt(weight)`); must be >= 0.
    pub weight: f64,
    /// Inactive tasks are ignored.
    pub active: bool,
}

impl Task {
    /// A task at level 1, weight 1, active.
    pub fn new(kind: TaskKind) -> Self {
        Self {
            kind,
            level: 1,
            weight: 1.0,
            active: true,
        }
    }

    /// Position of `point` (joint frame) of `joint`, all three axes.
    pub fn position(joint: usize, point: DVec3, target: DVec3) -> Self {
        Self::new(TaskKind::Position {
            effector: Effector { joint, point },
            axes: Axes::XYZ,
            target,
        })
    }

    /// Orientation of `joint`.
    pub fn orientation(joint: usize, target: DQuat) -> Self {
        Self::new(TaskKind::Orientation { joint, target })
    }

    /// Gaze of `joint` along its local `axis` toward `target`, from the joint centre.
    pub fn gaze(joint: usize, axis: DVec3, target: DVec3) -> Self {
        Self::new(TaskKind::Gaze {
            effector: Effector {
                joint,
                point: DVec3::ZERO,
            },
            axis,
            target,
        })
    }

    /// The `axis` of `joint` (joint frame) along the world direction `target`.
    pub fn direction(joint: usize, axis: DVec3, target: DVec3) -> Self {
        Self::new(TaskKind::Direction {
            joint,
            axis,
            target,
        })
    }

    /// The centre of mass inside the support polygon of `support`, `margin` from its edges.
    pub fn balance(support: Vec<Effector>, margin: f64) -> Self {
        Self::new(TaskKind::Balance {
            support,
            margin,
            body: None,
        })
    }

    /// `point_a` of `joint_a` and `point_b` of `joint_b` (joint frames) meet, all three axes.
    pub fn meet(joint_a: usize, point_a: DVec3, joint_b: usize, point_b: DVec3) -> Self {
        Self::new(TaskKind::Meet {
            a: Effector {
                joint: joint_a,
                point: point_a,
            },
            b: Effector {
                joint: joint_b,
                point: point_b,
            },
            axes: Axes::XYZ,
        })
    }

    /// `point` (joint frame) of `joint` on the world line through `origin` along `direction`.
    pub fn point_on_line(joint: usize, point: DVec3, origin: DVec3, direction: DVec3) -> Self {
        Self::new(TaskKind::PointOnLine {
            effector: Effector { joint, point },
            origin,
            direction,
        })
    }

    /// `point` (joint frame) of `joint` on the world plane through `origin` with `normal`;
    /// with `above`, on or above it.
    pub fn point_on_plane(
        joint: usize,
        point: DVec3,
        origin: DVec3,
        normal: DVec3,
        above: bool,
    ) -> Self {
        Self::new(TaskKind::PointOnPlane {
            effector: Effector { joint, point },
            origin,
            normal,
            above,
        })
    }

    /// Centre of mass on `axes`.
    pub fn center_of_mass(axes: Axes, target: DVec3) -> Self {
        Self::new(TaskKind::CenterOfMass {
            axes,
            target,
            body: None,
        })
    }

    /// Attraction of `dofs` toward `reference`.
    pub fn posture(reference: Vec<f64>, dofs: Vec<usize>) -> Self {
        Self::new(TaskKind::PostureAttraction { reference, dofs })
    }

    /// Attraction of every rotational DOF of every non-root joint toward the rest posture.
    pub fn rest_posture(skeleton: &Skeleton) -> Self {
        let dofs = (0..skeleton.dof_count())
            .filter(|&d| skeleton.dof_joint(d) != 0 && skeleton.dof_kinds()[d].is_rotation())
            .collect();
        Self::posture(vec![0.0; skeleton.dof_count()], dofs)
    }

    /// Sets the level (builder style).
    pub fn at_level(mut self, level: u32) -> Self {
        self.level = level;
        self
    }

    /// Sets the weight (builder style).
    pub fn with_weight(mut self, weight: f64) -> Self {
        self.weight = weight;
        self
    }

    /// Sets the axes of a position or centre-of-mass task (builder style).
    pub fn with_axes(mut self, new_axes: Axes) -> Self {
        match &mut self.kind {
            TaskKind::Position { axes, .. }
            | TaskKind::CenterOfMass { axes, .. }
            | TaskKind::Meet { axes, .. } => *axes = new_axes,
            _ => {}
        }
        self
    }

    /// Sets the active flag (builder style).
    pub fn with_active(mut self, active: bool) -> Self {
        self.active = active;
        self
    }

    /// Number of Jacobian rows.
    pub fn rows(&self) -> usize {
        match &self.kind {
            TaskKind::Position { axes, .. }
            | TaskKind::CenterOfMass { axes, .. }
            | TaskKind::Meet { axes, .. } => axes.count(),
            TaskKind::Orientation { .. } => 3,
            TaskKind::Gaze { .. } | TaskKind::Direction { .. } | TaskKind::PointOnLine { .. } => 2,
            TaskKind::Balance { .. } | TaskKind::Comfort { .. } | TaskKind::PointOnPlane { .. } => {
                1
            }
            TaskKind::Collision(c) => c.rows(),
            TaskKind::PostureAttraction { dofs, .. } => dofs.len(),
        }
    }

    /// Whether the task is never "met": the posture attraction, or comfort.
    pub fn is_posture(&self) -> bool {
        matches!(
            self.kind,
            TaskKind::PostureAttraction { .. } | TaskKind::Comfort { .. }
        )
    }

    /// Whether the rows the task uses vary with the posture (collision: one per constraint
    /// found, at most [`Task::rows`]).
    pub fn rows_vary(&self) -> bool {
        matches!(self.kind, TaskKind::Collision(_))
    }

    /// Whether the task is a comfort task (its level goes on while its cost falls).
    pub fn is_comfort(&self) -> bool {
        matches!(self.kind, TaskKind::Comfort { .. })
    }

    /// A comfort task lowering `model`'s cost.
    pub fn comfort(model: ComfortModel) -> Self {
        Self::new(TaskKind::Comfort {
            model: Arc::new(model),
        })
    }

    /// Checks the task against a skeleton. `index` is used in the error.
    pub fn validate(&self, skeleton: &Skeleton, index: usize) -> Result<(), IkError> {
        let bad = |reason: String| IkError::BadTask { index, reason };
        let joint_ok = |j: usize| {
            if j < skeleton.joint_count() {
                Ok(())
            } else {
                Err(bad(format!("joint index {j} out of range")))
            }
        };
        let finite = |v: DVec3, what: &str| {
            if v.is_finite() {
                Ok(())
            } else {
                Err(bad(format!("{what} is not finite")))
            }
        };
        let body_ok = |body: Option<usize>| {
            let root = body.unwrap_or(0);
            joint_ok(root)?;
            if skeleton.body_mass(root) > 0.0 {
                Ok(())
            } else {
                Err(bad(format!(
                    "{} task on a body without mass",
                    if matches!(self.kind, TaskKind::Balance { .. }) {
                        "balance"
                    } else {
                        "centre-of-mass"
                    }
                )))
            }
        };
        if !(self.weight.is_finite() && self.weight >= 0.0) {
            return Err(bad("weight must be finite and >= 0".into()));
        }
        if self.level == 0 {
            return Err(bad("levels start at 1".into()));
        }
        match &self.kind {
            TaskKind::Position {
                effector, target, ..
            } => {
                joint_ok(effector.joint)?;
                finite(effector.point, "point")?;
                finite(*target, "target")?;
            }
            TaskKind::Orientation { joint, target } => {
                joint_ok(*joint)?;
                if !target.is_finite() || target.length() < 1e-9 {
                    return Err(bad("target quaternion must be finite and non-zero".into()));
                }
            }
            TaskKind::Gaze {
                effector,
                axis,
                target,
            } => {
                joint_ok(effector.joint)?;
                finite(effector.point, "point")?;
                finite(*target, "target")?;
                finite(*axis, "axis")?;
                if axis.length() < 1e-9 {
                    return Err(bad("gaze axis has zero length".into()));
                }
            }
            TaskKind::Direction {
                joint,
                axis,
                target,
            } => {
                joint_ok(*joint)?;
                finite(*axis, "axis")?;
                finite(*target, "target")?;
                if axis.length() < 1e-9 {
                    return Err(bad("direction axis has zero length".into()));
                }
                if target.length() < 1e-9 {
                    return Err(bad("target direction has zero length".into()));
                }
            }
            TaskKind::CenterOfMass { target, body, .. } => {
                finite(*target, "target")?;
                body_ok(*body)?;
            }
            TaskKind::Meet { a, b, .. } => {
                joint_ok(a.joint)?;
                joint_ok(b.joint)?;
                finite(a.point, "point a")?;
                finite(b.point, "point b")?;
            }
            TaskKind::Balance {
                support,
                margin,
                body,
            } => {
                if support.is_empty() {
                    return Err(bad("balance needs at least one support point".into()));
                }
                for s in support {
                    joint_ok(s.joint)?;
                    finite(s.point, "support point")?;
                }
                if !(margin.is_finite() && *margin >= 0.0) {
                    return Err(bad("margin must be finite and >= 0".into()));
                }
                body_ok(*body)?;
            }
            TaskKind::Comfort { model } => {
                model.validate(skeleton).map_err(bad)?;
            }
            TaskKind::Collision(c) => c.validate(skeleton).map_err(bad)?,
            TaskKind::PointOnLine {
                effector,
                origin,
                direction: vector,
            }
            | TaskKind::PointOnPlane {
                effector,
                origin,
                normal: vector,
                ..
            } => {
                joint_ok(effector.joint)?;
                finite(effector.point, "point")?;
                finite(*origin, "origin")?;
                let what = if matches!(self.kind, TaskKind::PointOnLine { .. }) {
                    "line direction"
                } else {
                    "plane normal"
                };
                finite(*vector, what)?;
                if vector.length() < 1e-9 {
                    return Err(bad(format!("{what} has zero length")));
                }
            }
            TaskKind::PostureAttraction { reference, dofs } => {
                if reference.len() != skeleton.dof_count() {
                    return Err(bad(format!(
                        "reference has {} values, the skeleton {} DOF",
                        reference.len(),
                        skeleton.dof_count()
                    )));
                }
                if reference.iter().any(|v| !v.is_finite()) {
                    return Err(bad("reference is not finite".into()));
                }
                if let Some(d) = dofs.iter().find(|&&d| d >= skeleton.dof_count()) {
                    return Err(bad(format!("DOF index {d} out of range")));
                }
            }
        }
        Ok(())
    }

    /// Posture indices of the possibly non-zero Jacobian columns.
    pub fn support(&self, skeleton: &Skeleton) -> Vec<usize> {
        match &self.kind {
            TaskKind::Position { effector, .. }
            | TaskKind::Gaze { effector, .. }
            | TaskKind::PointOnLine { effector, .. }
            | TaskKind::PointOnPlane { effector, .. } => skeleton.chain_dofs(effector.joint),
            TaskKind::Orientation { joint, .. } | TaskKind::Direction { joint, .. } => skeleton
                .chain_dofs(*joint)
                .into_iter()
                .filter(|&d| skeleton.dof_kinds()[d].is_rotation())
                .collect(),
            TaskKind::CenterOfMass { body, .. } => skeleton.body_dofs(body.unwrap_or(0)),
            TaskKind::Balance { body, support, .. } => {
                let mut d = skeleton.body_dofs(body.unwrap_or(0));
                if body.is_some_and(|root| root != 0) {
                    // The support points move the polygon: their chains count too.
                    for point in support {
                        d.extend(skeleton.chain_dofs(point.joint));
                    }
                    d.sort_unstable();
                    d.dedup();
                }
                d
            }
            TaskKind::Meet { a, b, .. } => {
                let mut d = skeleton.chain_dofs(a.joint);
                d.extend(skeleton.chain_dofs(b.joint));
                d.sort_unstable();
                d.dedup();
                d
            }
            TaskKind::Collision(c) => c.support(skeleton),
            TaskKind::Comfort { .. } => (0..skeleton.dof_count())
                .filter(|&d| skeleton.dof_kinds()[d].is_rotation())
                .collect(),
            TaskKind::PostureAttraction { dofs, .. } => {
                let mut d = dofs.clone();
                d.sort_unstable();
                d.dedup();
                d
            }
        }
    }
}

/// `tasks` with their collision tasks leaving off the parts the others place on a solid or
/// the floor (see [`Collision::with_contacts`]): an active point-on-plane task that keeps its
/// point on the plane (not `above` it) places its joint on the solid whose surface holds the
/// plane's origin (a hand on a table top); a point-on-line task, on the solid that holds the
/// line's origin (a hand on a bar, round its axis); a position task on every axis, on the
/// solid or the floor whose surface holds its target (a hand on a ball, on the floor; not a
/// target inside a solid, which the collision task keeps the part out of).
/// Problem files, documents and the editor's frames alike.
pub fn with_placed_parts(skeleton: &Skeleton, tasks: &mut [Task]) {
    let placed: Vec<(usize, DVec3, bool)> = tasks
        .iter()
        .filter(|t| t.active)
        .filter_map(|t| match &t.kind {
            TaskKind::PointOnPlane {
                effector,
                origin,
                above: false,
                ..
            } => Some((effector.joint, *origin, false)),
            TaskKind::PointOnLine {
                effector, origin, ..
            } => Some((effector.joint, *origin, true)),
            TaskKind::Position {
                effector,
                axes,
                target,
            } if *axes == Axes::XYZ => Some((effector.joint, *target, false)),
            _ => None,
        })
        .collect();
    if placed.is_empty() {
        return;
    }
    for task in tasks.iter_mut() {
        if let TaskKind::Collision(c) = &task.kind {
            task.kind = TaskKind::Collision(c.clone().with_contacts(skeleton, &placed));
        }
    }
}

/// What a task measures, for finite-difference checks: a vector whose derivative is the
/// Jacobian, or (orientation) a rotation whose angular velocity is the Jacobian.
#[derive(Debug, Clone, PartialEq)]
pub enum TaskFeature {
    /// Rows of the Jacobian are the derivatives of these values.
    Vector(Vec<f64>),
    /// Rows of the Jacobian are the world angular velocity of this rotation.
    Rotation(DQuat),
}

/// Step limits applied to a task's desired change.
#[derive(Debug, Clone, Copy)]
pub(crate) struct StepLimits {
    pub linear: f64,
    pub angular: f64,
}
