//! Every decoder on simulated streams: whole, split at every point, one byte at a time, after
//! garbage, truncated and with flipped bits.

// Test helpers outside #[test] functions may unwrap too (clippy.toml only covers the tests).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use crate::common;

use common::*;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

#[test]
fn whole_stream_round_trips() {
    for case in cases() {
        let (bytes, truth) = stream(&case, 1.0);
        assert!(!truth.is_empty());
        let mut decoder = decoder(&case);
        let samples = decode_chunks(decoder.as_mut(), [bytes.as_slice()], true);
        assert_samples_close(&case, &samples, &truth);
        let stats = decoder.stats();
        assert_eq!(stats.bad_frames, 0, "{}: {stats:?}", case.name);
        assert_eq!(stats.skipped_bytes, 0, "{}: {stats:?}", case.name);
        assert_eq!(stats.bytes_in_frames, bytes.len() as u64, "{}", case.name);
        assert_sane(&samples);
    }
}

#[test]
fn every_split_point_gives_the_same_samples() {
    for case in cases() {
        let (bytes, truth) = stream(&case, 0.06);
        for split in 0..=bytes.len() {
            let (head, tail) = bytes.split_at(split);
            let mut decoder = decoder(&case);
            let samples = decode_chunks(decoder.as_mut(), [head, tail], true);
            assert_samples_close(&case, &samples, &truth);
        }
    }
}

#[test]
fn one_byte_chunks_give_the_same_samples() {
    for case in cases() {
        let (bytes, truth) = stream(&case, 0.3);
        let mut decoder = decoder(&case);
        let samples = decode_chunks(decoder.as_mut(), bytes.chunks(1), true);
        assert_samples_close(&case, &samples, &truth);
        assert_eq!(decoder.stats().bad_frames, 0, "{}", case.name);
    }
}

#[test]
fn random_chunking_gives_the_same_samples() {
    let mut rng = StdRng::seed_from_u64(7);
    for case in cases() {
        let (bytes, truth) = stream(&case, 0.5);
        let mut chunks = Vec::new();
        let mut rest = bytes.as_slice();
        while !rest.is_empty() {
            let n = rng.random_range(1..=40usize).min(rest.len());
            let (chunk, tail) = rest.split_at(n);
            chunks.push(chunk);
            rest = tail;
        }
        let mut decoder = decoder(&case);
        let samples = decode_chunks(decoder.as_mut(), chunks, true);
        assert_samples_close(&case, &samples, &truth);
    }
}

#[test]
fn garbage_prefix_costs_at_most_one_sample() {
    let mut rng = StdRng::seed_from_u64(11);
    for case in cases() {
        let (bytes, truth) = stream(&case, 0.4);
        for _ in 0..20 {
            let garbage_len = rng.random_range(1..200usize);
            let mut input: Vec<u8> = (0..garbage_len).map(|_| rng.random::<u8>()).collect();
            input.extend_from_slice(&bytes);
            let mut decoder = decoder(&case);
            let samples = decode_chunks(decoder.as_mut(), [input.as_slice()], true);
            assert_sane(&samples);
            let keep = truth.len() - case.samples_per_frame;
            assert!(
                samples.len() >= keep,
                "{}: lost too much after garbage",
                case.name
            );
            let tail = &samples[samples.len() - keep..];
            if case.angle_tolerance.is_some() {
                assert_samples_close(&case, tail, &truth[case.samples_per_frame..]);
            }
            assert!(decoder.stats().skipped_bytes >= 1, "{}", case.name);
        }
    }
}

#[test]
fn truncated_tail_gives_a_prefix() {
    let mut rng = StdRng::seed_from_u64(13);
    for case in cases() {
        let (bytes, truth) = stream(&case, 0.4);
        for _ in 0..20 {
            let cut = rng.random_range(0..bytes.len());
            let mut decoder = decoder(&case);
            let samples = decode_chunks(decoder.as_mut(), [&bytes[..cut]], false);
            assert!(samples.len() <= truth.len());
            if case.angle_tolerance.is_some() {
                assert_samples_close(&case, &samples, &truth[..samples.len()]);
            }
            let mut samples = samples;
            decoder.finish(&mut samples);
            assert_accounting(decoder.as_ref());
            assert_eq!(decoder.pending_bytes(), 0);
            assert_sane(&samples);
        }
    }
}

#[test]
fn flipped_bits_cost_few_samples_and_never_panic() {
    let mut rng = StdRng::seed_from_u64(17);
    for case in cases() {
        let (bytes, truth) = stream(&case, 0.4);
        for flips in [1usize, 3, 10] {
            let mut input = bytes.clone();
            for _ in 0..flips {
                let i = rng.random_range(0..input.len());
                input[i] ^= 1 << rng.random_range(0..8u32);
            }
            let mut decoder = decoder(&case);
            let samples = decode_chunks(decoder.as_mut(), input.chunks(17), true);
            assert_sane(&samples);
            if case.angle_tolerance.is_none() {
                continue;
            }
            let (matched, unmatched) = aligned_matches(&case, &samples, &truth);
            // A flip destroys at most the frame it hits and the one after it (a false start).
            assert!(
                matched + 3 * flips * case.samples_per_frame >= truth.len(),
                "{}: {flips} flips lost {} of {} samples",
                case.name,
                truth.len() - matched,
                truth.len()
            );
            if case.checksummed {
                assert_eq!(
                    unmatched, 0,
                    "{}: a corrupted frame produced a sample",
                    case.name
                );
            }
        }
    }
}

#[test]
fn reset_forgets_everything() {
    for case in cases() {
        let (bytes, truth) = stream(&case, 0.1);
        let mut decoder = decoder(&case);
        let mut samples = Vec::new();
        decoder.push(&bytes[..bytes.len() / 2 + 1], &mut samples);
        decoder.reset();
        assert_eq!(decoder.pending_bytes(), 0);
        assert_eq!(decoder.stats(), stance_mocap::DecoderStats::default());
        let samples = decode_chunks(decoder.as_mut(), [bytes.as_slice()], true);
        assert_samples_close(&case, &samples, &truth);
    }
}

#[test]
fn absurd_simulation_requests_are_errors() {
    use stance_mocap::simulate::{SimulationError, SimulationOptions, simulate};
    let case = &cases()[0];
    let huge = SimulationOptions {
        duration_secs: 1e300,
        ..SimulationOptions::default()
    };
    assert!(matches!(
        simulate(&case.device, &huge),
        Err(SimulationError::TooLong(_))
    ));
    let negative = SimulationOptions {
        rate_hz: -1.0,
        ..SimulationOptions::default()
    };
    assert_eq!(
        simulate(&case.device, &negative),
        Err(SimulationError::BadTiming)
    );
}
