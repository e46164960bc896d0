//! The devices Stance talks to: which protocol each speaks, the reference frame it usually
//! reports in, the bytes that start and stop its stream, and the decoder for its settings.

use glam::{DMat3, DQuat, DVec3};
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::ascii::{AsciiConfig, ComponentOrder};
use crate::decoder::{DecoderConfig, Protocol};
use crate::fob::{FobCommandError, FobConfig, FobMode, command};
use crate::hid::{GamepadConfig, GamepadModel};
use crate::polhemus::{FastrakConfig, LibertyConfig};

/// The devices the page can talk to.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum DeviceKind {
    /// Ascension Flock of Birds (RS-232 binary records).
    #[default]
    FlockOfBirds,
    /// Polhemus FASTRAK (ASCII records).
    Fastrak,
    /// Polhemus Liberty or Patriot (binary frames).
    Liberty,
    /// Xsens MTi (MTData2).
    Xsens,
    /// Hobby IMU boards printing quaternion lines (BNO055, BNO080...).
    AsciiImu,
    /// SlimeVR receiver (WebHID).
    SlimeVr,
    /// Sony DualSense (WebHID, gyro and accelerometer fused here).
    DualSense,
    /// Sony DualShock 4 (WebHID, gyro and accelerometer fused here).
    DualShock4,
}

impl DeviceKind {
    /// Every device, in the order a user interface lists them.
    pub const ALL: [DeviceKind; 8] = [
        DeviceKind::FlockOfBirds,
        DeviceKind::Fastrak,
        DeviceKind::Liberty,
        DeviceKind::Xsens,
        DeviceKind::AsciiImu,
        DeviceKind::SlimeVr,
        DeviceKind::DualSense,
        DeviceKind::DualShock4,
    ];

    /// The device's name with its link (serial or HID), for people.
    pub fn label(self) -> &'static str {
        match self {
            DeviceKind::FlockOfBirds => "Ascension Flock of Birds (serial)",
            DeviceKind::Fastrak => "Polhemus FASTRAK (serial)",
            DeviceKind::Liberty => "Polhemus Liberty / Patriot (serial)",
            DeviceKind::Xsens => "Xsens MTi (serial)",
            DeviceKind::AsciiImu => "IMU board, quaternion lines (serial)",
            DeviceKind::SlimeVr => "SlimeVR receiver (HID)",
            DeviceKind::DualSense => "DualSense controller (HID)",
            DeviceKind::DualShock4 => "DualShock 4 controller (HID)",
        }
    }

    /// The protocol the device speaks.
    pub fn protocol(self) -> Protocol {
        match self {
            DeviceKind::FlockOfBirds => Protocol::FlockOfBirds,
            DeviceKind::Fastrak => Protocol::Fastrak,
            DeviceKind::Liberty => Protocol::Liberty,
            DeviceKind::Xsens => Protocol::Xsens,
            DeviceKind::AsciiImu => Protocol::AsciiQuaternion,
            DeviceKind::SlimeVr => Protocol::SlimeVrHid,
            DeviceKind::DualSense | DeviceKind::DualShock4 => Protocol::Gamepad,
        }
    }

    /// The reference frame such a device usually reports in.
    pub fn usual_frame(self) -> DeviceFrame {
        match self {
            DeviceKind::FlockOfBirds | DeviceKind::Fastrak | DeviceKind::Liberty => {
                DeviceFrame::TransmitterZDown
            }
            _ => DeviceFrame::EarthZUp,
        }
    }

    /// The bytes the bridge writes before closing the port so that the device stops its
    /// continuous output (empty when nothing needs to be said). Each undoes only what the start
    /// bytes did, so the next connection's start bytes bring the stream back:
    /// Flock of Birds POINT (`B`: stream mode off, a record only on request), FASTRAK `c`
    /// (continuous output off), Liberty / Patriot `P\r` (single-record mode ends continuous
    /// output). Xsens and IMU boards stream without being asked and are left as they are.
    pub fn stop_bytes(self) -> Vec<u8> {
        match self {
            DeviceKind::FlockOfBirds => command::stop_streaming().to_vec(),
            DeviceKind::Fastrak => b"c".to_vec(),
            DeviceKind::Liberty => b"P\r".to_vec(),
            DeviceKind::Xsens
            | DeviceKind::AsciiImu
            | DeviceKind::SlimeVr
            | DeviceKind::DualSense
            | DeviceKind::DualShock4 => Vec::new(),
        }
    }
}

/// The reference frame of the device's orientations, as the user sets it up.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum DeviceFrame {
    /// A magnetic transmitter placed as its manual shows: X toward the front of the body,
    /// Y to the body's right, Z down.
    #[default]
    TransmitterZDown,
    /// An IMU earth frame: X toward the front of the body, Y to the body's left, Z up
    /// (use *Reset heading* once the person faces the front).
    EarthZUp,
    /// Already the editor's world: +Y up, +Z front, +X the body's left.
    EditorWorld,
}

impl DeviceFrame {
    /// Every frame, in the order a user interface lists them.
    pub const ALL: [DeviceFrame; 3] = [
        DeviceFrame::TransmitterZDown,
        DeviceFrame::EarthZUp,
        DeviceFrame::EditorWorld,
    ];

    /// The frame's axes, for people.
    pub fn label(self) -> &'static str {
        match self {
            DeviceFrame::TransmitterZDown => "Transmitter: X front, Y right, Z down",
            DeviceFrame::EarthZUp => "Earth: X front, Y left, Z up",
            DeviceFrame::EditorWorld => "Editor world: Y up, Z front",
        }
    }

    /// `A`: the rotation from the device frame to the editor's world (H-Anim: +Y up, +Z front,
    /// +X the body's left).
    pub fn world_from_device(self) -> DQuat {
        // Columns: the device's X, Y and Z axes in world coordinates.
        let columns = match self {
            DeviceFrame::TransmitterZDown => [DVec3::Z, DVec3::NEG_X, DVec3::NEG_Y],
            DeviceFrame::EarthZUp => [DVec3::Z, DVec3::X, DVec3::Y],
            DeviceFrame::EditorWorld => [DVec3::X, DVec3::Y, DVec3::Z],
        };
        DQuat::from_mat3(&DMat3::from_cols(columns[0], columns[1], columns[2])).normalize()
    }
}

/// Why the start bytes of a device could not be made.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum DeviceError {
    /// The Flock of Birds commands refused the settings (too many birds...).
    #[error("the Flock of Birds setup failed: {0}")]
    FlockOfBirds(#[from] FobCommandError),
}

/// A device with the settings that change how it is started and read.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DeviceSetup {
    /// The device.
    pub kind: DeviceKind,
    /// Flock of Birds record layout.
    pub fob_mode: FobMode,
    /// Flock of Birds group mode (records carry the bird address; needed for several birds).
    pub fob_group: bool,
    /// Number of birds the bridge configures (Flock of Birds; 0 counts as 1).
    pub fob_birds: u8,
    /// Component order of quaternion lines (IMU boards).
    pub ascii_order: ComponentOrder,
}

impl Default for DeviceSetup {
    fn default() -> Self {
        DeviceSetup {
            kind: DeviceKind::FlockOfBirds,
            fob_mode: FobMode::PositionQuaternion,
            fob_group: true,
            fob_birds: 4,
            ascii_order: ComponentOrder::Wxyz,
        }
    }
}

impl DeviceSetup {
    /// The configuration of the decoder that reads this device.
    pub fn decoder_config(&self) -> DecoderConfig {
        match self.kind {
            DeviceKind::FlockOfBirds => DecoderConfig::FlockOfBirds(self.fob_config()),
            DeviceKind::Fastrak => DecoderConfig::Fastrak(FastrakConfig::default()),
            DeviceKind::Liberty => DecoderConfig::Liberty(LibertyConfig::default()),
            DeviceKind::Xsens => DecoderConfig::Xsens,
            DeviceKind::AsciiImu => DecoderConfig::AsciiQuaternion(AsciiConfig {
                order: self.ascii_order,
                ..AsciiConfig::default()
            }),
            DeviceKind::SlimeVr => DecoderConfig::SlimeVrHid,
            DeviceKind::DualSense => DecoderConfig::Gamepad(GamepadConfig::default()),
            DeviceKind::DualShock4 => DecoderConfig::Gamepad(GamepadConfig {
                model: GamepadModel::DualShock4,
                ..GamepadConfig::default()
            }),
        }
    }

    /// The Flock of Birds configuration of these settings.
    pub fn fob_config(&self) -> FobConfig {
        FobConfig {
            mode: self.fob_mode,
            group_mode: self.fob_group,
            ..FobConfig::default()
        }
    }

    /// The bytes the bridge writes after opening the port, to set the device up and start its
    /// continuous output: the Flock of Birds setup ([`command::start_streaming`]), FASTRAK `C`,
    /// Liberty / Patriot `C\r`; nothing for devices that stream by themselves.
    pub fn start_bytes(&self) -> Result<Vec<u8>, DeviceError> {
        Ok(match self.kind {
            DeviceKind::FlockOfBirds => {
                command::start_streaming(&self.fob_config(), self.fob_birds.max(1))?
            }
            DeviceKind::Fastrak => b"C".to_vec(),
            DeviceKind::Liberty => b"C\r".to_vec(),
            DeviceKind::Xsens
            | DeviceKind::AsciiImu
            | DeviceKind::SlimeVr
            | DeviceKind::DualSense
            | DeviceKind::DualShock4 => Vec::new(),
        })
    }

    /// The bytes the bridge writes before closing the port ([`DeviceKind::stop_bytes`]).
    pub fn stop_bytes(&self) -> Vec<u8> {
        self.kind.stop_bytes()
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn stop_bytes_end_the_continuous_output_of_each_device() {
        for kind in DeviceKind::ALL {
            let expected: &[u8] = match kind {
                // POINT: the flock leaves stream mode.
                DeviceKind::FlockOfBirds => b"B",
                // Lowercase c: continuous output off.
                DeviceKind::Fastrak => b"c",
                // Single-record output ends continuous mode.
                DeviceKind::Liberty => b"P\r",
                _ => b"",
            };
            assert_eq!(kind.stop_bytes(), expected, "{kind:?}");
            let setup = DeviceSetup {
                kind,
                ..DeviceSetup::default()
            };
            assert_eq!(setup.stop_bytes(), expected, "{kind:?}");
        }
        assert_eq!(
            DeviceKind::FlockOfBirds.stop_bytes(),
            command::stop_streaming()
        );
    }

    #[test]
    fn start_bytes_follow_the_settings() {
        let fastrak = DeviceSetup {
            kind: DeviceKind::Fastrak,
            ..DeviceSetup::default()
        };
        assert_eq!(fastrak.start_bytes().unwrap(), b"C");
        let liberty = DeviceSetup {
            kind: DeviceKind::Liberty,
            ..DeviceSetup::default()
        };
        assert_eq!(liberty.start_bytes().unwrap(), b"C\r");
        let fob = DeviceSetup::default();
        let bytes = fob.start_bytes().unwrap();
        assert_eq!(bytes.last(), Some(&command::STREAM));
        assert!(bytes.windows(3).any(|w| w == command::group_mode(true)));
        let too_many = DeviceSetup {
            fob_birds: 31,
            ..DeviceSetup::default()
        };
        let error = too_many.start_bytes().unwrap_err();
        assert!(
            error
                .to_string()
                .starts_with("the Flock of Birds setup failed")
        );
        for kind in DeviceKind::ALL {
            let setup = DeviceSetup {
                kind,
                ..DeviceSetup::default()
            };
            assert_eq!(setup.decoder_config().protocol(), kind.protocol());
        }
    }
}
