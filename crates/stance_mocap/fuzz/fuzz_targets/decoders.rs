//! Every decoder on arbitrary bytes: the first byte picks the decoder and the chunk size,
//! the rest is fed as a byte stream and as HID reports. Must never panic, and the byte
//! accounting must always balance.
//!
//! Seeds: `fuzz/seeds/decoders/`, a short simulated stream of every protocol behind a selector
//! that picks its decoder (written by `cargo test -p stance_mocap --test all fuzz_seeds:: --
//! --ignored`); `scripts/fuzz.sh decoders` runs the target from them.
#![no_main]

use libfuzzer_sys::fuzz_target;
use stance_mocap::ascii::{AsciiConfig, ComponentOrder};
use stance_mocap::fob::{FobConfig, FobMode};
use stance_mocap::hid::{GamepadConfig, GamepadModel};
use stance_mocap::polhemus::{FastrakConfig, FastrakItem, LibertyConfig, LibertyItem};
use stance_mocap::{Decoder, DecoderConfig, new_decoder};

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

fn check(decoder: &dyn Decoder) {
    let stats = decoder.stats();
    assert_eq!(
        stats.bytes_received,
        stats.bytes_in_frames + stats.skipped_bytes + decoder.pending_bytes() as u64
    );
}

fuzz_target!(|data: &[u8]| {
    let Some((&selector, rest)) = data.split_first() else {
        return;
    };
    let chunk = usize::from(selector % 61) + 1;
    let mut decoder = new_decoder(&config(selector));
    let mut samples = Vec::new();
    for piece in rest.chunks(chunk) {
        decoder.push(piece, &mut samples);
        check(decoder.as_ref());
    }
    for (i, piece) in rest.chunks(chunk).enumerate() {
        decoder.push_report(i as u8, piece, &mut samples);
        check(decoder.as_ref());
    }
    decoder.finish(&mut samples);
    check(decoder.as_ref());
    for sample in &samples {
        if let Some(q) = sample.orientation {
            assert!(q.is_finite() && (q.length() - 1.0).abs() < 1e-6);
        }
    }
});
