//! The editor: menu bar, task and selection panels, status bar and the 3D viewport in the
//! middle, where the body is pulled, pinned and selected. Every edit goes through the undo
//! history; the document autosaves; posture links open and copy.

mod avatar_panel;
mod handles;
mod overlay;
mod panels;
mod sensors_panel;

use std::sync::mpsc::Receiver;

use egui::{Color32, Key, KeyboardShortcut, Modifiers, RichText, Sense};
use glam::{DVec3, Vec2};
use serde_json::{Map, Value, json};
use stance_document::link;
use stance_hanim::{LevelOfArticulation, LimbName, readable_name};
use stance_render::{BODY_COLOR_LINEAR, OrbitCamera, Scene, pick_capsule};

use crate::host::{BackendSummary, HostHooks, HostMessage};
use crate::model::{Command, EditorModel, Gesture};
use crate::posing::PosingError;
use crate::viewport::{ViewportInput, ViewportRenderer, apply_gestures};

/// Colour of the selected body part (linear RGB).
const SELECTED_COLOR_LINEAR: [f32; 4] = [0.15, 0.45, 0.85, 1.0];
/// Colour of the body part under the cursor (linear RGB).
const HOVERED_COLOR_LINEAR: [f32; 4] = [0.85, 0.45, 0.22, 1.0];
/// The Stance editor.
pub struct StanceApp {
    /// Everything the editor knows and does, without egui.
    model: EditorModel,
    camera: OrbitCamera,
    show_floor: bool,
    show_help: bool,
    show_trace: bool,
    backend: Option<BackendSummary>,
    renderer: Option<ViewportRenderer>,
    inbox: Option<Receiver<HostMessage>>,
    first_frame_reported: bool,
    viewport_size_px: [u32; 2],
    viewport_rect: egui::Rect,
    show_skeleton: bool,
    avatar_uploaded: bool,
    library_name: String,
    frame_ms: f64,
    /// CPU time of this frame's scene (mannequin capsules, or the avatar's skinning palettes).
    scene_ms: f64,
    /// CPU time of recording and submitting this frame's 3D draw (uploads included).
    render_ms: f64,
    clock_origin: web_time::Instant,
    /// Screen rectangles (points) of named buttons, published for the page's test hook.
    button_rects: Vec<(&'static str, egui::Rect)>,
    show_sensors: bool,
    /// A left click on the body pins it (touch-friendly one-click pin).
    pin_tool: bool,
    mapping_editor: avatar_panel::MappingEditor,
    /// The model's session generation the views were built for.
    session_generation: u64,
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
        let render_state = creation.wgpu_render_state.as_ref();
        let mut app = Self::without_gpu(hooks)?;
        app.backend =
            render_state.map(|state| BackendSummary::from_adapter(&state.adapter.get_info()));
        app.renderer = render_state.map(|state| ViewportRenderer::new(&state.device));
        Ok(app)
    }

    /// The editor with no GPU: panels work, the viewport says why it is empty (tests).
    pub fn without_gpu(hooks: Box<dyn HostHooks>) -> Result<Self, PosingError> {
        Ok(Self {
            model: EditorModel::new(hooks)?,
            camera: OrbitCamera::default(),
            show_floor: true,
            show_help: false,
            show_trace: true,
            backend: None,
            renderer: None,
            inbox: None,
            first_frame_reported: false,
            viewport_size_px: [0, 0],
            viewport_rect: egui::Rect::NOTHING,
            show_skeleton: false,
            avatar_uploaded: false,
            library_name: String::new(),
            frame_ms: 0.0,
            scene_ms: 0.0,
            render_ms: 0.0,
            clock_origin: web_time::Instant::now(),
            button_rects: Vec::new(),
            show_sensors: false,
            pin_tool: false,
            mapping_editor: avatar_panel::MappingEditor::default(),
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

    pub fn camera(&self) -> &OrbitCamera {
        &self.camera
    }

    fn now_secs(&self) -> f64 {
        self.clock_origin.elapsed().as_secs_f64()
    }

    /// Encodes the document into the address bar and the clipboard.
    pub fn copy_link(&mut self, ctx: &egui::Context) {
        let fragment = link::encode(&self.model.document());
        let url = self.model.hooks.share_link(&fragment);
        ctx.copy_text(url);
        self.model.apply(Command::Inform(format!(
            "Link copied to the clipboard ({} characters): opening it shows exactly this posture and these tasks.",
            fragment.len()
        )));
    }

    fn export_document(&mut self) {
        let text = self.model.document().to_json(true);
        if let Err(error) = self.model.hooks.download("stance-pose.json", &text) {
            self.model
                .apply(Command::Warn(format!("Could not export the pose: {error}")));
        }
    }

    fn export_library(&mut self) {
        let text = self.model.library.to_json();
        if let Err(error) = self.model.hooks.download("stance-library.json", &text) {
            self.model.apply(Command::Warn(format!(
                "Could not export the library: {error}"
            )));
        }
    }

    fn import_file(&mut self) {
        if let Err(error) = self.model.hooks.pick_file() {
            self.model
                .apply(Command::Warn(format!("Could not open a file: {error}")));
        }
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
            self.model.apply(Command::Redo);
        } else if ctx.input_mut(|input| input.consume_shortcut(&undo)) {
            self.model.apply(Command::Undo);
        }
        if ctx.egui_wants_keyboard_input() {
            return;
        }
        let plain = |key| KeyboardShortcut::new(Modifiers::NONE, key);
        if ctx.input_mut(|input| input.consume_shortcut(&plain(Key::P))) {
            self.model.apply(Command::PinSelected);
        }
        if ctx.input_mut(|input| input.consume_shortcut(&plain(Key::M))) {
            self.model.apply(Command::Mirror);
        }
        if ctx.input_mut(|input| input.consume_shortcut(&plain(Key::R))) {
            self.model.apply(Command::ResetToRest);
        }
        if ctx.input_mut(|input| input.consume_shortcut(&plain(Key::F))) {
            self.camera = OrbitCamera::default();
        }
        if ctx.input_mut(|input| input.consume_shortcut(&plain(Key::L))) {
            self.copy_link(ctx);
        }
        if ctx.input_mut(|input| input.consume_shortcut(&plain(Key::T))) {
            self.show_trace = !self.show_trace;
        }
        if ctx.input_mut(|input| input.consume_shortcut(&plain(Key::S))) {
            self.show_sensors = !self.show_sensors;
        }
        if ctx.input_mut(|input| {
            input.consume_shortcut(&plain(Key::F1)) || input.consume_shortcut(&plain(Key::H))
        }) {
            self.show_help = !self.show_help;
        }
        if ctx.input_mut(|input| input.consume_shortcut(&plain(Key::Escape))) {
            if self.model.gesture().is_some() {
                self.model.apply(Command::CancelGesture);
            } else {
                self.model.apply(Command::Select(None));
            }
        }
    }

    // -----------------------------------------------------------------------------------------
    // Panels

    fn menu_bar(&mut self, ui: &mut egui::Ui) {
        egui::MenuBar::new().ui(ui, |ui| {
            ui.label(RichText::new("Stance").strong());
            ui.separator();
            ui.menu_button("File", |ui| {
                if ui.button("Copy posture link (L)").clicked() {
                    self.copy_link(ui.ctx());
                    ui.close();
                }
                ui.separator();
                if ui.button("Export pose (JSON)…").clicked() {
                    self.export_document();
                    ui.close();
                }
                if ui.button("Import pose or library (JSON)…").clicked() {
                    self.import_file();
                    ui.close();
                }
                if ui.button("Export pose library (JSON)…").clicked() {
                    self.export_library();
                    ui.close();
                }
                ui.separator();
                self.export_posed_menu_item(ui);
            });
            ui.menu_button("Avatar", |ui| {
                if ui.button("Open avatar file (glTF, GLB, VRM)…").clicked() {
                    self.import_file();
                    ui.close();
                }
                if ui.button("Bundled skinned humanoid").clicked() {
                    self.model
                        .apply(Command::FetchAvatar("default-avatar.glb".to_owned()));
                    ui.close();
                }
                if ui
                    .add_enabled(
                        self.model.avatar().is_some(),
                        egui::Button::new("Back to the mannequin"),
                    )
                    .clicked()
                {
                    self.model.apply(Command::UseMannequin);
                    self.avatar_uploaded = false;
                    ui.close();
                }
                ui.checkbox(&mut self.show_skeleton, "Show the skeleton");
            });
            ui.menu_button("Edit", |ui| {
                if ui
                    .add_enabled(
                        self.model.history().can_undo(),
                        egui::Button::new("Undo").shortcut_text("Ctrl+Z"),
                    )
                    .clicked()
                {
                    self.model.apply(Command::Undo);
                    ui.close();
                }
                if ui
                    .add_enabled(
                        self.model.history().can_redo(),
                        egui::Button::new("Redo").shortcut_text("Ctrl+Shift+Z"),
                    )
                    .clicked()
                {
                    self.model.apply(Command::Redo);
                    ui.close();
                }
                ui.separator();
                if ui
                    .add(egui::Button::new("Pin selected part").shortcut_text("P"))
                    .clicked()
                {
                    self.model.apply(Command::PinSelected);
                    ui.close();
                }
                if ui
                    .add(egui::Button::new("Mirror left/right").shortcut_text("M"))
                    .clicked()
                {
                    self.model.apply(Command::Mirror);
                    ui.close();
                }
                if ui
                    .add(egui::Button::new("Reset to rest pose").shortcut_text("R"))
                    .clicked()
                {
                    self.model.apply(Command::ResetToRest);
                    ui.close();
                }
            });
            ui.menu_button("View", |ui| {
                ui.checkbox(&mut self.show_floor, "Floor grid");
                ui.checkbox(&mut self.show_trace, "Effector trace (T)");
                if ui.button("Frame the body (F)").clicked() {
                    self.camera = OrbitCamera::default();
                    ui.close();
                }
                ui.separator();
                ui.label("Level of articulation");
                let current = self.model.level_of_articulation();
                for loa in LevelOfArticulation::ALL {
                    if ui
                        .radio(current == loa, format!("LOA {}", loa.number()))
                        .clicked()
                    {
                        self.model.apply(Command::SetLevelOfArticulation(loa));
                    }
                }
            });
            ui.menu_button("Sensors", |ui| {
                if ui.button("Motion-capture sensors… (S)").clicked() {
                    self.show_sensors = true;
                    ui.close();
                }
            });
            ui.menu_button("Help", |ui| {
                if ui.button("Controls and shortcuts (H)").clicked() {
                    self.show_help = true;
                    ui.close();
                }
            });
        });
    }

    fn status_bar(&self, ui: &mut egui::Ui, frame: &eframe::Frame) {
        ui.horizontal(|ui| {
            match &self.backend {
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
            let [width, height] = self.viewport_size_px;
            ui.label(format!("{width}×{height} px"));
            if let Some(cpu_seconds) = frame.info().cpu_usage {
                ui.separator();
                ui.label(format!("frame {:.1} ms", cpu_seconds * 1000.0));
            }
            ui.separator();
            ui.label(format!("solver {:.2} ms", self.model.solver_ms));
            if let Some(report) = self.model.session.report() {
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
                ui.horizontal(|ui| {
                    ui.add(egui::Label::new(RichText::new(&notice.text).color(text_color)).wrap());
                    if ui.small_button("x").on_hover_text("dismiss").clicked() {
                        self.model.apply(Command::DismissNotice);
                    }
                });
            });
        if !notice.is_error {
            ui.ctx()
                .request_repaint_after(std::time::Duration::from_secs(1));
        }
    }

    // -----------------------------------------------------------------------------------------
    // Viewport

    /// The body part under `pointer` (on the bones drawn, as of the last step) and the point
    /// hit.
    fn pick(&self, pointer: egui::Pos2) -> Option<(usize, DVec3)> {
        if !self.viewport_rect.contains(pointer) {
            return None;
        }
        let (origin, direction) = self.pointer_ray(pointer);
        let (origin, direction) = (origin.as_vec3(), direction.as_vec3());
        let bones = self.model.bones();
        let capsules: Vec<_> = bones.iter().map(|bone| bone.capsule).collect();
        let hit = pick_capsule(&capsules, origin, direction)?;
        let bone = bones.get(hit.index)?;
        Some((bone.owner, hit.point_world.as_dvec3()))
    }

    /// Where the pointer meets the plane facing the camera through `plane_point_world`.
    fn pointer_on_view_plane(
        &self,
        pointer: egui::Pos2,
        plane_point_world: DVec3,
    ) -> Option<DVec3> {
        let (origin, direction) = self.pointer_ray(pointer);
        let normal = (self.camera.target_world.as_dvec3() - self.camera.eye_world().as_dvec3())
            .normalize_or_zero();
        ray_meets_plane(origin, direction, plane_point_world, normal, 1e-6)
    }

    /// The camera ray under the pointer: origin and direction in the world.
    fn pointer_ray(&self, pointer: egui::Pos2) -> (DVec3, DVec3) {
        let rect = self.viewport_rect;
        let local = pointer - rect.min;
        let (origin, direction) = self.camera.ray_through(
            Vec2::new(local.x, local.y),
            Vec2::new(rect.width(), rect.height()),
        );
        (origin.as_dvec3(), direction.as_dvec3())
    }

    fn viewport(&mut self, ui: &mut egui::Ui, frame: &eframe::Frame) {
        self.notice_strip(ui);
        let rect = ui.available_rect_before_wrap();
        self.viewport_rect = rect;
        // A stable id: the notice strip above comes and goes (with its own widgets), and an
        // automatic id would change with it and end a drag in progress.
        ui.allocate_rect(rect, Sense::hover());
        let response = ui.interact(
            rect,
            egui::Id::unique("stance_viewport"),
            Sense::click_and_drag(),
        );
        let input = ViewportInput::read(ui, &response);
        let pointer = response.hover_pos();
        self.viewport_gestures(ui, &response, &input);
        self.viewport_context_menu(&response);
        if self.model.is_busy() {
            ui.ctx().request_repaint();
        }
        self.draw_viewport(ui, frame, rect);
        self.model.readings_shown();
        self.draw_overlay(ui.painter(), rect);
        if self.show_skeleton
            || (self.model.avatar().is_some() && self.model.selected_joint().is_some())
        {
            self.draw_skeleton(&ui.painter().with_clip_rect(rect), rect);
        }
        self.draw_rings(&ui.painter().with_clip_rect(rect), rect);
        let gesture = self.model.gesture().is_some();
        let over_handle =
            !gesture && pointer.is_some_and(|pointer| self.pick_handle(pointer).is_some());
        if gesture {
            ui.ctx().set_cursor_icon(egui::CursorIcon::Grabbing);
        } else if over_handle || self.model.hovered_joint().is_some() {
            ui.ctx().set_cursor_icon(egui::CursorIcon::Grab);
        }
    }

    /// The pointer on the viewport, as commands: a drag with the primary button (no Shift,
    /// one finger) that starts on a handle (a task's goal, a ring or the swivel of the selected
    /// joint) moves it; on the body it pulls that point; elsewhere it moves the camera. A
    /// click selects (and with the pin tool or Alt pins).
    fn viewport_gestures(
        &mut self,
        ui: &egui::Ui,
        response: &egui::Response,
        input: &ViewportInput,
    ) {
        let pointer = response.hover_pos();
        let press_origin = ui.input(|input| input.pointer.press_origin());
        let interact_pos = response.interact_pointer_pos();
        if response.drag_started_by(egui::PointerButton::Primary)
            && !input.shift_held
            && input.touch_count < 2
            && let Some(origin) = press_origin
        {
            if let Some(handle) = self.pick_handle(origin) {
                self.model.apply(Command::BeginHandle(handle));
            } else if let Some((joint, point_world)) = self.pick(origin) {
                self.model.apply(Command::BeginPull { joint, point_world });
            }
        }
        let dragging = response.dragged() && input.touch_count < 2;
        match (self.model.gesture().cloned(), interact_pos) {
            (Some(gesture), Some(pointer)) if dragging => self.drag_gesture(&gesture, pointer),
            (Some(_), _) => self.model.apply(Command::EndGesture),
            (None, _) => {
                if apply_gestures(
                    &mut self.camera,
                    &input.gestures(),
                    self.viewport_rect.height(),
                ) {
                    ui.ctx().request_repaint();
                }
            }
        }
        let hovered = if self.model.gesture().is_some() {
            None
        } else {
            pointer.and_then(|pointer| self.pick(pointer).map(|(joint, _)| joint))
        };
        self.model.apply(Command::Hover(hovered));
        if response.clicked_by(egui::PointerButton::Primary) {
            let clicked =
                interact_pos.and_then(|pointer| self.pick(pointer).map(|(joint, _)| joint));
            self.model.apply(Command::Select(clicked));
            // The pin tool (or Alt + click): one click pins the part where it is.
            let alt = ui.input(|input| input.modifiers.alt);
            if let Some(joint) = clicked
                && (self.pin_tool || alt)
            {
                self.model.apply(Command::Pin(joint));
            }
        }
    }

    /// The pointer moved during `gesture`: the command that follows it.
    fn drag_gesture(&mut self, gesture: &Gesture, pointer: egui::Pos2) {
        let command = match gesture {
            Gesture::Pull {
                plane_point_world, ..
            } => self
                .pointer_on_view_plane(pointer, *plane_point_world)
                .map(|target_world| Command::MoveGrab { target_world }),
            Gesture::Goal {
                plane_point_world, ..
            } => self
                .pointer_on_view_plane(pointer, *plane_point_world)
                .map(|goal_world| Command::MoveGoal {
                    goal_world,
                    floor_world: self.pointer_on_floor(pointer),
                }),
            Gesture::Ring { centre_px, .. } => Some(Command::TurnRing {
                screen_angle: handles::screen_angle(
                    egui::pos2(centre_px[0], centre_px[1]),
                    pointer,
                ),
            }),
            Gesture::Swivel {
                centre_world,
                axis_world,
                ..
            } => self
                .pointer_around_axis(pointer, *centre_world, *axis_world)
                .map(|point_world| Command::TurnSwivel { point_world }),
        };
        if let Some(command) = command {
            self.model.apply(command);
        }
    }

    /// Right-click on the body: pin, select, add a task on that part.
    fn viewport_context_menu(&mut self, response: &egui::Response) {
        let context_joint = self.model.hovered_joint().or(self.model.selected_joint());
        response.context_menu(|ui| match context_joint {
            Some(joint) => {
                let name = self
                    .model
                    .session
                    .skeleton()
                    .joints()
                    .get(joint)
                    .map(|joint| readable_name(&joint.name))
                    .unwrap_or_default();
                ui.label(RichText::new(&name).strong());
                if ui.button("Pin here (level 1)").clicked() {
                    self.model.apply(Command::Pin(joint));
                    ui.close();
                }
                if ui.button("Select").clicked() {
                    self.model.apply(Command::Select(Some(joint)));
                    ui.close();
                }
                ui.separator();
                if ui.button("Add position task").clicked() {
                    self.model.apply(Command::Select(Some(joint)));
                    self.add_position_task(joint);
                    ui.close();
                }
                if ui.button("Add orientation task").clicked() {
                    self.model.apply(Command::Select(Some(joint)));
                    self.add_orientation_task(joint);
                    ui.close();
                }
                if let Some(limb) = self
                    .model
                    .session
                    .skeleton()
                    .joints()
                    .get(joint)
                    .and_then(|definition| LimbName::of_joint(&definition.name))
                    && ui.button("Add limb task (with swivel)").clicked()
                {
                    self.model.apply(Command::Select(Some(joint)));
                    self.add_limb_task(limb);
                    ui.close();
                }
            }
            None => {
                ui.label("Right-click a body part to pin it.");
            }
        });
    }

    /// The 3D picture of this frame's posture.
    fn draw_viewport(&mut self, ui: &mut egui::Ui, frame: &eframe::Frame, rect: egui::Rect) {
        let pixels_per_point = ui.ctx().pixels_per_point();
        let size_px = [
            (rect.width() * pixels_per_point).round().max(1.0) as u32,
            (rect.height() * pixels_per_point).round().max(1.0) as u32,
        ];
        self.viewport_size_px = size_px;
        if let (Some(renderer), Some(render_state)) =
            (&mut self.renderer, frame.wgpu_render_state())
            && let Some(model) = self
                .model
                .avatar
                .as_mut()
                .and_then(|avatar| avatar.model.take())
        {
            renderer.set_avatar(render_state, Some(&model));
            self.avatar_uploaded = true;
        }
        if self.model.avatar().is_none() && self.avatar_uploaded {
            self.avatar_uploaded = false;
        }
        let scene_started = web_time::Instant::now();
        let scene = self.scene();
        self.scene_ms = scene_started.elapsed().as_secs_f64() * 1000.0;
        match (&mut self.renderer, frame.wgpu_render_state()) {
            (Some(renderer), Some(render_state)) => {
                let render_started = web_time::Instant::now();
                let texture_id = renderer.render(render_state, size_px, &self.camera, &scene);
                self.render_ms = render_started.elapsed().as_secs_f64() * 1000.0;
                let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
                ui.painter().image(texture_id, rect, uv, Color32::WHITE);
                if !self.first_frame_reported {
                    self.first_frame_reported = true;
                    if let Some(backend) = &self.backend {
                        self.model.hooks.first_frame_rendered(backend);
                    }
                }
            }
            _ => {
                ui.painter().text(
                    rect.center(),
                    egui::Align2::CENTER_CENTER,
                    "The 3D view needs WebGPU or WebGL2, and neither could start.",
                    egui::FontId::proportional(16.0),
                    Color32::LIGHT_RED,
                );
            }
        }
    }

    fn scene(&self) -> Scene {
        let capsules = self
            .model
            .bones()
            .iter()
            .map(|bone| {
                let mut capsule = bone.capsule;
                capsule.color_linear = if Some(bone.owner) == self.model.selected_joint() {
                    SELECTED_COLOR_LINEAR
                } else if Some(bone.owner) == self.model.hovered_joint() {
                    HOVERED_COLOR_LINEAR
                } else {
                    BODY_COLOR_LINEAR
                };
                capsule
            })
            .collect();
        let session = self.model.session();
        let avatar_palettes = self
            .model
            .avatar()
            .and_then(|avatar| avatar.palettes(session.humanoid(), session.posture()))
            .unwrap_or_default();
        let show_avatar = self.model.avatar().is_some() && self.avatar_uploaded;
        Scene {
            // With an avatar the mannequin is hidden; the skeleton overlay shows the bones.
            capsules: if show_avatar { Vec::new() } else { capsules },
            show_floor: self.show_floor,
            show_avatar,
            avatar_palettes,
        }
    }

    fn help_window(&mut self, ctx: &egui::Context) {
        egui::Window::new("Controls and shortcuts")
            .open(&mut self.show_help)
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

    /// The editor's observable state as JSON: the document, joint positions in the world and
    /// on screen (CSS pixels), per-task statuses, the notice, and the rectangles of the main
    /// buttons. The page's test hook and scripts read it.
    pub fn state_json(&self) -> String {
        let skeleton = self.model.session.skeleton();
        let frames = self.model.session.frames();
        let rect = self.viewport_rect;
        let mut joints = Map::new();
        let mut screen = Map::new();
        for (index, joint) in skeleton.joints().iter().enumerate() {
            let Some(position) = frames.joint_position.get(index) else {
                continue;
            };
            joints.insert(
                joint.name.clone(),
                json!([position.x, position.y, position.z]),
            );
            if rect.is_positive()
                && let Some(pixel) = self
                    .camera
                    .project(position.as_vec3(), Vec2::new(rect.width(), rect.height()))
            {
                screen.insert(
                    joint.name.clone(),
                    json!([rect.min.x + pixel.x, rect.min.y + pixel.y]),
                );
            }
        }
        let tasks: Vec<Value> = self
            .model
            .session
            .tasks()
            .iter()
            .zip(self.model.session.statuses())
            .map(|(task, status)| {
                json!({
                    "description": crate::posing::describe_task(task),
                    "level": task.level,
                    "active": task.active,
                    "residual": status.residual,
                    "gave_way": status.gave_way,
                    "problem": status.problem,
                })
            })
            .collect();
        let buttons: Map<String, Value> = self
            .button_rects
            .iter()
            .map(|(name, rect)| {
                (
                    (*name).to_owned(),
                    json!([rect.min.x, rect.min.y, rect.width(), rect.height()]),
                )
            })
            .collect();
        let document = serde_json::from_str::<Value>(&self.model.session.document().to_json(false))
            .unwrap_or(Value::Null);
        let goals: Vec<Value> = self
            .goal_handles()
            .into_iter()
            .filter_map(|(task, goal)| {
                let pixel = self.to_screen(rect, goal)?;
                Some(json!({"task": task, "screen": [pixel.x, pixel.y]}))
            })
            .collect();
        let rings: Vec<Value> = self
            .rings()
            .iter()
            .filter_map(|ring| {
                let point = self.ring_points(rect, ring).first().copied()?;
                let centre = self.to_screen(rect, ring.centre_world)?;
                Some(json!({
                    "dof": skeleton.dof_name(ring.dof),
                    "index": ring.dof,
                    "value": self.model.session.posture().values().get(ring.dof),
                    "screen": [point.x, point.y],
                    "centre": [centre.x, centre.y],
                }))
            })
            .collect();
        json!({
            "revision": self.model.session.revision(),
            "settled": self.model.session.is_settled(),
            "loa": self.model.session.level_of_articulation().number(),
            "document": document,
            "joints": joints,
            "screen": screen,
            "tasks": tasks,
            "gave_way": self.model.session.report().and_then(|report| report.gave_way),
            "notice": self.model.notice.as_ref().map(|notice| json!({"text": notice.text, "error": notice.is_error})),
            "avatar": self.model.avatar.as_ref().map(|avatar| json!({
                "name": avatar.name,
                "vertices": avatar.vertex_count,
                "triangles": avatar.triangle_count,
                "uploaded": self.avatar_uploaded,
                "mapped": avatar.mapping_summary().0,
            })),
            "selected": self.model.selected_joint.and_then(|joint| skeleton.joints().get(joint)).map(|joint| joint.name.clone()),
            "pulling": self.model.is_pulling(),
            "dragging_handle": self.model.gesture().is_some() && !self.model.is_pulling(),
            "undo_steps": self.model.history.undo_steps(),
            "can_redo": self.model.history.can_redo(),
            "library": self.model.library.entries().iter().map(|entry| entry.name.clone()).collect::<Vec<_>>(),
            "solver_ms": self.model.solver_ms,
            "frame_ms": self.frame_ms,
            "scene_ms": self.scene_ms,
            "render_ms": self.render_ms,
            "wasm_memory_bytes": wasm_memory_bytes(),
            "viewport": [rect.min.x, rect.min.y, rect.width(), rect.height()],
            "buttons": buttons,
            "goals": goals,
            "rings": rings,
            "sensors": self.sensors_state_json(),
            "swivel": self.swivel_state(rect),
        })
        .to_string()
    }

    /// Draws the whole editor into `ui` (shared by eframe and the UI tests).
    pub fn show(&mut self, ui: &mut egui::Ui, frame: &eframe::Frame) {
        let ctx = ui.ctx().clone();
        self.button_rects.clear();
        self.drain_inbox();
        self.shortcuts(&ctx);
        // The frame's step runs before anything is drawn: the panels and the viewport show
        // this frame's posture and statuses. Gestures read below are solved by the next step.
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
        egui::Panel::left("side_panel")
            .resizable(true)
            .default_size(230.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| self.side_panel(ui));
            });
        egui::Panel::right("tasks_panel")
            .resizable(true)
            .default_size(330.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| self.tasks_panel(ui));
            });
        egui::CentralPanel::default()
            .frame(egui::Frame::NONE)
            .show(ui, |ui| self.viewport(ui, frame));
        self.help_window(&ctx);
        self.sensors_window(&ctx);
        self.mapping_window(&ctx);
        if let Some(cpu_seconds) = frame.info().cpu_usage {
            self.frame_ms = f64::from(cpu_seconds) * 1000.0;
        }
    }
}

/// Where the ray `origin + t direction` (t > 0) meets the plane through `plane_point` with
/// `normal`; `None` when the ray is within `min_cosine` of parallel to it or points away.
fn ray_meets_plane(
    origin: DVec3,
    direction: DVec3,
    plane_point: DVec3,
    normal: DVec3,
    min_cosine: f64,
) -> Option<DVec3> {
    let denominator = direction.dot(normal);
    if denominator.abs() < min_cosine {
        return None;
    }
    let distance = (plane_point - origin).dot(normal) / denominator;
    (distance > 0.0 && distance.is_finite()).then(|| origin + direction * distance)
}

/// The WebAssembly memory the editor holds (bytes); `None` natively.
fn wasm_memory_bytes() -> Option<u64> {
    #[cfg(target_arch = "wasm32")]
    {
        Some(core::arch::wasm32::memory_size::<0>() as u64 * 65_536)
    }
    #[cfg(not(target_arch = "wasm32"))]
    {
        None
    }
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
    ("Double click, F", "frame the body again"),
    ("Ctrl+Z", "undo"),
    ("Ctrl+Shift+Z, Ctrl+Y", "redo"),
    ("P", "pin the selected part"),
    ("M", "mirror the posture left/right"),
    ("R", "reset to the rest pose (tasks kept)"),
    ("L", "copy the posture link"),
    ("T", "show or hide the effector trace"),
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
