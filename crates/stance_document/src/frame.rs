//! The problem of one frame of interactive posing: the document's tasks and what the pointer
//! is doing (a part held where it stands, a point pulled along). One builder for the editor's
//! posing session and the `stance-ik` package's per-frame solver.

use glam::DVec3;
use stance_hanim::HumanoidSkeleton;
use stance_ik::{Collision, Obstacle, Skeleton, Task, TaskKind};

use crate::{TaskKindSpec, TaskSpec};

/// Grab-and-pull's temporary task: a point of a segment pulled toward the pointer, below every
/// hard task (the body follows while higher priorities hold).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grab {
    /// The joint whose segment was grabbed.
    pub joint: usize,
    /// The grabbed point in that joint's frame (m).
    pub point_local: DVec3,
    /// Where the pointer wants the point (m, world).
    pub target_world: DVec3,
}

/// What one frame solves.
#[derive(Debug, Clone, Copy)]
pub struct FrameProblem<'a> {
    /// The document's tasks.
    pub specs: &'a [TaskSpec],
    /// Whether the comfort tasks take part (while a part is pulled or held the body follows
    /// the pointer; comfort settles the posture once it is let go).
    pub comfort: bool,
    /// A joint held where it stands (world position), at level 1.
    pub held: Option<(usize, DVec3)>,
    /// The point being pulled.
    pub grab: Option<Grab>,
    /// Fixed solids the collision tasks hold the body off (the scene's props, in the
    /// character's frame).
    pub obstacles: &'a [Obstacle],
    /// Collision tasks already built for this body, by their kind (with `obstacles`): a
    /// collision spec found here is not built again (its capsules' pairs cost a search over
    /// every pair at rest).
    pub collisions: &'a [(TaskKindSpec, Collision)],
}

/// The level just below every hard (not soft) task of `specs`: where a pull goes, and a task
/// the user adds.
pub fn level_below_hard_tasks(specs: &[TaskSpec]) -> u32 {
    specs
        .iter()
        .filter(|task| !task.kind.is_soft())
        .map(|task| task.level)
        .max()
        .unwrap_or(0)
        + 1
}

impl FrameProblem<'_> {
    /// The solver tasks on `skeleton` (on a built `body` when given: its comfort tasks read its
    /// own anatomical axes): every task that converts (one that does not is left out; its
    /// status says why), the held joint at level 1, the pull one level below every hard task;
    /// the collision tasks leave off the parts placed on a surface
    /// ([`stance_ik::with_placed_parts`]).
    pub fn tasks(&self, skeleton: &Skeleton, body: Option<&HumanoidSkeleton>) -> Vec<Task> {
        let mut tasks = Vec::with_capacity(self.specs.len() + 2);
        for spec in self.specs {
            if !self.comfort && matches!(spec.kind, TaskKindSpec::Comfort { .. }) {
                continue;
            }
            if let Some((_, built)) = self.collisions.iter().find(|(kind, _)| *kind == spec.kind) {
                tasks.push(Task {
                    kind: TaskKind::Collision(built.clone()),
                    level: spec.level,
                    weight: spec.weight,
                    active: spec.active,
                });
                continue;
            }
            if let Ok(converted) = spec.solver_tasks_with(skeleton, body, self.specs) {
                tasks.extend(converted.into_iter().map(|mut task| {
                    if let TaskKind::Collision(c) = &task.kind
                        && !self.obstacles.is_empty()
                    {
                        task.kind =
                            TaskKind::Collision(c.clone().with_obstacles(self.obstacles.to_vec()));
                    }
                    task
                }));
            }
        }
        // The document's tasks place parts; the held joint and the pull do not.
        stance_ik::with_placed_parts(skeleton, &mut tasks);
        if let Some((joint, position)) = self.held {
            tasks.push(Task::position(joint, DVec3::ZERO, position).at_level(1));
        }
        if let Some(grab) = self.grab {
            tasks.push(
                Task::position(grab.joint, grab.point_local, grab.target_world)
                    .at_level(level_below_hard_tasks(self.specs)),
            );
        }
        tasks
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use stance_hanim::{SkeletonOptions, default_skeleton};

    use super::*;

    /// The pull goes one level below every hard task (soft ones aside), the held joint at
    /// level 1; comfort only when asked; a task the body cannot hold is left out.
    #[test]
    fn a_frame_holds_the_tasks_a_held_joint_and_a_pull_below_them() {
        let body = default_skeleton(&SkeletonOptions::default()).unwrap();
        let s = &body.skeleton;
        let specs: Vec<TaskSpec> = serde_json::from_str(
            r#"[{"kind":"position","joint":"l_talocrural","target":[0.1,0.08,0]},
                {"kind":"balance","level":2},
                {"kind":"position","joint":"l_tail","target":[0,0,0],"level":3},
                {"kind":"comfort","level":10}]"#,
        )
        .unwrap();
        let wrist = s.joint_index("r_radiocarpal").unwrap();
        let grab = Grab {
            joint: wrist,
            point_local: DVec3::ZERO,
            target_world: DVec3::new(0.0, 2.0, 1.0),
        };
        let frame = FrameProblem {
            specs: &specs,
            comfort: false,
            held: Some((wrist, DVec3::ONE)),
            grab: Some(grab),
            obstacles: &[],
            collisions: &[],
        };
        let tasks = frame.tasks(s, Some(&body));
        let summary: Vec<(u32, bool)> = tasks
            .iter()
            .map(|t| (t.level, matches!(t.kind, TaskKind::Position { .. })))
            .collect();
        // The unknown joint's task and comfort are left out; the pull goes below level 3
        // (the left-out task's level still counts: its status says why it is missing).
        assert_eq!(summary, [(1, true), (2, false), (1, true), (4, true)]);
        let with_comfort = FrameProblem {
            comfort: true,
            grab: None,
            held: None,
            ..frame
        }
        .tasks(s, Some(&body));
        assert_eq!(with_comfort.len(), 3);
        assert_eq!(with_comfort[2].level, 10);
    }
}
