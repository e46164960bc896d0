//! Polhemus trackers: FASTRAK ASCII records and Liberty / Patriot binary frames.
//!
//! Both report the sensor's orientation relative to the source (sensor to source rotation,
//! Euler angles as `Rz(azimuth) * Ry(elevation) * Rx(roll)`, quaternions scalar first).

use glam::{DMat3, DQuat, DVec3};
use serde::{Deserialize, Serialize};

use crate::decoder::{
    METRES_PER_INCH, Protocol, Sample, SensorId, az_el_roll_deg_from_quat, checked_rotation_matrix,
    checked_unit_quat, quat_from_az_el_roll_deg,
};
use crate::framing::{FrameFormat, FramedDecoder, Step};

/// Position units configured on the tracker (`U` command).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum PolhemusUnits {
    /// Inches (the factory setting).
    #[default]
    Inches,
    /// Centimetres.
    Centimetres,
}

impl PolhemusUnits {
    /// Metres per reported position unit.
    pub fn metres_per_unit(self) -> f64 {
        match self {
            PolhemusUnits::Inches => METRES_PER_INCH,
            PolhemusUnits::Centimetres => 0.01,
        }
    }
}

const QUATERNION_TOLERANCE: f64 = 0.02;
const MATRIX_TOLERANCE: f64 = 0.02;

// ---------------------------------------------------------------------------------------------
// FASTRAK ASCII
// ---------------------------------------------------------------------------------------------

/// FASTRAK output-list items (`O` command) that the decoder understands.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum FastrakItem {
    /// Item 2: x, y, z as `Sxxx.xx`.
    Position,
    /// Item 4: azimuth, elevation, roll as `Sxxx.xx` degrees.
    Euler,
    /// Item 11: quaternion w, x, y, z as `Sx.xxxx`.
    Quaternion,
}

impl FastrakItem {
    fn value_count(self) -> usize {
        match self {
            FastrakItem::Position | FastrakItem::Euler => 3,
            FastrakItem::Quaternion => 4,
        }
    }
}

/// Width of every ASCII field of the supported items.
const FASTRAK_FIELD_WIDTH: usize = 7;
/// Header: record type '0', station '1'..'4', error/status character.
const FASTRAK_HEADER_LEN: usize = 3;
const FASTRAK_MAX_LINE: usize = 256;

/// How a FASTRAK is set up: its output list and position units.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FastrakConfig {
    /// The output list, in order (default: position, Euler angles: the factory setting).
    pub items: Vec<FastrakItem>,
    /// Units of the reported positions (`U` command).
    pub units: PolhemusUnits,
}

impl Default for FastrakConfig {
    fn default() -> Self {
        FastrakConfig {
            items: vec![FastrakItem::Position, FastrakItem::Euler],
            units: PolhemusUnits::Inches,
        }
    }
}

impl FastrakConfig {
    fn value_count(&self) -> usize {
        self.items.iter().map(|item| item.value_count()).sum()
    }

    /// Length of a record without its CR LF.
    pub fn record_len(&self) -> usize {
        FASTRAK_HEADER_LEN + self.value_count() * FASTRAK_FIELD_WIDTH
    }
}

/// Streaming decoder of FASTRAK ASCII records (one per CR LF terminated line).
pub type FastrakDecoder = FramedDecoder<FastrakConfig>;

impl FastrakDecoder {
    /// A decoder of records with `config`'s output list and units.
    pub fn new(config: FastrakConfig) -> Self {
        FramedDecoder::with_format(config)
    }
}

impl FrameFormat for FastrakConfig {
    const PROTOCOL: Protocol = Protocol::Fastrak;
    // An unterminated last record is still a record.
    const LINE_BASED: bool = true;

    fn next_frame(&self, window: &[u8], samples: &mut Vec<Sample>) -> Step {
        fastrak_step(self, window, samples)
    }

    fn parse_last_line(&self, line: &[u8]) -> Option<Sample> {
        parse_fastrak_record(self, line)
    }
}

fn is_fastrak_header(bytes: &[u8]) -> bool {
    matches!(bytes, [b'0', b'1'..=b'4', status, ..] if (0x20..0x7F).contains(status))
}

/// Parses one record (no line terminator). Fixed-width fields first, whitespace-separated
/// numbers as a fallback (some firmware trims the fields).
fn parse_fastrak_record(config: &FastrakConfig, record: &[u8]) -> Option<Sample> {
    if !is_fastrak_header(record) {
        return None;
    }
    let station = *record.get(1)? - b'0';
    let body = std::str::from_utf8(record.get(FASTRAK_HEADER_LEN..)?).ok()?;
    let count = config.value_count();
    let values: Vec<f64> = if body.len() == count * FASTRAK_FIELD_WIDTH && body.is_ascii() {
        (0..count)
            .map(|i| {
                body.get(i * FASTRAK_FIELD_WIDTH..(i + 1) * FASTRAK_FIELD_WIDTH)
                    .and_then(|field| field.trim().parse::<f64>().ok())
            })
            .collect::<Option<Vec<f64>>>()?
    } else {
        body.split_ascii_whitespace()
            .map(|t| t.parse::<f64>().ok())
            .collect::<Option<_>>()?
    };
    if values.len() != count || values.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let mut sample = Sample {
        sensor: SensorId(u16::from(station)),
        ..Sample::default()
    };
    let mut rest = values.as_slice();
    for item in &config.items {
        let (item_values, tail) = rest.split_at_checked(item.value_count())?;
        rest = tail;
        match (item, item_values) {
            (FastrakItem::Position, [x, y, z]) => {
                sample.position_m = Some(DVec3::new(*x, *y, *z) * config.units.metres_per_unit());
            }
            (FastrakItem::Euler, [az, el, roll]) => {
                sample.orientation = Some(quat_from_az_el_roll_deg(*az, *el, *roll));
            }
            (FastrakItem::Quaternion, [w, x, y, z]) => {
                sample.orientation = Some(checked_unit_quat(*x, *y, *z, *w, QUATERNION_TOLERANCE)?);
            }
            _ => return None,
        }
    }
    Some(sample)
}

fn fastrak_step(config: &FastrakConfig, window: &[u8], samples: &mut Vec<Sample>) -> Step {
    let Some(newline) = window.iter().position(|&b| b == b'\n') else {
        return if window.len() > FASTRAK_MAX_LINE {
            Step::Bad(window.len())
        } else {
            Step::NeedMore
        };
    };
    let line_len = newline + 1;
    let Some(line) = window.get(..newline) else {
        return Step::Bad(line_len);
    };
    let record = line.strip_suffix(b"\r").unwrap_or(line);
    if record.iter().all(u8::is_ascii_whitespace) {
        return Step::Skip(line_len);
    }
    // Garbage glued before a record: find the header where a record of the expected length
    // would start and skip what comes before it.
    let expected = config.record_len();
    if record.len() > expected {
        let start = record.len() - expected;
        if record.get(start..).is_some_and(is_fastrak_header) && !is_fastrak_header(record) {
            return Step::Skip(start);
        }
    }
    match parse_fastrak_record(config, record) {
        Some(sample) => {
            samples.push(sample);
            Step::Frame(line_len)
        }
        None => Step::Bad(line_len),
    }
}

fn push_fastrak_field(line: &mut String, value: f64, decimals: usize) {
    let text = format!("{value:>width$.decimals$}", width = FASTRAK_FIELD_WIDTH);
    // Values that do not fit are clamped to the widest printable number.
    if text.len() == FASTRAK_FIELD_WIDTH {
        line.push_str(&text);
    } else {
        let limit = if decimals == 2 { 999.99 } else { 9.9999 };
        let clamped = value.clamp(-limit, limit);
        line.push_str(&format!(
            "{clamped:>width$.decimals$}",
            width = FASTRAK_FIELD_WIDTH
        ));
    }
}

/// Encodes one FASTRAK record with its CR LF (for the simulator and tests). Returns `None`
/// when the sample lacks a field the output list needs or the station is not 1..=4.
pub fn encode_fastrak_record(config: &FastrakConfig, sample: &Sample) -> Option<Vec<u8>> {
    let station = u8::try_from(sample.sensor.0)
        .ok()
        .filter(|s| (1..=4).contains(s))?;
    let mut line = String::from("0");
    line.push(char::from(b'0' + station));
    line.push(' ');
    for item in &config.items {
        match item {
            FastrakItem::Position => {
                let p = sample.position_m? / config.units.metres_per_unit();
                for v in p.to_array() {
                    push_fastrak_field(&mut line, v, 2);
                }
            }
            FastrakItem::Euler => {
                let (az, el, roll) = az_el_roll_deg_from_quat(sample.orientation?);
                for v in [az, el, roll] {
                    push_fastrak_field(&mut line, v, 2);
                }
            }
            FastrakItem::Quaternion => {
                let q = sample.orientation?;
                for v in [q.w, q.x, q.y, q.z] {
                    push_fastrak_field(&mut line, v, 4);
                }
            }
        }
    }
    line.push_str("\r\n");
    Some(line.into_bytes())
}

// ---------------------------------------------------------------------------------------------
// Liberty / Patriot binary
// ---------------------------------------------------------------------------------------------

/// Liberty output-list items (`O` command) in binary format, each made of 4-byte values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum LibertyItem {
    /// Item 2: x, y, z (f32).
    Position,
    /// Item 4: azimuth, elevation, roll in degrees (f32).
    Euler,
    /// Item 6: direction cosine matrix, 9 f32, rows of the sensor-to-source rotation.
    DirectionCosines,
    /// Item 7: quaternion w, x, y, z (f32).
    Quaternion,
    /// Item 8: timestamp in milliseconds (u32).
    TimestampMs,
    /// Item 9: frame count (u32).
    FrameCount,
}

impl LibertyItem {
    fn byte_len(self) -> usize {
        match self {
            LibertyItem::Position | LibertyItem::Euler => 12,
            LibertyItem::DirectionCosines => 36,
            LibertyItem::Quaternion => 16,
            LibertyItem::TimestampMs | LibertyItem::FrameCount => 4,
        }
    }
}

/// How a Liberty or Patriot is set up: its output list and position units.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LibertyConfig {
    /// The output list, in order (default: position, quaternion).
    pub items: Vec<LibertyItem>,
    /// Units of the reported positions (`U` command).
    pub units: PolhemusUnits,
}

impl Default for LibertyConfig {
    fn default() -> Self {
        LibertyConfig {
            items: vec![LibertyItem::Position, LibertyItem::Quaternion],
            units: PolhemusUnits::Inches,
        }
    }
}

impl LibertyConfig {
    /// Payload bytes of one station's frame.
    pub fn payload_len(&self) -> usize {
        self.items.iter().map(|item| item.byte_len()).sum()
    }
}

const LIBERTY_HEADER_LEN: usize = 8;
/// Frames larger than this are not data frames of any output list.
const LIBERTY_MAX_PAYLOAD: usize = 1024;
/// Liberty supports up to 16 stations (Patriot 2, Liberty Latus more through hubs).
const LIBERTY_MAX_STATION: u8 = 16;

/// Streaming decoder of Liberty ("LY") and Patriot ("PA") binary frames.
pub type LibertyDecoder = FramedDecoder<LibertyConfig>;

impl LibertyDecoder {
    /// A decoder of frames with `config`'s output list and units.
    pub fn new(config: LibertyConfig) -> Self {
        FramedDecoder::with_format(config)
    }
}

impl FrameFormat for LibertyConfig {
    const PROTOCOL: Protocol = Protocol::Liberty;

    fn next_frame(&self, window: &[u8], samples: &mut Vec<Sample>) -> Step {
        liberty_step(self, window, samples)
    }
}

fn f32_le(bytes: &[u8], offset: usize) -> Option<f64> {
    let chunk: [u8; 4] = bytes.get(offset..offset + 4)?.try_into().ok()?;
    let value = f64::from(f32::from_le_bytes(chunk));
    value.is_finite().then_some(value)
}

fn u32_le(bytes: &[u8], offset: usize) -> Option<u32> {
    let chunk: [u8; 4] = bytes.get(offset..offset + 4)?.try_into().ok()?;
    Some(u32::from_le_bytes(chunk))
}

fn is_liberty_magic(pair: &[u8]) -> bool {
    matches!(pair, [b'L', b'Y', ..] | [b'P', b'A', ..])
}

fn parse_liberty_payload(config: &LibertyConfig, station: u8, payload: &[u8]) -> Option<Sample> {
    let mut sample = Sample {
        sensor: SensorId(u16::from(station)),
        ..Sample::default()
    };
    let mut offset = 0;
    for item in &config.items {
        let f = |i: usize| f32_le(payload, offset + 4 * i);
        match item {
            LibertyItem::Position => {
                let p = DVec3::new(f(0)?, f(1)?, f(2)?);
                sample.position_m = Some(p * config.units.metres_per_unit());
            }
            LibertyItem::Euler => {
                sample.orientation = Some(quat_from_az_el_roll_deg(f(0)?, f(1)?, f(2)?));
            }
            LibertyItem::DirectionCosines => {
                let mut rows = [0.0; 9];
                for (i, slot) in rows.iter_mut().enumerate() {
                    *slot = f(i)?;
                }
                let m = DMat3::from_cols_array(&rows).transpose();
                sample.orientation = Some(checked_rotation_matrix(m, MATRIX_TOLERANCE)?);
            }
            LibertyItem::Quaternion => {
                let (w, x, y, z) = (f(0)?, f(1)?, f(2)?, f(3)?);
                sample.orientation = Some(checked_unit_quat(x, y, z, w, QUATERNION_TOLERANCE)?);
            }
            LibertyItem::TimestampMs => {
                sample.device_time_us = Some(u64::from(u32_le(payload, offset)?) * 1000);
            }
            LibertyItem::FrameCount => {
                sample.counter = Some(u32_le(payload, offset)?);
            }
        }
        offset += item.byte_len();
    }
    Some(sample)
}

fn liberty_step(config: &LibertyConfig, window: &[u8], samples: &mut Vec<Sample>) -> Step {
    // Find the next magic ("LY" or "PA").
    let Some(start) = window.windows(2).position(is_liberty_magic) else {
        // Keep a possible first half of the magic.
        let keep = usize::from(matches!(window.last(), Some(b'L' | b'P')));
        return if window.len() > keep {
            Step::Skip(window.len() - keep)
        } else {
            Step::NeedMore
        };
    };
    if start > 0 {
        return Step::Skip(start);
    }
    let Some(header) = window.get(..LIBERTY_HEADER_LEN) else {
        return Step::NeedMore;
    };
    let station = header.get(2).copied().unwrap_or(0);
    let payload_len = usize::from(u16::from_le_bytes([
        header.get(6).copied().unwrap_or(0),
        header.get(7).copied().unwrap_or(0),
    ]));
    if !(1..=LIBERTY_MAX_STATION).contains(&station) || payload_len > LIBERTY_MAX_PAYLOAD {
        // Not a real header: drop the first magic byte and keep searching.
        return Step::Bad(1);
    }
    if payload_len != config.payload_len() {
        // A frame of another output list, a command reply or a corrupted size: trusting the
        // size could skip good frames, so look for the next magic instead.
        return Step::Bad(1);
    }
    let frame_len = LIBERTY_HEADER_LEN + payload_len;
    let Some(payload) = window.get(LIBERTY_HEADER_LEN..frame_len) else {
        return Step::NeedMore;
    };
    match parse_liberty_payload(config, station, payload) {
        Some(sample) => {
            samples.push(sample);
            Step::Frame(frame_len)
        }
        None => Step::Bad(1),
    }
}

/// Which tracker writes a Liberty-format frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum LibertyFamily {
    /// Polhemus Liberty: frames start with "LY".
    #[default]
    Liberty,
    /// Polhemus Patriot: frames start with "PA".
    Patriot,
}

/// Encodes one binary frame (for the simulator and tests). `None` when the sample lacks a
/// field of the output list or the station is outside 1..=16.
pub fn encode_liberty_frame(
    config: &LibertyConfig,
    family: LibertyFamily,
    sample: &Sample,
) -> Option<Vec<u8>> {
    let station = u8::try_from(sample.sensor.0)
        .ok()
        .filter(|s| (1..=LIBERTY_MAX_STATION).contains(s))?;
    let magic = match family {
        LibertyFamily::Liberty => *b"LY",
        LibertyFamily::Patriot => *b"PA",
    };
    let payload_len = u16::try_from(config.payload_len()).ok()?;
    let mut frame = Vec::with_capacity(LIBERTY_HEADER_LEN + usize::from(payload_len));
    frame.extend_from_slice(&magic);
    frame.extend_from_slice(&[station, b'C', 0, 0]);
    frame.extend_from_slice(&payload_len.to_le_bytes());
    for item in &config.items {
        match item {
            LibertyItem::Position => {
                let p = sample.position_m? / config.units.metres_per_unit();
                p.to_array()
                    .into_iter()
                    .for_each(|v| push_f32_le(&mut frame, v));
            }
            LibertyItem::Euler => {
                let (az, el, roll) = az_el_roll_deg_from_quat(sample.orientation?);
                [az, el, roll]
                    .into_iter()
                    .for_each(|v| push_f32_le(&mut frame, v));
            }
            LibertyItem::DirectionCosines => {
                let m = DMat3::from_quat(sample.orientation?).transpose();
                m.to_cols_array()
                    .into_iter()
                    .for_each(|v| push_f32_le(&mut frame, v));
            }
            LibertyItem::Quaternion => {
                let q: DQuat = sample.orientation?;
                [q.w, q.x, q.y, q.z]
                    .into_iter()
                    .for_each(|v| push_f32_le(&mut frame, v));
            }
            LibertyItem::TimestampMs => {
                let ms = (sample.device_time_us.unwrap_or(0) / 1000) as u32;
                frame.extend_from_slice(&ms.to_le_bytes());
            }
            LibertyItem::FrameCount => {
                frame.extend_from_slice(&sample.counter.unwrap_or(0).to_le_bytes());
            }
        }
    }
    Some(frame)
}

fn push_f32_le(frame: &mut Vec<u8>, value: f64) {
    frame.extend_from_slice(&(value as f32).to_le_bytes());
}
