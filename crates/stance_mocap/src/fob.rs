//! Ascension Flock of Birds (and compatible: pcBIRD, SpacePad, MotionStar serial) RS-232
//! binary records, and the commands the bridge sends.
//!
//! A record is a sequence of 14-bit words sent least significant byte first. The first byte of
//! a record has bit 7 set (the phasing bit), every other byte has it clear, which is how the
//! decoder finds record starts after garbage. In group mode each record ends with the bird's
//! address byte. Orientation is reported by the bird as the rotation from the transmitter
//! frame to the sensor frame; samples carry its inverse (sensor to transmitter), like VRPN.

use glam::{DMat3, DQuat, DVec3};
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::decoder::{
    METRES_PER_INCH, Protocol, Sample, SensorId, az_el_roll_deg_from_quat, checked_rotation_matrix,
    checked_unit_quat, quat_from_az_el_roll_deg,
};
use crate::framing::{FrameFormat, FramedDecoder, Step};

/// Record layout selected by the mode command.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum FobMode {
    /// 'V': x, y, z.
    Position,
    /// 'W': azimuth, elevation, roll.
    Angles,
    /// 'X': 3x3 rotation matrix.
    Matrix,
    /// 'Y': position then angles.
    PositionAngles,
    /// 'Z': position then matrix.
    PositionMatrix,
    /// '\': quaternion, scalar first.
    Quaternion,
    /// ']': position then quaternion.
    #[default]
    PositionQuaternion,
}

impl FobMode {
    /// All modes, for tests and user interfaces.
    pub const ALL: [FobMode; 7] = [
        FobMode::Position,
        FobMode::Angles,
        FobMode::Matrix,
        FobMode::PositionAngles,
        FobMode::PositionMatrix,
        FobMode::Quaternion,
        FobMode::PositionQuaternion,
    ];

    /// Number of 16-bit words in a record of this mode.
    pub fn word_count(self) -> usize {
        match self {
            FobMode::Position | FobMode::Angles => 3,
            FobMode::Matrix => 9,
            FobMode::PositionAngles => 6,
            FobMode::PositionMatrix => 12,
            FobMode::Quaternion => 4,
            FobMode::PositionQuaternion => 7,
        }
    }

    /// The command byte that selects this mode.
    pub fn command_byte(self) -> u8 {
        match self {
            FobMode::Position => b'V',
            FobMode::Angles => b'W',
            FobMode::Matrix => b'X',
            FobMode::PositionAngles => b'Y',
            FobMode::PositionMatrix => b'Z',
            FobMode::Quaternion => b'\\',
            FobMode::PositionQuaternion => b']',
        }
    }

    /// Whether records of this mode carry an orientation.
    pub fn has_orientation(self) -> bool {
        self != FobMode::Position
    }

    /// Whether records of this mode carry a position.
    pub fn has_position(self) -> bool {
        matches!(
            self,
            FobMode::Position
                | FobMode::PositionAngles
                | FobMode::PositionMatrix
                | FobMode::PositionQuaternion
        )
    }
}

/// How the birds are set up.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FobConfig {
    /// Record layout the birds are set to (the mode command).
    pub mode: FobMode,
    /// Group mode: every record ends with the bird's address byte.
    pub group_mode: bool,
    /// Full-scale position range in inches (36 standard, 72 with the scaling option, 144 ERT).
    pub position_range_inches: f64,
    /// Sensor id given to records when not in group mode (which carry no address).
    pub standalone_sensor: SensorId,
}

impl Default for FobConfig {
    fn default() -> Self {
        FobConfig {
            mode: FobMode::PositionQuaternion,
            group_mode: false,
            position_range_inches: 36.0,
            standalone_sensor: SensorId(1),
        }
    }
}

impl FobConfig {
    /// Bytes in one record, including the group-mode address byte.
    pub fn record_len(&self) -> usize {
        self.mode.word_count() * 2 + usize::from(self.group_mode)
    }
}

const PHASING_BIT: u8 = 0x80;
const FULL_SCALE: f64 = 32768.0;
/// Quaternions and matrices carry 14 significant bits; anything farther from unit length or
/// orthonormality than this is a corrupted record.
const UNIT_TOLERANCE: f64 = 0.02;

/// Streaming decoder of Flock of Birds records.
pub type FobDecoder = FramedDecoder<FobConfig>;

impl FobDecoder {
    /// A decoder of records laid out as `config` says.
    pub fn new(config: FobConfig) -> Self {
        FramedDecoder::with_format(config)
    }

    /// The record layout it reads.
    pub fn config(&self) -> &FobConfig {
        self.format()
    }
}

/// Reads word `index` of a record: LS byte then MS byte, 7 data bits each, left-justified.
fn word(record: &[u8], index: usize) -> Option<i16> {
    let ls = *record.get(index * 2)?;
    let ms = *record.get(index * 2 + 1)?;
    let bits = (u16::from(ms & 0x7F) << 9) | (u16::from(ls & 0x7F) << 2);
    Some(bits as i16)
}

fn words(record: &[u8], first: usize, count: usize) -> Option<Vec<f64>> {
    (first..first + count)
        .map(|i| word(record, i).map(f64::from))
        .collect()
}

impl FrameFormat for FobConfig {
    const PROTOCOL: Protocol = Protocol::FlockOfBirds;

    fn next_frame(&self, window: &[u8], samples: &mut Vec<Sample>) -> Step {
        record_step(self, window, samples)
    }
}

/// Finds the next record: its phasing bit, its length, its address in group mode.
fn record_step(config: &FobConfig, window: &[u8], samples: &mut Vec<Sample>) -> Step {
    let Some(&first) = window.first() else {
        return Step::NeedMore;
    };
    if first & PHASING_BIT == 0 {
        let garbage = window
            .iter()
            .position(|b| b & PHASING_BIT != 0)
            .unwrap_or(window.len());
        return Step::Skip(garbage);
    }
    let record_len = config.record_len();
    let data_len = config.mode.word_count() * 2;
    // A phasing bit inside the record means this record was cut short: restart there.
    let seen = window.len().min(record_len);
    if let Some(restart) = window
        .get(1..seen)
        .and_then(|rest| rest.iter().position(|b| b & PHASING_BIT != 0))
    {
        return Step::Bad(restart + 1);
    }
    if window.len() < record_len {
        return Step::NeedMore;
    }
    let Some(record) = window.get(..record_len) else {
        return Step::NeedMore;
    };
    let sensor = if config.group_mode {
        match record.get(data_len) {
            Some(&address) if (1..=126).contains(&address) => SensorId(u16::from(address)),
            _ => return Step::Bad(record_len),
        }
    } else {
        config.standalone_sensor
    };
    match decode_record(config, record, sensor) {
        Some(sample) => {
            samples.push(sample);
            Step::Frame(record_len)
        }
        None => Step::Bad(record_len),
    }
}

fn decode_record(config: &FobConfig, record: &[u8], sensor: SensorId) -> Option<Sample> {
    let mode = config.mode;
    let mut sample = Sample {
        sensor,
        ..Sample::default()
    };
    let mut next_word = 0;
    if mode.has_position() {
        let p = words(record, 0, 3)?;
        let scale = config.position_range_inches / FULL_SCALE * METRES_PER_INCH;
        sample.position_m = Some(DVec3::new(
            p.first()? * scale,
            p.get(1)? * scale,
            p.get(2)? * scale,
        ));
        next_word = 3;
    }
    sample.orientation = match mode {
        FobMode::Position => None,
        FobMode::Angles | FobMode::PositionAngles => {
            let a = words(record, next_word, 3)?;
            let deg = 180.0 / FULL_SCALE;
            Some(quat_from_az_el_roll_deg(
                a.first()? * deg,
                a.get(1)? * deg,
                a.get(2)? * deg,
            ))
        }
        FobMode::Matrix | FobMode::PositionMatrix => {
            let m = words(record, next_word, 9)?;
            let mut columns = [0.0; 9];
            for (slot, value) in columns.iter_mut().zip(&m) {
                *slot = value / FULL_SCALE;
            }
            // The bird sends the transmitter-to-sensor matrix column by column.
            let sensor_from_transmitter = DMat3::from_cols_array(&columns);
            Some(checked_rotation_matrix(
                sensor_from_transmitter.transpose(),
                UNIT_TOLERANCE,
            )?)
        }
        FobMode::Quaternion | FobMode::PositionQuaternion => {
            let q = words(record, next_word, 4)?;
            let s = 1.0 / FULL_SCALE;
            // q0 is the scalar; the bird's quaternion rotates the transmitter into the sensor.
            let sensor_from_transmitter = checked_unit_quat(
                q.get(1)? * s,
                q.get(2)? * s,
                q.get(3)? * s,
                q.first()? * s,
                UNIT_TOLERANCE,
            )?;
            Some(sensor_from_transmitter.conjugate())
        }
    };
    Some(sample)
}

/// Errors building commands or records.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum FobCommandError {
    /// A bird address for the RS232-TO-FBB prefix outside 1..=30.
    #[error("bird address {0} is outside 1..=30")]
    BadAddress(u8),
    /// A sample's sensor id outside 1..=126, which a group-mode record's address byte cannot carry.
    #[error("group mode needs a bird address in 1..=126, got {0}")]
    BadRecordAddress(u16),
    /// The sample lacks the position or orientation that the mode's records carry.
    #[error("the {0:?} mode needs a {1} in the sample")]
    MissingField(FobMode, &'static str),
}

/// Commands sent to the flock (RS-232 command set).
pub mod command {
    use super::{FobCommandError, FobConfig, FobMode};

    /// Start continuous output of records.
    pub const STREAM: u8 = b'@';
    /// Request one record (also stops streaming).
    pub const POINT: u8 = b'B';
    /// Wake up / start running.
    pub const RUN: u8 = b'F';
    /// Stop the transmitter.
    pub const SLEEP: u8 = b'G';
    /// CHANGE VALUE command byte.
    pub const CHANGE_VALUE: u8 = b'P';
    /// CHANGE VALUE parameter: position scaling (36 or 72 inch full-scale range).
    pub const PARAMETER_POSITION_SCALING: u8 = 3;
    /// CHANGE VALUE parameter: group mode (records end with the bird address).
    pub const PARAMETER_GROUP_MODE: u8 = 35;
    /// CHANGE VALUE parameter: FBB auto-configuration (number of birds on the bus).
    pub const PARAMETER_AUTO_CONFIG: u8 = 50;

    /// Selects the record layout.
    pub fn set_mode(mode: FobMode) -> [u8; 1] {
        [mode.command_byte()]
    }

    /// `CHANGE VALUE GROUP MODE`: on, every record carries the bird address.
    pub fn group_mode(enabled: bool) -> [u8; 3] {
        [CHANGE_VALUE, PARAMETER_GROUP_MODE, u8::from(enabled)]
    }

    /// `CHANGE VALUE FBB AUTO-CONFIGURATION` with the number of birds.
    pub fn auto_config(bird_count: u8) -> [u8; 3] {
        [CHANGE_VALUE, PARAMETER_AUTO_CONFIG, bird_count]
    }

    /// `CHANGE VALUE POSITION SCALING`: false = 36 inches, true = 72 inches.
    pub fn position_scaling(range_72_inches: bool) -> [u8; 3] {
        [
            CHANGE_VALUE,
            PARAMETER_POSITION_SCALING,
            u8::from(range_72_inches),
        ]
    }

    /// The RS232-TO-FBB prefix that routes the following command to one bird.
    pub fn to_bird(address: u8) -> Result<u8, FobCommandError> {
        match address {
            1..=15 => Ok(0xF0 | address),
            16..=30 => Ok(0xE0 | (address - 16)),
            _ => Err(FobCommandError::BadAddress(address)),
        }
    }

    /// The whole setup the bridge sends before streaming: auto-configure `bird_count` birds,
    /// select the mode on each (addresses 1..=bird_count), set group mode as configured,
    /// then STREAM.
    pub fn start_streaming(config: &FobConfig, bird_count: u8) -> Result<Vec<u8>, FobCommandError> {
        let mut bytes = Vec::new();
        if bird_count > 1 {
            bytes.extend_from_slice(&auto_config(bird_count));
            for address in 1..=bird_count {
                bytes.push(to_bird(address)?);
                bytes.extend_from_slice(&set_mode(config.mode));
            }
        } else {
            bytes.extend_from_slice(&set_mode(config.mode));
        }
        if (config.position_range_inches - 72.0).abs() < 1e-9 {
            bytes.extend_from_slice(&position_scaling(true));
        }
        bytes.extend_from_slice(&group_mode(config.group_mode));
        bytes.push(STREAM);
        Ok(bytes)
    }

    /// Stops streaming (POINT mode: nothing is sent until the next request).
    pub fn stop_streaming() -> [u8; 1] {
        [POINT]
    }
}

fn push_word(bytes: &mut Vec<u8>, value: f64) {
    let v = value.round().clamp(-32768.0, 32767.0) as i16 as u16;
    let first = bytes.is_empty();
    let ls = ((v >> 2) & 0x7F) as u8 | if first { PHASING_BIT } else { 0 };
    let ms = ((v >> 9) & 0x7F) as u8;
    bytes.push(ls);
    bytes.push(ms);
}

/// Encodes one record as a bird would send it (for the simulator and tests).
pub fn encode_record(config: &FobConfig, sample: &Sample) -> Result<Vec<u8>, FobCommandError> {
    let mode = config.mode;
    let mut bytes = Vec::with_capacity(config.record_len());
    if mode.has_position() {
        let p = sample
            .position_m
            .ok_or(FobCommandError::MissingField(mode, "position"))?;
        let scale = FULL_SCALE / (config.position_range_inches * METRES_PER_INCH);
        for value in p.to_array() {
            push_word(&mut bytes, value * scale);
        }
    }
    if mode != FobMode::Position {
        let q = sample
            .orientation
            .ok_or(FobCommandError::MissingField(mode, "orientation"))?;
        match mode {
            FobMode::Angles | FobMode::PositionAngles => {
                let (az, el, roll) = az_el_roll_deg_from_quat(q);
                for value in [az, el, roll] {
                    push_word(&mut bytes, value * FULL_SCALE / 180.0);
                }
            }
            FobMode::Matrix | FobMode::PositionMatrix => {
                let sensor_from_transmitter = DMat3::from_quat(q).transpose();
                for value in sensor_from_transmitter.to_cols_array() {
                    push_word(&mut bytes, value * FULL_SCALE);
                }
            }
            _ => {
                let bird = canonical(q.conjugate());
                for value in [bird.w, bird.x, bird.y, bird.z] {
                    push_word(&mut bytes, value * FULL_SCALE);
                }
            }
        }
    }
    if config.group_mode {
        match u8::try_from(sample.sensor.0) {
            Ok(address @ 1..=126) => bytes.push(address),
            _ => return Err(FobCommandError::BadRecordAddress(sample.sensor.0)),
        }
    }
    Ok(bytes)
}

/// The quaternion with a non-negative scalar part (same rotation).
fn canonical(q: DQuat) -> DQuat {
    if q.w < 0.0 { -q } else { q }
}
