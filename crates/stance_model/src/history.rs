//! Undo and redo of every edit: snapshots of a character's document taken before each edit
//! of it, and of the cast (the scene's characters) before each change of it.
//!
//! An edit that goes on over many frames (dragging a value, pulling a body part) is one step:
//! edits with the same [`EditKind`] that follow each other within [`COALESCE_SECS`] merge.

use stance_document::{BetweenTask, Document, Placement, Prop};
use stance_hanim::hands::Finger;

use crate::model::Hands;

/// How far back undo goes.
pub const MAX_UNDO_STEPS: usize = 200;
/// Successive edits of the same kind closer than this merge into one undo step.
pub const COALESCE_SECS: f64 = 0.75;

/// What an edit touched; successive edits of the same kind coalesce.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum EditKind {
    /// A one-off command (add, remove, reset, mirror, load...): never merges.
    Command,
    /// A field of a task, by task position and field name.
    TaskField(usize, &'static str),
    /// A DOF of a joint edited directly.
    Joint(usize),
    /// The stiffness of a DOF.
    Stiffness(usize),
    /// A grab-and-pull gesture.
    Pull,
    /// The swivel angle of a limb.
    Swivel(usize),
    /// The curl of a finger (the whole hand for `None`) of some hands.
    HandCurl(Hands, Option<Finger>),
    /// A character's name or place, edited over frames.
    Cast,
}

/// A character's place in the cast as the history keeps it.
#[derive(Debug, Clone, PartialEq)]
pub struct CastEntry {
    /// The character's id.
    pub id: u64,
    /// Its name.
    pub name: String,
    /// Where it stood.
    pub placement: Placement,
}

/// The scene as it was apart from the characters' documents: the characters' order, names and
/// placements, the selected one, and the props.
#[derive(Debug, Clone, PartialEq)]
pub struct CastSnapshot {
    /// The characters in the scene's order.
    pub order: Vec<CastEntry>,
    /// The selected character's id.
    pub selected: u64,
    /// The props.
    pub props: Vec<Prop>,
    /// The tasks between characters.
    pub between: Vec<BetweenTask>,
}

/// One step back or forward.
#[derive(Debug, Clone, PartialEq)]
pub enum Step {
    /// An edit of one character: its document before, and for a change of body (an avatar
    /// swap, back to the mannequin) the body to bring back, as the editor stored it (see
    /// [`crate::model::EditorModel`]'s kept bodies).
    Edit {
        /// The character's id.
        character: u64,
        /// Its document.
        document: Box<Document>,
        /// The body to bring back.
        body: Option<u64>,
    },
    /// A change of the cast (a character added, duplicated, removed, renamed, moved).
    Cast(CastSnapshot),
}

/// What the next undo or redo changes: the caller selects that character and passes its
/// state as it is now ([`History::undo`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pending {
    /// An edit of the character `character`; `changes_body`: its body changes back.
    Edit {
        /// The character's id.
        character: u64,
        /// Whether the step changes the body.
        changes_body: bool,
    },
    /// The cast.
    Cast,
}

impl Step {
    fn pending(&self) -> Pending {
        match self {
            Step::Edit {
                character, body, ..
            } => Pending::Edit {
                character: *character,
                changes_body: body.is_some(),
            },
            Step::Cast(_) => Pending::Cast,
        }
    }
}

/// The undo and redo stacks.
#[derive(Debug, Default)]
pub struct History {
    undo: Vec<Step>,
    redo: Vec<Step>,
    /// The last edit: of which character (`None`: the cast), what, when.
    last_edit: Option<(Option<u64>, EditKind, f64)>,
}

impl History {
    /// Records `before`, the document of the character `character` as it was before an edit
    /// of `kind` at `now_secs`. Returns whether a new undo step was made (false when it merged
    /// with the previous one).
    pub fn record(
        &mut self,
        character: u64,
        before: &Document,
        kind: EditKind,
        now_secs: f64,
    ) -> bool {
        if self.merges(Some(character), kind, now_secs) {
            return false;
        }
        let unchanged = matches!(self.undo.last(), Some(Step::Edit { character: last, document, body: None })
            if *last == character && **document == *before);
        if unchanged {
            return false;
        }
        self.push_undo(Step::Edit {
            character,
            document: Box::new(before.clone()),
            body: None,
        });
        true
    }

    /// Whether an edit of `kind` on `character` at `now_secs` merges with the last one (and
    /// notes it as the last edit; the redo stack empties either way).
    fn merges(&mut self, character: Option<u64>, kind: EditKind, now_secs: f64) -> bool {
        let merges = kind != EditKind::Command
            && self
                .last_edit
                .as_ref()
                .is_some_and(|(last_character, last_kind, last_secs)| {
                    *last_character == character
                        && *last_kind == kind
                        && (now_secs - last_secs).abs() < COALESCE_SECS
                })
            && !self.undo.is_empty();
        self.last_edit = Some((character, kind, now_secs));
        self.redo.clear();
        merges
    }

    /// Records a change of body of the character `character`: `before`, its document before
    /// it, and `body`, the stored body that undo brings back. Always a step of its own.
    pub fn record_body_change(
        &mut self,
        character: u64,
        before: &Document,
        body: u64,
        now_secs: f64,
    ) {
        self.last_edit = Some((Some(character), EditKind::Command, now_secs));
        self.redo.clear();
        self.push_undo(Step::Edit {
            character,
            document: Box::new(before.clone()),
            body: Some(body),
        });
    }

    /// Records `before`, the cast as it was before a change at `now_secs`; `coalesce`: the
    /// change goes on over frames (a drag, typing a name) and merges with the last one of its
    /// kind.
    pub fn record_cast(&mut self, before: CastSnapshot, coalesce: bool, now_secs: f64) {
        let kind = if coalesce {
            EditKind::Cast
        } else {
            EditKind::Command
        };
        if self.merges(None, kind, now_secs) {
            return;
        }
        self.push_undo(Step::Cast(before));
    }

    fn push_undo(&mut self, step: Step) {
        self.undo.push(step);
        if self.undo.len() > MAX_UNDO_STEPS {
            self.undo.remove(0);
        }
    }

    /// Ends the current gesture: the next edit starts a new undo step even if of the same kind.
    pub fn break_coalescing(&mut self) {
        self.last_edit = None;
    }

    /// What the next undo changes.
    pub fn next_undo(&self) -> Option<Pending> {
        self.undo.last().map(Step::pending)
    }

    /// What the next redo changes.
    pub fn next_redo(&self) -> Option<Pending> {
        self.redo.last().map(Step::pending)
    }

    /// The step to go back to; `current` (the state [`Self::next_undo`] names, as it is now)
    /// becomes redoable.
    pub fn undo(&mut self, current: Step) -> Option<Step> {
        let previous = self.undo.pop()?;
        self.redo.push(current);
        self.last_edit = None;
        Some(previous)
    }

    /// The step to go forward to; `current` becomes undoable.
    pub fn redo(&mut self, current: Step) -> Option<Step> {
        let next = self.redo.pop()?;
        self.undo.push(current);
        self.last_edit = None;
        Some(next)
    }

    /// Drops the next undo (`back`) or redo step without taking it.
    pub fn discard(&mut self, back: bool) {
        if back {
            self.undo.pop();
        } else {
            self.redo.pop();
        }
    }

    /// The stored bodies the steps refer to.
    pub fn bodies(&self) -> impl Iterator<Item = u64> + '_ {
        self.undo
            .iter()
            .chain(&self.redo)
            .filter_map(|step| match step {
                Step::Edit { body, .. } => *body,
                Step::Cast(_) => None,
            })
    }

    /// The characters the steps of the cast name.
    pub fn characters(&self) -> impl Iterator<Item = u64> + '_ {
        self.undo
            .iter()
            .chain(&self.redo)
            .filter_map(|step| match step {
                Step::Cast(snapshot) => Some(snapshot.order.iter().map(|entry| entry.id)),
                Step::Edit { .. } => None,
            })
            .flatten()
    }

    /// Whether there is an edit to take back.
    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }

    /// Whether there is an edit taken back to do again.
    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }

    /// How many edits can be taken back (at most [`MAX_UNDO_STEPS`]).
    pub fn undo_steps(&self) -> usize {
        self.undo.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use stance_document::{TaskKindSpec, TaskSpec};

    fn document_with(tasks: usize) -> Document {
        Document {
            tasks: (0..tasks)
                .map(|_| {
                    TaskSpec::new(TaskKindSpec::Posture {
                        joints: None,
                        reference: None,
                    })
                })
                .collect(),
            ..Document::default()
        }
    }

    const A: u64 = 0;
    const B: u64 = 1;

    fn edit(character: u64, document: &Document, body: Option<u64>) -> Step {
        Step::Edit {
            character,
            document: Box::new(document.clone()),
            body,
        }
    }

    fn cast(ids: &[u64], selected: u64) -> CastSnapshot {
        CastSnapshot {
            order: ids
                .iter()
                .map(|&id| CastEntry {
                    id,
                    name: format!("Character {id}"),
                    placement: Placement::default(),
                })
                .collect(),
            selected,
            props: Vec::new(),
            between: Vec::new(),
        }
    }

    #[test]
    fn undo_then_redo_walks_back_and_forth_exactly() {
        let mut history = History::default();
        let (zero, one, two) = (document_with(0), document_with(1), document_with(2));
        history.record(A, &zero, EditKind::Command, 0.0);
        history.record(A, &one, EditKind::Command, 0.1);
        assert_eq!(history.undo(edit(A, &two, None)), Some(edit(A, &one, None)));
        assert_eq!(
            history.undo(edit(A, &one, None)),
            Some(edit(A, &zero, None))
        );
        assert_eq!(history.undo(edit(A, &zero, None)), None);
        assert_eq!(
            history.redo(edit(A, &zero, None)),
            Some(edit(A, &one, None))
        );
        assert_eq!(history.redo(edit(A, &one, None)), Some(edit(A, &two, None)));
        assert!(!history.can_redo());
    }

    #[test]
    fn a_drag_is_one_step_and_a_new_edit_clears_redo() {
        let mut history = History::default();
        let zero = document_with(0);
        assert!(history.record(A, &zero, EditKind::TaskField(0, "weight"), 0.0));
        for frame in 1..30 {
            let merged = !history.record(
                A,
                &document_with(frame),
                EditKind::TaskField(0, "weight"),
                f64::from(frame as u32) * 0.016,
            );
            assert!(merged);
        }
        assert_eq!(history.undo_steps(), 1);
        let undone = history.undo(edit(A, &document_with(30), None));
        assert_eq!(undone, Some(edit(A, &zero, None)));
        history.record(A, &zero, EditKind::Command, 5.0);
        assert!(!history.can_redo());
    }

    /// The same field of the same task on two characters: two steps, each naming its own.
    #[test]
    fn edits_of_two_characters_never_merge() {
        let mut history = History::default();
        let (zero, one) = (document_with(0), document_with(1));
        assert!(history.record(A, &zero, EditKind::TaskField(0, "weight"), 0.0));
        assert!(history.record(B, &one, EditKind::TaskField(0, "weight"), 0.1));
        assert_eq!(
            history.next_undo(),
            Some(Pending::Edit {
                character: B,
                changes_body: false
            })
        );
        assert_eq!(
            history.undo(edit(B, &zero, None)),
            Some(edit(B, &one, None))
        );
        assert_eq!(
            history.next_undo(),
            Some(Pending::Edit {
                character: A,
                changes_body: false
            })
        );
    }

    /// A change of body is a step of its own that names the body to bring back, and the
    /// body the caller stored when undoing it is the one redo brings back.
    #[test]
    fn a_change_of_body_carries_its_bodies_back_and_forth() {
        let mut history = History::default();
        let (zero, one) = (document_with(0), document_with(1));
        history.record(A, &zero, EditKind::Joint(3), 0.0);
        history.record_body_change(A, &one, 7, 0.1);
        history.record_body_change(A, &one, 8, 0.2);
        assert_eq!(history.undo_steps(), 3);
        assert_eq!(
            history.next_undo(),
            Some(Pending::Edit {
                character: A,
                changes_body: true
            })
        );
        assert_eq!(
            history.undo(edit(A, &one, Some(9))),
            Some(edit(A, &one, Some(8)))
        );
        assert_eq!(history.bodies().collect::<Vec<_>>(), [7, 9]);
        assert_eq!(
            history.redo(edit(A, &one, Some(10))),
            Some(edit(A, &one, Some(9)))
        );
        history.record(A, &one, EditKind::Command, 1.0);
        assert_eq!(history.bodies().collect::<Vec<_>>(), [7, 10]);
    }

    /// Renaming over frames is one step; the characters a step of the cast names are the
    /// ones kept for it.
    #[test]
    fn changes_of_the_cast_are_steps_that_name_their_characters() {
        let mut history = History::default();
        history.record_cast(cast(&[A], A), false, 0.0);
        history.record_cast(cast(&[A, B], B), true, 1.0);
        history.record_cast(cast(&[A, B], B), true, 1.1);
        assert_eq!(history.undo_steps(), 2);
        assert_eq!(history.next_undo(), Some(Pending::Cast));
        let mut named: Vec<u64> = history.characters().collect();
        named.sort_unstable();
        named.dedup();
        assert_eq!(named, [A, B]);
        let back = history.undo(Step::Cast(cast(&[A], A)));
        assert_eq!(back, Some(Step::Cast(cast(&[A, B], B))));
    }

    #[test]
    fn the_stack_is_bounded() {
        let mut history = History::default();
        for step in 0..(MAX_UNDO_STEPS + 50) {
            history.record(A, &document_with(step), EditKind::Command, step as f64);
        }
        assert_eq!(history.undo_steps(), MAX_UNDO_STEPS);
    }
}
