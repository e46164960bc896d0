//! The editor's model, without egui: the posing session (posture, tasks, solver), the undo
//! history, the selection, the one gesture in progress, the avatar and its mapping
//! corrections, the pose library, the sensors, the notice and the autosave.
//!
//! The UI sends [`Command`]s; [`EditorModel::apply`] carries every one of them out in one
//! place (undo and redo included). [`EditorModel::step`] runs once per frame, before anything
//! is drawn: sensors, then the solve, then forward kinematics once, then the cached bones
//! (picking and drawing) and the effector trace. Panels and the viewport draw from that state.
//! Every change of the posing session (avatar, LOA, mannequin, mapping) goes through
//! `EditorModel::replace_session`, which resets what belonged to the old one.

mod avatars;
mod bones;
mod cast;
mod clips;
mod comfort;
mod command;
mod control_maps;
mod dispatch;
mod hands;
mod joined;
mod keypoints;
mod mapping;
mod motion;
mod opening;
pub mod photo;
mod prop_files;
mod props;
mod storage;
mod tasks;

use glam::DVec3;
use serde_json::Value;
use stance_document::{AvatarReference, Document, PostureRest, link};
use stance_hanim::{LevelOfArticulation, Mapping, readable_name};
use stance_ik::Clock;
use stance_render::MannequinBone;

pub use self::cast::{CHARACTER_SPACING_M, Cast, Character, SceneCommand};
pub use self::clips::{AUTOSAVE_CLIP_BYTES, AnimationFormat, CLIP_FPS, PickPurpose};
pub use self::comfort::{ComfortCommand, ComfortView, heat_color};
pub use self::control_maps::{OPENPOSE_IMAGE_FILE_NAME, OPENPOSE_KEYPOINTS_FILE_NAME, RenderedMap};
/// Said when a document made on the avatar before a posture meant the same pose on every body
/// (its values relative to the avatar's own rest) was converted to the standard pose.
pub(crate) const CONVERTED_NOTE: &str = " The document was made before a posture meant the same pose on every body: its values, relative to this avatar's own rest, were converted and show the pose it was saved with.";

pub use self::command::{
    AvatarCommand, Change, Command, FileCommand, Gesture, GestureCommand, HistoryCommand,
    LibraryCommand, Notice, NoticeCommand, PostureCommand, SessionChange, TaskCommand, ViewCommand,
};
pub use self::dispatch::{Outbox, SharedLink};
pub use self::hands::{HandCommand, Hands};
pub use self::joined::NewBetween;
pub use self::keypoints::{FLIPPABLE_LIMBS, KeypointsCommand, LiftPurpose, Lifting};
pub use self::mapping::{Correction, carry_posture};
pub use self::motion::{
    IntervalEdge, MotionCommand, SPEED_RANGE, TRAJECTORY_FRAMES_PER_STEP, Timeline,
};
pub use self::prop_files::{
    AUTOSAVE_PROP_FILE_BYTES, LeftOutFile, NotCarried, PropFile, PropFiles, left_out_words,
    size_words,
};
pub use self::tasks::{NewTask, make_task, table1_example};
use crate::avatar::LoadedAvatar;
use crate::history::{EditKind, History, Pending, Step};
use crate::host::{HostHooks, HostMessage};
use crate::library::{Autosave, PoseLibrary};
use crate::posing::{PosingError, PosingSession};
use crate::sensors::{SensorCommand, SensorHub, SensorSettings};

/// The name a *Save image* PNG downloads as.
pub const IMAGE_FILE_NAME: &str = "stance-posture.png";
/// The file name of an exported scene (GLB).
pub const SCENE_FILE_NAME: &str = "stance-scene.glb";
/// Seconds an information notice stays (errors stay until dismissed).
pub const NOTICE_SECS: f64 = 8.0;
/// Points of the effector trace kept.
const MAX_TRACE_POINTS: usize = 2000;
/// The trace takes a new point when the grabbed point moved this far (m).
const TRACE_STEP_M: f64 = 0.002;

/// The editor's model.
pub struct EditorModel {
    /// The selected character: the one every tool works on.
    character: Character,
    /// The scene's other characters.
    cast: Cast,
    history: History,
    selected_joint: Option<usize>,
    hovered_joint: Option<usize>,
    /// The body's collision capsules are shown in the viewport.
    show_capsules: bool,
    gesture: Option<Gesture>,
    /// Earlier bodies that undo or redo of a change of body brings back, by the id the
    /// history names them with (see `model/avatars.rs`).
    kept_bodies: Vec<(u64, avatars::KeptBody)>,
    /// The id of the next kept body.
    next_body: u64,
    /// Texture images the host decoded for the avatar file it opens next (file, images).
    decoded_images: Option<(String, Vec<stance_asset::DecodedImage>)>,
    /// A document waiting for its avatar to arrive (a link or autosave naming a URL).
    pending_document: Option<Document>,
    /// The avatar file the host is importing for the editor (its name).
    pending_import: Option<String>,
    trace: Vec<DVec3>,
    notice: Option<Notice>,
    library: PoseLibrary,
    sensors: SensorHub,
    /// The next picked file is a sensor recording to replay.
    /// What the next picked file is for, when the user asked for one.
    pending_pick: Option<PickPurpose>,
    /// Counts the times the document's saved view should be shown (a document with one was
    /// opened, or undo and redo changed it): the viewport follows each new count.
    view_requests: u64,
    hooks: Box<dyn HostHooks>,
    autosave: Autosave,
    /// Seconds since the editor started, as of the last step.
    now_secs: f64,
    /// Whether the last step put sensor readings in the posture.
    sensors_drove: bool,
    /// CPU time of the last step's solve (ms).
    solver_ms: f64,
    /// How many times the session was replaced (views keep per-session state by it).
    session_generation: u64,
    /// The comfort panel: report and heat map.
    comfort: ComfortView,
    /// The keypoints lift the host is running (*File > Open keypoints*, a depth flip).
    lifting: Option<Lifting>,
    /// Counts the lift requests.
    next_lift: u64,
    /// The photo behind the viewport (*File > Open photo*), and whether it is shown.
    photo: Option<photo::ReferencePhoto>,
    photo_shown: bool,
    /// Counts the photos opened.
    next_photo: u64,
    /// The imported prop files (*File > Import prop...*), by name.
    prop_files: PropFiles,
}

impl std::fmt::Debug for EditorModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EditorModel")
            .field("character", &self.character)
            .field("selected_joint", &self.selected_joint)
            .field("gesture", &self.gesture)
            .finish_non_exhaustive()
    }
}

impl EditorModel {
    /// The model on the built-in mannequin at LOA 2, with the library and sensor settings
    /// the host kept.
    pub fn new(hooks: Box<dyn HostHooks>) -> Result<Self, PosingError> {
        let session = PosingSession::new(LevelOfArticulation::Loa2)?;
        let mut model = Self {
            character: Character::new(0, stance_document::default_character_name(1), session),
            cast: Cast::default(),
            history: History::default(),
            selected_joint: None,
            hovered_joint: None,
            show_capsules: false,
            gesture: None,
            kept_bodies: Vec::new(),
            next_body: 0,
            decoded_images: None,
            pending_document: None,
            pending_import: None,
            trace: Vec::new(),
            notice: None,
            library: PoseLibrary::default(),
            sensors: SensorHub::default(),
            pending_pick: None,
            view_requests: 0,
            hooks,
            autosave: Autosave::default(),
            now_secs: 0.0,
            sensors_drove: false,
            solver_ms: 0.0,
            session_generation: 0,
            comfort: ComfortView::default(),
            lifting: None,
            next_lift: 0,
            photo: None,
            prop_files: PropFiles::default(),
            photo_shown: false,
            next_photo: 0,
        };
        model.load_library();
        if let Some(settings) = SensorSettings::load(model.hooks.as_ref()) {
            model.sensors = SensorHub::new(settings);
        }
        model.refresh_bones();
        Ok(model)
    }

    // -----------------------------------------------------------------------------------------
    // What the UI reads

    /// The posing session: the body, its posture, the tasks and the solver.
    pub fn session(&self) -> &PosingSession {
        &self.character.session
    }

    /// The undo and redo history.
    pub fn history(&self) -> &History {
        &self.history
    }

    /// The body's H-Anim level of articulation (how many joints it has).
    pub fn level_of_articulation(&self) -> LevelOfArticulation {
        self.character.session.level_of_articulation()
    }

    /// The selected joint (skeleton index), if any.
    pub fn selected_joint(&self) -> Option<usize> {
        self.selected_joint
    }

    /// The joint under the pointer (skeleton index), if any.
    pub fn hovered_joint(&self) -> Option<usize> {
        self.hovered_joint
    }

    /// Whether the viewport shows the body's collision capsules (`ViewCommand::ShowCapsules`).
    pub fn show_capsules(&self) -> bool {
        self.show_capsules
    }

    /// The gesture in progress, if any.
    pub fn gesture(&self) -> Option<&Gesture> {
        self.gesture.as_ref()
    }

    /// Whether a grab-and-pull is in progress.
    pub fn is_pulling(&self) -> bool {
        matches!(self.gesture, Some(Gesture::Pull { .. }))
    }

    /// The loaded avatar; `None` while the built-in mannequin is shown.
    pub fn avatar(&self) -> Option<&LoadedAvatar> {
        self.character.avatar.as_ref()
    }

    /// The message shown above the viewport, if any.
    pub fn notice(&self) -> Option<&Notice> {
        self.notice.as_ref()
    }

    /// The pose library: postures saved under names.
    pub fn library(&self) -> &PoseLibrary {
        &self.library
    }

    /// The motion sensors: connection, calibration, replay.
    pub fn sensors(&self) -> &SensorHub {
        &self.sensors
    }

    /// The effector trace of the current pull (world points).
    pub fn trace(&self) -> &[DVec3] {
        &self.trace
    }

    /// The posed mannequin's bones (capsules with the joint that carries each) as of the last
    /// step: what is drawn and picked.
    pub fn bones(&self) -> &[MannequinBone] {
        &self.character.bones
    }

    /// How many times the session was replaced (a new body, LOA or mapping).
    pub fn session_generation(&self) -> u64 {
        self.session_generation
    }

    /// The comfort of the current posture (measured once per posture).
    pub fn comfort_report(&self) -> stance_hanim::comfort::ComfortReport {
        self.comfort
            .report(&self.character.session, self.session_generation)
    }

    /// The comfort panel's view: heat map, settings, the last report measured.
    pub fn comfort(&self) -> &ComfortView {
        &self.comfort
    }

    /// CPU time of the last step's solve (ms).
    pub fn solver_ms(&self) -> f64 {
        self.solver_ms
    }

    /// What the editor needs from the page or the native shell.
    pub fn hooks(&self) -> &dyn HostHooks {
        self.hooks.as_ref()
    }

    /// Whether the avatar `name` has a mapping correction to revert.
    pub fn can_revert_mapping(&self, name: &str) -> bool {
        self.character
            .mapping_corrections
            .before_last(name)
            .is_some()
    }

    /// Seconds since the editor started, as of the last step.
    pub fn now_secs(&self) -> f64 {
        self.now_secs
    }

    /// The document: the session's posture and tasks, the avatar they are for, and the clip
    /// the keys are over (embedded; named only when its file is not loaded).
    pub fn document(&self) -> Document {
        let mut document = document_of(
            &self.character.session,
            self.character.avatar_url.as_deref(),
        );
        document.clip = self.character.timeline.document_clip().cloned();
        document
    }

    /// Whether anything still moves: the solver has not settled, a gesture or a replay goes
    /// on, the trajectory is being computed (the UI keeps drawing frames).
    pub fn is_busy(&self) -> bool {
        !self.character.session.is_settled()
            || self.gesture.is_some()
            || self.sensors.replay_progress().is_some()
            || self.character.timeline.is_playing()
            || self.trajectory_pending()
    }

    // -----------------------------------------------------------------------------------------
    // The frame

    /// One frame at `now_secs`: a replay advances and the calibrated sensors set their
    /// joints, the solver runs this frame's iterations (within the time budget `clock`
    /// measures), forward kinematics runs once, and the bones and the trace follow; the
    /// document autosaves when it changed.
    pub fn step(&mut self, now_secs: f64, clock: Option<&dyn Clock>) {
        self.now_secs = now_secs;
        self.expire_notice();
        if let Some(message) = self.sensors.tick(now_secs) {
            self.inform(message);
        }
        self.motion_before_solve(now_secs);
        self.sensors_drove = self.sensors.drive(&mut self.character.session);
        self.hold_off_props();
        let started = web_time::Instant::now();
        if !self.solve_joined_frame(clock) {
            self.character.session.solve_frame(clock);
        }
        self.solver_ms = started.elapsed().as_secs_f64() * 1000.0;
        self.motion_after_solve();
        self.capture_frame(now_secs);
        self.extend_trace();
        self.refresh_bones();
        self.autosave();
    }

    /// The scene's props as obstacles of the selected character's collision tasks, in its
    /// frame (a prop added, moved or removed, or the character placed, wakes the solver).
    fn hold_off_props(&mut self) {
        let character_from_scene = self.character.placement().scene_from_character().inverse();
        let obstacles = self
            .props()
            .iter()
            .map(|prop| prop.obstacle(character_from_scene))
            .collect();
        self.character.session.set_obstacles(obstacles);
    }

    /// The pointer moved a gesture in this frame, after its [`step`](Self::step) (the view
    /// reads the pointer once the frame's layout is known): solves again within `clock`'s
    /// budget, so that the body drawn in the frame that read the pointer follows it, not
    /// one frame later. Nothing to do without a gesture or when the step's posture still
    /// holds.
    pub fn follow_input(&mut self, clock: Option<&dyn Clock>) {
        if self.gesture.is_none() || self.character.session.is_settled() {
            return;
        }
        let started = web_time::Instant::now();
        if !self.solve_joined_frame(clock) {
            self.character.session.solve_frame(clock);
        }
        self.solver_ms += started.elapsed().as_secs_f64() * 1000.0;
        self.extend_trace();
        self.refresh_bones();
    }

    /// The pulled point's path: a point where it moved far enough from the last one.
    fn extend_trace(&mut self) {
        if let Some(point) = self.character.session.grabbed_point_world() {
            let moved = self
                .trace
                .last()
                .is_none_or(|last| (*last - point).length() > TRACE_STEP_M);
            if moved && self.trace.len() < MAX_TRACE_POINTS {
                self.trace.push(point);
            }
        }
    }

    /// The sensors' readings were shown: their latency is measured up to here.
    pub fn readings_shown(&mut self) {
        if self.sensors_drove {
            self.sensors.shown();
        }
    }

    /// The bones follow the posture: rebuilt when the session's revision moved (or the
    /// session was replaced), not every frame.
    fn refresh_bones(&mut self) {
        self.character.refresh_bones();
    }

    fn expire_notice(&mut self) {
        if let Some(notice) = &self.notice
            && !notice.is_error
            && self.now_secs - notice.since_secs > NOTICE_SECS
        {
            self.notice = None;
        }
    }

    // -----------------------------------------------------------------------------------------
    // Commands

    /// Says what went wrong when the host refused.
    fn host_result(&mut self, result: Result<(), String>, what: &str) {
        if let Err(error) = result {
            self.warn(format!("{what}: {error}"));
        }
    }

    /// Carries out what the host sent (links, files, sensor bytes).
    pub fn receive(&mut self, message: HostMessage) {
        self.apply(message.into());
    }

    pub(crate) fn inform(&mut self, text: impl Into<String>) {
        self.notify(text.into(), false);
    }

    pub(crate) fn warn(&mut self, text: impl Into<String>) {
        let text = text.into();
        log::warn!("{text}");
        self.notify(text, true);
    }

    fn notify(&mut self, text: String, is_error: bool) {
        self.notice = Some(Notice {
            text,
            is_error,
            since_secs: self.now_secs,
        });
    }

    // -----------------------------------------------------------------------------------------
    // Edits: each one records the document before it, so that undo restores it exactly.

    fn record(&mut self, kind: EditKind) {
        let before = self.character.session.document();
        self.history
            .record(self.character.id, &before, kind, self.now_secs);
    }

    fn undo(&mut self) {
        self.travel(true);
    }

    fn redo(&mut self) {
        self.travel(false);
    }

    /// Undo (`back`) or redo: the step's character is selected first (undo shows what it
    /// changes); its state as it is now becomes the step the other way.
    fn travel(&mut self, back: bool) {
        self.end_gesture();
        let what = if back { "undo" } else { "redo" };
        let pending = if back {
            self.history.next_undo()
        } else {
            self.history.next_redo()
        };
        let Some(pending) = pending else {
            self.inform(format!("Nothing to {what}."));
            return;
        };
        let current = match pending {
            Pending::Edit {
                character,
                changes_body,
            } => {
                if !self.switch_to_character(character) {
                    // Its character is gone for good (never the case while a step of the
                    // cast names it): the step is dropped.
                    self.history.discard(back);
                    self.warn(format!(
                        "Could not {what}: its character is no longer in the scene."
                    ));
                    return;
                }
                let document = self.character.session.document();
                // A change of body goes back: the current body is kept for the other way.
                let body = changes_body.then(|| self.keep_body());
                Step::Edit {
                    character: self.character.id,
                    document: Box::new(document),
                    body,
                }
            }
            Pending::Cast => Step::Cast(self.cast_snapshot()),
        };
        let current_body = match &current {
            Step::Edit { body, .. } => *body,
            Step::Cast(_) => None,
        };
        let step = if back {
            self.history.undo(current)
        } else {
            self.history.redo(current)
        };
        match step {
            Some(Step::Edit { document, body, .. }) => {
                if let Some(body) = body {
                    self.bring_back_body(body, current_body);
                }
                self.restore(&document, what);
            }
            Some(Step::Cast(snapshot)) => self.restore_cast(&snapshot),
            None => {}
        }
        self.forget_unreferenced_bodies();
        self.forget_unreferenced_characters();
    }

    /// Undo or redo: `document` on the current body, which may lack some of its joints (the
    /// step crossed an avatar swap or a change of level of articulation): their values are
    /// left out.
    fn restore(&mut self, document: &Document, what: &str) {
        self.motion_restored();
        let camera = self.character.session.camera();
        let skeleton = self.character.session.skeleton();
        let mut document = document.clone();
        document.posture = document.posture.fitted(skeleton);
        if let Some(motion) = &mut document.motion {
            for key in &mut motion.keys {
                key.posture = key.posture.fitted(skeleton);
            }
        }
        if let Err(error) = self.character.session.restore_document(&document) {
            self.warn(format!("Could not {what}: {error}"));
        }
        if self.character.session.camera() != camera {
            self.view_requests += 1;
        }
    }

    /// Changes when the document's saved view should be shown (see
    /// [`PosingSession::camera`]): a document with one was opened, or undo or redo changed it.
    pub fn view_request(&self) -> u64 {
        self.view_requests
    }

    /// Opens `document` in the session as one undoable edit; `Err` says why it does not fit.
    /// A document with a posture opens exactly as it was saved; one with tasks and no
    /// posture (written by hand or by a script) is posed by the solver from the rest pose.
    /// Opens `document` as one undoable edit. A document made on the avatar now loaded before
    /// postures meant the same pose on every body ([`PostureRest::Avatar`]) is converted
    /// from that avatar's own rest; returns whether it was (say so: [`CONVERTED_NOTE`]).
    fn open_document(&mut self, document: &Document) -> Result<bool, PosingError> {
        let on_this_avatar = matches!(&document.avatar, AvatarReference::Url(url)
            if self.character.avatar.is_some() && self.character.avatar_url.as_ref() == Some(url));
        let converted = document.rest == PostureRest::Avatar && on_this_avatar;
        let document = &if converted {
            document.in_standard_rest(self.character.session.humanoid())
        } else {
            document.clone()
        };
        let current = self.character.session.document();
        if document.posture.joints.is_empty() {
            self.character.session.load_document(document)?;
        } else {
            self.character.session.restore_document(document)?;
        }
        self.history.record(
            self.character.id,
            &current,
            EditKind::Command,
            self.now_secs,
        );
        if document.camera.is_some() {
            self.view_requests += 1;
        }
        Ok(converted)
    }

    fn pin(&mut self, joint: usize) {
        self.record(EditKind::Command);
        self.character.session.pin(joint);
        self.selected_joint = Some(joint);
        let name = self
            .character
            .session
            .skeleton()
            .joints()
            .get(joint)
            .map(|joint| readable_name(&joint.name))
            .unwrap_or_default();
        self.inform(format!("Pinned the {name} where it is (level 1)."));
    }

    // -----------------------------------------------------------------------------------------
    // Gestures

    fn begin_pull(&mut self, joint: usize, point_world: DVec3) {
        self.end_gesture();
        let document_before = Box::new(self.character.session.document());
        self.record(EditKind::Command);
        self.history.break_coalescing();
        self.character.session.begin_grab(joint, point_world);
        self.trace.clear();
        self.trace.push(point_world);
        self.selected_joint = Some(joint);
        self.gesture = Some(Gesture::Pull {
            joint,
            plane_point_world: point_world,
            document_before,
        });
    }

    /// Starts dragging a handle: one undo step for the whole drag.
    fn begin_handle(&mut self, gesture: Gesture) {
        if matches!(gesture, Gesture::Pull { .. }) {
            return;
        }
        self.end_gesture();
        self.record(EditKind::Command);
        self.history.break_coalescing();
        if let Gesture::Swivel { limb, .. } = &gesture {
            self.character.session.hold_limb_end(*limb);
        }
        self.gesture = Some(gesture);
    }

    fn end_gesture(&mut self) {
        if self.gesture.is_some() {
            self.motion_posture_edited();
        }
        match self.gesture.take() {
            Some(Gesture::Pull { .. }) => self.character.session.end_grab(),
            Some(Gesture::Swivel { .. }) => {
                self.character.session.release_hold();
                self.history.break_coalescing();
            }
            Some(_) => self.history.break_coalescing(),
            None => {}
        }
    }

    /// Escape: a pull's body goes back to where it was; a handle stays where it got to.
    fn cancel_gesture(&mut self) {
        match self.gesture.take() {
            Some(Gesture::Pull {
                document_before, ..
            }) => {
                self.character.session.end_grab();
                if let Err(error) = self.character.session.restore_document(&document_before) {
                    self.warn(format!("Could not cancel the pull: {error}"));
                }
            }
            other => {
                self.gesture = other;
                self.end_gesture();
            }
        }
    }

    // -----------------------------------------------------------------------------------------
    // Sessions: one way to replace the posing session.

    /// Puts `session` in place of the current one: the gesture, selection, hover, trace and
    /// the sensors' hold end (they belonged to the old body); for a new body the history
    /// starts again.
    pub(crate) fn replace_session(&mut self, session: PosingSession, change: SessionChange) {
        self.gesture = None;
        let motion = self.character.session.motion().cloned();
        self.character.session = session;
        self.sensors.release();
        self.selected_joint = None;
        self.hovered_joint = None;
        self.trace.clear();
        if change == SessionChange::NewBody {
            self.history = History::default();
            self.kept_bodies.clear();
        }
        self.session_generation += 1;
        self.motion_session_replaced(motion);
        self.character.bones_revision = None;
        self.refresh_bones();
    }

    /// The body at another level of articulation: the posture carries over by joint name
    /// (world rotations), the tasks whose joints remain stay; one undoable edit.
    fn set_level_of_articulation(&mut self, loa: LevelOfArticulation) {
        if loa == self.character.session.level_of_articulation() {
            return;
        }
        let humanoid = match &self.character.avatar {
            Some(avatar) => avatar.skeleton(loa),
            None => stance_hanim::default_skeleton(&stance_hanim::SkeletonOptions {
                loa,
                ..stance_hanim::SkeletonOptions::default()
            })
            .map_err(|error| error.to_string()),
        };
        match humanoid
            .and_then(|humanoid| mapping::rebuilt_session(&self.character.session, humanoid))
        {
            Ok((session, dropped)) => {
                self.record(EditKind::Command);
                self.replace_session(session, SessionChange::Rebuilt);
                if !dropped.is_empty() {
                    self.inform(format!(
                        "At LOA {} these tasks have no joint and were dropped (undo brings them back): {}.",
                        loa.number(),
                        dropped.join(", ")
                    ));
                }
            }
            Err(error) => self.warn(format!("Could not switch to LOA {}: {error}", loa.number())),
        }
    }

    /// Offers the scene in its current postures as a GLB download: the avatar file alone
    /// (what `stance export-posed` writes) for one character at the origin without props,
    /// else the whole scene (`scene_glb`); says why when it cannot.
    fn export_posed_avatar(&mut self) {
        let single = self.is_single_character();
        let (file_name, posed, what) = match self.character.avatar.as_mut() {
            Some(avatar) if single => (
                crate::avatar::posed_file_name(&avatar.name),
                avatar.posed_glb(
                    self.character.session.humanoid(),
                    self.character.session.posture(),
                ),
                "the avatar in this posture",
            ),
            _ => (
                SCENE_FILE_NAME.to_owned(),
                self.scene_glb(),
                "the scene in these postures",
            ),
        };
        let result = posed.and_then(|bytes| {
            self.hooks
                .download_bytes(&file_name, &bytes)
                .map(|()| bytes.len())
        });
        match result {
            Ok(size) => self.inform(format!(
                "Exported {file_name} ({} KB): {what}, for any glTF viewer or engine.",
                size.div_ceil(1024)
            )),
            Err(error) => self.warn(format!("{file_name} could not be exported: {error}")),
        }
    }

    /// Hands a rendered image (PNG, `width` x `height` pixels) to the host as
    /// [`IMAGE_FILE_NAME`].
    fn save_image(&mut self, png: &[u8], width: u32, height: u32) {
        match self.hooks.download_bytes(IMAGE_FILE_NAME, png) {
            Ok(()) => self.inform(format!(
                "Saved a {width}x{height} image as {IMAGE_FILE_NAME}."
            )),
            Err(error) => self.warn(format!("Could not save the image: {error}")),
        }
    }

    /// Rebuilds the avatar's skeleton and the session from `mapping`, remembered as one
    /// correction to revert.
    fn apply_mapping(&mut self, mapping: Mapping, corrections: Vec<Correction>) {
        let Some(avatar) = &self.character.avatar else {
            return;
        };
        if corrections.is_empty() {
            self.inform("Nothing to apply: pick another H-Anim joint in a row first.");
            return;
        }
        let name = avatar.name.clone();
        let before = avatar.avatar.mapping.clone();
        let changes = mapping::describe_changes(avatar, &before, &mapping);
        match self.remap_avatar(mapping) {
            Ok(dropped) => {
                self.character
                    .mapping_corrections
                    .remember(name, before, corrections);
                self.inform(format!(
                    "Mapping corrected ({}): {} Ctrl+Z does not undo this; Revert last correction in the mapping window does.",
                    mapping::summarize(&changes),
                    mapping::rebuilt_summary(&self.character.session, &dropped)
                ));
            }
            Err(error) => self.warn(format!(
                "The corrected mapping could not be applied: {error}. The skeleton stays as it was."
            )),
        }
    }

    fn revert_mapping_correction(&mut self) {
        let Some(avatar) = &self.character.avatar else {
            return;
        };
        let name = avatar.name.clone();
        let Some(previous) = self.character.mapping_corrections.before_last(&name) else {
            self.inform("There is no mapping correction to revert.");
            return;
        };
        match previous
            .map_err(|error| error.to_string())
            .and_then(|mapping| self.remap_avatar(mapping))
        {
            Ok(dropped) => {
                self.character.mapping_corrections.forget_last(&name);
                self.inform(format!(
                    "Reverted the last mapping correction: {}",
                    mapping::rebuilt_summary(&self.character.session, &dropped)
                ));
            }
            Err(error) => self.warn(format!("The correction could not be reverted: {error}")),
        }
    }

    /// Rebuilds the avatar's skeleton and the posing session from `mapping` at the current
    /// LOA: the posture carries over by joint name, the tasks that still fit stay. On error
    /// nothing changes. Returns the dropped tasks, described.
    fn remap_avatar(&mut self, mapping: Mapping) -> Result<Vec<String>, String> {
        let loa = self.character.session.level_of_articulation();
        let Some(avatar) = self.character.avatar.as_ref() else {
            return Err("no avatar is loaded".to_owned());
        };
        let humanoid = avatar.skeleton_with_mapping(&mapping, loa)?;
        let (session, dropped) = mapping::rebuilt_session(&self.character.session, humanoid)?;
        if let Some(avatar) = self.character.avatar.as_mut() {
            avatar.avatar.mapping = mapping;
        }
        self.replace_session(session, SessionChange::Rebuilt);
        Ok(dropped)
    }
}

/// The session's document, for the avatar at `avatar_url` (`None`: the built-in one).
fn document_of(session: &PosingSession, avatar_url: Option<&str>) -> Document {
    let mut document = session.document();
    if let Some(url) = avatar_url {
        document.avatar = AvatarReference::Url(url.to_owned());
    }
    document
}
