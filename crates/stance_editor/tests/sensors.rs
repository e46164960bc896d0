//! Motion-capture sensors in the editor, natively: the same path as the page's WebSerial and
//! WebHID bridge (bytes and reports through the host inbox) and as a replayed recording.
//! A simulated right arm (`stance_mocap::simulate`) is the ground truth.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::sync::mpsc::{Sender, channel};

use egui::Key;
use egui_kittest::Harness;
use glam::DQuat;
use serde_json::Value;
use stance_editor::posing::PosingSession;
use stance_editor::sensors::{
    AssignmentPreset, DeviceFrame, DeviceKind, SensorConnection, SensorHub, SensorSettings,
    preset_button_name,
};
use stance_editor::{HostMessage, MemoryHost, StanceApp};
use stance_hanim::LevelOfArticulation;
use stance_mocap::fob::{FobConfig, FobMode, encode_record};
use stance_mocap::simulate::{SimulatedDevice, SimulationOptions, simulate};
use stance_mocap::{Sample, SensorId};

use crate::common;
use common::{click_button, harness_for, state};

const RATE_HZ: f64 = 50.0;

fn fob_group_config() -> FobConfig {
    FobConfig {
        mode: FobMode::PositionQuaternion,
        group_mode: true,
        ..FobConfig::default()
    }
}

/// The simulated arm as Flock of Birds group-mode records: bytes per frame and the truth.
fn simulated_fob() -> (Vec<Vec<u8>>, Vec<Vec<Sample>>) {
    let stream = simulate(
        &SimulatedDevice::FlockOfBirds(fob_group_config()),
        &SimulationOptions {
            rate_hz: RATE_HZ,
            duration_secs: 4.0,
            ..SimulationOptions::default()
        },
    )
    .unwrap();
    let record = fob_group_config().record_len();
    let frames: Vec<Vec<u8>> = stream
        .bytes
        .chunks(record * 4)
        .map(<[u8]>::to_vec)
        .collect();
    let truth: Vec<Vec<Sample>> = stream.truth.chunks(4).map(<[Sample]>::to_vec).collect();
    assert_eq!(frames.len(), truth.len());
    (frames, truth)
}

/// Angle between two rotations, degrees.
fn angle_deg(a: DQuat, b: DQuat) -> f64 {
    let d = (a.inverse() * b).normalize();
    (2.0 * d.w.abs().clamp(0.0, 1.0).acos()).to_degrees()
}

/// World rotation the editor must give the segment of `sensor` (Molet et al.): calibrated
/// when the joint's world rotation was `joint_at_calibration` and every sensor read identity
/// (the simulated arm hangs at t = 0), so `J(t) = A S(t) A^-1 J_cal`.
fn expected_world(truth: &[Sample], sensor: u16, joint_at_calibration: DQuat) -> DQuat {
    let a = DeviceFrame::TransmitterZDown.world_from_device();
    let s = truth
        .iter()
        .find(|sample| sample.sensor == SensorId(sensor))
        .and_then(|sample| sample.orientation)
        .unwrap();
    a * s * a.inverse() * joint_at_calibration
}

fn quat(value: &Value) -> DQuat {
    let q: Vec<f64> = value
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    DQuat::from_xyzw(q[0], q[1], q[2], q[3])
}

fn harness(host: &MemoryHost) -> (Harness<'static, StanceApp>, Sender<HostMessage>) {
    let (sender, receiver) = channel();
    let app = StanceApp::without_gpu(Box::new(host.clone()))
        .unwrap()
        .with_inbox(receiver);
    (harness_for(app), sender)
}

fn send_bytes(sender: &Sender<HostMessage>, bytes: &[u8]) {
    sender
        .send(HostMessage::SensorBytes {
            bytes: bytes.to_vec(),
            arrived: web_time::Instant::now(),
        })
        .unwrap();
}

/// Through the editor as a user works: open the window (S), connect (the page gets a serial
/// request that sets the flock up and starts streaming), stream, assign, calibrate; the arm
/// then follows the recorded motion within a degree while the pinned feet stay put; an
/// unplugged device says so and the posture stays.
#[test]
fn a_streamed_flock_of_birds_drives_the_arm_after_calibration() {
    let host = MemoryHost::default();
    let (mut harness, sender) = harness(&host);
    let feet_before = [
        harness
            .state()
            .model()
            .session()
            .joint_position("l_talocrural")
            .unwrap(),
        harness
            .state()
            .model()
            .session()
            .joint_position("r_talocrural")
            .unwrap(),
    ];
    harness.key_press(Key::S);
    harness.run_steps(2);
    click_button(&mut harness, "sensors_connect");
    let requests = host.inner.borrow().sensor_requests.clone();
    match requests.as_slice() {
        [
            SensorConnection::Serial {
                baud_rate,
                setup,
                stop,
            },
        ] => {
            assert_eq!(*baud_rate, 115_200);
            assert_eq!(stop.as_slice(), b"B", "POINT stops the stream");
            assert_eq!(setup.last(), Some(&b'@'), "ends with STREAM: {setup:?}");
            assert!(
                setup.windows(3).any(|w| w == [b'P', 35, 1]),
                "group mode on"
            );
        }
        other => panic!("expected one serial request, got {other:?}"),
    }
    assert_eq!(state(&harness)["sensors"]["link"], "connecting");
    sender
        .send(HostMessage::SensorConnected {
            device: "test port".to_owned(),
        })
        .unwrap();
    let (frames, truth) = simulated_fob();
    // The first frame (the person stands like the avatar), split mid-record on purpose.
    let (head, tail) = frames[0].split_at(7);
    send_bytes(&sender, head);
    send_bytes(&sender, tail);
    harness.run_steps(2);
    let sensors = state(&harness)["sensors"].clone();
    assert_eq!(sensors["link"], "connected");
    assert_eq!(sensors["samples"], 4);
    assert_eq!(sensors["sensors"].as_array().unwrap().len(), 4);

    click_button(
        &mut harness,
        preset_button_name(AssignmentPreset::TorsoRightArm),
    );
    assert_eq!(state(&harness)["sensors"]["assigned"], 4);
    harness.run_steps(10);
    let at_calibration = |harness: &Harness<'static, StanceApp>, joint: &str| {
        let session = harness.state().model().session();
        session
            .frames()
            .rotation(session.skeleton().joint_index(joint).unwrap())
    };
    let joints_at_calibration: Vec<DQuat> = ["r_shoulder", "r_elbow", "r_radiocarpal", "vt1"]
        .iter()
        .map(|joint| at_calibration(&harness, joint))
        .collect();
    click_button(&mut harness, "sensors_calibrate");
    assert_eq!(
        state(&harness)["sensors"]["calibrated"],
        true,
        "{}",
        state(&harness)["notice"]
    );

    let mut sent = 0;
    for k in [25, 50, 100, 150] {
        for frame in &frames[sent + 1..=k] {
            send_bytes(&sender, frame);
        }
        sent = k;
        harness.run_steps(30);
        let sensors = state(&harness)["sensors"].clone();
        let driven = &sensors["driven"];
        for ((joint, sensor), calibrated) in [
            ("r_shoulder", 2),
            ("r_elbow", 3),
            ("r_radiocarpal", 4),
            ("vt1", 1),
        ]
        .into_iter()
        .zip(&joints_at_calibration)
        {
            let world = quat(&driven[joint]["world"]);
            let error = angle_deg(world, expected_world(&truth[k], sensor, *calibrated));
            assert!(error < 0.2, "frame {k}: {joint} off by {error:.3} degrees");
        }
        let session = harness.state().model().session();
        assert!(
            session.is_settled(),
            "frame {k}: the solver settles with sensors holding"
        );
        for (foot, before) in ["l_talocrural", "r_talocrural"].iter().zip(feet_before) {
            let moved = (session.joint_position(foot).unwrap() - before).length();
            assert!(moved < 1e-3, "frame {k}: {foot} moved {moved} m");
        }
        let latency = &sensors["latency_max_ms"];
        assert!(latency.as_f64().is_some(), "latency measured");
    }

    let held = harness.state().model().session().posture().clone();
    sender
        .send(HostMessage::SensorLost {
            reason: "The serial device was unplugged.".to_owned(),
        })
        .unwrap();
    harness.run_steps(20);
    let after = state(&harness);
    assert_eq!(after["sensors"]["link"], "lost");
    let notice = after["notice"]["text"].as_str().unwrap();
    assert!(notice.contains("unplugged"), "{notice}");
    assert_eq!(after["notice"]["error"], true);
    let posture = harness.state().model().session().posture();
    let drift = posture
        .values()
        .iter()
        .zip(held.values())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(drift < 1e-9, "the posture stays: moved by {drift}");
}

/// Calibration in a posture that is not the rest pose: the driven joints reproduce the
/// calibration posture at the calibration instant.
#[test]
fn at_the_calibration_instant_the_joints_keep_the_calibration_posture() {
    let mut session = PosingSession::new(LevelOfArticulation::Loa2).unwrap();
    let skeleton = session.skeleton().clone();
    let shoulder = skeleton.joint_index("r_shoulder").unwrap();
    let elbow = skeleton.joint_index("r_elbow").unwrap();
    session.drive_joints(&[
        (shoulder, DQuat::from_rotation_x(-0.6)),
        (elbow, DQuat::from_rotation_x(-1.0)),
    ]);
    let mut hub = SensorHub::new(SensorSettings::default());
    let (frames, _) = simulated_fob();
    hub.receive_bytes(&frames[40], 0.0, web_time::Instant::now());
    hub.apply_preset(AssignmentPreset::TorsoRightArm, &skeleton);
    let world_before: Vec<DQuat> = (0..skeleton.joint_count())
        .map(|joint| session.frames().rotation(joint))
        .collect();
    hub.calibrate(&skeleton, session.frames()).unwrap();
    let rotations = hub
        .take_driven_rotations(&skeleton, session.frames(), false)
        .unwrap();
    session.drive_joints(&rotations);
    for joint in hub.driven_joints(&skeleton) {
        let error = angle_deg(session.frames().rotation(joint), world_before[joint]);
        assert!(error < 1e-6, "{}: {error}", skeleton.joints()[joint].name);
    }
    assert!(
        hub.take_driven_rotations(&skeleton, session.frames(), false)
            .is_none(),
        "nothing new"
    );
}

/// Ten sensors at 120 Hz for ten seconds, delivered in the chunks a 60 Hz page sees: every
/// frame decoded, none dropped, each sensor at 120 Hz.
#[test]
fn ten_sensors_at_120_hz_lose_no_frame() {
    let config = fob_group_config();
    let mut bytes = Vec::new();
    let frames = 1200;
    for frame in 0..frames {
        for bird in 1..=10u16 {
            let angle = 0.001 * f64::from(frame) + f64::from(bird);
            let sample = Sample {
                sensor: SensorId(bird),
                position_m: Some(glam::DVec3::new(0.1, 0.2, 0.3)),
                orientation: Some(DQuat::from_rotation_z(angle)),
                ..Sample::default()
            };
            bytes.extend(encode_record(&config, &sample).unwrap());
        }
    }
    let mut hub = SensorHub::new(SensorSettings::default());
    let per_browser_frame = bytes.len() / 600;
    let start = web_time::Instant::now();
    for (index, chunk) in bytes.chunks(per_browser_frame).enumerate() {
        hub.receive_bytes(chunk, index as f64 / 60.0, web_time::Instant::now());
    }
    let elapsed = start.elapsed().as_secs_f64();
    let stats = hub.stats();
    assert_eq!(hub.sample_count(), 12_000);
    assert_eq!(stats.bad_frames, 0);
    assert_eq!(stats.skipped_bytes, 0);
    for (sensor, track) in hub.tracks() {
        assert_eq!(track.samples, 1200, "sensor {sensor:?}");
        let rate = track.rate_hz();
        assert!((rate - 120.0).abs() < 8.0, "sensor {sensor:?} at {rate} Hz");
    }
    eprintln!(
        "[sensors] 10 sensors x 120 Hz x 10 s: {} bytes decoded in {:.1} ms ({:.0} MB/s)",
        bytes.len(),
        elapsed * 1e3,
        bytes.len() as f64 / elapsed / 1e6
    );
}

/// A recording gives back exactly the bytes received, and replaying it decodes the same
/// samples at the replay rate.
#[test]
fn a_recording_replays_like_the_device() {
    let (frames, truth) = simulated_fob();
    let mut hub = SensorHub::new(SensorSettings::default());
    hub.start_recording();
    let mut sent = Vec::new();
    for frame in &frames {
        hub.receive_bytes(frame, 0.0, web_time::Instant::now());
        sent.extend_from_slice(frame);
    }
    let recording = hub.stop_recording().unwrap();
    assert_eq!(recording, sent);

    let mut replay = SensorHub::new(SensorSettings {
        replay_rate_hz: RATE_HZ,
        ..SensorSettings::default()
    });
    replay.start_replay("arm.bin", recording, 10.0);
    assert!(replay.tick(10.0).is_none());
    assert_eq!(replay.sample_count(), 0, "nothing at the start instant");
    assert!(replay.tick(11.0).is_none());
    let after_one_second = replay.sample_count();
    assert!(
        (after_one_second as f64 - 4.0 * RATE_HZ).abs() <= 8.0,
        "one second of samples: {after_one_second}"
    );
    let message = replay.tick(20.0).unwrap();
    assert!(message.contains("finished"), "{message}");
    assert_eq!(replay.sample_count(), truth.len() as u64 * 4);
    assert_eq!(replay.stats().bad_frames, 0);
    let last = truth.last().unwrap();
    for sample in last {
        let track = &replay.tracks()[&sample.sensor];
        let error = angle_deg(track.last.orientation.unwrap(), sample.orientation.unwrap());
        assert!(error < 0.2, "{error}");
    }
}

/// A SlimeVR receiver over HID (reports, not bytes) through the editor: calibrated in the
/// earth frame, the arm follows.
#[test]
fn slimevr_hid_reports_drive_the_arm() {
    let stream = simulate(
        &SimulatedDevice::SlimeVr,
        &SimulationOptions {
            rate_hz: RATE_HZ,
            duration_secs: 2.0,
            ..SimulationOptions::default()
        },
    )
    .unwrap();
    let mut session = PosingSession::new(LevelOfArticulation::Loa2).unwrap();
    let skeleton = session.skeleton().clone();
    let mut hub = SensorHub::new(SensorSettings {
        device: DeviceKind::SlimeVr,
        frame: DeviceFrame::EarthZUp,
        ..SensorSettings::default()
    });
    assert!(matches!(
        hub.settings().connection().unwrap(),
        SensorConnection::Hid { filters } if filters == vec![(0x1209, 0x7690)]
    ));
    // The recording is a report log; split it into reports as WebHID delivers them.
    let reports = report_log(&stream.bytes);
    let per_frame = reports.len() / stream.truth.len().div_ceil(4).max(1);
    assert!(per_frame >= 1);
    let frames: Vec<&[(u8, Vec<u8>)]> = reports.chunks(per_frame).collect();
    for (id, data) in frames[0] {
        hub.receive_report(*id, data, 0.0, web_time::Instant::now());
    }
    hub.apply_preset(AssignmentPreset::TorsoRightArm, &skeleton);
    let at_calibration: Vec<DQuat> = (0..skeleton.joint_count())
        .map(|joint| session.frames().rotation(joint))
        .collect();
    hub.calibrate(&skeleton, session.frames()).unwrap();
    session.hold_joints(&hub.driven_joints(&skeleton));
    for (id, data) in frames.iter().skip(1).take(50).flat_map(|f| f.iter()) {
        hub.receive_report(*id, data, 0.0, web_time::Instant::now());
    }
    for _ in 0..30 {
        hub.drive(&mut session);
        session.solve_frame(None);
    }
    let latest = hub.latest_orientations();
    let a = DeviceFrame::EarthZUp.world_from_device();
    let first: Vec<DQuat> = stream.truth[..4]
        .iter()
        .map(|s| s.orientation.unwrap())
        .collect();
    // Sensors 1..4 (torso, upper arm, forearm, hand) went to the preset's segments in order.
    for (joint, sensor, index) in [
        ("r_shoulder", 2u16, 1usize),
        ("r_elbow", 3, 2),
        ("r_radiocarpal", 4, 3),
    ] {
        let joint_index = skeleton.joint_index(joint).unwrap();
        let expected = a
            * latest[&SensorId(sensor)]
            * first[index].inverse()
            * a.inverse()
            * at_calibration[joint_index];
        let world = session.frames().rotation(joint_index);
        let error = angle_deg(world, expected);
        assert!(error < 0.2, "{joint}: {error:.3} degrees");
    }
}

/// Splits a report log (`encode_report_record`) into (report id, data).
fn report_log(bytes: &[u8]) -> Vec<(u8, Vec<u8>)> {
    let mut reports = Vec::new();
    let mut rest = bytes;
    while rest.len() >= 5 && rest[..2] == *b"HR" {
        let id = rest[2];
        let len = usize::from(rest[3]);
        reports.push((id, rest[4..4 + len].to_vec()));
        rest = &rest[5 + len..];
    }
    assert!(rest.is_empty(), "a well-formed log");
    reports
}

#[test]
fn settings_survive_as_json_and_bad_requests_say_why() {
    let settings = SensorSettings {
        device: DeviceKind::AsciiImu,
        baud_rate: 57_600,
        ..SensorSettings::default()
    };
    let text = serde_json::to_string(&settings).unwrap();
    assert_eq!(
        serde_json::from_str::<SensorSettings>(&text).unwrap(),
        settings
    );
    let partial: SensorSettings = serde_json::from_str(r#"{"baud_rate": 9600}"#).unwrap();
    assert_eq!(partial.baud_rate, 9600);
    let bad = SensorSettings {
        baud_rate: 0,
        ..SensorSettings::default()
    };
    assert!(bad.connection().unwrap_err().contains("baud"));
    let json: Value =
        serde_json::from_str(&SensorSettings::default().connection().unwrap().to_json()).unwrap();
    assert_eq!(json["kind"], "serial");
    assert_eq!(json["baud_rate"], 115_200);
    assert_eq!(json["stop"], serde_json::json!([b'B']));
}

/// A file the decoder cannot read plays out over frames (bounded work per frame) and ends
/// with counts that say so.
#[test]
fn an_unreadable_replay_is_paced_and_reported() {
    let mut hub = SensorHub::new(SensorSettings::default());
    let garbage: Vec<u8> = (0..1_000_000u32)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 24) as u8 & 0x7F)
        .collect();
    hub.start_replay("noise.bin", garbage, 0.0);
    let mut ticks = 0;
    let message = loop {
        ticks += 1;
        let (done, total) = hub.replay_progress().unwrap();
        assert!(done <= total);
        if let Some(message) = hub.tick(f64::from(ticks) / 60.0) {
            break message;
        }
        assert!(ticks < 100, "the replay ends");
    };
    assert!(ticks >= 4, "spread over frames: {ticks}");
    assert!(message.contains("0 samples"), "{message}");
    assert_eq!(hub.stats().bytes_received, 1_000_000);
    assert_eq!(hub.sample_count(), 0);
}
