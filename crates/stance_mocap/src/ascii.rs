//! Text lines with a quaternion, as printed by hobby IMU boards, for example
//! `Quaternion: 0.71, 0.00, 0.00, 0.71` (Adafruit BNO055, scalar first) or
//! `0.00,0.00,0.71,0.71,0.05,` (SparkFun BNO080: i, j, k, real, accuracy).
//!
//! A line is split at its last `:`; a label that is a number gives the sensor id
//! (`2: 1, 0, 0, 0`), any other label is ignored (sensor 0). The first four numbers after it
//! are the quaternion in the configured component order; further numbers are ignored.

use glam::DQuat;
use serde::{Deserialize, Serialize};

use crate::decoder::{Protocol, Sample, SensorId, checked_unit_quat};
use crate::framing::{FrameFormat, FramedDecoder, Step};

/// Order of the quaternion components on a line.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum ComponentOrder {
    /// Scalar first: w, x, y, z.
    #[default]
    Wxyz,
    /// Scalar last: x, y, z, w.
    Xyzw,
}

/// How a board prints its quaternion lines.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AsciiConfig {
    /// Order of the four quaternion components on a line.
    pub order: ComponentOrder,
    /// Printed quaternions are rounded; lines whose norm is farther from 1 are rejected.
    pub norm_tolerance: f64,
    /// Longer lines are garbage.
    pub max_line_len: usize,
}

impl Default for AsciiConfig {
    fn default() -> Self {
        AsciiConfig {
            order: ComponentOrder::Wxyz,
            norm_tolerance: 0.05,
            max_line_len: 256,
        }
    }
}

/// Streaming decoder of quaternion text lines (LF or CR LF terminated).
pub type AsciiQuaternionDecoder = FramedDecoder<AsciiConfig>;

impl AsciiQuaternionDecoder {
    /// A decoder of lines as `config` describes them.
    pub fn new(config: AsciiConfig) -> Self {
        FramedDecoder::with_format(config)
    }
}

impl FrameFormat for AsciiConfig {
    const PROTOCOL: Protocol = Protocol::AsciiQuaternion;
    const LINE_BASED: bool = true;

    fn next_frame(&self, window: &[u8], samples: &mut Vec<Sample>) -> Step {
        line_step(self, window, samples)
    }

    fn parse_last_line(&self, line: &[u8]) -> Option<Sample> {
        parse_line(self, line)
    }
}

fn parse_line(config: &AsciiConfig, line: &[u8]) -> Option<Sample> {
    let text = std::str::from_utf8(line).ok()?;
    let (label, numbers) = match text.rfind(':') {
        Some(colon) => (text.get(..colon)?, text.get(colon + 1..)?),
        None => ("", text),
    };
    let sensor = label.trim().parse::<u16>().unwrap_or(0);
    let mut components = [0.0f64; 4];
    let mut tokens = numbers
        .split(|c: char| c == ',' || c == ';' || c.is_ascii_whitespace())
        .filter(|t| !t.is_empty());
    for slot in &mut components {
        *slot = tokens.next()?.parse::<f64>().ok()?;
    }
    let [a, b, c, d] = components;
    let (x, y, z, w) = match config.order {
        ComponentOrder::Wxyz => (b, c, d, a),
        ComponentOrder::Xyzw => (a, b, c, d),
    };
    let orientation = checked_unit_quat(x, y, z, w, config.norm_tolerance)?;
    Some(Sample {
        sensor: SensorId(sensor),
        orientation: Some(orientation),
        ..Sample::default()
    })
}

fn line_step(config: &AsciiConfig, window: &[u8], samples: &mut Vec<Sample>) -> Step {
    let Some(newline) = window.iter().position(|&b| b == b'\n') else {
        return if window.len() > config.max_line_len {
            Step::Bad(window.len())
        } else {
            Step::NeedMore
        };
    };
    let line_len = newline + 1;
    let line = window.get(..newline).unwrap_or_default();
    let line = line.strip_suffix(b"\r").unwrap_or(line);
    if line.iter().all(u8::is_ascii_whitespace) {
        return Step::Skip(line_len);
    }
    if line.len() > config.max_line_len {
        return Step::Bad(line_len);
    }
    match parse_line(config, line) {
        Some(sample) => {
            samples.push(sample);
            Step::Frame(line_len)
        }
        None => Step::Bad(line_len),
    }
}

/// Writes one line `"<sensor>: a, b, c, d\r\n"` with four decimals (for the simulator and
/// tests).
pub fn encode_line(order: ComponentOrder, sensor: SensorId, orientation: DQuat) -> Vec<u8> {
    let q = orientation;
    let [a, b, c, d] = match order {
        ComponentOrder::Wxyz => [q.w, q.x, q.y, q.z],
        ComponentOrder::Xyzw => [q.x, q.y, q.z, q.w],
    };
    format!("{}: {a:.4}, {b:.4}, {c:.4}, {d:.4}\r\n", sensor.0).into_bytes()
}
