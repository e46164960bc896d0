//! The sensor rig: which body segment each sensor drives, and ready-made rigs.

use serde::{Deserialize, Serialize};

/// What one sensor drives.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum SensorAssignment {
    /// The segment of this joint (an H-Anim joint name).
    Joint(String),
    /// The upper back: the spine joints present share the sensor's rotation (Molet et al.:
    /// lumbar joints half of it, thoracic joints the other half, evenly within each).
    Spine,
}

/// Ready-made assignments: sensors in increasing id order go to these segments.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum AssignmentPreset {
    /// Upper back, right upper arm, forearm, hand.
    TorsoRightArm,
    /// Upper back, left upper arm, forearm, hand.
    TorsoLeftArm,
    /// Upper back, head, both upper arms and forearms, both thighs and shanks.
    FullBody,
}

impl AssignmentPreset {
    /// Every preset, in the order a user interface lists them.
    pub const ALL: [AssignmentPreset; 3] = [
        AssignmentPreset::TorsoRightArm,
        AssignmentPreset::TorsoLeftArm,
        AssignmentPreset::FullBody,
    ];

    /// The preset's name with its number of sensors, for people.
    pub fn label(self) -> &'static str {
        match self {
            AssignmentPreset::TorsoRightArm => "Torso + right arm (4)",
            AssignmentPreset::TorsoLeftArm => "Torso + left arm (4)",
            AssignmentPreset::FullBody => "Full body (10)",
        }
    }

    /// The segments sensors drive, in increasing sensor id order (H-Anim joint names; a body
    /// may lack some of them).
    pub fn segments(self) -> Vec<SensorAssignment> {
        let joint = |name: &str| SensorAssignment::Joint(name.to_owned());
        match self {
            AssignmentPreset::TorsoRightArm => vec![
                SensorAssignment::Spine,
                joint("r_shoulder"),
                joint("r_elbow"),
                joint("r_radiocarpal"),
            ],
            AssignmentPreset::TorsoLeftArm => vec![
                SensorAssignment::Spine,
                joint("l_shoulder"),
                joint("l_elbow"),
                joint("l_radiocarpal"),
            ],
            AssignmentPreset::FullBody => vec![
                SensorAssignment::Spine,
                joint("skullbase"),
                joint("l_shoulder"),
                joint("l_elbow"),
                joint("r_shoulder"),
                joint("r_elbow"),
                joint("l_hip"),
                joint("l_knee"),
                joint("r_hip"),
                joint("r_knee"),
            ],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_have_as_many_segments_as_their_labels_say() {
        for preset in AssignmentPreset::ALL {
            let segments = preset.segments();
            assert!(
                preset.label().contains(&format!("({})", segments.len())),
                "{preset:?}"
            );
            assert_eq!(segments.first(), Some(&SensorAssignment::Spine));
            let mut unique = segments.clone();
            unique.sort();
            unique.dedup();
            assert_eq!(unique.len(), segments.len(), "{preset:?}: no segment twice");
        }
    }
}
