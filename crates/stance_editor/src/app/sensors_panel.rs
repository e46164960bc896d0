//! The sensors window: device, connection, per-sensor figures, assignment to segments,
//! calibration, heading reset, recording and replay, as commands to the model's sensors.

use crate::model::FileCommand;
use crate::model::Outbox;
use egui::RichText;
use stance_mocap::SensorId;
use stance_mocap::ascii::ComponentOrder;
use stance_mocap::fob::FobMode;

use super::ButtonRects;
use crate::model::{Command, EditorModel};
use crate::sensors::{
    AssignmentPreset, DeviceFrame, DeviceKind, SensorAssignment, SensorCommand, SensorLink,
    SensorSettings, assignment_label, preset_button_name,
};

/// Baud rates offered first (any other can be typed).
const BAUD_RATES: [u32; 6] = [9_600, 19_200, 38_400, 57_600, 115_200, 230_400];

/// The sensors window over the model.
pub(super) struct SensorsWindow<'a> {
    pub model: &'a EditorModel,
    pub outbox: &'a mut Outbox,
    /// Where the viewport is (the window opens over it).
    pub viewport_rect: egui::Rect,
    pub buttons: &'a mut ButtonRects,
}

impl SensorsWindow<'_> {
    /// The window while `open`.
    pub(super) fn show(&mut self, ctx: &egui::Context, open: &mut bool) {
        if !*open {
            return;
        }
        // Sized to its contents (which grow as sensors appear), scrolling past the viewport.
        egui::Window::new("Sensors")
            .open(open)
            .default_pos(self.viewport_rect.left_top() + egui::vec2(12.0, 40.0))
            .resizable(false)
            .vscroll(true)
            .max_height((self.viewport_rect.height() - 60.0).max(200.0))
            .show(ctx, |ui| {
                ui.set_width(360.0);
                self.contents(ui);
            });
    }

    fn command(&mut self, command: SensorCommand) {
        self.outbox.send(Command::Sensors(command));
    }

    fn contents(&mut self, ui: &mut egui::Ui) {
        let mut settings = self.model.sensors().settings().clone();
        let busy = self.model.sensors().link().is_live()
            || self.model.sensors().replay_progress().is_some();
        ui.add_enabled_ui(!busy, |ui| device_settings(ui, &mut settings));
        if settings != *self.model.sensors().settings() {
            self.command(SensorCommand::SetSettings(Box::new(settings)));
        }

        self.connection_row(ui);
        self.link_line(ui);

        self.calibration_section(ui);
        ui.separator();
        ui.label(RichText::new("Sensors and segments").strong());
        ui.horizontal_wrapped(|ui| {
            for preset in AssignmentPreset::ALL {
                let button = ui.small_button(preset.label());
                self.buttons.push((preset_button_name(preset), button.rect));
                if button.clicked() {
                    self.command(SensorCommand::ApplyPreset(preset));
                }
            }
        });
        self.sensor_table(ui);
    }

    /// Connect or disconnect, replay or stop, record or save.
    fn connection_row(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            if self.model.sensors().link().is_live() {
                let button = ui.button("Disconnect");
                self.buttons.push(("sensors_disconnect", button.rect));
                if button.clicked() {
                    self.command(SensorCommand::Disconnect);
                }
            } else {
                let button = ui
                    .add_enabled(
                        self.model.sensors().replay_progress().is_none(),
                        egui::Button::new("Connect…"),
                    )
                    .on_hover_text("The browser asks which serial port or HID device to use");
                self.buttons.push(("sensors_connect", button.rect));
                if button.clicked() {
                    self.command(SensorCommand::Connect);
                }
            }
            if self.model.sensors().replay_progress().is_some() {
                if ui.button("Stop replay").clicked() {
                    self.command(SensorCommand::StopReplay);
                }
            } else {
                let button = ui
                    .add_enabled(
                        !self.model.sensors().link().is_live(),
                        egui::Button::new("Replay file…"),
                    )
                    .on_hover_text("Play a recording (or `stance simulate-sensors` output)");
                self.buttons.push(("sensors_replay", button.rect));
                if button.clicked() {
                    self.outbox.send(Command::File(FileCommand::PickRecording));
                }
            }
            let recording = self.model.sensors().is_recording();
            let button = ui.button(if recording { "Stop and save" } else { "Record" });
            self.buttons.push(("sensors_record", button.rect));
            if button.clicked() {
                self.command(if recording {
                    SensorCommand::SaveRecording
                } else {
                    SensorCommand::StartRecording
                });
            }
        });
    }

    /// Calibrate, reset the heading, release the joints.
    fn calibration_section(&mut self, ui: &mut egui::Ui) {
        ui.separator();
        ui.label(
            "Calibrate while the person holds the posture the avatar shows (rest pose or \
             T-pose). Then each sensor drives its segment; the other joints keep the tasks.",
        );
        ui.horizontal(|ui| {
            let button = ui.add_enabled(
                !self.model.sensors().assignments().is_empty(),
                egui::Button::new("Calibrate"),
            );
            self.buttons.push(("sensors_calibrate", button.rect));

            if button.clicked() {
                self.command(SensorCommand::Calibrate);
            }
            let calibrated = self.model.sensors().is_calibrated();
            let button = ui
                .add_enabled(calibrated, egui::Button::new("Reset heading"))
                .on_hover_text("Face the front, then press: turns every sensor about the vertical");
            self.buttons.push(("sensors_reset_heading", button.rect));
            if button.clicked() {
                self.command(SensorCommand::ResetHeading);
            }
            if ui
                .add_enabled(calibrated, egui::Button::new("Release joints"))
                .on_hover_text("Stop driving the joints (the solver takes them back)")
                .clicked()
            {
                self.command(SensorCommand::ReleaseJoints);
            }
        });
        if self.model.sensors().is_calibrated() {
            ui.label(format!(
                "Driving {} joints.",
                self.model
                    .sensors()
                    .driven_joints(self.model.session().skeleton())
                    .len()
            ));
        }
    }

    fn link_line(&self, ui: &mut egui::Ui) {
        let stats = self.model.sensors().stats();
        let (text, colour) = match self.model.sensors().link() {
            SensorLink::Idle => ("Not connected".to_owned(), ui.visuals().weak_text_color()),
            SensorLink::Connecting => (
                "Waiting for the device…".to_owned(),
                ui.visuals().text_color(),
            ),
            SensorLink::Connected { device } => (
                format!("Connected: {device}"),
                egui::Color32::from_rgb(60, 160, 80),
            ),
            SensorLink::Replaying { name } => {
                let (done, total) = self.model.sensors().replay_progress().unwrap_or_default();
                (
                    format!(
                        "Replaying {name}: {}%",
                        (done * 100).checked_div(total).unwrap_or(100)
                    ),
                    ui.visuals().text_color(),
                )
            }
            SensorLink::Lost { reason } => (format!("Lost: {reason}"), ui.visuals().error_fg_color),
        };
        ui.colored_label(colour, text);
        ui.label(format!(
            "{} samples, {} bad frames, {} bytes skipped",
            self.model.sensors().sample_count(),
            stats.bad_frames,
            stats.skipped_bytes
        ));
        if let Some(bytes) = self
            .model
            .sensors()
            .is_recording()
            .then(|| self.model.sensors().stats().bytes_received)
        {
            ui.label(format!("Recording ({} KiB received)", bytes / 1024));
        }
        if self.model.sensors().is_recording_full() {
            ui.colored_label(
                ui.visuals().warn_fg_color,
                format!(
                    "The recording is full ({} MiB): stop and save it.",
                    crate::sensors::MAX_RECORDING_BYTES / (1024 * 1024)
                ),
            );
        }
        if let Some((median, max)) = self.model.sensors().latency_ms() {
            ui.label(format!(
                "Bytes to posture: {median:.1} ms median, {max:.1} ms max"
            ));
        }
    }

    fn sensor_table(&mut self, ui: &mut egui::Ui) {
        let tracks: Vec<(SensorId, f64, Option<[f64; 3]>)> = self
            .model
            .sensors()
            .tracks()
            .iter()
            .map(|(sensor, track)| {
                let angles = track.last.orientation.map(|q| {
                    let (yaw, pitch, roll) = q.to_euler(glam::EulerRot::ZYX);
                    [yaw.to_degrees(), pitch.to_degrees(), roll.to_degrees()]
                });
                (*sensor, track.rate_hz(), angles)
            })
            .collect();
        if tracks.is_empty() {
            ui.label("No sensor has sent anything yet.");
            return;
        }
        let mut segments: Vec<SensorAssignment> = vec![SensorAssignment::Spine];
        segments.extend(
            self.model
                .session()
                .skeleton()
                .joints()
                .iter()
                .filter(|joint| joint.has_rotation() && joint.parent.is_some())
                .map(|joint| SensorAssignment::Joint(joint.name.clone())),
        );
        let mut change: Option<(SensorId, Option<SensorAssignment>)> = None;
        egui::Grid::new("sensor_grid")
            .striped(true)
            .num_columns(4)
            .show(ui, |ui| {
                ui.label("Sensor");
                ui.label("Rate");
                ui.label("Yaw, pitch, roll");
                ui.label("Drives");
                ui.end_row();
                for (sensor, rate, angles) in tracks {
                    ui.label(format!("{}", sensor.0));
                    ui.label(format!("{rate:.0} Hz"));
                    match angles {
                        Some([yaw, pitch, roll]) => {
                            ui.label(format!("{yaw:.0}°, {pitch:.0}°, {roll:.0}°"))
                        }
                        None => ui.label("no orientation"),
                    };
                    let current = self.model.sensors().assignments().get(&sensor).cloned();
                    let text = current
                        .as_ref()
                        .map_or_else(|| "nothing".to_owned(), assignment_label);
                    egui::ComboBox::from_id_salt(("sensor_segment", sensor.0))
                        .selected_text(text)
                        .height(300.0)
                        .show_ui(ui, |ui| {
                            if ui.selectable_label(current.is_none(), "nothing").clicked() {
                                change = Some((sensor, None));
                            }
                            for segment in &segments {
                                let label = assignment_label(segment);
                                if ui
                                    .selectable_label(current.as_ref() == Some(segment), label)
                                    .clicked()
                                {
                                    change = Some((sensor, Some(segment.clone())));
                                }
                            }
                        });
                    ui.end_row();
                }
            });
        if let Some((sensor, assignment)) = change {
            self.command(SensorCommand::Assign { sensor, assignment });
        }
    }
}

/// The device, its serial settings and its reference frame.
fn device_settings(ui: &mut egui::Ui, settings: &mut SensorSettings) {
    egui::ComboBox::from_label("Device")
        .selected_text(settings.device.label())
        .show_ui(ui, |ui| {
            for device in DeviceKind::ALL {
                if ui
                    .selectable_label(settings.device == device, device.label())
                    .clicked()
                    && settings.device != device
                {
                    settings.device = device;
                    settings.frame = device.usual_frame();
                    if let Some(baud) = device.protocol().default_baud_rate() {
                        settings.baud_rate = baud;
                    }
                }
            }
        });
    if !settings.device.protocol().is_hid() {
        ui.horizontal(|ui| {
            egui::ComboBox::from_id_salt("baud_rate")
                .selected_text(format!("{} baud", settings.baud_rate))
                .show_ui(ui, |ui| {
                    for baud in BAUD_RATES {
                        ui.selectable_value(&mut settings.baud_rate, baud, format!("{baud}"));
                    }
                });
            ui.add(
                egui::DragValue::new(&mut settings.baud_rate)
                    .range(300..=4_000_000)
                    .suffix(" baud"),
            );
        });
    }
    protocol_settings(ui, settings);
    egui::ComboBox::from_label("Frame")
        .selected_text(settings.frame.label())
        .show_ui(ui, |ui| {
            for frame in DeviceFrame::ALL {
                ui.selectable_value(&mut settings.frame, frame, frame.label());
            }
        });
    ui.add(
        egui::DragValue::new(&mut settings.replay_rate_hz)
            .range(1.0..=1000.0)
            .prefix("replay at ")
            .suffix(" Hz"),
    );
}

/// The settings of the device's own protocol (Flock of Birds records, IMU line order).
fn protocol_settings(ui: &mut egui::Ui, settings: &mut SensorSettings) {
    match settings.device {
        DeviceKind::FlockOfBirds => {
            egui::ComboBox::from_label("Record")
                .selected_text(fob_mode_label(settings.fob_mode))
                .show_ui(ui, |ui| {
                    for mode in [
                        FobMode::PositionQuaternion,
                        FobMode::Quaternion,
                        FobMode::PositionAngles,
                        FobMode::Angles,
                        FobMode::PositionMatrix,
                        FobMode::Matrix,
                        FobMode::Position,
                    ] {
                        ui.selectable_value(&mut settings.fob_mode, mode, fob_mode_label(mode));
                    }
                });
            ui.horizontal(|ui| {
                ui.checkbox(&mut settings.fob_group, "Group mode");
                ui.add(
                    egui::DragValue::new(&mut settings.fob_birds)
                        .range(1..=30)
                        .suffix(" birds"),
                );
            });
        }
        DeviceKind::AsciiImu => {
            ui.horizontal(|ui| {
                ui.label("Components");
                ui.selectable_value(&mut settings.ascii_order, ComponentOrder::Wxyz, "w x y z");
                ui.selectable_value(&mut settings.ascii_order, ComponentOrder::Xyzw, "x y z w");
            });
        }
        _ => {}
    }
}

fn fob_mode_label(mode: FobMode) -> &'static str {
    match mode {
        FobMode::Position => "position",
        FobMode::Angles => "angles",
        FobMode::Matrix => "matrix",
        FobMode::PositionAngles => "position + angles",
        FobMode::PositionMatrix => "position + matrix",
        FobMode::Quaternion => "quaternion",
        FobMode::PositionQuaternion => "position + quaternion",
    }
}
