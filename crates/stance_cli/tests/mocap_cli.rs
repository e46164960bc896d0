//! `stance simulate-sensors` and `stance decode` round trips through the built binary.

// Test helpers outside #[test] functions may unwrap too (clippy.toml only covers the tests).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::PathBuf;
use std::process::{Command, Stdio};

use serde_json::Value;
use stance_mocap::simulate::{SimulatedDevice, SimulationOptions, simulate};

fn stance() -> Command {
    Command::new(env!("CARGO_BIN_EXE_stance"))
}

fn temp_file(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("stance-mocap-cli-{}-{name}", std::process::id()))
}

/// Runs `stance decode` and returns the sample lines and the summary.
fn decode(protocol_args: &[&str], file: &str, stdin: Option<Vec<u8>>) -> (Vec<Value>, Value) {
    let mut command = stance();
    command.arg("decode").args(protocol_args).arg(file);
    command.stdout(Stdio::piped()).stderr(Stdio::piped());
    if stdin.is_some() {
        command.stdin(Stdio::piped());
    }
    let mut child = command.spawn().expect("run stance decode");
    if let Some(bytes) = stdin {
        use std::io::Write;
        child.stdin.take().unwrap().write_all(&bytes).unwrap();
    }
    let output = child.wait_with_output().unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let mut lines: Vec<Value> = String::from_utf8(output.stdout)
        .unwrap()
        .lines()
        .map(|line| serde_json::from_str(line).expect("JSON line"))
        .collect();
    let summary = lines.pop().expect("summary line");
    (lines, summary["summary"].clone())
}

fn simulate_to_file(protocol_args: &[&str], extra: &[&str], name: &str) -> PathBuf {
    let path = temp_file(name);
    let output = stance()
        .arg("simulate-sensors")
        .args(protocol_args)
        .args(extra)
        .args(["--duration-secs", "1", "--rate-hz", "50", "--out"])
        .arg(&path)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    path
}

#[test]
fn every_protocol_round_trips_through_the_cli() {
    let cases: &[(&[&str], &[&str], usize)] = &[
        (&["--protocol", "fob", "--group"], &[], 4),
        (
            &["--protocol", "fob", "--fob-mode", "pos-angles", "--group"],
            &[],
            4,
        ),
        (&["--protocol", "fob", "--fob-mode", "matrix"], &[], 1),
        (
            &["--protocol", "fob", "--fob-mode", "quat", "--group"],
            &[],
            4,
        ),
        (
            &["--protocol", "fob", "--fob-mode", "angles", "--group"],
            &[],
            4,
        ),
        (&["--protocol", "fastrak"], &[], 4),
        (
            &[
                "--protocol",
                "fastrak",
                "--polhemus-items",
                "pos,quat",
                "--units",
                "cm",
            ],
            &[],
            4,
        ),
        (&["--protocol", "liberty"], &[], 4),
        (
            &[
                "--protocol",
                "liberty",
                "--polhemus-items",
                "count,time,pos,euler",
            ],
            &["--patriot"],
            4,
        ),
        (
            &["--protocol", "xsens"],
            &["--xsens-precision", "fixed1632"],
            4,
        ),
        (&["--protocol", "ascii", "--order", "xyzw"], &[], 4),
        (&["--protocol", "slimevr-hid"], &[], 4),
        (&["--protocol", "dualsense"], &[], 1),
        (&["--protocol", "ds4"], &["--bluetooth"], 1),
    ];
    for (index, (protocol_args, extra, sensors)) in cases.iter().enumerate() {
        let path = simulate_to_file(protocol_args, extra, &format!("case{index}"));
        let (samples, summary) = decode(protocol_args, path.to_str().unwrap(), None);
        let frames = 51; // 1 s at 50 Hz, both ends included
        assert_eq!(samples.len(), frames * sensors, "{protocol_args:?}");
        assert_eq!(summary["samples"], samples.len(), "{protocol_args:?}");
        assert_eq!(summary["bad_frames"], 0, "{protocol_args:?}");
        assert_eq!(summary["skipped_bytes"], 0, "{protocol_args:?}");
        assert_eq!(summary["bytes"], std::fs::metadata(&path).unwrap().len());
        for sample in &samples {
            let q = sample["quaternion"].as_array().expect("quaternion");
            assert_eq!(q.len(), 4);
            let norm: f64 = q
                .iter()
                .map(|c| c.as_f64().unwrap().powi(2))
                .sum::<f64>()
                .sqrt();
            assert!((norm - 1.0).abs() < 1e-5, "{sample}");
            assert!(sample["sensor"].is_u64());
        }
        std::fs::remove_file(path).ok();
    }
}

#[test]
fn decoded_fob_values_match_the_simulated_motion_in_metres_and_xyzw() {
    let path = simulate_to_file(&["--protocol", "fob", "--group"], &[], "fob-values");
    let (samples, _) = decode(
        &["--protocol", "fob", "--group"],
        path.to_str().unwrap(),
        None,
    );
    std::fs::remove_file(path).ok();
    let device = SimulatedDevice::FlockOfBirds(stance_mocap::fob::FobConfig {
        group_mode: true,
        ..Default::default()
    });
    let options = SimulationOptions {
        rate_hz: 50.0,
        duration_secs: 1.0,
        ..Default::default()
    };
    let truth = simulate(&device, &options).unwrap().truth;
    assert_eq!(samples.len(), truth.len());
    for (line, want) in samples.iter().zip(&truth) {
        assert_eq!(line["sensor"], want.sensor.0);
        let p: Vec<f64> = line["position_m"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let want_p = want.position_m.unwrap();
        assert!(
            glam::DVec3::new(p[0], p[1], p[2]).distance(want_p) < 5e-4,
            "{line}"
        );
        let q: Vec<f64> = line["quaternion"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let got = glam::DQuat::from_xyzw(q[0], q[1], q[2], q[3]).normalize();
        assert!(
            got.angle_between(want.orientation.unwrap()) < 0.3f64.to_radians(),
            "{line}"
        );
    }
}

#[test]
fn decode_reads_standard_input_and_counts_garbage() {
    let output = stance()
        .args([
            "simulate-sensors",
            "--protocol",
            "xsens",
            "--duration-secs",
            "0.2",
        ])
        .output()
        .unwrap();
    assert!(output.status.success());
    let mut bytes = b"garbage before the first message".to_vec();
    let garbage = bytes.len();
    bytes.extend_from_slice(&output.stdout);
    bytes.truncate(bytes.len() - 5); // a truncated last message
    let (samples, summary) = decode(&["--protocol", "xsens"], "-", Some(bytes.clone()));
    assert_eq!(samples.len(), 21 * 4 - 1);
    assert_eq!(summary["bad_frames"], 0);
    let skipped = summary["skipped_bytes"].as_u64().unwrap();
    assert!(skipped as usize > garbage, "{summary}");
    assert_eq!(summary["bytes"], bytes.len());
    // Each sample carries the Xsens packet counter and device time.
    assert!(
        samples
            .iter()
            .all(|s| s["counter"].is_u64() && s["time_us"].is_u64())
    );
}

#[test]
fn decode_rejects_a_missing_file() {
    let output = stance()
        .args([
            "decode",
            "--protocol",
            "fob",
            "/nonexistent/stance-mocap-recording.bin",
        ])
        .output()
        .unwrap();
    assert!(!output.status.success());
    assert!(String::from_utf8_lossy(&output.stderr).contains("reading"));
}
