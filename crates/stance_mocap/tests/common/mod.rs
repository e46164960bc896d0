//! Helpers shared by the test files: the decoder/simulator pairs and sample comparison.
#![allow(dead_code, clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use stance_mocap::ascii::{AsciiConfig, ComponentOrder};
use stance_mocap::fob::{FobConfig, FobMode};
use stance_mocap::hid::{GamepadConfig, GamepadModel};
use stance_mocap::polhemus::{
    FastrakConfig, FastrakItem, LibertyConfig, LibertyFamily, LibertyItem, PolhemusUnits,
};
use stance_mocap::simulate::{SimulatedDevice, SimulationOptions, simulate};
use stance_mocap::xsens::Precision;
use stance_mocap::{Decoder, DecoderConfig, Sample, new_decoder};

/// One protocol set-up to exercise: how to decode it and how to simulate it.
pub struct Case {
    pub name: String,
    pub decoder: DecoderConfig,
    pub device: SimulatedDevice,
    /// Orientation tolerance in radians (None: orientation is fused, not compared).
    pub angle_tolerance: Option<f64>,
    pub position_tolerance_m: f64,
    /// Frames carry a checksum: corrupted frames never produce a sample.
    pub checksummed: bool,
    /// Samples in one frame of the stream (SlimeVR reports carry four).
    pub samples_per_frame: usize,
}

pub fn cases() -> Vec<Case> {
    let mut cases = Vec::new();
    for mode in FobMode::ALL {
        for group_mode in [false, true] {
            let config = FobConfig {
                mode,
                group_mode,
                ..FobConfig::default()
            };
            cases.push(Case {
                name: format!("fob {mode:?} group={group_mode}"),
                decoder: DecoderConfig::FlockOfBirds(config.clone()),
                device: SimulatedDevice::FlockOfBirds(config),
                angle_tolerance: Some(0.3f64.to_radians()),
                position_tolerance_m: 0.0005,
                checksummed: false,
                samples_per_frame: 1,
            });
        }
    }
    let fob72 = FobConfig {
        mode: FobMode::PositionQuaternion,
        group_mode: true,
        position_range_inches: 72.0,
        ..FobConfig::default()
    };
    cases.push(Case {
        name: "fob 72 inch range".into(),
        decoder: DecoderConfig::FlockOfBirds(fob72.clone()),
        device: SimulatedDevice::FlockOfBirds(fob72),
        angle_tolerance: Some(0.3f64.to_radians()),
        position_tolerance_m: 0.001,
        checksummed: false,
        samples_per_frame: 1,
    });
    for (items, units) in [
        (
            vec![FastrakItem::Position, FastrakItem::Euler],
            PolhemusUnits::Inches,
        ),
        (
            vec![FastrakItem::Position, FastrakItem::Quaternion],
            PolhemusUnits::Centimetres,
        ),
        (vec![FastrakItem::Quaternion], PolhemusUnits::Inches),
    ] {
        let config = FastrakConfig {
            items: items.clone(),
            units,
        };
        cases.push(Case {
            name: format!("fastrak {items:?} {units:?}"),
            decoder: DecoderConfig::Fastrak(config.clone()),
            device: SimulatedDevice::Fastrak(config),
            angle_tolerance: Some(0.3f64.to_radians()),
            position_tolerance_m: 0.0005,
            checksummed: false,
            samples_per_frame: 1,
        });
    }
    for (items, family) in [
        (
            vec![LibertyItem::Position, LibertyItem::Quaternion],
            LibertyFamily::Liberty,
        ),
        (
            vec![
                LibertyItem::FrameCount,
                LibertyItem::TimestampMs,
                LibertyItem::Position,
                LibertyItem::Euler,
            ],
            LibertyFamily::Patriot,
        ),
        (
            vec![LibertyItem::Position, LibertyItem::DirectionCosines],
            LibertyFamily::Liberty,
        ),
    ] {
        let config = LibertyConfig {
            items: items.clone(),
            units: PolhemusUnits::Inches,
        };
        cases.push(Case {
            name: format!("liberty {items:?} {family:?}"),
            decoder: DecoderConfig::Liberty(config.clone()),
            device: SimulatedDevice::Liberty(config, family),
            angle_tolerance: Some(0.01f64.to_radians()),
            position_tolerance_m: 1e-5,
            checksummed: false,
            samples_per_frame: 1,
        });
    }
    for precision in [
        Precision::Float32,
        Precision::Fixed1220,
        Precision::Fixed1632,
        Precision::Float64,
    ] {
        cases.push(Case {
            name: format!("xsens {precision:?}"),
            decoder: DecoderConfig::Xsens,
            device: SimulatedDevice::Xsens(precision),
            angle_tolerance: Some(0.01f64.to_radians()),
            position_tolerance_m: 1e-5,
            checksummed: true,
            samples_per_frame: 1,
        });
    }
    for order in [ComponentOrder::Wxyz, ComponentOrder::Xyzw] {
        cases.push(Case {
            name: format!("ascii {order:?}"),
            decoder: DecoderConfig::AsciiQuaternion(AsciiConfig {
                order,
                ..AsciiConfig::default()
            }),
            device: SimulatedDevice::AsciiQuaternion(order),
            angle_tolerance: Some(0.1f64.to_radians()),
            position_tolerance_m: 1e-5,
            checksummed: false,
            samples_per_frame: 1,
        });
    }
    cases.push(Case {
        name: "slimevr".into(),
        decoder: DecoderConfig::SlimeVrHid,
        device: SimulatedDevice::SlimeVr,
        angle_tolerance: Some(0.1f64.to_radians()),
        position_tolerance_m: 1e-5,
        checksummed: true,
        samples_per_frame: 4,
    });
    for model in [GamepadModel::DualSense, GamepadModel::DualShock4] {
        for bluetooth in [false, true] {
            let config = GamepadConfig {
                model,
                ..GamepadConfig::default()
            };
            cases.push(Case {
                name: format!("gamepad {model:?} bluetooth={bluetooth}"),
                decoder: DecoderConfig::Gamepad(config.clone()),
                device: SimulatedDevice::Gamepad { config, bluetooth },
                angle_tolerance: None,
                position_tolerance_m: 1e-5,
                checksummed: true,
                samples_per_frame: 1,
            });
        }
    }
    cases
}

pub fn stream(case: &Case, duration_secs: f64) -> (Vec<u8>, Vec<Sample>) {
    let options = SimulationOptions {
        duration_secs,
        rate_hz: 50.0,
        ..SimulationOptions::default()
    };
    let simulated = simulate(&case.device, &options).expect("simulation");
    (simulated.bytes, simulated.truth)
}

pub fn decoder(case: &Case) -> Box<dyn Decoder + Send> {
    new_decoder(&case.decoder)
}

/// Pushes the chunks, checking the byte accounting after every push, then finishes.
pub fn decode_chunks<'a>(
    decoder: &mut dyn Decoder,
    chunks: impl IntoIterator<Item = &'a [u8]>,
    finish: bool,
) -> Vec<Sample> {
    let mut samples = Vec::new();
    for chunk in chunks {
        decoder.push(chunk, &mut samples);
        assert_accounting(decoder);
    }
    if finish {
        decoder.finish(&mut samples);
        assert_accounting(decoder);
        assert_eq!(decoder.pending_bytes(), 0);
    }
    assert_eq!(decoder.stats().samples, samples.len() as u64);
    samples
}

pub fn assert_accounting(decoder: &dyn Decoder) {
    let stats = decoder.stats();
    assert_eq!(
        stats.bytes_received,
        stats.bytes_in_frames + stats.skipped_bytes + decoder.pending_bytes() as u64,
        "byte accounting broken: {stats:?}, pending {}",
        decoder.pending_bytes()
    );
}

pub fn samples_close(case: &Case, got: &Sample, want: &Sample) -> bool {
    if got.sensor != want.sensor {
        return false;
    }
    match (got.position_m, want.position_m) {
        (Some(a), Some(b)) if a.distance(b) > case.position_tolerance_m => return false,
        (None, Some(_)) | (Some(_), None) => return false,
        _ => {}
    }
    if let Some(tolerance) = case.angle_tolerance {
        match (got.orientation, want.orientation) {
            (Some(a), Some(b)) if a.angle_between(b) > tolerance => return false,
            (None, Some(_)) | (Some(_), None) => return false,
            _ => {}
        }
    }
    for (a, b) in [(got.counter, want.counter)] {
        if a.is_some() && b.is_some() && a != b {
            return false;
        }
    }
    true
}

pub fn assert_samples_close(case: &Case, got: &[Sample], want: &[Sample]) {
    assert_eq!(got.len(), want.len(), "{}: sample count", case.name);
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        assert!(
            samples_close(case, g, w),
            "{}: sample {i} differs:\n got {g:?}\nwant {w:?}",
            case.name
        );
    }
}

/// How many of `got` match `want` in order (greedy alignment), and how many did not.
pub fn aligned_matches(case: &Case, got: &[Sample], want: &[Sample]) -> (usize, usize) {
    let mut next = 0;
    let mut matched = 0;
    let mut unmatched = 0;
    for sample in got {
        match want
            .get(next..)
            .and_then(|rest| rest.iter().position(|w| samples_close(case, sample, w)))
        {
            Some(offset) => {
                matched += 1;
                next += offset + 1;
            }
            None => unmatched += 1,
        }
    }
    (matched, unmatched)
}

/// Sample stream properties every decoder must keep, whatever it was given.
pub fn assert_sane(samples: &[Sample]) {
    for sample in samples {
        if let Some(q) = sample.orientation {
            assert!(
                q.is_finite() && (q.length() - 1.0).abs() < 1e-6,
                "bad quaternion {q:?}"
            );
        }
        for v in [
            sample.position_m,
            sample.acceleration_mps2,
            sample.angular_velocity_radps,
        ]
        .into_iter()
        .flatten()
        {
            assert!(v.is_finite(), "non-finite vector {v:?}");
        }
    }
}
