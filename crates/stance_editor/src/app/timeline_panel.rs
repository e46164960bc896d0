//! The timeline panel at the bottom: play and pause, the frame slider, frame / time / fps,
//! loop and speed, the key track (click a diamond to go there, drag it to move it, its menu
//! deletes or copies it), a row per task with an active interval (its ends drag) and the
//! clip's foot contacts. Everything it does is a `MotionCommand`.

use crate::model::FileCommand;
use crate::model::Outbox;
use egui::{Color32, Pos2, Rect, Sense, Stroke, pos2, vec2};
use stance_document::TaskInterval;

use stance_motion::RestMatch;

use super::ButtonRects;
use crate::model::{
    AnimationFormat, Command, EditorModel, IntervalEdge, MotionCommand, SPEED_RANGE,
};

const KEY_COLOR: Color32 = Color32::from_rgb(250, 200, 80);
const PLAYHEAD_COLOR: Color32 = Color32::from_rgb(240, 90, 90);
const INTERVAL_COLOR: Color32 = Color32::from_rgb(110, 170, 240);
const CONTACT_COLOR: Color32 = Color32::from_rgb(120, 200, 130);
/// Width of the row labels (points).
const LABEL_WIDTH: f32 = 150.0;
/// Height of a track row (points).
const ROW_HEIGHT: f32 = 16.0;

/// The timeline panel over the model.
pub(super) struct TimelinePanel<'a> {
    pub model: &'a EditorModel,
    pub outbox: &'a mut Outbox,
    pub buttons: &'a mut ButtonRects,
}

/// Where frames and seconds are on a track.
#[derive(Debug, Clone, Copy)]
struct Track {
    rect: Rect,
    frames: usize,
    frame_time: f64,
}

impl Track {
    fn x_of_frame(&self, frame: f64) -> f32 {
        let last = (self.frames.max(2) - 1) as f64;
        self.rect.left() + (frame / last).clamp(0.0, 1.0) as f32 * self.rect.width()
    }

    fn x_of_secs(&self, secs: f64) -> f32 {
        self.x_of_frame(secs / self.frame_time)
    }

    fn frame_at(&self, x: f32) -> usize {
        let last = (self.frames.max(2) - 1) as f32;
        let fraction = ((x - self.rect.left()) / self.rect.width().max(1.0)).clamp(0.0, 1.0);
        (fraction * last).round() as usize
    }

    fn secs_at(&self, x: f32) -> f64 {
        let last = (self.frames.max(2) - 1) as f64;
        let fraction = f64::from((x - self.rect.left()) / self.rect.width().max(1.0));
        fraction.clamp(0.0, 1.0) * last * self.frame_time
    }
}

impl TimelinePanel<'_> {
    /// The panel's height (points) for what it shows: the transport, the clip's settings,
    /// the key track, a row per task and the contacts' row (at most 12 rows; the rest
    /// scrolls).
    pub(super) fn height(model: &EditorModel) -> f32 {
        let clip = model.timeline().has_clip();
        let rows = 1
            + model.session().tasks().len()
            + usize::from(!model.timeline().contacts().is_empty());
        let lines = 1 + usize::from(clip);
        lines as f32 * 26.0 + rows.min(12) as f32 * (ROW_HEIGHT + 4.0) + 12.0
    }

    fn command(&mut self, command: MotionCommand) {
        self.outbox.send(Command::Motion(command));
    }

    /// The panel's contents.
    pub(super) fn show(&mut self, ui: &mut egui::Ui) {
        self.transport(ui);
        if self.model.timeline().has_clip() {
            self.clip_settings(ui);
        }
        let track = self.key_track(ui);
        self.interval_rows(ui, track);
        self.contact_row(ui, track);
    }

    /// Play, step, the frame slider, frame / time / fps, loop, speed, set key.
    fn transport(&mut self, ui: &mut egui::Ui) {
        let timeline = self.model.timeline();
        let (playing, looping, speed) = (
            timeline.is_playing(),
            timeline.is_looping(),
            timeline.speed(),
        );
        let mut frame = timeline.frame();
        let (frames, frame_time) = (self.model.frame_count(), self.model.frame_time());
        ui.horizontal(|ui| {
            ui.spacing_mut().slider_width = 280.0;
            let play = ui.button(if playing { "Pause" } else { "Play" });
            self.buttons.push(("timeline_play", play.rect));
            if play.clicked() {
                self.command(MotionCommand::TogglePlay);
            }
            if ui.button("<").on_hover_text("previous frame").clicked() {
                self.command(MotionCommand::StepFrames(-1));
            }
            if ui.button(">").on_hover_text("next frame").clicked() {
                self.command(MotionCommand::StepFrames(1));
            }
            let slider =
                egui::Slider::new(&mut frame, 0..=frames.saturating_sub(1)).show_value(false);
            if ui.add(slider).changed() {
                self.command(MotionCommand::Seek(frame));
            }
            ui.label(format!(
                "frame {frame} / {}  ·  {:.2} s  ·  {:.1} fps",
                frames.saturating_sub(1),
                frame as f64 * frame_time,
                1.0 / frame_time
            ));
            let mut looped = looping;
            if ui.checkbox(&mut looped, "Loop").changed() {
                self.command(MotionCommand::SetLooping(looped));
            }
            let mut new_speed = speed;
            let drag = egui::DragValue::new(&mut new_speed)
                .range(SPEED_RANGE.0..=SPEED_RANGE.1)
                .speed(0.02)
                .suffix("x");
            if ui.add(drag).on_hover_text("playback speed").changed() {
                self.command(MotionCommand::SetSpeed(new_speed));
            }
            let key = ui.button("Set key (K)");
            self.buttons.push(("timeline_set_key", key.rect));
            if key.clicked() {
                self.command(MotionCommand::SetKey);
            }
            if let Some(name) = self.model.timeline().clip_name() {
                ui.label(format!("clip: {name}"));
            }
        });
    }

    /// How the clip is put on the body: the rest match and the foot contacts' thresholds
    /// (a change retargets the clip).
    fn clip_settings(&mut self, ui: &mut egui::Ui) {
        let options = self.model.timeline().retarget_options().clone();
        let mut changed = options.clone();
        ui.horizontal(|ui| {
            ui.label("Rest match:");
            for (value, label, hint) in [
                (
                    RestMatch::Directions,
                    "bone directions",
                    "T-pose and A-pose bodies match",
                ),
                (
                    RestMatch::Same,
                    "same rest",
                    "both rest poses are the same pose",
                ),
                (
                    RestMatch::FirstFrame,
                    "first frame",
                    "the clip's first frame is the rest",
                ),
            ] {
                ui.radio_value(&mut changed.rest_match, value, label)
                    .on_hover_text(hint);
            }
            let mut lift = options.arm_lift();
            let arms = egui::DragValue::new(&mut lift)
                .range(-60.0..=60.0)
                .speed(0.5)
                .suffix("°");
            ui.label("arms");
            if ui
                .add(arms)
                .on_hover_text("raise (+) or lower (-) both arms' rest match")
                .changed()
            {
                changed = std::mem::take(&mut changed).with_arm_lift(lift);
            }
            ui.separator();
            let mut held = changed.contacts.is_some();
            ui.checkbox(&mut held, "Contacts").on_hover_text(
                "detected on the clip (heel and ball of each foot), held by level-1 tasks; \
                     height and speed are for a 0.9 m leg at walking pace and scale with the clip",
            );
            let mut settings = changed.contacts.unwrap_or_default();
            ui.add_enabled_ui(held, |ui| {
                ui.label("height");
                ui.add(
                    egui::DragValue::new(&mut settings.height)
                        .range(0.0..=0.5)
                        .speed(0.002)
                        .suffix(" m"),
                );
                ui.label("speed");
                ui.add(
                    egui::DragValue::new(&mut settings.speed)
                        .range(0.0..=5.0)
                        .speed(0.01)
                        .suffix(" m/s"),
                );
                ui.checkbox(&mut settings.body_parts, "hands, knees, pelvis")
                    .on_hover_text("contacts of their own for these parts too");
            });
            changed.contacts = held.then_some(settings);
        });
        if changed != options {
            self.command(MotionCommand::SetRetargetOptions(Box::new(changed)));
        }
    }

    /// A row: its label, and the track's rectangle to its right.
    fn row(
        ui: &mut egui::Ui,
        label: &str,
        frames: usize,
        frame_time: f64,
    ) -> (Track, egui::Response) {
        let (rect, response) =
            ui.allocate_exact_size(vec2(ui.available_width(), ROW_HEIGHT), Sense::click());
        let label_rect = Rect::from_min_size(rect.min, vec2(LABEL_WIDTH, rect.height()));
        ui.painter().text(
            label_rect.left_center(),
            egui::Align2::LEFT_CENTER,
            label,
            egui::FontId::proportional(11.0),
            ui.visuals().text_color(),
        );
        let track_rect = Rect::from_min_max(
            pos2(rect.left() + LABEL_WIDTH, rect.top()),
            pos2(rect.right() - 8.0, rect.bottom()),
        );
        ui.painter()
            .rect_filled(track_rect, 2.0, ui.visuals().extreme_bg_color);
        let track = Track {
            rect: track_rect,
            frames,
            frame_time,
        };
        (track, response)
    }

    /// The keys as diamonds: click = go there, drag = move, menu = delete or copy here.
    fn key_track(&mut self, ui: &mut egui::Ui) -> Track {
        let (frames, frame_time) = (self.model.frame_count(), self.model.frame_time());
        let (track, background) = Self::row(ui, "Keys", frames, frame_time);
        if background.clicked()
            && let Some(pointer) = background.interact_pointer_pos()
            && track.rect.contains(pointer)
        {
            self.command(MotionCommand::Seek(track.frame_at(pointer.x)));
        }
        let here = self.model.timeline().frame();
        let playhead = track.x_of_frame(here as f64);
        ui.painter().line_segment(
            [
                pos2(playhead, track.rect.top()),
                pos2(playhead, track.rect.bottom()),
            ],
            Stroke::new(2.0, PLAYHEAD_COLOR),
        );
        for key in self.model.key_frames() {
            let centre = pos2(track.x_of_frame(key as f64), track.rect.center().y);
            let area = Rect::from_center_size(centre, vec2(12.0, 14.0));
            let response = ui.interact(
                area,
                ui.scope_id().with(("key", key)),
                Sense::click_and_drag(),
            );
            let drawn_at = match response.interact_pointer_pos() {
                Some(pointer) if response.dragged() => pos2(pointer.x, centre.y),
                _ => centre,
            };
            diamond(
                ui.painter(),
                drawn_at,
                if response.hovered() { 7.0 } else { 5.5 },
            );
            if response.clicked() {
                self.command(MotionCommand::Seek(key));
            }
            if response.drag_stopped()
                && let Some(pointer) = response.interact_pointer_pos()
            {
                let to = track.frame_at(pointer.x);
                self.command(MotionCommand::MoveKey { from: key, to });
            }
            response
                .on_hover_text(format!("key at frame {key}"))
                .context_menu(|ui| {
                    if ui.button("Delete key").clicked() {
                        self.command(MotionCommand::DeleteKey(key));
                        ui.close();
                    }
                    if ui.button(format!("Copy to frame {here}")).clicked() {
                        self.command(MotionCommand::CopyKey {
                            from: key,
                            to: here,
                        });
                        ui.close();
                    }
                });
        }
        track
    }

    /// A row per task: its interval as a bar with draggable ends, or a button to give it one.
    fn interval_rows(&mut self, ui: &mut egui::Ui, track: Track) {
        let tasks: Vec<(String, Option<TaskInterval>)> = self
            .model
            .session()
            .tasks()
            .iter()
            .map(|task| (task.description(), task.interval))
            .collect();
        let now = self.model.timeline().frame() as f64 * track.frame_time;
        for (index, (description, interval)) in tasks.into_iter().enumerate() {
            let (row, _) = Self::row(ui, &description, track.frames, track.frame_time);
            let Some(interval) = interval else {
                let area = Rect::from_min_size(row.rect.min, vec2(90.0, row.rect.height()));
                let add = ui.put(area, egui::Button::new("+ interval").small());
                if add
                    .on_hover_text("active for 1 s from the playhead")
                    .clicked()
                {
                    let interval = TaskInterval::new(now, now + 1.0);
                    self.command(MotionCommand::SetInterval {
                        task: index,
                        interval: Some(interval),
                    });
                }
                continue;
            };
            self.interval_bar(ui, row, index, interval);
        }
    }

    fn interval_bar(&mut self, ui: &mut egui::Ui, row: Track, task: usize, interval: TaskInterval) {
        let (top, bottom) = (row.rect.top() + 3.0, row.rect.bottom() - 3.0);
        let (start, end) = (row.x_of_secs(interval.start), row.x_of_secs(interval.end));
        let ramp_in = row.x_of_secs(interval.start - interval.ease_in);
        let ramp_out = row.x_of_secs(interval.end + interval.ease_out);
        let faint = INTERVAL_COLOR.gamma_multiply(0.4);
        let painter = ui.painter();
        painter.rect_filled(
            Rect::from_min_max(pos2(ramp_in, top), pos2(start, bottom)),
            0.0,
            faint,
        );
        painter.rect_filled(
            Rect::from_min_max(pos2(end, top), pos2(ramp_out, bottom)),
            0.0,
            faint,
        );
        painter.rect_filled(
            Rect::from_min_max(pos2(start, top), pos2(end.max(start + 1.0), bottom)),
            2.0,
            INTERVAL_COLOR,
        );
        for (edge, x) in [(IntervalEdge::Start, start), (IntervalEdge::End, end)] {
            let area = Rect::from_center_size(pos2(x, row.rect.center().y), vec2(8.0, ROW_HEIGHT));
            let id = ui
                .scope_id()
                .with(("interval", task, edge == IntervalEdge::Start));
            let response = ui.interact(area, id, Sense::drag());
            if response.dragged()
                && let Some(pointer) = response.interact_pointer_pos()
            {
                let secs = row.secs_at(pointer.x);
                self.command(MotionCommand::DragInterval { task, edge, secs });
            }
            let response = response.on_hover_cursor(egui::CursorIcon::ResizeHorizontal);
            if response.hovered() {
                ui.painter().line_segment(
                    [pos2(x, row.rect.top()), pos2(x, row.rect.bottom())],
                    Stroke::new(2.0, Color32::WHITE),
                );
            }
        }
        let clear = Rect::from_min_size(
            pos2(row.rect.left() - 22.0, row.rect.top()),
            vec2(18.0, row.rect.height()),
        );
        if ui
            .put(clear, egui::Button::new("x").small())
            .on_hover_text("always active")
            .clicked()
        {
            self.command(MotionCommand::SetInterval {
                task,
                interval: None,
            });
        }
    }

    /// The clip's foot contacts (read-only bars).
    fn contact_row(&mut self, ui: &mut egui::Ui, track: Track) {
        if self.model.timeline().contacts().is_empty() {
            return;
        }
        let (row, _) = Self::row(ui, "Contacts", track.frames, track.frame_time);
        for contact in self.model.timeline().contacts() {
            let left = contact.joint.starts_with("l_");
            let (top, bottom) = if left {
                (row.rect.top() + 2.0, row.rect.center().y - 1.0)
            } else {
                (row.rect.center().y + 1.0, row.rect.bottom() - 2.0)
            };
            let rect = Rect::from_min_max(
                pos2(row.x_of_frame(contact.start as f64), top),
                pos2(
                    row.x_of_frame(contact.end as f64)
                        .max(row.x_of_frame(contact.start as f64) + 2.0),
                    bottom,
                ),
            );
            // A sliding contact (kept on the floor, not held still): an outline.
            if contact.slides {
                ui.painter().rect_stroke(
                    rect,
                    1.0,
                    egui::Stroke::new(1.0, CONTACT_COLOR),
                    egui::StrokeKind::Inside,
                );
            } else {
                ui.painter().rect_filled(rect, 1.0, CONTACT_COLOR);
            }
        }
    }
}

/// A key's diamond.
fn diamond(painter: &egui::Painter, centre: Pos2, radius: f32) {
    let points = vec![
        centre + vec2(0.0, -radius),
        centre + vec2(radius, 0.0),
        centre + vec2(0.0, radius),
        centre + vec2(-radius, 0.0),
    ];
    painter.add(egui::Shape::convex_polygon(
        points,
        KEY_COLOR,
        Stroke::new(1.0, Color32::BLACK),
    ));
}

/// The Motion menu: clips in (a file, the avatar's own animations, a recording of the body),
/// the clip's mapping, the timeline out (GLB on the avatar, BVH), the panel. Returns true
/// when the clip's mapping window was asked for.
pub(super) fn motion_menu(
    model: &EditorModel,
    outbox: &mut Outbox,
    ui: &mut egui::Ui,
    shown: &mut bool,
) -> bool {
    let mut command = None;
    let mut mapping = false;
    if ui.button("Open clip (BVH, glTF animation)…").clicked() {
        command = Some(Command::File(FileCommand::PickClip));
    }
    let animations: Vec<String> = model
        .avatar()
        .map(|loaded| {
            loaded
                .avatar
                .animations
                .iter()
                .map(|a| a.name.clone())
                .collect()
        })
        .unwrap_or_default();
    for (index, name) in animations.iter().enumerate() {
        let label = format!("Play the avatar's animation: {name}");
        if ui.button(label).clicked() {
            command = Some(Command::Motion(MotionCommand::OpenAvatarAnimation(index)));
        }
    }
    let recording = model.timeline().is_recording();
    let record = if recording {
        "Stop recording (the recording becomes a clip)"
    } else {
        "Record the body (sensors, replay or posing)"
    };
    if ui.button(record).clicked() {
        command = Some(Command::Motion(MotionCommand::Record(!recording)));
    }
    if model.timeline().has_clip() {
        if ui.button("Clip mapping…").clicked() {
            mapping = true;
            ui.close();
        }
        if ui.button("Close clip").clicked() {
            command = Some(Command::Motion(MotionCommand::CloseClip));
        }
    }
    ui.separator();
    let has_timeline = model.has_timeline();
    let glb = ui
        .add_enabled(
            has_timeline && model.avatar().is_some(),
            egui::Button::new("Export animation on the avatar (GLB)…"),
        )
        .on_disabled_hover_text("open a clip or set keys, on a loaded avatar");
    if glb.clicked() {
        command = Some(Command::File(FileCommand::ExportAnimation(
            AnimationFormat::Glb,
        )));
    }
    let bvh = ui
        .add_enabled(has_timeline, egui::Button::new("Export animation (BVH)…"))
        .on_disabled_hover_text("open a clip or set keys first");
    if bvh.clicked() {
        command = Some(Command::File(FileCommand::ExportAnimation(
            AnimationFormat::Bvh,
        )));
    }
    ui.separator();
    ui.checkbox(shown, "Show the timeline");
    if let Some(command) = command {
        outbox.send(command);
        ui.close();
    }
    mapping
}
