//! The comfort panel's model: the posture's comfort report (RULA with its parts, the joint
//! loads against gravity), measured once per posture, and the heat map's colours.

use std::cell::RefCell;

use stance_hanim::comfort::{ComfortReport, ComfortSettings, comfort_report};
use stance_hanim::strength::built_axes;

use super::Change;
use crate::posing::PosingSession;

/// What the comfort panel asks of its model.
#[derive(Debug, Clone, PartialEq)]
pub enum ComfortCommand {
    /// Colour the body by joint load (the heat map), or not.
    ShowHeatMap(bool),
    /// RULA's inputs that a posture does not show, and the weights: the report is measured
    /// again with them.
    SetSettings(ComfortSettings),
}

/// The comfort of the session's posture, cached by session revision (a cache the views fill
/// as they read it: measuring is not a change of the model).
#[derive(Debug, Default)]
pub struct ComfortView {
    /// Colour the body by joint load (the heat map).
    heat_map: bool,
    /// RULA's inputs that a posture does not show, and the weights.
    settings: ComfortSettings,
    report: RefCell<Option<((u64, u64), ComfortReport)>>,
}

impl ComfortView {
    /// Carries out a command of the comfort panel (the view changes, not the document).
    pub fn apply(&mut self, command: ComfortCommand) -> Change {
        match command {
            ComfortCommand::ShowHeatMap(on) => self.heat_map = on,
            ComfortCommand::SetSettings(settings) => {
                if settings != self.settings {
                    self.settings = settings;
                    self.report = RefCell::new(None);
                }
            }
        }
        Change::View
    }

    /// Whether the body is coloured by joint load.
    pub fn heat_map(&self) -> bool {
        self.heat_map
    }

    /// RULA's inputs that a posture does not show, and the weights.
    pub fn settings(&self) -> ComfortSettings {
        self.settings
    }

    /// The report for the session's posture (`generation` tells sessions apart).
    pub fn report(&self, session: &PosingSession, generation: u64) -> ComfortReport {
        let key = (generation, session.revision());
        let mut cached = self.report.borrow_mut();
        if let Some((k, report)) = cached.as_ref()
            && *k == key
        {
            return report.clone();
        }
        let report = comfort_report(
            session.skeleton(),
            &built_axes(session.humanoid()),
            session.posture(),
            &self.settings,
        );
        *cached = Some((key, report.clone()));
        report
    }

    /// Per joint of `skeleton`, its load share for the heat map (0 where unknown); `None`
    /// while the heat map is off or nothing was measured yet.
    pub fn heat_shares(&self, skeleton: &stance_ik::Skeleton) -> Option<Vec<f64>> {
        if !self.heat_map {
            return None;
        }
        let cached = self.report.borrow();
        let (_, report) = cached.as_ref()?;
        Some(
            skeleton
                .joints()
                .iter()
                .map(|joint| {
                    report
                        .loads
                        .iter()
                        .find(|load| load.joint == joint.name)
                        .and_then(|load| load.share)
                        .unwrap_or(0.0)
                })
                .collect(),
        )
    }
}

/// The heat map's colour of a load share (linear RGBA): the body's colour up to 5 %, then
/// through amber to red at 30 % of the joint's strength and above.
pub fn heat_color(share: f64, body: [f32; 4]) -> [f32; 4] {
    const AMBER: [f32; 4] = [0.9, 0.55, 0.05, 1.0];
    const RED: [f32; 4] = [0.85, 0.05, 0.03, 1.0];
    let mix = |a: [f32; 4], b: [f32; 4], t: f64| {
        let t = t.clamp(0.0, 1.0) as f32;
        [0, 1, 2, 3].map(|i| a[i] + (b[i] - a[i]) * t)
    };
    if share <= 0.05 {
        body
    } else if share <= 0.15 {
        mix(body, AMBER, (share - 0.05) / 0.10)
    } else {
        mix(AMBER, RED, (share - 0.15) / 0.15)
    }
}

impl super::EditorModel {
    /// Sets a DOF's stiffness (`None`: its anatomical default) as one undoable edit; a value
    /// the body refuses is named and changes nothing.
    pub(super) fn set_stiffness(&mut self, dof: usize, value: Option<f64>) {
        let before = self.character.session.document();
        match self.character.session.set_stiffness(dof, value) {
            Ok(()) => {
                self.history.record(
                    self.character.id,
                    &before,
                    crate::history::EditKind::Stiffness(dof),
                    self.now_secs,
                );
            }
            Err(error) => self.warn(format!("The stiffness was not changed: {error}")),
        }
    }
}
