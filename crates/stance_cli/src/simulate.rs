//! `stance simulate-sensors`: writes the byte stream of a simulated device (a right arm
//! reaching and bending) that `stance decode` and the page's replay read back.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use clap::ValueEnum;
use stance_mocap::simulate::{SimulationOptions, simulate};
use stance_mocap::xsens::Precision;

use crate::decode::ProtocolArgs;

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum PrecisionArg {
    Float32,
    Fixed1220,
    Fixed1632,
    Float64,
}

impl From<PrecisionArg> for Precision {
    fn from(precision: PrecisionArg) -> Self {
        match precision {
            PrecisionArg::Float32 => Precision::Float32,
            PrecisionArg::Fixed1220 => Precision::Fixed1220,
            PrecisionArg::Fixed1632 => Precision::Fixed1632,
            PrecisionArg::Float64 => Precision::Float64,
        }
    }
}

#[derive(clap::Args, Debug)]
pub struct SimulateArgs {
    #[command(flatten)]
    pub protocol: ProtocolArgs,
    /// Frames per second (one record per sensor per frame).
    #[arg(long, default_value_t = 100.0)]
    pub rate_hz: f64,
    /// Length of the recording in seconds.
    #[arg(long, default_value_t = 4.0)]
    pub duration_secs: f64,
    /// Xsens value precision.
    #[arg(long, value_enum, default_value = "float32")]
    pub xsens_precision: PrecisionArg,
    /// Write Patriot ("PA") instead of Liberty ("LY") frames.
    #[arg(long)]
    pub patriot: bool,
    /// Gamepads: Bluetooth reports (with CRC) instead of USB reports.
    #[arg(long)]
    pub bluetooth: bool,
    /// Output file (standard output when absent).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Also write the simulated samples (what a perfect decoder gives back, in stream order)
    /// as a JSON array to this file: ground truth for replay tests.
    #[arg(long)]
    pub truth: Option<PathBuf>,
}

pub fn run(args: SimulateArgs) -> anyhow::Result<()> {
    let device = args.protocol.simulated_device(
        args.xsens_precision.into(),
        args.patriot,
        args.bluetooth,
    )?;
    let options = SimulationOptions {
        rate_hz: args.rate_hz,
        duration_secs: args.duration_secs,
        ..SimulationOptions::default()
    };
    let stream = simulate(&device, &options)?;
    if let Some(path) = &args.truth {
        let text = serde_json::to_string(&stream.truth).context("serialising the truth")?;
        std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))?;
    }
    match &args.out {
        Some(path) => std::fs::write(path, &stream.bytes)
            .with_context(|| format!("writing {}", path.display()))?,
        None => {
            let mut stdout = std::io::stdout().lock();
            stdout.write_all(&stream.bytes)?;
            stdout.flush()?;
        }
    }
    eprintln!(
        "simulated {} samples, {} bytes{}",
        stream.truth.len(),
        stream.bytes.len(),
        args.out
            .as_ref()
            .map(|p| format!(" -> {}", p.display()))
            .unwrap_or_default()
    );
    Ok(())
}
