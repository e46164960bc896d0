//! The editor shell: menu bar, side panel, status bar and the viewport in the middle.

use egui::{Color32, RichText, Sense};
use stance_hanim::LevelOfArticulation;
use stance_render::{OrbitCamera, Scene, rest_pose_capsules};

use crate::viewport::{ViewportInput, ViewportRenderer, apply_gestures};

/// The graphics backend and adapter the viewport runs on, as the status bar names them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BackendSummary {
    /// "WebGPU", "WebGL2", "Vulkan", ...
    pub backend: String,
    /// The adapter's name as the driver reports it.
    pub adapter: String,
}

impl BackendSummary {
    fn from_adapter(info: &wgpu::AdapterInfo) -> Self {
        let backend = match info.backend {
            wgpu::Backend::BrowserWebGpu => "WebGPU",
            wgpu::Backend::Gl if cfg!(target_arch = "wasm32") => "WebGL2",
            wgpu::Backend::Gl => "OpenGL",
            wgpu::Backend::Vulkan => "Vulkan",
            wgpu::Backend::Metal => "Metal",
            wgpu::Backend::Dx12 => "DirectX 12",
            wgpu::Backend::Noop => "no GPU",
        };
        let adapter = if info.name.is_empty() {
            "unnamed adapter".to_owned()
        } else {
            info.name.clone()
        };
        Self {
            backend: backend.to_owned(),
            adapter,
        }
    }
}

/// What the host page (or the native shell) wants to hear from the editor.
pub trait HostHooks {
    /// Called once, after the first frame with the 3D scene has been rendered.
    fn first_frame_rendered(&self, backend: &BackendSummary);
}

/// Hooks that do nothing: the native shell and tests.
#[derive(Debug, Default)]
pub struct NoHostHooks;

impl HostHooks for NoHostHooks {
    fn first_frame_rendered(&self, _backend: &BackendSummary) {}
}

/// The Stance editor.
pub struct StanceApp {
    camera: OrbitCamera,
    level_of_articulation: LevelOfArticulation,
    show_floor: bool,
    show_controls_help: bool,
    backend: Option<BackendSummary>,
    renderer: Option<ViewportRenderer>,
    hooks: Box<dyn HostHooks>,
    first_frame_reported: bool,
    viewport_size_px: [u32; 2],
}

impl StanceApp {
    /// Creates the editor; GPU resources are made once here, from eframe's wgpu state.
    pub fn new(creation: &eframe::CreationContext<'_>, hooks: Box<dyn HostHooks>) -> Self {
        let render_state = creation.wgpu_render_state.as_ref();
        Self {
            backend: render_state
                .map(|state| BackendSummary::from_adapter(&state.adapter.get_info())),
            renderer: render_state.map(|state| ViewportRenderer::new(&state.device)),
            ..Self::without_gpu(hooks)
        }
    }

    /// The editor with no GPU: panels work, the viewport says why it is empty (tests).
    pub fn without_gpu(hooks: Box<dyn HostHooks>) -> Self {
        Self {
            camera: OrbitCamera::default(),
            level_of_articulation: LevelOfArticulation::Loa2,
            show_floor: true,
            show_controls_help: false,
            backend: None,
            renderer: None,
            hooks,
            first_frame_reported: false,
            viewport_size_px: [0, 0],
        }
    }

    pub fn camera(&self) -> &OrbitCamera {
        &self.camera
    }

    pub fn level_of_articulation(&self) -> LevelOfArticulation {
        self.level_of_articulation
    }

    fn scene(&self) -> Scene {
        Scene {
            capsules: rest_pose_capsules(self.level_of_articulation),
            show_floor: self.show_floor,
        }
    }

    fn menu_bar(&mut self, ui: &mut egui::Ui) {
        egui::MenuBar::new().ui(ui, |ui| {
            ui.label(RichText::new("Stance").strong());
            ui.separator();
            ui.menu_button("View", |ui| {
                ui.checkbox(&mut self.show_floor, "Floor grid");
                if ui.button("Frame the body").clicked() {
                    self.camera = OrbitCamera::default();
                    ui.close();
                }
                ui.separator();
                ui.label("Level of articulation");
                for loa in LevelOfArticulation::ALL {
                    ui.radio_value(
                        &mut self.level_of_articulation,
                        loa,
                        format!("LOA {}", loa.number()),
                    );
                }
            });
            ui.menu_button("Help", |ui| {
                if ui.button("Camera controls").clicked() {
                    self.show_controls_help = true;
                    ui.close();
                }
            });
        });
    }

    fn side_panel(&mut self, ui: &mut egui::Ui) {
        ui.heading("Humanoid");
        ui.label("H-Anim 2.0 default body");
        egui::ComboBox::from_label("Articulation")
            .selected_text(format!("LOA {}", self.level_of_articulation.number()))
            .show_ui(ui, |ui| {
                for loa in LevelOfArticulation::ALL {
                    ui.selectable_value(
                        &mut self.level_of_articulation,
                        loa,
                        format!("LOA {}", loa.number()),
                    );
                }
            });
        let joint_count = stance_hanim::humanoid_joints(self.level_of_articulation).len();
        ui.label(format!("{joint_count} joints"));
        ui.separator();
        ui.heading("Camera");
        egui::Grid::new("camera").num_columns(2).show(ui, |ui| {
            ui.label("Turn");
            let mut yaw_degrees = self.camera.yaw.to_degrees();
            if ui
                .add(
                    egui::DragValue::new(&mut yaw_degrees)
                        .suffix("°")
                        .speed(1.0),
                )
                .changed()
            {
                self.camera.yaw = yaw_degrees.to_radians().rem_euclid(std::f32::consts::TAU);
            }
            ui.end_row();
            ui.label("Tilt");
            let mut pitch_degrees = self.camera.pitch.to_degrees();
            if ui
                .add(
                    egui::DragValue::new(&mut pitch_degrees)
                        .suffix("°")
                        .range(-85.0..=85.0),
                )
                .changed()
            {
                self.camera.pitch = pitch_degrees.to_radians();
            }
            ui.end_row();
            ui.label("Distance");
            ui.add(
                egui::DragValue::new(&mut self.camera.distance_m)
                    .suffix(" m")
                    .speed(0.02)
                    .range(0.2..=60.0),
            );
            ui.end_row();
        });
        ui.checkbox(&mut self.show_floor, "Floor grid");
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
        });
    }

    fn viewport(&mut self, ui: &mut egui::Ui, frame: &eframe::Frame) {
        let rect = ui.available_rect_before_wrap();
        let response = ui.allocate_rect(rect, Sense::click_and_drag());
        let input = ViewportInput::read(ui, &response);
        if apply_gestures(&mut self.camera, &input.gestures(), rect.height()) {
            ui.ctx().request_repaint();
        }
        let pixels_per_point = ui.ctx().pixels_per_point();
        let size_px = [
            (rect.width() * pixels_per_point).round().max(1.0) as u32,
            (rect.height() * pixels_per_point).round().max(1.0) as u32,
        ];
        self.viewport_size_px = size_px;
        let scene = self.scene();
        match (&mut self.renderer, frame.wgpu_render_state()) {
            (Some(renderer), Some(render_state)) => {
                let texture_id = renderer.render(render_state, size_px, &self.camera, &scene);
                let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
                ui.painter().image(texture_id, rect, uv, Color32::WHITE);
                if !self.first_frame_reported {
                    self.first_frame_reported = true;
                    if let Some(backend) = &self.backend {
                        self.hooks.first_frame_rendered(backend);
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

    fn controls_help(&mut self, ctx: &egui::Context) {
        egui::Window::new("Camera controls")
            .open(&mut self.show_controls_help)
            .resizable(false)
            .collapsible(false)
            .show(ctx, |ui| {
                egui::Grid::new("controls").num_columns(2).show(ui, |ui| {
                    for (gesture, effect) in [
                        ("Left drag / one finger", "turn around the body"),
                        (
                            "Right or middle drag, Shift + left drag, two fingers",
                            "pan",
                        ),
                        ("Wheel / pinch / Ctrl + wheel", "zoom"),
                        ("Double click", "frame the body again"),
                    ] {
                        ui.label(RichText::new(gesture).strong());
                        ui.label(effect);
                        ui.end_row();
                    }
                });
            });
    }

    /// Draws the whole editor into `ui` (shared by eframe and the UI tests).
    pub fn show(&mut self, ui: &mut egui::Ui, frame: &eframe::Frame) {
        egui::Panel::top("menu_bar").show(ui, |ui| self.menu_bar(ui));
        egui::Panel::bottom("status_bar").show(ui, |ui| self.status_bar(ui, frame));
        egui::Panel::left("side_panel")
            .resizable(true)
            .default_size(220.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| self.side_panel(ui));
            });
        egui::CentralPanel::default()
            .frame(egui::Frame::NONE)
            .show(ui, |ui| self.viewport(ui, frame));
        let ctx = ui.ctx().clone();
        self.controls_help(&ctx);
    }
}

impl eframe::App for StanceApp {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        self.show(ui, frame);
    }
}
