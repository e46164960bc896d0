//! `stance decode`: a recorded sensor byte stream in, one JSON line per sample out, then a
//! summary line with the decoder's counts.

use std::io::{BufWriter, Read, Write};
use std::path::PathBuf;

use anyhow::Context;
use clap::ValueEnum;
use serde_json::{Map, Value, json};
use stance_mocap::ascii::{AsciiConfig, ComponentOrder};
use stance_mocap::fob::{FobConfig, FobMode};
use stance_mocap::hid::{GamepadConfig, GamepadModel};
use stance_mocap::polhemus::{
    FastrakConfig, FastrakItem, LibertyConfig, LibertyFamily, LibertyItem, PolhemusUnits,
};
use stance_mocap::simulate::SimulatedDevice;
use stance_mocap::xsens::Precision;
use stance_mocap::{DecoderConfig, Sample, new_decoder};

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ProtocolArg {
    /// Ascension Flock of Birds binary records.
    Fob,
    /// Polhemus FASTRAK ASCII records.
    Fastrak,
    /// Polhemus Liberty / Patriot binary frames.
    Liberty,
    /// Xsens MTData2 messages.
    Xsens,
    /// Quaternion text lines of hobby IMU boards.
    Ascii,
    /// SlimeVR receiver HID reports (report log).
    SlimevrHid,
    /// DualSense HID reports (report log), fused with a Madgwick filter.
    Dualsense,
    /// DualShock 4 HID reports (report log), fused with a Madgwick filter.
    Ds4,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum FobModeArg {
    Position,
    Angles,
    Matrix,
    PosAngles,
    PosMatrix,
    Quat,
    PosQuat,
}

impl From<FobModeArg> for FobMode {
    fn from(mode: FobModeArg) -> Self {
        match mode {
            FobModeArg::Position => FobMode::Position,
            FobModeArg::Angles => FobMode::Angles,
            FobModeArg::Matrix => FobMode::Matrix,
            FobModeArg::PosAngles => FobMode::PositionAngles,
            FobModeArg::PosMatrix => FobMode::PositionMatrix,
            FobModeArg::Quat => FobMode::Quaternion,
            FobModeArg::PosQuat => FobMode::PositionQuaternion,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum OrderArg {
    Wxyz,
    Xyzw,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum UnitsArg {
    Inches,
    Cm,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum PolhemusItemArg {
    /// Position (FASTRAK item 2, Liberty item 2).
    Pos,
    /// Azimuth, elevation, roll (item 4).
    Euler,
    /// Quaternion (FASTRAK item 11, Liberty item 7).
    Quat,
    /// Direction cosines (Liberty item 6).
    Matrix,
    /// Timestamp in ms (Liberty item 8).
    Time,
    /// Frame count (Liberty item 9).
    Count,
}

/// Which device and how it is configured; shared by `decode` and `simulate-sensors`.
#[derive(clap::Args, Debug, Clone)]
pub struct ProtocolArgs {
    /// The device protocol.
    #[arg(long, value_enum)]
    pub protocol: ProtocolArg,
    /// Flock of Birds record layout.
    #[arg(long, value_enum, default_value = "pos-quat")]
    pub fob_mode: FobModeArg,
    /// Flock of Birds group mode (records end with the bird address).
    #[arg(long)]
    pub group: bool,
    /// Flock of Birds full-scale position range in inches (36, 72 or 144).
    #[arg(long, default_value_t = 36.0)]
    pub fob_range_inches: f64,
    /// Component order of ASCII quaternion lines.
    #[arg(long, value_enum, default_value = "wxyz")]
    pub order: OrderArg,
    /// Polhemus output list, comma separated (default: pos,euler for FASTRAK, pos,quat for
    /// Liberty).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub polhemus_items: Vec<PolhemusItemArg>,
    /// Polhemus position units.
    #[arg(long, value_enum, default_value = "inches")]
    pub units: UnitsArg,
}

impl ProtocolArgs {
    fn units(&self) -> PolhemusUnits {
        match self.units {
            UnitsArg::Inches => PolhemusUnits::Inches,
            UnitsArg::Cm => PolhemusUnits::Centimetres,
        }
    }

    fn fob(&self) -> FobConfig {
        FobConfig {
            mode: self.fob_mode.into(),
            group_mode: self.group,
            position_range_inches: self.fob_range_inches,
            ..FobConfig::default()
        }
    }

    fn fastrak(&self) -> anyhow::Result<FastrakConfig> {
        let mut config = FastrakConfig {
            units: self.units(),
            ..FastrakConfig::default()
        };
        if !self.polhemus_items.is_empty() {
            config.items = self
                .polhemus_items
                .iter()
                .map(|item| match item {
                    PolhemusItemArg::Pos => Ok(FastrakItem::Position),
                    PolhemusItemArg::Euler => Ok(FastrakItem::Euler),
                    PolhemusItemArg::Quat => Ok(FastrakItem::Quaternion),
                    other => anyhow::bail!("FASTRAK ASCII output has no {other:?} item here"),
                })
                .collect::<anyhow::Result<_>>()?;
        }
        Ok(config)
    }

    fn liberty(&self) -> LibertyConfig {
        let mut config = LibertyConfig {
            units: self.units(),
            ..LibertyConfig::default()
        };
        if !self.polhemus_items.is_empty() {
            config.items = self
                .polhemus_items
                .iter()
                .map(|item| match item {
                    PolhemusItemArg::Pos => LibertyItem::Position,
                    PolhemusItemArg::Euler => LibertyItem::Euler,
                    PolhemusItemArg::Quat => LibertyItem::Quaternion,
                    PolhemusItemArg::Matrix => LibertyItem::DirectionCosines,
                    PolhemusItemArg::Time => LibertyItem::TimestampMs,
                    PolhemusItemArg::Count => LibertyItem::FrameCount,
                })
                .collect();
        }
        config
    }

    fn order(&self) -> ComponentOrder {
        match self.order {
            OrderArg::Wxyz => ComponentOrder::Wxyz,
            OrderArg::Xyzw => ComponentOrder::Xyzw,
        }
    }

    fn gamepad(&self) -> GamepadConfig {
        let model = if self.protocol == ProtocolArg::Ds4 {
            GamepadModel::DualShock4
        } else {
            GamepadModel::DualSense
        };
        GamepadConfig {
            model,
            ..GamepadConfig::default()
        }
    }

    /// The decoder configuration these arguments describe.
    pub fn decoder_config(&self) -> anyhow::Result<DecoderConfig> {
        Ok(match self.protocol {
            ProtocolArg::Fob => DecoderConfig::FlockOfBirds(self.fob()),
            ProtocolArg::Fastrak => DecoderConfig::Fastrak(self.fastrak()?),
            ProtocolArg::Liberty => DecoderConfig::Liberty(self.liberty()),
            ProtocolArg::Xsens => DecoderConfig::Xsens,
            ProtocolArg::Ascii => DecoderConfig::AsciiQuaternion(AsciiConfig {
                order: self.order(),
                ..AsciiConfig::default()
            }),
            ProtocolArg::SlimevrHid => DecoderConfig::SlimeVrHid,
            ProtocolArg::Dualsense | ProtocolArg::Ds4 => DecoderConfig::Gamepad(self.gamepad()),
        })
    }

    /// The simulated device these arguments describe.
    pub fn simulated_device(
        &self,
        xsens_precision: Precision,
        patriot: bool,
        bluetooth: bool,
    ) -> anyhow::Result<SimulatedDevice> {
        Ok(match self.protocol {
            ProtocolArg::Fob => SimulatedDevice::FlockOfBirds(self.fob()),
            ProtocolArg::Fastrak => SimulatedDevice::Fastrak(self.fastrak()?),
            ProtocolArg::Liberty => {
                let family = if patriot {
                    LibertyFamily::Patriot
                } else {
                    LibertyFamily::Liberty
                };
                SimulatedDevice::Liberty(self.liberty(), family)
            }
            ProtocolArg::Xsens => SimulatedDevice::Xsens(xsens_precision),
            ProtocolArg::Ascii => SimulatedDevice::AsciiQuaternion(self.order()),
            ProtocolArg::SlimevrHid => SimulatedDevice::SlimeVr,
            ProtocolArg::Dualsense | ProtocolArg::Ds4 => SimulatedDevice::Gamepad {
                config: self.gamepad(),
                bluetooth,
            },
        })
    }
}

#[derive(clap::Args, Debug)]
pub struct DecodeArgs {
    #[command(flatten)]
    pub protocol: ProtocolArgs,
    /// Bytes fed to the decoder per push (as a serial port would deliver them).
    #[arg(long, default_value_t = 4096)]
    pub chunk_bytes: usize,
    /// The recorded stream; `-` reads standard input.
    pub file: PathBuf,
}

/// Rounds to a micro-unit so that the JSON stays readable.
fn rounded(value: f64) -> Value {
    // Adding 0.0 turns -0.0 into 0.0.
    json!((value * 1e6).round() / 1e6 + 0.0)
}

fn sample_json(index: usize, sample: &Sample) -> Value {
    let mut line = Map::new();
    line.insert("index".into(), json!(index));
    line.insert("sensor".into(), json!(sample.sensor.0));
    if let Some(counter) = sample.counter {
        line.insert("counter".into(), json!(counter));
    }
    if let Some(time_us) = sample.device_time_us {
        line.insert("time_us".into(), json!(time_us));
    }
    if let Some(p) = sample.position_m {
        line.insert(
            "position_m".into(),
            Value::Array(p.to_array().map(rounded).to_vec()),
        );
    }
    if let Some(q) = sample.orientation {
        line.insert(
            "quaternion".into(),
            Value::Array(q.to_array().map(rounded).to_vec()),
        );
    }
    if let Some(a) = sample.acceleration_mps2 {
        line.insert(
            "acceleration_mps2".into(),
            Value::Array(a.to_array().map(rounded).to_vec()),
        );
    }
    if let Some(w) = sample.angular_velocity_radps {
        let values = w.to_array().map(rounded).to_vec();
        line.insert("angular_velocity_radps".into(), Value::Array(values));
    }
    Value::Object(line)
}

pub fn run(args: DecodeArgs) -> anyhow::Result<()> {
    let bytes = if args.file.as_os_str() == "-" {
        let mut bytes = Vec::new();
        std::io::stdin()
            .read_to_end(&mut bytes)
            .context("reading standard input")?;
        bytes
    } else {
        std::fs::read(&args.file).with_context(|| format!("reading {}", args.file.display()))?
    };
    let config = args.protocol.decoder_config()?;
    let mut decoder = new_decoder(&config);
    let stdout = std::io::stdout();
    let mut out = BufWriter::new(stdout.lock());
    let mut samples = Vec::new();
    let mut index = 0usize;
    let mut write_samples = |samples: &mut Vec<Sample>, out: &mut BufWriter<_>| {
        for sample in samples.drain(..) {
            writeln!(out, "{}", sample_json(index, &sample))?;
            index += 1;
        }
        anyhow::Ok(())
    };
    for chunk in bytes.chunks(args.chunk_bytes.max(1)) {
        decoder.push(chunk, &mut samples);
        write_samples(&mut samples, &mut out)?;
    }
    decoder.finish(&mut samples);
    write_samples(&mut samples, &mut out)?;
    let stats = decoder.stats();
    let summary = json!({
        "summary": {
            "protocol": format!("{:?}", config.protocol()),
            "samples": stats.samples,
            "frames": stats.frames,
            "bad_frames": stats.bad_frames,
            "skipped_bytes": stats.skipped_bytes,
            "bytes": stats.bytes_received,
            "bytes_in_frames": stats.bytes_in_frames,
        }
    });
    writeln!(out, "{summary}")?;
    out.flush()?;
    Ok(())
}
