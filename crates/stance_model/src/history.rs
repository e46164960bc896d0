//! Undo and redo of every edit: snapshots of the document taken before each edit.
//!
//! An edit that goes on over many frames (dragging a value, pulling a body part) is one step:
//! edits with the same [`EditKind`] that follow each other within [`COALESCE_SECS`] merge.

use stance_document::Document;
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
}

/// One step back or forward: the document, and for a change of body (an avatar swap, back to
/// the mannequin) the body to bring back, as the editor stored it (see
/// [`crate::model::EditorModel`]'s kept bodies).
#[derive(Debug, Clone, PartialEq)]
struct Step {
    document: Document,
    body: Option<u64>,
}

/// The undo and redo stacks.
#[derive(Debug, Default)]
pub struct History {
    undo: Vec<Step>,
    redo: Vec<Step>,
    last_edit: Option<(EditKind, f64)>,
}

impl History {
    /// Records `before`, the document as it was before an edit of `kind` at `now_secs`.
    /// Returns whether a new undo step was made (false when it merged with the previous one).
    pub fn record(&mut self, before: &Document, kind: EditKind, now_secs: f64) -> bool {
        let merges = kind != EditKind::Command
            && self
                .last_edit
                .as_ref()
                .is_some_and(|(last_kind, last_secs)| {
                    *last_kind == kind && (now_secs - last_secs).abs() < COALESCE_SECS
                })
            && !self.undo.is_empty();
        self.last_edit = Some((kind, now_secs));
        self.redo.clear();
        if merges {
            return false;
        }
        if self
            .undo
            .last()
            .is_some_and(|step| step.body.is_none() && step.document == *before)
        {
            return false;
        }
        self.push_undo(Step {
            document: before.clone(),
            body: None,
        });
        true
    }

    /// Records a change of body: `before`, the document before it, and `body`, the stored
    /// body that undo brings back. Always a step of its own.
    pub fn record_body_change(&mut self, before: &Document, body: u64, now_secs: f64) {
        self.last_edit = Some((EditKind::Command, now_secs));
        self.redo.clear();
        self.push_undo(Step {
            document: before.clone(),
            body: Some(body),
        });
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

    /// Whether the next undo changes the body back (the caller stores the current body and
    /// passes it to [`History::undo`]).
    pub fn undo_changes_body(&self) -> bool {
        self.undo.last().is_some_and(|step| step.body.is_some())
    }

    /// Whether the next redo changes the body again.
    pub fn redo_changes_body(&self) -> bool {
        self.redo.last().is_some_and(|step| step.body.is_some())
    }

    /// The document to go back to, and the body to bring back when the step changed the body;
    /// `current` (on `current_body`, stored by the caller when the step changes the body)
    /// becomes redoable.
    pub fn undo(
        &mut self,
        current: &Document,
        current_body: Option<u64>,
    ) -> Option<(Document, Option<u64>)> {
        let previous = self.undo.pop()?;
        self.redo.push(Step {
            document: current.clone(),
            body: current_body,
        });
        self.last_edit = None;
        Some((previous.document, previous.body))
    }

    /// The document to go forward to, and the body to bring back; `current` (on
    /// `current_body`) becomes undoable.
    pub fn redo(
        &mut self,
        current: &Document,
        current_body: Option<u64>,
    ) -> Option<(Document, Option<u64>)> {
        let next = self.redo.pop()?;
        self.undo.push(Step {
            document: current.clone(),
            body: current_body,
        });
        self.last_edit = None;
        Some((next.document, next.body))
    }

    /// The stored bodies the steps refer to.
    pub fn bodies(&self) -> impl Iterator<Item = u64> + '_ {
        self.undo
            .iter()
            .chain(&self.redo)
            .filter_map(|step| step.body)
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

    #[test]
    fn undo_then_redo_walks_back_and_forth_exactly() {
        let mut history = History::default();
        let (zero, one, two) = (document_with(0), document_with(1), document_with(2));
        history.record(&zero, EditKind::Command, 0.0);
        history.record(&one, EditKind::Command, 0.1);
        assert_eq!(history.undo(&two, None), Some((one.clone(), None)));
        assert_eq!(history.undo(&one, None), Some((zero.clone(), None)));
        assert_eq!(history.undo(&zero, None), None);
        assert_eq!(history.redo(&zero, None), Some((one.clone(), None)));
        assert_eq!(history.redo(&one, None), Some((two, None)));
        assert!(!history.can_redo());
    }

    #[test]
    fn a_drag_is_one_step_and_a_new_edit_clears_redo() {
        let mut history = History::default();
        let zero = document_with(0);
        assert!(history.record(&zero, EditKind::TaskField(0, "weight"), 0.0));
        for frame in 1..30 {
            let merged = !history.record(
                &document_with(frame),
                EditKind::TaskField(0, "weight"),
                f64::from(frame as u32) * 0.016,
            );
            assert!(merged);
        }
        assert_eq!(history.undo_steps(), 1);
        let undone = history.undo(&document_with(30), None);
        assert_eq!(undone, Some((zero.clone(), None)));
        history.record(&zero, EditKind::Command, 5.0);
        assert!(!history.can_redo());
    }

    /// A change of body is a step of its own that names the body to bring back, and the
    /// body the caller stored when undoing it is the one redo brings back.
    #[test]
    fn a_change_of_body_carries_its_bodies_back_and_forth() {
        let mut history = History::default();
        let (zero, one) = (document_with(0), document_with(1));
        history.record(&zero, EditKind::Joint(3), 0.0);
        history.record_body_change(&one, 7, 0.1);
        history.record_body_change(&one, 8, 0.2);
        assert_eq!(history.undo_steps(), 3);
        assert!(history.undo_changes_body());
        assert_eq!(history.undo(&one, Some(9)), Some((one.clone(), Some(8))));
        assert!(history.redo_changes_body());
        assert_eq!(history.bodies().collect::<Vec<_>>(), [7, 9]);
        assert_eq!(history.redo(&one, Some(10)), Some((one.clone(), Some(9))));
        history.record(&one, EditKind::Command, 1.0);
        assert_eq!(history.bodies().collect::<Vec<_>>(), [7, 10]);
    }

    #[test]
    fn the_stack_is_bounded() {
        let mut history = History::default();
        for step in 0..(MAX_UNDO_STEPS + 50) {
            history.record(&document_with(step), EditKind::Command, step as f64);
        }
        assert_eq!(history.undo_steps(), MAX_UNDO_STEPS);
    }
}
