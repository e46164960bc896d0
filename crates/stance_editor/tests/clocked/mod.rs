//! The editor model driven frame by frame at 60 Hz, without egui: what the model tests share.

#![allow(dead_code)]

use glam::DVec3;
use stance_editor::model::MotionCommand;
use stance_editor::{Command, EditorModel, MemoryHost};

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

    /// Steps until the solver settles (at most `limit` frames).
    pub fn settle_within(&mut self, limit: usize) {
        for _ in 0..limit {
            self.frames(1);
            if self.model.session().is_settled() {
                return;
            }
        }
    }

    /// Steps until the solver settles (at most 300 frames).
    pub fn settle(&mut self) {
        self.settle_within(300);
    }

    pub fn apply(&mut self, command: Command) {
        self.model.apply(command);
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
