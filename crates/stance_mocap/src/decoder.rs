//! The common face of all decoders: [`Decoder`], [`Sample`], [`DecoderStats`] and the protocol
//! registry that the bridge and the CLI use to build one.

use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};

use crate::ascii::{AsciiConfig, AsciiQuaternionDecoder};
use crate::fob::{FobConfig, FobDecoder};
use crate::hid::{GamepadConfig, GamepadDecoder, SlimeVrDecoder};
use crate::polhemus::{FastrakConfig, FastrakDecoder, LibertyConfig, LibertyDecoder};
use crate::xsens::XsensDecoder;

/// Which sensor of a device a sample belongs to (bird address, Polhemus station, Xsens bus id,
/// SlimeVR tracker id, or the number before `:` on an ASCII line).
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize,
)]
#[serde(transparent)]
pub struct SensorId(pub u16);

/// One decoded measurement of one sensor.
///
/// `orientation` maps vectors from the sensor frame into the device's reference frame
/// (transmitter/source frame for magnetic trackers, earth frame for IMUs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Sample {
    /// Which sensor of the device measured this.
    pub sensor: SensorId,
    /// Packet or frame counter reported by the device, when it has one.
    pub counter: Option<u32>,
    /// Device clock in microseconds, when the device reports one (may wrap per device).
    pub device_time_us: Option<u64>,
    /// Position of the sensor in the device reference frame, in metres.
    pub position_m: Option<DVec3>,
    /// Rotation from the sensor frame to the device reference frame (unit quaternion).
    pub orientation: Option<DQuat>,
    /// Specific force measured by an accelerometer, sensor frame, m/s².
    pub acceleration_mps2: Option<DVec3>,
    /// Angular velocity measured by a gyroscope, sensor frame, rad/s.
    pub angular_velocity_radps: Option<DVec3>,
}

/// Running counts of a decoder. At any time
/// `bytes_received == bytes_in_frames + skipped_bytes + pending_bytes()`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct DecoderStats {
    /// Bytes given to `push`/`push_report`.
    pub bytes_received: u64,
    /// Bytes that formed valid frames (whether or not the frame carried a sample).
    pub bytes_in_frames: u64,
    /// Bytes dropped: garbage between frames, bad frames and a truncated tail at `finish`.
    pub skipped_bytes: u64,
    /// Valid frames (records, packets, lines).
    pub frames: u64,
    /// Frames that looked like frames but failed a check (checksum, phasing bits, size,
    /// unparsable numbers, implausible values).
    pub bad_frames: u64,
    /// Samples produced.
    pub samples: u64,
}

/// A streaming decoder: bytes in arbitrary chunks in, samples out.
///
/// Decoders never panic on any input; they resynchronise after garbage and count what they
/// dropped. Serial protocols take bytes through [`Decoder::push`]; HID protocols take input
/// reports through [`Decoder::push_report`] and read recorded report logs
/// ([`crate::hid::encode_report_record`]) through `push`.
pub trait Decoder {
    /// The protocol this decoder reads.
    fn protocol(&self) -> Protocol;
    /// Feeds bytes; appends every completed sample to `samples`.
    fn push(&mut self, bytes: &[u8], samples: &mut Vec<Sample>);
    /// Feeds one HID input report (report id and the data after it, as WebHID gives them).
    /// Serial decoders treat the data as more bytes.
    fn push_report(&mut self, report_id: u8, data: &[u8], samples: &mut Vec<Sample>) {
        let _ = report_id;
        self.push(data, samples);
    }
    /// End of stream: completes what can be completed (an unterminated last text line) and
    /// counts the rest of the buffer as skipped.
    fn finish(&mut self, samples: &mut Vec<Sample>);
    /// Counts so far.
    fn stats(&self) -> DecoderStats;
    /// Bytes buffered while waiting for the rest of a frame.
    fn pending_bytes(&self) -> usize;
    /// Forgets buffered bytes, filter state and counts (e.g. after a reconnect).
    fn reset(&mut self);
    /// Convenience: pushes `bytes` and returns the samples.
    fn decode(&mut self, bytes: &[u8]) -> Vec<Sample> {
        let mut samples = Vec::new();
        self.push(bytes, &mut samples);
        samples
    }
}

/// The protocols Stance reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Protocol {
    /// Ascension Flock of Birds, RS-232 binary records.
    FlockOfBirds,
    /// Polhemus FASTRAK ASCII records.
    Fastrak,
    /// Polhemus Liberty / Patriot binary frames.
    Liberty,
    /// Xsens MTi MTData2 messages.
    Xsens,
    /// Text lines of hobby IMU boards with a quaternion.
    AsciiQuaternion,
    /// SlimeVR receiver over HID.
    SlimeVrHid,
    /// Sony DualSense or DualShock 4 over HID (gyro + accelerometer fused here).
    Gamepad,
}

/// A WebHID device filter (`navigator.hid.requestDevice({filters})`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct HidFilter {
    /// USB vendor id.
    pub vendor_id: u16,
    /// USB product id.
    pub product_id: u16,
}

impl Protocol {
    /// True when the device talks over WebHID rather than a serial port.
    pub fn is_hid(self) -> bool {
        matches!(self, Protocol::SlimeVrHid | Protocol::Gamepad)
    }

    /// A sensible serial baud rate to offer first (the user may change it).
    pub fn default_baud_rate(self) -> Option<u32> {
        match self {
            Protocol::FlockOfBirds => Some(115_200),
            Protocol::Fastrak => Some(9_600),
            Protocol::Liberty => Some(115_200),
            Protocol::Xsens => Some(115_200),
            Protocol::AsciiQuaternion => Some(115_200),
            Protocol::SlimeVrHid | Protocol::Gamepad => None,
        }
    }

    /// WebHID filters for the devices of this protocol (empty for serial protocols).
    pub fn hid_filters(self) -> &'static [HidFilter] {
        const SLIMEVR: &[HidFilter] = &[HidFilter {
            vendor_id: 0x1209,
            product_id: 0x7690,
        }];
        const SONY: &[HidFilter] = &[
            HidFilter {
                vendor_id: 0x054C,
                product_id: 0x0CE6,
            }, // DualSense
            HidFilter {
                vendor_id: 0x054C,
                product_id: 0x0DF2,
            }, // DualSense Edge
            HidFilter {
                vendor_id: 0x054C,
                product_id: 0x05C4,
            }, // DualShock 4 (CUH-ZCT1)
            HidFilter {
                vendor_id: 0x054C,
                product_id: 0x09CC,
            }, // DualShock 4 (CUH-ZCT2)
        ];
        match self {
            Protocol::SlimeVrHid => SLIMEVR,
            Protocol::Gamepad => SONY,
            _ => &[],
        }
    }
}

/// Everything needed to build a decoder for one device.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum DecoderConfig {
    /// Flock of Birds records in the configured mode.
    FlockOfBirds(FobConfig),
    /// FASTRAK ASCII records with the configured output list.
    Fastrak(FastrakConfig),
    /// Liberty / Patriot binary frames with the configured output list.
    Liberty(LibertyConfig),
    /// Xsens MTData2 messages (they describe their own contents).
    Xsens,
    /// Quaternion text lines in the configured component order.
    AsciiQuaternion(AsciiConfig),
    /// SlimeVR receiver reports (or a report log of them).
    SlimeVrHid,
    /// DualSense / DualShock 4 reports, fused into orientations.
    Gamepad(GamepadConfig),
}

impl DecoderConfig {
    /// The protocol the decoder built from this configuration reads.
    pub fn protocol(&self) -> Protocol {
        match self {
            DecoderConfig::FlockOfBirds(_) => Protocol::FlockOfBirds,
            DecoderConfig::Fastrak(_) => Protocol::Fastrak,
            DecoderConfig::Liberty(_) => Protocol::Liberty,
            DecoderConfig::Xsens => Protocol::Xsens,
            DecoderConfig::AsciiQuaternion(_) => Protocol::AsciiQuaternion,
            DecoderConfig::SlimeVrHid => Protocol::SlimeVrHid,
            DecoderConfig::Gamepad(_) => Protocol::Gamepad,
        }
    }
}

/// Builds the decoder for a configuration.
pub fn new_decoder(config: &DecoderConfig) -> Box<dyn Decoder + Send> {
    match config {
        DecoderConfig::FlockOfBirds(c) => Box::new(FobDecoder::new(c.clone())),
        DecoderConfig::Fastrak(c) => Box::new(FastrakDecoder::new(c.clone())),
        DecoderConfig::Liberty(c) => Box::new(LibertyDecoder::new(c.clone())),
        DecoderConfig::Xsens => Box::new(XsensDecoder::new()),
        DecoderConfig::AsciiQuaternion(c) => Box::new(AsciiQuaternionDecoder::new(c.clone())),
        DecoderConfig::SlimeVrHid => Box::new(SlimeVrDecoder::new()),
        DecoderConfig::Gamepad(c) => Box::new(GamepadDecoder::new(c.clone())),
    }
}

/// Builds a unit quaternion from components, rejecting non-finite values and norms farther
/// than `tolerance` from 1. The result is normalised.
pub(crate) fn checked_unit_quat(x: f64, y: f64, z: f64, w: f64, tolerance: f64) -> Option<DQuat> {
    let q = DQuat::from_xyzw(x, y, z, w);
    if !q.is_finite() {
        return None;
    }
    let norm = q.length();
    if (norm - 1.0).abs() > tolerance || norm < 1e-9 {
        return None;
    }
    Some(q / norm)
}

/// Rotation from azimuth (about Z), elevation (about Y) and roll (about X), in degrees:
/// `Rz(az) * Ry(el) * Rx(roll)`, the convention of Ascension and Polhemus.
pub(crate) fn quat_from_az_el_roll_deg(azimuth: f64, elevation: f64, roll: f64) -> DQuat {
    DQuat::from_euler(
        glam::EulerRot::ZYX,
        azimuth.to_radians(),
        elevation.to_radians(),
        roll.to_radians(),
    )
}

/// The inverse of [`quat_from_az_el_roll_deg`]: `(azimuth, elevation, roll)` in degrees.
pub(crate) fn az_el_roll_deg_from_quat(q: DQuat) -> (f64, f64, f64) {
    let (az, el, roll) = q.to_euler(glam::EulerRot::ZYX);
    (az.to_degrees(), el.to_degrees(), roll.to_degrees())
}

/// A rotation matrix is accepted when it is orthonormal within `tolerance` and right-handed.
pub(crate) fn checked_rotation_matrix(m: glam::DMat3, tolerance: f64) -> Option<DQuat> {
    if !m.is_finite() {
        return None;
    }
    let error = (m.transpose() * m - glam::DMat3::IDENTITY).to_cols_array();
    if error.iter().any(|e| e.abs() > tolerance) || m.determinant() < 0.5 {
        return None;
    }
    let q = DQuat::from_mat3(&m);
    if !q.is_finite() || q.length() < 1e-9 {
        return None;
    }
    Some(q.normalize())
}

/// Metres per inch.
pub const METRES_PER_INCH: f64 = 0.0254;
