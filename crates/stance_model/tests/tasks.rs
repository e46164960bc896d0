//! The task list edited by commands alone, as the tasks panel sends them: remove a task, move
//! one to another level, swap two levels, move a level to another's place; each one is one
//! undo step, and each says what it changed.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use stance_document::TaskSpec;
use stance_model::model::{HistoryCommand, PostureCommand, TaskCommand, ViewCommand};
use stance_model::{Change, Command};

use crate::clocked::Clocked;

/// The editor with the paper's Table 1 (levels 1, 2, 3 and the lowest ones), settled.
fn table1() -> Clocked {
    let mut editor = Clocked::new();
    editor.settle();
    editor.apply(Command::Task(TaskCommand::LoadTable1Example));
    editor.settle();
    editor
}

fn tasks(editor: &Clocked) -> Vec<TaskSpec> {
    editor.model.session().tasks().to_vec()
}

/// The level numbers in use, ascending.
fn levels(tasks: &[TaskSpec]) -> Vec<u32> {
    let mut levels: Vec<u32> = tasks.iter().map(|task| task.level).collect();
    levels.sort_unstable();
    levels.dedup();
    levels
}

/// Undo takes the edit back: the task list is `before` again.
fn undo_restores(editor: &mut Clocked, before: &[TaskSpec]) {
    assert_eq!(
        editor.apply(Command::History(HistoryCommand::Undo)),
        Change::Document
    );
    assert_eq!(tasks(editor), before);
}

#[test]
fn removing_a_task_drops_it_alone_and_undo_brings_it_back() {
    // Catches: the wrong index removed, the edit not recorded for undo.
    let mut editor = table1();
    let before = tasks(&editor);
    assert!(before.len() > 3, "{before:?}");
    let change = editor.apply(Command::Task(TaskCommand::Remove(1)));
    assert_eq!(change, Change::Document);
    let mut expected = before.clone();
    expected.remove(1);
    assert_eq!(tasks(&editor), expected);
    undo_restores(&mut editor, &before);
}

#[test]
fn a_task_out_of_range_or_a_move_to_its_own_level_changes_nothing() {
    // Catches: an index past the end panicking, a no-op edit taking an undo step.
    let mut editor = table1();
    let before = tasks(&editor);
    let can_undo = editor.model.history().can_undo();
    let own_level = before[0].level;
    for command in [
        TaskCommand::Remove(before.len()),
        TaskCommand::MoveToLevel {
            task: before.len() + 4,
            level: 1,
        },
        TaskCommand::MoveToLevel {
            task: 0,
            level: own_level,
        },
        TaskCommand::SwapLevels(own_level, own_level),
        TaskCommand::MoveLevel {
            from: 999,
            onto: None,
        },
    ] {
        assert_eq!(editor.apply(Command::Task(command)), Change::Nothing);
    }
    assert_eq!(tasks(&editor), before);
    assert_eq!(editor.model.history().can_undo(), can_undo);
}

#[test]
fn a_task_moved_to_another_level_takes_its_number_and_undo_puts_it_back() {
    // Catches: another task moved, the level not set, no undo step.
    let mut editor = table1();
    let before = tasks(&editor);
    let lowest = *levels(&before).last().unwrap();
    assert_ne!(before[0].level, lowest);
    let change = editor.apply(Command::Task(TaskCommand::MoveToLevel {
        task: 0,
        level: lowest,
    }));
    assert_eq!(change, Change::Document);
    let after = tasks(&editor);
    assert_eq!(after[0].level, lowest);
    assert_eq!(after[1..], before[1..]);
    undo_restores(&mut editor, &before);
}

#[test]
fn swapping_two_levels_swaps_their_tasks_and_undo_swaps_them_back() {
    // Catches: only one level renumbered (the two merged), other levels touched.
    let mut editor = table1();
    let before = tasks(&editor);
    let numbers = levels(&before);
    let (a, b) = (numbers[0], numbers[1]);
    let change = editor.apply(Command::Task(TaskCommand::SwapLevels(a, b)));
    assert_eq!(change, Change::Document);
    for (old, new) in before.iter().zip(tasks(&editor)) {
        let expected = match old.level {
            level if level == a => b,
            level if level == b => a,
            level => level,
        };
        assert_eq!(new.level, expected, "{old:?}");
        assert_eq!(new.kind, old.kind);
    }
    undo_restores(&mut editor, &before);
}

#[test]
fn a_level_moved_to_the_last_place_keeps_the_level_numbers_and_shifts_the_others_up() {
    // Catches: the numbers in use changed (the default gaps lost), the levels in between not
    // shifted by one place, no undo step.
    let mut editor = table1();
    let before = tasks(&editor);
    let numbers = levels(&before);
    assert!(numbers.len() >= 3, "{numbers:?}");
    let first = numbers[0];
    let change = editor.apply(Command::Task(TaskCommand::MoveLevel {
        from: first,
        onto: None,
    }));
    assert_eq!(change, Change::Document);
    let after = tasks(&editor);
    assert_eq!(levels(&after), numbers);
    for (old, new) in before.iter().zip(&after) {
        let rank = numbers.iter().position(|&n| n == old.level).unwrap();
        let expected = if old.level == first {
            *numbers.last().unwrap()
        } else {
            numbers[rank - 1]
        };
        assert_eq!(new.level, expected, "{old:?}");
    }
    undo_restores(&mut editor, &before);
}

#[test]
fn a_level_moved_onto_another_takes_its_place() {
    // Catches: `onto` read as the level after, the moved level lost.
    let mut editor = table1();
    let before = tasks(&editor);
    let numbers = levels(&before);
    let (first, second, third) = (numbers[0], numbers[1], numbers[2]);
    editor.apply(Command::Task(TaskCommand::MoveLevel {
        from: third,
        onto: Some(first),
    }));
    for (old, new) in before.iter().zip(tasks(&editor)) {
        let expected = match old.level {
            level if level == third => first,
            level if level == first => second,
            level if level == second => third,
            level => level,
        };
        assert_eq!(new.level, expected, "{old:?}");
    }
}

#[test]
fn each_command_says_what_it_changed() {
    // Catches: a posture edit not reported as one (the timeline would not key it), a view
    // command reported as an edit of the document.
    let mut editor = table1();
    assert_eq!(
        editor.apply(Command::View(ViewCommand::Select(Some(3)))),
        Change::View
    );
    assert_eq!(
        editor.apply(Command::Posture(PostureCommand::Mirror)),
        Change::Posture
    );
    assert_eq!(
        editor.apply(Command::Posture(PostureCommand::SetDof {
            dof: 3,
            value: 0.2
        })),
        Change::Posture
    );
    assert_eq!(
        editor.apply(Command::Posture(PostureCommand::Pin(3))),
        Change::Document
    );
}
