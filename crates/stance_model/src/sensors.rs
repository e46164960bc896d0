//! Motion-capture sensors in the editor: the device link, decoding, per-sensor statistics,
//! assignment of sensors to body segments, calibration after Molet et al., recording and
//! replay.
//!
//! Bytes reach a [`SensorHub`] from three sources that take the same path: the page's WebSerial
//! or WebHID bridge (through [`crate::HostMessage`]), a recorded file replayed at the device's
//! pace ([`SensorHub::start_replay`]), and native tests. The hub decodes them with
//! `stance_mocap`, keeps the latest orientation of each sensor and, once calibrated, gives the
//! local rotations of the joints the sensors drive. Joints without a sensor keep the solver's
//! posture and tasks, so feet stay pinned by IK while the torso and arms follow the sensors.

use std::collections::{BTreeMap, VecDeque};

use glam::DQuat;
use serde_json::{Value, json};
use stance_hanim::chains::spine_chain;
use stance_ik::{Frames, Skeleton};

use crate::host::HostHooks;
use crate::posing::PosingSession;
use stance_mocap::calibration::{Calibration, CalibrationSetup, SensorTarget};
use stance_mocap::hid::encode_report_record;
use stance_mocap::{Decoder, DecoderStats, Sample, SensorId, new_decoder};

// The device and rig vocabulary lives in stance_mocap; the editor's settings and hub use it.
pub use self::settings::{SENSOR_SETTINGS_KEY, SensorConnection, SensorSettings};
pub use stance_mocap::device::{DeviceFrame, DeviceKind};
pub use stance_mocap::rig::{AssignmentPreset, SensorAssignment};

mod settings;

/// Samples per sensor per second while replaying a recording, unless the user says otherwise.
pub const DEFAULT_REPLAY_RATE_HZ: f64 = 100.0;
/// Bytes fed to the decoder at a time while replaying (small enough to stop on time).
const REPLAY_CHUNK_BYTES: usize = 32;
/// At most this many bytes are replayed per frame, so that a file the decoder cannot read
/// (no samples to pace it) plays out over frames with its progress shown instead of freezing
/// the page.
const MAX_REPLAY_BYTES_PER_TICK: usize = 256 * 1024;
/// Seconds of arrivals kept to measure each sensor's rate.
const RATE_WINDOW_SECS: f64 = 1.0;
/// Latency samples kept for the median and maximum.
const LATENCY_WINDOW: usize = 240;
/// Largest recording kept in memory (bytes); recording stops there with a message.
pub const MAX_RECORDING_BYTES: usize = 64 * 1024 * 1024;

/// The state of the device link.
#[derive(Clone, Debug, PartialEq)]
pub enum SensorLink {
    /// No device and no replay.
    Idle,
    /// The page is asking the user for a device and opening it.
    Connecting,
    /// A device is open and sending.
    Connected {
        /// The device's name as the browser gives it.
        device: String,
    },
    /// A recording plays as if it came from the device.
    Replaying {
        /// The recording's file name.
        name: String,
    },
    /// The device went away or failed; the posture stays as the last sample left it.
    Lost {
        /// What happened, for the user.
        reason: String,
    },
}

impl SensorLink {
    fn word(&self) -> &'static str {
        match self {
            SensorLink::Idle => "idle",
            SensorLink::Connecting => "connecting",
            SensorLink::Connected { .. } => "connected",
            SensorLink::Replaying { .. } => "replaying",
            SensorLink::Lost { .. } => "lost",
        }
    }

    /// Bytes from a device are expected.
    pub fn is_live(&self) -> bool {
        matches!(self, SensorLink::Connecting | SensorLink::Connected { .. })
    }
}

/// What a sensor drives, for people (joints by their described names).
pub fn assignment_label(assignment: &SensorAssignment) -> String {
    match assignment {
        SensorAssignment::Joint(name) => stance_hanim::readable_name(name),
        SensorAssignment::Spine => "spine (upper back)".to_owned(),
    }
}

/// The name of a preset's button in the page's state (tests click it).
pub fn preset_button_name(preset: AssignmentPreset) -> &'static str {
    match preset {
        AssignmentPreset::TorsoRightArm => "sensors_preset_right_arm",
        AssignmentPreset::TorsoLeftArm => "sensors_preset_left_arm",
        AssignmentPreset::FullBody => "sensors_preset_full_body",
    }
}

/// Running figures of one sensor.
#[derive(Clone, Debug, Default)]
pub struct SensorTrack {
    /// The sensor's latest sample, as the device reported it.
    pub last: Sample,
    /// Samples decoded from this sensor since the device was connected or the replay started.
    pub samples: u64,
    arrivals_secs: VecDeque<f64>,
}

impl SensorTrack {
    /// Samples per second over the last second.
    pub fn rate_hz(&self) -> f64 {
        match (self.arrivals_secs.front(), self.arrivals_secs.back()) {
            (Some(first), Some(last)) if last > first => {
                (self.arrivals_secs.len() - 1) as f64 / (last - first)
            }
            _ => 0.0,
        }
    }
}

/// A recording being played back as if it came from the device.
#[derive(Debug, Clone)]
struct Replay {
    bytes: Vec<u8>,
    offset: usize,
    started_secs: f64,
}

/// Why calibrating failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SensorError {
    /// No sensor drives anything.
    #[error("no sensor is assigned to a body segment")]
    NothingAssigned,
    /// An assigned sensor (by id) has not reported an orientation.
    #[error("sensor {0} has sent no orientation yet")]
    NoReading(u16),
    /// A sensor is assigned to a joint (by H-Anim name) that this body lacks.
    #[error("this body has no joint {0}")]
    UnknownJoint(String),
    /// A sensor is assigned to the spine, and this body has no spine joints.
    #[error("this body has no spine joints for the upper-back sensor")]
    NoSpine,
    /// The calibration itself failed.
    #[error("{0}")]
    Calibration(#[from] stance_mocap::calibration::CalibrationError),
}

/// The editor's sensors: link, decoder, tracks, assignments, calibration, recording, replay.
pub struct SensorHub {
    settings: SensorSettings,
    decoder: Box<dyn Decoder + Send>,
    link: SensorLink,
    tracks: BTreeMap<SensorId, SensorTrack>,
    assignments: BTreeMap<SensorId, SensorAssignment>,
    calibration: Option<Calibration<String>>,
    recording: Option<Vec<u8>>,
    /// The recording reached [`MAX_RECORDING_BYTES`] and takes nothing more.
    recording_full: bool,
    replay: Option<Replay>,
    samples: u64,
    scratch: Vec<Sample>,
    /// New orientations since the posture was last driven.
    fresh: bool,
    /// The session's revision after the last drive (the body has not moved since when equal).
    driven_revision: Option<u64>,
    /// When the oldest bytes not yet shown in a posture arrived.
    oldest_unshown: Option<web_time::Instant>,
    latencies_ms: VecDeque<f64>,
}

impl std::fmt::Debug for SensorHub {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SensorHub")
            .field("settings", &self.settings)
            .field("link", &self.link)
            .field("sensors", &self.tracks.len())
            .field("calibrated", &self.calibration.is_some())
            .finish_non_exhaustive()
    }
}

impl Default for SensorHub {
    fn default() -> Self {
        Self::new(SensorSettings::default())
    }
}

/// What the UI asks of the sensors.
#[derive(Debug, Clone)]
pub enum SensorCommand {
    /// New device settings (kept in the host's storage).
    SetSettings(Box<SensorSettings>),
    /// Ask the page to open the device chosen in the settings.
    Connect,
    /// Close the device; the posture stays as it is.
    Disconnect,
    /// Calibrate the assigned sensors in the current posture; they then drive their joints.
    Calibrate,
    /// Stop driving the joints (the solver takes them back).
    ReleaseJoints,
    /// Turn every sensor about the vertical so that the body faces the front.
    ResetHeading,
    /// Play a recorded byte stream through the same decoder and calibration as a device.
    Replay {
        /// The recording's file name.
        name: String,
        /// The recorded bytes (serial bytes, or a HID report log).
        bytes: Vec<u8>,
    },
    /// Stop the replay where it is.
    StopReplay,
    /// Start keeping what the device sends, to save as a recording.
    StartRecording,
    /// Stop recording and offer the recording as a download.
    SaveRecording,
    /// Assign the sensors, in increasing id order, to a preset's segments.
    ApplyPreset(AssignmentPreset),
    /// What one sensor drives (nothing: `None`).
    Assign {
        /// The sensor, by the id the device gives it.
        sensor: SensorId,
        /// The joint or the spine it drives; `None` for nothing.
        assignment: Option<SensorAssignment>,
    },
    /// The device is open.
    Connected {
        /// The device's name as the browser gives it.
        device: String,
    },
    /// Bytes from the serial device.
    Bytes {
        /// The bytes as read, in order (a line may be split across messages).
        bytes: Vec<u8>,
        /// When the page received them.
        arrived: web_time::Instant,
    },
    /// One input report from the HID device.
    Report {
        /// The HID report ID (0 when the device uses none).
        report_id: u8,
        /// The report's bytes, without the report ID.
        data: Vec<u8>,
        /// When the page received it.
        arrived: web_time::Instant,
    },
    /// The device went away or failed; the posture stays as the last reading left it.
    Lost {
        /// What happened, for the user.
        reason: String,
    },
}

/// What came of a sensor command, for the user.
#[derive(Debug, Clone, PartialEq)]
pub enum SensorOutcome {
    /// Nothing to say.
    Quiet,
    /// A message for the user.
    Inform(String),
    /// A problem for the user.
    Warn(String),
}

impl SensorHub {
    /// Carries out `command`: the session's held joints follow calibration and release; the
    /// host opens, closes and downloads.
    pub fn apply(
        &mut self,
        command: SensorCommand,
        session: &mut PosingSession,
        hooks: &dyn HostHooks,
        now_secs: f64,
    ) -> SensorOutcome {
        match command {
            SensorCommand::SetSettings(settings) => {
                if *settings != self.settings {
                    settings.store(hooks);
                    self.set_settings(*settings);
                }
                SensorOutcome::Quiet
            }
            SensorCommand::Connect => self.connect(hooks),
            SensorCommand::Disconnect => {
                hooks.disconnect_sensor();
                self.disconnected();
                SensorOutcome::Inform(
                    "Sensors disconnected; the posture stays as it is.".to_owned(),
                )
            }
            SensorCommand::Calibrate => self.calibrate_session(session),
            SensorCommand::ReleaseJoints => self.release_joints(session),
            SensorCommand::ResetHeading => self.reset_heading_said(),
            SensorCommand::Replay { name, bytes } => self.replay(&name, bytes, now_secs),
            SensorCommand::StopReplay => {
                self.stop_replay();
                SensorOutcome::Quiet
            }
            SensorCommand::StartRecording => {
                self.start_recording();
                SensorOutcome::Quiet
            }
            SensorCommand::SaveRecording => self.save_recording(hooks),
            SensorCommand::ApplyPreset(preset) => {
                self.apply_preset(preset, session.skeleton());
                self.release_joints(session)
            }
            SensorCommand::Assign { sensor, assignment } => {
                self.assign(sensor, assignment);
                self.release_joints(session)
            }
            SensorCommand::Connected { device } => {
                let text = format!("Sensors: {device} connected.");
                self.connected(device);
                SensorOutcome::Inform(text)
            }
            SensorCommand::Bytes { bytes, arrived } => {
                self.receive_bytes(&bytes, now_secs, arrived);
                SensorOutcome::Quiet
            }
            SensorCommand::Report {
                report_id,
                data,
                arrived,
            } => {
                self.receive_report(report_id, &data, now_secs, arrived);
                SensorOutcome::Quiet
            }
            SensorCommand::Lost { reason } => {
                let text =
                    format!("Sensors: {reason} The posture stays as the last reading left it.");
                self.lost(reason);
                SensorOutcome::Warn(text)
            }
        }
    }

    /// Calibrates the sensors on `session`'s posture: the driven joints are held.
    fn calibrate_session(&mut self, session: &mut PosingSession) -> SensorOutcome {
        match self.calibrate(session.skeleton(), session.frames()) {
            Ok(()) => {
                let joints = self.driven_joints(session.skeleton());
                session.hold_joints(&joints);
                SensorOutcome::Inform(format!(
                    "Sensors calibrated: they now drive {} joints; the other joints keep the tasks.",
                    joints.len()
                ))
            }
            Err(error) => SensorOutcome::Warn(format!("Calibration failed: {error}.")),
        }
    }

    /// Resets the heading; says so when there was one to reset.
    fn reset_heading_said(&mut self) -> SensorOutcome {
        if self.reset_heading() {
            SensorOutcome::Inform("Heading reset: the body faces the front again.".to_owned())
        } else {
            SensorOutcome::Quiet
        }
    }

    /// Replays the recording `name` (its `bytes`) from `now_secs`.
    fn replay(&mut self, name: &str, bytes: Vec<u8>, now_secs: f64) -> SensorOutcome {
        if bytes.is_empty() {
            return SensorOutcome::Warn(format!("Sensors: {name} is empty."));
        }
        self.start_replay(name, bytes, now_secs);
        SensorOutcome::Inform(format!("Replaying {name}."))
    }

    /// The sensors stop driving their joints; the solver takes them back.
    fn release_joints(&mut self, session: &mut PosingSession) -> SensorOutcome {
        self.release();
        session.hold_joints(&[]);
        SensorOutcome::Quiet
    }

    /// Asks the page to open the device chosen in the settings.
    fn connect(&mut self, hooks: &dyn HostHooks) -> SensorOutcome {
        let request = match self.settings.connection() {
            Ok(request) => request,
            Err(error) => return SensorOutcome::Warn(format!("Sensors: {error}.")),
        };
        self.settings.store(hooks);
        self.begin_connect();
        match hooks.connect_sensor(&request) {
            Ok(()) => SensorOutcome::Quiet,
            Err(error) => {
                self.lost(error.clone());
                SensorOutcome::Warn(format!("Sensors: {error}"))
            }
        }
    }

    fn save_recording(&mut self, hooks: &dyn HostHooks) -> SensorOutcome {
        let Some(bytes) = self.stop_recording() else {
            return SensorOutcome::Quiet;
        };
        let name = self.recording_name();
        match hooks.download_bytes(&name, &bytes) {
            Ok(()) => SensorOutcome::Inform(format!("Saved {} bytes as {name}.", bytes.len())),
            Err(error) => SensorOutcome::Warn(format!("The recording could not be saved: {error}")),
        }
    }
}

impl SensorHub {
    /// A hub with `settings`: no device, no sensors, not calibrated.
    pub fn new(settings: SensorSettings) -> Self {
        let decoder = new_decoder(&settings.decoder_config());
        Self {
            settings,
            decoder,
            link: SensorLink::Idle,
            tracks: BTreeMap::new(),
            assignments: BTreeMap::new(),
            calibration: None,
            recording: None,
            recording_full: false,
            replay: None,
            samples: 0,
            scratch: Vec::new(),
            fresh: false,
            driven_revision: None,
            oldest_unshown: None,
            latencies_ms: VecDeque::new(),
        }
    }

    /// The device settings: which device, its link and decoder options.
    pub fn settings(&self) -> &SensorSettings {
        &self.settings
    }

    /// Changes the device settings: a new decoder, sensors and calibration forgotten.
    pub fn set_settings(&mut self, settings: SensorSettings) {
        if settings == self.settings {
            return;
        }
        let decoder_changed = settings.decoder_config() != self.settings.decoder_config();
        self.settings = settings;
        if decoder_changed {
            self.decoder = new_decoder(&self.settings.decoder_config());
            self.forget_sensors();
        }
    }

    /// A new device: readings, counts and calibration forgotten.
    fn forget_sensors(&mut self) {
        self.reset_stream();
        self.calibration = None;
        self.fresh = false;
        self.oldest_unshown = None;
    }

    /// A new stream from the same device (connect, replay): decoder, readings and counts start
    /// again; the calibration stays.
    fn reset_stream(&mut self) {
        self.decoder.reset();
        self.tracks.clear();
        self.samples = 0;
    }

    /// The state of the device link.
    pub fn link(&self) -> &SensorLink {
        &self.link
    }

    /// The running figures of each sensor heard since the device was connected or the replay
    /// started, by sensor id.
    pub fn tracks(&self) -> &BTreeMap<SensorId, SensorTrack> {
        &self.tracks
    }

    /// What each assigned sensor drives, by sensor id.
    pub fn assignments(&self) -> &BTreeMap<SensorId, SensorAssignment> {
        &self.assignments
    }

    /// Whether the sensors are calibrated (they then drive their joints).
    pub fn is_calibrated(&self) -> bool {
        self.calibration.is_some()
    }

    /// Whether what the device sends is being recorded.
    pub fn is_recording(&self) -> bool {
        self.recording.is_some()
    }

    /// The decoder's running counts: bytes received, frames, bad frames, skipped bytes.
    pub fn stats(&self) -> DecoderStats {
        self.decoder.stats()
    }

    /// Samples decoded since the device was connected or the replay started.
    pub fn sample_count(&self) -> u64 {
        self.samples
    }

    /// The page is opening a device: counts start again.
    pub fn begin_connect(&mut self) {
        self.replay = None;
        self.reset_stream();
        self.link = SensorLink::Connecting;
    }

    /// The device `device` (its name as the browser gives it) is open.
    pub fn connected(&mut self, device: String) {
        self.link = SensorLink::Connected { device };
    }

    /// The device went away or failed (the posture stays as it is).
    pub fn lost(&mut self, reason: String) {
        self.replay = None;
        self.link = SensorLink::Lost { reason };
    }

    /// The user closed the link.
    pub fn disconnected(&mut self) {
        self.replay = None;
        self.link = SensorLink::Idle;
    }

    /// Bytes from a serial device (or a replay).
    pub fn receive_bytes(&mut self, bytes: &[u8], now_secs: f64, arrived: web_time::Instant) {
        if bytes.is_empty() {
            return;
        }
        self.record(bytes);
        let mut samples = std::mem::take(&mut self.scratch);
        samples.clear();
        self.decoder.push(bytes, &mut samples);
        self.ingest(&samples, now_secs, arrived);
        self.scratch = samples;
    }

    /// One input report from a HID device.
    pub fn receive_report(
        &mut self,
        report_id: u8,
        data: &[u8],
        now_secs: f64,
        arrived: web_time::Instant,
    ) {
        if self.recording.is_some()
            && let Some(record) = encode_report_record(report_id, data)
        {
            self.record(&record);
        }
        let mut samples = std::mem::take(&mut self.scratch);
        samples.clear();
        self.decoder.push_report(report_id, data, &mut samples);
        self.ingest(&samples, now_secs, arrived);
        self.scratch = samples;
    }

    fn record(&mut self, bytes: &[u8]) {
        if let Some(recording) = &mut self.recording {
            if recording.len() + bytes.len() > MAX_RECORDING_BYTES {
                self.recording_full = true;
                return;
            }
            recording.extend_from_slice(bytes);
        }
    }

    /// The recording is full (see [`MAX_RECORDING_BYTES`]): stop and save it.
    pub fn is_recording_full(&self) -> bool {
        self.recording.is_some() && self.recording_full
    }

    fn ingest(&mut self, samples: &[Sample], now_secs: f64, arrived: web_time::Instant) {
        for sample in samples {
            let track = self.tracks.entry(sample.sensor).or_default();
            track.last = *sample;
            track.samples += 1;
            track.arrivals_secs.push_back(now_secs);
            while track
                .arrivals_secs
                .front()
                .is_some_and(|&first| now_secs - first > RATE_WINDOW_SECS)
            {
                track.arrivals_secs.pop_front();
            }
            self.samples += 1;
        }
        if samples.iter().any(|sample| sample.orientation.is_some()) {
            self.fresh = true;
            // Latency counts readings that will move the body (not those before calibration).
            if self.calibration.is_some() {
                self.oldest_unshown.get_or_insert(arrived);
            }
        }
    }

    /// Starts recording what the device sends (serial bytes, or HID reports as a report log
    /// that `stance decode` and the replay read).
    pub fn start_recording(&mut self) {
        self.recording = Some(Vec::new());
        self.recording_full = false;
    }

    /// Stops recording and gives the bytes (a file named by [`SensorHub::recording_name`]).
    pub fn stop_recording(&mut self) -> Option<Vec<u8>> {
        self.recording.take()
    }

    /// A file name for a recording of this device.
    pub fn recording_name(&self) -> String {
        let stem = match self.settings.device {
            DeviceKind::FlockOfBirds => "fob",
            DeviceKind::Fastrak => "fastrak",
            DeviceKind::Liberty => "liberty",
            DeviceKind::Xsens => "xsens",
            DeviceKind::AsciiImu => "imu-lines",
            DeviceKind::SlimeVr => "slimevr-hid",
            DeviceKind::DualSense => "dualsense-hid",
            DeviceKind::DualShock4 => "ds4-hid",
        };
        format!("stance-sensors-{stem}.bin")
    }

    /// Plays `bytes` back through the decoder at the replay rate, as if the device sent them.
    pub fn start_replay(&mut self, name: &str, bytes: Vec<u8>, now_secs: f64) {
        self.reset_stream();
        self.link = SensorLink::Replaying {
            name: name.to_owned(),
        };
        self.replay = Some(Replay {
            bytes,
            offset: 0,
            started_secs: now_secs,
        });
    }

    /// Replay progress: bytes played and total.
    pub fn replay_progress(&self) -> Option<(usize, usize)> {
        self.replay
            .as_ref()
            .map(|replay| (replay.offset, replay.bytes.len()))
    }

    /// Advances a replay to `now_secs`. Returns a message when the replay ended.
    pub fn tick(&mut self, now_secs: f64) -> Option<String> {
        let mut replay = self.replay.take()?;
        let rate = if self.settings.replay_rate_hz.is_finite() && self.settings.replay_rate_hz > 0.0
        {
            self.settings.replay_rate_hz
        } else {
            DEFAULT_REPLAY_RATE_HZ
        };
        // Samples per sensor due by now; the busiest sensor sets the pace.
        let wanted = ((now_secs - replay.started_secs).max(0.0) * rate).ceil() as u64;
        let arrived = web_time::Instant::now();
        let tick_end = replay.offset.saturating_add(MAX_REPLAY_BYTES_PER_TICK);
        while self.busiest_track_samples() < wanted
            && replay.offset < replay.bytes.len()
            && replay.offset < tick_end
        {
            let end = (replay.offset + REPLAY_CHUNK_BYTES).min(replay.bytes.len());
            let chunk = replay.bytes.get(replay.offset..end).unwrap_or_default();
            replay.offset = end;
            self.receive_bytes(chunk, now_secs, arrived);
        }
        if replay.offset >= replay.bytes.len() {
            let mut tail = Vec::new();
            self.decoder.finish(&mut tail);
            self.ingest(&tail, now_secs, arrived);
            let name = match std::mem::replace(&mut self.link, SensorLink::Idle) {
                SensorLink::Replaying { name } => name,
                _ => "the recording".to_owned(),
            };
            let stats = self.decoder.stats();
            return Some(format!(
                "Replay of {name} finished: {} samples, {} bad frames, {} bytes skipped.",
                stats.samples, stats.bad_frames, stats.skipped_bytes
            ));
        }
        self.replay = Some(replay);
        None
    }

    fn busiest_track_samples(&self) -> u64 {
        self.tracks
            .values()
            .map(|track| track.samples)
            .max()
            .unwrap_or(0)
    }

    /// Stops a replay where it is.
    pub fn stop_replay(&mut self) {
        if self.replay.take().is_some() {
            self.link = SensorLink::Idle;
        }
    }

    /// Assigns a sensor to a segment (`None` frees it). A segment driven by another sensor is
    /// taken from it. The calibration is dropped: calibrate again.
    pub fn assign(&mut self, sensor: SensorId, assignment: Option<SensorAssignment>) {
        match assignment {
            Some(assignment) => {
                self.assignments.retain(|_, other| *other != assignment);
                self.assignments.insert(sensor, assignment);
            }
            None => {
                self.assignments.remove(&sensor);
            }
        }
        self.calibration = None;
    }

    /// Assigns the sensors seen so far (or ids 1, 2, ... when none was seen) in increasing id
    /// order to the preset's segments; segments this body lacks are skipped.
    pub fn apply_preset(&mut self, preset: AssignmentPreset, skeleton: &Skeleton) {
        let segments: Vec<SensorAssignment> = preset
            .segments()
            .into_iter()
            .filter(|segment| match segment {
                SensorAssignment::Joint(name) => skeleton.joint_index(name).is_some(),
                SensorAssignment::Spine => !spine_chain(skeleton).is_empty(),
            })
            .collect();
        let mut sensors: Vec<SensorId> = self.tracks.keys().copied().collect();
        if sensors.is_empty() {
            sensors = (1..=segments.len())
                .filter_map(|id| u16::try_from(id).ok().map(SensorId))
                .collect();
        }
        self.assignments.clear();
        for (sensor, segment) in sensors.into_iter().zip(segments) {
            self.assignments.insert(sensor, segment);
        }
        self.calibration = None;
    }

    /// The latest orientation of each sensor.
    pub fn latest_orientations(&self) -> BTreeMap<SensorId, DQuat> {
        self.tracks
            .iter()
            .filter_map(|(sensor, track)| track.last.orientation.map(|q| (*sensor, q)))
            .collect()
    }

    /// Calibrates in the current posture (`frames`): the person holds the posture the avatar
    /// shows, and each sensor's sensor-to-joint rotation is computed (Molet et al.).
    pub fn calibrate(&mut self, skeleton: &Skeleton, frames: &Frames) -> Result<(), SensorError> {
        if self.assignments.is_empty() {
            return Err(SensorError::NothingAssigned);
        }
        let latest = self.latest_orientations();
        let mut setup =
            CalibrationSetup::new(self.settings.frame.world_from_device(), parents(skeleton));
        for (sensor, assignment) in &self.assignments {
            if !latest.contains_key(sensor) {
                return Err(SensorError::NoReading(sensor.0));
            }
            let target = match assignment {
                SensorAssignment::Joint(name) => {
                    if skeleton.joint_index(name).is_none() {
                        return Err(SensorError::UnknownJoint(name.clone()));
                    }
                    SensorTarget::Joint(name.clone())
                }
                SensorAssignment::Spine => {
                    let chain = spine_chain(skeleton);
                    if chain.is_empty() {
                        return Err(SensorError::NoSpine);
                    }
                    SensorTarget::Chain(chain)
                }
            };
            setup = setup.bind(*sensor, target);
        }
        let calibration =
            Calibration::calibrate(&setup, &world_rotations(skeleton, frames), &latest)?;
        self.calibration = Some(calibration);
        self.fresh = true;
        Ok(())
    }

    /// Turns every sensor's heading so that the body faces where it faced at calibration
    /// (pitch and roll kept).
    pub fn reset_heading(&mut self) -> bool {
        let latest = self.latest_orientations();
        match &mut self.calibration {
            Some(calibration) => {
                calibration.reset_heading(&latest);
                self.fresh = true;
                true
            }
            None => false,
        }
    }

    /// Forgets the calibration: the sensors stop driving the body.
    pub fn release(&mut self) {
        self.calibration = None;
        self.fresh = false;
    }

    /// The joints the calibrated sensors drive now, with their local rotations, when new
    /// readings arrived since the last call or when `again` (the rest of the body moved, so
    /// the local rotations that keep the measured world rotations changed).
    pub fn take_driven_rotations(
        &mut self,
        skeleton: &Skeleton,
        frames: &Frames,
        again: bool,
    ) -> Option<Vec<(usize, DQuat)>> {
        if !self.fresh && !again {
            return None;
        }
        let calibration = self.calibration.as_ref()?;
        self.fresh = false;
        let locals = calibration.local_rotations(
            &self.latest_orientations(),
            &world_rotations(skeleton, frames),
        );
        Some(
            locals
                .into_iter()
                .filter_map(|(name, rotation)| {
                    skeleton.joint_index(&name).map(|joint| (joint, rotation))
                })
                .collect(),
        )
    }

    /// One frame of sensors on a posing session: the calibrated sensors hold their joints
    /// and set their rotations. The solver moves the rest of the body (balance...), so the
    /// driven joints are set again every frame to keep their world rotations the measured
    /// ones; unchanged rotations do not wake the solver. Returns whether readings were used.
    pub fn drive(&mut self, session: &mut PosingSession) -> bool {
        let held = self.driven_joints(session.skeleton());
        if held != session.held_joints() {
            session.hold_joints(&held);
        }
        let fresh = self.fresh;
        // Nothing to redo while neither the readings nor the body changed.
        let moved = self.driven_revision != Some(session.revision());
        let rotations = self.take_driven_rotations(
            session.skeleton(),
            session.frames(),
            !held.is_empty() && moved,
        );
        let used = rotations.is_some();
        if let Some(rotations) = rotations {
            session.drive_joints(&rotations);
        }
        self.driven_revision = Some(session.revision());
        fresh && used
    }

    /// Joints held by the calibrated sensors (whether or not a reading arrived yet).
    pub fn driven_joints(&self, skeleton: &Skeleton) -> Vec<usize> {
        if self.calibration.is_none() {
            return Vec::new();
        }
        let mut joints = Vec::new();
        for assignment in self.assignments.values() {
            match assignment {
                SensorAssignment::Joint(name) => joints.extend(skeleton.joint_index(name)),
                SensorAssignment::Spine => joints.extend(
                    spine_chain(skeleton)
                        .iter()
                        .filter_map(|(name, _)| skeleton.joint_index(name)),
                ),
            }
        }
        joints.sort_unstable();
        joints.dedup();
        joints
    }

    /// The posture now shows every reading that arrived: the latency of the oldest one.
    pub fn shown(&mut self) {
        if let Some(arrived) = self.oldest_unshown.take() {
            self.latencies_ms
                .push_back(arrived.elapsed().as_secs_f64() * 1000.0);
            while self.latencies_ms.len() > LATENCY_WINDOW {
                self.latencies_ms.pop_front();
            }
        }
    }

    /// Median and largest latency from bytes to posture over the last readings (ms).
    pub fn latency_ms(&self) -> Option<(f64, f64)> {
        if self.latencies_ms.is_empty() {
            return None;
        }
        let mut sorted: Vec<f64> = self.latencies_ms.iter().copied().collect();
        sorted.sort_by(f64::total_cmp);
        let median = sorted.get(sorted.len() / 2).copied().unwrap_or_default();
        let max = sorted.last().copied().unwrap_or_default();
        Some((median, max))
    }

    /// The hub's observable state (for the page's test hook and scripts).
    pub fn state_json(&self) -> Value {
        let stats = self.decoder.stats();
        let sensors: Vec<Value> = self
            .tracks
            .iter()
            .map(|(sensor, track)| {
                json!({
                    "id": sensor.0,
                    "samples": track.samples,
                    "rate_hz": track.rate_hz(),
                    "orientation": track.last.orientation.map(|q| [q.x, q.y, q.z, q.w]),
                    "position_m": track.last.position_m.map(|p| [p.x, p.y, p.z]),
                    "assignment": self.assignments.get(sensor).map(assignment_label),
                })
            })
            .collect();
        let (latency_median_ms, latency_max_ms) = self.latency_ms().unzip();
        json!({
            "link": self.link.word(),
            "device": self.settings.device.label(),
            "reason": match &self.link { SensorLink::Lost { reason } => Some(reason.clone()), _ => None },
            "samples": self.samples,
            "bytes": stats.bytes_received,
            "bad_frames": stats.bad_frames,
            "skipped_bytes": stats.skipped_bytes,
            "sensors": sensors,
            "assigned": self.assignments.len(),
            "calibrated": self.calibration.is_some(),
            "recording": self.recording.as_ref().map(Vec::len),
            "replay": self.replay_progress().map(|(done, total)| json!([done, total])),
            "latency_median_ms": latency_median_ms,
            "latency_max_ms": latency_max_ms,
        })
    }
}

/// Child -> parent joint names.
fn parents(skeleton: &Skeleton) -> BTreeMap<String, String> {
    let joints = skeleton.joints();
    joints
        .iter()
        .filter_map(|joint| {
            let parent = joints.get(joint.parent?)?;
            Some((joint.name.clone(), parent.name.clone()))
        })
        .collect()
}

/// World rotation of every joint.
fn world_rotations(skeleton: &Skeleton, frames: &Frames) -> BTreeMap<String, DQuat> {
    skeleton
        .joints()
        .iter()
        .enumerate()
        .map(|(index, joint)| (joint.name.clone(), frames.rotation(index)))
        .collect()
}
