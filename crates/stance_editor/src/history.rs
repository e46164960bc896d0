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

/// The undo and redo stacks.
#[derive(Debug, Default)]
pub struct History {
    undo: Vec<Document>,
    redo: Vec<Document>,
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
        if self.undo.last() == Some(before) {
            return false;
        }
        self.undo.push(before.clone());
        if self.undo.len() > MAX_UNDO_STEPS {
            self.undo.remove(0);
        }
        true
    }

    /// Ends the current gesture: the next edit starts a new undo step even if of the same kind.
    pub fn break_coalescing(&mut self) {
        self.last_edit = None;
    }

    /// The document to go back to; `current` becomes redoable.
    pub fn undo(&mut self, current: &Document) -> Option<Document> {
        let previous = self.undo.pop()?;
        self.redo.push(current.clone());
        self.last_edit = None;
        Some(previous)
    }

    /// The document to go forward to; `current` becomes undoable.
    pub fn redo(&mut self, current: &Document) -> Option<Document> {
        let next = self.redo.pop()?;
        self.undo.push(current.clone());
        self.last_edit = None;
        Some(next)
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
        assert_eq!(history.undo(&two), Some(one.clone()));
        assert_eq!(history.undo(&one), Some(zero.clone()));
        assert_eq!(history.undo(&zero), None);
        assert_eq!(history.redo(&zero), Some(one.clone()));
        assert_eq!(history.redo(&one), Some(two));
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
        let undone = history.undo(&document_with(30));
        assert_eq!(undone, Some(zero.clone()));
        history.record(&zero, EditKind::Command, 5.0);
        assert!(!history.can_redo());
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
