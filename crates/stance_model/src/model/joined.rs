//! Characters joined by tasks between them (a hand in another's hand) are posed together:
//! while the selected character is joined to others, each frame solves their bodies as one
//! prioritized problem (`stance_ik::Bodies`): every member's frame tasks (the selected one's
//! pull and held joint included) in the scene through its placement, the tasks between them,
//! and the solved postures handed back to each member's session. Their collision tasks join
//! into one that also keeps them apart; comfort is built for one body and waits while the
//! characters are joined.

use stance_document::{
    BetweenTask, CharacterPoint, body_placement, joined_groups_of, joined_tasks,
};
use stance_ik::{Bodies, Clock, Posture, Skeleton, Solver, Task};

use super::EditorModel;
use super::cast::Character;
use crate::posing::PosingSession;

/// What a task between characters names on the selected character and another one.
#[derive(Debug, Clone, PartialEq)]
pub struct NewBetween {
    /// The selected character's part (skeleton index of its joint).
    pub joint: usize,
    /// The other character (its id).
    pub other: u64,
    /// The other character's part (its H-Anim joint name).
    pub other_joint: String,
}

impl EditorModel {
    /// The tasks between characters, with the characters' places in the scene's order.
    pub fn between_tasks(&self) -> &[BetweenTask] {
        self.cast_between()
    }

    /// The scene indices of the characters posed with the selected one, itself included, in
    /// the scene's order; just the selected one when no active task joins it to another.
    pub fn joined_with_selected(&self) -> Vec<usize> {
        let selected = self.selected_index();
        joined_groups_of(self.character_count(), self.cast_between())
            .into_iter()
            .find(|group| group.contains(&selected))
            .unwrap_or_else(|| vec![selected])
    }

    /// The frame's solve when the selected character is joined to others: returns false (and
    /// does nothing) when it is not, so that its session solves alone.
    pub(super) fn solve_joined_frame(&mut self, clock: Option<&dyn Clock>) -> bool {
        let group = self.joined_with_selected();
        if group.len() < 2 {
            return false;
        }
        let between = self.cast_between().to_vec();
        let waiting = self.pending_document.is_some();
        let mut members = self.members_mut(&group);
        // Joined characters wait while the selected one's avatar is on its way (solved on the
        // mannequin's proportions, they would all move before it arrives and is given to the
        // others waiting for it).
        if waiting || members.iter().all(|m| m.session.is_settled()) {
            return true;
        }
        let joined = match joined_problem(&members, &group, &between) {
            Ok(joined) => joined,
            Err(message) => {
                log::warn!("joined solve: {message}");
                return false;
            }
        };
        let (bodies, tasks, mut posture) = joined;
        let solver = self.cast_solver();
        let report = match solver.solve_with_clock(bodies.skeleton(), &tasks, &mut posture, clock) {
            Ok(report) => report,
            Err(error) => {
                log::warn!("joined solve: {error}");
                return false;
            }
        };
        let Ok(postures) = bodies.split(&posture) else {
            return false;
        };
        members = self.members_mut(&group);
        for (member, posture) in members.iter_mut().zip(postures) {
            member.session.take_joined_solve(posture, report.clone());
            member.refresh_bones();
        }
        true
    }

    /// Adds a meet between the selected character's part and another character's, one level
    /// below the hard tasks of both (undone with the cast).
    pub(super) fn add_between(&mut self, new: NewBetween) -> super::Change {
        let selected = self.selected_index();
        let Some(other) = self.characters().position(|(c, _)| c.id() == new.other) else {
            return super::Change::Nothing;
        };
        let Some(joint) = self.character.session.skeleton().joints().get(new.joint) else {
            return super::Change::Nothing;
        };
        let joint = joint.name.clone();
        let level = self
            .members_mut(&[selected, other])
            .iter()
            .map(|m| stance_document::level_below_hard_tasks(m.session.tasks()))
            .max()
            .unwrap_or(1);
        let task = BetweenTask::meet(
            CharacterPoint {
                character: selected,
                joint,
                point: [0.0; 3],
            },
            CharacterPoint {
                character: other,
                joint: new.other_joint,
                point: [0.0; 3],
            },
            level,
        );
        let description = self.between_description(&task);
        self.edit_between(|between| between.push(task));
        self.inform(format!("{description} (level {level})."));
        super::Change::Document
    }

    /// Removes the task between characters at `index`.
    pub(super) fn remove_between(&mut self, index: usize) -> super::Change {
        if index >= self.cast_between().len() {
            return super::Change::Nothing;
        }
        self.edit_between(|between| {
            between.remove(index);
        });
        super::Change::Document
    }

    /// How far apart each task between characters holds its two points now (m, in the
    /// scene); `None` where a character or joint is missing.
    pub fn between_distances(&self) -> Vec<Option<f64>> {
        self.cast_between()
            .iter()
            .map(|task| {
                let a = self.point_in_scene(&task.a)?;
                let b = self.point_in_scene(&task.b)?;
                Some((a - b).length())
            })
            .collect()
    }

    fn point_in_scene(&self, p: &CharacterPoint) -> Option<glam::DVec3> {
        let (character, _) = self.characters().nth(p.character)?;
        let session = character.session();
        let joint = session.skeleton().joint_index(&p.joint)?;
        let local = session
            .frames()
            .point(joint, glam::DVec3::from_array(p.point));
        Some(
            character
                .placement()
                .scene_from_character()
                .transform_point3(local),
        )
    }

    /// Hands held with the character `other`: the selected character's hand and the other's
    /// that stand nearest each other now (side by side, the hands between them; face to
    /// face, the hands on the same side of the space between them).
    pub fn hands_toward(&self, other: u64) -> Option<NewBetween> {
        let selected = self.selected_index();
        let index = self.characters().position(|(c, _)| c.id() == other)?;
        let hands = ["l_radiocarpal", "r_radiocarpal"];
        let mut best: Option<(f64, &str, &str)> = None;
        for mine in hands {
            for theirs in hands {
                let at = |character: usize, joint: &str| {
                    self.point_in_scene(&CharacterPoint {
                        character,
                        joint: joint.to_owned(),
                        point: [0.0; 3],
                    })
                };
                let (Some(a), Some(b)) = (at(selected, mine), at(index, theirs)) else {
                    continue;
                };
                let d = (a - b).length();
                if best.is_none_or(|(bd, _, _)| d < bd) {
                    best = Some((d, mine, theirs));
                }
            }
        }
        let (_, mine, theirs) = best?;
        Some(NewBetween {
            joint: self.character.session.skeleton().joint_index(mine)?,
            other,
            other_joint: theirs.to_owned(),
        })
    }

    /// "Ann's right hand meets Bo's left hand".
    pub fn between_description(&self, task: &BetweenTask) -> String {
        let part = |p: &CharacterPoint| {
            let name = self.characters().nth(p.character).map_or_else(
                || format!("character {}", p.character + 1),
                |(c, _)| c.name().to_owned(),
            );
            format!("{name}'s {}", stance_hanim::readable_name(&p.joint))
        };
        format!("{} meets {}", part(&task.a), part(&task.b))
    }

    /// The characters at the scene indices `group`, in the scene's order (the selected one
    /// among them when it is in `group`).
    pub(super) fn members_mut(&mut self, group: &[usize]) -> Vec<&mut Character> {
        let selected = self.selected_index();
        let (others, character) = self.cast_and_selected_mut();
        let mut picked: Vec<(usize, &mut Character)> = others
            .iter_mut()
            .enumerate()
            .map(|(i, c)| (if i < selected { i } else { i + 1 }, c))
            .filter(|(i, _)| group.contains(i))
            .collect();
        if group.contains(&selected) {
            picked.push((selected, character));
        }
        picked.sort_by_key(|(i, _)| *i);
        picked.into_iter().map(|(_, c)| c).collect()
    }
}

type Joined = (Bodies, Vec<Task>, Posture);

/// The joined problem of `members` (the characters `group`, in order): their bodies placed,
/// every member's frame tasks moved onto them (those that cannot move left out), the tasks
/// `between` them, and their postures joined.
fn joined_problem(
    members: &[&mut Character],
    group: &[usize],
    between: &[BetweenTask],
) -> Result<Joined, String> {
    if members.len() != group.len() {
        return Err(format!(
            "{} characters for a group of {}",
            members.len(),
            group.len()
        ));
    }
    let placed: Vec<(&Skeleton, stance_ik::BodyPlacement)> = members
        .iter()
        .map(|m| (m.session().skeleton(), body_placement(&m.placement())))
        .collect();
    let bodies = Bodies::new(&placed).map_err(|e| e.to_string())?;
    let frame_tasks: Vec<Vec<Task>> = members.iter().map(|m| m.session().frame_tasks()).collect();
    let own: Vec<&[Task]> = frame_tasks.iter().map(Vec::as_slice).collect();
    let skeletons: Vec<&Skeleton> = members.iter().map(|m| m.session().skeleton()).collect();
    // Comfort, built for one body, waits while the characters are joined.
    let (tasks, _) =
        joined_tasks(&bodies, group, &own, &skeletons, between).map_err(|e| e.to_string())?;
    let postures: Vec<&Posture> = members.iter().map(|m| m.session().posture()).collect();
    let posture = bodies.posture(&postures).map_err(|e| e.to_string())?;
    Ok((bodies, tasks, posture))
}

/// A solver for joined frames, with a session's frame settings.
pub(super) fn joined_solver() -> Solver {
    Solver::new(PosingSession::frame_settings()).unwrap_or_default()
}
