//! A simulated device: a moving right arm (torso, upper arm, forearm, hand sensors) written in
//! any protocol, for demos, replay in the page and round-trip tests.
//!
//! Poses are expressed in a magnetic transmitter's frame (X forward, Y right, Z down), the arm
//! hanging along +Z at rest. IMU protocols (Xsens, SlimeVR, gamepads) report an earth frame
//! with Z up instead: their orientations are the same physical poses turned by 180 degrees
//! about X ([`EARTH_FROM_TRANSMITTER`]).

use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::ascii::{ComponentOrder, encode_line};
use crate::decoder::{Sample, SensorId};
use crate::fob::{FobCommandError, FobConfig, encode_record};
use crate::fusion::STANDARD_GRAVITY;
use crate::hid::{
    GamepadConfig, GamepadMotionReport, SLIMEVR_PACKET_LEN, encode_gamepad_report,
    encode_report_record, encode_slimevr_packet,
};
use crate::polhemus::{
    FastrakConfig, FastrakItem, LibertyConfig, LibertyFamily, LibertyItem, encode_fastrak_record,
    encode_liberty_frame,
};
use crate::xsens::{Precision, encode_mtdata2};

/// Simulated sensor on the torso, at [`ArmMotion::torso_m`].
pub const SENSOR_TORSO: SensorId = SensorId(1);
/// Simulated sensor at the middle of the upper arm.
pub const SENSOR_UPPER_ARM: SensorId = SensorId(2);
/// Simulated sensor at the middle of the forearm.
pub const SENSOR_FOREARM: SensorId = SensorId(3);
/// Simulated sensor on the back of the hand, 6 cm past the wrist.
pub const SENSOR_HAND: SensorId = SensorId(4);
/// All simulated sensors, proximal to distal.
pub const ARM_SENSORS: [SensorId; 4] =
    [SENSOR_TORSO, SENSOR_UPPER_ARM, SENSOR_FOREARM, SENSOR_HAND];

/// Rotation from the transmitter frame (Z down) to an earth frame with Z up.
pub const EARTH_FROM_TRANSMITTER: DQuat = DQuat::from_xyzw(1.0, 0.0, 0.0, 0.0);

/// A right arm reaching forward and out and bending the elbow, periodically.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ArmMotion {
    /// Torso sensor position in the transmitter frame.
    pub torso_m: DVec3,
    /// Shoulder to elbow, metres.
    pub upper_arm_len_m: f64,
    /// Elbow to wrist, metres.
    pub forearm_len_m: f64,
    /// Duration of one reach and return, seconds.
    pub period_secs: f64,
}

impl Default for ArmMotion {
    fn default() -> Self {
        ArmMotion {
            torso_m: DVec3::new(0.35, 0.0, 0.05),
            upper_arm_len_m: 0.30,
            forearm_len_m: 0.26,
            period_secs: 4.0,
        }
    }
}

/// Orientation and position of each sensor at one instant (transmitter frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArmPose {
    /// Torso sensor: position (m) and orientation.
    pub torso: (DVec3, DQuat),
    /// Upper-arm sensor: position (m) and orientation.
    pub upper_arm: (DVec3, DQuat),
    /// Forearm sensor: position (m) and orientation.
    pub forearm: (DVec3, DQuat),
    /// Hand sensor: position (m) and orientation.
    pub hand: (DVec3, DQuat),
}

impl ArmPose {
    /// Position and orientation of one of the [`ARM_SENSORS`]; `None` for any other id.
    pub fn sensor(&self, sensor: SensorId) -> Option<(DVec3, DQuat)> {
        match sensor {
            SENSOR_TORSO => Some(self.torso),
            SENSOR_UPPER_ARM => Some(self.upper_arm),
            SENSOR_FOREARM => Some(self.forearm),
            SENSOR_HAND => Some(self.hand),
            _ => None,
        }
    }
}

impl ArmMotion {
    /// The pose at `time_secs`.
    pub fn pose(&self, time_secs: f64) -> ArmPose {
        let phase = std::f64::consts::TAU * time_secs / self.period_secs.max(1e-3);
        let raise = 0.5 - 0.5 * phase.cos(); // 0 at rest, 1 at the top of the motion
        let torso_rotation = DQuat::from_rotation_z(10f64.to_radians() * phase.sin());
        let flexion = 70f64.to_radians() * raise;
        let abduction = 25f64.to_radians() * (2.0 * phase).sin().abs();
        let humeral_twist = 15f64.to_radians() * phase.sin();
        let elbow = 90f64.to_radians() * raise;
        let wrist = 20f64.to_radians() * (2.0 * phase).sin();

        let upper_rotation = torso_rotation
            * DQuat::from_rotation_y(flexion)
            * DQuat::from_rotation_x(-abduction)
            * DQuat::from_rotation_z(humeral_twist);
        let fore_rotation = upper_rotation * DQuat::from_rotation_y(elbow);
        let hand_rotation = fore_rotation * DQuat::from_rotation_x(wrist);

        let shoulder = self.torso_m + torso_rotation * DVec3::new(0.0, 0.18, -0.1);
        let elbow_m = shoulder + upper_rotation * DVec3::new(0.0, 0.0, self.upper_arm_len_m);
        let wrist_m = elbow_m + fore_rotation * DVec3::new(0.0, 0.0, self.forearm_len_m);
        ArmPose {
            torso: (self.torso_m, torso_rotation),
            upper_arm: (
                shoulder + upper_rotation * DVec3::new(0.0, 0.0, 0.5 * self.upper_arm_len_m),
                upper_rotation,
            ),
            forearm: (
                elbow_m + fore_rotation * DVec3::new(0.0, 0.0, 0.5 * self.forearm_len_m),
                fore_rotation,
            ),
            hand: (
                wrist_m + hand_rotation * DVec3::new(0.0, 0.0, 0.06),
                hand_rotation,
            ),
        }
    }

    /// Angular velocity of a sensor in its own frame (rad/s), by central difference.
    pub fn angular_velocity(&self, sensor: SensorId, time_secs: f64) -> DVec3 {
        let h = 1e-4;
        let before = self.pose(time_secs - h).sensor(sensor).map(|(_, q)| q);
        let after = self.pose(time_secs + h).sensor(sensor).map(|(_, q)| q);
        match (before, after) {
            (Some(before), Some(after)) => {
                let delta = before.inverse() * after;
                let delta = if delta.w < 0.0 { -delta } else { delta };
                let (axis, angle) = delta.to_axis_angle();
                if axis.is_finite() {
                    axis * angle / (2.0 * h)
                } else {
                    DVec3::ZERO
                }
            }
            _ => DVec3::ZERO,
        }
    }
}

/// The device to imitate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum SimulatedDevice {
    /// Flock of Birds; in group mode all four birds, otherwise one (the hand) reporting as
    /// `config.standalone_sensor`.
    FlockOfBirds(FobConfig),
    /// Polhemus FASTRAK ASCII records, the four sensors as stations 1 to 4.
    Fastrak(FastrakConfig),
    /// Polhemus Liberty or Patriot binary frames, the four sensors as stations 1 to 4.
    Liberty(LibertyConfig, LibertyFamily),
    /// One MTData2 message per sensor and frame, bus id = sensor id.
    Xsens(Precision),
    /// Quaternion text lines (`id: a, b, c, d`) in the given component order; orientation only.
    AsciiQuaternion(ComponentOrder),
    /// Report log of 64-byte receiver reports, four type-1 packets each.
    SlimeVr,
    /// Report log of a controller held in the hand (sensor 0).
    Gamepad {
        /// Scales and fusion settings of the controller.
        config: GamepadConfig,
        /// Bluetooth reports (with CRC) instead of USB ones.
        bluetooth: bool,
    },
}

/// What to simulate: the motion, the frame rate and how long.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SimulationOptions {
    /// The arm movement.
    pub motion: ArmMotion,
    /// Frames per second (each frame has one record per sensor).
    pub rate_hz: f64,
    /// Length of the stream, seconds (frames at `0, 1/rate, ...` up to and including it).
    pub duration_secs: f64,
}

impl Default for SimulationOptions {
    fn default() -> Self {
        SimulationOptions {
            motion: ArmMotion::default(),
            rate_hz: 100.0,
            duration_secs: 4.0,
        }
    }
}

/// Why [`simulate`] wrote no stream.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SimulationError {
    /// The rate is not a positive finite number, or the duration is negative or not finite.
    #[error("rate must be positive and finite and the duration non-negative")]
    BadTiming,
    /// The stream would have this many frames, more than 1,000,000.
    #[error("the stream would hold {0} frames; at most 1,000,000 are simulated")]
    TooLong(u64),
    /// The Flock of Birds configuration cannot encode the samples.
    #[error(transparent)]
    Fob(#[from] FobCommandError),
    /// The named protocol's encoder refused a sample.
    #[error("the {0} encoder cannot write this sample (check the output list and sensor ids)")]
    Encode(&'static str),
}

/// A simulated byte stream with the samples a perfect decoder would give back.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SimulatedStream {
    /// The encoded stream, as the device would send it.
    pub bytes: Vec<u8>,
    /// The samples that decoding `bytes` must give, in order.
    pub truth: Vec<Sample>,
}

/// Writes the stream.
pub fn simulate(
    device: &SimulatedDevice,
    options: &SimulationOptions,
) -> Result<SimulatedStream, SimulationError> {
    let rate_ok = options.rate_hz.is_finite() && options.rate_hz > 0.0;
    let duration_ok = options.duration_secs.is_finite() && options.duration_secs >= 0.0;
    if !rate_ok || !duration_ok {
        return Err(SimulationError::BadTiming);
    }
    // `as` saturates, so absurd durations become u64::MAX and are refused below.
    let frame_count = ((options.duration_secs * options.rate_hz).floor() as u64).saturating_add(1);
    if frame_count > 1_000_000 {
        return Err(SimulationError::TooLong(frame_count));
    }
    let mut stream = SimulatedStream::default();
    let motion = options.motion;
    for frame in 0..frame_count {
        let time_secs = frame as f64 / options.rate_hz;
        let time_us = (time_secs * 1e6).round() as u64;
        let pose = motion.pose(time_secs);
        let sample_of = |sensor: SensorId, earth: bool| -> Sample {
            let (position, orientation) = pose.sensor(sensor).unwrap_or_default();
            let orientation = if earth {
                EARTH_FROM_TRANSMITTER * orientation
            } else {
                orientation
            };
            Sample {
                sensor,
                orientation: Some(orientation),
                position_m: (!earth).then_some(position),
                ..Sample::default()
            }
        };
        match device {
            SimulatedDevice::FlockOfBirds(config) => {
                let sensors: Vec<SensorId> = if config.group_mode {
                    ARM_SENSORS.to_vec()
                } else {
                    vec![SENSOR_HAND]
                };
                for sensor in sensors {
                    let mut sample = sample_of(sensor, false);
                    if !config.group_mode {
                        sample.sensor = config.standalone_sensor;
                    }
                    stream.bytes.extend(encode_record(config, &sample)?);
                    if !config.mode.has_position() {
                        sample.position_m = None;
                    }
                    if !config.mode.has_orientation() {
                        sample.orientation = None;
                    }
                    stream.truth.push(sample);
                }
            }
            SimulatedDevice::Fastrak(config) => {
                for sensor in ARM_SENSORS {
                    let mut sample = sample_of(sensor, false);
                    let record = encode_fastrak_record(config, &sample)
                        .ok_or(SimulationError::Encode("FASTRAK"))?;
                    stream.bytes.extend(record);
                    if !config.items.contains(&FastrakItem::Position) {
                        sample.position_m = None;
                    }
                    stream.truth.push(sample);
                }
            }
            SimulatedDevice::Liberty(config, family) => {
                for sensor in ARM_SENSORS {
                    let mut sample = sample_of(sensor, false);
                    sample.counter = Some(frame as u32);
                    sample.device_time_us = Some(time_us / 1000 * 1000);
                    let record = encode_liberty_frame(config, *family, &sample)
                        .ok_or(SimulationError::Encode("Liberty"))?;
                    stream.bytes.extend(record);
                    if !config.items.contains(&LibertyItem::Position) {
                        sample.position_m = None;
                    }
                    if !config.items.contains(&LibertyItem::FrameCount) {
                        sample.counter = None;
                    }
                    if !config.items.contains(&LibertyItem::TimestampMs) {
                        sample.device_time_us = None;
                    }
                    stream.truth.push(sample);
                }
            }
            SimulatedDevice::Xsens(precision) => {
                for sensor in ARM_SENSORS {
                    let mut sample = sample_of(sensor, true);
                    sample.counter = Some((frame & 0xFFFF) as u32);
                    sample.device_time_us = Some(time_us / 100 * 100);
                    let message = encode_mtdata2(&sample, *precision)
                        .ok_or(SimulationError::Encode("Xsens"))?;
                    stream.bytes.extend(message);
                    stream.truth.push(sample);
                }
            }
            SimulatedDevice::AsciiQuaternion(order) => {
                for sensor in ARM_SENSORS {
                    let sample = sample_of(sensor, false);
                    let q = sample.orientation.unwrap_or_default();
                    stream.bytes.extend(encode_line(*order, sensor, q));
                    stream.truth.push(Sample {
                        position_m: None,
                        ..sample
                    });
                }
            }
            SimulatedDevice::SlimeVr => {
                let mut report = Vec::with_capacity(SLIMEVR_PACKET_LEN * ARM_SENSORS.len());
                for sensor in ARM_SENSORS {
                    let mut sample = sample_of(sensor, true);
                    let q = sample.orientation.unwrap_or_default();
                    sample.acceleration_mps2 =
                        Some(q.inverse() * DVec3::new(0.0, 0.0, STANDARD_GRAVITY));
                    let packet =
                        encode_slimevr_packet(&sample).ok_or(SimulationError::Encode("SlimeVR"))?;
                    report.extend_from_slice(&packet);
                    stream.truth.push(sample);
                }
                let record =
                    encode_report_record(0, &report).ok_or(SimulationError::Encode("SlimeVR"))?;
                stream.bytes.extend(record);
            }
            SimulatedDevice::Gamepad { config, bluetooth } => {
                let mut sample = sample_of(SENSOR_HAND, true);
                sample.sensor = SensorId(0);
                let q = sample.orientation.unwrap_or_default();
                let accel = q.inverse() * DVec3::new(0.0, 0.0, STANDARD_GRAVITY);
                let gyro = motion.angular_velocity(SENSOR_HAND, time_secs);
                sample.acceleration_mps2 = Some(accel);
                sample.angular_velocity_radps = Some(gyro);
                sample.device_time_us = Some(time_us);
                sample.counter = Some((frame & 0xFF) as u32);
                let report = GamepadMotionReport {
                    gyro_radps: gyro,
                    accel_mps2: accel,
                    time_us,
                    sequence: (frame & 0xFF) as u8,
                };
                let (report_id, data) = encode_gamepad_report(config, &report, *bluetooth);
                let record = encode_report_record(report_id, &data)
                    .ok_or(SimulationError::Encode("gamepad"))?;
                stream.bytes.extend(record);
                stream.truth.push(sample);
            }
        }
    }
    Ok(stream)
}
