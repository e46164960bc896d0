//! The editor model driven frame by frame at 60 Hz, without egui: what the model tests share.

#![allow(dead_code)]
// Test-support code (not itself a #[test]): panicking on broken fixtures is what we want.
// Since the tests became one binary (tests/all.rs) the allowances of the files that include
// this module no longer reach it.
#![allow(clippy::expect_used, clippy::unwrap_used, clippy::panic)]

use glam::DVec3;
use stance_model::model::FileCommand;
use stance_model::model::MotionCommand;
use stance_model::{Change, Command, EditorModel, Gesture, MemoryHost};

/// Seconds between two frames.
pub const FRAME: f64 = 1.0 / 60.0;

/// The model and its clock.
pub struct Clocked {
    pub model: EditorModel,
    pub now: f64,
}

impl Clocked {
    pub fn new() -> Self {
        Self::with_host(MemoryHost::default())
    }

    pub fn with_host(host: MemoryHost) -> Self {
        let Ok(model) = EditorModel::new(Box::new(host)) else {
            panic!("the model starts on the mannequin");
        };
        let mut clocked = Self { model, now: 0.0 };
        clocked.frames(1);
        clocked
    }

    pub fn frames(&mut self, count: usize) {
        for _ in 0..count {
            self.now += FRAME;
            self.model.step(self.now, None);
        }
    }

    /// Steps until the solver settles; panics, saying where the solver stands, when it has
    /// not within `limit` frames (a test that goes on unsettled would check a posture still
    /// on its way).
    pub fn settle_within(&mut self, limit: usize) {
        for _ in 0..limit {
            self.frames(1);
            if self.model.session().is_settled() {
                return;
            }
        }
        panic!("{}", unsettled(&self.model, limit));
    }

    /// Steps until the solver settles (at most 300 frames, else a panic).
    pub fn settle(&mut self) {
        self.settle_within(300);
    }

    pub fn apply(&mut self, command: Command) -> Change {
        self.model.apply(command)
    }

    pub fn motion(&mut self, command: MotionCommand) {
        self.model.apply(Command::Motion(command));
    }

    pub fn joint(&self, name: &str) -> usize {
        self.model
            .session()
            .skeleton()
            .joint_index(name)
            .unwrap_or_else(|| panic!("{name} is in the body"))
    }

    pub fn position(&self, name: &str) -> DVec3 {
        self.model
            .session()
            .joint_position(name)
            .unwrap_or_else(|| panic!("{name} has a position"))
    }
}

/// Why a settle gave up: the frames spent, the last solve's status, iterations and each
/// level's residual, and what the model was doing.
pub fn unsettled(model: &EditorModel, frames: usize) -> String {
    let session = model.session();
    let solve = match session.report() {
        Some(report) => {
            let levels: Vec<String> = report
                .levels
                .iter()
                .map(|l| {
                    format!(
                        "level {} {} residual {:.3e}",
                        l.level,
                        if l.met { "met" } else { "unmet" },
                        l.residual_after
                    )
                })
                .collect();
            format!(
                "last solve {:?} after {} iterations, gave way {:?}; {}",
                report.status,
                report.iterations,
                report.gave_way,
                levels.join(", ")
            )
        }
        None => "no solve yet".to_owned(),
    };
    let gesture = match model.gesture() {
        None => "none",
        Some(Gesture::Pull { .. }) => "pull",
        Some(Gesture::Goal { .. }) => "goal drag",
        Some(Gesture::Ring { .. }) => "ring",
        Some(Gesture::Swivel { .. }) => "swivel",
    };
    format!(
        "the model did not settle within {frames} frames: {solve}; gesture {gesture}, {} tasks",
        session.tasks().len()
    )
}

/// The editor's model on `host`, after its first step.
pub fn editor_on(host: &MemoryHost) -> EditorModel {
    let mut model = EditorModel::new(Box::new(host.clone())).expect("the editor starts");
    model.step(0.0, None);
    model
}

/// Opens `bytes` as the file `name`, as a pick or a drop does.
pub fn open(model: &mut EditorModel, name: &str, bytes: &[u8]) {
    model.apply(Command::File(FileCommand::OpenFile {
        name: name.into(),
        bytes: bytes.to_vec(),
    }));
}
