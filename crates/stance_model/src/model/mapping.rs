//! The avatar mapping corrections kept for the session: each avatar's automatic mapping and
//! the batches of corrections applied to it, made again when the same file is opened again
//! and reverted one batch at a time.

use std::collections::BTreeMap;

use glam::{DQuat, DVec3};
use stance_document::TaskSpec;
use stance_hanim::{HumanoidSkeleton, LevelOfArticulation, Mapping, MappingError};
use stance_ik::{Posture, Skeleton};

use crate::avatar::LoadedAvatar;
use crate::posing::PosingSession;

/// One correction: source joint (node index) `source` drives `hanim`, or nothing.
#[derive(Debug, Clone, PartialEq)]
pub struct Correction {
    /// The avatar's joint (index of its node in the file).
    pub source: usize,
    /// The H-Anim joint it drives from now on; `None` takes its mapping away.
    pub hanim: Option<&'static str>,
}

impl Correction {
    /// Makes the correction in `mapping`.
    pub fn apply(&self, mapping: &mut Mapping) -> Result<(), MappingError> {
        match self.hanim {
            Some(hanim) => mapping.set(hanim, self.source),
            None => {
                if let Some(hanim) = mapping.hanim_of(self.source) {
                    mapping.remove(hanim);
                }
                Ok(())
            }
        }
    }
}

/// The corrections applied to one avatar (by name) during the session.
#[derive(Debug)]
struct AvatarCorrections {
    /// The mapping the file got on import.
    automatic: Mapping,
    /// Each applied batch, oldest first.
    applied: Vec<Vec<Correction>>,
}

impl AvatarCorrections {
    /// The automatic mapping with the first `batches` batches applied.
    fn mapping(&self, batches: usize) -> Result<Mapping, MappingError> {
        let mut mapping = self.automatic.clone();
        for correction in self.applied.iter().take(batches).flatten() {
            correction.apply(&mut mapping)?;
        }
        Ok(mapping)
    }
}

/// Every avatar's corrections, by avatar name.
#[derive(Debug, Default)]
pub struct MappingCorrections {
    by_avatar: BTreeMap<String, AvatarCorrections>,
}

impl MappingCorrections {
    /// An avatar file was imported: when the user corrected an avatar of that name earlier in
    /// the session (the same file: same automatic mapping), those corrections are made again
    /// and `humanoid` rebuilt. Returns a line for the load message.
    pub fn reapply(
        &mut self,
        avatar: &mut LoadedAvatar,
        loa: LevelOfArticulation,
        humanoid: &mut HumanoidSkeleton,
    ) -> Option<String> {
        let entry = self.by_avatar.get(&avatar.name)?;
        if entry.automatic != avatar.avatar.mapping {
            // Another file under the same name: its joints are not the same.
            self.by_avatar.remove(&avatar.name);
            return None;
        }
        if entry.applied.is_empty() {
            return None;
        }
        let count: usize = entry.applied.iter().map(Vec::len).sum();
        let rebuilt = entry
            .mapping(entry.applied.len())
            .map_err(|error| error.to_string())
            .and_then(|mapping| {
                let built = avatar.skeleton_with_mapping(&mapping, loa)?;
                Ok((mapping, built))
            });
        match rebuilt {
            Ok((mapping, built)) => {
                avatar.avatar.mapping = mapping;
                *humanoid = built;
                Some(format!(
                    "Your {count} mapping correction(s) of this session were made again."
                ))
            }
            Err(error) => {
                self.by_avatar.remove(&avatar.name);
                Some(format!(
                    "Your mapping corrections could not be made again ({error}); the automatic mapping is used."
                ))
            }
        }
    }

    /// Remembers a batch applied to `avatar` (whose mapping was `before` the first batch).
    pub fn remember(&mut self, avatar: String, before: Mapping, batch: Vec<Correction>) {
        self.by_avatar
            .entry(avatar)
            .or_insert_with(|| AvatarCorrections {
                automatic: before,
                applied: Vec::new(),
            })
            .applied
            .push(batch);
    }

    /// The mapping before the last batch applied to `avatar`; `None` when there is none.
    pub fn before_last(&self, avatar: &str) -> Option<Result<Mapping, MappingError>> {
        let entry = self.by_avatar.get(avatar)?;
        let last = entry.applied.len().checked_sub(1)?;
        Some(entry.mapping(last))
    }

    /// Forgets the last batch applied to `avatar` (it was reverted).
    pub fn forget_last(&mut self, avatar: &str) {
        if let Some(entry) = self.by_avatar.get_mut(avatar) {
            entry.applied.pop();
        }
    }
}

/// Each joint of the file whose H-Anim joint differs between `before` and `after`, in words.
pub fn describe_changes(avatar: &LoadedAvatar, before: &Mapping, after: &Mapping) -> Vec<String> {
    avatar
        .joint_nodes()
        .into_iter()
        .filter(|&source| before.hanim_of(source) != after.hanim_of(source))
        .map(|source| {
            let node = avatar
                .avatar
                .nodes
                .get(source)
                .map_or("?", |node| node.name.as_str());
            match after.hanim_of(source) {
                Some(hanim) => format!("{node} drives {hanim}"),
                None => format!("{node} drives no joint"),
            }
        })
        .collect()
}

/// The first changes in a line.
pub fn summarize(changes: &[String]) -> String {
    const SHOWN: usize = 4;
    let mut text = changes
        .iter()
        .take(SHOWN)
        .cloned()
        .collect::<Vec<_>>()
        .join(", ");
    if changes.len() > SHOWN {
        text.push_str(&format!(" and {} more", changes.len() - SHOWN));
    }
    if text.is_empty() {
        text.push_str("no joint changed");
    }
    text
}

/// The posture of `old` on `skeleton`, by joint name: each joint keeps its world rotation (a
/// joint new to the skeleton turns with its parent), projected onto its DOF; the root keeps
/// its translation.
pub fn carry_posture(old: &PosingSession, skeleton: &Skeleton) -> Option<Posture> {
    let old_skeleton = old.skeleton();
    let frames = old.frames();
    let mut world: Vec<DQuat> = Vec::with_capacity(skeleton.joint_count());
    for joint in skeleton.joints() {
        let own = old_skeleton
            .joint_index(&joint.name)
            .filter(|&index| index < frames.world_from_joint_rotation.len())
            .map(|index| frames.rotation(index).normalize());
        let inherited = joint.parent.and_then(|parent| world.get(parent).copied());
        world.push(own.or(inherited).unwrap_or(DQuat::IDENTITY));
    }
    let locals: Vec<DQuat> = skeleton
        .joints()
        .iter()
        .zip(&world)
        .map(
            |(joint, rotation)| match joint.parent.and_then(|parent| world.get(parent)) {
                Some(parent) => (parent.inverse() * *rotation).normalize(),
                None => *rotation,
            },
        )
        .collect();
    let values = old.posture().values();
    let mut translation = DVec3::ZERO;
    if let Some(root) = old_skeleton.joints().first() {
        for axis in 0..3 {
            if let Some(value) = root.translation_dof[axis].and_then(|dof| values.get(dof)) {
                translation[axis] = *value;
            }
        }
    }
    Posture::from_rotations(skeleton, translation, &locals).ok()
}

/// A session on `humanoid` carrying the current one over: the posture by joint name
/// (each joint keeps its world rotation), the tasks that still fit. Returns the session
/// and the dropped tasks, described.
pub fn rebuilt_session(
    old: &PosingSession,
    humanoid: HumanoidSkeleton,
) -> Result<(PosingSession, Vec<String>), String> {
    let mut session = PosingSession::with_humanoid(humanoid).map_err(|error| error.to_string())?;
    let (kept, dropped): (Vec<TaskSpec>, Vec<TaskSpec>) = old
        .tasks()
        .iter()
        .cloned()
        .partition(|task| task.to_solver_tasks(session.skeleton(), &[]).is_ok());
    if let Some(posture) = carry_posture(old, session.skeleton()) {
        session.set_posture(posture);
    }
    session.set_tasks(kept);
    Ok((session, dropped.iter().map(TaskSpec::description).collect()))
}

/// What a rebuilt skeleton kept and dropped, for the notice.
pub fn rebuilt_summary(session: &PosingSession, dropped: &[String]) -> String {
    let skeleton = session.skeleton();
    let mut text = format!(
        "the skeleton was rebuilt ({} joints, {} DOF); the posture and {} task(s) carried over.",
        skeleton.joint_count(),
        skeleton.dof_count(),
        session.tasks().len()
    );
    if !dropped.is_empty() {
        text.push_str(&format!(
            " Dropped, their joints are gone: {}.",
            dropped.join(", ")
        ));
    }
    text
}

#[cfg(test)]
mod tests {
    use stance_hanim::LevelOfArticulation;

    use super::*;

    #[test]
    fn a_posture_carries_over_by_joint_name() {
        let mut old = PosingSession::new(LevelOfArticulation::Loa2).unwrap();
        let elbow = old.skeleton().joint_index("l_elbow").unwrap();
        let dof = old.skeleton().joints()[elbow].dof_start;
        old.set_dof(dof, 0.7);
        let target = PosingSession::new(LevelOfArticulation::Loa1).unwrap();
        let carried = carry_posture(&old, target.skeleton()).unwrap();
        let frames = stance_ik::Frames::new(target.skeleton(), &carried);
        let new_elbow = target.skeleton().joint_index("l_elbow").unwrap();
        let angle = frames
            .rotation(new_elbow)
            .angle_between(old.frames().rotation(elbow));
        assert!(angle < 1e-6, "the elbow turned {angle} rad away");
    }
}
