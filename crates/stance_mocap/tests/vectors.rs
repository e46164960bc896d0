//! Byte-level test vectors of every protocol, decoded whole, split at every point and byte by
//! byte.

// Test helpers outside #[test] functions may unwrap too (clippy.toml only covers the tests).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use glam::{DQuat, DVec3};
use stance_mocap::ascii::{AsciiConfig, AsciiQuaternionDecoder, ComponentOrder};
use stance_mocap::fob::{FobConfig, FobDecoder, FobMode, command, encode_record};
use stance_mocap::hid::SlimeVrDecoder;
use stance_mocap::polhemus::{FastrakConfig, FastrakDecoder, LibertyConfig, LibertyDecoder};
use stance_mocap::xsens::XsensDecoder;
use stance_mocap::{Decoder, Sample, SensorId};

const INCH: f64 = 0.0254;

fn hex(text: &str) -> Vec<u8> {
    text.split_whitespace()
        .map(|b| u8::from_str_radix(b, 16).unwrap())
        .collect()
}

/// Decodes `bytes` whole, split at every point and one byte at a time; all must agree.
fn decode_every_way(make: impl Fn() -> Box<dyn Decoder>, bytes: &[u8]) -> Vec<Sample> {
    let mut whole = Vec::new();
    let mut decoder = make();
    decoder.push(bytes, &mut whole);
    decoder.finish(&mut whole);
    for split in 0..=bytes.len() {
        let mut decoder = make();
        let mut samples = Vec::new();
        decoder.push(&bytes[..split], &mut samples);
        decoder.push(&bytes[split..], &mut samples);
        decoder.finish(&mut samples);
        assert_eq!(samples, whole, "split at {split}");
    }
    let mut decoder = make();
    let mut samples = Vec::new();
    for byte in bytes {
        decoder.push(std::slice::from_ref(byte), &mut samples);
    }
    decoder.finish(&mut samples);
    assert_eq!(samples, whole, "one byte at a time");
    whole
}

fn assert_vec(got: Option<DVec3>, want: DVec3, tolerance: f64) {
    let got = got.expect("position");
    assert!(got.distance(want) < tolerance, "got {got:?}, want {want:?}");
}

fn assert_quat(got: Option<DQuat>, want: DQuat, tolerance: f64) {
    let got = got.expect("orientation");
    assert!(
        got.angle_between(want) < tolerance,
        "got {got:?}, want {want:?}"
    );
}

fn az_el_roll(az: f64, el: f64, roll: f64) -> DQuat {
    DQuat::from_euler(
        glam::EulerRot::ZYX,
        az.to_radians(),
        el.to_radians(),
        roll.to_radians(),
    )
}

#[test]
fn fob_position_angles_group_mode_vector() {
    let bytes = hex("80 10 00 78 00 20 00 20 00 70 00 08 02");
    let config = FobConfig {
        mode: FobMode::PositionAngles,
        group_mode: true,
        ..FobConfig::default()
    };
    let samples = decode_every_way(|| Box::new(FobDecoder::new(config.clone())), &bytes);
    assert_eq!(samples.len(), 1);
    let sample = samples[0];
    assert_eq!(sample.sensor, SensorId(2));
    assert_vec(sample.position_m, DVec3::new(9.0, -4.5, 18.0) * INCH, 1e-9);
    assert_quat(sample.orientation, az_el_roll(90.0, -45.0, 22.5), 1e-9);
    // And back: the encoder writes the same bytes.
    assert_eq!(encode_record(&config, &sample).unwrap(), bytes);
}

#[test]
fn fob_position_quaternion_vector() {
    let bytes = hex("80 10 00 78 00 20 20 2D 00 00 00 00 20 2D");
    let config = FobConfig {
        mode: FobMode::PositionQuaternion,
        ..FobConfig::default()
    };
    let samples = decode_every_way(|| Box::new(FobDecoder::new(config.clone())), &bytes);
    assert_eq!(samples.len(), 1);
    assert_eq!(samples[0].sensor, config.standalone_sensor);
    assert_vec(
        samples[0].position_m,
        DVec3::new(9.0, -4.5, 18.0) * INCH,
        1e-9,
    );
    // The bird reports q0 = 0.70703125 (scalar), q3 = 0.70703125: transmitter to sensor.
    // Samples carry sensor to transmitter, the conjugate.
    let bird = DQuat::from_xyzw(0.0, 0.0, 0.70703125, 0.70703125).normalize();
    assert_quat(samples[0].orientation, bird.conjugate(), 1e-9);
    assert_eq!(encode_record(&config, &samples[0]).unwrap(), bytes);
}

#[test]
fn fob_matrix_agrees_with_angles() {
    // The same orientation sent as angles and as a matrix decodes to the same rotation.
    let orientation = az_el_roll(30.0, 20.0, -10.0);
    let sample = Sample {
        sensor: SensorId(1),
        orientation: Some(orientation),
        ..Sample::default()
    };
    for mode in [FobMode::Angles, FobMode::Matrix, FobMode::Quaternion] {
        let config = FobConfig {
            mode,
            ..FobConfig::default()
        };
        let bytes = encode_record(&config, &sample).unwrap();
        assert_eq!(bytes.len(), config.record_len());
        let samples = decode_every_way(|| Box::new(FobDecoder::new(config.clone())), &bytes);
        assert_quat(samples[0].orientation, orientation, 2e-4);
    }
}

#[test]
fn fob_group_mode_rejects_address_zero_and_counts_it() {
    let mut bytes = hex("80 10 00 78 00 20 00 20 00 70 00 08 00");
    bytes.extend(hex("80 10 00 78 00 20 00 20 00 70 00 08 03"));
    let config = FobConfig {
        mode: FobMode::PositionAngles,
        group_mode: true,
        ..FobConfig::default()
    };
    let mut decoder = FobDecoder::new(config);
    let samples = decoder.decode(&bytes);
    assert_eq!(samples.len(), 1);
    assert_eq!(samples[0].sensor, SensorId(3));
    assert_eq!(decoder.stats().bad_frames, 1);
    assert_eq!(decoder.stats().skipped_bytes, 13);
}

#[test]
fn fob_commands() {
    assert_eq!(command::group_mode(true), [0x50, 0x23, 0x01]);
    assert_eq!(command::group_mode(false), [0x50, 0x23, 0x00]);
    assert_eq!(command::auto_config(4), [0x50, 0x32, 0x04]);
    assert_eq!(command::STREAM, b'@');
    assert_eq!(command::POINT, b'B');
    assert_eq!(command::to_bird(2).unwrap(), 0xF2);
    assert_eq!(command::to_bird(17).unwrap(), 0xE1);
    assert!(command::to_bird(0).is_err());
    assert!(command::to_bird(31).is_err());
    let modes: Vec<u8> = FobMode::ALL
        .iter()
        .map(|m| command::set_mode(*m)[0])
        .collect();
    assert_eq!(modes, b"VWXYZ\\]".to_vec());
    let config = FobConfig {
        mode: FobMode::PositionQuaternion,
        group_mode: true,
        ..FobConfig::default()
    };
    let setup = command::start_streaming(&config, 2).unwrap();
    assert_eq!(
        setup,
        vec![0x50, 0x32, 2, 0xF1, b']', 0xF2, b']', 0x50, 0x23, 1, b'@']
    );
    let single = command::start_streaming(&FobConfig::default(), 1).unwrap();
    assert_eq!(single, vec![b']', 0x50, 0x23, 0, b'@']);
    assert_eq!(command::stop_streaming(), [b'B']);
}

#[test]
fn fastrak_vector() {
    let bytes = b"01    9.00  -4.50  18.00  90.00 -45.00  22.50\r\n";
    let samples = decode_every_way(
        || Box::new(FastrakDecoder::new(FastrakConfig::default())),
        bytes,
    );
    assert_eq!(samples.len(), 1);
    assert_eq!(samples[0].sensor, SensorId(1));
    assert_vec(
        samples[0].position_m,
        DVec3::new(9.0, -4.5, 18.0) * INCH,
        1e-9,
    );
    assert_quat(samples[0].orientation, az_el_roll(90.0, -45.0, 22.5), 1e-9);
}

#[test]
fn fastrak_fields_that_touch_and_an_unterminated_last_record() {
    // "-100.00" fills its 7 columns: no space separates it from the previous field.
    let bytes = b"02 -100.00  -4.50  18.00-170.00 -45.00  22.50\r\n03   1.00   2.00   3.00   0.00   0.00   0.00";
    let mut decoder = FastrakDecoder::new(FastrakConfig::default());
    let mut samples = Vec::new();
    decoder.push(bytes, &mut samples);
    assert_eq!(samples.len(), 1);
    decoder.finish(&mut samples);
    assert_eq!(samples.len(), 2);
    assert_vec(
        samples[0].position_m,
        DVec3::new(-100.0, -4.5, 18.0) * INCH,
        1e-9,
    );
    assert_quat(
        samples[0].orientation,
        az_el_roll(-170.0, -45.0, 22.5),
        1e-9,
    );
    assert_eq!(samples[1].sensor, SensorId(3));
    let stats = decoder.stats();
    assert_eq!(stats.bytes_in_frames, bytes.len() as u64);
}

#[test]
fn liberty_vector() {
    let bytes = hex(
        "4C 59 01 43 00 00 1C 00 00 00 10 41 00 00 90 C0 00 00 90 41 F3 04 35 3F \
         00 00 00 00 00 00 00 00 F3 04 35 3F",
    );
    let samples = decode_every_way(
        || Box::new(LibertyDecoder::new(LibertyConfig::default())),
        &bytes,
    );
    assert_eq!(samples.len(), 1);
    assert_eq!(samples[0].sensor, SensorId(1));
    assert_vec(
        samples[0].position_m,
        DVec3::new(9.0, -4.5, 18.0) * INCH,
        1e-6,
    );
    let want = DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2);
    assert_quat(samples[0].orientation, want, 1e-4);
    // Patriot frames differ only in the magic.
    let mut patriot = bytes.clone();
    patriot[0] = b'P';
    patriot[1] = b'A';
    let samples = decode_every_way(
        || Box::new(LibertyDecoder::new(LibertyConfig::default())),
        &patriot,
    );
    assert_eq!(samples.len(), 1);
}

#[test]
fn xsens_vector() {
    let bytes = hex(
        "FA FF 36 26 10 20 02 46 82 10 60 04 01 C4 FC 3E 20 10 10 3F 71 CE 6C BE A5 6B CF \
         3C 61 3B D8 BD 69 1D 25 E0 20 04 00 40 00 03 12",
    );
    let samples = decode_every_way(|| Box::new(XsensDecoder::new()), &bytes);
    assert_eq!(samples.len(), 1);
    let sample = samples[0];
    assert_eq!(sample.sensor, SensorId(0));
    assert_eq!(sample.counter, Some(18050));
    assert_eq!(sample.device_time_us, Some(0x01C4_FC3E * 100));
    let want = DQuat::from_xyzw(-0.323088, 0.013747, -0.056913, 0.944556).normalize();
    assert_quat(sample.orientation, want, 1e-5);
    // A wrong checksum drops the message and counts a bad frame.
    let mut corrupted = bytes.clone();
    *corrupted.last_mut().unwrap() ^= 0x01;
    let mut decoder = XsensDecoder::new();
    assert!(decoder.decode(&corrupted).is_empty());
    decoder.finish(&mut Vec::new());
    assert_eq!(decoder.stats().bad_frames, 1);
    assert_eq!(decoder.stats().skipped_bytes, corrupted.len() as u64);
}

#[test]
fn xsens_other_messages_are_frames_without_samples() {
    // WakeUp (MID 0x3E) with no data: FA FF 3E 00 C3.
    let bytes = hex("FA FF 3E 00 C3");
    let mut decoder = XsensDecoder::new();
    assert!(decoder.decode(&bytes).is_empty());
    assert_eq!(decoder.stats().frames, 1);
    assert_eq!(decoder.stats().bad_frames, 0);
}

#[test]
fn ascii_vectors() {
    let adafruit = b"Quaternion: 0.71, 0.00, 0.00, 0.71\r\n";
    let config = AsciiConfig {
        order: ComponentOrder::Wxyz,
        ..AsciiConfig::default()
    };
    let samples = decode_every_way(
        || Box::new(AsciiQuaternionDecoder::new(config.clone())),
        adafruit,
    );
    assert_eq!(samples.len(), 1);
    assert_eq!(samples[0].sensor, SensorId(0));
    // w = 0.71, x = 0, y = 0, z = 0.71.
    let want = DQuat::from_xyzw(0.0, 0.0, 0.71, 0.71).normalize();
    assert_quat(samples[0].orientation, want, 1e-9);

    let sparkfun = b"0.00,0.00,0.71,0.71,0.05,\r\n";
    let config = AsciiConfig {
        order: ComponentOrder::Xyzw,
        ..AsciiConfig::default()
    };
    let samples = decode_every_way(
        || Box::new(AsciiQuaternionDecoder::new(config.clone())),
        sparkfun,
    );
    assert_eq!(samples.len(), 1);
    let want = DQuat::from_xyzw(0.0, 0.0, 0.71, 0.71).normalize();
    assert_quat(samples[0].orientation, want, 1e-9);
}

#[test]
fn ascii_rejects_lines_that_are_not_quaternions() {
    let text =
        b"Orientation: 359.00, -1.00, 2.00\r\nCalibration: 3, 3, 3, 3\r\n\r\n2: 1, 0, 0, 0\n";
    let mut decoder = AsciiQuaternionDecoder::new(AsciiConfig::default());
    let samples = decoder.decode(text);
    assert_eq!(samples.len(), 1);
    assert_eq!(samples[0].sensor, SensorId(2));
    assert_eq!(decoder.stats().bad_frames, 2);
}

#[test]
fn slimevr_vector() {
    let packet = hex("01 00 00 00 00 00 00 00 FF 7F 00 00 00 00 E8 04");
    let mut decoder = SlimeVrDecoder::new();
    let mut samples = Vec::new();
    decoder.push_report(0, &packet, &mut samples);
    assert_eq!(samples.len(), 1);
    assert_eq!(samples[0].sensor, SensorId(0));
    assert_quat(samples[0].orientation, DQuat::IDENTITY, 1e-9);
    assert_vec(
        samples[0].acceleration_mps2,
        DVec3::new(0.0, 0.0, 9.8125),
        1e-12,
    );
    // The same packet through a report log, split every way.
    let record = stance_mocap::hid::encode_report_record(0, &packet).unwrap();
    let logged = decode_every_way(|| Box::new(SlimeVrDecoder::new()), &record);
    assert_eq!(logged, samples);
}

#[test]
fn slimevr_compressed_packets_and_other_types() {
    // Type 2: exponential map 10/11/11 bits; mid-scale values (512, 1024, 1024) are identity.
    let bits: u32 = 512 | (1024 << 10) | (1024 << 21);
    let mut compressed = vec![2u8, 5, 0, 0, 0];
    compressed.extend_from_slice(&bits.to_le_bytes());
    compressed.extend_from_slice(&[0, 0, 0, 0, 0x80, 0x04, 0]);
    assert_eq!(compressed.len(), 16);
    let info = [0u8; 16];
    let mut unknown = [0u8; 16];
    unknown[0] = 9;
    let report = [compressed.as_slice(), &info, &unknown].concat();
    let mut decoder = SlimeVrDecoder::new();
    let mut samples = Vec::new();
    decoder.push_report(0, &report, &mut samples);
    assert_eq!(samples.len(), 1);
    assert_eq!(samples[0].sensor, SensorId(5));
    assert_quat(samples[0].orientation, DQuat::IDENTITY, 2e-3);
    assert_vec(
        samples[0].acceleration_mps2,
        DVec3::new(0.0, 0.0, 9.0),
        1e-12,
    );
    let stats = decoder.stats();
    assert_eq!((stats.frames, stats.bad_frames), (2, 1));
}
