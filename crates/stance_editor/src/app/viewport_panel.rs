//! The 3D viewport: the camera, the pointer's gestures as commands to the model (pull, handles,
//! selection, the context menu), and the picture of the model's posture with its overlays.

use crate::model::Outbox;
use crate::model::{GestureCommand, PostureCommand, SceneCommand, TaskCommand, ViewCommand};
use egui::{Color32, RichText, Sense};
use glam::{DAffine3, DVec3};
use stance_document::CameraSpec;
use stance_hanim::{LimbName, readable_name};
use stance_render::{BODY_COLOR_LINEAR, OrbitCamera, Scene, ViewPreset, pick_capsule};

use super::handles::Handles;
use super::lens::Lens;
use super::overlay::Overlay;
use super::prop_gizmo::{PropGizmo, pick_prop};
use crate::cast_models::{CastModels, ModelKey};
use crate::cast_view::{
    mesh_prop_instances, pick_other, placed_capsule, placed_palettes, prop_instances,
    scene_from_character,
};
use crate::image::ImageExport;
use crate::model::{AvatarCommand, Command, EditorModel, NewBetween, NewTask, heat_color};
use crate::viewport::{ViewportInput, ViewportRenderer, apply_gestures};
use stance_model::BackendSummary;

/// The most a frame (or a host task) spends uploading an avatar, in ms, and the most texture
/// bytes it writes (see `upload_meshes`): more would wait for the GPU process to drain the
/// command buffer's transfer memory (WebGL in Chromium), in the frame.
const UPLOAD_MS_PER_SHARE: f64 = 12.0;
const UPLOAD_STEPS_PER_SHARE: usize = (8 << 20) / stance_render::UPLOAD_STEP_BYTES;
/// The most a host task spends uploading: its writes are submitted step by step (4 MB each), so
/// the GPU process drains them as they come and the task's time is what it costs.
const UPLOAD_MS_PER_TASK: f64 = 16.0;
/// While the host steps an avatar's upload in its own tasks, a frame every so often steps it
/// too (should the host stop), in seconds.
const UPLOAD_FALLBACK_S: f32 = 0.5;
/// Colour of the selected body part (linear RGB).
const SELECTED_COLOR_LINEAR: [f32; 4] = [0.15, 0.45, 0.85, 1.0];
/// Colour of the body part under the cursor (linear RGB).
const HOVERED_COLOR_LINEAR: [f32; 4] = [0.85, 0.45, 0.22, 1.0];

/// The viewport: camera, display options, the GPU renderer and this frame's figures.
pub(super) struct ViewportPanel {
    pub camera: OrbitCamera,
    /// The selected character's placement in the scene, as of this frame's input.
    scene_from_character: DAffine3,
    /// The viewport's rectangle this frame (points).
    pub rect: egui::Rect,
    /// Its size in physical pixels.
    pub size_px: [u32; 2],
    pub show_floor: bool,
    pub show_trace: bool,
    pub show_skeleton: bool,
    /// A left click on the body pins it (touch-friendly one-click pin).
    pub pin_tool: bool,
    pub backend: Option<BackendSummary>,
    renderer: Option<ViewportRenderer>,
    /// eframe's wgpu device and queue, for the uploads the host steps between frames.
    render_state: Option<egui_wgpu::RenderState>,
    /// The host steps the avatar's upload under way in tasks of its own
    /// ([`HostHooks::upload_in_tasks`](crate::HostHooks::upload_in_tasks)), not the frames.
    upload_in_tasks: bool,
    /// The avatar's upload finished since the last frame.
    upload_finished: bool,
    /// Whether the loaded avatar's mesh is on the GPU.
    pub avatar_uploaded: bool,
    /// How long the avatar's upload to the GPU took (ms).
    pub avatar_upload_ms: f64,
    /// How many shares of it the host stepped between frames.
    pub avatar_upload_tasks: usize,
    /// The mannequin drawn as a skinned figure (else as capsules).
    pub show_figure: bool,
    /// Which GPU model is where: the selected character's in the renderer's avatar place, the
    /// other characters' among the cast's, and the figures that pose those on the mannequin.
    cast: CastModels,
    first_frame_reported: bool,
    /// CPU time of this frame's scene (mannequin capsules, or the avatar's skinning palettes).
    pub scene_ms: f64,
    /// CPU time of recording and submitting this frame's 3D draw (uploads included).
    pub render_ms: f64,
    /// The model's view request last followed (see `EditorModel::view_request`).
    view_request: u64,
    /// *Save image*: asked, rendering on this viewport's GPU, handed to the model.
    pub image: ImageExport,
    /// The selected prop, its gizmo and the drag on a prop under way.
    pub(super) props: PropGizmo,
    /// The reference photo's texture (*File > Open photo*), by the photo's id.
    photo_texture: Option<(u64, egui::TextureHandle)>,
    /// Where the photo was drawn this frame (points), when it was.
    pub photo_rect: Option<egui::Rect>,
}

impl ViewportPanel {
    /// A viewport with the floor and the trace shown, drawing with eframe's wgpu
    /// `render_state` (none: the viewport says why it is empty).
    pub(super) fn new(render_state: Option<&egui_wgpu::RenderState>) -> Self {
        let backend = render_state.map(|state| backend_summary(&state.adapter.get_info()));
        let renderer = render_state.map(|state| ViewportRenderer::new(&state.device));
        Self {
            camera: OrbitCamera::default(),
            scene_from_character: DAffine3::IDENTITY,
            rect: egui::Rect::NOTHING,
            size_px: [0, 0],
            show_floor: true,
            show_trace: true,
            show_skeleton: false,
            pin_tool: false,
            backend,
            renderer,
            render_state: render_state.cloned(),
            upload_in_tasks: false,
            upload_finished: false,
            avatar_uploaded: false,
            avatar_upload_ms: 0.0,
            avatar_upload_tasks: 0,
            show_figure: true,
            cast: CastModels::default(),
            first_frame_reported: false,
            scene_ms: 0.0,
            render_ms: 0.0,
            view_request: 0,
            image: ImageExport::default(),
            props: PropGizmo::default(),
            photo_texture: None,
            photo_rect: None,
        }
    }

    /// Turns to a standard view.
    pub(super) fn set_view(&mut self, preset: ViewPreset) {
        self.camera.set_view(preset);
    }

    /// Looks from the other side (Blender's numpad 9).
    pub(super) fn opposite_view(&mut self) {
        self.camera.yaw =
            (self.camera.yaw + std::f32::consts::PI).rem_euclid(std::f32::consts::TAU);
        self.camera.pitch = -self.camera.pitch;
    }

    /// Frames the joints of the whole body, or of the selected part and what it carries.
    pub(super) fn frame(&mut self, model: &EditorModel, selection_only: bool) {
        let session = model.session();
        let skeleton = session.skeleton();
        let positions = &session.frames().joint_position;
        let chosen = model.selected_joint().filter(|_| selection_only);
        let points: Vec<DVec3> = (0..skeleton.joint_count())
            .filter(|&j| chosen.is_none_or(|s| skeleton.is_ancestor_or_self(s, j)))
            .filter_map(|j| positions.get(j).copied())
            .collect();
        let (Some(first), false) = (points.first(), points.is_empty()) else {
            return;
        };
        let (lo, hi) = points
            .iter()
            .fold((*first, *first), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
        let centre = (lo + hi) * 0.5;
        let radius = ((hi - lo).length() * 0.5).max(0.08);
        self.camera.frame(centre.as_vec3(), radius as f32);
    }

    /// The camera as a document saves it.
    pub(super) fn camera_spec(&self) -> CameraSpec {
        let c = &self.camera;
        CameraSpec {
            target: c.target_world.as_dvec3().to_array(),
            yaw: f64::from(c.yaw),
            pitch: f64::from(c.pitch),
            distance: f64::from(c.distance_m),
            orthographic: c.orthographic,
        }
    }

    /// A document's saved camera is shown when the model asks (a document with one was
    /// opened, or undo or redo changed it); otherwise the user moves the view freely.
    pub(super) fn follow_document_camera(&mut self, model: &EditorModel) {
        if model.view_request() == self.view_request {
            return;
        }
        self.view_request = model.view_request();
        if let Some(spec) = model.session().camera() {
            self.camera = OrbitCamera::saved(
                spec.target,
                spec.yaw,
                spec.pitch,
                spec.distance,
                spec.orthographic,
            );
        }
    }

    /// The current view saved with the document (undoable).
    pub(super) fn save_camera(&self, outbox: &mut Outbox) {
        outbox.send(Command::Posture(PostureCommand::SaveCamera(Some(
            self.camera_spec(),
        ))));
    }

    /// The camera looking through this frame's rectangle.
    pub(super) fn lens(&self) -> Lens<'_> {
        Lens {
            camera: &self.camera,
            rect: self.rect,
            scene_from_character: self.scene_from_character,
        }
    }

    /// The model's handles as this viewport shows them.
    pub(super) fn handles<'a>(&'a self, model: &'a EditorModel) -> Handles<'a> {
        Handles {
            model,
            lens: self.lens(),
        }
    }

    /// The viewport's input in `ui`'s remaining space: a gesture that starts, as a command
    /// to `model` (the app carries it out before [`Self::follow_pointer`] moves it). Returns
    /// the viewport's response and input.
    pub(super) fn read_input(
        &mut self,
        ui: &mut egui::Ui,
        model: &EditorModel,
        outbox: &mut Outbox,
    ) -> (egui::Response, ViewportInput) {
        let rect = ui.available_rect_before_wrap();
        self.rect = rect;
        self.scene_from_character = model.character().placement().scene_from_character();
        // A stable id: the notice strip above comes and goes (with its own widgets), and an
        // automatic id would change with it and end a drag in progress.
        ui.allocate_rect(rect, Sense::hover());
        let response = ui.interact(
            rect,
            egui::Id::unique("stance_viewport"),
            Sense::click_and_drag(),
        );
        let input = ViewportInput::read(ui, &response);
        self.begin_gesture(ui, &response, &input, model, outbox);
        (response, input)
    }

    /// The picture of the model's posture with its overlays, after [`Self::read_input`]
    /// (`response`): the body drawn follows the pointer read in the same frame.
    pub(super) fn show(
        &mut self,
        ui: &mut egui::Ui,
        frame: &eframe::Frame,
        model: &EditorModel,
        outbox: &mut Outbox,
        response: &egui::Response,
    ) {
        context_menu(response, model, outbox);
        if model.is_busy() {
            ui.ctx().request_repaint();
        }
        self.draw(ui, frame, model, outbox);
        self.advance_image(ui, frame, model, outbox);
        self.draw_overlays(ui, model, response.hover_pos());
    }

    /// Goals, the pulled point, the balance, the trace, the skeleton, rings and swivel; the
    /// cursor says what a drag would do.
    fn draw_overlays(&self, ui: &egui::Ui, model: &EditorModel, pointer: Option<egui::Pos2>) {
        let overlay = Overlay {
            model,
            lens: self.lens(),
            show_trace: self.show_trace,
        };
        overlay.draw(ui.painter());
        let clipped = ui.painter().with_clip_rect(self.rect);
        let covered = model.avatar().is_some() || self.figure_shown(model);
        if self.show_skeleton || (covered && model.selected_joint().is_some()) {
            overlay.draw_skeleton(&clipped);
        }
        let handles = self.handles(model);
        handles.draw_rings(&clipped);
        self.props.draw(&clipped, model, &self.lens());
        let gesture = model.gesture().is_some();
        let over_handle =
            !gesture && pointer.is_some_and(|pointer| handles.pick_handle(pointer).is_some());
        if gesture {
            ui.ctx().set_cursor_icon(egui::CursorIcon::Grabbing);
        } else if over_handle || model.hovered_joint().is_some() {
            ui.ctx().set_cursor_icon(egui::CursorIcon::Grab);
        }
    }

    /// The body part under `pointer` (on the bones drawn, as of the last step) and the point
    /// hit.
    pub(super) fn pick(&self, model: &EditorModel, pointer: egui::Pos2) -> Option<(usize, DVec3)> {
        if !self.rect.contains(pointer) {
            return None;
        }
        let (origin, direction) = self.lens().pointer_ray(pointer);
        let (origin, direction) = (origin.as_vec3(), direction.as_vec3());
        let bones = model.bones();
        let capsules: Vec<_> = bones.iter().map(|bone| bone.capsule).collect();
        let hit = pick_capsule(&capsules, origin, direction)?;
        let bone = bones.get(hit.index)?;
        Some((bone.owner, hit.point_world.as_dvec3()))
    }

    /// The character other than the selected one under `pointer`, nearer than the selected
    /// one's body there.
    pub(super) fn pick_other(&self, model: &EditorModel, pointer: egui::Pos2) -> Option<u64> {
        if !self.rect.contains(pointer) {
            return None;
        }
        let (origin, direction) = self.lens().pointer_scene_ray(pointer);
        let (origin, direction) = (origin.as_vec3(), direction.as_vec3());
        let (id, distance) = pick_other(model, origin, direction)?;
        let selected = self.pick(model, pointer).map(|(_, point_world)| {
            let point_scene = self.scene_from_character.transform_point3(point_world);
            (point_scene.as_vec3() - origin).length()
        });
        selected.is_none_or(|near| distance < near).then_some(id)
    }

    /// The pointer on the viewport, as commands: a drag with the primary button (no Shift,
    /// one finger) that starts on a handle (a task's goal, a ring or the swivel of the
    /// selected joint) moves it; on the body it pulls that point; elsewhere it moves the
    /// camera ([`Self::follow_pointer`]). A click selects (and with the pin tool or Alt pins).
    fn begin_gesture(
        &mut self,
        ui: &egui::Ui,
        response: &egui::Response,
        input: &ViewportInput,
        model: &EditorModel,
        outbox: &mut Outbox,
    ) {
        let press_origin = ui.input(|input| input.pointer.press_origin());
        if response.drag_started_by(egui::PointerButton::Primary)
            && !input.shift_held
            && input.touch_count < 2
            && let Some(origin) = press_origin
        {
            if let Some(handle) = self.handles(model).pick_handle(origin) {
                outbox.send(Command::Gesture(GestureCommand::BeginHandle(handle)));
                return;
            }
            let body = self.pick(model, origin);
            let (ray_origin, _) = self.lens().pointer_scene_ray(origin);
            let body_distance = body.map(|(_, point_world)| {
                (self.scene_from_character.transform_point3(point_world) - ray_origin).length()
            });
            let mut props = std::mem::take(&mut self.props);
            let began = props.begin(model, &self.lens(), origin, body_distance);
            self.props = props;
            if began {
                return;
            }
            if let Some((joint, point_world)) = body {
                outbox.send(Command::Gesture(GestureCommand::BeginPull {
                    joint,
                    point_world,
                }));
            }
        }
    }

    /// The pointer moves the gesture in progress (the app carries it out and solves it at
    /// once, before [`Self::show`] draws), or the camera; hover, click, select and pin.
    pub(super) fn follow_pointer(
        &mut self,
        ui: &egui::Ui,
        response: &egui::Response,
        input: &ViewportInput,
        model: &EditorModel,
        outbox: &mut Outbox,
    ) {
        let pointer = response.hover_pos();
        let interact_pos = response.interact_pointer_pos();
        let dragging = response.dragged() && input.touch_count < 2;
        if self.props.dragging() {
            let mut props = std::mem::take(&mut self.props);
            props.follow(&self.lens(), interact_pos.filter(|_| dragging), outbox);
            self.props = props;
            return;
        }
        match (model.gesture().cloned(), interact_pos) {
            (Some(gesture), Some(pointer)) if dragging => {
                if let Some(command) = self.lens().follow(&gesture, pointer) {
                    outbox.send(command);
                }
            }
            (Some(_), _) => outbox.send(Command::Gesture(GestureCommand::EndGesture)),
            (None, _) => {
                if apply_gestures(&mut self.camera, &input.gestures(), self.rect.height()) {
                    ui.ctx().request_repaint();
                }
            }
        }
        let hovered = if model.gesture().is_some() {
            None
        } else {
            pointer.and_then(|pointer| self.pick(model, pointer).map(|(joint, _)| joint))
        };
        outbox.send(Command::View(ViewCommand::Hover(hovered)));
        if response.clicked_by(egui::PointerButton::Primary) {
            let clicked =
                interact_pos.and_then(|pointer| self.pick(model, pointer).map(|(joint, _)| joint));
            // A click on another character selects it; on a prop, the prop (its gizmo shows).
            if clicked.is_none()
                && let Some(id) = interact_pos.and_then(|pointer| self.pick_other(model, pointer))
            {
                outbox.send(Command::Scene(SceneCommand::Select(id)));
                return;
            }
            let prop = interact_pos
                .filter(|_| clicked.is_none())
                .and_then(|pointer| {
                    let (origin, direction) = self.lens().pointer_scene_ray(pointer);
                    pick_prop(model, origin, direction).map(|(index, _)| index)
                });
            self.props.select(prop);
            if prop.is_some() {
                return;
            }
            outbox.send(Command::View(ViewCommand::Select(clicked)));
            // The pin tool (or Alt + click): one click pins the part where it is.
            let alt = ui.input(|input| input.modifiers.alt);
            if let Some(joint) = clicked
                && (self.pin_tool || alt)
            {
                outbox.send(Command::Posture(PostureCommand::Pin(joint)));
            }
        }
    }

    /// The 3D picture of this frame's posture.
    fn draw(
        &mut self,
        ui: &mut egui::Ui,
        frame: &eframe::Frame,
        model: &EditorModel,
        outbox: &mut Outbox,
    ) {
        let rect = self.rect;
        let pixels_per_point = ui.ctx().pixels_per_point();
        self.size_px = [
            (rect.width() * pixels_per_point).round().max(1.0) as u32,
            (rect.height() * pixels_per_point).round().max(1.0) as u32,
        ];
        let ctx = ui.ctx().clone();
        self.upload_meshes(&ctx, frame, model, outbox);
        let scene_started = web_time::Instant::now();
        let scene = self.scene(model);
        self.scene_ms = scene_started.elapsed().as_secs_f64() * 1000.0;
        self.draw_photo(ui, model);
        match (&mut self.renderer, frame.wgpu_render_state()) {
            (Some(renderer), Some(render_state)) => {
                let render_started = web_time::Instant::now();
                let texture_id = renderer.render(render_state, self.size_px, &self.camera, &scene);
                self.render_ms = render_started.elapsed().as_secs_f64() * 1000.0;
                let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
                ui.painter().image(texture_id, rect, uv, Color32::WHITE);
                if !self.first_frame_reported {
                    self.first_frame_reported = true;
                    if let Some(backend) = &self.backend {
                        model.hooks().first_frame_rendered(backend);
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

    /// The reference photo behind the picture (*File > Open photo*): its height spans the
    /// viewport's, as the lifted camera's vertical field of view spans the photo's, centred,
    /// so that through the lifted character's saved view the body lies on the person.
    fn draw_photo(&mut self, ui: &egui::Ui, model: &EditorModel) {
        self.photo_rect = None;
        let Some(photo) = model.photo().filter(|_| model.photo_shown()) else {
            return;
        };
        if self
            .photo_texture
            .as_ref()
            .is_none_or(|(id, _)| *id != photo.id)
        {
            let [width, height] = photo.reference_size_px;
            let image = egui::ColorImage::from_rgba_unmultiplied(
                [width as usize, height as usize],
                &photo.rgba,
            );
            let texture =
                ui.ctx()
                    .load_texture("reference-photo", image, egui::TextureOptions::LINEAR);
            self.photo_texture = Some((photo.id, texture));
        }
        let Some((_, texture)) = &self.photo_texture else {
            return;
        };
        let [width, height] = photo.size_px.map(|n| n.max(1) as f32);
        let size = egui::vec2(self.rect.height() * width / height, self.rect.height());
        let rect = egui::Rect::from_center_size(self.rect.center(), size);
        let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
        ui.painter()
            .with_clip_rect(self.rect)
            .image(texture.id(), rect, uv, Color32::WHITE);
        self.photo_rect = Some(rect);
    }

    /// Puts on the GPU what the characters are drawn with: the selected one's avatar, else the
    /// mannequin's figure, in the renderer's avatar place; the others' models beside it
    /// ([`CastModels`]). An avatar goes up a few MB of texture at a time, at most
    /// [`UPLOAD_MS_PER_SHARE`] a frame (or in the host's tasks), so that no frame carries the
    /// whole load; its body shows as capsules meanwhile. The others' models that are not on
    /// the GPU yet go up in the same steps, by the frames alone, in a frame whose share the
    /// selected avatar's upload did not take (see `crate::cast_models`).
    fn upload_meshes(
        &mut self,
        ctx: &egui::Context,
        frame: &eframe::Frame,
        model: &EditorModel,
        outbox: &mut Outbox,
    ) {
        let Some(render_state) = frame.wgpu_render_state() else {
            return;
        };
        if self.renderer.is_none() {
            return;
        }
        self.begin_avatar_upload(model, outbox);
        let selected_uploading = self
            .renderer
            .as_ref()
            .is_some_and(|r| r.is_uploading_avatar())
            && model.avatar().is_some();
        if selected_uploading {
            if self.upload_in_tasks {
                ctx.request_repaint_after(std::time::Duration::from_secs_f32(UPLOAD_FALLBACK_S));
            } else {
                ctx.request_repaint();
            }
            self.upload_share(false);
        }
        // Finished by this frame's share or by the host's tasks since the last frame.
        if std::mem::take(&mut self.upload_finished) {
            self.avatar_uploaded = true;
        }
        let Some(renderer) = &mut self.renderer else {
            return;
        };
        let renderer = renderer.scene_renderer_mut();
        let (device, queue) = (&render_state.device, &render_state.queue);
        if model.avatar().is_none() {
            // (An avatar's upload under way there goes on for the cast: `CastModels::update`.)
            self.avatar_uploaded = false;
        }
        if let Err(error) = self
            .cast
            .update(model, renderer, device, queue, self.show_figure)
        {
            log::warn!("the mannequin's figure could not be made: {error}");
            self.show_figure = false;
        }
        if !selected_uploading
            && self.cast.upload_share(
                renderer,
                device,
                queue,
                UPLOAD_STEPS_PER_SHARE,
                UPLOAD_MS_PER_SHARE,
            )
        {
            ctx.request_repaint();
        }
    }

    /// Begins the upload of a newly opened avatar's GPU model (the model hands it over once),
    /// or puts it in place at once where it is on the GPU already (another character's, or
    /// this one's when it was selected before: [`CastModels::begin_selected`]). Frames that
    /// repaint the canvas are slow to come while a large avatar arrives (a
    /// software-composited canvas is read back each time): the page steps the upload in tasks
    /// of its own where it can. Returns whether it does.
    pub(super) fn begin_avatar_upload(&mut self, model: &EditorModel, outbox: &mut Outbox) -> bool {
        let Some(renderer) = &mut self.renderer else {
            return false;
        };
        let Some(avatar) = model.avatar() else {
            return false;
        };
        let Some(mesh) = avatar.mesh().cloned() else {
            return false;
        };
        outbox.send(Command::Avatar(AvatarCommand::MeshTaken));
        self.avatar_uploaded = false;
        self.avatar_upload_ms = 0.0;
        self.avatar_upload_tasks = 0;
        let key = ModelKey::of_avatar(avatar);
        if !self
            .cast
            .begin_selected(renderer.scene_renderer_mut(), key, mesh)
        {
            // On the GPU already: drawn from the next frame, nothing to step.
            self.upload_in_tasks = false;
            self.upload_finished = true;
            return false;
        }
        self.upload_in_tasks = model.hooks().upload_in_tasks();
        self.upload_in_tasks
    }

    /// One share of the avatar's upload under way: a frame's ([`UPLOAD_MS_PER_SHARE`],
    /// [`UPLOAD_STEPS_PER_SHARE`]), or with `flush` a host task's ([`UPLOAD_MS_PER_TASK`]),
    /// which submits each step's writes (no frame submits them). Returns whether more is
    /// left.
    fn upload_share(&mut self, flush: bool) -> bool {
        let (Some(renderer), Some(render_state)) = (&mut self.renderer, &self.render_state) else {
            return false;
        };
        if !renderer.is_uploading_avatar() {
            return false;
        }
        if flush {
            self.avatar_upload_tasks += 1;
        }
        let started = web_time::Instant::now();
        let (most_steps, most_ms) = if flush {
            (usize::MAX, UPLOAD_MS_PER_TASK)
        } else {
            (UPLOAD_STEPS_PER_SHARE, UPLOAD_MS_PER_SHARE)
        };
        let mut done = false;
        let mut steps = 0;
        while !done && steps < most_steps && started.elapsed().as_secs_f64() * 1e3 < most_ms {
            done = renderer.continue_avatar_upload(render_state);
            if flush {
                render_state.queue.submit(std::iter::empty());
            }
            steps += 1;
        }
        self.avatar_upload_ms += started.elapsed().as_secs_f64() * 1e3;
        if done {
            self.upload_in_tasks = false;
            // Uploaded by a frame, or between frames: the next frame draws it.
            self.upload_finished = true;
        }
        !done
    }

    /// A share of the avatar's upload stepped by the host between frames (see
    /// [`HostHooks::upload_in_tasks`](crate::HostHooks::upload_in_tasks)): true while more is
    /// left; the caller asks for a frame once it is done.
    pub(super) fn upload_task(&mut self) -> bool {
        self.upload_share(true)
    }

    /// Whether the viewport draws with a GPU (images need one).
    pub(super) fn has_gpu(&self) -> bool {
        self.renderer.is_some()
    }

    /// *Save image* on this viewport's GPU (its renderer holds the avatar's mesh): the model
    /// renders an asked image and downloads it once the read-back completes, frames later.
    fn advance_image(
        &mut self,
        ui: &egui::Ui,
        frame: &eframe::Frame,
        model: &EditorModel,
        outbox: &mut Outbox,
    ) {
        if !self.image.is_busy() {
            return;
        }
        // The image draws the characters on the models the viewport holds, as it does.
        if let (Some(renderer), Some(render_state)) =
            (&mut self.renderer, frame.wgpu_render_state())
        {
            let queue = &render_state.queue;
            let renderer = renderer.scene_renderer_mut();
            let device = &render_state.device;
            if self
                .image
                .advance(model, outbox, device, queue, renderer, &self.cast)
            {
                ui.ctx().request_repaint();
            }
        }
    }

    /// Whether the mannequin is drawn as its figure this frame (not with an avatar, nor with
    /// the heat map, which colours the capsules, nor while the collision capsules are shown).
    pub(super) fn figure_shown(&self, model: &EditorModel) -> bool {
        self.show_figure
            && self.renderer.as_ref().is_some_and(|renderer| {
                self.cast
                    .selected_as_figure(model, renderer.scene_renderer())
            })
    }

    /// What the renderer draws: the selected character as the mannequin's figure, or its
    /// capsules (selection and hover coloured), or its avatar's skinning palettes once its
    /// mesh is on the GPU; the others each on its model ([`CastModels::others`]).
    fn scene(&self, model: &EditorModel) -> Scene {
        // The collision capsules shown on request: the body drawn as its capsules.
        let show_avatar =
            model.avatar().is_some() && self.avatar_uploaded && !model.show_capsules();
        let show_figure = self.figure_shown(model);
        // With an avatar or the figure the capsules are hidden; the skeleton overlay shows the
        // bones of a selection.
        let capsules = if show_avatar || show_figure {
            Vec::new()
        } else {
            self.selected_capsules(model)
        };
        let session = model.session();
        let place = scene_from_character(model.character());
        let avatar_palettes = match model.avatar() {
            Some(avatar) if show_avatar => avatar.palettes(session.humanoid(), session.posture()),
            None if show_figure => self
                .cast
                .figure(session.level_of_articulation())
                .and_then(|figure| figure.palettes(session.skeleton(), session.posture())),
            _ => None,
        }
        .map(|palettes| placed_palettes(palettes, place))
        .unwrap_or_default();
        let mut capsules: Vec<_> = capsules
            .into_iter()
            .map(|capsule| placed_capsule(capsule, place))
            .collect();
        let renderer = self.renderer.as_ref().map(ViewportRenderer::scene_renderer);
        let others = self.cast.others(model, renderer);
        capsules.extend(others.capsules);
        // Over the reference photo: no background, floor or shadows, which would cover it.
        let photo = model.photo_shown();
        Scene {
            props: prop_instances(model),
            mesh_props: mesh_prop_instances(model),
            shadows: if photo {
                Vec::new()
            } else {
                crate::cast_view::contact_shadows(model)
            },
            capsules,
            show_floor: self.show_floor && !photo,
            transparent_background: photo,
            show_avatar: show_avatar || show_figure || !others.more_avatar_poses.is_empty(),
            avatar_palettes,
            more_avatar_poses: others.more_avatar_poses,
            cast_poses: others.cast_poses,
            ..Scene::default()
        }
    }

    /// The selected character's capsules in its own frame, coloured by selection, hover and
    /// the heat map.
    fn selected_capsules(&self, model: &EditorModel) -> Vec<stance_render::Capsule> {
        let heat = model.comfort().heat_shares(model.session().skeleton());
        model
            .bones()
            .iter()
            .map(|bone| {
                let mut capsule = bone.capsule;
                capsule.color_linear = if Some(bone.owner) == model.selected_joint() {
                    SELECTED_COLOR_LINEAR
                } else if Some(bone.owner) == model.hovered_joint() {
                    HOVERED_COLOR_LINEAR
                } else if let Some(share) = heat.as_ref().and_then(|h| h.get(bone.owner)) {
                    heat_color(*share, BODY_COLOR_LINEAR)
                } else {
                    BODY_COLOR_LINEAR
                };
                capsule
            })
            .collect()
    }
}

/// The parts of another character a part of the selected one can meet from the body's menu.
const MEETING_PARTS: [&str; 7] = [
    "l_radiocarpal",
    "r_radiocarpal",
    "l_shoulder",
    "r_shoulder",
    "l_elbow",
    "r_elbow",
    "skullbase",
];

/// Right-click on the body: pin, select, add a task on that part.
fn context_menu(response: &egui::Response, model: &EditorModel, outbox: &mut Outbox) {
    let context_joint = model.hovered_joint().or(model.selected_joint());
    response.context_menu(|ui| {
        let Some(joint) = context_joint else {
            ui.label("Right-click a body part to pin it.");
            return;
        };
        let name = model
            .session()
            .skeleton()
            .joints()
            .get(joint)
            .map(|definition| definition.name.clone())
            .unwrap_or_default();
        ui.label(RichText::new(readable_name(&name)).strong());
        let mut command = None;
        if ui.button("Pin here (level 1)").clicked() {
            command = Some(Command::Posture(PostureCommand::Pin(joint)));
        }
        if ui.button("Select").clicked() {
            command = Some(Command::View(ViewCommand::Select(Some(joint))));
        }
        ui.separator();
        if ui.button("Add position task").clicked() {
            command = Some(Command::Task(TaskCommand::Add(NewTask::Position(joint))));
        }
        if ui.button("Add orientation task").clicked() {
            command = Some(Command::Task(TaskCommand::Add(NewTask::Orientation(joint))));
        }
        if let Some(limb) = LimbName::of_joint(&name)
            && ui.button("Add limb task (with swivel)").clicked()
        {
            command = Some(Command::Task(TaskCommand::Add(NewTask::Limb(limb))));
        }
        // On a prop: a hand on a bar, a foot on a step, a hand on a ball or a table.
        if !model.props().is_empty() {
            ui.separator();
        }
        for (index, prop) in model.props().iter().enumerate() {
            if ui.button(format!("Put on {}", prop.name)).clicked() {
                command = Some(Command::Task(TaskCommand::AddOnProp { joint, prop: index }));
            }
        }
        // On another character: this part meets one of theirs (both posed together).
        for (other, selected) in model.characters() {
            if selected {
                continue;
            }
            ui.menu_button(format!("Meet {}'s", other.name()), |ui| {
                for part in MEETING_PARTS {
                    if ui.button(readable_name(part)).clicked() {
                        command = Some(Command::Scene(SceneCommand::AddBetween(NewBetween {
                            joint,
                            other: other.id(),
                            other_joint: (*part).to_owned(),
                        })));
                    }
                }
            });
        }
        if let Some(command) = command {
            if matches!(
                command,
                Command::Task(TaskCommand::Add(_) | TaskCommand::AddOnProp { .. })
            ) {
                outbox.send(Command::View(ViewCommand::Select(Some(joint))));
            }
            outbox.send(command);
            ui.close();
        }
    });
}

/// The backend and adapter `info` names, as the status bar says them.
fn backend_summary(info: &wgpu::AdapterInfo) -> BackendSummary {
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
    BackendSummary {
        backend: backend.to_owned(),
        adapter,
    }
}
