//! The Madgwick filter and the gamepad decoder on simulated motion.

// Test helpers outside #[test] functions may unwrap too (clippy.toml only covers the tests).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use glam::{DQuat, DVec3};
use stance_mocap::fusion::{Madgwick, MadgwickSettings, STANDARD_GRAVITY};
use stance_mocap::hid::{
    GamepadConfig, GamepadDecoder, GamepadModel, GamepadMotionReport, crc32, encode_gamepad_report,
};
use stance_mocap::simulate::{SimulatedDevice, SimulationOptions, simulate};
use stance_mocap::{Decoder, new_decoder};

/// Angle between the up directions two orientations see (tilt error, heading ignored).
fn tilt_error(a: DQuat, b: DQuat) -> f64 {
    (a.inverse() * DVec3::Z).angle_between(b.inverse() * DVec3::Z)
}

#[test]
fn crc32_matches_the_standard_check_value() {
    assert_eq!(crc32(*b"123456789"), 0xCBF4_3926);
}

#[test]
fn madgwick_starts_level_with_gravity() {
    let mut filter = Madgwick::new(MadgwickSettings::default());
    let tilted = DQuat::from_rotation_x(0.6) * DQuat::from_rotation_y(-0.3);
    let accel = tilted.inverse() * DVec3::new(0.0, 0.0, STANDARD_GRAVITY);
    let q = filter.update(DVec3::ZERO, accel, 0.01);
    assert!(tilt_error(q, tilted) < 1e-9);
}

#[test]
fn madgwick_corrects_a_wrong_tilt_and_follows_rotation() {
    let mut filter = Madgwick::new(MadgwickSettings {
        beta: 0.2,
        ..Default::default()
    });
    // Start believing the sensor is level while it is tilted by 30 degrees.
    filter.update(DVec3::ZERO, DVec3::new(0.0, 0.0, STANDARD_GRAVITY), 0.01);
    let truth = DQuat::from_rotation_x(30f64.to_radians());
    let accel = truth.inverse() * DVec3::new(0.0, 0.0, STANDARD_GRAVITY);
    let mut q = DQuat::IDENTITY;
    for _ in 0..2000 {
        q = filter.update(DVec3::ZERO, accel, 0.005);
    }
    assert!(
        tilt_error(q, truth) < 0.5f64.to_radians(),
        "{}",
        tilt_error(q, truth)
    );
    // Pure yaw rotation for one second at 90 deg/s: gyro integration alone.
    let yaw_rate = DVec3::new(0.0, 0.0, 90f64.to_radians());
    let start = q;
    for _ in 0..200 {
        q = filter.update(q.inverse() * yaw_rate, accel, 0.005);
    }
    let turned = q * start.inverse();
    let (axis, angle) = turned.to_axis_angle();
    assert!(
        (angle - 90f64.to_radians()).abs() < 1f64.to_radians(),
        "{angle}"
    );
    assert!(axis.z > 0.99);
}

#[test]
fn gamepad_stream_follows_the_simulated_hand() {
    for model in [GamepadModel::DualSense, GamepadModel::DualShock4] {
        for bluetooth in [false, true] {
            let config = GamepadConfig {
                model,
                ..GamepadConfig::default()
            };
            let device = SimulatedDevice::Gamepad {
                config: config.clone(),
                bluetooth,
            };
            let options = SimulationOptions {
                rate_hz: 250.0,
                duration_secs: 4.0,
                ..Default::default()
            };
            let simulated = simulate(&device, &options).unwrap();
            let mut decoder = new_decoder(&stance_mocap::DecoderConfig::Gamepad(config));
            let samples = decoder.decode(&simulated.bytes);
            assert_eq!(samples.len(), simulated.truth.len());
            let worst = samples
                .iter()
                .zip(&simulated.truth)
                .map(|(s, t)| tilt_error(s.orientation.unwrap(), t.orientation.unwrap()))
                .fold(0.0, f64::max);
            assert!(
                worst < 3f64.to_radians(),
                "{model:?} bt={bluetooth}: worst tilt {worst}"
            );
            // Device time is recovered from the controller's timestamps.
            let last = samples.last().unwrap();
            let want = simulated.truth.last().unwrap().device_time_us.unwrap();
            assert!(last.device_time_us.unwrap().abs_diff(want) < 10);
        }
    }
}

#[test]
fn gamepad_bluetooth_crc_rejects_corruption() {
    let config = GamepadConfig::default();
    let report = GamepadMotionReport {
        gyro_radps: DVec3::new(0.1, 0.2, 0.3),
        accel_mps2: DVec3::new(0.0, STANDARD_GRAVITY, 0.0),
        time_us: 1000,
        sequence: 3,
    };
    let (report_id, mut data) = encode_gamepad_report(&config, &report, true);
    let mut decoder = GamepadDecoder::new(config);
    let mut samples = Vec::new();
    decoder.push_report(report_id, &data, &mut samples);
    assert_eq!(samples.len(), 1);
    let gyro = samples[0].angular_velocity_radps.unwrap();
    assert!(gyro.distance(report.gyro_radps) < 0.01);
    data[20] ^= 0x10;
    decoder.push_report(report_id, &data, &mut samples);
    assert_eq!(samples.len(), 1);
    assert_eq!(decoder.stats().bad_frames, 1);
}
