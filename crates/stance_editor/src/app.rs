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
use glam::{DVec3, Vec2, Vec3};
use serde_json::{Map, Value, json};
use stance_document::{AvatarReference, Document, link};
use stance_hanim::LevelOfArticulation;
use stance_render::{
    BODY_COLOR_LINEAR, MannequinBone, MannequinJoint, OrbitCamera, Scene, mannequin_bones,
    pick_capsule,
};

use self::handles::HandleDrag;
use crate::avatar::LoadedAvatar;
use crate::history::{EditKind, History};
use crate::host::{BackendSummary, HostHooks, HostMessage};
use crate::library::{AUTOSAVE_KEY, LIBRARY_KEY, PoseLibrary};
use crate::posing::{PosingError, PosingSession, describe_joint};
use crate::sensors::SensorHub;
use crate::viewport::{ViewportInput, ViewportRenderer, apply_gestures};

/// Colour of the selected body part (linear RGB).
const SELECTED_COLOR_LINEAR: [f32; 4] = [0.15, 0.45, 0.85, 1.0];
/// Colour of the body part under the cursor (linear RGB).
const HOVERED_COLOR_LINEAR: [f32; 4] = [0.85, 0.45, 0.22, 1.0];
/// Seconds between autosaves while the document changes.
const AUTOSAVE_INTERVAL_SECS: f64 = 1.0;
/// Seconds an information notice stays (errors stay until dismissed).
const NOTICE_SECS: f64 = 8.0;
/// Points of the effector trace kept.
const MAX_TRACE_POINTS: usize = 2000;

/// A message for the user, shown above the viewport.
#[derive(Debug, Clone, PartialEq)]
pub struct Notice {
    pub text: String,
    pub is_error: bool,
    pub since_secs: f64,
}

/// A grab-and-pull in progress: the pulled point moves in the plane facing the camera
/// through `plane_point_world`.
#[derive(Debug, Clone)]
struct PullGesture {
    plane_point_world: DVec3,
    document_before: Document,
}

/// The Stance editor.
pub struct StanceApp {
    camera: OrbitCamera,
    show_floor: bool,
    show_help: bool,
    show_trace: bool,
    backend: Option<BackendSummary>,
    renderer: Option<ViewportRenderer>,
    hooks: Box<dyn HostHooks>,
    inbox: Option<Receiver<HostMessage>>,
    first_frame_reported: bool,
    viewport_size_px: [u32; 2],
    viewport_rect: egui::Rect,
    session: PosingSession,
    history: History,
    selected_joint: Option<usize>,
    hovered_joint: Option<usize>,
    pull: Option<PullGesture>,
    handle_drag: Option<HandleDrag>,
    avatar: Option<LoadedAvatar>,
    /// The URL the avatar came from (links and autosave name it); `None` for local files.
    avatar_url: Option<String>,
    /// A document waiting for its avatar to arrive (a link or autosave naming a URL).
    pending_document: Option<Document>,
    show_skeleton: bool,
    avatar_uploaded: bool,
    trace: Vec<DVec3>,
    notice: Option<Notice>,
    library: PoseLibrary,
    library_name: String,
    autosaved: Option<Document>,
    last_autosave_secs: f64,
    solver_ms: f64,
    frame_ms: f64,
    /// CPU time of this frame's scene (mannequin capsules, or the avatar's skinning palettes).
    scene_ms: f64,
    /// CPU time of recording and submitting this frame's 3D draw (uploads included).
    render_ms: f64,
    clock_origin: web_time::Instant,
    /// Screen rectangles (points) of named buttons, published for the page's test hook.
    button_rects: Vec<(&'static str, egui::Rect)>,
    sensors: SensorHub,
    show_sensors: bool,
    /// A left click on the body pins it (touch-friendly one-click pin).
    pin_tool: bool,
    /// The next picked file is a sensor recording to replay.
    replay_pick_pending: bool,
    mapping_editor: avatar_panel::MappingEditor,
}

impl std::fmt::Debug for StanceApp {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StanceApp")
            .field("session", &self.session)
            .field("selected_joint", &self.selected_joint)
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
        let session = PosingSession::new(LevelOfArticulation::Loa2)?;
        let mut app = Self {
            camera: OrbitCamera::default(),
            show_floor: true,
            show_help: false,
            show_trace: true,
            backend: None,
            renderer: None,
            hooks,
            inbox: None,
            first_frame_reported: false,
            viewport_size_px: [0, 0],
            viewport_rect: egui::Rect::NOTHING,
            session,
            history: History::default(),
            selected_joint: None,
            hovered_joint: None,
            pull: None,
            handle_drag: None,
            avatar: None,
            avatar_url: None,
            pending_document: None,
            show_skeleton: false,
            avatar_uploaded: false,
            trace: Vec::new(),
            notice: None,
            library: PoseLibrary::default(),
            library_name: String::new(),
            autosaved: None,
            last_autosave_secs: f64::NEG_INFINITY,
            solver_ms: 0.0,
            frame_ms: 0.0,
            scene_ms: 0.0,
            render_ms: 0.0,
            clock_origin: web_time::Instant::now(),
            button_rects: Vec::new(),
            sensors: SensorHub::default(),
            show_sensors: false,
            pin_tool: false,
            replay_pick_pending: false,
            mapping_editor: avatar_panel::MappingEditor::default(),
        };
        app.load_library();
        app.load_sensor_settings();
        Ok(app)
    }

    /// Messages from the host (links, files) arrive through this receiver.
    pub fn with_inbox(mut self, inbox: Receiver<HostMessage>) -> Self {
        self.inbox = Some(inbox);
        self
    }

    /// Opens what the page was opened with: a posture link when the address has one (a bad
    /// link says why and the editor opens normally), otherwise the autosaved work.
    pub fn open_startup(&mut self, link_fragment: Option<&str>) {
        let fragment = link_fragment
            .map(|fragment| fragment.trim_start_matches('#').trim())
            .filter(|fragment| !fragment.is_empty());
        if let Some(fragment) = fragment
            && self.open_link(fragment, 0.0)
        {
            return;
        }
        if let Some(text) = self.hooks.load_text(AUTOSAVE_KEY) {
            match Document::from_json(&text) {
                Ok(document) => {
                    if let AvatarReference::Url(url) = &document.avatar {
                        self.pending_document = Some(document.clone());
                        let url = url.clone();
                        self.fetch_avatar(&url);
                    }
                    if let Err(error) = self.session.restore_document(&document) {
                        self.warn(format!("The autosaved work could not be restored: {error}"));
                    } else {
                        self.autosaved = Some(document);
                    }
                }
                Err(error) => {
                    self.warn(format!("The autosaved work could not be read: {error}"));
                }
            }
        }
    }

    pub fn camera(&self) -> &OrbitCamera {
        &self.camera
    }

    pub fn level_of_articulation(&self) -> LevelOfArticulation {
        self.session.level_of_articulation()
    }

    pub fn session(&self) -> &PosingSession {
        &self.session
    }

    pub fn notice(&self) -> Option<&Notice> {
        self.notice.as_ref()
    }

    pub fn selected_joint(&self) -> Option<usize> {
        self.selected_joint
    }

    pub fn library(&self) -> &PoseLibrary {
        &self.library
    }

    /// The document: the session's posture and tasks, and the avatar they are for.
    pub fn document(&self) -> Document {
        let mut document = self.session.document();
        if let Some(url) = &self.avatar_url {
            document.avatar = AvatarReference::Url(url.clone());
        }
        document
    }

    pub fn avatar(&self) -> Option<&LoadedAvatar> {
        self.avatar.as_ref()
    }

    /// Loads an avatar file; on failure says why and keeps the current one.
    pub fn load_avatar(&mut self, name: &str, bytes: &[u8]) {
        let loa = self.session.level_of_articulation();
        let mut mapping_note = None;
        match LoadedAvatar::load(name, bytes, loa).and_then(|(mut avatar, mut humanoid)| {
            mapping_note = self.mapping_editor.reapply(&mut avatar, loa, &mut humanoid);
            let session =
                PosingSession::with_humanoid(humanoid).map_err(|error| error.to_string())?;
            Ok((avatar, session))
        }) {
            Ok((avatar, session)) => {
                let (mapped, unmapped) = avatar.mapping_summary();
                let mut text = format!(
                    "Loaded {name}: {} vertices, {mapped} joints mapped onto H-Anim ({unmapped} left unmapped); posed at LOA {}.",
                    avatar.vertex_count,
                    loa.number()
                );
                if !avatar.warnings.is_empty() {
                    text.push_str(&format!(" Notes: {}", avatar.warnings.join("; ")));
                }
                if let Some(note) = mapping_note {
                    text.push_str(&format!(" {note}"));
                }
                self.session = session;
                self.sensors.release();
                self.history = History::default();
                self.avatar = Some(avatar);
                self.avatar_url = is_url(name).then(|| name.to_owned());
                self.selected_joint = None;
                self.hovered_joint = None;
                self.pull = None;
                self.handle_drag = None;
                self.trace.clear();
                self.camera = OrbitCamera::default();
                self.inform(text);
                if let Some(document) = self.pending_document.take()
                    && let Err(error) = self.session.restore_document(&document)
                {
                    self.warn(format!("The posture does not fit this avatar: {error}"));
                }
            }
            Err(error) => {
                self.pending_document = None;
                self.warn(format!(
                    "{name} could not be opened as an avatar: {error}. The previous avatar stays."
                ));
            }
        }
    }

    /// Back to the built-in mannequin (the posture carries over by joint name).
    pub fn use_mannequin(&mut self) {
        let document = self.session.document();
        match PosingSession::new(self.session.level_of_articulation()) {
            Ok(mut session) => {
                if session.restore_document(&document).is_err() {
                    self.inform("The posture did not fit the mannequin; it stands at rest.");
                }
                self.session = session;
                self.sensors.release();
                self.history = History::default();
                self.avatar = None;
                self.avatar_url = None;
                self.avatar_uploaded = false;
                self.selected_joint = None;
            }
            Err(error) => self.warn(format!("The mannequin could not be built: {error}")),
        }
    }

    /// Asks the page to fetch an avatar by URL (it arrives as a file).
    fn fetch_avatar(&mut self, url: &str) {
        if let Err(error) = self.hooks.fetch(url) {
            self.pending_document = None;
            self.warn(format!("The avatar at {url} could not be fetched: {error}"));
        }
    }

    fn now_secs(&self) -> f64 {
        self.clock_origin.elapsed().as_secs_f64()
    }

    fn inform(&mut self, text: impl Into<String>) {
        self.notice = Some(Notice {
            text: text.into(),
            is_error: false,
            since_secs: self.now_secs(),
        });
    }

    fn warn(&mut self, text: impl Into<String>) {
        let text = text.into();
        log::warn!("{text}");
        self.notice = Some(Notice {
            text,
            is_error: true,
            since_secs: self.now_secs(),
        });
    }

    // -----------------------------------------------------------------------------------------
    // Edits: each one records the document before it, so that undo restores it exactly.

    fn record(&mut self, kind: EditKind) {
        let before = self.session.document();
        let now = self.now_secs();
        self.history.record(&before, kind, now);
    }

    /// Replaces the task list as one undoable edit of `kind`.
    fn commit_tasks(&mut self, kind: EditKind, tasks: Vec<stance_document::TaskSpec>) {
        if tasks.as_slice() != self.session.tasks() {
            self.record(kind);
            self.session.set_tasks(tasks);
        }
    }

    pub fn undo(&mut self) {
        self.cancel_pull_silently();
        let current = self.session.document();
        match self.history.undo(&current) {
            Some(previous) => self.restore(&previous, "undo"),
            None => self.inform("Nothing to undo."),
        }
    }

    pub fn redo(&mut self) {
        self.cancel_pull_silently();
        let current = self.session.document();
        match self.history.redo(&current) {
            Some(next) => self.restore(&next, "redo"),
            None => self.inform("Nothing to redo."),
        }
    }

    fn restore(&mut self, document: &Document, what: &str) {
        if let Err(error) = self.session.restore_document(document) {
            self.warn(format!("Could not {what}: {error}"));
        }
    }

    pub fn reset_to_rest(&mut self) {
        self.record(EditKind::Command);
        self.session.reset_to_rest();
        self.trace.clear();
    }

    pub fn mirror(&mut self) {
        self.record(EditKind::Command);
        self.session.mirror();
    }

    pub fn pin_selected(&mut self) {
        match self.selected_joint {
            Some(joint) => self.pin(joint),
            None => self.inform("Select a body part first (click it), then pin it."),
        }
    }

    fn pin(&mut self, joint: usize) {
        self.record(EditKind::Command);
        self.session.pin(joint);
        let name = self
            .session
            .skeleton()
            .joints()
            .get(joint)
            .map(|joint| describe_joint(&joint.name))
            .unwrap_or_default();
        self.inform(format!("Pinned the {name} where it is (level 1)."));
    }

    fn set_level_of_articulation(&mut self, loa: LevelOfArticulation) {
        if loa == self.session.level_of_articulation() {
            return;
        }
        let document = self.session.document();
        let built = match &self.avatar {
            Some(avatar) => avatar.skeleton(loa).and_then(|humanoid| {
                PosingSession::with_humanoid(humanoid).map_err(|e| e.to_string())
            }),
            None => PosingSession::new(loa).map_err(|error| error.to_string()),
        };
        match built.and_then(|mut session| {
            session
                .restore_document(&document)
                .map_err(|error| error.to_string())?;
            Ok(session)
        }) {
            Ok(session) => {
                self.record(EditKind::Command);
                self.session = session;
                self.sensors.release();
                self.selected_joint = None;
                self.hovered_joint = None;
                self.pull = None;
            }
            Err(error) => self.warn(format!("Could not switch to LOA {}: {error}", loa.number())),
        }
    }

    /// Opens a posture link (fragment or URL); on failure says why and changes nothing.
    /// Returns whether it opened.
    pub fn open_link(&mut self, link_text: &str, _now: f64) -> bool {
        match link::decode(link_text) {
            Ok(document) => {
                let current = self.session.document();
                match self.session.restore_document(&document) {
                    Ok(()) => {
                        self.history
                            .record(&current, EditKind::Command, self.now_secs());
                        self.selected_joint = None;
                        self.trace.clear();
                        match &document.avatar {
                            AvatarReference::Url(url) if self.avatar_url.as_ref() != Some(url) => {
                                self.inform(format!(
                                    "Opened the posture link; loading its avatar {url}…"
                                ));
                                self.pending_document = Some(document.clone());
                                let url = url.clone();
                                self.fetch_avatar(&url);
                            }
                            _ => self.inform("Opened the posture link."),
                        }
                        true
                    }
                    Err(error) => {
                        self.warn(format!(
                            "This posture link does not fit the humanoid: {error}. The editor opened normally."
                        ));
                        false
                    }
                }
            }
            Err(error) => {
                self.warn(format!(
                    "This posture link could not be opened: {error}. The editor opened normally."
                ));
                false
            }
        }
    }

    /// Encodes the document into the address bar and the clipboard.
    pub fn copy_link(&mut self, ctx: &egui::Context) {
        let fragment = link::encode(&self.document());
        let url = self.hooks.share_link(&fragment);
        ctx.copy_text(url);
        self.inform(format!(
            "Link copied to the clipboard ({} characters): opening it shows exactly this posture and these tasks.",
            fragment.len()
        ));
    }

    /// Opens a JSON file: a document (posture and tasks) or a pose library.
    pub fn open_file(&mut self, name: &str, bytes: &[u8]) {
        if std::mem::take(&mut self.replay_pick_pending) {
            self.replay_sensor_recording(name, bytes.to_vec());
            return;
        }
        let lower = name.to_ascii_lowercase();
        let is_avatar = [".glb", ".gltf", ".vrm"].iter().any(|extension| {
            lower
                .split(['?', '#'])
                .next()
                .unwrap_or("")
                .ends_with(extension)
        }) || bytes.starts_with(b"glTF");
        if is_avatar {
            self.load_avatar(name, bytes);
            return;
        }
        let Ok(text) = std::str::from_utf8(bytes) else {
            self.warn(format!("{name} is not a text (JSON) file."));
            return;
        };
        let is_library = serde_json::from_str::<Value>(text)
            .ok()
            .is_some_and(|value| value.get("entries").is_some());
        if is_library {
            match PoseLibrary::from_json(text) {
                Ok((imported, warnings)) => {
                    let mut added = 0;
                    for entry in imported.entries() {
                        if self
                            .library
                            .save(&entry.name, entry.document.clone())
                            .is_ok()
                        {
                            added += 1;
                        }
                    }
                    self.store_library();
                    if warnings.is_empty() {
                        self.inform(format!("Imported {added} poses from {name}."));
                    } else {
                        self.warn(format!(
                            "Imported {added} poses from {name}; skipped: {}",
                            warnings.join("; ")
                        ));
                    }
                }
                Err(error) => self.warn(format!("{name}: {error}")),
            }
            return;
        }
        match Document::from_json(text) {
            Ok(document) => {
                let current = self.session.document();
                match self.session.restore_document(&document) {
                    Ok(()) => {
                        self.history
                            .record(&current, EditKind::Command, self.now_secs());
                        self.inform(format!("Opened {name}."));
                    }
                    Err(error) => self.warn(format!("{name} does not fit the humanoid: {error}")),
                }
            }
            Err(error) => self.warn(format!("{name} is not a Stance document: {error}")),
        }
    }

    fn export_document(&mut self) {
        let text = self.document().to_json(true);
        if let Err(error) = self.hooks.download("stance-pose.json", &text) {
            self.warn(format!("Could not export the pose: {error}"));
        }
    }

    fn export_library(&mut self) {
        let text = self.library.to_json();
        if let Err(error) = self.hooks.download("stance-library.json", &text) {
            self.warn(format!("Could not export the library: {error}"));
        }
    }

    fn import_file(&mut self) {
        if let Err(error) = self.hooks.pick_file() {
            self.warn(format!("Could not open a file: {error}"));
        }
    }

    fn load_library(&mut self) {
        let Some(text) = self.hooks.load_text(LIBRARY_KEY) else {
            return;
        };
        match PoseLibrary::from_json(&text) {
            Ok((library, warnings)) => {
                self.library = library;
                if !warnings.is_empty() {
                    self.warn(format!(
                        "Some saved poses could not be read: {}",
                        warnings.join("; ")
                    ));
                }
            }
            Err(error) => self.warn(format!("The pose library could not be read: {error}")),
        }
    }

    fn store_library(&mut self) {
        if let Err(error) = self.hooks.save_text(LIBRARY_KEY, &self.library.to_json()) {
            self.warn(format!("The pose library could not be saved: {error}"));
        }
    }

    pub fn save_to_library(&mut self, name: &str) {
        match self.library.save(name, self.session.document()) {
            Ok(()) => {
                self.store_library();
                self.inform(format!("Saved the pose \"{}\".", name.trim()));
            }
            Err(error) => self.warn(error),
        }
    }

    fn load_from_library(&mut self, index: usize) {
        let Some(entry) = self.library.entries().get(index).cloned() else {
            return;
        };
        let current = self.session.document();
        match self.session.restore_document(&entry.document) {
            Ok(()) => {
                self.history
                    .record(&current, EditKind::Command, self.now_secs());
                self.inform(format!("Loaded the pose \"{}\".", entry.name));
            }
            Err(error) => self.warn(format!(
                "The pose \"{}\" does not fit the humanoid: {error}",
                entry.name
            )),
        }
    }

    fn autosave(&mut self) {
        let now = self.now_secs();
        if self.pull.is_some() || now - self.last_autosave_secs < AUTOSAVE_INTERVAL_SECS {
            return;
        }
        let document = self.document();
        if self.autosaved.as_ref() == Some(&document) {
            return;
        }
        self.last_autosave_secs = now;
        match self.hooks.save_text(AUTOSAVE_KEY, &document.to_json(false)) {
            Ok(()) => self.autosaved = Some(document),
            Err(error) => {
                // Say it once, not every second.
                if self.autosaved.is_some() || self.notice.is_none() {
                    self.warn(format!("Autosave failed: {error}"));
                }
                self.autosaved = Some(document);
            }
        }
    }

    fn drain_inbox(&mut self) {
        let messages: Vec<HostMessage> = match &self.inbox {
            Some(inbox) => inbox.try_iter().collect(),
            None => return,
        };
        for message in messages {
            match message {
                HostMessage::OpenLink(fragment) => {
                    let now = self.now_secs();
                    self.open_link(&fragment, now);
                }
                HostMessage::OpenFile { name, bytes } => self.open_file(&name, &bytes),
                HostMessage::Failed(reason) => {
                    self.replay_pick_pending = false;
                    self.warn(reason);
                }
                HostMessage::SensorConnected { device } => {
                    self.inform(format!("Sensors: {device} connected."));
                    self.sensors.connected(device);
                }
                HostMessage::SensorBytes { bytes, arrived } => {
                    let now = self.now_secs();
                    self.sensors.receive_bytes(&bytes, now, arrived);
                }
                HostMessage::SensorReport {
                    report_id,
                    data,
                    arrived,
                } => {
                    let now = self.now_secs();
                    self.sensors.receive_report(report_id, &data, now, arrived);
                }
                HostMessage::SensorLost { reason } => {
                    self.warn(format!(
                        "Sensors: {reason} The posture stays as the last reading left it."
                    ));
                    self.sensors.lost(reason);
                }
            }
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
            self.redo();
        } else if ctx.input_mut(|input| input.consume_shortcut(&undo)) {
            self.undo();
        }
        if ctx.egui_wants_keyboard_input() {
            return;
        }
        let plain = |key| KeyboardShortcut::new(Modifiers::NONE, key);
        if ctx.input_mut(|input| input.consume_shortcut(&plain(Key::P))) {
            self.pin_selected();
        }
        if ctx.input_mut(|input| input.consume_shortcut(&plain(Key::M))) {
            self.mirror();
        }
        if ctx.input_mut(|input| input.consume_shortcut(&plain(Key::R))) {
            self.reset_to_rest();
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
            if self.pull.is_some() {
                self.cancel_pull();
            } else {
                self.selected_joint = None;
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
                    self.fetch_avatar("default-avatar.glb");
                    ui.close();
                }
                if ui
                    .add_enabled(
                        self.avatar.is_some(),
                        egui::Button::new("Back to the mannequin"),
                    )
                    .clicked()
                {
                    self.use_mannequin();
                    ui.close();
                }
                ui.checkbox(&mut self.show_skeleton, "Show the skeleton");
            });
            ui.menu_button("Edit", |ui| {
                if ui
                    .add_enabled(
                        self.history.can_undo(),
                        egui::Button::new("Undo").shortcut_text("Ctrl+Z"),
                    )
                    .clicked()
                {
                    self.undo();
                    ui.close();
                }
                if ui
                    .add_enabled(
                        self.history.can_redo(),
                        egui::Button::new("Redo").shortcut_text("Ctrl+Shift+Z"),
                    )
                    .clicked()
                {
                    self.redo();
                    ui.close();
                }
                ui.separator();
                if ui
                    .add(egui::Button::new("Pin selected part").shortcut_text("P"))
                    .clicked()
                {
                    self.pin_selected();
                    ui.close();
                }
                if ui
                    .add(egui::Button::new("Mirror left/right").shortcut_text("M"))
                    .clicked()
                {
                    self.mirror();
                    ui.close();
                }
                if ui
                    .add(egui::Button::new("Reset to rest pose").shortcut_text("R"))
                    .clicked()
                {
                    self.reset_to_rest();
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
                let current = self.session.level_of_articulation();
                for loa in LevelOfArticulation::ALL {
                    if ui
                        .radio(current == loa, format!("LOA {}", loa.number()))
                        .clicked()
                    {
                        self.set_level_of_articulation(loa);
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
            ui.label(format!("solver {:.2} ms", self.solver_ms));
            if let Some(report) = self.session.report() {
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
        let now = self.now_secs();
        if let Some(notice) = &self.notice
            && !notice.is_error
            && now - notice.since_secs > NOTICE_SECS
        {
            self.notice = None;
        }
        let Some(notice) = self.notice.clone() else {
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
                        self.notice = None;
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

    /// The posed mannequin: one capsule per bone, with the joint that carries it.
    fn mannequin(&self) -> Vec<MannequinBone> {
        let skeleton = self.session.skeleton();
        let frames = self.session.frames();
        let joints: Vec<MannequinJoint<'_>> = skeleton
            .joints()
            .iter()
            .enumerate()
            .map(|(index, joint)| MannequinJoint {
                name: &joint.name,
                parent: joint.parent,
                position_world: frames
                    .joint_position
                    .get(index)
                    .copied()
                    .unwrap_or_default()
                    .as_vec3(),
                up_world: frames
                    .world_from_joint_rotation
                    .get(index)
                    .map_or(Vec3::Y, |rotation| (*rotation * DVec3::Y).as_vec3()),
            })
            .collect();
        mannequin_bones(&joints)
    }

    fn pick(&self, bones: &[MannequinBone], pointer: egui::Pos2) -> Option<(usize, DVec3)> {
        if !self.viewport_rect.contains(pointer) {
            return None;
        }
        let (origin, direction) = self.pointer_ray(pointer);
        let (origin, direction) = (origin.as_vec3(), direction.as_vec3());
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

    fn begin_pull(&mut self, joint: usize, point_world: DVec3) {
        let document_before = self.session.document();
        self.record(EditKind::Command);
        self.history.break_coalescing();
        self.session.begin_grab(joint, point_world);
        self.trace.clear();
        self.trace.push(point_world);
        self.selected_joint = Some(joint);
        self.pull = Some(PullGesture {
            plane_point_world: point_world,
            document_before,
        });
    }

    fn end_pull(&mut self) {
        if self.pull.take().is_some() {
            self.session.end_grab();
        }
    }

    /// Escape during a pull: the body goes back to where it was.
    fn cancel_pull(&mut self) {
        if let Some(pull) = self.pull.take() {
            self.session.end_grab();
            if let Err(error) = self.session.restore_document(&pull.document_before) {
                self.warn(format!("Could not cancel the pull: {error}"));
            }
        }
    }

    fn cancel_pull_silently(&mut self) {
        if self.pull.take().is_some() {
            self.session.end_grab();
        }
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
        let bones = self.mannequin();
        let pointer = response.hover_pos();
        let press_origin = ui.input(|input| input.pointer.press_origin());
        let interact_pos = response.interact_pointer_pos();

        // A drag with the primary button (no Shift, one finger) that starts on a handle (a
        // task's goal, a ring of the selected joint) moves it; on the body it pulls that
        // point; elsewhere it moves the camera.
        if response.drag_started_by(egui::PointerButton::Primary)
            && !input.shift_held
            && input.touch_count < 2
            && let Some(origin) = press_origin
        {
            if let Some(drag) = self.pick_handle(origin) {
                self.begin_handle_drag(drag);
            } else if let Some((joint, point_world)) = self.pick(&bones, origin) {
                self.begin_pull(joint, point_world);
            }
        }
        if self.handle_drag.is_some() {
            match interact_pos {
                Some(pointer) if response.dragged() && input.touch_count < 2 => {
                    self.drag_handle(pointer);
                }
                _ => self.end_handle_drag(),
            }
        } else if let Some(pull) = &self.pull {
            if response.dragged() && input.touch_count < 2 {
                if let Some(pointer) = interact_pos
                    && let Some(target) =
                        self.pointer_on_view_plane(pointer, pull.plane_point_world)
                {
                    self.session.move_grab(target);
                }
            } else {
                self.end_pull();
            }
        } else if apply_gestures(&mut self.camera, &input.gestures(), rect.height()) {
            ui.ctx().request_repaint();
        }

        self.hovered_joint = if self.pull.is_some() || self.handle_drag.is_some() {
            None
        } else {
            pointer.and_then(|pointer| self.pick(&bones, pointer).map(|(joint, _)| joint))
        };
        if response.clicked_by(egui::PointerButton::Primary) {
            let clicked =
                interact_pos.and_then(|pointer| self.pick(&bones, pointer).map(|(joint, _)| joint));
            self.selected_joint = clicked;
            // The pin tool (or Alt + click): one click pins the part where it is.
            let alt = ui.input(|input| input.modifiers.alt);
            if let Some(joint) = clicked
                && (self.pin_tool || alt)
            {
                self.pin(joint);
            }
        }
        let context_joint = self.hovered_joint.or(self.selected_joint);
        response.context_menu(|ui| match context_joint {
            Some(joint) => {
                let name = self
                    .session
                    .skeleton()
                    .joints()
                    .get(joint)
                    .map(|joint| describe_joint(&joint.name))
                    .unwrap_or_default();
                ui.label(RichText::new(&name).strong());
                if ui.button("Pin here (level 1)").clicked() {
                    self.selected_joint = Some(joint);
                    self.pin(joint);
                    ui.close();
                }
                if ui.button("Select").clicked() {
                    self.selected_joint = Some(joint);
                    ui.close();
                }
                ui.separator();
                if ui.button("Add position task").clicked() {
                    self.selected_joint = Some(joint);
                    self.add_position_task(joint);
                    ui.close();
                }
                if ui.button("Add orientation task").clicked() {
                    self.selected_joint = Some(joint);
                    self.add_orientation_task(joint);
                    ui.close();
                }
                if let Some(limb) = self
                    .session
                    .skeleton()
                    .joints()
                    .get(joint)
                    .and_then(|definition| panels::limb_of(&definition.name))
                    && ui.button("Add limb task (with swivel)").clicked()
                {
                    self.selected_joint = Some(joint);
                    self.add_limb_task(limb);
                    ui.close();
                }
            }
            None => {
                ui.label("Right-click a body part to pin it.");
            }
        });

        // Sensor readings drive their joints; the solver then moves the rest of the body.
        let sensors_drove = self.apply_sensors();
        // Solve this frame's iterations before drawing, so the picture shows this frame's pose.
        let started = web_time::Instant::now();
        let origin = self.clock_origin;
        let clock = move || origin.elapsed().as_secs_f64();
        self.session.solve_frame(Some(&clock));
        self.solver_ms = started.elapsed().as_secs_f64() * 1000.0;
        if let Some(point) = self.session.grabbed_point_world() {
            let moved = self
                .trace
                .last()
                .is_none_or(|last| (*last - point).length() > 0.002);
            if moved && self.trace.len() < MAX_TRACE_POINTS {
                self.trace.push(point);
            }
        }
        if !self.session.is_settled()
            || self.pull.is_some()
            || self.handle_drag.is_some()
            || self.sensors.replay_progress().is_some()
        {
            ui.ctx().request_repaint();
        }

        let pixels_per_point = ui.ctx().pixels_per_point();
        let size_px = [
            (rect.width() * pixels_per_point).round().max(1.0) as u32,
            (rect.height() * pixels_per_point).round().max(1.0) as u32,
        ];
        self.viewport_size_px = size_px;
        if let (Some(renderer), Some(render_state)) =
            (&mut self.renderer, frame.wgpu_render_state())
            && let Some(model) = self.avatar.as_mut().and_then(|avatar| avatar.model.take())
        {
            renderer.set_avatar(render_state, Some(&model));
            self.avatar_uploaded = true;
        }
        if self.avatar.is_none() && self.avatar_uploaded {
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
        if sensors_drove {
            self.sensors.shown();
        }
        self.draw_overlay(ui.painter(), rect);
        if self.show_skeleton || (self.avatar.is_some() && self.selected_joint.is_some()) {
            self.draw_skeleton(&ui.painter().with_clip_rect(rect), rect);
        }
        self.draw_rings(&ui.painter().with_clip_rect(rect), rect);
        let over_handle = self.pull.is_none()
            && self.handle_drag.is_none()
            && pointer.is_some_and(|pointer| self.pick_handle(pointer).is_some());
        if self.pull.is_some() || self.handle_drag.is_some() {
            ui.ctx().set_cursor_icon(egui::CursorIcon::Grabbing);
        } else if over_handle || self.hovered_joint.is_some() {
            ui.ctx().set_cursor_icon(egui::CursorIcon::Grab);
        }
    }

    fn scene(&self) -> Scene {
        let capsules = self
            .mannequin()
            .into_iter()
            .map(|bone| {
                let mut capsule = bone.capsule;
                capsule.color_linear = if Some(bone.owner) == self.selected_joint {
                    SELECTED_COLOR_LINEAR
                } else if Some(bone.owner) == self.hovered_joint {
                    HOVERED_COLOR_LINEAR
                } else {
                    BODY_COLOR_LINEAR
                };
                capsule
            })
            .collect();
        let avatar_palettes = self
            .avatar
            .as_ref()
            .and_then(|avatar| avatar.palettes(self.session.humanoid(), self.session.posture()))
            .unwrap_or_default();
        let show_avatar = self.avatar.is_some() && self.avatar_uploaded;
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
        let skeleton = self.session.skeleton();
        let frames = self.session.frames();
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
            .session
            .tasks()
            .iter()
            .zip(self.session.statuses())
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
        let document = serde_json::from_str::<Value>(&self.session.document().to_json(false))
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
                    "value": self.session.posture().values().get(ring.dof),
                    "screen": [point.x, point.y],
                    "centre": [centre.x, centre.y],
                }))
            })
            .collect();
        json!({
            "revision": self.session.revision(),
            "settled": self.session.is_settled(),
            "loa": self.session.level_of_articulation().number(),
            "document": document,
            "joints": joints,
            "screen": screen,
            "tasks": tasks,
            "gave_way": self.session.report().and_then(|report| report.gave_way),
            "notice": self.notice.as_ref().map(|notice| json!({"text": notice.text, "error": notice.is_error})),
            "avatar": self.avatar.as_ref().map(|avatar| json!({
                "name": avatar.name,
                "vertices": avatar.vertex_count,
                "triangles": avatar.triangle_count,
                "uploaded": self.avatar_uploaded,
                "mapped": avatar.mapping_summary().0,
            })),
            "selected": self.selected_joint.and_then(|joint| skeleton.joints().get(joint)).map(|joint| joint.name.clone()),
            "pulling": self.pull.is_some(),
            "dragging_handle": self.handle_drag.is_some(),
            "undo_steps": self.history.undo_steps(),
            "can_redo": self.history.can_redo(),
            "library": self.library.entries().iter().map(|entry| entry.name.clone()).collect::<Vec<_>>(),
            "solver_ms": self.solver_ms,
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
        self.autosave();
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

fn is_url(name: &str) -> bool {
    name.starts_with("http://")
        || name.starts_with("https://")
        || (!name.contains(['\\', ':']) && name.contains('/'))
        || name == "default-avatar.glb"
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
