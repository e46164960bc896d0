//! Decoder throughput on simulated streams: `cargo run --release -p stance_mocap --example
//! decode_throughput`. Prints MB/s per protocol and the sample rate it sustains.

use std::time::Instant;

use stance_mocap::ascii::ComponentOrder;
use stance_mocap::fob::{FobConfig, FobMode};
use stance_mocap::hid::GamepadConfig;
use stance_mocap::polhemus::{FastrakConfig, LibertyConfig, LibertyFamily};
use stance_mocap::simulate::{SimulatedDevice, SimulationOptions, simulate};
use stance_mocap::xsens::Precision;
use stance_mocap::{DecoderConfig, new_decoder};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let fob = FobConfig {
        mode: FobMode::PositionQuaternion,
        group_mode: true,
        ..Default::default()
    };
    let cases = [
        (
            "fob",
            DecoderConfig::FlockOfBirds(fob.clone()),
            SimulatedDevice::FlockOfBirds(fob),
        ),
        (
            "fastrak",
            DecoderConfig::Fastrak(FastrakConfig::default()),
            SimulatedDevice::Fastrak(FastrakConfig::default()),
        ),
        (
            "liberty",
            DecoderConfig::Liberty(LibertyConfig::default()),
            SimulatedDevice::Liberty(LibertyConfig::default(), LibertyFamily::Liberty),
        ),
        (
            "xsens",
            DecoderConfig::Xsens,
            SimulatedDevice::Xsens(Precision::Float32),
        ),
        (
            "ascii",
            DecoderConfig::AsciiQuaternion(Default::default()),
            SimulatedDevice::AsciiQuaternion(ComponentOrder::Wxyz),
        ),
        (
            "slimevr-hid",
            DecoderConfig::SlimeVrHid,
            SimulatedDevice::SlimeVr,
        ),
        (
            "dualsense",
            DecoderConfig::Gamepad(GamepadConfig::default()),
            SimulatedDevice::Gamepad {
                config: GamepadConfig::default(),
                bluetooth: false,
            },
        ),
    ];
    let options = SimulationOptions {
        rate_hz: 120.0,
        duration_secs: 600.0,
        ..Default::default()
    };
    for (name, decoder_config, device) in cases {
        let stream = simulate(&device, &options)?;
        let mut best_secs = f64::INFINITY;
        let mut count = 0;
        for _ in 0..3 {
            let mut decoder = new_decoder(&decoder_config);
            let mut samples = Vec::with_capacity(stream.truth.len());
            let start = Instant::now();
            // 64-byte chunks, like a serial port or a HID report log would deliver them.
            for chunk in stream.bytes.chunks(64) {
                decoder.push(chunk, &mut samples);
            }
            best_secs = best_secs.min(start.elapsed().as_secs_f64());
            count = samples.len();
        }
        let megabytes = stream.bytes.len() as f64 / 1e6;
        println!(
            "{name:12} {:7.1} MB/s  {:6.2} M samples/s  ({count} samples, {:.1} MB)",
            megabytes / best_secs,
            count as f64 / best_secs / 1e6,
            megabytes
        );
    }
    Ok(())
}
