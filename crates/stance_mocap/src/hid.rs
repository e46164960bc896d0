//! WebHID devices: the SlimeVR receiver and Sony DualSense / DualShock 4 controllers.
//!
//! The bridge hands each input report to [`Decoder::push_report`] (report id and the data
//! after it, as WebHID's `inputreport` event gives them). Recorded sessions are stored as a
//! *report log*, a byte stream of records written by [`encode_report_record`]:
//!
//! `'H' 'R' report_id len data[len] check`, where `check` makes the sum of
//! `report_id + len + data + check` zero modulo 256.
//!
//! [`Decoder::push`] on a HID decoder reads such a log, resynchronising after garbage like the
//! serial decoders do. Frames (for the counts) are SlimeVR packets and gamepad reports.

use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};

use crate::decoder::{Decoder, DecoderStats, Protocol, Sample, SensorId, checked_unit_quat};
use crate::framing::{Framer, Step};
use crate::fusion::{Madgwick, MadgwickSettings, STANDARD_GRAVITY};

// ---------------------------------------------------------------------------------------------
// Report log records
// ---------------------------------------------------------------------------------------------

const RECORD_MAGIC: [u8; 2] = *b"HR";
/// Magic, report id, length.
const RECORD_HEADER_LEN: usize = 4;
/// Header plus the check byte.
const RECORD_OVERHEAD: usize = RECORD_HEADER_LEN + 1;

/// Wraps one input report into a report-log record. `None` when the report is longer than
/// 255 bytes (no HID device here sends such reports).
pub fn encode_report_record(report_id: u8, data: &[u8]) -> Option<Vec<u8>> {
    let len = u8::try_from(data.len()).ok()?;
    let mut record = Vec::with_capacity(data.len() + RECORD_OVERHEAD);
    record.extend_from_slice(&RECORD_MAGIC);
    record.push(report_id);
    record.push(len);
    record.extend_from_slice(data);
    let sum = record
        .iter()
        .skip(2)
        .fold(0u8, |acc, &b| acc.wrapping_add(b));
    record.push(sum.wrapping_neg());
    Some(record)
}

/// Finds the next record; on a valid one calls `on_report(report_id, data)`.
fn record_step(window: &[u8], mut on_report: impl FnMut(u8, &[u8])) -> Step {
    let Some(start) = window.windows(2).position(|pair| pair == RECORD_MAGIC) else {
        let keep = usize::from(window.last() == Some(&b'H'));
        return if window.len() > keep {
            Step::Skip(window.len() - keep)
        } else {
            Step::NeedMore
        };
    };
    if start > 0 {
        return Step::Skip(start);
    }
    let Some(&[_, _, report_id, len]) = window.first_chunk::<4>() else {
        return Step::NeedMore;
    };
    let record_len = usize::from(len) + RECORD_OVERHEAD;
    let Some(record) = window.get(..record_len) else {
        return Step::NeedMore;
    };
    let sum = record
        .iter()
        .skip(2)
        .fold(0u8, |acc, &b| acc.wrapping_add(b));
    if sum != 0 {
        return Step::Bad(1);
    }
    let data = record
        .get(RECORD_HEADER_LEN..record_len - 1)
        .unwrap_or_default();
    on_report(report_id, data);
    Step::Frame(record_len)
}

/// Counts of a HID decoder: the record layer (report logs) and the report layer (packets).
#[derive(Clone, Debug, Default)]
struct HidCounts {
    records: Framer,
    reports: DecoderStats,
}

impl HidCounts {
    fn stats(&self) -> DecoderStats {
        let records = self.records.stats;
        let reports = self.reports;
        DecoderStats {
            bytes_received: records.bytes_received + reports.bytes_received,
            bytes_in_frames: reports.bytes_in_frames + records.frames * RECORD_OVERHEAD as u64,
            skipped_bytes: records.skipped_bytes + reports.skipped_bytes,
            frames: reports.frames,
            bad_frames: records.bad_frames + reports.bad_frames,
            samples: reports.samples,
        }
    }

    fn reset(&mut self) {
        self.records.reset();
        self.reports = DecoderStats::default();
    }
}

fn count_good(stats: &mut DecoderStats, bytes: usize) {
    stats.frames += 1;
    stats.bytes_in_frames += bytes as u64;
}

fn count_bad(stats: &mut DecoderStats, bytes: usize) {
    stats.bad_frames += 1;
    stats.skipped_bytes += bytes as u64;
}

fn i16_le(bytes: &[u8], offset: usize) -> Option<i16> {
    Some(i16::from_le_bytes(
        bytes.get(offset..offset + 2)?.try_into().ok()?,
    ))
}

fn vec3_i16_le(bytes: &[u8], offset: usize) -> Option<[i16; 3]> {
    Some([
        i16_le(bytes, offset)?,
        i16_le(bytes, offset + 2)?,
        i16_le(bytes, offset + 4)?,
    ])
}

// ---------------------------------------------------------------------------------------------
// SlimeVR receiver
// ---------------------------------------------------------------------------------------------

/// SlimeVR HID packets are 16 bytes, several per report: `type, tracker id, data[14]`.
pub const SLIMEVR_PACKET_LEN: usize = 16;
const SLIMEVR_QUATERNION_TOLERANCE: f64 = 0.02;

/// What a SlimeVR packet turned out to be.
enum SlimeVrPacket {
    Rotation(Sample),
    /// Info, status, runtime, button or registration packets: valid, no sample.
    Other,
}

fn q15(raw: i16) -> f64 {
    f64::from(raw) / 32768.0
}

fn parse_slimevr_packet(packet: &[u8]) -> Option<SlimeVrPacket> {
    let &[packet_type, tracker_id, ..] = packet else {
        return None;
    };
    let sensor = SensorId(u16::from(tracker_id));
    let accel_q7 = |offset: usize| -> Option<DVec3> {
        let a = vec3_i16_le(packet, offset)?;
        Some(DVec3::new(f64::from(a[0]), f64::from(a[1]), f64::from(a[2])) / 128.0)
    };
    match packet_type {
        // 1: full precision quaternion + acceleration; 4: quaternion + magnetometer.
        1 | 4 => {
            let q = [
                i16_le(packet, 2)?,
                i16_le(packet, 4)?,
                i16_le(packet, 6)?,
                i16_le(packet, 8)?,
            ];
            let orientation = checked_unit_quat(
                q15(q[0]),
                q15(q[1]),
                q15(q[2]),
                q15(q[3]),
                SLIMEVR_QUATERNION_TOLERANCE,
            )?;
            let acceleration_mps2 = if packet_type == 1 {
                Some(accel_q7(10)?)
            } else {
                None
            };
            Some(SlimeVrPacket::Rotation(Sample {
                sensor,
                orientation: Some(orientation),
                acceleration_mps2,
                ..Sample::default()
            }))
        }
        // 2 and 7: quaternion as a quantised exponential map (10/11/11 bits) + acceleration.
        2 | 7 => {
            let bits = u32::from_le_bytes(packet.get(5..9)?.try_into().ok()?);
            let v = DVec3::new(
                f64::from(bits & 1023) / 1024.0,
                f64::from((bits >> 10) & 2047) / 2048.0,
                f64::from((bits >> 21) & 2047) / 2048.0,
            ) * 2.0
                - DVec3::ONE;
            let d = v.length_squared();
            let inv_sqrt_d = 1.0 / (d + 1e-6).sqrt();
            let half_angle = std::f64::consts::FRAC_PI_2 * d * inv_sqrt_d;
            let k = half_angle.sin() * inv_sqrt_d;
            let q = DQuat::from_xyzw(k * v.x, k * v.y, k * v.z, half_angle.cos());
            Some(SlimeVrPacket::Rotation(Sample {
                sensor,
                orientation: Some(q.normalize()),
                acceleration_mps2: Some(accel_q7(9)?),
                ..Sample::default()
            }))
        }
        0 | 3 | 5 | 6 | 255 => Some(SlimeVrPacket::Other),
        _ => None,
    }
}

/// Decoder of SlimeVR receiver reports (VID 0x1209, PID 0x7690). Orientations are in the
/// tracker's earth frame (+Z up), as the trackers send them.
#[derive(Clone, Debug, Default)]
pub struct SlimeVrDecoder {
    counts: HidCounts,
}

impl SlimeVrDecoder {
    /// A decoder with zeroed counts.
    pub fn new() -> Self {
        SlimeVrDecoder::default()
    }
}

fn slimevr_report(stats: &mut DecoderStats, data: &[u8], samples: &mut Vec<Sample>) {
    for packet in data.chunks(SLIMEVR_PACKET_LEN) {
        if packet.len() < SLIMEVR_PACKET_LEN {
            count_bad(stats, packet.len());
            continue;
        }
        match parse_slimevr_packet(packet) {
            Some(SlimeVrPacket::Rotation(sample)) => {
                samples.push(sample);
                stats.samples += 1;
                count_good(stats, packet.len());
            }
            Some(SlimeVrPacket::Other) => count_good(stats, packet.len()),
            None => count_bad(stats, packet.len()),
        }
    }
}

impl Decoder for SlimeVrDecoder {
    fn protocol(&self) -> Protocol {
        Protocol::SlimeVrHid
    }

    fn push(&mut self, bytes: &[u8], samples: &mut Vec<Sample>) {
        let reports = &mut self.counts.reports;
        self.counts.records.push(bytes, |window| {
            record_step(window, |_, data| slimevr_report(reports, data, samples))
        });
    }

    fn push_report(&mut self, _report_id: u8, data: &[u8], samples: &mut Vec<Sample>) {
        self.counts.reports.bytes_received += data.len() as u64;
        slimevr_report(&mut self.counts.reports, data, samples);
    }

    fn finish(&mut self, _samples: &mut Vec<Sample>) {
        self.counts.records.drop_pending();
    }

    fn stats(&self) -> DecoderStats {
        self.counts.stats()
    }

    fn pending_bytes(&self) -> usize {
        self.counts.records.pending()
    }

    fn reset(&mut self) {
        self.counts.reset();
    }
}

/// Encodes a full-precision (type 1) SlimeVR packet for the simulator and tests.
pub fn encode_slimevr_packet(sample: &Sample) -> Option<[u8; SLIMEVR_PACKET_LEN]> {
    let tracker_id = u8::try_from(sample.sensor.0).ok()?;
    let q = sample.orientation?;
    let accel = sample.acceleration_mps2.unwrap_or(DVec3::ZERO);
    let to_q15 = |v: f64| ((v * 32768.0).round().clamp(-32768.0, 32767.0) as i16).to_le_bytes();
    let to_q7 = |v: f64| ((v * 128.0).round().clamp(-32768.0, 32767.0) as i16).to_le_bytes();
    let mut packet = vec![1, tracker_id];
    for field in [
        to_q15(q.x),
        to_q15(q.y),
        to_q15(q.z),
        to_q15(q.w),
        to_q7(accel.x),
        to_q7(accel.y),
        to_q7(accel.z),
    ] {
        packet.extend_from_slice(&field);
    }
    packet.try_into().ok()
}

// ---------------------------------------------------------------------------------------------
// DualSense / DualShock 4
// ---------------------------------------------------------------------------------------------

/// Which Sony controller; both send report id 1 over USB with different layouts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum GamepadModel {
    /// Sony DualSense (and DualSense Edge).
    #[default]
    DualSense,
    /// Sony DualShock 4 (both hardware revisions).
    DualShock4,
}

/// How a Sony controller's reports are read and fused.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GamepadConfig {
    /// Which controller, hence which report layout.
    pub model: GamepadModel,
    /// Degrees per second per raw gyro unit (nominal 1/16 for ±2000 °/s; the controller's
    /// calibration feature report refines it).
    pub gyro_dps_per_unit: f64,
    /// Standard gravities per raw accelerometer unit (nominal 1/8192 for ±4 g).
    pub accel_g_per_unit: f64,
    /// Report rate used when the controller's timestamps are unusable.
    pub nominal_rate_hz: f64,
    /// Madgwick filter settings for turning gyro and accelerometer into an orientation.
    pub fusion: MadgwickSettings,
}

impl Default for GamepadConfig {
    fn default() -> Self {
        GamepadConfig {
            model: GamepadModel::DualSense,
            gyro_dps_per_unit: 1.0 / 16.0,
            accel_g_per_unit: 1.0 / 8192.0,
            nominal_rate_hz: 250.0,
            fusion: MadgwickSettings::default(),
        }
    }
}

/// USB input report id of both controllers (63 data bytes).
pub const REPORT_USB: u8 = 0x01;
/// Bluetooth input report id of the DualSense ([`BLUETOOTH_REPORT_DATA_LEN`] data bytes).
pub const REPORT_DUALSENSE_BLUETOOTH: u8 = 0x31;
/// Bluetooth input report id of the DualShock 4 ([`BLUETOOTH_REPORT_DATA_LEN`] data bytes).
pub const REPORT_DUALSHOCK4_BLUETOOTH: u8 = 0x11;
/// Bluetooth reports are 78 bytes with the id, the last 4 a CRC-32 seeded with 0xA1.
pub const BLUETOOTH_REPORT_DATA_LEN: usize = 77;
const BLUETOOTH_CRC_SEED: u8 = 0xA1;

/// Where the motion data sits in a report's data (after the report id).
#[derive(Clone, Copy, Debug)]
struct MotionLayout {
    gyro: usize,
    accel: usize,
    timestamp: usize,
    /// Microseconds per timestamp tick, as a fraction (numerator, denominator).
    tick_us: (u64, u64),
    /// Width of the timestamp in bytes (4 on DualSense, 2 on DualShock 4).
    timestamp_len: usize,
    sequence: Option<usize>,
    bluetooth: bool,
}

fn layout(model: GamepadModel, report_id: u8) -> Option<MotionLayout> {
    // Offsets from Linux hid-playstation.c.
    let dualsense = |base: usize, bluetooth: bool| MotionLayout {
        gyro: base + 15,
        accel: base + 21,
        timestamp: base + 27,
        tick_us: (1, 3),
        timestamp_len: 4,
        sequence: Some(base + 6),
        bluetooth,
    };
    let dualshock4 = |base: usize, bluetooth: bool| MotionLayout {
        gyro: base + 12,
        accel: base + 18,
        timestamp: base + 9,
        tick_us: (16, 3),
        timestamp_len: 2,
        sequence: None,
        bluetooth,
    };
    match (report_id, model) {
        (REPORT_USB, GamepadModel::DualSense) => Some(dualsense(0, false)),
        (REPORT_USB, GamepadModel::DualShock4) => Some(dualshock4(0, false)),
        (REPORT_DUALSENSE_BLUETOOTH, _) => Some(dualsense(1, true)),
        (REPORT_DUALSHOCK4_BLUETOOTH, _) => Some(dualshock4(2, true)),
        _ => None,
    }
}

/// CRC-32 (IEEE 802.3, reflected), as used by the controllers' Bluetooth reports.
pub fn crc32(bytes: impl IntoIterator<Item = u8>) -> u32 {
    let mut crc = 0xFFFF_FFFFu32;
    for byte in bytes {
        crc ^= u32::from(byte);
        for _ in 0..8 {
            let mask = (crc & 1).wrapping_neg();
            crc = (crc >> 1) ^ (0xEDB8_8320 & mask);
        }
    }
    !crc
}

fn bluetooth_crc_ok(report_id: u8, data: &[u8]) -> bool {
    let Some((body, crc)) = data.split_at_checked(BLUETOOTH_REPORT_DATA_LEN - 4) else {
        return false;
    };
    let Ok(expected) = <[u8; 4]>::try_from(crc) else {
        return false;
    };
    let computed = crc32(
        [BLUETOOTH_CRC_SEED, report_id]
            .into_iter()
            .chain(body.iter().copied()),
    );
    computed == u32::from_le_bytes(expected)
}

/// Decoder of DualSense / DualShock 4 input reports: the controller gives angular velocity
/// and acceleration, a Madgwick filter turns them into an orientation in an earth frame with
/// +Z up (heading arbitrary until a heading reset).
#[derive(Clone, Debug)]
pub struct GamepadDecoder {
    config: GamepadConfig,
    counts: HidCounts,
    motion: GamepadMotion,
}

#[derive(Clone, Debug)]
struct GamepadMotion {
    filter: Madgwick,
    last_tick: Option<u32>,
    time_us: u64,
}

impl GamepadDecoder {
    /// A decoder with `config`'s scales and filter settings, its filter not yet aligned.
    pub fn new(config: GamepadConfig) -> Self {
        let filter = Madgwick::new(config.fusion);
        GamepadDecoder {
            config,
            counts: HidCounts::default(),
            motion: GamepadMotion {
                filter,
                last_tick: None,
                time_us: 0,
            },
        }
    }
}

fn gamepad_report(
    config: &GamepadConfig,
    motion: &mut GamepadMotion,
    stats: &mut DecoderStats,
    report_id: u8,
    data: &[u8],
    samples: &mut Vec<Sample>,
) {
    let Some(layout) = layout(config.model, report_id) else {
        // Output-report echoes, feature replies, reduced Bluetooth reports: not motion data.
        count_good(stats, data.len());
        return;
    };
    match parse_motion(config, motion, layout, report_id, data) {
        Some(sample) => {
            samples.push(sample);
            stats.samples += 1;
            count_good(stats, data.len());
        }
        None => count_bad(stats, data.len()),
    }
}

fn parse_motion(
    config: &GamepadConfig,
    motion: &mut GamepadMotion,
    layout: MotionLayout,
    report_id: u8,
    data: &[u8],
) -> Option<Sample> {
    if layout.bluetooth && !bluetooth_crc_ok(report_id, data) {
        return None;
    }
    let gyro_raw = vec3_i16_le(data, layout.gyro)?;
    let accel_raw = vec3_i16_le(data, layout.accel)?;
    let tick = match layout.timestamp_len {
        4 => u32::from_le_bytes(
            data.get(layout.timestamp..layout.timestamp + 4)?
                .try_into()
                .ok()?,
        ),
        _ => u32::from(u16::from_le_bytes(
            data.get(layout.timestamp..layout.timestamp + 2)?
                .try_into()
                .ok()?,
        )),
    };
    let to_vec = |raw: [i16; 3], scale: f64| {
        DVec3::new(f64::from(raw[0]), f64::from(raw[1]), f64::from(raw[2])) * scale
    };
    let gyro_radps = to_vec(gyro_raw, config.gyro_dps_per_unit.to_radians());
    let accel_mps2 = to_vec(accel_raw, config.accel_g_per_unit * STANDARD_GRAVITY);
    let nominal_dt = if config.nominal_rate_hz > 0.0 {
        1.0 / config.nominal_rate_hz
    } else {
        0.004
    };
    let dt_secs = match motion.last_tick {
        Some(last) => {
            let wrap_mask = if layout.timestamp_len == 4 {
                u32::MAX
            } else {
                u32::from(u16::MAX)
            };
            let delta_ticks = u64::from(tick.wrapping_sub(last) & wrap_mask);
            let delta_us = delta_ticks * layout.tick_us.0 / layout.tick_us.1;
            motion.time_us = motion.time_us.wrapping_add(delta_us);
            let dt = delta_us as f64 * 1e-6;
            if dt > 0.0 && dt <= 0.1 {
                dt
            } else {
                nominal_dt
            }
        }
        None => {
            motion.time_us = u64::from(tick) * layout.tick_us.0 / layout.tick_us.1;
            nominal_dt
        }
    };
    motion.last_tick = Some(tick);
    let orientation = motion.filter.update(gyro_radps, accel_mps2, dt_secs);
    let counter = layout
        .sequence
        .and_then(|i| data.get(i))
        .map(|&s| u32::from(s));
    Some(Sample {
        sensor: SensorId(0),
        counter,
        device_time_us: Some(motion.time_us),
        position_m: None,
        orientation: Some(orientation),
        acceleration_mps2: Some(accel_mps2),
        angular_velocity_radps: Some(gyro_radps),
    })
}

impl Decoder for GamepadDecoder {
    fn protocol(&self) -> Protocol {
        Protocol::Gamepad
    }

    fn push(&mut self, bytes: &[u8], samples: &mut Vec<Sample>) {
        let reports = &mut self.counts.reports;
        let config = &self.config;
        let motion = &mut self.motion;
        self.counts.records.push(bytes, |window| {
            record_step(window, |report_id, data| {
                gamepad_report(config, motion, reports, report_id, data, samples)
            })
        });
    }

    fn push_report(&mut self, report_id: u8, data: &[u8], samples: &mut Vec<Sample>) {
        self.counts.reports.bytes_received += data.len() as u64;
        gamepad_report(
            &self.config,
            &mut self.motion,
            &mut self.counts.reports,
            report_id,
            data,
            samples,
        );
    }

    fn finish(&mut self, _samples: &mut Vec<Sample>) {
        self.counts.records.drop_pending();
    }

    fn stats(&self) -> DecoderStats {
        self.counts.stats()
    }

    fn pending_bytes(&self) -> usize {
        self.counts.records.pending()
    }

    fn reset(&mut self) {
        self.counts.reset();
        self.motion.filter.reset();
        self.motion.last_tick = None;
        self.motion.time_us = 0;
    }
}

/// Raw motion fields of one gamepad report, for the simulator and tests.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GamepadMotionReport {
    /// Angular velocity, controller frame, rad/s.
    pub gyro_radps: DVec3,
    /// Accelerometer reading (specific force), controller frame, m/s².
    pub accel_mps2: DVec3,
    /// Device clock in microseconds, written as the controller's timestamp ticks.
    pub time_us: u64,
    /// Report sequence number (written by DualSense layouts only).
    pub sequence: u8,
}

/// Encodes a report as the controller sends it: `(report_id, data)`. Over USB (report 1, 63
/// data bytes) unless `bluetooth` (0x31 / 0x11, 77 data bytes with CRC).
pub fn encode_gamepad_report(
    config: &GamepadConfig,
    motion: &GamepadMotionReport,
    bluetooth: bool,
) -> (u8, Vec<u8>) {
    let report_id = match (bluetooth, config.model) {
        (false, _) => REPORT_USB,
        (true, GamepadModel::DualSense) => REPORT_DUALSENSE_BLUETOOTH,
        (true, GamepadModel::DualShock4) => REPORT_DUALSHOCK4_BLUETOOTH,
    };
    let data_len = if bluetooth {
        BLUETOOTH_REPORT_DATA_LEN
    } else {
        63
    };
    let mut data = vec![0u8; data_len];
    let Some(layout) = layout(config.model, report_id) else {
        return (report_id, data);
    };
    let gyro = motion.gyro_radps / config.gyro_dps_per_unit.to_radians();
    let accel = motion.accel_mps2 / (config.accel_g_per_unit * STANDARD_GRAVITY);
    let mut put = |offset: usize, bytes: &[u8]| {
        if let Some(slot) = data.get_mut(offset..offset + bytes.len()) {
            slot.copy_from_slice(bytes);
        }
    };
    for (base, v) in [(layout.gyro, gyro), (layout.accel, accel)] {
        for (i, c) in v.to_array().into_iter().enumerate() {
            let raw = c.round().clamp(-32768.0, 32767.0) as i16;
            put(base + 2 * i, &raw.to_le_bytes());
        }
    }
    let ticks = motion.time_us * layout.tick_us.1 / layout.tick_us.0;
    if layout.timestamp_len == 4 {
        put(layout.timestamp, &(ticks as u32).to_le_bytes());
    } else {
        put(layout.timestamp, &(ticks as u16).to_le_bytes());
    }
    if let Some(sequence) = layout.sequence {
        put(sequence, &[motion.sequence]);
    }
    if bluetooth {
        let body_len = BLUETOOTH_REPORT_DATA_LEN - 4;
        let body = data.get(..body_len).unwrap_or_default();
        let crc = crc32(
            [BLUETOOTH_CRC_SEED, report_id]
                .into_iter()
                .chain(body.iter().copied()),
        );
        if let Some(slot) = data.get_mut(body_len..body_len + 4) {
            slot.copy_from_slice(&crc.to_le_bytes());
        }
    }
    (report_id, data)
}
