//! Xsens MTi Xbus messages carrying MTData2.
//!
//! Message: `FA BID MID LEN [EXT_LEN_HI EXT_LEN_LO when LEN = FF] DATA CS`, where the sum of
//! every byte after the preamble, checksum included, is 0 modulo 256. MTData2 data is a list
//! of `(data id u16 BE, size u8, value)` packets, big-endian values. The low bits of a data id
//! select the precision (float32, fixed 12.20, fixed 16.32, float64) and the coordinate
//! system (ENU, NED, NWU); orientations map sensor vectors into that earth frame.

use glam::{DMat3, DQuat, DVec3};

use crate::decoder::{Protocol, Sample, SensorId, checked_rotation_matrix, checked_unit_quat};
use crate::framing::{FrameFormat, FramedDecoder, Step};

/// First byte of every Xbus message.
pub const PREAMBLE: u8 = 0xFA;
/// Bus identifier of a stand-alone device ("master").
pub const BUS_ID_MASTER: u8 = 0xFF;
/// Message id of MTData2 (the data message).
pub const MID_MTDATA2: u8 = 0x36;
/// MTData2 data identifiers (with their precision/coordinate bits cleared).
pub const DATA_PACKET_COUNTER: u16 = 0x1020;
/// SampleTimeFine: device clock, ticks of 100 µs.
pub const DATA_SAMPLE_TIME_FINE: u16 = 0x1060;
/// Orientation quaternion, w x y z, sensor to earth frame.
pub const DATA_QUATERNION: u16 = 0x2010;
/// Orientation as a rotation matrix, column-major, sensor to earth frame.
pub const DATA_ROTATION_MATRIX: u16 = 0x2020;
/// Orientation as Euler angles: roll, pitch, yaw in degrees (Z-Y-X order).
pub const DATA_EULER_ANGLES: u16 = 0x2030;
/// Acceleration (specific force), sensor frame, m/s².
pub const DATA_ACCELERATION: u16 = 0x4020;
/// Rate of turn, sensor frame, rad/s.
pub const DATA_RATE_OF_TURN: u16 = 0x8020;

/// Longest payload accepted (extended-length messages go up to 2048 bytes on MTi devices).
const MAX_PAYLOAD: usize = 2048;
const UNIT_TOLERANCE: f64 = 0.02;
/// SampleTimeFine counts at 10 kHz.
const MICROSECONDS_PER_FINE_TICK: u64 = 100;

/// Value precision selected by the two low bits of a data id.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize,
)]
pub enum Precision {
    /// IEEE 754 single precision (4 bytes).
    #[default]
    Float32,
    /// Signed fixed point with 12 integer and 20 fraction bits (4 bytes).
    Fixed1220,
    /// Signed fixed point with 16 integer and 32 fraction bits (6 bytes, fraction first).
    Fixed1632,
    /// IEEE 754 double precision (8 bytes).
    Float64,
}

impl Precision {
    /// The precision that a data id's two low bits select.
    pub fn from_data_id(id: u16) -> Precision {
        match id & 0x3 {
            0 => Precision::Float32,
            1 => Precision::Fixed1220,
            2 => Precision::Fixed1632,
            _ => Precision::Float64,
        }
    }

    /// The two low bits of a data id that select this precision.
    pub fn bits(self) -> u16 {
        match self {
            Precision::Float32 => 0,
            Precision::Fixed1220 => 1,
            Precision::Fixed1632 => 2,
            Precision::Float64 => 3,
        }
    }

    /// Bytes of one value in this precision.
    pub fn value_len(self) -> usize {
        match self {
            Precision::Float32 | Precision::Fixed1220 => 4,
            Precision::Fixed1632 => 6,
            Precision::Float64 => 8,
        }
    }

    fn read(self, bytes: &[u8]) -> Option<f64> {
        let value = match self {
            Precision::Float32 => f64::from(f32::from_be_bytes(bytes.try_into().ok()?)),
            Precision::Float64 => f64::from_be_bytes(bytes.try_into().ok()?),
            Precision::Fixed1220 => {
                f64::from(i32::from_be_bytes(bytes.try_into().ok()?)) / 1048576.0
            }
            Precision::Fixed1632 => {
                // 32-bit fraction first, then the signed 16-bit integer part.
                let fraction = u32::from_be_bytes(bytes.get(0..4)?.try_into().ok()?);
                let integer = i16::from_be_bytes(bytes.get(4..6)?.try_into().ok()?);
                let raw = (i64::from(integer) << 32) | i64::from(fraction);
                raw as f64 / 4294967296.0
            }
        };
        value.is_finite().then_some(value)
    }

    fn write(self, value: f64, out: &mut Vec<u8>) {
        match self {
            Precision::Float32 => out.extend_from_slice(&(value as f32).to_be_bytes()),
            Precision::Float64 => out.extend_from_slice(&value.to_be_bytes()),
            Precision::Fixed1220 => {
                out.extend_from_slice(&((value * 1048576.0).round() as i32).to_be_bytes());
            }
            Precision::Fixed1632 => {
                let raw = (value * 4294967296.0).round() as i64;
                out.extend_from_slice(&(raw as u32).to_be_bytes());
                out.extend_from_slice(&((raw >> 32) as i16).to_be_bytes());
            }
        }
    }
}

/// Xbus message framing (the protocol has nothing to configure).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct XbusFormat;

/// Streaming decoder of Xbus messages; MTData2 messages become samples, other valid messages
/// count as frames without samples.
pub type XsensDecoder = FramedDecoder<XbusFormat>;

impl XsensDecoder {
    /// A decoder with empty buffer and counts.
    pub fn new() -> Self {
        FramedDecoder::with_format(XbusFormat)
    }
}

impl FrameFormat for XbusFormat {
    const PROTOCOL: Protocol = Protocol::Xsens;

    fn next_frame(&self, window: &[u8], samples: &mut Vec<Sample>) -> Step {
        xsens_step(window, samples)
    }
}

fn values(bytes: &[u8], precision: Precision, count: usize) -> Option<Vec<f64>> {
    if bytes.len() != precision.value_len() * count {
        return None;
    }
    bytes
        .chunks_exact(precision.value_len())
        .map(|chunk| precision.read(chunk))
        .collect()
}

fn vec3(v: &[f64]) -> Option<DVec3> {
    match v {
        [x, y, z] => Some(DVec3::new(*x, *y, *z)),
        _ => None,
    }
}

/// Decodes an MTData2 payload. `None` when a packet overruns the payload or a value is
/// malformed; `Some(None)` when the message is fine but carries nothing Stance uses.
fn parse_mtdata2(bus_id: u8, payload: &[u8]) -> Option<Option<Sample>> {
    let sensor = if bus_id == BUS_ID_MASTER {
        0
    } else {
        u16::from(bus_id)
    };
    let mut sample = Sample {
        sensor: SensorId(sensor),
        ..Sample::default()
    };
    let mut rest = payload;
    while !rest.is_empty() {
        let (&[id_hi, id_lo, size], tail) = rest.split_first_chunk::<3>()?;
        let (data, tail) = tail.split_at_checked(usize::from(size))?;
        rest = tail;
        let id = u16::from_be_bytes([id_hi, id_lo]);
        let precision = Precision::from_data_id(id);
        match id & 0xFFF0 {
            DATA_PACKET_COUNTER if id == DATA_PACKET_COUNTER => {
                sample.counter = Some(u32::from(u16::from_be_bytes(data.try_into().ok()?)));
            }
            DATA_SAMPLE_TIME_FINE if id == DATA_SAMPLE_TIME_FINE => {
                let ticks = u64::from(u32::from_be_bytes(data.try_into().ok()?));
                sample.device_time_us = Some(ticks * MICROSECONDS_PER_FINE_TICK);
            }
            DATA_QUATERNION => {
                let q = values(data, precision, 4)?;
                let &[w, x, y, z] = q.as_slice() else {
                    return None;
                };
                sample.orientation = Some(checked_unit_quat(x, y, z, w, UNIT_TOLERANCE)?);
            }
            DATA_ROTATION_MATRIX => {
                let m = values(data, precision, 9)?;
                let columns: [f64; 9] = m.try_into().ok()?;
                let matrix = DMat3::from_cols_array(&columns);
                sample.orientation = Some(checked_rotation_matrix(matrix, UNIT_TOLERANCE)?);
            }
            DATA_EULER_ANGLES => {
                let e = values(data, precision, 3)?;
                let &[roll, pitch, yaw] = e.as_slice() else {
                    return None;
                };
                sample.orientation = Some(DQuat::from_euler(
                    glam::EulerRot::ZYX,
                    yaw.to_radians(),
                    pitch.to_radians(),
                    roll.to_radians(),
                ));
            }
            DATA_ACCELERATION => {
                sample.acceleration_mps2 = Some(vec3(&values(data, precision, 3)?)?);
            }
            DATA_RATE_OF_TURN => {
                sample.angular_velocity_radps = Some(vec3(&values(data, precision, 3)?)?);
            }
            _ => {}
        }
    }
    let useful = sample.orientation.is_some()
        || sample.acceleration_mps2.is_some()
        || sample.angular_velocity_radps.is_some();
    Some(useful.then_some(sample))
}

fn xsens_step(window: &[u8], samples: &mut Vec<Sample>) -> Step {
    let Some(start) = window.iter().position(|&b| b == PREAMBLE) else {
        return Step::Skip(window.len());
    };
    if start > 0 {
        return Step::Skip(start);
    }
    let Some(&[_, bus_id, message_id, len]) = window.first_chunk::<4>() else {
        return Step::NeedMore;
    };
    let (header_len, payload_len) = if len == 0xFF {
        let Some(&[hi, lo]) = window.get(4..6).and_then(|b| b.first_chunk::<2>()) else {
            return Step::NeedMore;
        };
        (6, usize::from(u16::from_be_bytes([hi, lo])))
    } else {
        (4, usize::from(len))
    };
    if payload_len > MAX_PAYLOAD {
        return Step::Bad(1);
    }
    let frame_len = header_len + payload_len + 1;
    let Some(frame) = window.get(..frame_len) else {
        return Step::NeedMore;
    };
    let sum = frame
        .iter()
        .skip(1)
        .fold(0u8, |acc, &b| acc.wrapping_add(b));
    if sum != 0 {
        // Probably a stray 0xFA: look for the next preamble right after it.
        return Step::Bad(1);
    }
    if message_id != MID_MTDATA2 {
        return Step::Frame(frame_len);
    }
    let payload = frame
        .get(header_len..header_len + payload_len)
        .unwrap_or_default();
    match parse_mtdata2(bus_id, payload) {
        Some(Some(sample)) => {
            samples.push(sample);
            Step::Frame(frame_len)
        }
        Some(None) => Step::Frame(frame_len),
        None => Step::Bad(frame_len),
    }
}

/// Wraps a payload into a message with preamble, length and checksum.
pub fn encode_message(bus_id: u8, message_id: u8, payload: &[u8]) -> Option<Vec<u8>> {
    if payload.len() > MAX_PAYLOAD {
        return None;
    }
    let mut message = vec![PREAMBLE, bus_id, message_id];
    if payload.len() < 0xFF {
        message.push(payload.len() as u8);
    } else {
        message.push(0xFF);
        message.extend_from_slice(&(payload.len() as u16).to_be_bytes());
    }
    message.extend_from_slice(payload);
    let sum = message
        .iter()
        .skip(1)
        .fold(0u8, |acc, &b| acc.wrapping_add(b));
    message.push(sum.wrapping_neg());
    Some(message)
}

/// Encodes an MTData2 message with packet counter, SampleTimeFine and the quaternion in the
/// given precision (for the simulator and tests). The bus id is the sensor id, or `FF` for 0.
pub fn encode_mtdata2(sample: &Sample, precision: Precision) -> Option<Vec<u8>> {
    let bus_id = match sample.sensor.0 {
        0 => BUS_ID_MASTER,
        id => u8::try_from(id).ok().filter(|&b| b != BUS_ID_MASTER)?,
    };
    let mut payload = Vec::new();
    if let Some(counter) = sample.counter {
        payload.extend_from_slice(&DATA_PACKET_COUNTER.to_be_bytes());
        payload.push(2);
        payload.extend_from_slice(&(counter as u16).to_be_bytes());
    }
    if let Some(time_us) = sample.device_time_us {
        payload.extend_from_slice(&DATA_SAMPLE_TIME_FINE.to_be_bytes());
        payload.push(4);
        let ticks = (time_us / MICROSECONDS_PER_FINE_TICK) as u32;
        payload.extend_from_slice(&ticks.to_be_bytes());
    }
    if let Some(q) = sample.orientation {
        payload.extend_from_slice(&(DATA_QUATERNION | precision.bits()).to_be_bytes());
        payload.push((precision.value_len() * 4) as u8);
        for v in [q.w, q.x, q.y, q.z] {
            precision.write(v, &mut payload);
        }
    }
    for (id, vector) in [
        (DATA_ACCELERATION, sample.acceleration_mps2),
        (DATA_RATE_OF_TURN, sample.angular_velocity_radps),
    ] {
        if let Some(v) = vector {
            payload.extend_from_slice(&(id | precision.bits()).to_be_bytes());
            payload.push((precision.value_len() * 3) as u8);
            for c in v.to_array() {
                precision.write(c, &mut payload);
            }
        }
    }
    encode_message(bus_id, MID_MTDATA2, &payload)
}
