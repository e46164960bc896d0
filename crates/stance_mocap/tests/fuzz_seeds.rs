//! The seed corpus of the `decoders` fuzz target (`fuzz/seeds/decoders/`): a short simulated
//! stream of every protocol, prefixed with a selector byte that picks its decoder in the
//! target. `the_fuzz_seeds_decode` checks the committed seeds; `write_fuzz_seeds` (ignored)
//! writes them again: `cargo test -p stance_mocap --test all fuzz_seeds:: -- --ignored`.

#![cfg(not(target_arch = "wasm32"))]
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::{Path, PathBuf};

use stance_mocap::ascii::{AsciiConfig, ComponentOrder};
use stance_mocap::fob::{FobConfig, FobMode};
use stance_mocap::hid::{GamepadConfig, GamepadModel};
use stance_mocap::polhemus::{
    FastrakConfig, FastrakItem, LibertyConfig, LibertyFamily, LibertyItem,
};
use stance_mocap::simulate::{SimulatedDevice, SimulationOptions, simulate};
use stance_mocap::xsens::Precision;
use stance_mocap::{DecoderConfig, new_decoder};

fn seed_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds/decoders")
}

/// The decoder the fuzz target picks for `selector` (keep in step with
/// `fuzz/fuzz_targets/decoders.rs`).
fn config(selector: u8) -> DecoderConfig {
    let fob_mode = FobMode::ALL[usize::from(selector >> 4) % FobMode::ALL.len()];
    match selector % 9 {
        0 => DecoderConfig::FlockOfBirds(FobConfig {
            mode: fob_mode,
            ..Default::default()
        }),
        1 => DecoderConfig::FlockOfBirds(FobConfig {
            mode: fob_mode,
            group_mode: true,
            ..Default::default()
        }),
        2 => DecoderConfig::Fastrak(FastrakConfig {
            items: vec![FastrakItem::Position, FastrakItem::Quaternion],
            ..Default::default()
        }),
        3 => DecoderConfig::Liberty(LibertyConfig {
            items: vec![
                LibertyItem::FrameCount,
                LibertyItem::Position,
                LibertyItem::Quaternion,
            ],
            ..Default::default()
        }),
        4 => DecoderConfig::Xsens,
        5 => DecoderConfig::AsciiQuaternion(AsciiConfig {
            order: ComponentOrder::Xyzw,
            ..Default::default()
        }),
        6 => DecoderConfig::SlimeVrHid,
        7 => DecoderConfig::Gamepad(GamepadConfig::default()),
        _ => DecoderConfig::Gamepad(GamepadConfig {
            model: GamepadModel::DualShock4,
            ..Default::default()
        }),
    }
}

/// The first selector that picks decoder `decoder` (and Flock of Birds mode `mode`).
fn selector(decoder: u8, mode: usize) -> u8 {
    (0..=255u8)
        .find(|s| s % 9 == decoder && usize::from(s >> 4) % FobMode::ALL.len() == mode)
        .unwrap()
}

/// Every seed: (file name, selector, the device that writes its stream).
fn devices() -> Vec<(String, u8, SimulatedDevice)> {
    let mut out = Vec::new();
    for (m, mode) in FobMode::ALL.into_iter().enumerate() {
        for group_mode in [false, true] {
            out.push((
                format!("fob-{mode:?}{}", if group_mode { "-group" } else { "" }),
                selector(u8::from(group_mode), m),
                SimulatedDevice::FlockOfBirds(FobConfig {
                    mode,
                    group_mode,
                    ..FobConfig::default()
                }),
            ));
        }
    }
    out.push((
        "fastrak".into(),
        selector(2, 0),
        SimulatedDevice::Fastrak(FastrakConfig {
            items: vec![FastrakItem::Position, FastrakItem::Quaternion],
            ..FastrakConfig::default()
        }),
    ));
    out.push((
        "liberty".into(),
        selector(3, 0),
        SimulatedDevice::Liberty(
            LibertyConfig {
                items: vec![
                    LibertyItem::FrameCount,
                    LibertyItem::Position,
                    LibertyItem::Quaternion,
                ],
                ..LibertyConfig::default()
            },
            LibertyFamily::Liberty,
        ),
    ));
    for precision in [Precision::Float32, Precision::Fixed1632] {
        out.push((
            format!("xsens-{precision:?}"),
            selector(4, 0),
            SimulatedDevice::Xsens(precision),
        ));
    }
    out.push((
        "ascii".into(),
        selector(5, 0),
        SimulatedDevice::AsciiQuaternion(ComponentOrder::Xyzw),
    ));
    out.push(("slimevr".into(), selector(6, 0), SimulatedDevice::SlimeVr));
    for (d, model) in [(7, GamepadModel::DualSense), (8, GamepadModel::DualShock4)] {
        for bluetooth in [false, true] {
            out.push((
                format!("{model:?}{}", if bluetooth { "-bluetooth" } else { "" }),
                selector(d, 0),
                SimulatedDevice::Gamepad {
                    config: GamepadConfig {
                        model,
                        ..GamepadConfig::default()
                    },
                    bluetooth,
                },
            ));
        }
    }
    out
}

#[test]
#[ignore = "writes the seed corpus: run with --ignored after changing the generators"]
fn write_fuzz_seeds() {
    let dir = seed_dir();
    std::fs::create_dir_all(&dir).unwrap();
    let options = SimulationOptions {
        rate_hz: 50.0,
        duration_secs: 0.06,
        ..SimulationOptions::default()
    };
    for (name, selector, device) in devices() {
        let mut data = vec![selector];
        data.extend_from_slice(&simulate(&device, &options).unwrap().bytes);
        std::fs::write(dir.join(name), data).unwrap();
    }
}

#[test]
fn the_fuzz_seeds_decode() {
    let mut expected: Vec<String> = devices().into_iter().map(|(n, _, _)| n).collect();
    expected.sort();
    let mut found = Vec::new();
    for entry in std::fs::read_dir(seed_dir()).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let data = std::fs::read(&path).unwrap();
        assert!(data.len() < 4096, "{name}: {} bytes", data.len());
        let mut decoder = new_decoder(&config(data[0]));
        let mut samples = Vec::new();
        decoder.push(&data[1..], &mut samples);
        decoder.finish(&mut samples);
        assert!(!samples.is_empty(), "{name}: no sample");
        assert_eq!(decoder.stats().skipped_bytes, 0, "{name}");
        found.push(name);
    }
    found.sort();
    assert_eq!(found, expected);
}
