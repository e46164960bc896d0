//! A deterministic fuzz loop in the normal test suite: seeded random and mutated inputs, in
//! random chunks, through every decoder. Nothing may panic, every sample must be sane and the
//! byte accounting must hold.

// Test helpers outside #[test] functions may unwrap too (clippy.toml only covers the tests).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use crate::common;

use common::*;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

/// Bytes that mean something to some protocol, so that random input reaches deep paths.
const INTERESTING: &[u8] = &[
    0x80, 0x81, 0xFF, 0x00, 0x7F, 0xFA, 0x36, b'L', b'Y', b'P', b'A', b'H', b'R', b'\r', b'\n',
    b'0', b'1', b'2', b':', b',', b'.', b'-', b' ', 0x01, 0x11, 0x31, 0x4C,
];

fn random_input(rng: &mut StdRng, valid: &[u8]) -> Vec<u8> {
    match rng.random_range(0..4u32) {
        0 => (0..rng.random_range(0..300usize))
            .map(|_| rng.random::<u8>())
            .collect(),
        1 => (0..rng.random_range(0..300usize))
            .map(|_| INTERESTING[rng.random_range(0..INTERESTING.len())])
            .collect(),
        _ => {
            // A valid stream, mutated: bit flips, deletions, insertions, duplicated slices.
            let mut bytes = valid.to_vec();
            for _ in 0..rng.random_range(1..8u32) {
                if bytes.is_empty() {
                    break;
                }
                let i = rng.random_range(0..bytes.len());
                match rng.random_range(0..4u32) {
                    0 => bytes[i] ^= 1 << rng.random_range(0..8u32),
                    1 => {
                        bytes.remove(i);
                    }
                    2 => bytes.insert(i, rng.random()),
                    _ => {
                        let end = (i + rng.random_range(1..20usize)).min(bytes.len());
                        let copy = bytes[i..end].to_vec();
                        let at = rng.random_range(0..bytes.len());
                        bytes.splice(at..at, copy);
                    }
                }
            }
            bytes
        }
    }
}

#[test]
fn fuzz_every_decoder_with_seeded_inputs() {
    let mut rng = StdRng::seed_from_u64(0x5EED);
    let mut inputs = 0usize;
    for case in cases() {
        let (valid, _) = stream(&case, 0.1);
        for _ in 0..400 {
            let input = random_input(&mut rng, &valid);
            let mut decoder = decoder(&case);
            let mut samples = Vec::new();
            let mut rest = input.as_slice();
            while !rest.is_empty() {
                let n = rng.random_range(1..=64usize).min(rest.len());
                let (chunk, tail) = rest.split_at(n);
                if rng.random_range(0..4u32) == 0 {
                    let report_id = INTERESTING[rng.random_range(0..INTERESTING.len())];
                    decoder.push_report(report_id, chunk, &mut samples);
                } else {
                    decoder.push(chunk, &mut samples);
                }
                assert_accounting(decoder.as_ref());
                rest = tail;
            }
            decoder.finish(&mut samples);
            assert_accounting(decoder.as_ref());
            assert_eq!(decoder.pending_bytes(), 0);
            assert_eq!(
                decoder.stats().samples,
                samples.len() as u64,
                "{}",
                case.name
            );
            assert_sane(&samples);
            inputs += 1;
        }
    }
    assert!(inputs >= 10_000, "only {inputs} inputs");
}

#[test]
fn fuzz_hid_reports_of_every_length() {
    let mut rng = StdRng::seed_from_u64(99);
    for case in cases() {
        let mut decoder = decoder(&case);
        let mut samples = Vec::new();
        for len in 0..200usize {
            for report_id in [0u8, 0x01, 0x11, 0x31, 0xFF] {
                let data: Vec<u8> = (0..len).map(|_| rng.random()).collect();
                decoder.push_report(report_id, &data, &mut samples);
                assert_accounting(decoder.as_ref());
            }
        }
        assert_sane(&samples);
    }
}
