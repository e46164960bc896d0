//! What the UI says to the model: [`Command`]s, the [`Gesture`] in progress, and what the
//! model says back ([`Notice`]).

use glam::DVec3;
use stance_document::{Document, LimbName, TaskKindSpec, TaskSpec};
use stance_hanim::{LevelOfArticulation, Mapping};

use super::cast::SceneCommand;
use super::clips::AnimationFormat;
use super::comfort::ComfortCommand;
use super::hands::HandCommand;
use super::mapping::Correction;
use super::motion::MotionCommand;
use super::tasks::NewTask;
use crate::history::EditKind;
use crate::host::HostMessage;
use crate::sensors::SensorCommand;

/// A message for the user, shown above the viewport.
#[derive(Debug, Clone, PartialEq)]
pub struct Notice {
    /// What the user is told, in one or two sentences.
    pub text: String,
    /// An error stays until dismissed; information goes after
    /// [`NOTICE_SECS`](crate::model::NOTICE_SECS) seconds.
    pub is_error: bool,
    /// When it appeared, in seconds since the editor started.
    pub since_secs: f64,
}

/// The gesture in progress: at most one at a time.
#[derive(Debug, Clone)]
pub enum Gesture {
    /// Grab-and-pull: the grabbed point follows the pointer in the plane facing the camera
    /// through `plane_point_world`; cancelling restores `document_before`.
    Pull {
        /// The grabbed joint (skeleton index).
        joint: usize,
        /// Where the grab started (world frame, m).
        plane_point_world: DVec3,
        /// The document as it was when the pull started.
        document_before: Box<Document>,
    },
    /// The goal of `tasks` (several when their goals coincide) moves in the plane facing the
    /// camera through `plane_point_world`.
    Goal {
        /// The moved tasks (indices in the task list).
        tasks: Vec<usize>,
        /// The goal's place when the drag started (world frame, m).
        plane_point_world: DVec3,
    },
    /// A ring of the joint gizmo: DOF `dof` turns with the pointer around `centre_px`
    /// (screen points), from `start_value`.
    Ring {
        /// The turned DOF (index in the posture's values).
        dof: usize,
        /// The ring's centre on screen (points).
        centre_px: [f32; 2],
        /// The pointer's screen angle around the centre at the last move (rad).
        last_angle: f32,
        /// The pointer's turn since the drag started, unwrapped across ±π (rad).
        accumulated: f64,
        /// The DOF's value when the drag started (rad).
        start_value: f64,
        /// +1 when the DOF axis points toward the camera (a counter-clockwise drag on screen
        /// is then a positive rotation), -1 otherwise.
        sign: f64,
    },
    /// The swivel handle: the elbow or knee turns around the limb's axis with the pointer.
    Swivel {
        /// The turned limb.
        limb: LimbName,
        /// The limb's swivel angle when the drag started (rad).
        start_swivel: f64,
        /// Unit direction from the axis to the middle joint when the drag started.
        start_direction: DVec3,
        /// The swivel circle's centre, on the limb's axis (world frame, m).
        centre_world: DVec3,
        /// The limb's axis, a unit vector from the upper joint toward the end joint (world
        /// frame).
        axis_world: DVec3,
    },
}

/// What the UI asks the model to do: one command per feature, each carried out by that
/// feature's `apply` (see [`EditorModel::apply`](crate::EditorModel::apply)), which says what
/// changed.
#[derive(Debug, Clone)]
pub enum Command {
    /// Selection and hover.
    View(ViewCommand),
    /// The one gesture in progress: pull, goal, ring, swivel.
    Gesture(GestureCommand),
    /// An edit of the posture (a DOF, a limb's swivel, rest, mirror, a pin, the saved view).
    Posture(PostureCommand),
    /// An edit of the task list.
    Task(TaskCommand),
    /// Undo and redo.
    History(HistoryCommand),
    /// A hand preset or a finger curl (bodies with fingers).
    Hands(HandCommand),
    /// The body: avatar, mannequin, level of articulation, mapping.
    Avatar(AvatarCommand),
    /// Opening and offering files and links.
    File(FileCommand),
    /// The pose library.
    Library(LibraryCommand),
    /// A command for the sensors.
    Sensors(SensorCommand),
    /// A command for the timeline (clip, playhead, keys, intervals, trajectory).
    Motion(MotionCommand),
    /// A command for the comfort panel (heat map, RULA inputs).
    Comfort(ComfortCommand),
    /// The message above the viewport.
    Notice(NoticeCommand),
    /// The scene's characters: add, duplicate, remove, rename, select, place.
    Scene(SceneCommand),
    /// Keypoints lifted into characters, and a lifted limb's depth flipped.
    Keypoints(super::KeypointsCommand),
}

/// What a command changed: the views redraw, the document is saved, the timeline keys a
/// posture edit. Ordered: each one includes the ones before it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Default)]
pub enum Change {
    /// Nothing (the command did not apply, or changed nothing).
    #[default]
    Nothing,
    /// What is shown (selection, playhead, notice, panels), not the document.
    View,
    /// The document (tasks, body, keys, files opened), undoable where the history keeps it.
    Document,
    /// The posture itself, by an edit of the user: paused on a timeline, it becomes a key.
    Posture,
}

/// Selection and hover: what the views show, not the document.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ViewCommand {
    /// Select a joint (or nothing).
    Select(Option<usize>),
    /// The joint under the pointer (or nothing).
    Hover(Option<usize>),
    /// Show the body's collision capsules in the viewport (over a figure or an avatar), or
    /// not.
    ShowCapsules(bool),
}

/// The gesture in progress: begin, move, end.
#[derive(Debug, Clone)]
pub enum GestureCommand {
    /// Grab `joint` at `point_world` and start pulling it.
    BeginPull {
        /// The grabbed joint (skeleton index).
        joint: usize,
        /// The grabbed point on the body (world frame, m).
        point_world: DVec3,
    },
    /// Start a handle drag (goal, ring or swivel); a pull starts with `BeginPull`.
    BeginHandle(Gesture),
    /// The pulled point's new target.
    MoveGrab {
        /// Where the pointer is on the plane of the pull (world frame, m).
        target_world: DVec3,
    },
    /// The dragged goal's new place, and where the pointer meets the floor (balance goals
    /// slide on the floor).
    MoveGoal {
        /// Where the pointer is on the plane of the drag (world frame, m).
        goal_world: DVec3,
        /// Where the pointer's ray meets the floor (y = 0), if it does.
        floor_world: Option<DVec3>,
    },
    /// The pointer's screen angle around the ring's centre (radians).
    TurnRing {
        /// The angle, measured on screen where y points down (rad).
        screen_angle: f32,
    },
    /// Where the pointer meets the swivel circle's plane.
    TurnSwivel {
        /// The pointer on the circle's plane (world frame, m).
        point_world: DVec3,
    },
    /// The gesture ends where it is.
    EndGesture,
    /// The gesture ends and a pull's body goes back to where it was.
    CancelGesture,
}

/// An edit of the posture, each one undoable.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PostureCommand {
    /// Pin a joint where it is (level 1).
    Pin(usize),
    /// Pin the selected joint.
    PinSelected,
    /// Set one DOF (a slider or field), as one edit of `EditKind::Joint`.
    SetDof {
        /// The DOF (index in the posture's values).
        dof: usize,
        /// Its new value (rad; m for a translation of the root).
        value: f64,
    },
    /// Set a rotation DOF's stiffness in [0, 1) (`None`: back to the anatomical default), as
    /// one edit of `EditKind::Stiffness`.
    SetStiffness {
        /// The DOF (index in the posture's values).
        dof: usize,
        /// Its stiffness, or `None` for the body's default.
        value: Option<f64>,
    },
    /// Set a limb's swivel angle (rad).
    SetSwivel {
        /// The arm or leg.
        limb: LimbName,
        /// The elbow's or knee's angle around the limb's axis (rad).
        swivel_angle: f64,
    },
    /// Put the body back in its rest posture; the tasks stay.
    ResetToRest,
    /// Swap left and right: the posture and the tasks with it, reflected in the body's
    /// sagittal plane.
    Mirror,
    /// Save this camera with the document (`None`: forget it); undoable.
    SaveCamera(Option<stance_document::CameraSpec>),
}

/// An edit of the task list, each one undoable.
#[derive(Debug, Clone)]
pub enum TaskCommand {
    /// Replace the task list as one edit of `kind` (a field edited in the tasks panel).
    Set {
        /// What kind of edit it is (edits of one kind in quick succession make one undo step).
        kind: EditKind,
        /// The whole new task list, in priority order.
        tasks: Vec<TaskSpec>,
    },
    /// Add a task made from where the body stands.
    Add(NewTask),
    /// Put a part of the selected character on a prop: a hand on a bar (the point on its axis),
    /// a hand or foot on a box's top or a plane (the point on its surface), a hand on a ball
    /// (the point on its surface nearest the part).
    AddOnProp {
        /// The part (skeleton index of its joint).
        joint: usize,
        /// The prop (index in the scene's props).
        prop: usize,
    },
    /// The paper's Table 1 in place of the tasks.
    LoadTable1Example,
    /// Collision avoidance on or off: on, the body's collision tasks act (one is added just
    /// below the pins where there is none); off, they stay in the list, inactive.
    SetCollision(bool),
    /// Remove the task at this index of the list.
    Remove(usize),
    /// Move the task at index `task` to level `level` (dropped onto it).
    MoveToLevel {
        /// The task (index in the list).
        task: usize,
        /// Its new priority level.
        level: u32,
    },
    /// Swap two levels: the tasks of each take the other's number.
    SwapLevels(u32, u32),
    /// Move the tasks of level `from` to the place of level `onto` (`None`: the lowest place);
    /// the levels in between shift by one place, the level numbers in use stay the same.
    MoveLevel {
        /// The moved level.
        from: u32,
        /// The level whose place it takes, or `None` for the last place.
        onto: Option<u32>,
    },
}

/// Undo and redo.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HistoryCommand {
    /// Take back the last edit.
    Undo,
    /// Do again the last edit taken back.
    Redo,
}

/// The body: an avatar, the mannequin, the level of articulation, the mapping onto H-Anim.
#[derive(Debug, Clone)]
pub enum AvatarCommand {
    /// Rebuild the body at another level of articulation: the posture carries over by joint
    /// name, and the tasks whose joints remain stay.
    SetLevelOfArticulation(LevelOfArticulation),
    /// Load an avatar file (glTF, GLB, VRM).
    LoadAvatar {
        /// The file's name: the avatar goes by it (notices, mapping corrections).
        name: String,
        /// The file's contents.
        bytes: Vec<u8>,
    },
    /// Ask the page to fetch an avatar by URL (it arrives as a file).
    FetchAvatar(String),
    /// Back to the built-in mannequin.
    UseMannequin,
    /// Rebuild the avatar's skeleton from a corrected mapping (`corrections` made it).
    ApplyMapping {
        /// The corrected mapping of the avatar's joints onto H-Anim.
        mapping: Box<Mapping>,
        /// The corrections, in the order the user made them.
        corrections: Vec<Correction>,
    },
    /// Go back to the mapping before the last applied correction.
    RevertMappingCorrection,
    /// The texture images of the avatar file `file` decoded by the host: its next import
    /// takes them instead of decoding them.
    DecodedImages {
        /// The file (name or URL) they belong to.
        file: String,
        /// The images' pixels.
        images: Vec<stance_asset::DecodedImage>,
    },
    /// The avatar the host imported for the editor, or why it could not.
    AvatarImported {
        /// The file's name or URL.
        name: String,
        /// The avatar, or what is wrong with the file.
        result: Result<Box<crate::host::ImportedAvatar>, String>,
    },
    /// Offer the avatar in the current posture as a GLB download.
    ExportPosedAvatar,
    /// The renderer took the avatar's GPU model for its upload ([`LoadedAvatar::mesh`]): the
    /// model lets go of its copy.
    ///
    /// [`LoadedAvatar::mesh`]: crate::avatar::LoadedAvatar::mesh
    MeshTaken,
}

/// Files and links: opening what the user picked or dropped, offering downloads.
#[derive(Debug, Clone)]
pub enum FileCommand {
    /// Open a posture link (fragment or URL).
    OpenLink(String),
    /// Open a file: avatar, document, pose library, or a sensor recording when one was asked.
    OpenFile {
        /// The file's name (with the contents, it tells what kind of file it is).
        name: String,
        /// The file's contents.
        bytes: Vec<u8>,
    },
    /// Open files picked or dropped together (name, contents): a `.gltf` among them opens as
    /// an avatar with the others as its `.bin` buffers and images; the rest open in turn.
    OpenFiles(Vec<(String, Vec<u8>)>),
    /// Ask the page for a file to open.
    PickFile,
    /// Ask the page for a sensor recording to replay.
    PickRecording,
    /// Ask the page for a motion clip (BVH, or a glTF file's animation).
    PickClip,
    /// Ask the page for a static glTF/GLB mesh to import as a prop.
    PickProp,
    /// Offer the document as a JSON download.
    ExportDocument,
    /// Offer the timeline (clip, keys and timed tasks, baked) as a download.
    ExportAnimation(AnimationFormat),
    /// Offer an image of the posture (a PNG the views rendered with the GPU, `width` x
    /// `height` pixels) as a download.
    SaveImage {
        /// The PNG file's bytes.
        png: Vec<u8>,
        /// Width, pixels.
        width: u32,
        /// Height, pixels.
        height: u32,
    },
    /// Offer the OpenPose control map (its skeleton image, a PNG the views drew from
    /// [`EditorModel::openpose`], `width` x `height` pixels, and its keypoints as OpenPose
    /// JSON) as two downloads.
    ///
    /// [`EditorModel::openpose`]: crate::EditorModel::openpose
    SaveOpenPose {
        /// The PNG file's bytes.
        png: Vec<u8>,
        /// The keypoints' JSON.
        json: String,
        /// Width, pixels.
        width: u32,
        /// Height, pixels.
        height: u32,
    },
    /// Offer a control map the views rendered with the GPU (a PNG, `width` x `height`
    /// pixels) as a download named after it.
    SaveControlMap {
        /// Which map.
        map: super::RenderedMap,
        /// The PNG file's bytes.
        png: Vec<u8>,
        /// Width, pixels.
        width: u32,
        /// Height, pixels.
        height: u32,
    },
    /// The host's job `id` (a clip, a lift) failed where it ran: `reason` says why.
    JobFailed {
        /// The request.
        id: u64,
        /// What went wrong, in words.
        reason: String,
    },
    /// The host failed to do what the editor asked (reading a file...).
    HostFailed(String),
    /// The views shared the document's posture link ([`EditorModel::share_link`]): the
    /// notice says what it carries.
    ///
    /// [`EditorModel::share_link`]: crate::EditorModel::share_link
    LinkShared {
        /// The link's fragment, in characters.
        characters: usize,
        /// The length the timeline's keys would have made it, when they were left out.
        keys_left_out: Option<usize>,
    },
}

/// The pose library: postures saved under names.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LibraryCommand {
    /// Save the posture in the library under a name.
    Save(String),
    /// Load the library's entry `index`.
    Load(usize),
    /// Delete the library's entry `index`.
    Delete(usize),
    /// Offer the pose library as a JSON download.
    Export,
}

/// The message shown above the viewport.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum NoticeCommand {
    /// A message for the user.
    Inform(String),
    /// A problem for the user.
    Warn(String),
    /// Close the notice shown above the viewport.
    Dismiss,
}

/// Why a session is replaced: what carries over.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SessionChange {
    /// Another body with a document of its own (a document or link that names its avatar):
    /// the history starts again.
    NewBody,
    /// The same document on a rebuilt or another body (LOA switch, mapping correction, avatar
    /// swap, back to the mannequin): the history stays.
    Rebuilt,
}

impl Gesture {
    /// A ring gesture follows the pointer to `screen_angle`: the turn accumulates across the
    /// ±π seam. Returns the DOF and its new value; `None` for another gesture.
    pub fn turn_ring(&mut self, screen_angle: f32) -> Option<(usize, f64)> {
        let Gesture::Ring {
            dof,
            last_angle,
            accumulated,
            start_value,
            sign,
            ..
        } = self
        else {
            return None;
        };
        let mut delta = screen_angle - *last_angle;
        if delta > std::f32::consts::PI {
            delta -= std::f32::consts::TAU;
        } else if delta < -std::f32::consts::PI {
            delta += std::f32::consts::TAU;
        }
        *accumulated += f64::from(delta);
        *last_angle = screen_angle;
        // Screen y points down: a counter-clockwise drag has a negative screen angle.
        Some((*dof, *start_value - *sign * *accumulated))
    }

    /// The swivel angle a swivel gesture reaches with the pointer at `point_world` (on the
    /// circle's plane): the start angle plus the turn from where the drag started,
    /// right-handed about the axis. `None` for another gesture or a point on the axis.
    pub fn swivel_at(&self, point_world: DVec3) -> Option<(LimbName, f64)> {
        let Gesture::Swivel {
            limb,
            start_swivel,
            start_direction,
            centre_world,
            axis_world,
        } = self
        else {
            return None;
        };
        let direction = point_world - *centre_world;
        let direction = direction - *axis_world * direction.dot(*axis_world);
        if direction.length() < 1e-9 {
            return None;
        }
        let turn = axis_world
            .dot(start_direction.cross(direction))
            .atan2(start_direction.dot(direction));
        Some((*limb, *start_swivel + turn))
    }
}

/// `tasks` with the goals of `moved` at `goal_world`; a balance goal slides on the floor
/// under the pointer (`floor_world`).
pub(super) fn goals_moved(
    tasks: &[TaskSpec],
    moved: &[usize],
    goal_world: DVec3,
    floor_world: Option<DVec3>,
) -> Vec<TaskSpec> {
    let mut tasks = tasks.to_vec();
    for &task in moved {
        let Some(spec) = tasks.get_mut(task) else {
            continue;
        };
        match &mut spec.kind {
            TaskKindSpec::Position { target, .. }
            | TaskKindSpec::Gaze { target, .. }
            | TaskKindSpec::Limb { target, .. } => *target = goal_world.to_array(),
            TaskKindSpec::Com { target, .. } => {
                if let Some(on_floor) = floor_world {
                    target[0] = on_floor.x;
                    target[2] = on_floor.z;
                }
            }
            // No goal to drag: the goal handles are drawn for the kinds above only.
            TaskKindSpec::Orientation { .. }
            | TaskKindSpec::Direction { .. }
            | TaskKindSpec::Balance { .. }
            | TaskKindSpec::Posture { .. }
            | TaskKindSpec::Comfort { .. }
            | TaskKindSpec::Line { .. }
            | TaskKindSpec::Plane { .. }
            | TaskKindSpec::Collision { .. } => {}
        }
    }
    tasks
}

impl From<HostMessage> for Command {
    /// What the host sends, as the command it asks for.
    fn from(message: HostMessage) -> Self {
        match message {
            HostMessage::OpenLink(fragment) => Command::File(FileCommand::OpenLink(fragment)),
            HostMessage::OpenFile { name, bytes } => {
                Command::File(FileCommand::OpenFile { name, bytes })
            }
            HostMessage::OpenFiles(files) => Command::File(FileCommand::OpenFiles(files)),
            HostMessage::DecodedImages { file, images } => {
                Command::Avatar(AvatarCommand::DecodedImages { file, images })
            }
            HostMessage::Failed(reason) => Command::File(FileCommand::HostFailed(reason)),
            HostMessage::AvatarImported { name, result } => {
                Command::Avatar(AvatarCommand::AvatarImported { name, result })
            }
            // Only clips report their progress (a lift shows a busy notice).
            HostMessage::JobProgress { id, fraction } => {
                Command::Motion(MotionCommand::ClipProgress { id, fraction })
            }
            HostMessage::KeypointsLifted { id, result } => {
                Command::Keypoints(super::KeypointsCommand::Lifted { id, result })
            }
            HostMessage::JobFailed { id, reason } => {
                Command::File(FileCommand::JobFailed { id, reason })
            }
            HostMessage::PhotoDetected(photo) => {
                Command::Keypoints(super::KeypointsCommand::OpenPhoto(photo))
            }
            HostMessage::PhotoFailed { name, reason } => {
                Command::Keypoints(super::KeypointsCommand::PhotoFailed { name, reason })
            }
            HostMessage::ClipOpened { id, result } => {
                Command::Motion(MotionCommand::ClipOpened { id, result })
            }
            HostMessage::SensorConnected { device } => {
                Command::Sensors(SensorCommand::Connected { device })
            }
            HostMessage::SensorBytes { bytes, arrived } => {
                Command::Sensors(SensorCommand::Bytes { bytes, arrived })
            }
            HostMessage::SensorReport {
                report_id,
                data,
                arrived,
            } => Command::Sensors(SensorCommand::Report {
                report_id,
                data,
                arrived,
            }),
            HostMessage::SensorLost { reason } => Command::Sensors(SensorCommand::Lost { reason }),
        }
    }
}
