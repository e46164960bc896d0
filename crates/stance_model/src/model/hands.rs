//! Hand poses in the editor: a preset or a curl on the left hand, the right one or both
//! (mirrored: each hand flexes toward its own palm), each one undoable step. The DOF values
//! come from [`stance_hanim::hands`]; here they become edits of the posture.

use stance_hanim::Side;
use stance_hanim::hands::{Finger, HandPreset};

use super::{Change, EditorModel};
use crate::history::EditKind;

/// Which hands an edit poses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Hands {
    /// The body's left hand.
    Left,
    /// The body's right hand.
    Right,
    /// Both, mirror images of each other.
    Both,
}

impl Hands {
    /// All three, in the order the panel shows them.
    pub const ALL: [Hands; 3] = [Hands::Left, Hands::Right, Hands::Both];

    /// The sides posed.
    pub fn sides(self) -> &'static [Side] {
        match self {
            Hands::Left => &[Side::Left],
            Hands::Right => &[Side::Right],
            Hands::Both => &[Side::Left, Side::Right],
        }
    }

    /// "left", "right", "both".
    pub fn name(self) -> &'static str {
        match self {
            Hands::Left => "left",
            Hands::Right => "right",
            Hands::Both => "both",
        }
    }
}

/// A hand edit (see [`crate::Command::Hands`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum HandCommand {
    /// Pose the fingers of `hands` as `preset`: one undo step.
    Preset {
        /// The hands posed.
        hands: Hands,
        /// The pose.
        preset: HandPreset,
    },
    /// Curl `finger` (every digit for `None`) of `hands` to `curl`, 0 straight to 1 closed as
    /// far as the joints' limits allow; a slider's drag makes one undo step.
    Curl {
        /// The hands posed.
        hands: Hands,
        /// The digit, or the whole hand.
        finger: Option<Finger>,
        /// 0 to 1.
        curl: f64,
    },
}

impl EditorModel {
    /// Whether the body has finger joints (hand presets and curl apply).
    pub fn has_fingers(&self) -> bool {
        [Side::Left, Side::Right]
            .into_iter()
            .any(|side| self.character.session.hand(side).is_ok())
    }

    /// How curled `finger` (the whole hand for `None`) of `hands` is, 0 to 1 (the mean over
    /// both hands for [`Hands::Both`]); `None` without fingers.
    pub fn hand_curl(&self, hands: Hands, finger: Option<Finger>) -> Option<f64> {
        let posture = self.character.session.posture();
        let curls: Vec<f64> = hands
            .sides()
            .iter()
            .filter_map(|&side| {
                self.character
                    .session
                    .hand(side)
                    .ok()?
                    .curl_of(posture, finger)
            })
            .collect();
        (!curls.is_empty()).then(|| curls.iter().sum::<f64>() / curls.len() as f64)
    }

    /// Carries out a hand edit: the DOF values of every hand asked for, as one undo step; a
    /// notice says why when the body has no fingers to pose.
    /// Says whether the posture changed.
    pub(super) fn apply_hands(&mut self, command: HandCommand) -> Change {
        let (hands, kind) = match command {
            HandCommand::Preset { hands, .. } => (hands, EditKind::Command),
            HandCommand::Curl { hands, finger, .. } => (hands, EditKind::HandCurl(hands, finger)),
        };
        let skeleton = self.character.session.skeleton();
        let mut values = Vec::new();
        let mut problems = Vec::new();
        for &side in hands.sides() {
            match self.character.session.hand(side) {
                Ok(rig) => values.extend(match command {
                    HandCommand::Preset { preset, .. } => rig.preset(skeleton, preset),
                    HandCommand::Curl { finger, curl, .. } => rig.curl(skeleton, finger, curl),
                }),
                Err(problem) => problems.push(problem.to_string()),
            }
        }
        if values.is_empty() {
            let why = problems.first().cloned().unwrap_or_default();
            self.inform(format!("No hand pose: {why}."));
            return Change::View;
        }
        let posture = self.character.session.posture().values();
        let unchanged = values
            .iter()
            .all(|&(dof, value)| posture.get(dof) == Some(&value));
        if unchanged {
            return Change::Nothing;
        }
        self.record(kind);
        self.character.session.set_dofs(&values);
        if let Some(problem) = problems.first() {
            self.inform(format!("Only one hand was posed: {problem}."));
        }
        Change::Posture
    }
}
