//! The editor: menu bar, task and selection panels, status bar and the 3D viewport in the
//! middle, where the body is pulled, pinned and selected. Every edit goes through the undo
//! history; the document autosaves; posture links open and copy.

mod avatar_panel;
mod comfort_panel;
mod control_maps_window;
mod handles;
mod hands_panel;
mod image_window;
mod lens;
mod overlay;
mod prop_gizmo;
mod scene_panel;
mod sensors_panel;
mod side_panel;
mod state;
mod tasks_panel;
mod timeline_panel;
mod viewport_panel;

use crate::model::{
    AvatarCommand, FileCommand, GestureCommand, HistoryCommand, LibraryCommand, NoticeCommand,
    PostureCommand, ViewCommand,
};
use std::sync::mpsc::Receiver;

use egui::{Color32, Key, KeyboardShortcut, Modifiers, RichText};
use stance_hanim::LevelOfArticulation;
use stance_ik::Clock;
use stance_render::{OrbitCamera, ViewPreset};

use self::avatar_panel::MappingEditor;
use self::avatar_panel::SubjectKind;
use self::sensors_panel::SensorsWindow;
use self::side_panel::SidePanel;
use self::state::PageState;
use self::tasks_panel::TasksPanel;
use self::timeline_panel::TimelinePanel;
use self::viewport_panel::ViewportPanel;
use crate::model::{Command, EditorModel, MotionCommand, Outbox};
use crate::posing::PosingError;
use stance_model::{HostHooks, HostMessage};

/// The Stance editor.
pub struct StanceApp {
    /// Everything the editor knows and does, without egui.
    model: EditorModel,
    /// What the views sent the model this frame: carried out between the views
    /// ([`StanceApp::carry_out`]).
    outbox: Outbox,
    viewport: ViewportPanel,
    windows: Windows,
    mapping_editor: MappingEditor,
    /// The name typed for the next saved pose.
    library_name: String,
    inbox: Option<Receiver<HostMessage>>,
    /// CPU time of the last frame (ms).
    frame_ms: f64,
    clock_origin: web_time::Instant,
    /// Screen rectangles (points) of named buttons, published for the page's test hook.
    button_rects: ButtonRects,
    /// The model's session generation the views were built for.
    session_generation: u64,
}

/// Screen rectangles (points) of named buttons, for the page's test hook.
pub(crate) type ButtonRects = Vec<(&'static str, egui::Rect)>;

/// Which windows are open.
#[derive(Debug, Default)]
pub(crate) struct Windows {
    pub help: bool,
    pub sensors: bool,
    pub mapping: bool,
    /// Whose mapping the mapping window shows (the avatar's or the clip's).
    pub mapping_subject: SubjectKind,
    /// The timeline panel: `None` shows it when a clip or keys exist.
    pub timeline: Option<bool>,
    /// *Save image*.
    pub image: image_window::ImageWindow,
    /// *Export control maps*.
    pub control_maps: control_maps_window::ControlMapsWindow,
}

impl std::fmt::Debug for StanceApp {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StanceApp")
            .field("model", &self.model)
            .finish_non_exhaustive()
    }
}

impl StanceApp {
    /// Creates the editor; GPU resources are made once here, from eframe's wgpu state.
    pub fn new(
        creation: &eframe::CreationContext<'_>,
        hooks: Box<dyn HostHooks>,
    ) -> Result<Self, PosingError> {
        crate::fonts::install(&creation.egui_ctx);
        let mut app = Self::without_gpu(hooks)?;
        app.viewport = ViewportPanel::new(creation.wgpu_render_state.as_ref());
        Ok(app)
    }

    /// The editor with no GPU: panels work, the viewport says why it is empty (tests).
    pub fn without_gpu(hooks: Box<dyn HostHooks>) -> Result<Self, PosingError> {
        Ok(Self {
            model: EditorModel::new(hooks)?,
            outbox: Outbox::default(),
            viewport: ViewportPanel::new(None),
            windows: Windows::default(),
            mapping_editor: MappingEditor::default(),
            library_name: String::new(),
            inbox: None,
            frame_ms: 0.0,
            clock_origin: web_time::Instant::now(),
            button_rects: Vec::new(),
            session_generation: 0,
        })
    }

    /// Messages from the host (links, files) arrive through this receiver.
    pub fn with_inbox(mut self, inbox: Receiver<HostMessage>) -> Self {
        self.inbox = Some(inbox);
        self
    }

    /// Opens what the page was opened with: a posture link when the address has one (a bad
    /// link says why and the editor opens normally), otherwise the autosaved work.
    pub fn open_startup(&mut self, link_fragment: Option<&str>) {
        self.model.open_startup(link_fragment);
    }

    /// The editor's model (what the panels and the viewport show).
    pub fn model(&self) -> &EditorModel {
        &self.model
    }

    /// Carries out a command as the UI would (scripts and tests).
    pub fn apply(&mut self, command: Command) {
        self.model.apply(command);
    }

    /// Carries out what the views sent the model so far.
    fn carry_out(&mut self) {
        self.model.apply_outbox(&mut self.outbox);
    }

    /// The viewport's orbit camera.
    pub fn camera(&self) -> &OrbitCamera {
        &self.viewport.camera
    }

    fn now_secs(&self) -> f64 {
        self.clock_origin.elapsed().as_secs_f64()
    }

    fn drain_inbox(&mut self) {
        let messages: Vec<HostMessage> = match &self.inbox {
            Some(inbox) => inbox.try_iter().collect(),
            None => return,
        };
        for message in messages {
            self.model.receive(message);
        }
    }

    // -----------------------------------------------------------------------------------------
    // Keyboard

    fn shortcuts(&mut self, ctx: &egui::Context) {
        let redo_shift = KeyboardShortcut::new(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
        let undo = KeyboardShortcut::new(Modifiers::COMMAND, Key::Z);
        let redo_y = KeyboardShortcut::new(Modifiers::COMMAND, Key::Y);
        if ctx.input_mut(|input| input.consume_shortcut(&redo_shift))
            || ctx.input_mut(|input| input.consume_shortcut(&redo_y))
        {
            self.outbox.send(Command::History(HistoryCommand::Redo));
        } else if ctx.input_mut(|input| input.consume_shortcut(&undo)) {
            self.outbox.send(Command::History(HistoryCommand::Undo));
        }
        if ctx.egui_wants_keyboard_input() {
            return;
        }
        let plain = |key| KeyboardShortcut::new(Modifiers::NONE, key);
        if ctx.input_mut(|input| input.consume_shortcut(&plain(Key::P))) {
            self.outbox
                .send(Command::Posture(PostureCommand::PinSelected));
        }
        if ctx.input_mut(|input| input.consume_shortcut(&plain(Key::M))) {
            self.outbox.send(Command::Posture(PostureCommand::Mirror));
        }
        if ctx.input_mut(|input| input.consume_shortcut(&plain(Key::R))) {
            self.outbox
                .send(Command::Posture(PostureCommand::ResetToRest));
        }
        if ctx.input_mut(|input| input.consume_shortcut(&plain(Key::F))) {
            self.viewport.frame(&self.model, false);
        }
        self.view_keys(ctx);
        if ctx.input_mut(|input| input.consume_shortcut(&plain(Key::L))) {
            copy_link(ctx, &self.model, &mut self.outbox);
        }
        if ctx.input_mut(|input| input.consume_shortcut(&plain(Key::T))) {
            self.viewport.show_trace = !self.viewport.show_trace;
        }
        if ctx.input_mut(|input| input.consume_shortcut(&plain(Key::K))) {
            self.outbox.send(Command::Motion(MotionCommand::SetKey));
        }
        if ctx.input_mut(|input| input.consume_shortcut(&plain(Key::S))) {
            self.windows.sensors = !self.windows.sensors;
        }
        if ctx.input_mut(|input| {
            input.consume_shortcut(&plain(Key::F1)) || input.consume_shortcut(&plain(Key::H))
        }) {
            self.windows.help = !self.windows.help;
        }
        if ctx.input_mut(|input| input.consume_shortcut(&plain(Key::Escape))) {
            if self.model.gesture().is_some() {
                self.outbox
                    .send(Command::Gesture(GestureCommand::CancelGesture));
            } else {
                self.outbox.send(Command::View(ViewCommand::Select(None)));
            }
        }
    }

    // -----------------------------------------------------------------------------------------
    // Panels

    fn menu_bar(&mut self, ui: &mut egui::Ui) {
        egui::MenuBar::new().ui(ui, |ui| {
            ui.label(RichText::new("Stance").strong());
            ui.separator();
            let file = ui.menu_button("File", |ui| self.file_menu(ui));
            self.button_rects.push(("file_menu", file.response.rect));
            ui.menu_button("Avatar", |ui| self.avatar_menu(ui));
            ui.menu_button("Edit", |ui| self.edit_menu(ui));
            let view = ui.menu_button("View", |ui| self.view_menu(ui));
            self.button_rects.push(("view_menu", view.response.rect));
            ui.menu_button("Motion", |ui| {
                let before = self.timeline_shown();
                let mut shown = before;
                if timeline_panel::motion_menu(&self.model, &mut self.outbox, ui, &mut shown) {
                    self.windows.mapping = true;
                    self.windows.mapping_subject = SubjectKind::Clip;
                }
                if shown != before {
                    self.windows.timeline = Some(shown);
                }
            });
            ui.menu_button("Sensors", |ui| {
                if ui.button("Motion-capture sensors… (S)").clicked() {
                    self.windows.sensors = true;
                    ui.close();
                }
            });
            ui.menu_button("Help", |ui| {
                if ui.button("Controls and shortcuts (H)").clicked() {
                    self.windows.help = true;
                    ui.close();
                }
            });
        });
    }

    fn file_menu(&mut self, ui: &mut egui::Ui) {
        if ui.button("Copy posture link (L)").clicked() {
            copy_link(ui.ctx(), &self.model, &mut self.outbox);
            ui.close();
        }
        ui.separator();
        let mut command = None;
        if ui.button("Export pose (JSON)…").clicked() {
            command = Some(Command::File(FileCommand::ExportDocument));
        }
        if ui.button("Import pose or library (JSON)…").clicked() {
            command = Some(Command::File(FileCommand::PickFile));
        }
        let keypoints = ui.button("Open keypoints (OpenPose JSON)…").on_hover_text(
            "a character per person, posed to match the keypoints through their camera",
        );
        self.button_rects.push(("open_keypoints", keypoints.rect));
        if keypoints.clicked() {
            command = Some(Command::Keypoints(crate::model::KeypointsCommand::Pick));
        }
        let photo = ui.button("Open photo…").on_hover_text(
            "the person in a photo, found by a pose detector in the browser and posed like keypoints; the photo stays behind the view",
        );
        self.button_rects.push(("open_photo", photo.rect));
        if photo.clicked() {
            command = Some(Command::Keypoints(
                crate::model::KeypointsCommand::PickPhoto,
            ));
        }
        let prop = ui.button("Import prop…").on_hover_text(
            "a static glTF/GLB mesh (a chair, a table) placed in front of the character",
        );
        self.button_rects.push(("import_prop", prop.rect));
        if prop.clicked() {
            command = Some(Command::File(FileCommand::PickProp));
        }
        if ui.button("Export pose library (JSON)…").clicked() {
            command = Some(Command::Library(LibraryCommand::Export));
        }
        ui.separator();
        // One character at the origin exports its avatar file; anything more, the scene
        // (a mannequin as its figure).
        let label = if self.model.is_single_character() && self.model.avatar().is_some() {
            "Export posed avatar (GLB)…"
        } else {
            "Export posed scene (GLB)…"
        };
        let posed = ui.button(label);
        self.button_rects.push(("export_posed", posed.rect));
        if posed.clicked() {
            command = Some(Command::Avatar(AvatarCommand::ExportPosedAvatar));
        }
        ui.separator();
        let save_image = ui.button("Save image (PNG)…");
        self.button_rects.push(("save_image_menu", save_image.rect));
        if save_image.clicked() {
            self.windows.image.open = true;
            ui.close();
        }
        let control_maps = ui.button("Export control maps…");
        self.button_rects
            .push(("control_maps_menu", control_maps.rect));
        if control_maps.clicked() {
            self.windows.control_maps.open = true;
            ui.close();
        }
        if let Some(command) = command {
            self.outbox.send(command);
            ui.close();
        }
    }

    fn avatar_menu(&mut self, ui: &mut egui::Ui) {
        let mut command = None;
        if ui.button("Open avatar file (glTF, GLB, VRM)…").clicked() {
            command = Some(Command::File(FileCommand::PickFile));
        }
        if ui.button("Bundled skinned humanoid").clicked() {
            command = Some(Command::Avatar(AvatarCommand::FetchAvatar(
                "default-avatar.glb".to_owned(),
            )));
        }
        if ui
            .add_enabled(
                self.model.avatar().is_some(),
                egui::Button::new("Back to the mannequin"),
            )
            .clicked()
        {
            command = Some(Command::Avatar(AvatarCommand::UseMannequin));
        }
        ui.checkbox(&mut self.viewport.show_skeleton, "Show the skeleton");
        if let Some(command) = command {
            self.outbox.send(command);
            ui.close();
        }
    }

    fn edit_menu(&mut self, ui: &mut egui::Ui) {
        let history = self.model.history();
        let entries = [
            (
                "Undo",
                "Ctrl+Z",
                history.can_undo(),
                Command::History(HistoryCommand::Undo),
            ),
            (
                "Redo",
                "Ctrl+Shift+Z",
                history.can_redo(),
                Command::History(HistoryCommand::Redo),
            ),
            (
                "Pin selected part",
                "P",
                true,
                Command::Posture(PostureCommand::PinSelected),
            ),
            (
                "Mirror left/right",
                "M",
                true,
                Command::Posture(PostureCommand::Mirror),
            ),
            (
                "Reset to rest pose",
                "R",
                true,
                Command::Posture(PostureCommand::ResetToRest),
            ),
        ];
        let mut chosen = None;
        for (position, (label, shortcut, enabled, command)) in entries.into_iter().enumerate() {
            if position == 2 {
                ui.separator();
            }
            if ui
                .add_enabled(enabled, egui::Button::new(label).shortcut_text(shortcut))
                .clicked()
            {
                chosen = Some(command);
            }
        }
        if let Some(command) = chosen {
            self.outbox.send(command);
            ui.close();
        }
    }

    /// Blender's numpad views: 1 front, 3 right side, 7 top (with Ctrl or Alt: the opposite
    /// side), 9 the opposite view, 5 orthographic or perspective, . (period) frames the
    /// selection.
    fn view_keys(&mut self, ctx: &egui::Context) {
        let pressed = |modifiers, key| {
            ctx.input_mut(|input| input.consume_shortcut(&KeyboardShortcut::new(modifiers, key)))
        };
        for modifiers in [Modifiers::CTRL, Modifiers::ALT] {
            if pressed(modifiers, Key::Num1) {
                self.viewport.set_view(ViewPreset::Back);
            }
            if pressed(modifiers, Key::Num3) {
                self.viewport.set_view(ViewPreset::Left);
            }
        }
        let plain = Modifiers::NONE;
        if pressed(plain, Key::Num1) {
            self.viewport.set_view(ViewPreset::Front);
        }
        if pressed(plain, Key::Num3) {
            self.viewport.set_view(ViewPreset::Right);
        }
        if pressed(plain, Key::Num7) {
            self.viewport.set_view(ViewPreset::Top);
        }
        if pressed(plain, Key::Num9) {
            self.viewport.opposite_view();
        }
        if pressed(plain, Key::Num5) {
            self.viewport.camera.orthographic = !self.viewport.camera.orthographic;
        }
        if pressed(plain, Key::Period) {
            self.viewport.frame(&self.model, true);
        }
    }

    fn camera_menu(&mut self, ui: &mut egui::Ui) {
        for (preset, key) in [
            (ViewPreset::Front, "1"),
            (ViewPreset::Back, "Ctrl+1"),
            (ViewPreset::Right, "3"),
            (ViewPreset::Left, "Ctrl+3"),
            (ViewPreset::Top, "7"),
            (ViewPreset::ThreeQuarter, ""),
        ] {
            let label = if key.is_empty() {
                preset.label().to_owned()
            } else {
                format!("{} ({key})", preset.label())
            };
            if ui.button(label).clicked() {
                self.viewport.set_view(preset);
                ui.close();
            }
        }
        ui.checkbox(&mut self.viewport.camera.orthographic, "Orthographic (5)");
        if ui.button("Frame the selection (.)").clicked() {
            self.viewport.frame(&self.model, true);
            ui.close();
        }
        if ui.button("Frame the body (F)").clicked() {
            self.viewport.frame(&self.model, false);
            ui.close();
        }
        ui.separator();
        if ui.button("Save this view with the document").clicked() {
            self.viewport.save_camera(&mut self.outbox);
            ui.close();
        }
        if self.model.session().camera().is_some()
            && ui.button("Forget the document's view").clicked()
        {
            self.outbox
                .send(Command::Posture(PostureCommand::SaveCamera(None)));
            ui.close();
        }
    }

    fn view_menu(&mut self, ui: &mut egui::Ui) {
        ui.checkbox(&mut self.viewport.show_figure, "Mannequin as a figure")
            .on_hover_text("off: the mannequin's capsules (the heat map always colours them)");
        let mut capsules = self.model.show_capsules();
        if ui
            .checkbox(&mut capsules, "Collision capsules")
            .on_hover_text("the capsules the collision task holds apart, over the figure or avatar")
            .changed()
        {
            self.outbox
                .send(Command::View(ViewCommand::ShowCapsules(capsules)));
        }
        ui.checkbox(&mut self.viewport.show_floor, "Floor grid");
        if let Some(photo) = self.model.photo() {
            let mut shown = self.model.photo_shown();
            let toggle = ui
                .checkbox(&mut shown, "Photo behind the view")
                .on_hover_text(format!(
                    "{} as the reference (lined up through the lifted character's saved view; the floor is hidden meanwhile)",
                    photo.name
                ));
            self.button_rects.push(("show_photo", toggle.rect));
            if toggle.changed() {
                self.outbox.send(Command::Keypoints(
                    crate::model::KeypointsCommand::ShowPhoto(shown),
                ));
            }
        }
        ui.checkbox(&mut self.viewport.show_trace, "Effector trace (T)");
        let mut timeline = self.timeline_shown();
        if ui.checkbox(&mut timeline, "Timeline").changed() {
            self.windows.timeline = Some(timeline);
        }
        ui.menu_button("Camera", |ui| self.camera_menu(ui));
        ui.separator();
        ui.label("Level of articulation");
        let current = self.model.level_of_articulation();
        for loa in LevelOfArticulation::ALL {
            if ui
                .radio(current == loa, format!("LOA {}", loa.number()))
                .clicked()
            {
                self.outbox
                    .send(Command::Avatar(AvatarCommand::SetLevelOfArticulation(loa)));
            }
        }
    }

    /// Whether the timeline panel shows: as set in the View menu, else when a clip or keys
    /// exist.
    fn timeline_shown(&self) -> bool {
        self.windows
            .timeline
            .unwrap_or_else(|| self.model.has_timeline())
    }

    fn status_bar(&self, ui: &mut egui::Ui, frame: &eframe::Frame) {
        ui.horizontal(|ui| {
            match &self.viewport.backend {
                Some(backend) => {
                    ui.label(RichText::new(&backend.backend).strong())
                        .on_hover_text("graphics backend");
                    ui.separator();
                    ui.label(&backend.adapter).on_hover_text("graphics adapter");
                }
                None => {
                    ui.colored_label(Color32::LIGHT_RED, "no GPU backend");
                }
            }
            ui.separator();
            let [width, height] = self.viewport.size_px;
            ui.label(format!("{width}×{height} px"));
            if let Some(cpu_seconds) = frame.info().cpu_usage {
                ui.separator();
                ui.label(format!("frame {:.1} ms", cpu_seconds * 1000.0));
            }
            ui.separator();
            ui.label(format!("solver {:.2} ms", self.model.solver_ms()));
            if let Some(report) = self.model.session().report() {
                ui.separator();
                let status = match report.status {
                    stance_ik::SolveStatus::Converged => "converged",
                    stance_ik::SolveStatus::Stalled => "stalled",
                    stance_ik::SolveStatus::IterationBudget
                    | stance_ik::SolveStatus::TimeBudget => "solving…",
                };
                ui.label(status);
                if let Some(level) = report.gave_way {
                    ui.colored_label(
                        Color32::from_rgb(230, 150, 60),
                        format!("level {level} gave way"),
                    );
                }
            }
        });
    }

    /// While the host lifts keypoints (off the editor's thread): a busy notice and *Cancel*.
    /// No spinner: its animation redraws the editor every frame, and in the page the lift's
    /// reply then waits for the frame under way (0.7 s in software GL); the page's own busy
    /// bar moves instead (web/loading.js).
    fn lifting_strip(&mut self, ui: &mut egui::Ui) {
        let Some(words) = self.model.lifting().map(crate::model::Lifting::words) else {
            return;
        };
        let cancel = Command::Keypoints(crate::model::KeypointsCommand::Cancel);
        let hover = "stop the lift: the scene stays as it is";
        self.job_strip(ui, ("cancel_lift", hover, cancel), |ui| {
            ui.label(words);
        });
    }

    /// While the host opens a clip (off the editor's thread): its progress and *Cancel*.
    fn opening_strip(&mut self, ui: &mut egui::Ui) {
        let Some((name, progress)) = self
            .model
            .timeline()
            .opening()
            .map(|(name, progress)| (name.to_owned(), progress))
        else {
            return;
        };
        let cancel = Command::Motion(crate::model::MotionCommand::CancelOpening);
        let hover = "stop opening the clip: the document stays as it is";
        self.job_strip(ui, ("cancel_clip", hover, cancel), |ui| {
            let file = name.rsplit('/').next().unwrap_or(&name);
            ui.add(egui::ProgressBar::new(progress as f32).text(format!(
                "Opening {file}: {:.0} %",
                (progress * 100.0).floor()
            )));
        });
    }

    /// The strip of a job the host runs off the editor's thread: *Cancel* (its button's
    /// name for the tests, its hover text, the command it sends), then what `show` draws.
    fn job_strip(
        &mut self,
        ui: &mut egui::Ui,
        (name, hover, command): (&'static str, &str, Command),
        show: impl FnOnce(&mut egui::Ui),
    ) {
        egui::Frame::new()
            .fill(Color32::from_rgb(30, 60, 90))
            .inner_margin(egui::Margin::symmetric(8, 4))
            .show(ui, |ui| {
                ui.horizontal(|ui| {
                    let cancel = ui.button("Cancel").on_hover_text(hover);
                    self.button_rects.push((name, cancel.rect));
                    if cancel.clicked() {
                        self.outbox.send(command);
                    }
                    show(ui);
                });
            });
    }

    fn notice_strip(&mut self, ui: &mut egui::Ui) {
        let Some(notice) = self.model.notice().cloned() else {
            return;
        };
        let (fill, text_color) = if notice.is_error {
            (
                Color32::from_rgb(90, 30, 30),
                Color32::from_rgb(255, 210, 200),
            )
        } else {
            (
                Color32::from_rgb(30, 60, 90),
                Color32::from_rgb(210, 230, 255),
            )
        };
        egui::Frame::new()
            .fill(fill)
            .inner_margin(egui::Margin::symmetric(8, 4))
            .show(ui, |ui| {
                // The dismiss button first, from the right: the text wraps in the width left
                // beside it. (After a wrapped text, the button stuck out past the panel and
                // widened the viewport under the tasks panel.)
                ui.with_layout(egui::Layout::right_to_left(egui::Align::Min), |ui| {
                    if ui.small_button("x").on_hover_text("dismiss").clicked() {
                        self.outbox.send(Command::Notice(NoticeCommand::Dismiss));
                    }
                    ui.with_layout(egui::Layout::left_to_right(egui::Align::Min), |ui| {
                        ui.add(
                            egui::Label::new(RichText::new(&notice.text).color(text_color)).wrap(),
                        );
                    });
                });
            });
        if !notice.is_error {
            ui.ctx()
                .request_repaint_after(std::time::Duration::from_secs(1));
        }
    }

    fn help_window(&mut self, ctx: &egui::Context) {
        egui::Window::new("Controls and shortcuts")
            .open(&mut self.windows.help)
            .resizable(false)
            .collapsible(false)
            .show(ctx, |ui| {
                egui::Grid::new("controls").num_columns(2).show(ui, |ui| {
                    for (gesture, effect) in HELP_ROWS {
                        ui.label(RichText::new(*gesture).strong());
                        ui.label(*effect);
                        ui.end_row();
                    }
                });
            });
    }

    // -----------------------------------------------------------------------------------------
    // State for the page

    /// A message from the host taken between frames instead of at the next one (the messages
    /// queued before it first): an avatar it opens begins its GPU upload at once, in tasks
    /// the host steps (see [`HostHooks::upload_in_tasks`]). Returns whether the next frame
    /// can wait: the host steps that upload (its last share asks for the frame that draws
    /// the avatar), or the message handed an avatar file to the host's import
    /// ([`HostHooks::import_avatar`]) and nothing shows until it is back. Else the caller
    /// asks for a frame.
    pub fn receive_between_frames(&mut self, message: HostMessage) -> bool {
        self.drain_inbox();
        let opens_file = matches!(
            message,
            HostMessage::OpenFile { .. } | HostMessage::OpenFiles(_)
        );
        let awaited = self.model.importing().map(str::to_owned);
        self.model.receive(message);
        let handed_to_host = opens_file
            && self.model.importing().is_some()
            && self.model.importing() != awaited.as_deref();
        let uploading = self
            .viewport
            .begin_avatar_upload(&self.model, &mut self.outbox);
        self.carry_out();
        uploading || handed_to_host
    }

    /// A share of the avatar's GPU upload, stepped by the host between frames (see
    /// [`HostHooks::upload_in_tasks`]): a few MB, its writes submitted. True while more is
    /// left; once done, the next frame draws the avatar.
    pub fn upload_avatar_task(&mut self) -> bool {
        self.viewport.upload_task()
    }

    /// The editor's observable state as JSON (see `app/state.rs`): the page's test hook and
    /// scripts read it; it is built only when asked.
    pub fn state_json(&self) -> String {
        PageState {
            model: &self.model,
            viewport: &self.viewport,
            buttons: &self.button_rects,
            frame_ms: self.frame_ms,
        }
        .to_json()
    }

    /// Draws the whole editor into `ui` (shared by eframe and the UI tests): the views read
    /// the model and send it commands, carried out after each view.
    pub fn show(&mut self, ui: &mut egui::Ui, frame: &eframe::Frame) {
        let ctx = ui.ctx().clone();
        self.button_rects.clear();
        self.drain_inbox();
        self.shortcuts(&ctx);
        self.carry_out();
        // The frame's step runs before anything is drawn: the panels and the viewport show
        // this frame's posture and statuses. A gesture the viewport reads below is solved
        // there again before the body is drawn (EditorModel::follow_input).
        let origin = self.clock_origin;
        let clock = move || origin.elapsed().as_secs_f64();
        self.model.step(self.now_secs(), Some(&clock));
        if self.model.session_generation() != self.session_generation {
            // Another body: the mapping draft was for the old one.
            self.session_generation = self.model.session_generation();
            self.mapping_editor.restart();
        }
        egui::Panel::top("menu_bar").show(ui, |ui| self.menu_bar(ui));
        egui::Panel::bottom("status_bar").show(ui, |ui| self.status_bar(ui, frame));
        self.carry_out();
        self.panels(ui);
        egui::CentralPanel::default()
            .frame(egui::Frame::NONE)
            .show(ui, |ui| self.central(ui, frame, &clock));
        self.show_windows(&ctx);
        if let Some(cpu_seconds) = frame.info().cpu_usage {
            self.frame_ms = f64::from(cpu_seconds) * 1000.0;
        }
    }

    /// The timeline, side and tasks panels, each one's commands carried out before the next.
    fn panels(&mut self, ui: &mut egui::Ui) {
        if self.timeline_shown() {
            egui::Panel::bottom("timeline_panel")
                .exact_size(TimelinePanel::height(&self.model))
                .show(ui, |ui| {
                    let mut panel = TimelinePanel {
                        model: &self.model,
                        outbox: &mut self.outbox,
                        buttons: &mut self.button_rects,
                    };
                    egui::ScrollArea::vertical().show(ui, |ui| panel.show(ui));
                });
            self.carry_out();
        }
        egui::Panel::left("side_panel")
            .resizable(true)
            .default_size(230.0)
            .show(ui, |ui| {
                let mut panel = SidePanel {
                    model: &self.model,
                    outbox: &mut self.outbox,
                    pin_tool: &mut self.viewport.pin_tool,
                    windows: &mut self.windows,
                    library_name: &mut self.library_name,
                    buttons: &mut self.button_rects,
                };
                egui::ScrollArea::vertical().show(ui, |ui| panel.show(ui));
            });
        self.carry_out();
        egui::Panel::right("tasks_panel")
            .resizable(true)
            .default_size(330.0)
            .show(ui, |ui| {
                let mut panel = TasksPanel {
                    model: &self.model,
                    outbox: &mut self.outbox,
                    buttons: &mut self.button_rects,
                };
                egui::ScrollArea::vertical().show(ui, |ui| panel.show(ui));
            });
        self.carry_out();
    }

    /// The strips above the viewport and the viewport: its input is carried out and a gesture
    /// it moved solved again (within `clock`'s frame budget) before the body is drawn, so that
    /// the body drawn follows the pointer read in the same frame.
    fn central(&mut self, ui: &mut egui::Ui, frame: &eframe::Frame, clock: &dyn Clock) {
        self.opening_strip(ui);
        self.lifting_strip(ui);
        self.notice_strip(ui);
        self.carry_out();
        self.viewport.follow_document_camera(&self.model);
        let (response, input) = self.viewport.read_input(ui, &self.model, &mut self.outbox);
        self.carry_out();
        self.viewport
            .follow_pointer(ui, &response, &input, &self.model, &mut self.outbox);
        self.carry_out();
        self.model.follow_input(Some(clock));
        self.viewport
            .show(ui, frame, &self.model, &mut self.outbox, &response);
        self.model.readings_shown();
        self.carry_out();
    }

    /// The windows: help, Save image, Export control maps, sensors, mapping.
    fn show_windows(&mut self, ctx: &egui::Context) {
        self.help_window(ctx);
        self.windows
            .image
            .show(ctx, &mut self.viewport, &mut self.button_rects);
        self.windows.control_maps.show(
            ctx,
            (&self.model, &mut self.outbox),
            &mut self.viewport,
            &mut self.button_rects,
        );
        let mut sensors = SensorsWindow {
            model: &self.model,
            outbox: &mut self.outbox,
            viewport_rect: self.viewport.rect,
            buttons: &mut self.button_rects,
        };
        sensors.show(ctx, &mut self.windows.sensors);
        self.mapping_editor.show(
            ctx,
            &self.model,
            &mut self.outbox,
            (&mut self.windows.mapping, self.windows.mapping_subject),
            &mut self.button_rects,
        );
        self.carry_out();
    }
}

/// Encodes the document into the address bar and the clipboard.
fn copy_link(ctx: &egui::Context, model: &EditorModel, outbox: &mut Outbox) {
    let shared = model.share_link();
    ctx.copy_text(shared.url);
    outbox.send(Command::File(FileCommand::LinkShared {
        characters: shared.characters,
        keys_left_out: shared.keys_left_out,
    }));
}

/// The help window's rows: gesture or key, and what it does.
const HELP_ROWS: &[(&str, &str)] = &[
    (
        "Left drag on the body",
        "grab and pull that point (higher priorities hold)",
    ),
    ("Escape while pulling", "cancel the pull"),
    (
        "Left drag on a goal marker",
        "move that task's goal (in the plane facing you)",
    ),
    (
        "Left drag on a ring of the selected joint",
        "turn that joint about the ring's axis (within its limits)",
    ),
    (
        "Click a body part",
        "select it (joint angles, swivel, tasks)",
    ),
    (
        "Right-click a body part",
        "pin it, or add a position, orientation or limb task on it",
    ),
    (
        "Alt + click a body part, or the pin tool",
        "pin it in one click",
    ),
    ("Left drag elsewhere / one finger", "turn around the body"),
    (
        "Right or middle drag, Shift + left drag, two fingers",
        "pan",
    ),
    ("Wheel / pinch / Ctrl + wheel", "zoom"),
    ("Double click", "the default view again"),
    ("F / . (period)", "frame the body / the selected part"),
    (
        "1, 3, 7 (Ctrl or Alt: the other side), 9",
        "front, right side, top view (back, left side), the opposite view",
    ),
    ("5", "orthographic or perspective"),
    ("Ctrl+Z", "undo"),
    ("Ctrl+Shift+Z, Ctrl+Y", "redo"),
    ("P", "pin the selected part"),
    ("M", "mirror the posture left/right"),
    ("R", "reset to the rest pose (tasks kept)"),
    ("L", "copy the posture link"),
    ("T", "show or hide the effector trace"),
    (
        "K",
        "set a key at the timeline's frame (a pull or edit while paused keys too)",
    ),
    (
        "S",
        "motion-capture sensors: connect, assign, calibrate, record, replay",
    ),
    ("Escape", "deselect"),
    (
        "Drop a .glb/.gltf/.vrm file",
        "pose your own avatar (or Avatar > Open)",
    ),
    ("H, F1", "this help"),
];

impl eframe::App for StanceApp {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        self.show(ui, frame);
    }

    /// Lets the page reach the app (its test hook builds `state_json` when asked).
    #[cfg(target_arch = "wasm32")]
    fn as_any_mut(&mut self) -> Option<&mut dyn std::any::Any> {
        Some(&mut *self)
    }
}
